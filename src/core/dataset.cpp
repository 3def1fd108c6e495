// Merging the independent time stamps of a RobotLog into filter steps
// (include/seif/core/dataset.hpp).
#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/core/dataset.hpp>

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace seif {

Dataset buildDataset(const RobotLog& log) {
  Dataset d;
  d.source = log.source;
  d.groundtruth = log.groundtruth;
  d.landmarks = log.landmarks;
  d.noise = log.noise;
  d.dropped = log.dropped;

  const std::vector<OdometryRecord>& odo = log.odometry;
  const std::vector<MeasurementRecord>& meas = log.measurements;
  for (std::size_t i = 1; i < odo.size(); ++i) {
    if (odo[i].time < odo[i - 1].time) {
      throw DataError(log.source, 0,
                      "odometry row " + std::to_string(i) + " goes backwards in time");
    }
  }

  // Measurements in time order; a stable sort keeps the log order within one stamp.
  std::vector<std::size_t> order(meas.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto earlier = [&](std::size_t a, std::size_t b) { return meas[a].time < meas[b].time; };
  if (!std::is_sorted(order.begin(), order.end(), earlier)) {
    std::stable_sort(order.begin(), order.end(), earlier);
  }

  if (odo.empty()) {
    d.dropped.before_first_control += meas.size();
    return d;
  }
  d.start_time = odo.front().time;

  std::size_t m = 0;  // next measurement (index into order)
  while (m < order.size() && meas[order[m]].time < d.start_time) ++m;
  d.dropped.before_first_control += m;

  d.steps.reserve(odo.size() + (order.size() - m));
  std::size_t i = 0;           // odometry row in force
  double now = d.start_time;   // time reached by the previous step
  while (true) {
    const bool more_meas = m < order.size();
    const bool more_odo = i + 1 < odo.size();
    if (!more_meas && !more_odo) break;
    if (more_meas && (!more_odo || meas[order[m]].time <= odo[i + 1].time)) {
      // Predict with row i up to the measurement stamp, then update with all at that stamp.
      // At a stamp shared with the next odometry row, this comes first (row i ends there).
      Step s;
      s.time = meas[order[m]].time;
      s.u = VelocityControl{odo[i].v, odo[i].w, s.time - now};
      while (m < order.size() && meas[order[m]].time == s.time) {
        const MeasurementRecord& r = meas[order[m]];
        s.observations.push_back(observationOf(r));
        ++m;
      }
      now = s.time;
      d.steps.push_back(std::move(s));
    } else {
      // Row i ends where row i + 1 starts.
      const double t = odo[i + 1].time;
      if (t > now) {
        Step s;
        s.time = t;
        s.u = VelocityControl{odo[i].v, odo[i].w, t - now};
        d.steps.push_back(std::move(s));
        now = t;
      }
      ++i;
    }
  }
  return d;
}

Pose2 interpolatePose(const std::vector<TimedPose>& track, double t) {
  if (track.empty()) throw InvalidArgument("interpolatePose: empty track");
  if (!(t > track.front().time)) return track.front().pose;  // also catches NaN
  if (t >= track.back().time) return track.back().pose;
  // First sample strictly after t; the one before it is at or before t.
  const auto after = std::upper_bound(track.begin(), track.end(), t,
                                      [](double v, const TimedPose& p) { return v < p.time; });
  const TimedPose& a = *(after - 1);
  const TimedPose& b = *after;
  const double s = (t - a.time) / (b.time - a.time);
  Pose2 p;
  p.head<2>() = a.pose.head<2>() + s * (b.pose.head<2>() - a.pose.head<2>());
  p.z() = wrapAngle(a.pose.z() + s * wrapAngle(b.pose.z() - a.pose.z()));
  return p;
}

double timeOutsideTrack(const std::vector<TimedPose>& track, double t) {
  if (track.empty()) throw InvalidArgument("timeOutsideTrack: empty track");
  return std::max({0.0, track.front().time - t, t - track.back().time});
}

std::string startPoseFromGroundTruth(const std::vector<TimedPose>& track, double t) {
  const double gap = timeOutsideTrack(track, t);
  if (!(gap > 1.0)) return "ground truth at the first control";
  std::ostringstream s;
  s << "ground truth's " << (track.front().time > t ? "first" : "last") << " pose, " << gap
    << " s from the first control (the ground truth does not cover it: the start pose is off by what the robot "
       "moved in between)";
  return s.str();
}

}  // namespace seif
