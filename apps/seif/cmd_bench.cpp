// seif bench: time per step and peak memory of each filter once its map holds N landmarks
// (issue 3, "Benchmark"); writes OUT/bench.json and OUT/bench.png (scripts/figures/bench.py).
// Every (filter, N) runs in a forked child, so one case's peak memory cannot inflate the
// next; a case whose estimated memory or time exceeds the budget is skipped, with the reason.
#include "commands.hpp"
#include "options.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/bench.hpp>
#include <seif/sim/world.hpp>

#include <Eigen/Core>
#include <csignal>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace seif::cli {
namespace {

constexpr int kCalibrationLandmarks = 100;  // a dense filter's first case beyond 2x this is
                                            // extrapolated from a calibration run at this N

struct BenchArgs {
  std::vector<std::string> filters = {"ekf", "eif", "seif"};
  std::vector<int> landmarks = {100, 1000, 10000, 100000, 1000000};
  int window = 200;
  int repeat = 3;
  std::string out = "out/bench";
  std::uint64_t world_seed = 1;
  double max_seconds = 120.0;
  double max_memory_gb = 4.0;
  bool no_figure = false;
  SeifFlags seif;
};

// ---------------------------------------------------------------- machine --------------

std::string firstField(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key, 0) != 0) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const auto begin = line.find_first_not_of(" \t", colon + 1);
    return begin == std::string::npos ? std::string() : line.substr(begin);
  }
  return {};
}

nlohmann::json machineJson() {
  nlohmann::json m;
  m["cpu_model"] = firstField("/proc/cpuinfo", "model name");
  m["cores"] = std::thread::hardware_concurrency();
  const std::string mem = firstField("/proc/meminfo", "MemTotal");  // "24576000 kB"
  m["memory_gb"] = mem.empty() ? nlohmann::json(nullptr)
                               : nlohmann::json(std::round(std::stod(mem) / (1024.0 * 1024.0) * 10.0) / 10.0);
  utsname u{};
  if (uname(&u) == 0) m["kernel"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
#if defined(__clang__)
  m["compiler"] = std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
  m["compiler"] = std::string("gcc ") + __VERSION__;
#endif
#if defined(NDEBUG)
  m["build"] = "optimised (NDEBUG)";
#else
  m["build"] = "debug (asserts on): times are not representative";
#endif
  m["eigen"] = std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
               std::to_string(EIGEN_MINOR_VERSION);
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  m["date"] = date;
  return m;
}

// ---------------------------------------------------------------- one case -------------

nlohmann::json measurementJson(const BenchMeasurement& m) {
  const double mapped = static_cast<double>(std::max<std::size_t>(1, m.map_last));
  return {{"filter", m.filter},
          {"landmarks", m.landmarks},
          {"us_per_step_median", m.us_per_step_median},
          {"us_per_step_p90", m.us_per_step_p90},
          {"us_per_step_mean", m.us_per_step_mean},
          {"us_per_step_max", m.us_per_step_max},
          {"peak_rss_mb", m.peak_rss_mb},
          {"steps", m.steps},
          {"steps_run", m.steps_run},
          {"map_landmarks_window", {m.map_first, m.map_last}},
          {"observations_per_step", m.observations_per_step},
          {"filter_peak_mb", m.filter_peak_mb},
          {"filter_final_mb", m.filter_final_mb},
          {"mb_per_landmark", m.filter_peak_mb / mapped},
          {"data_rss_mb", m.data_rss_mb},
          {"sim_peak_mb", m.sim_peak_mb},
          {"base_rss_mb", m.base_rss_mb},
          {"peak_reset", m.peak_reset},
          {"max_blocks_touched", m.max_blocks_touched},
          {"max_robot_links", m.max_robot_links},
          {"sim_seconds", m.sim_seconds},
          {"run_seconds", m.run_seconds}};
}

BenchMeasurement measurementFromJson(const nlohmann::json& j) {
  BenchMeasurement m;
  m.filter = j.at("filter").get<std::string>();
  m.landmarks = j.at("landmarks").get<int>();
  m.us_per_step_median = j.at("us_per_step_median").get<double>();
  m.us_per_step_p90 = j.at("us_per_step_p90").get<double>();
  m.us_per_step_mean = j.at("us_per_step_mean").get<double>();
  m.us_per_step_max = j.at("us_per_step_max").get<double>();
  m.peak_rss_mb = j.at("peak_rss_mb").get<double>();
  m.steps = j.at("steps").get<std::size_t>();
  m.steps_run = j.at("steps_run").get<std::size_t>();
  m.map_first = j.at("map_landmarks_window").at(0).get<std::size_t>();
  m.map_last = j.at("map_landmarks_window").at(1).get<std::size_t>();
  m.observations_per_step = j.at("observations_per_step").get<double>();
  m.filter_peak_mb = j.at("filter_peak_mb").get<double>();
  m.filter_final_mb = j.at("filter_final_mb").get<double>();
  m.data_rss_mb = j.at("data_rss_mb").get<double>();
  m.sim_peak_mb = j.at("sim_peak_mb").get<double>();
  m.base_rss_mb = j.at("base_rss_mb").get<double>();
  m.peak_reset = j.at("peak_reset").get<bool>();
  m.max_blocks_touched = j.at("max_blocks_touched").get<std::size_t>();
  m.max_robot_links = j.at("max_robot_links").get<std::size_t>();
  m.sim_seconds = j.at("sim_seconds").get<double>();
  m.run_seconds = j.at("run_seconds").get<double>();
  return m;
}

struct Outcome {
  std::optional<BenchMeasurement> measurement;
  std::string error;  // when there is no measurement
};

/// Runs one case in a forked child that sends its measurement back as JSON through a pipe.
/// The child is killed by SIGALRM after `timeout_seconds`.
Outcome runIsolated(const BenchCase& c, unsigned timeout_seconds) {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("bench: pipe() failed");
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("bench: fork() failed");
  if (pid == 0) {  // the child: measure, write, leave without running the parent's atexit
    close(fds[0]);
    alarm(timeout_seconds);
    std::string payload;
    int code = 0;
    try {
      payload = measurementJson(runBenchCase(c)).dump();
    } catch (const std::exception& e) {
      payload = nlohmann::json{{"error", e.what()}}.dump();
      code = 3;
    }
    const char* p = payload.data();
    std::size_t left = payload.size();
    while (left > 0) {
      const ssize_t w = write(fds[1], p, left);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) _exit(4);
      p += w;
      left -= static_cast<std::size_t>(w);
    }
    close(fds[1]);
    _exit(code);
  }
  close(fds[1]);
  std::string payload;
  char buf[4096];
  for (;;) {
    const ssize_t r = read(fds[0], buf, sizeof buf);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    payload.append(buf, static_cast<std::size_t>(r));
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  Outcome o;
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    o.error = sig == SIGALRM   ? "timed out after " + std::to_string(timeout_seconds) + " s"
              : sig == SIGKILL ? "killed (SIGKILL: out of memory?)"
                               : "killed by signal " + std::to_string(sig);
    return o;
  }
  try {
    const nlohmann::json j = nlohmann::json::parse(payload);
    if (j.contains("error")) {
      o.error = j.at("error").get<std::string>();
    } else {
      o.measurement = measurementFromJson(j);
    }
  } catch (const std::exception&) {
    o.error = "the benchmark child exited with status " + std::to_string(WEXITSTATUS(status)) +
              " without a result";
  }
  return o;
}

