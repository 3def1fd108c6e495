#include "options.hpp"

#include <seif/core/errors.hpp>
#include <seif/filters/information_ops.hpp>
#include <seif/io/atomic_file.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>

namespace seif::cli {

namespace {

/// `text` without one leading '+' (std::from_chars accepts '-' only).
std::string_view withoutPlus(const std::string& text) {
  std::string_view s(text);
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  return s;
}

/// The whole of `text` as a T (std::from_chars: decimal, no spaces), or nothing.
template <typename T>
std::optional<T> parseAll(const std::string& text) {
  const std::string_view s = withoutPlus(text);
  T value{};
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return value;
}

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

bool isPositiveFinite(double v) { return std::isfinite(v) && v > 0.0; }

CLI::Validator positiveFinite() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        const auto v = parseAll<double>(input);
        if (v && isPositiveFinite(*v)) return {};
        return "must be finite and > 0, found " + input;
      },
      "FINITE > 0");
}

CLI::Validator integerIn(long long lo, long long hi) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& input) -> std::string {
        const auto v = parseAll<long long>(input);
        if (!v || *v < lo || *v > hi) return "must be an integer in " + range + ", found " + input;
        input = std::to_string(*v);  // canonical: CLI11 would read 010 as octal
        return {};
      },
      range);
}

CLI::Validator seedValue() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        // from_chars reads no sign into an unsigned type: "-1" is refused, not wrapped.
        const auto v = parseAll<std::uint64_t>(input);
        if (!v) return "must be an integer in [0, " + std::to_string(UINT64_MAX) + "], found " + input;
        input = std::to_string(*v);
        return {};
      },
      "[0, 2^64-1]");
}

void requireOutputFolder(const std::string& out) {
  if (out.empty()) throw std::invalid_argument("--out: must not be empty");
  requireWritableDirectory(out);
}

NoiseModel mrclamDefaultNoise() {
  NoiseModel n;
  // Measured on dataset 6 against Vicon: 1-s means of the velocity commands differ from the
  // true velocities by 0.013 m/s and 0.038 rad/s (white per-step noise at ~67 Hz: sigma *
  // sqrt(0.015 s)); range residuals have a robust sd of 0.08-0.18 m with a heavy tail,
  // bearing residuals 0.006-0.012 rad. The values below were then chosen among a small grid
  // by the EKF's errors over the five robots (README, "MRCLAM").
  n.sigma_v = 0.05;
  n.sigma_w = 0.2;
  n.sigma_range = 0.2;
  n.sigma_bearing = 0.03;
  return n;
}

void NoiseFlags::add(CLI::App& cmd) {
  const CLI::Validator positive = positiveFinite();
  cmd.add_option("--sigma-v", sigma_v, "forward-velocity noise std [m/s]")->check(positive);
  cmd.add_option("--sigma-w", sigma_w, "rotational-velocity noise std [rad/s]")->check(positive);
  cmd.add_option("--sigma-range", sigma_range, "range noise std [m]")->check(positive);
  cmd.add_option("--sigma-bearing", sigma_bearing, "bearing noise std [rad]")->check(positive);
}

NoiseModel NoiseFlags::resolve(const std::optional<NoiseModel>& dataset_noise) const {
  NoiseModel n = dataset_noise.value_or(mrclamDefaultNoise());
  if (sigma_v) n.sigma_v = *sigma_v;
  if (sigma_w) n.sigma_w = *sigma_w;
  if (sigma_range) n.sigma_range = *sigma_range;
  if (sigma_bearing) n.sigma_bearing = *sigma_bearing;
  // The flags were checked as they were parsed; this covers the final values, whichever
  // their source (a flag set in code, the dataset's meta.json).
  const struct {
    const char* flag;
    const char* key;
    const std::optional<double>& given;
    double value;
  } sigmas[] = {{"--sigma-v", "sigma_v", sigma_v, n.sigma_v},
                {"--sigma-w", "sigma_w", sigma_w, n.sigma_w},
                {"--sigma-range", "sigma_range", sigma_range, n.sigma_range},
                {"--sigma-bearing", "sigma_bearing", sigma_bearing, n.sigma_bearing}};
  for (const auto& s : sigmas) {
    if (isPositiveFinite(s.value)) continue;
    const std::string rule = " must be finite and > 0, found " + number(s.value);
    if (s.given) throw std::invalid_argument(std::string(s.flag) + ":" + rule);
    throw ModelError(std::string("the dataset's noise ") + s.key + " (meta.json)" + rule);
  }
  return n;
}

