#include "io/robot_log_source.hpp"
#include <seif/models/range_bearing.hpp>

#include <limits>

namespace seif {

RobotLogSource::RobotLogSource(const RobotLog& log, const NoiseModel& noise, NoiseForm form) : log_(log) {
  info_.source = log.source;
  info_.format = "memory";
  info_.motion = std::make_shared<VelocityModel>(noise.sigma_v, noise.sigma_w, form);
  info_.sensor = std::make_shared<RangeBearingModel>(noise.sigma_range, noise.sigma_bearing);
  info_.landmarks = log.landmarks;
  info_.has_groundtruth = !log.groundtruth.empty();
  if (!log.odometry.empty() && info_.has_groundtruth) {
    info_.start_pose = interpolatePose(log.groundtruth, log.odometry.front().time);
    info_.start_pose_source = startPoseFromGroundTruth(log.groundtruth, log.odometry.front().time);
  } else {
    info_.start_pose_source = "origin: the log has no ground truth";
  }
}

bool RobotLogSource::next(Event& event) {
  constexpr double kEnd = std::numeric_limits<double>::infinity();
  const double t_odo = odometry_ < log_.odometry.size() ? log_.odometry[odometry_].time : kEnd;
  const double t_meas = measurement_ < log_.measurements.size() ? log_.measurements[measurement_].time : kEnd;
  const double t_gt = groundtruth_ < log_.groundtruth.size() ? log_.groundtruth[groundtruth_].time : kEnd;
  if (t_odo == kEnd && t_meas == kEnd && t_gt == kEnd) return false;
  if (t_gt < t_meas && t_gt < t_odo) {  // ground truth first only when strictly earlier
    event = log_.groundtruth[groundtruth_++];
  } else if (t_meas <= t_odo) {  // observations before the control starting at their stamp
    ObservationEvent obs{t_meas, {}};
    while (measurement_ < log_.measurements.size() && log_.measurements[measurement_].time == t_meas) {
      const MeasurementRecord& m = log_.measurements[measurement_++];
      obs.observations.push_back(observationOf(m));
    }
    event = std::move(obs);
  } else {
    const OdometryRecord& r = log_.odometry[odometry_++];
    event = ControlEvent{r.time, VelocityControl{r.v, r.w, 0.0}};
  }
  return true;
}

double RobotLogSource::progress() const {
  return log_.odometry.empty() ? 1.0 : static_cast<double>(odometry_) / static_cast<double>(log_.odometry.size());
}

std::map<std::string, std::size_t> RobotLogSource::dropped() const {
  return {{"robot_measurements", log_.dropped.robot_measurements}, {"unknown_barcodes", log_.dropped.unknown_barcodes}};
}

}  // namespace seif
