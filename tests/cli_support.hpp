#pragma once
// Runs the `seif` executable as a user would and captures what it prints.
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

/// Runs `seif <args>` (args are passed to the shell as written). With `timeout_seconds` > 0
/// the run (and any process it forks) is stopped after that long and the status is 124.
inline CliResult runCli(const std::string& args, int timeout_seconds = 0) {
  const auto dir = scratchDir("cli");
  const std::string limit =
      timeout_seconds > 0 ? "timeout -k 5 " + std::to_string(timeout_seconds) + " " : std::string();
  const std::string cmd = limit + std::string(SEIF_CLI_PATH) + " " + args + " >" +
                          (dir / "out").string() + " 2>" + (dir / "err").string() + " </dev/null";
  const auto start = std::chrono::steady_clock::now();
  const int raw = std::system(cmd.c_str());
  CliResult r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(dir / "out");
  r.err = slurp(dir / "err");
  return r;
}

}  // namespace seif::test
