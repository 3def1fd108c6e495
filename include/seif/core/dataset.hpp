#pragma once
// The vocabulary every source of data shares (docs/architecture.md "The flow"):
//   events   time-ordered records a reader or the simulator yields: a control or odometry
//            record, the observations of one instant, a ground-truth pose, a GPS fix;
//   Step     one filter cycle (predict with an input, then update with observations),
//            which the run loop assembles from events (eval/run.hpp);
//   RobotLog one robot's records in memory, as the simulator makes them and the MRCLAM
//            layout stores them; buildDataset() merges their stamps into steps.
#include <seif/core/types.hpp>

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace seif {

struct OdometryRecord {
  double time = 0.0;  ///< [s]
  double v = 0.0;     ///< forward velocity [m/s]
  double w = 0.0;     ///< rotational velocity [rad/s], CCW positive
};

struct MeasurementRecord {
  double time = 0.0;
  int subject = -1;  ///< landmark subject number (after mapping the barcode); kClutterSubject: none
  double range = 0.0;
  double bearing = 0.0;
};

/// The subject of a false detection (the simulator's clutter): no landmark. MRCLAM numbers
/// robots 1-5 and landmarks from 6; seif's own folders list clutter as subject 0 in
/// Barcodes.dat (io/mrclam.hpp), which the UTIAS data never do.
inline constexpr int kClutterSubject = 0;

/// The observation a measurement record makes: landmark = truth = subject, and for clutter
/// neither (kUnknownLandmark): a filter with known association refuses it (ModelError).
inline Observation observationOf(const MeasurementRecord& m) {
  const int id = m.subject == kClutterSubject ? kUnknownLandmark : m.subject;
  return Observation{id, Vec2(m.range, m.bearing), std::nullopt, id};
}

struct TimedPose {
  double time = 0.0;
  Pose2 pose = Pose2::Zero();
};

/// A GPS fix: position in the dataset's local metric frame [m].
struct GpsFix {
  double time = 0.0;
  Vec2 position = Vec2::Zero();
};

// --- events --------------------------------------------------------------------------------

/// A control or odometry record. A VelocityControl or AckermannControl is a rate, in force
/// from `time` until the next control (its dt is ignored: the run loop sets it); an
/// OdometryIncrement is the motion from the previous record's pose to the pose at `time`.
struct ControlEvent {
  double time = 0.0;
  MotionInput input;
  long long pose = -1;  ///< id of the pose reached, when the source numbers poses (graph files)
};

/// The observations made at one instant (one linearisation point).
struct ObservationEvent {
  double time = 0.0;
  std::vector<Observation> observations;
};

/// One event of a data stream. At equal stamps a source yields observations before the
/// control that starts there (that control acts after them).
using Event = std::variant<ControlEvent, ObservationEvent, TimedPose, GpsFix>;

inline double eventTime(const Event& e) {
  return std::visit([](const auto& v) { return v.time; }, e);
}
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
  MotionInput u;
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
/// applies every measurement with exactly that stamp (in log order; observationOf(): landmark
/// = truth = subject, clutter has neither). Steps with dt == 0 and no observation are not emitted, so the sum of all dt is
/// the last step time minus start_time. start_time = first odometry stamp. With no odometry
/// at all, every measurement is dropped as before_first_control and there are no steps.
/// Throws DataError (naming log.source) if the odometry stamps go backwards.
Dataset buildDataset(const RobotLog& log);

/// The ground-truth pose at time t, interpolated linearly (heading along the shortest
/// arc, result wrapped to (-pi, pi]); clamps outside the recorded span. Requires a
/// non-empty, time-sorted track (throws InvalidArgument when empty).
Pose2 interpolatePose(const std::vector<TimedPose>& track, double t);
/// How far [s] `t` lies outside the track's time span (0 within it): how far interpolatePose()
/// had to take an end pose for it.
double timeOutsideTrack(const std::vector<TimedPose>& track, double t);
/// A start pose's source when the ground truth interpolated at the first control came from
/// an end of the track over a second away: "ground truth at the first control" otherwise.
std::string startPoseFromGroundTruth(const std::vector<TimedPose>& track, double t);

}  // namespace seif
