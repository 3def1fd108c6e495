#pragma once
// Events -> filter steps: the rule that turns any time-ordered event stream (every
// dataset reader, the simulator's log) into the steps the run loop feeds to a filter.
#include <seif/core/dataset.hpp>
#include <seif/io/event_source.hpp>

#include <cstddef>
#include <optional>
#include <vector>

namespace seif {

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
  /// The next step; false at the end of the stream. Events whose time goes backwards, and a
  /// rate control held over more than an hour (streams whose clocks disagree), are a
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

}  // namespace seif
