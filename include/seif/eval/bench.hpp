#pragma once
// The scaling benchmark behind `seif bench` (issue 3, "Benchmark"): time per step and memory
// of a filter once its map holds N landmarks, on the corridor world (about one new landmark
// per step, so a run of the whole corridor maps all N), and the cost model that decides
// which (filter, N) would not fit in memory or time.
//
// runBenchCase() measures one case in the calling process; runBench() runs the whole study,
// each case in a forked child so that the peak memory of one case does not leak into the next.
#include <seif/association/association.hpp>
#include <seif/filters/seif_options.hpp>
#include <seif/filters/slam_filter.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <utility>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace seif {

/// One (filter, N) of the benchmark.
struct BenchCase {
  std::string filter = "seif";  ///< "ekf" | "eif" | "seif"
  int landmarks = 1000;         ///< N: landmarks of the corridor world
  /// Steps timed: the last `window` steps of the corridor (at most half of its steps), when
  /// the map holds N - window .. N landmarks.
  int window = 200;
  std::uint64_t seed = 1;  ///< seed of the simulated world
  Linearization linearization = Linearization::Standard;
  int iterations = 1;
  SeifOptions seif;        ///< used when filter == "seif"
  /// known: the corridor's ids. nn | jcbb: the ids hidden, each scan associated (and timed)
  /// by an Associator with these options.
  AssociationOptions association;
};

/// What one case measured. Times in microseconds, memory in MiB (2^20 bytes).
struct BenchMeasurement {
  std::string filter;
  int landmarks = 0;
  std::size_t steps = 0;           ///< steps timed (the window)
  std::size_t steps_run = 0;       ///< steps run in all (the whole corridor)
  std::size_t map_first = 0;       ///< landmarks in the map before the window's first step
  std::size_t map_last = 0;        ///< landmarks in the map after the last step
  double us_per_step_median = 0.0;
  double us_per_step_p90 = 0.0;
  double us_per_step_mean = 0.0;
  double us_per_step_max = 0.0;
  double observations_per_step = 0.0;  ///< mean over the window
  double sim_seconds = 0.0;            ///< simulate + buildDataset
  double run_seconds = 0.0;            ///< all filter steps
  std::size_t max_blocks_touched = 0;  ///< over the window
  std::size_t max_robot_links = 0;     ///< over the window
  /// Peak RSS of the process over the whole case (simulator, dataset and filter).
  double peak_rss_mb = 0.0;
  /// RSS when the case started (the program itself), and the peak RSS while simulating and
  /// building the dataset (the log and the dataset both alive).
  double base_rss_mb = 0.0;
  double sim_peak_mb = 0.0;
  /// RSS with the dataset loaded, before the filter was built (the simulator's log freed).
  double data_rss_mb = 0.0;
  /// Peak RSS while the filter ran, minus data_rss_mb: the filter's own peak footprint,
  /// transient copies included. Meaningful only when peak_reset is true.
  double filter_peak_mb = 0.0;
  /// RSS after the last step, minus data_rss_mb: the filter's resident footprint.
  double filter_final_mb = 0.0;
  /// Whether the kernel let the peak be reset after the dataset was built
  /// (/proc/self/clear_refs, Linux >= 4.0); without it filter_peak_mb is not isolated.
  bool peak_reset = false;
  /// With association (BenchCase::association): its method, the window's scans (steps with
  /// observations), the time the Associator took per scan, and its score over the whole run
  /// (AssociationCounts: scored observations, correct, landmarks at the end).
  std::string association = "known";
  std::size_t scans = 0;
  double us_association_per_scan_median = 0.0;
  double us_association_per_scan_p90 = 0.0;
  double us_association_per_scan_max = 0.0;
  std::size_t association_scored = 0;
  std::size_t association_correct = 0;
  std::size_t landmarks_final = 0;
};

/// Simulates the corridor world with c.landmarks landmarks (presetConfig(Corridor, N, 0,
/// seed)), runs c.filter over all of its steps, each timed with steady_clock, and reports
/// the window (see BenchCase::window) and the memory. Throws what the filter throws.
BenchMeasurement runBenchCase(const BenchCase& c);

/// q-quantile (0 <= q <= 1) with linear interpolation between order statistics; 0 if empty.
double quantile(std::vector<double> values, double q);

/// This process's resident memory now and its peak (VmRSS, VmHWM of /proc/self/status),
/// in MiB; the peak falls back to getrusage() where /proc is missing.
struct ProcessMemory {
  double rss_mb = 0.0;
  double peak_mb = 0.0;
};
ProcessMemory processMemory();

/// Resets the peak (VmHWM) to the current RSS; false when the kernel does not allow it.
bool resetPeakMemory();

// ---------------------------------------------------------------- cost model ----------

/// How the cost of one step grows with the map: t(N) ~ N^exponent (EKF 2: the dense
/// covariance update; EIF 3: a Cholesky factorisation of H per update; SEIF 0).
double stepCostExponent(std::string_view filter);

/// Bytes of the dense n x n matrices (n = 3 + 2N) a dense filter holds at its peak: the
/// matrix, the copy made when it grows by a landmark, and the factor (EIF) or the
/// symmetrisation temporary (EKF). 0 for the SEIF.
double denseMatrixBytes(std::string_view filter, int landmarks);

