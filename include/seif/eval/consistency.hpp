#pragma once
// Monte-Carlo consistency of any set of filters on a simulator world (`seif consistency`):
// the normalised estimation error squared (NEES, Bar-Shalom, Li, Kirubarajan 2001, §5.4.2)
// of the pose (3 dof) and of every landmark (2 dof), against time, averaged over R runs and
// compared with the chi-square 95 % band of that average. Two frames:
//   global:   e = estimate - truth, P = the filter's marginal covariance;
//   relative: everything relative to the first landmark the filter mapped, m0 - the frame
//             in which the map's translation is observable: e = (m_i - m0)^ - (m_i - m0),
//             P = S_ii + S_00 - S_i0 - S_0i; the pose as (p - m0, theta).
// Beside NEES, the final landmark error (unaligned and after rigid alignment). Run r
// simulates the world with seed world.seed + r; every filter sees the same data; runs are
// independent and stored by index, so the results do not depend on the number of threads.
// Or real data with ground truth (ConsistencyOptions::datasets, e.g. the five MRCLAM
// robots): run r is dataset r with its own models; the series are then sampled at the same
// fractions of each run.
#include <seif/core/dataset.hpp>
#include <seif/eval/stats.hpp>
#include <seif/filters/factory.hpp>
#include <seif/sim/world.hpp>

#include <atomic>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace seif {

/// One real run of the study: a dataset with ground truth (poses and landmarks) and the
/// filter configuration of its models (as `seif run` builds it).
struct ConsistencyDataset {
  std::string name;  ///< e.g. "MRCLAM_Dataset6 robot 3"
  Dataset data;
  FilterConfig config;
};

/// The MRCLAM robots of `folder` as consistency runs (Vicon poses and surveyed landmarks the
/// truth). Throws DataError as the reader does, InvalidArgument for a robot outside 1..5.
std::vector<ConsistencyDataset> mrclamConsistencyRuns(const std::filesystem::path& folder,
                                                      const std::vector<int>& robots);

struct ConsistencyOptions {
  WorldConfig world;
  /// When not empty, the runs (one per dataset; `world` and `runs` unused).
  std::vector<ConsistencyDataset> datasets;
  int runs = 50;
  std::vector<FilterSpec> filters;
  /// Points of the NEES-against-time series, evenly spaced over the steps (the last step
  /// always included); each costs every filter its marginals (SEIF: one factorisation).
  int samples = 50;
  unsigned threads = 0;  ///< 0: the number of cores
  /// Also measure, for every filter whose estimate is not its posterior's mean (the
  /// amortised SEIF: SlamFilter::posteriorMean), the posterior N(H^-1 b, H^-1): the same
  /// covariances with the mean H^-1 b, as a row of its own after the filter's
  /// (ConsistencyFilterResult::posterior_mean). It separates what the filter's information
  /// claims from how far its constant-time mean lags it. Costs one sparse solve per sample.
  bool posterior_mean = false;
  /// Set to true (from another thread or a signal handler) to stop the study: the runs under
  /// way stop after their step and are left out with those not started; the result holds
  /// the runs every filter finished (ConsistencyResult::interrupted).
  const std::atomic<bool>* stop = nullptr;
};

/// NEES of one filter at one instant: global and relative frame, pose and landmark (the
/// landmark value is the mean over the mapped landmarks). NaN where undefined (no landmark
/// yet, fewer than two for the relative frame, or a smoother before its end).
struct NeesPoint {
  double pose = 0.0;
  double landmark = 0.0;
  double pose_relative = 0.0;
  double landmark_relative = 0.0;
};

/// A run in which a filter stopped with a NumericError (it diverged): the run's name ("seed
/// 6", or the dataset's) and the error.
struct ConsistencyFailure {
  std::string run;
  std::string error;
};

struct ConsistencyFilterResult {
  std::string name;               ///< the spec as given, e.g. "seif:sparsify=eseif"; "... [posterior mean]"
  std::size_t spec = 0;           ///< its index in ConsistencyOptions::filters
  /// The figures of the posterior's mean H^-1 b instead of the filter's own estimate
  /// (ConsistencyOptions::posterior_mean); the covariances are the same.
  bool posterior_mean = false;
  std::vector<NeesPoint> nees;    ///< mean over runs at each sample step (finite values only)
  NeesPoint nees_final;           ///< mean over runs after the last step
  std::vector<double> landmark_nees_runs;  ///< final landmark NEES of each run
  double error_final = 0.0;          ///< landmark RMSE [m], mean over runs
  double error_aligned_final = 0.0;  ///< the same after rigid alignment to the truth
  double mse_final = 0.0;            ///< mean squared landmark error [m^2], mean over runs
  double mse_aligned_final = 0.0;
  /// mse and mse_aligned of each run (NaN where it stopped): paired with another filter's
  /// of the same runs by pairedRatio() (eval/stats.hpp), as the table's ratios to the batch.
  std::vector<double> mse_runs, mse_aligned_runs;
  double seconds = 0.0;              ///< filter time, summed over runs (finish() included)
  /// The runs it stopped in. Their figures are left out of every mean above (NaN in
  /// landmark_nees_runs); the other filters' figures of those runs are kept.
  std::vector<ConsistencyFailure> failed_runs;
};

