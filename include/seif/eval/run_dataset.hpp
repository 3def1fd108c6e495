#pragma once
// `seif run` as one library call: open a dataset (any format), build the filter with the
// dataset's models, stream the run, measure it and write its outputs:
//   trajectory.tum  the filter's poses (TUM: t x y z qx qy qz qw)
//   dead_reckoning.tum  the controls integrated alone from the same start, at the same stamps
//   map.csv         id, x, y and the landmark's 2x2 marginal covariance
//   metrics.json    timing, structure, errors (its keys: RunReport below; "interrupted" when
//                   stopped, "failure" the error that ended a run early)
//   gps.csv         time, x, y of the dataset's GPS fixes, when it has any
//   trajectory_filter.tum, map_filter.csv  with `smooth`: the filter's, before the batch
// Errors: ATE and map error against ground truth when the dataset has it (after the best
// rigid 2-D alignment and as estimated); gps_rmse and dead_reckoning_gps_rmse against GPS
// when the dataset has it (trajectory interpolated at the GPS stamps inside its span, after
// the best rigid 2-D alignment, metres).
#include <seif/eval/association_ceiling.hpp>
#include <seif/eval/run.hpp>
#include <seif/filters/batch_options.hpp>
#include <seif/filters/seif_options.hpp>
#include <seif/io/event_source.hpp>

#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace seif {

struct RunRequest {
  std::filesystem::path dataset;
  DatasetFormat format = DatasetFormat::Auto;
  DatasetOptions dataset_options;
  std::string filter = "seif";  ///< a filter spec: "ekf", "eif", "seif", "batch", with options
  double outlier_gate = FilterConfig{}.outlier_gate;
  /// The defaults of the options `filter` does not set (the flags of `seif run`).
  Linearization linearization = Linearization::Standard;
  int iterations = 1;
  SeifOptions seif;
  BatchOptions batch;
  /// Run `filter`, then the batch MAP from its estimate (makeSmoother): the outputs are the
  /// smoothed ones, the filter's are written beside them and compared.
  bool smooth = false;
  /// Data association (association/association.hpp): known uses the data's ids; nn and jcbb hide
  /// them from the filter (they only score the association: metrics.json "association").
  AssociationOptions association;
  bool map_covariances = true;  ///< map.csv with each landmark's exact marginal covariance
  /// trajectory_cov.csv: the pose covariance after every step (SEIF: one factorisation per
  /// step with covariance=exact; O(1) with covariance=local).
  bool trajectory_covariances = false;
  /// Save the filter and the run so far to `checkpoint` after every `checkpoint_every`
  /// steps (0: never), replacing the previous checkpoint atomically.
  std::size_t checkpoint_every = 0;
  std::filesystem::path checkpoint;
  /// Resume the run saved in this checkpoint (of the same dataset): the filter is the
  /// checkpoint's (`filter` and the filter options, when not the defaults, must be its run's:
  /// InvalidArgument otherwise, as for `smooth`), the steps it consumed are skipped, and the
  /// outputs equal those of the run that was never interrupted.
  std::filesystem::path resume;
  std::string command_line;     ///< recorded in metrics.json
  /// Set to true (from another thread or a signal handler) to stop the run before its next
  /// step: the outputs are written for the steps run (RunOutput::interrupted, metrics.json
  /// "interrupted"), and with `checkpoint` a checkpoint is saved there to resume from (even
  /// with checkpoint_every = 0). Null: the run goes to the end of the data.
  const std::atomic<bool>* stop = nullptr;
};

struct RunErrors {
  std::optional<double> ate, dead_reckoning_ate, landmark;                  ///< aligned
  std::optional<double> ate_unaligned, dead_reckoning_ate_unaligned, landmark_unaligned;
  std::optional<double> gps, dead_reckoning_gps;                            ///< aligned
  std::optional<double> gps_median;  ///< median distance to the fixes, same alignment (robust to GPS jumps)
  std::size_t gps_fixes = 0;  ///< fixes inside the trajectory's time span (those compared)
  /// gps, over the fixes that are not jumps (gpsJumps()): aligned and measured without them.
  std::optional<double> gps_without_jumps;
  std::size_t gps_jumps = 0;  ///< the jumps among the fixes compared
};