/// Runs a case `repeat` times, each in its own child, and keeps the run with the lowest
/// median: interference from other processes only ever slows a run down, so the fastest
/// run is the closest to the filter's own cost. A case whose corridor is too short for the
/// whole window (N < 2 window) runs proportionally more often, so that every case times
/// about repeat x window steps. All medians are kept for bench.json; the peak memory is the
/// largest of all runs.
struct Repeated {
  Outcome best;
  std::vector<double> medians;
};
Repeated runRepeated(const BenchCase& c, int repeat, unsigned timeout_seconds) {
  Repeated r;
  double peak = 0.0;
  int runs = repeat;
  for (int i = 0; i < runs; ++i) {
    Outcome o = runIsolated(c, timeout_seconds);
    if (!o.measurement) {
      if (!r.best.measurement) r.best = o;
      break;
    }
    if (i == 0 && o.measurement->steps > 0) {
      const auto timed = static_cast<int>(o.measurement->steps);
      runs = repeat * ((c.window + timed - 1) / timed);
    }
    r.medians.push_back(o.measurement->us_per_step_median);
    peak = std::max(peak, o.measurement->peak_rss_mb);
    if (!r.best.measurement || o.measurement->us_per_step_median < r.best.measurement->us_per_step_median) {
      r.best = o;
    }
  }
  if (r.best.measurement) r.best.measurement->peak_rss_mb = peak;
  return r;
}

// ---------------------------------------------------------------- skipping -------------

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

