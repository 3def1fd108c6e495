#include "options.hpp"

#include <seif/core/errors.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace seif::cli {

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
  auto positive = CLI::PositiveNumber;
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
  // Information filters need a positive measurement noise; zero control noise is fine.
  if (!(n.sigma_range > 0) || !(n.sigma_bearing > 0)) {
    throw std::invalid_argument("measurement noise must be positive (--sigma-range, --sigma-bearing)");
  }
  return n;
}

void SeifFlags::add(CLI::App& cmd) {
  cmd.add_option("--active", active,
                 "SEIF: theta_x, landmarks kept linked to the robot (the paper: 6)")
      ->check(CLI::Range(1, 39))
      ->capture_default_str();
  cmd.add_option("--relax", relax,
                 "SEIF: K, landmarks relaxed per step besides the robot and the active ones")
      ->check(CLI::NonNegativeNumber)
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
  const std::filesystem::path p(file);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
  std::ofstream out(p);
  out << j.dump(2) << "\n";
  if (!out) throw DataError(file, 0, "write failed");
}

}  // namespace seif::cli
