#include <seif/core/errors.hpp>
#include <seif/eval/bench.hpp>
#include <seif/eval/run.hpp>
#include <seif/eval/run_loop.hpp>
#include <seif/filters/factory.hpp>
#include <seif/sim/world.hpp>

#include <sys/resource.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

namespace seif {
namespace {

/// Returns freed heap memory to the kernel, so that RSS measures what is still in use.
void trimHeap() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

/// Times the steps from `first` on (the window) and reads the map and link counts there.
class WindowTimer : public RunObserver {
 public:
  WindowTimer(std::size_t first, BenchMeasurement& m, std::vector<double>& us, std::size_t& observations)
      : first_(first), m_(m), us_(us), observations_(observations) {}
  void onStart(const SlamFilter& filter, double) override {
    if (first_ == 0) m_.map_first = filter.landmarkIds().size();
  }
  void afterUpdate(const SlamFilter& filter, const Step& step, std::size_t k, double seconds) override {
    if (k + 1 == first_) m_.map_first = filter.landmarkIds().size();  // before the window's first step
    if (k < first_) return;
    us_.push_back(1e6 * seconds);
    observations_ += step.observations.size();
    m_.max_blocks_touched = std::max(m_.max_blocks_touched, filter.blocksTouched());
    m_.max_robot_links = std::max(m_.max_robot_links, filter.robotLinks());
  }

 private:
  std::size_t first_;
  BenchMeasurement& m_;
  std::vector<double>& us_;
  std::size_t& observations_;
};

}  // namespace

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double f = pos - static_cast<double>(lo);
  return (1.0 - f) * values[lo] + f * values[hi];
}

ProcessMemory processMemory() {
  ProcessMemory m;
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    std::istringstream s(line);
    std::string key;
    double kb = 0.0;
    s >> key >> kb;
    if (!s) continue;
    if (key == "VmRSS:") m.rss_mb = kb / 1024.0;
    if (key == "VmHWM:") m.peak_mb = kb / 1024.0;
  }
  if (m.peak_mb == 0.0) {
    rusage usage{};
    if (getrusage(RUSAGE_SELF, &usage) == 0) m.peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;
  }
  return m;
}

bool resetPeakMemory() {
  std::ofstream clear("/proc/self/clear_refs");
  if (!clear) return false;
  clear << "5" << std::flush;  // proc(5): "5" resets the peak resident set size
  return static_cast<bool>(clear);
}

BenchMeasurement runBenchCase(const BenchCase& c) {
  if (c.landmarks < 1) throw InvalidArgument("bench: the number of landmarks must be >= 1");
  if (c.window < 1) throw InvalidArgument("bench: the window must be >= 1 step");
  using Clock = std::chrono::steady_clock;
  BenchMeasurement m;
  m.filter = c.filter;
  m.landmarks = c.landmarks;

  m.base_rss_mb = processMemory().rss_mb;
  const auto t_sim = Clock::now();
  const WorldConfig world = presetConfig(WorldPreset::Corridor, c.landmarks, 0, c.seed);
  Dataset data = buildDataset(simulate(world));  // the log dies here
  const Pose2 start = startPose(data);
  data.groundtruth = {};  // keep only what the filter reads
  data.landmarks = {};
  trimHeap();
  m.sim_seconds = std::chrono::duration<double>(Clock::now() - t_sim).count();

  const FilterConfig config = paperFilterConfig(world.noise);
  const ProcessMemory before = processMemory();
  m.data_rss_mb = before.rss_mb;
  m.sim_peak_mb = before.peak_mb;
  m.peak_reset = resetPeakMemory();

  const std::size_t total = data.steps.size();
  const std::size_t window =
      std::min(static_cast<std::size_t>(c.window), std::max<std::size_t>(1, total / 2));
  const std::size_t first = total - std::min(window, total);
  std::vector<double> us;
  us.reserve(window);
  std::size_t observations = 0;

  FilterConfig filter_config = config;
  filter_config.linearization = c.linearization;
  filter_config.iterations = c.iterations;
  SeifOptions seif = c.seif;
  if (needsCovarianceBounds(c.association)) seif.bounds = true;
  auto filter = makeFilter(c.filter, start, filter_config, seif);
  WindowTimer timer(first, m, us, observations);
  // Association, timed per scan in the window (the filter's step time excludes it).
  std::optional<Associator> associator;
  std::vector<double> association_us;
  RunLoopOptions loop;
  m.association = std::string(associationMethodName(c.association.method));
  if (c.association.method != AssociationMethod::Known) {
    associator.emplace(c.association);
    association_us.reserve(window);
    loop.associate = [&](SlamFilter& f, const Step&, std::size_t k, std::vector<Observation>& z) {
      const bool scan = !z.empty();
      const auto t0 = Clock::now();
      associator->associate(f, k, z);
      if (k >= first && scan) association_us.push_back(1e6 * std::chrono::duration<double>(Clock::now() - t0).count());
    };
  }
  const auto t_run = Clock::now();
  try {
    runLoop(*filter, data, {&timer}, loop);
    if (associator) associator->finish(*filter);
  } catch (const std::exception& e) {
    throw NumericError(c.filter + " on the corridor of " + std::to_string(c.landmarks) + " landmarks: " + e.what());
  }
  m.run_seconds = std::chrono::duration<double>(Clock::now() - t_run).count();
  m.steps = us.size();
  m.steps_run = total;
  m.map_last = filter->landmarkIds().size();
  if (associator) {
    const AssociationCounts& counts = associator->counts();
    m.scans = association_us.size();
    m.us_association_per_scan_median = quantile(association_us, 0.5);
    m.us_association_per_scan_p90 = quantile(association_us, 0.9);
    m.us_association_per_scan_max = association_us.empty() ? 0.0 : *std::max_element(association_us.begin(), association_us.end());
    m.association_scored = counts.scored;
    m.association_correct = counts.correct;
    m.landmarks_final = counts.landmarks_final;
  }
  if (!us.empty()) {
    m.us_per_step_median = quantile(us, 0.5);
    m.us_per_step_p90 = quantile(us, 0.9);
    m.us_per_step_max = *std::max_element(us.begin(), us.end());
    double sum = 0.0;
    for (double v : us) sum += v;
    m.us_per_step_mean = sum / static_cast<double>(us.size());
    m.observations_per_step = static_cast<double>(observations) / static_cast<double>(us.size());
  }

  const ProcessMemory after = processMemory();
  m.peak_rss_mb = std::max(before.peak_mb, after.peak_mb);
  m.filter_peak_mb = std::max(0.0, after.peak_mb - m.data_rss_mb);
  m.filter_final_mb = std::max(0.0, after.rss_mb - m.data_rss_mb);
  return m;
}