/// The reason to skip a case, or nothing when its estimate is within the budget. The time
/// budget is for all `runs` of the case.
std::optional<std::string> skipReason(const std::string& filter, int n, const BenchEstimate& e, int runs,
                                      const BenchArgs& args) {
  const double gb = e.bytes / 1e9;
  const bool too_big = gb > args.max_memory_gb;
  const bool too_slow = runs * e.build_seconds > args.max_seconds;
  if (!too_big && !too_slow) return std::nullopt;
  const std::string N = std::to_string(n);
  std::string what;
  if (filter == "ekf") {
    what = "dense O(N^2) covariance of " + N + " landmarks";
  } else if (filter == "eif") {
    what = "dense O(N^2) information matrix of " + N + " landmarks, factored (O(N^3)) every update,";
  } else {
    what = "the SEIF over " + N + " landmarks";
  }
  std::string memory;
  if (e.matrix_bytes > 0.0) {
    const std::string dim = std::to_string(3 + 2 * static_cast<long long>(n));
    memory = "3 x " + dim + "^2 doubles = " + fmt("%.2g", e.matrix_bytes / 1e9) + " GB";
  } else {
    memory = "an estimated " + fmt("%.2g", gb) + " GB";
  }
  memory += too_big ? " (budget " + fmt("%g", args.max_memory_gb) + " GB)" : "";
  const std::string time = "~O(N^" + fmt("%.2g", e.exponent) + ") per step: estimated " +
                           fmt("%.2g", e.seconds_per_step) + " s/step, " + fmt("%.2g", e.build_seconds) +
                           " s to map them" +
                           (runs > 1 ? ", x" + std::to_string(runs) + " runs" : std::string()) +
                           (too_slow ? " (budget " + fmt("%g", args.max_seconds) + " s)" : "");
  return what + " needs " + memory + " and " + time;
}

BenchPoint pointOf(const BenchMeasurement& m) {
  BenchPoint p;
  // The window's median belongs to the map size in the middle of the window.
  p.landmarks = 0.5 * static_cast<double>(m.map_first + m.map_last);
  p.seconds_per_step = 1e-6 * m.us_per_step_median;
  p.filter_bytes = m.peak_reset ? m.filter_peak_mb * 1024.0 * 1024.0 : 0.0;
  p.data_bytes = std::max(0.0, m.sim_peak_mb - m.base_rss_mb) * 1024.0 * 1024.0;
  p.steps = static_cast<double>(m.steps_run);
  return p;
}

// ---------------------------------------------------------------- output ---------------

void printHeader() {
  std::printf("%-6s %9s %9s %6s %12s %12s %10s %10s %10s\n", "filter", "N", "mapped", "steps",
              "median us", "p90 us", "peak MB", "filter MB", "B/landmark");
}

void printRow(const BenchMeasurement& m) {
  const double per = m.filter_peak_mb * 1024.0 * 1024.0 / static_cast<double>(std::max<std::size_t>(1, m.map_last));
  std::printf("%-6s %9d %9zu %6zu %12.1f %12.1f %10.1f %10.1f %10.0f\n", m.filter.c_str(), m.landmarks,
              m.map_last, m.steps, m.us_per_step_median, m.us_per_step_p90, m.peak_rss_mb,
              m.filter_peak_mb, per);
  std::fflush(stdout);
}

void printSkipped(const std::string& filter, int n, const std::string& why) {
  std::printf("%-6s %9d   skipped: %s\n", filter.c_str(), n, why.c_str());
  std::fflush(stdout);
}

const BenchMeasurement* find(const std::vector<BenchMeasurement>& all, const std::string& filter, int n) {
  for (const BenchMeasurement& m : all) {
    if (m.filter == filter && m.landmarks == n) return &m;
  }
  return nullptr;
}

