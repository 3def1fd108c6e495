// Events -> filter steps (include/seif/eval/step_assembler.hpp).
#include <seif/core/errors.hpp>
#include <seif/eval/step_assembler.hpp>
#include <seif/models/odometry_model.hpp>

#include <sstream>
#include <type_traits>
#include <variant>

namespace seif {
namespace {

[[noreturn]] void backwards(const EventSource& source, double t, double now) {
  std::ostringstream msg;
  msg << "events go back in time (" << t << " after " << now << ")";
  throw DataError(source.info().source, 0, msg.str());
}

/// The longest a rate control is held [s]: a log whose controls and observations are an hour
/// apart has streams whose clocks disagree (one shifted, or in other units), not a pause.
constexpr double kMaxControlHold = 3600.0;

void checkHold(const EventSource& source, double t, double now) {
  if (t - now <= kMaxControlHold) return;
  std::ostringstream msg;
  msg << "an event at t = " << t << " comes " << t - now << " s after the control in force (from t = " << now
      << "): a control is held an hour at most (do the streams' clocks agree?)";
  throw DataError(source.info().source, 0, msg.str());
}

}  // namespace

void StepAssembler::setRateStep(Step& step, double t) const {
  step.time = t;
  step.u = control_;
  std::visit([&](auto& u) {
    if constexpr (!std::is_same_v<std::decay_t<decltype(u)>, OdometryIncrement>) u.dt = t - now_;
  }, step.u);
}

bool StepAssembler::next(EventSource& source, Step& step, std::vector<TimedPose>* groundtruth,
                         std::vector<GpsFix>* gps) {
  Event e;
  while (source.next(e)) {
    const double t = eventTime(e);
    if (started_ && t < now_) backwards(source, t, now_);
    if (auto* gt = std::get_if<TimedPose>(&e)) {
      if (groundtruth) groundtruth->push_back(*gt);
    } else if (auto* fix = std::get_if<GpsFix>(&e)) {
      if (gps) gps->push_back(*fix);
    } else if (auto* c = std::get_if<ControlEvent>(&e)) {
      if (std::holds_alternative<OdometryIncrement>(c->input)) {
        // An increment ends at its stamp; its observations may still follow.
        std::optional<Step> done = std::move(pending_);
        pending_ = Step{t, c->input, {}};
        started_ = true;
        now_ = t;
        if (done) {
          step = std::move(*done);
          return true;
        }
        continue;
      }
      if (started_ && t > now_ && has_control_) {  // the previous control ends here
        checkHold(source, t, now_);
        setRateStep(step, t);
        step.observations.clear();
        control_ = c->input;
        now_ = t;
        return true;
      }
      if (!started_) start_time_ = t;
      started_ = true;
      control_ = c->input;
      has_control_ = true;
      if (early_) {  // observations at the first control's stamp: a step of dt = 0
        const bool same = early_->time == t;
        if (!same) dropped_before_first_control_ += early_->observations.size();
        std::optional<ObservationEvent> first = std::move(early_);
        early_.reset();
        now_ = t;
        if (same) {
          setRateStep(step, t);
          step.observations = std::move(first->observations);
          return true;
        }
        continue;
      }
      now_ = t;
    } else {
      auto& obs = std::get<ObservationEvent>(e);
      if (pending_) {
        if (pending_->time == t) {
          for (Observation& z : obs.observations) pending_->observations.push_back(std::move(z));
          continue;
        }
        step = std::move(*pending_);
        pending_.reset();
        // These observations are from the pose reached: a zero-motion step follows.
        pending_ = Step{t, OdometryIncrement{Vec3::Zero(), Mat3::Zero()}, std::move(obs.observations)};
        now_ = t;
        return true;
      }
      if (!has_control_) {
        if (dynamic_cast<const OdometryModel*>(source.info().motion.get()) == nullptr) {
          // Before the first control; kept if that control starts at this very stamp.
          if (early_) dropped_before_first_control_ += early_->observations.size();
          early_ = std::move(obs);
          continue;
        }
        started_ = true;  // observations from the start pose of an odometry chain
        step = Step{t, OdometryIncrement{Vec3::Zero(), Mat3::Zero()}, std::move(obs.observations)};
        now_ = t;
        return true;
      }
      checkHold(source, t, now_);
      setRateStep(step, t);
      step.observations = std::move(obs.observations);
      now_ = t;
      return true;
    }
  }
  if (pending_) {
    step = std::move(*pending_);
    pending_.reset();
    return true;
  }
  return false;
}

}  // namespace seif