// ---------------------------------------------------------------- cost model ----------

double stepCostExponent(std::string_view filter) {
  if (filter == "ekf") return 2.0;
  if (filter == "eif") return 3.0;
  if (filter == "seif") return 0.0;
  throw InvalidArgument("unknown filter '" + std::string(filter) + "' (expected ekf, eif or seif)");
}

double denseMatrixBytes(std::string_view filter, int landmarks) {
  if (stepCostExponent(filter) == 0.0) return 0.0;
  const double n = 3.0 + 2.0 * static_cast<double>(landmarks);
  return 3.0 * 8.0 * n * n;
}

BenchEstimate estimateBenchCase(std::string_view filter, int landmarks, double steps,
                                std::span<const BenchPoint> measured) {
  if (measured.empty()) throw InvalidArgument("estimateBenchCase: needs a measured case");
  BenchEstimate e;
  const double p0 = stepCostExponent(filter);
  const BenchPoint& a = measured.back();
  e.exponent = p0;
  if (measured.size() >= 2) {
    const BenchPoint& b = measured[measured.size() - 2];
    if (a.landmarks > b.landmarks && a.seconds_per_step > 0.0 && b.seconds_per_step > 0.0) {
      const double slope = std::log(a.seconds_per_step / b.seconds_per_step) / std::log(a.landmarks / b.landmarks);
      e.exponent = std::clamp(slope, p0, p0 + 1.0);
    }
  }
  const double n = static_cast<double>(landmarks);
  e.seconds_per_step = a.seconds_per_step * std::pow(n / std::max(1.0, a.landmarks), e.exponent);
  e.build_seconds = steps * e.seconds_per_step / (e.exponent + 1.0);
  e.matrix_bytes = denseMatrixBytes(filter, landmarks);
  // Memory of a sparse filter: the marginal bytes per landmark between the last two measured
  // cases (fixed overheads cancel), else the last case's average (conservative at small N).
  double per_landmark = a.filter_bytes > 0.0 ? a.filter_bytes / std::max(1.0, a.landmarks) : 1024.0;
  if (measured.size() >= 2) {
    const BenchPoint& b = measured[measured.size() - 2];
    if (a.landmarks > b.landmarks && a.filter_bytes > b.filter_bytes && b.filter_bytes > 0.0) {
      per_landmark = (a.filter_bytes - b.filter_bytes) / (a.landmarks - b.landmarks);
    }
  }
  const double filter_bytes = e.matrix_bytes > 0.0 ? e.matrix_bytes : per_landmark * n;
  const double data_bytes =
      a.data_bytes > 0.0 && a.steps >= 1e4 ? a.data_bytes / a.steps * steps : 1024.0 * steps;
  e.bytes = filter_bytes + data_bytes;
  return e;
}

}  // namespace seif
