#pragma once
// Runs the `seif` executable as a user would and captures what it prints.
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <utility>

namespace seif::test {

struct CliResult {
  int status = -1;  // 124 when stopped by the time limit
  std::string out;
  std::string err;
  double seconds = 0.0;  // wall time
};

/// A fresh scratch folder under the system temp dir, removed with everything in it when the
/// object goes out of scope (keep it as `const auto dir = scratchDir(...)`, or return it:
/// a copy into a plain path would outlive the folder).
class ScratchDir : public std::filesystem::path {
 public:
  explicit ScratchDir(const std::string& name)
      : std::filesystem::path(std::filesystem::temp_directory_path() /
                              ("seif-test-" + name + "-" + std::to_string(std::random_device{}()))) {
    std::filesystem::remove_all(*this);
    std::filesystem::create_directories(*this);
  }
  ScratchDir(ScratchDir&& other) noexcept : std::filesystem::path(std::move(other)) { other.clear(); }
  ~ScratchDir() {
    std::error_code ignored;
    if (!empty()) std::filesystem::remove_all(*this, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  ScratchDir& operator=(ScratchDir&&) = delete;
};

inline ScratchDir scratchDir(const std::string& name) { return ScratchDir(name); }

inline std::string slurp(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A run folder's metrics.json without what measures the machine (timings, the command line).
inline nlohmann::json estimateMetrics(const std::filesystem::path& dir) {
  nlohmann::json j = nlohmann::json::parse(slurp(dir / "metrics.json"));
  for (const char* key : {"seconds", "seconds_wall", "seconds_trajectory_and_map", "us_per_step",
                          "us_per_step_median", "command_line"}) {
    j.erase(key);
  }
  if (j.contains("association")) j["association"].erase("seconds");
  return j;
}

/// Runs `prefix seif <args>` through the shell (args as written) and captures its output.
inline CliResult runCliBehind(const std::string& prefix, const std::string& args) {
  const auto dir = scratchDir("cli");
  const std::string cmd = prefix + std::string(SEIF_CLI_PATH) + " " + args + " >" + (dir / "out").string() + " 2>" +
                          (dir / "err").string() + " </dev/null";
  const auto start = std::chrono::steady_clock::now();
  const int raw = std::system(cmd.c_str());
  CliResult r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(dir / "out");
  r.err = slurp(dir / "err");
  return r;
}

/// Runs `seif <args>` (args are passed to the shell as written). With `timeout_seconds` > 0
/// the run (and any process it forks) is stopped after that long and the status is 124.
inline CliResult runCli(const std::string& args, int timeout_seconds = 0) {
  return runCliBehind(
      timeout_seconds > 0 ? "timeout -k 5 " + std::to_string(timeout_seconds) + " " : std::string(), args);
}

/// Runs `seif <args>` and sends it `signal` (a name: INT, TERM) after `seconds`; the status
/// is the one seif exits with (a second signal after 30 s more kills it: status 137).
inline CliResult runCliSignalled(const std::string& args, const std::string& signal, double seconds) {
  return runCliBehind("timeout --preserve-status -k 30 -s " + signal + " " + std::to_string(seconds) + " ", args);
}

}  // namespace seif::test