struct ConsistencyResult {
  int runs = 0;  ///< the runs summarised: all those asked for, unless interrupted
  /// Stopped (ConsistencyOptions::stop) before every run finished: the figures are those of
  /// the runs in `run_names`, out of `runs_requested`.
  bool interrupted = false;
  int runs_requested = 0;
  std::vector<std::string> run_names;  ///< the runs summarised ("seed 6", or the dataset's)
  std::size_t steps = 0;
  Band pose_band;      ///< 95 % band of the mean of `runs` 3-dof NEES values
  Band landmark_band;  ///< 95 % band of the mean of `runs` 2-dof NEES values
  std::vector<std::size_t> sample_steps;  ///< steps after which each NeesPoint was taken (1-based)
  std::vector<ConsistencyFilterResult> filters;
};

/// Throws InvalidArgument for options runConsistency() cannot run: no runs or filters, a
/// dataset without steps, ground truth or models, seeds that would wrap past 2^64 - 1.
void checkConsistencyOptions(const ConsistencyOptions& options);

/// Runs the study. `progress(done, total)` counts runs and is called from worker threads,
/// one call at a time. Stopped (options.stop) before any run finished, it throws
/// Interrupted. A filter that stops with a NumericError in a run is listed in its
/// result's failed_runs, and the study goes on. Other errors throw, naming the run and the
/// filter; InvalidArgument for runs < 1, samples < 1 or no filter.
ConsistencyResult runConsistency(const ConsistencyOptions& options,
                                 const std::function<void(std::size_t, std::size_t)>& progress = {});

/// One line for a stopped study (ConsistencyResult::interrupted): "consistency
/// interrupted: 12 of 50 runs finished". `seif consistency` and seif.run_consistency say
/// after it where the results are.
std::string interruptedText(const ConsistencyResult& result);

/// The NEES of `filter` now against the true pose and landmark positions (by id), with its
/// marginal covariances and its own estimate, or `mean` (the whole state in the state
/// order, e.g. SlamFilter::posteriorMean) when given.
NeesPoint measureNees(const SlamFilter& filter, const Pose2& true_pose, const std::map<int, Vec2>& truth,
                      const Eigen::VectorXd* mean = nullptr);

/// nees.json: {"runs", "runs_requested", "interrupted", "run_names", "steps", "band95": {"pose": [lo, hi], "landmark": [lo, hi]},
/// "sample_steps", "filters": [{"name", "filter_spec", "estimate" ("own" | "posterior_mean"), "pose_nees_final", "landmark_nees_final",
/// "pose_nees_relative_final", "landmark_nees_relative_final", "error_final",
/// "error_aligned_final", "mse_final", "mse_aligned_final", "mse_runs", "mse_aligned_runs",
/// "mse_ratio_to_batch" and "mse_aligned_ratio_to_batch" ({"ratio", "ci95", "pairs"}, null
/// without a batch row: consistencyTable's reference), "seconds", "nees": {"pose": [...],
/// "landmark": [...], "pose_relative": [...], "landmark_relative": [...]},
/// "failed_runs": [{"run", "error"}]}]}.
/// NaN is written as null.
std::string consistencyJson(const ConsistencyResult& result, const ConsistencyOptions& options);

/// nees.csv: "filter,step,pose,landmark,pose_relative,landmark_relative", one row per filter
/// and sample step: the NEES series of the figures.
std::string consistencyCsv(const ConsistencyResult& result);

/// Writes DIR/nees.json, DIR/nees.csv and DIR/table.md (consistencyTable) into `dir`.
void writeConsistencyResults(const ConsistencyResult& result, const ConsistencyOptions& options,
                             const std::filesystem::path& dir);

/// The console / README table: one row per filter with final NEES (global, relative),
/// errors, and their mean squared error as a multiple of the first smoother's ("batch")
/// when one ran, with the half-width of its 95 % interval over the paired runs
/// (pairedRatio()).
std::string consistencyTable(const ConsistencyResult& result);

/// The first smoother's row ("batch", "batch:..."), the reference of the ratios; nullptr
/// when none ran.
const ConsistencyFilterResult* batchReference(const ConsistencyResult& result);

}  // namespace seif