struct RunReport {
  std::string filter;  ///< the spec that ran (a resumed run's: the checkpoint's)
  DatasetInfo info;
  RunOutput output;
  RunErrors errors;
  std::size_t landmarks = 0;
  std::optional<SmootherReport> smoother;     ///< a smoother's solve
  std::optional<RunErrors> filter_errors;     ///< with `smooth`: the filter's, before the batch
  std::optional<double> filter_map_distance;  ///< with `smooth`: RMS distance of the filter's map from the batch's [m]
  /// With `smooth`: the distance of the filter's position from the batch's at every pose of
  /// the trajectory (the start and each step), RMS and median [m]. Where a dataset's ground
  /// truth is poor (Victoria Park's GPS), the batch MAP under the same models is the reference.
  std::optional<Vec2> filter_trajectory_distance;
  /// With `smooth`: over the landmarks, trace(filter's covariance) / trace(batch's), median
  /// and 10th / 90th percentile. The batch's marginals under the same models are the honest
  /// reference: below 1 the filter claims too little variance.
  std::optional<Vec3> filter_covariance_ratio;
  std::optional<AssociationCounts> association;  ///< with nn or jcbb (or drop_unlabelled): what the association did
  /// The options it ran with: the request's, or a resumed checkpoint's.
  AssociationOptions association_options;
  /// With nn or jcbb on data with ground-truth poses and landmarks: what the true map and
  /// poses would associate (eval/association_ceiling.hpp).
  std::optional<AssociationCeiling> association_ceiling;
  double seconds_wall = 0.0;     ///< open, read and filter
  double seconds_outputs = 0.0;  ///< trajectory, map with covariances, metrics
};

/// Runs `request` and writes the three files into `out` (which must exist and be writable),
/// first removing what an earlier run wrote there. `progress(fraction)` is called during the
/// run. Throws DataError for bad input, NumericError for a numerical failure,
/// InvalidArgument for a bad request, Interrupted for a run stopped before its first step.
/// A failure after the first step does not throw: the outputs of the steps before it are
/// written (metrics.json "failure" holds its message) and it is returned in
/// RunReport::output.failure for the caller to report or rethrow.
RunReport runDataset(const RunRequest& request, const std::filesystem::path& out,
                     const std::function<void(double)>& progress = {});

/// The report `seif run` prints after a run: the filter, models and noise with their
/// sources, the errors against each reference the dataset has, timing, smoothing and
/// association figures, and what was written into `out_dir`.
std::string runSummary(const RunRequest& request, const RunReport& report, const std::filesystem::path& out_dir);

/// RMS distance between the trajectory, interpolated at each GPS stamp inside its span, and
/// the fixes, after the best rigid 2-D alignment; nullopt without fixes in the span.
/// `compared` receives the number of fixes used.
std::optional<double> gpsRmse(const std::vector<TimedPose>& trajectory, const std::vector<GpsFix>& gps,
                              std::size_t* compared = nullptr, std::optional<double>* median = nullptr);

/// The speed above which a GPS fix counts as a jump [m/s]: three times the fastest encoder
/// speed on Victoria Park (6.6 m/s). There, 12 of the 4 465 pairs of consecutive fixes (0.2 s
/// apart) imply more than that (noise, or a receiver stepping back after a gap), but only one
/// fix does so from both its neighbours: a spike of 141 m in 2.2 s.
inline constexpr double kGpsJumpSpeed = 20.0;

/// Which fixes are jumps of a failing receiver: a fix is one when the speed it implies from
/// each neighbouring fix (distance over the time between them) exceeds `max_speed`. An
/// isolated spike is caught; a fix with one plausible neighbour is kept; the first and last
/// fix have one neighbour to test. Fixes must be sorted by time.
std::vector<bool> gpsJumps(const std::vector<GpsFix>& gps, double max_speed = kGpsJumpSpeed);

/// The SEIF's options as a JSON object (metrics.json "seif", `seif bench` and `seif paper`).
std::string seifOptionsJson(const SeifOptions& options);

/// The errors of a finished run (see the top of this file).
RunErrors evaluateRun(const SlamFilter& filter, const DatasetInfo& info, const RunOutput& out);

}  // namespace seif
