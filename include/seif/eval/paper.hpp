#pragma once
// The experiment of Thrun et al. 2002, §4 (algorithm.md "What the paper measured"): on the
// simulator's paper world (50 landmarks, 500 update cycles, known data association) run the
// EKF, the SEIF with exact mean and the constant-time SEIF on identical data, and measure
// each one's final map error, final number of links and time per update. One call of
// runPaperExperiment() is one run of the Monte-Carlo study; runPaper() runs many in
// parallel, summarises them (eval/stats.hpp) and writePaperResults() writes what `seif
// paper` leaves behind.
#include <seif/eval/run.hpp>
#include <seif/eval/stats.hpp>
#include <seif/filters/factory.hpp>
#include <seif/filters/seif_options.hpp>
#include <seif/filters/slam_filter.hpp>
#include <seif/core/dataset.hpp>
#include <seif/sim/world.hpp>

#include <Eigen/Core>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace seif {

/// What the experiment varies. The defaults are the paper's.
struct PaperOptions {
  int landmarks = 0;  ///< N; <= 0: the paper preset's 50
  int steps = 0;      ///< update cycles; <= 0: the paper preset's 500
  int active = 6;     ///< theta_x of both SEIFs (the paper: 6)
  int relax = 10;     ///< K of the constant-time SEIF (the paper: 10)
  PaperPath path = PaperPath::Lawnmower;  ///< the robot's path (the paper does not give one)
  /// Extra constant-time SEIFs, one per theta_x listed (the journal version's study),
  /// named "seif_active_<theta_x>" and run on the same data.
  std::vector<int> sweep_active;
  /// Filters beyond the paper, by spec (filters/factory.hpp: "batch",
  /// "ekf:linearization=fej", "seif:sparsify=eseif,beta=4", ...), run after the sweep on the
  /// same data and named by their spec.
  std::vector<std::string> extra;
};

/// One filter of the experiment.
struct PaperFilterSpec {
  std::string name;  ///< "ekf", "seif_exact", "seif" or "seif_active_<theta_x>"
  bool ekf = false;  ///< EkfSlam; otherwise SeifSlam with `seif`
  SeifOptions seif;  ///< the SEIF's options (its seed is set per run)
  std::optional<FilterSpec> spec;  ///< a filter beyond the paper (PaperOptions::extra): built from it
};

/// The filters in the order runPaperExperiment() runs and reports them: "ekf",
/// "seif_exact" (SeifOptions::Mean::Exact), "seif" (amortised, K = relax), then the sweep.
std::vector<PaperFilterSpec> paperFilters(const PaperOptions& options);

/// The simulator configuration of the run with simulator seed `seed`:
/// presetConfig(WorldPreset::Paper, options.landmarks, options.steps, seed) on options.path.
WorldConfig paperWorld(std::uint64_t seed, const PaperOptions& options);

/// Mean squared landmark position error [m^2]: the mean over the landmarks the filter
/// mapped (and `truth` knows) of |estimate - true position|^2. This is the "final error"
/// of `seif paper` when taken after the last step. `count` receives the number of
/// landmarks averaged; NaN when there are none.
double landmarkMse(const SlamFilter& filter, const std::map<int, Vec2>& truth,
                   std::size_t* count = nullptr);

/// What one filter did in one run.
struct PaperFilterResult {
  std::string name;
  double mse = 0.0;         ///< landmarkMse() after the last step [m^2]
  double rmse = 0.0;        ///< sqrt(mse) [m]
  /// The map's shape error: mse after the best rigid 2-D alignment of the mapped landmarks
  /// to the truth (landmarkRmse(Alignment::Rigid) squared) [m^2]; <= mse.
  double aligned_mse = 0.0;
  double pose_error = 0.0;  ///< final robot position error [m]
  std::size_t mapped = 0;   ///< landmarks in the filter's map at the end
  FilterStats stats;        ///< after the last step (links = non-zero off-diagonal H blocks)
  std::vector<double> step_seconds;  ///< wall time of every predict + update [s]
  /// NEES after the last step with the filter's own covariances (eval/consistency.hpp):
  /// landmark (mean over the map, 2 dof expected) and pose (3 dof).
  double landmark_nees = 0.0;
  double pose_nees = 0.0;
};

/// One run: the data, and every filter's result on it.
struct PaperRun {
  std::uint64_t seed = 0;   ///< simulator seed (also the SEIFs' relaxation seed)
  std::size_t steps = 0;    ///< filter steps (buildDataset())
  SimStats sim;             ///< what the simulator saw
  std::vector<PaperFilterResult> filters;  ///< in paperFilters() order
};

/// Everything reported about one filter over all successful runs.
struct PaperFilterSummary {
  std::string name;
  std::vector<std::uint64_t> seeds;
  std::vector<double> mse, rmse, aligned_mse, links, mapped, robot_links, pose_error, landmark_nees, pose_nees;
  std::vector<double> diff_to_ekf;  // per-run mse - ekf mse [m^2]
  Summary error, rms, aligned_error, link, map, diff, pose, nees, nees_pose;
  double us_median = 0.0;
  double us_mean = 0.0;
  // Error relative to the EKF on the same runs: the ratio of the means, its 95% CI by the
  // delta method for paired samples (residuals mse_i - ratio * ekf_i), and the median of the
  // per-run ratios (what a typical run does; the means are dominated by a few runs).
  double ratio = 1.0, ratio_ci95 = 0.0, ratio_median = 1.0;
  double aligned_ratio = 1.0;  // aligned_error's ratio of means to the EKF's
};