/// The targets, from what was measured: SEIF median at the largest N within 1.5x
/// its median at the smallest; SEIF at least 100x faster than the EKF at 1000 landmarks
/// (else at the largest N both ran).
nlohmann::json targets(const std::vector<BenchMeasurement>& all) {
  nlohmann::json t = nlohmann::json::object();
  std::vector<const BenchMeasurement*> seif;
  for (const BenchMeasurement& m : all) {
    if (m.filter == "seif") seif.push_back(&m);
  }
  if (seif.size() >= 2) {
    const BenchMeasurement& lo = *seif.front();
    const BenchMeasurement& hi = *seif.back();
    const double ratio = hi.us_per_step_median / lo.us_per_step_median;
    t["seif_growth"] = {{"from_landmarks", lo.landmarks},
                        {"to_landmarks", hi.landmarks},
                        {"ratio", ratio},
                        {"target", "<= 1.5"},
                        {"met", ratio <= 1.5}};
    std::printf("SEIF median at N=%d / at N=%d: %.1f / %.1f us = %.2fx (target <= 1.5x): %s\n",
                hi.landmarks, lo.landmarks, hi.us_per_step_median, lo.us_per_step_median, ratio,
                ratio <= 1.5 ? "met" : "NOT met");
  }
  int common = 0;
  for (const BenchMeasurement& m : all) {
    if (m.filter == "ekf" && find(all, "seif", m.landmarks)) common = std::max(common, m.landmarks);
  }
  if (find(all, "ekf", 1000) && find(all, "seif", 1000)) common = 1000;
  if (common > 0) {
    const BenchMeasurement& ekf = *find(all, "ekf", common);
    const BenchMeasurement& s = *find(all, "seif", common);
    const double ratio = ekf.us_per_step_median / s.us_per_step_median;
    t["ekf_over_seif"] = {{"landmarks", common}, {"ratio", ratio}, {"target", ">= 100"}, {"met", ratio >= 100.0}};
    std::printf("EKF / SEIF median at N=%d: %.1f / %.1f us = %.0fx (target >= 100x): %s\n", common,
                ekf.us_per_step_median, s.us_per_step_median, ratio, ratio >= 100.0 ? "met" : "NOT met");
  }
  if (!seif.empty()) {
    nlohmann::json per = nlohmann::json::array();
    std::printf("SEIF memory per landmark (filter peak / mapped):");
    for (const BenchMeasurement* m : seif) {
      const double b = m->filter_peak_mb * 1024.0 * 1024.0 / static_cast<double>(std::max<std::size_t>(1, m->map_last));
      per.push_back({{"landmarks", m->landmarks}, {"bytes_per_landmark", b}});
      std::printf(" %.0f B at N=%d;", b, m->landmarks);
    }
    std::printf("\n");
    t["seif_bytes_per_landmark"] = per;
  }
  return t;
}

// ---------------------------------------------------------------- the command ----------

void bench(const BenchArgs& args) {
  requireOutputFolder(args.out);
  std::vector<int> sizes = args.landmarks;
  std::sort(sizes.begin(), sizes.end());
  sizes.erase(std::unique(sizes.begin(), sizes.end()), sizes.end());
  std::vector<std::string> filters;
  for (const std::string& f : args.filters) {
    if (std::find(filters.begin(), filters.end(), f) == filters.end()) filters.push_back(f);
  }
  const SeifOptions seif_options = args.seif.resolve();
  const std::filesystem::path dir(args.out);
  // A child that runs far past its estimate is stopped (the estimate was wrong).
  const auto timeout = static_cast<unsigned>(std::min(86400.0, 10.0 * args.max_seconds + 60.0));

#if !defined(NDEBUG)
  std::printf("warning: this seif was built without NDEBUG (a debug build): times are not representative\n");
#endif
  std::printf("seif bench: corridor world (seed %llu), last %d steps timed, best of %d runs, "
              "budget %g s and %g GB per case\n",
              static_cast<unsigned long long>(args.world_seed), args.window, args.repeat,
              args.max_seconds, args.max_memory_gb);
  printHeader();

  nlohmann::json results = nlohmann::json::array();
  nlohmann::json calibration = nlohmann::json::array();
  std::vector<BenchMeasurement> measured;
  for (const std::string& filter : filters) {
    std::vector<BenchPoint> points;
    for (const int n : sizes) {
      BenchCase c;
      c.filter = filter;
      c.landmarks = n;
      c.window = args.window;
      c.seed = args.world_seed;
      c.seif = seif_options;
      const double steps = presetConfig(WorldPreset::Corridor, n, 0, args.world_seed).steps;
      if (points.empty() && n > 2 * kCalibrationLandmarks) {
        BenchCase cal = c;
        cal.landmarks = kCalibrationLandmarks;
        const Outcome o = runIsolated(cal, timeout);
        if (!o.measurement) throw NumericError("bench: calibration of " + filter + " failed: " + o.error);
        points.push_back(pointOf(*o.measurement));
        calibration.push_back(measurementJson(*o.measurement));
      }
      std::optional<BenchEstimate> estimate;
      if (!points.empty()) {
        estimate = estimateBenchCase(filter, n, steps, points);
        const int timed = static_cast<int>(std::min<double>(args.window, std::max(1.0, std::floor(steps / 2))));
        const int runs = args.repeat * ((args.window + timed - 1) / timed);
        if (auto why = skipReason(filter, n, *estimate, runs, args)) {
          results.push_back({{"filter", filter},
                             {"landmarks", n},
                             {"us_per_step_median", nullptr},
                             {"us_per_step_p90", nullptr},
                             {"peak_rss_mb", nullptr},
                             {"steps", 0},
                             {"skipped", *why},
                             {"estimate", {{"seconds_per_step", estimate->seconds_per_step},
                                           {"build_seconds", estimate->build_seconds},
                                           {"gb", estimate->bytes / 1e9},
                                           {"exponent", estimate->exponent}}}});
          printSkipped(filter, n, *why);
          continue;
        }
      }
      if (isatty(STDERR_FILENO)) std::fprintf(stderr, "  running %s with %d landmarks...\r", filter.c_str(), n);
      const Repeated rep = runRepeated(c, args.repeat, timeout);
      const Outcome& o = rep.best;
      if (isatty(STDERR_FILENO)) std::fprintf(stderr, "%60s\r", "");
      if (!o.measurement) {
        results.push_back({{"filter", filter}, {"landmarks", n}, {"us_per_step_median", nullptr},
                           {"us_per_step_p90", nullptr}, {"peak_rss_mb", nullptr}, {"steps", 0},
                           {"skipped", "failed: " + o.error}});
        printSkipped(filter, n, "failed: " + o.error);
        continue;
      }
      nlohmann::json row = measurementJson(*o.measurement);
      row["repeat_medians"] = rep.medians;
      if (estimate) {
        row["estimate"] = {{"seconds_per_step", estimate->seconds_per_step},
                           {"build_seconds", estimate->build_seconds},
                           {"gb", estimate->bytes / 1e9},
                           {"exponent", estimate->exponent}};
      }
      results.push_back(row);
      measured.push_back(*o.measurement);
      points.push_back(pointOf(*o.measurement));
      printRow(*o.measurement);
    }
  }

  nlohmann::json config = {{"world", "corridor"},
                           {"world_seed", args.world_seed},
                           {"window", args.window},
                           {"repeat", args.repeat},
                           {"filters", filters},
                           {"landmarks", sizes},
                           {"max_seconds", args.max_seconds},
                           {"max_memory_gb", args.max_memory_gb},
                           {"seif", toJson(seif_options)}};
  const nlohmann::json target = targets(measured);
  const nlohmann::json doc = {{"machine", machineJson()},
                              {"config", config},
                              {"results", results},
                              {"calibration", calibration},
                              {"targets", target}};
  const std::filesystem::path json = dir / "bench.json";
  writeJson(json.string(), doc);
  std::printf("wrote %s\n", json.string().c_str());
  if (args.no_figure) return;
  if (renderFigure("bench.py", {json.string(), (dir / "bench.png").string()})) {
    std::printf("wrote %s\n", (dir / "bench.png").string().c_str());
  }
}

}  // namespace

void addBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Time per step and peak memory of each filter once its map holds N landmarks.\n"
      "For each (filter, N): simulate the corridor world with N landmarks (about one new\n"
      "landmark per step), run the filter over the whole corridor and time the last --window\n"
      "steps (the map then holds N - window .. N landmarks); each case runs in its own process.\n"
      "A case whose estimated memory or time (extrapolated from the smaller cases) exceeds the\n"
      "budget is skipped and the reason recorded. Writes OUT/bench.json and OUT/bench.png\n"
      "(rendered by scripts/figures/bench.py with /usr/bin/python3 and matplotlib).");
  cmd->add_option("--filters", args->filters, "comma-separated filters: ekf, eif, seif")
      ->delimiter(',')
      ->check(CLI::IsMember({"ekf", "eif", "seif"}))
      ->capture_default_str();
  cmd->add_option("--landmarks", args->landmarks, "comma-separated map sizes N")
      ->delimiter(',')
      ->transform(integerIn(1, 100000000))
      ->capture_default_str();
  cmd->add_option("--window", args->window, "steps timed at the end of the corridor (at most half of them)")
      ->transform(integerIn(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--repeat", args->repeat,
                  "runs per case, each in its own process; the one with the lowest median is reported")
      ->transform(integerIn(1, 100))
      ->capture_default_str();
  cmd->add_option("--out", args->out, "output folder")->capture_default_str();
  cmd->add_option("--world-seed", args->world_seed, "seed of the simulated corridor")
      ->transform(seedValue())
      ->capture_default_str();
  cmd->add_option("--max-seconds", args->max_seconds,
                  "skip a case whose estimated run time exceeds this many seconds")
      ->check(positiveFinite())
      ->capture_default_str();
  cmd->add_option("--max-memory-gb", args->max_memory_gb,
                  "skip a case whose estimated peak memory exceeds this many GB")
      ->check(positiveFinite())
      ->capture_default_str();
  cmd->add_flag("--no-figure", args->no_figure, "do not render OUT/bench.png");
  args->seif.add(*cmd);
  cmd->callback([args] { bench(*args); });
}

}  // namespace seif::cli
