// `seif bench` as one call (runBench in include/seif/eval/bench.hpp): the cases in forked
// children, the budget's estimates, the targets and bench.json.
#include <seif/core/errors.hpp>
#include <seif/eval/bench.hpp>
#include <seif/sim/world.hpp>

#include "eval/parallel.hpp"
#include "json_fields.hpp"
#include "text_format.hpp"

#include <Eigen/Core>
#include <csignal>
#include <fcntl.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace seif {
namespace {

constexpr int kCalibrationLandmarks = 100;  // a dense filter's first case beyond 2x this is
                                            // extrapolated from a calibration run at this N

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
          {"run_seconds", m.run_seconds},
          {"association", m.association},
          {"scans", m.scans},
          {"us_association_per_scan_median", m.us_association_per_scan_median},
          {"us_association_per_scan_p90", m.us_association_per_scan_p90},
          {"us_association_per_scan_max", m.us_association_per_scan_max},
          {"association_scored", m.association_scored},
          {"association_correct", m.association_correct},
          {"landmarks_final", m.landmarks_final}};
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
  m.association = j.at("association").get<std::string>();
  m.scans = j.at("scans").get<std::size_t>();
  m.us_association_per_scan_median = j.at("us_association_per_scan_median").get<double>();
  m.us_association_per_scan_p90 = j.at("us_association_per_scan_p90").get<double>();
  m.us_association_per_scan_max = j.at("us_association_per_scan_max").get<double>();
  m.association_scored = j.at("association_scored").get<std::size_t>();
  m.association_correct = j.at("association_correct").get<std::size_t>();
  m.landmarks_final = j.at("landmarks_final").get<std::size_t>();
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
  if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("bench: pipe() failed");
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("bench: fork() failed");
  if (pid == 0) {  // the child: measure, write, leave without running the parent's atexit
    close(fds[0]);
    // The caller's handlers (an embedding interpreter's, say) would keep the alarm and
    // Ctrl-C from ending the child.
    for (int sig : {SIGALRM, SIGINT, SIGTERM}) std::signal(sig, SIG_DFL);
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
/// about repeat x window steps, but at most kMaxRepeatFactor times as often, and no more
/// runs start once the case has taken `max_seconds` (after `repeat` runs). All medians are
/// kept for bench.json; the peak memory is the largest of all runs. Once `stop` is set no
/// more runs start.
struct Repeated {
  Outcome best;
  std::vector<double> medians;
};
constexpr int kMaxRepeatFactor = 20;
Repeated runRepeated(const BenchCase& c, int repeat, unsigned timeout_seconds, double max_seconds,
                     const std::atomic<bool>* stop) {
  Repeated r;
  double peak = 0.0;
  int runs = repeat;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < runs; ++i) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (i >= repeat && elapsed > max_seconds) break;
    if (i > 0 && stopRequested(stop)) break;  // the runs so far
    Outcome o = runIsolated(c, timeout_seconds);
    if (!o.measurement) {
      if (!r.best.measurement) r.best = o;
      break;
    }
    if (i == 0 && o.measurement->steps > 0) {
      const auto timed = static_cast<int>(o.measurement->steps);
      runs = repeat * std::min(kMaxRepeatFactor, (c.window + timed - 1) / timed);
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

/// The reason to skip a case, or nothing when its estimate is within the budget. The time
/// budget is for all `runs` of the case.
std::optional<std::string> skipReason(const std::string& filter, int n, const BenchEstimate& e, int runs,
                                      const BenchRequest& args) {
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
    memory = "3 x " + dim + "^2 doubles = " + formatted("%.2g", e.matrix_bytes / 1e9) + " GB";
  } else {
    memory = "an estimated " + formatted("%.2g", gb) + " GB";
  }
  memory += too_big ? " (budget " + formatted("%g", args.max_memory_gb) + " GB)" : "";
  const std::string time = "~O(N^" + formatted("%.2g", e.exponent) + ") per step: estimated " +
                           formatted("%.2g", e.seconds_per_step) + " s/step, " + formatted("%.2g", e.build_seconds) +
                           " s to map them" +
                           (runs > 1 ? ", x" + std::to_string(runs) + " runs" : std::string()) +
                           (too_slow ? " (budget " + formatted("%g", args.max_seconds) + " s)" : "");
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

nlohmann::json estimateJson(const BenchEstimate& e) {
  return {{"seconds_per_step", e.seconds_per_step},
          {"build_seconds", e.build_seconds},
          {"gb", e.bytes / 1e9},
          {"exponent", e.exponent}};
}

const BenchMeasurement* find(const std::vector<BenchMeasurement>& all, const std::string& filter, int n) {
  for (const BenchMeasurement& m : all) {
    if (m.filter == filter && m.landmarks == n) return &m;
  }
  return nullptr;
}

}  // namespace

BenchReport runBench(const BenchRequest& request, const std::function<void(const BenchRow&)>& row_done) {
  if (request.filters.empty()) throw InvalidArgument("bench: no filter to measure");
  for (const std::string& f : request.filters) (void)stepCostExponent(f);  // an unknown one, before any work
  if (request.landmarks.empty()) throw InvalidArgument("bench: no map size to measure");
  for (int n : request.landmarks) {
    if (n < 1) throw InvalidArgument("bench: the number of landmarks must be >= 1 (got " + std::to_string(n) + ")");
  }
  if (request.window < 1) throw InvalidArgument("bench: the window must be >= 1 step");
  if (request.repeat < 1) throw InvalidArgument("bench: repeat must be >= 1 run per case");
  if (!(request.max_seconds > 0.0 && std::isfinite(request.max_seconds)) ||
      !(request.max_memory_gb > 0.0 && std::isfinite(request.max_memory_gb))) {
    throw InvalidArgument("bench: the time and memory budgets must be positive and finite");
  }
  BenchReport report;
  report.request = request;
  report.request.stop = nullptr;  // the request's flag need not outlive the call
  BenchRequest& args = report.request;
  std::sort(args.landmarks.begin(), args.landmarks.end());
  args.landmarks.erase(std::unique(args.landmarks.begin(), args.landmarks.end()), args.landmarks.end());
  args.filters.clear();
  for (const std::string& f : request.filters) {
    if (std::find(args.filters.begin(), args.filters.end(), f) == args.filters.end()) args.filters.push_back(f);
  }
  // A child that runs far past its estimate is stopped (the estimate was wrong).
  const auto timeout = static_cast<unsigned>(std::min(86400.0, 10.0 * args.max_seconds + 60.0));
  std::vector<BenchMeasurement> measured;
  for (const std::string& filter : args.filters) {
    std::vector<BenchPoint> points;
    for (const int n : args.landmarks) {
      if (stopRequested(request.stop)) {
        report.interrupted = true;
        break;
      }
      BenchCase c;
      c.filter = filter;
      c.landmarks = n;
      c.window = args.window;
      c.seed = args.world_seed;
      c.seif = args.seif;
      c.linearization = args.linearization;
      c.iterations = args.iterations;
      c.association = args.association;
      BenchRow row;
      row.filter = filter;
      row.landmarks = n;
      const double steps = presetConfig(WorldPreset::Corridor, n, 0, args.world_seed).steps;
      if (points.empty() && n > 2 * kCalibrationLandmarks) {
        BenchCase cal = c;
        cal.landmarks = kCalibrationLandmarks;
        const Outcome o = runIsolated(cal, timeout);
        if (!o.measurement && stopRequested(request.stop)) {  // its child ended by the same Ctrl-C
          report.interrupted = true;
          break;
        }
        if (!o.measurement) throw NumericError("bench: calibration of " + filter + " failed: " + o.error);
        points.push_back(pointOf(*o.measurement));
        report.calibration.push_back(*o.measurement);
      }
      if (!points.empty()) {
        row.estimate = estimateBenchCase(filter, n, steps, points);
        const int timed = static_cast<int>(std::min<double>(args.window, std::max(1.0, std::floor(steps / 2))));
        const int runs = args.repeat * std::min(kMaxRepeatFactor, (args.window + timed - 1) / timed);
        if (auto why = skipReason(filter, n, *row.estimate, runs, args)) row.skipped = *why;
      }
      if (row.skipped.empty()) {
        Repeated rep = runRepeated(c, args.repeat, timeout, args.max_seconds, request.stop);
        if (!rep.best.measurement && stopRequested(request.stop)) {  // its child ended by the same Ctrl-C
          report.interrupted = true;
          break;
        }
        row.repeat_medians = std::move(rep.medians);
        row.measurement = rep.best.measurement;
        if (row.measurement) {
          measured.push_back(*row.measurement);
          points.push_back(pointOf(*row.measurement));
        } else {
          row.skipped = "failed: " + rep.best.error;
        }
      }
      if (row_done) row_done(row);
      report.rows.push_back(std::move(row));
    }
  }
  report.targets = benchTargets(measured);
  return report;
}

BenchTargets benchTargets(const std::vector<BenchMeasurement>& all) {
  BenchTargets t;
  std::vector<const BenchMeasurement*> seif;
  for (const BenchMeasurement& m : all) {
    if (m.filter == "seif") seif.push_back(&m);
  }
  if (seif.size() >= 2) {
    const BenchMeasurement& lo = *seif.front();
    const BenchMeasurement& hi = *seif.back();
    const double ratio = hi.us_per_step_median / lo.us_per_step_median;
    t.seif_growth = BenchTargets::Growth{lo.landmarks, hi.landmarks, lo.us_per_step_median, hi.us_per_step_median,
                                         ratio, ratio <= 1.5};
    if (lo.scans > 0 && hi.scans > 0) {
      const double a = hi.us_association_per_scan_median / lo.us_association_per_scan_median;
      t.seif_association_growth = BenchTargets::Growth{lo.landmarks, hi.landmarks, lo.us_association_per_scan_median,
                                                       hi.us_association_per_scan_median, a, a <= 1.5};
    }
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
    t.ekf_over_seif = BenchTargets::Speedup{common, ekf.us_per_step_median, s.us_per_step_median, ratio, ratio >= 100.0};
  }
  for (const BenchMeasurement* m : seif) {
    const double b = m->filter_peak_mb * 1024.0 * 1024.0 / static_cast<double>(std::max<std::size_t>(1, m->map_last));
    t.seif_bytes_per_landmark.emplace_back(m->landmarks, b);
  }
  return t;
}

std::string benchJson(const BenchReport& report) {
  const BenchRequest& args = report.request;
  nlohmann::json results = nlohmann::json::array();
  for (const BenchRow& row : report.rows) {
    nlohmann::json j;
    if (row.measurement) {
      j = measurementJson(*row.measurement);
      j["repeat_medians"] = row.repeat_medians;
    } else {
      j = {{"filter", row.filter}, {"landmarks", row.landmarks}, {"us_per_step_median", nullptr},
           {"us_per_step_p90", nullptr}, {"peak_rss_mb", nullptr}, {"steps", 0}, {"skipped", row.skipped}};
    }
    if (row.estimate && (row.measurement || row.skipped.rfind("failed: ", 0) != 0)) j["estimate"] = estimateJson(*row.estimate);
    results.push_back(std::move(j));
  }
  nlohmann::json calibration = nlohmann::json::array();
  for (const BenchMeasurement& m : report.calibration) calibration.push_back(measurementJson(m));
  nlohmann::json targets = nlohmann::json::object();
  const BenchTargets& t = report.targets;
  if (t.seif_growth) {
    targets["seif_growth"] = {{"from_landmarks", t.seif_growth->from_landmarks},
                              {"to_landmarks", t.seif_growth->to_landmarks},
                              {"ratio", t.seif_growth->ratio},
                              {"target", "<= 1.5"},
                              {"met", t.seif_growth->met}};
  }
  if (t.seif_association_growth) {
    const auto& g = *t.seif_association_growth;
    targets["seif_association_growth"] = {{"from_landmarks", g.from_landmarks},
                                          {"to_landmarks", g.to_landmarks},
                                          {"ratio", g.ratio},
                                          {"target", "<= 1.5"},
                                          {"met", g.met}};
  }
  if (t.ekf_over_seif) {
    targets["ekf_over_seif"] = {{"landmarks", t.ekf_over_seif->landmarks},
                                {"ratio", t.ekf_over_seif->ratio},
                                {"target", ">= 100"},
                                {"met", t.ekf_over_seif->met}};
  }
  if (!t.seif_bytes_per_landmark.empty()) {
    nlohmann::json per = nlohmann::json::array();
    for (const auto& [n, bytes] : t.seif_bytes_per_landmark) per.push_back({{"landmarks", n}, {"bytes_per_landmark", bytes}});
    targets["seif_bytes_per_landmark"] = per;
  }
  const nlohmann::json config = {{"world", "corridor"},
                                 {"world_seed", args.world_seed},
                                 {"window", args.window},
                                 {"repeat", args.repeat},
                                 {"filters", args.filters},
                                 {"landmarks", args.landmarks},
                                 {"max_seconds", args.max_seconds},
                                 {"max_memory_gb", args.max_memory_gb},
                                 {"linearization", linearizationName(args.linearization)},
                                 {"iterations", args.iterations},
                                 {"seif", toJson(args.seif)},
                                 {"association", associationMethodName(args.association.method)},
                                 {"gate_marginal", gateMarginalName(args.association.marginal)}};
  const nlohmann::json doc = {{"machine", machineJson()},
                              {"config", config},
                              {"results", results},
                              {"calibration", calibration},
                              {"targets", targets},
                              {"interrupted", report.interrupted}};
  return doc.dump(2) + "\n";
}

}  // namespace seif