/// The summary of filter `f` (paperFilters() order; filter 0 is the EKF, the reference of
/// the ratios) over `runs` (non-empty).
PaperFilterSummary summarizePaperFilter(std::size_t f, const std::vector<PaperRun>& runs);

/// The filters of a run kept alive after it, with their data: for figures.
struct PaperRunDetail {
  Dataset data;
  std::vector<std::unique_ptr<SlamFilter>> filters;  ///< in paperFilters() order
  std::vector<RunOutput> outputs;
};

/// Simulates paperWorld(seed, options) and runs every filter of paperFilters(options) on
/// the same data, from the true start pose (startPose()) with the world's true noise.
/// Deterministic in (seed, options) except the step times. Fills `detail` if given.
/// A filter failure is rethrown as NumericError naming the seed.
PaperRun runPaperExperiment(std::uint64_t seed, const PaperOptions& options,
                            PaperRunDetail* detail = nullptr);

// ---------------------------------------------------------------- the whole study ---------

/// `seif paper` as one call: `runs` independent runs of the paper world, summarised.
struct PaperRequest {
  int runs = 100;
  std::uint64_t seed = 1;  ///< run r uses simulator seed seed + r
  unsigned jobs = 0;       ///< threads; 0: the number of cores (results do not depend on it)
  PaperOptions options;
  /// Set to true (from another thread or a signal handler) to stop the study: no run starts
  /// after it, the runs under way finish, and the report holds them (PaperReport::interrupted).
  const std::atomic<bool>* stop = nullptr;
};

/// A run that failed and is left out of the statistics.
struct PaperFailure {
  std::uint64_t seed = 0;
  std::string error;
};

struct PaperReport {
  PaperRequest request;
  unsigned jobs = 1;      ///< threads used
  WorldConfig world;      ///< paperWorld(request.seed, request.options)
  std::vector<PaperFilterSpec> specs;         ///< paperFilters(request.options)
  std::vector<PaperRun> runs;                 ///< the successful runs, in seed order
  std::vector<PaperFailure> failed;           ///< in seed order
  /// Stopped (PaperRequest::stop) before every run had started: `runs` and `failed` hold
  /// those that ran, the others are in neither.
  bool interrupted = false;
  std::vector<PaperFilterSummary> summaries;  ///< one per spec
  /// The figures' run, chosen by a rule fixed in advance: the run whose constant-time SEIF
  /// has the median final error (the lower median for an even count), run again with its
  /// filters kept (the paper's three filters; no sweep).
  std::size_t typical = 0;  ///< index into runs
  PaperRunDetail typical_detail;
};

/// Throws InvalidArgument when runs < 1 or seed + runs - 1 passes 2^64 - 1.
void checkPaperRequest(const PaperRequest& request);

/// Runs the study on the experiments' thread pool (eval/parallel.hpp); `progress(done,
/// total)` counts runs, one call at a time. A failed run is recorded, not thrown; throws
/// NumericError when every run failed, Interrupted when stopped before any run succeeded,
/// and what checkPaperRequest() throws.
PaperReport runPaper(const PaperRequest& request,
                     const std::function<void(std::size_t, std::size_t)>& progress = {});

/// One line for a stopped study (PaperReport::interrupted): "paper interrupted: 12 of 50
/// runs ran". `seif paper` and seif.run_paper say after it where the results are.
std::string interruptedText(const PaperReport& report);

/// What `seif paper` prints: the table beside the paper's numbers, its notes, and the
/// sweep's and the beyond-the-paper tables when they ran.
std::string paperSummaryText(const PaperReport& report);

/// Writes DIR/results.json, DIR/table.md and DIR/figure_data/<filter>.json (the data of
/// scripts/figures/paper.py), creating DIR.
void writePaperResults(const PaperReport& report, const std::filesystem::path& dir);

/// A filter's state laid out for figures, landmarks ordered by id (so that two filters'
/// matrices are comparable whatever order they mapped the landmarks in).
struct FilterSnapshot {
  struct Link {
    int a = -1;  ///< landmark id, or -1 for the robot
    int b = -1;  ///< landmark id
    /// Largest |H_ij| / sqrt(H_ii H_jj) over the entries of the link's block.
    double strength = 0.0;
  };
  std::vector<int> ids;         ///< landmark ids, ascending: matrix order after the pose
  Eigen::VectorXd mean;         ///< [x, y, th, landmarks by id]
  Eigen::MatrixXd covariance;   ///< same order
  Eigen::MatrixXd information;  ///< same order
  /// Non-zero off-diagonal blocks of the information matrix: robot-landmark links first
  /// (a = -1), then landmark-landmark links (a < b).
  std::vector<Link> links;
};

/// Dense: O(N^3) for information filters. For figures and tests.
FilterSnapshot snapshotById(const SlamFilter& filter);

}  // namespace seif
