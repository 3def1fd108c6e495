#pragma once
// Runs a filter over a dataset and measures it: the one loop behind `seif run`,
// `seif paper` and `seif bench`. A dataset comes either in memory (Dataset: the simulator's
// worlds) or as a stream of events (EventSource: every reader); StepAssembler turns events
// into filter steps, and the run never holds the observations of more than one step.
#include <seif/filters/slam_filter.hpp>
#include <seif/core/dataset.hpp>
#include <seif/io/event_source.hpp>

#include <cstddef>
#include <functional>
#include <map>
#include <string>
#include <optional>
#include <vector>

namespace seif {

struct RunOutput {
  std::size_t steps = 0;
  std::vector<TimedPose> trajectory;  ///< the start pose, then the pose after every step
  std::vector<double> step_seconds;   ///< wall time of every step (predict + update)
  /// The pose covariance beside every trajectory pose, when asked for (runFilter's
  /// pose_covariances): the filter's poseCovariance() after each step (its cost: see
  /// SlamFilter), or a smoother's marginals after finish().
  std::vector<Mat3> pose_covariances;
  double seconds = 0.0;               ///< sum of step_seconds
  FilterStats final_stats;
  std::size_t max_robot_links = 0;     ///< over all steps
  std::size_t max_blocks_touched = 0;  ///< over all steps
  std::size_t rejected_observations = 0;  ///< by the gross-outlier gate (OutlierGate)
  // Streamed runs only (runFilter over an EventSource): what the stream carried besides
  // controls and observations, and the controls integrated alone. All O(steps).
  std::vector<TimedPose> dead_reckoning;  ///< the start pose, then after every step
  std::vector<TimedPose> groundtruth;
  std::vector<GpsFix> gps;
  std::map<std::string, std::size_t> dropped;  ///< by the source and the assembler, by reason
};

/// Turns a time-ordered event stream into filter steps (the rule of buildDataset(), for any
/// motion input). A rate control (velocity, Ackermann) is in force from its stamp until the
/// next control; an observation event predicts with it up to its stamp, then updates, and
/// a control stamp after the last step closes an interval without observations. An
/// odometry increment is one step ending at its stamp; observations with the same stamp
/// join that step, observations before any increment get a zero-motion step. Observations
/// before the first rate control are dropped and counted ("before_first_control"), those at
/// its very stamp form a step of dt = 0 (as buildDataset()).
/// Ground truth and GPS are handed on as they come.
class StepAssembler {
 public:
  /// The next step; false at the end of the stream. Events whose time goes backwards are a
  /// DataError naming the source.
  bool next(EventSource& source, Step& step, std::vector<TimedPose>* groundtruth,
            std::vector<GpsFix>* gps);
  /// Time of the start pose: the first rate control's stamp, or 0 (pose index 0) for
  /// odometry increments. Valid after the first next().
  double startTime() const { return start_time_; }
  std::size_t droppedBeforeFirstControl() const { return dropped_before_first_control_; }

 private:
  /// `step` = the control in force from now_ to t, without observations.
  void setRateStep(Step& step, double t) const;

  MotionInput control_;  // the rate control in force, when has_control_
  bool has_control_ = false;
  std::optional<Step> pending_;         // an odometry step waiting for its observations
  std::optional<ObservationEvent> early_;  // observations before the first rate control
  bool started_ = false;
  double now_ = 0.0;  // time the last emitted step ended
  double start_time_ = 0.0;
  std::size_t dropped_before_first_control_ = 0;
};

/// Streams `source` through `filter`, whose config must hold the source's models (the
/// filter is built from info()). `progress(fraction)` is called now and then.
/// A failure inside a step is rethrown as NumericError naming the step and its time.
RunOutput runFilter(SlamFilter& filter, EventSource& source,
                    const std::function<void(double)>& progress = {}, bool pose_covariances = false);

/// The pose the filter starts from: the ground truth at the first step's time when the
/// dataset has ground truth, else the origin.
Pose2 startPose(const Dataset& data);

/// Runs every step of `data` through `filter`. `progress(done, total)` is called now and then.
/// A failure inside a step is rethrown as NumericError naming the step and its time.
RunOutput runFilter(SlamFilter& filter, const Dataset& data,
                    const std::function<void(std::size_t, std::size_t)>& progress = {});

/// Integrates the controls alone from `start` (dead reckoning), at the same stamps as runFilter.
std::vector<TimedPose> deadReckoning(const Dataset& data, const Pose2& start, const MotionModel& motion);

/// Whether an error is measured in the ground truth's frame as it is (the filters start at
/// the true pose) or after the rigid 2-D motion that best aligns estimate and truth
/// (least squares, Horn/Umeyama without scale), as the TUM benchmark and evo define ATE.
enum class Alignment { None, Rigid };

/// RMS of |R p_i + t - q_i| over point pairs, with (R, t) = identity or the best rigid fit;
/// `residuals` receives each |R p_i + t - q_i| when given.
double alignedRmse(const std::vector<Vec2>& estimate, const std::vector<Vec2>& truth,
                   Alignment alignment, std::vector<double>* residuals = nullptr);

/// Absolute trajectory error: RMS position error against the ground truth interpolated at
/// the estimate's stamps (stamps outside the ground truth's span are skipped).
/// nullopt without ground truth.
std::optional<double> ateRmse(const std::vector<TimedPose>& estimate,
                              const std::vector<TimedPose>& groundtruth,
                              Alignment alignment = Alignment::None);

/// RMS landmark position error of the filter's map against the true positions of the
/// landmarks it mapped. nullopt without ground truth or mapped landmarks.
std::optional<double> landmarkRmse(const SlamFilter& filter, const std::map<int, Vec2>& truth,
                                   Alignment alignment = Alignment::None);

}  // namespace seif