/// A measured case used to extrapolate: median seconds per step with `landmarks` mapped.
struct BenchPoint {
  double landmarks = 0.0;
  double seconds_per_step = 0.0;
  double filter_bytes = 0.0;  ///< the filter's peak footprint (0 when unknown)
  double data_bytes = 0.0;    ///< peak RSS of simulating the case, beyond the program's own
  double steps = 0.0;         ///< steps of that case's corridor
};

/// Extrapolated cost of a case from earlier measurements of the same filter (ordered by
/// landmarks; at least one). The step time follows a power law through the largest
/// measured case with exponent max(stepCostExponent, the slope between the two largest
/// cases), capped at stepCostExponent + 1. Building the map up to N over `steps` steps
/// (the map grows linearly) costs steps * t(N) / (exponent + 1). Memory: the dense matrices,
/// or the SEIF's measured bytes per landmark, plus the simulation's bytes per step (measured
/// on a case of at least 10^4 steps, else 1 KiB per step).
struct BenchEstimate {
  double exponent = 0.0;
  double seconds_per_step = 0.0;  ///< at N landmarks
  double build_seconds = 0.0;     ///< the whole corridor
  double bytes = 0.0;             ///< peak memory of the case (filter + dataset)
  double matrix_bytes = 0.0;      ///< of which dense matrices (denseMatrixBytes)
};
BenchEstimate estimateBenchCase(std::string_view filter, int landmarks, double steps,
                                std::span<const BenchPoint> measured);

// ---------------------------------------------------------------- the whole study ----------

/// `seif bench` as one call: every (filter, N), each measured in forked children so that
/// one case's peak memory cannot inflate the next; a case whose estimate (extrapolated
/// from the smaller cases) exceeds the budget is skipped with the reason.
struct BenchRequest {
  std::vector<std::string> filters = {"ekf", "eif", "seif"};  ///< duplicates are dropped
  std::vector<int> landmarks = {100, 1000, 10000, 100000, 1000000};  ///< sorted, deduplicated
  int window = 200;
  /// Runs per case, each in its own child; the one with the lowest median is reported
  /// (interference only ever slows a run down). A case whose corridor is shorter than
  /// 2 window runs proportionally more often, so that every case times about repeat x
  /// window steps.
  int repeat = 3;
  std::uint64_t world_seed = 1;
  double max_seconds = 120.0;   ///< time budget of all runs of one case
  double max_memory_gb = 4.0;   ///< memory budget of one case
  Linearization linearization = Linearization::Standard;
  int iterations = 1;
  SeifOptions seif;
  AssociationOptions association;  ///< BenchCase::association, for every case
  /// Set to true (from another thread or a signal handler) to stop the study before its next
  /// case: the report holds the cases finished (BenchReport::interrupted). A case whose run
  /// failed while stopping (its child ended by the same Ctrl-C) is left out.
  const std::atomic<bool>* stop = nullptr;
};

/// One (filter, N) of the study.
struct BenchRow {
  std::string filter;
  int landmarks = 0;
  std::optional<BenchMeasurement> measurement;  ///< the best run; its peak memory the largest
  std::vector<double> repeat_medians;           ///< every run's median [us]
  std::optional<BenchEstimate> estimate;        ///< when smaller cases allowed one
  std::string skipped;  ///< why there is no measurement (over budget, or "failed: ...")
};

/// The targets, from what was measured: the SEIF's median at the largest N within
/// 1.5x its median at the smallest (and so its association time per scan, when associating); the SEIF at least 100x faster than the EKF at 1000
/// landmarks (else at the largest N both ran); the SEIF's bytes per landmark.
struct BenchTargets {
  struct Growth {
    int from_landmarks = 0, to_landmarks = 0;
    double from_us = 0.0, to_us = 0.0, ratio = 0.0;
    bool met = false;
  };
  struct Speedup {
    int landmarks = 0;
    double ekf_us = 0.0, seif_us = 0.0, ratio = 0.0;
    bool met = false;
  };
  std::optional<Growth> seif_growth;
  /// With association: the SEIF's median association time per scan, largest N over smallest.
  std::optional<Growth> seif_association_growth;
  std::optional<Speedup> ekf_over_seif;
  std::vector<std::pair<int, double>> seif_bytes_per_landmark;  ///< (N, bytes)
};

struct BenchReport {
  BenchRequest request;  ///< with the filters and sizes deduplicated
  std::vector<BenchRow> rows;
  std::vector<BenchMeasurement> calibration;  ///< cases run only to extrapolate from
  BenchTargets targets;
  bool interrupted = false;  ///< stopped (BenchRequest::stop) before every case was run
};

/// The table `seif bench` prints: its header, one line per case (measured or skipped), the
/// targets' lines; benchSummaryText() all of them for a finished report.
std::string benchHeaderText();
std::string benchRowText(const BenchRow& row);
std::string benchTargetsText(const BenchTargets& targets);
std::string benchSummaryText(const BenchReport& report);

/// One line for a stopped study (BenchReport::interrupted): "bench interrupted after 3
/// cases". `seif bench` and seif.run_bench say after it where the rows are.
std::string interruptedText(const BenchReport& report);

/// Runs the study; `row_done(row)` follows every case, measured or skipped. Throws
/// NumericError when a calibration case fails.
BenchReport runBench(const BenchRequest& request, const std::function<void(const BenchRow&)>& row_done = {});

BenchTargets benchTargets(const std::vector<BenchMeasurement>& measured);

/// bench.json: {"machine", "config", "results" (one per row), "calibration", "targets",
/// "interrupted"}.
std::string benchJson(const BenchReport& report);

}  // namespace seif
