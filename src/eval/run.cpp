#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include <seif/models/odometry_model.hpp>

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace seif {

Pose2 startPose(const Dataset& data) {
  if (data.groundtruth.empty()) return Pose2::Zero();
  return interpolatePose(data.groundtruth, data.start_time);
}

namespace {

/// One filter cycle of a run, timed and checked (the one place a run calls the filter).
void runStep(SlamFilter& filter, const Step& step, std::size_t k, RunOutput& out) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  try {
    filter.step(step.u, step.observations);
  } catch (const std::exception& e) {
    std::ostringstream msg;
    msg << filter.name() << ": step " << k << " (t = " << std::fixed << step.time << "): " << e.what();
    throw NumericError(msg.str());
  }
  const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
  out.step_seconds.push_back(dt);
  out.seconds += dt;
  const Pose2 x = filter.pose();
  if (!x.allFinite()) {
    std::ostringstream msg;
    msg << filter.name() << ": the pose estimate is not finite after step " << k;
    throw NumericError(msg.str());
  }
  out.trajectory.push_back({step.time, x});
  out.max_robot_links = std::max(out.max_robot_links, filter.robotLinks());
  out.max_blocks_touched = std::max(out.max_blocks_touched, filter.blocksTouched());
  ++out.steps;
}

void finish(SlamFilter& filter, RunOutput& out) {
  const auto t0 = std::chrono::steady_clock::now();
  filter.finish();  // a smoother's solve: part of its time
  out.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // A smoother's trajectory is the smoothed one, known only now.
  const std::vector<Pose2> smoothed = filter.smoothedTrajectory();
  if (!smoothed.empty()) {
    if (smoothed.size() != out.trajectory.size()) {
      throw NumericError(filter.name() + ": the smoothed trajectory has " + std::to_string(smoothed.size()) +
                         " poses for " + std::to_string(out.trajectory.size()) + " steps");
    }
    for (std::size_t k = 0; k < smoothed.size(); ++k) out.trajectory[k].pose = smoothed[k];
    if (!out.pose_covariances.empty()) out.pose_covariances = filter.smoothedTrajectoryCovariances();
  }
  out.final_stats = filter.stats();
  out.rejected_observations = filter.rejectedObservations();
  out.max_robot_links = std::max(out.max_robot_links, out.final_stats.robot_links);
}

[[noreturn]] void backwards(const EventSource& source, double t, double now) {
  std::ostringstream msg;
  msg << "events go back in time (" << t << " after " << now << ")";
  throw DataError(source.info().source, 0, msg.str());
}

}  // namespace

RunOutput runFilter(SlamFilter& filter, const Dataset& data,
                    const std::function<void(std::size_t, std::size_t)>& progress) {
  RunOutput out;
  const std::size_t total = data.steps.size();
  out.trajectory.reserve(total + 1);
  out.step_seconds.reserve(total);
  out.trajectory.push_back({data.start_time, filter.pose()});
  const std::size_t every = std::max<std::size_t>(1, total / 100);
  for (std::size_t k = 0; k < total; ++k) {
    runStep(filter, data.steps[k], k, out);
    if (progress && (k % every == 0 || k + 1 == total)) progress(k + 1, total);
  }
  finish(filter, out);
  return out;
}

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

RunOutput runFilter(SlamFilter& filter, EventSource& source, const std::function<void(double)>& progress,
                    bool pose_covariances) {
  RunOutput out;
  StepAssembler steps;
  Step step;
  const MotionModel& motion = *source.info().motion;
  Pose2 dead_reckoning = filter.pose();
  std::size_t k = 0;
  while (steps.next(source, step, &out.groundtruth, &out.gps)) {
    if (k == 0) {
      out.trajectory.push_back({steps.startTime(), filter.pose()});
      out.dead_reckoning.push_back(out.trajectory.back());
      if (pose_covariances) out.pose_covariances.push_back(filter.poseCovariance());
    }
    runStep(filter, step, k, out);
    if (pose_covariances) out.pose_covariances.push_back(filter.poseCovariance());
    dead_reckoning = motion.apply(dead_reckoning, step.u);
    out.dead_reckoning.push_back({step.time, dead_reckoning});
    if (progress && k % 1024 == 0) progress(source.progress());
    ++k;
  }
  if (progress) progress(1.0);
  finish(filter, out);
  out.dropped = source.dropped();
  if (steps.droppedBeforeFirstControl() > 0) out.dropped["before_first_control"] += steps.droppedBeforeFirstControl();
  return out;
}

std::vector<TimedPose> deadReckoning(const Dataset& data, const Pose2& start, const MotionModel& motion) {
  std::vector<TimedPose> track;
  track.reserve(data.steps.size() + 1);
  Pose2 x = start;
  track.push_back({data.start_time, x});
  for (const Step& step : data.steps) {
    x = motion.apply(x, step.u);
    track.push_back({step.time, x});
  }
  return track;
}

double alignedRmse(const std::vector<Vec2>& estimate, const std::vector<Vec2>& truth,
                   Alignment alignment, std::vector<double>* residuals) {
  const std::size_t n = estimate.size();
  if (n == 0 || n != truth.size()) throw InvalidArgument("alignedRmse: point sets differ in size");
  Eigen::Matrix2d R = Eigen::Matrix2d::Identity();
  Vec2 t = Vec2::Zero();
  if (alignment == Alignment::Rigid && n >= 2) {
    Vec2 ce = Vec2::Zero(), ct = Vec2::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      ce += estimate[i];
      ct += truth[i];
    }
    ce /= static_cast<double>(n);
    ct /= static_cast<double>(n);
    // The rotation angle maximising sum (q_i - ct)^T R (p_i - ce), in closed form in 2-D.
    double sxx = 0.0, sxy = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2 p = estimate[i] - ce, q = truth[i] - ct;
      sxx += p.dot(q);
      sxy += p.x() * q.y() - p.y() * q.x();
    }
    const double angle = std::atan2(sxy, sxx);
    R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
    t = ct - R * ce;
  }
  double sum = 0.0;
  if (residuals) residuals->clear();
  for (std::size_t i = 0; i < n; ++i) {
    const double e2 = (R * estimate[i] + t - truth[i]).squaredNorm();
    sum += e2;
    if (residuals) residuals->push_back(std::sqrt(e2));
  }
  return std::sqrt(sum / static_cast<double>(n));
}

std::optional<double> ateRmse(const std::vector<TimedPose>& estimate,
                              const std::vector<TimedPose>& groundtruth, Alignment alignment) {
  if (groundtruth.empty()) return std::nullopt;
  const double t0 = groundtruth.front().time, t1 = groundtruth.back().time;
  std::vector<Vec2> est, truth;
  for (const TimedPose& p : estimate) {
    if (p.time < t0 || p.time > t1) continue;
    est.push_back(p.pose.head<2>());
    truth.push_back(interpolatePose(groundtruth, p.time).head<2>());
  }
  if (est.empty()) return std::nullopt;
  return alignedRmse(est, truth, alignment);
}

std::optional<double> landmarkRmse(const SlamFilter& filter, const std::map<int, Vec2>& truth,
                                   Alignment alignment) {
  std::vector<Vec2> est, ref;
  for (int id : filter.landmarkIds()) {
    const auto it = truth.find(id);
    if (it == truth.end()) continue;
    est.push_back(filter.landmark(id));
    ref.push_back(it->second);
  }
  if (est.empty()) return std::nullopt;
  return alignedRmse(est, ref, alignment);
}

}  // namespace seif
