#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include <seif/models/velocity_motion.hpp>

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace seif {

Pose2 startPose(const Dataset& data) {
  if (data.groundtruth.empty()) return Pose2::Zero();
  return interpolatePose(data.groundtruth, data.start_time);
}

RunOutput runFilter(SlamFilter& filter, const Dataset& data,
                    const std::function<void(std::size_t, std::size_t)>& progress) {
  using Clock = std::chrono::steady_clock;
  RunOutput out;
  const std::size_t total = data.steps.size();
  out.trajectory.reserve(total + 1);
  out.step_seconds.reserve(total);
  out.trajectory.push_back({data.start_time, filter.pose()});
  const std::size_t every = std::max<std::size_t>(1, total / 100);
  for (std::size_t k = 0; k < total; ++k) {
    const Step& step = data.steps[k];
    const auto t0 = Clock::now();
    try {
      filter.step(step.u, step.observations);
    } catch (const std::exception& e) {
      std::ostringstream msg;
      msg << filter.name() << ": step " << k << " (t = " << std::fixed << step.time
          << "): " << e.what();
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
    if (progress && (k % every == 0 || k + 1 == total)) progress(k + 1, total);
  }
  out.final_stats = filter.stats();
  out.rejected_observations = filter.rejectedObservations();
  out.max_robot_links = std::max(out.max_robot_links, out.final_stats.robot_links);
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
                   Alignment alignment) {
  const std::size_t n = estimate.size();
  if (n == 0 || n != truth.size()) throw std::invalid_argument("alignedRmse: point sets differ in size");
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
  for (std::size_t i = 0; i < n; ++i) sum += (R * estimate[i] + t - truth[i]).squaredNorm();
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
