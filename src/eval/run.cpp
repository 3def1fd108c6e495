#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include <seif/models/velocity_motion.hpp>

#include <chrono>
#include <cmath>
#include <sstream>

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
  out.max_robot_links = std::max(out.max_robot_links, out.final_stats.robot_links);
  return out;
}

std::vector<TimedPose> deadReckoning(const Dataset& data, const Pose2& start) {
  std::vector<TimedPose> track;
  track.reserve(data.steps.size() + 1);
  Pose2 x = start;
  track.push_back({data.start_time, x});
  for (const Step& step : data.steps) {
    x = VelocityMotionModel::apply(x, step.u);
    track.push_back({step.time, x});
  }
  return track;
}

std::optional<double> ateRmse(const std::vector<TimedPose>& estimate,
                              const std::vector<TimedPose>& groundtruth) {
  if (groundtruth.empty()) return std::nullopt;
  const double t0 = groundtruth.front().time, t1 = groundtruth.back().time;
  double sum = 0.0;
  std::size_t n = 0;
  for (const TimedPose& p : estimate) {
    if (p.time < t0 || p.time > t1) continue;
    sum += (p.pose.head<2>() - interpolatePose(groundtruth, p.time).head<2>()).squaredNorm();
    ++n;
  }
  if (n == 0) return std::nullopt;
  return std::sqrt(sum / static_cast<double>(n));
}

std::optional<double> landmarkRmse(const SlamFilter& filter, const std::map<int, Vec2>& truth) {
  double sum = 0.0;
  std::size_t n = 0;
  for (int id : filter.landmarkIds()) {
    const auto it = truth.find(id);
    if (it == truth.end()) continue;
    sum += (filter.landmark(id) - it->second).squaredNorm();
    ++n;
  }
  if (n == 0) return std::nullopt;
  return std::sqrt(sum / static_cast<double>(n));
}

}  // namespace seif