void SeifFlags::add(CLI::App& cmd) {
  cmd.add_option("--active", active,
                 "SEIF: theta_x, landmarks kept linked to the robot (the paper: 6)")
      ->transform(integerIn(1, kMaxLocalLandmarks - 1))
      ->capture_default_str();
  cmd.add_option("--relax", relax,
                 "SEIF: K, landmarks relaxed per step besides the robot and the active ones "
                 "(at most every landmark once: K is capped at the map size)")
      ->transform(integerIn(0, INT_MAX))
      ->capture_default_str();
  cmd.add_option("--mean", mean,
                 "SEIF mean recovery: amortized (constant time) or exact (sparse Cholesky each step)")
      ->check(CLI::IsMember({"amortized", "exact"}))
      ->capture_default_str();
  cmd.add_option("--deactivate", deactivate,
                 "SEIF sparsification: deactivate the weakest-linked or the oldest-seen landmarks")
      ->check(CLI::IsMember({"weakest", "oldest"}))
      ->capture_default_str();
  cmd.add_option("--recovery", recovery,
                 "SEIF: relax the amortized mean before the measurement update (the book's order) "
                 "or after it; see docs/seif.md")
      ->check(CLI::IsMember({"after-update", "before-update"}))
      ->capture_default_str();
  cmd.add_option("--relax-order", relax_order,
                 "SEIF: the K relaxed landmarks are taken cyclically in map order, or drawn at random "
                 "(the paper; slower in huge maps: cache misses)")
      ->check(CLI::IsMember({"random", "cyclic"}))
      ->capture_default_str();
  cmd.add_option("--seed", seed, "SEIF: seed of the random choice of relaxed landmarks")
      ->transform(seedValue())
      ->capture_default_str();
}

SeifOptions SeifFlags::resolve() const {
  SeifOptions o;
  o.max_active = active;
  o.relax = relax;
  o.mean = SeifOptions::parseMean(mean);
  o.deactivate = SeifOptions::parseDeactivate(deactivate);
  o.recovery = SeifOptions::parseRecovery(recovery);
  o.relax_order = SeifOptions::parseRelaxOrder(relax_order);
  o.seed = seed;
  return o;
}

nlohmann::json toJson(const NoiseModel& n) {
  return {{"sigma_v", n.sigma_v},
          {"sigma_w", n.sigma_w},
          {"sigma_range", n.sigma_range},
          {"sigma_bearing", n.sigma_bearing}};
}

nlohmann::json toJson(const SeifOptions& o) {
  return {{"active", o.max_active},
          {"relax", o.relax},
          {"mean", o.mean == SeifOptions::Mean::Exact ? "exact" : "amortized"},
          {"deactivate", o.deactivate == SeifOptions::Deactivate::Oldest ? "oldest" : "weakest"},
          {"recovery", o.recovery == SeifOptions::Recovery::BeforeMeasurement ? "before-update" : "after-update"},
          {"relax_order", o.relax_order == SeifOptions::RelaxOrder::Cyclic ? "cyclic" : "random"},
          {"seed", o.seed}};
}

nlohmann::json toJson(const FilterStats& s) {
  return {{"landmarks", s.landmarks},
          {"links", s.links},
          {"robot_links", s.robot_links},
          {"max_landmark_links", s.max_landmark_links},
          {"blocks_touched", s.blocks_touched}};
}

Progress::Progress(std::string label) : label_(std::move(label)), tty_(isatty(STDERR_FILENO) != 0) {}

void Progress::operator()(std::size_t done, std::size_t total) {
  if (!tty_ || total == 0) return;
  const int width = 30;
  const int filled = static_cast<int>(width * done / total);
  std::fprintf(stderr, "\r%s [%.*s%*s] %3zu%%", label_.c_str(), filled,
               "##############################", width - filled, "", 100 * done / total);
  std::fflush(stderr);
  drawn_ = true;
}

Progress::~Progress() {
  if (drawn_) std::fprintf(stderr, "\n");
}

namespace {

/// Runs `argv` (argv[0] an absolute path) without a shell; its exit status, or -1.
int runProgram(std::vector<std::string> argv, bool quiet) {
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    if (quiet) {
      std::freopen("/dev/null", "w", stdout);
      std::freopen("/dev/null", "w", stderr);
    }
    std::vector<char*> cargs;
    for (std::string& a : argv) cargs.push_back(a.data());
    cargs.push_back(nullptr);
    execv(cargs[0], cargs.data());
    _exit(127);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

bool renderFigure(const std::string& script, const std::vector<std::string>& args) {
  const std::string python = "/usr/bin/python3";
  const std::string path = std::string(SEIF_FIGURE_SCRIPT_DIR) + "/figures/" + script;
  std::vector<std::string> argv = {python, path};
  argv.insert(argv.end(), args.begin(), args.end());
  std::string later;
  for (const std::string& a : argv) later += (later.empty() ? "" : " ") + a;
  if (access(python.c_str(), X_OK) != 0 || access(path.c_str(), R_OK) != 0 ||
      runProgram({python, "-c", "import matplotlib"}, true) != 0) {
    std::printf("figures: not rendered (needs %s with matplotlib: apt-get install "
                "python3-matplotlib); render later with: %s\n",
                python.c_str(), later.c_str());
    return false;
  }
  const int code = runProgram(argv, false);
  if (code != 0) {
    std::printf("figures: `%s` failed (exit %d)\n", later.c_str(), code);
    return false;
  }
  return true;
}

void writeJson(const std::string& file, const nlohmann::json& j) {
  writeFileAtomically(file, j.dump(2) + "\n");
}

}  // namespace seif::cli
