#pragma once
// The one data flow of seif:  simulator or files -> RobotLog -> Dataset (steps) -> filter.
// A RobotLog mirrors the UTIAS MRCLAM files of one robot (barcodes already mapped to
// subjects); buildDataset() merges its independent time stamps into filter steps.
#include <seif/core/types.hpp>

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace seif {

struct OdometryRecord {
  double time = 0.0;  ///< [s]
  double v = 0.0;     ///< forward velocity [m/s]
  double w = 0.0;     ///< rotational velocity [rad/s], CCW positive
};

struct MeasurementRecord {
  double time = 0.0;
  int subject = -1;  ///< landmark subject number (after mapping the barcode)
  double range = 0.0;
  double bearing = 0.0;
};

struct TimedPose {
  double time = 0.0;
  Pose2 pose = Pose2::Zero();
};

/// What was dropped while reading, and why (reported, never silently lost).
struct DropCounts {
  std::size_t robot_measurements = 0;     ///< measurements of other robots (subjects 1-5)
  std::size_t unknown_barcodes = 0;       ///< barcodes in no list
  std::size_t before_first_control = 0;   ///< measurements older than the first odometry row
};

/// One robot's log, as in the MRCLAM layout. Records are sorted by time.
struct RobotLog {
  std::string source;  ///< folder it came from (for messages)
  int robot = 1;
  std::vector<OdometryRecord> odometry;
  std::vector<MeasurementRecord> measurements;
  std::vector<TimedPose> groundtruth;       ///< may be empty
  std::map<int, Vec2> landmarks;            ///< ground-truth landmark positions; may be empty
  std::optional<NoiseModel> noise;          ///< the true noise, when the log says it (meta.json)
  DropCounts dropped;
};

/// One filter cycle: predict with u (which ends at `time`), then update with the
/// observations made at `time` (possibly none).
struct Step {
  double time = 0.0;
  VelocityControl u;
  std::vector<Observation> observations;
};

struct Dataset {
  std::string source;
  double start_time = 0.0;
  std::vector<Step> steps;
  std::vector<TimedPose> groundtruth;  ///< may be empty
  std::map<int, Vec2> landmarks;       ///< ground truth; may be empty
  std::optional<NoiseModel> noise;
  DropCounts dropped;
};

/// Merges odometry rows and measurement stamps into steps. Odometry row i holds from its
/// stamp to the next row's; a measurement inside that interval splits the prediction at
/// its stamp, and measurements sharing a stamp form one update. At equal stamps the
/// measurements come before the control that starts there. Measurements before the first
/// odometry row are dropped and counted; those after the last row are applied with the
/// last control.
///
/// Precisely: step times are the odometry stamps after the first and the measurement stamps
/// (at or after the first odometry stamp); each step predicts with the control in force
/// from the previous step's time (start_time for the first) up to its own time, then
/// applies every measurement with exactly that stamp (in log order; Observation::landmark =
/// subject). Steps with dt == 0 and no observation are not emitted, so the sum of all dt is
/// the last step time minus start_time. start_time = first odometry stamp. With no odometry
/// at all, every measurement is dropped as before_first_control and there are no steps.
/// Throws DataError (naming log.source) if the odometry stamps go backwards.
Dataset buildDataset(const RobotLog& log);

/// The ground-truth pose at time t, interpolated linearly (heading along the shortest
/// arc, result wrapped to (-pi, pi]); clamps outside the recorded span. Requires a
/// non-empty, time-sorted track (throws std::invalid_argument when empty).
Pose2 interpolatePose(const std::vector<TimedPose>& track, double t);

}  // namespace seif
