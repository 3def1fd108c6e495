#pragma once
// Core vocabulary of seif. Conventions (docs/conventions.md): SI units, state order
// [x, y, theta, l1x, l1y, l2x, ...], angles in radians wrapped to (-pi, pi].
#include <Eigen/Core>

#include <optional>
#include <variant>

namespace seif {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat2 = Eigen::Matrix2d;
using Mat3 = Eigen::Matrix3d;
using Mat23 = Eigen::Matrix<double, 2, 3>;
using Mat32 = Eigen::Matrix<double, 3, 2>;
using Pose2 = Eigen::Vector3d;  ///< (x, y, theta)

/// A control of the velocity motion model: forward speed v [m/s], turn rate w [rad/s],
/// applied for dt seconds.
struct VelocityControl {
  double v = 0.0;
  double w = 0.0;
  double dt = 0.0;
};

/// A control of a car-like (Ackermann) vehicle: speed measured at the encoder [m/s] and
/// the steering angle of the front wheels [rad, left positive], applied for dt seconds.
struct AckermannControl {
  double speed = 0.0;
  double steering = 0.0;
  double dt = 0.0;
};

/// A relative-odometry record: the next pose in the frame of the current one (dx, dy, dth)
/// with its own 3x3 covariance (iSAM, g2o and DLR-style logs).
struct OdometryIncrement {
  Vec3 delta = Vec3::Zero();
  Mat3 covariance = Mat3::Identity();
};

/// What moves the vehicle over one step: each motion model (models/) takes one of these.
using MotionInput = std::variant<VelocityControl, AckermannControl, OdometryIncrement>;

/// Landmark id of an observation whose association is unknown (the association step decides).
inline constexpr int kUnknownLandmark = -1;

/// One observation of a point landmark, in the units of the sensor model that made it
/// (range-bearing: (range [m], bearing [rad], sensor frame, x forward, left positive);
/// Cartesian: (x, y) [m] in the sensor frame).
struct Observation {
  int landmark = kUnknownLandmark;  ///< landmark id when the association is known
  Vec2 z = Vec2::Zero();
  std::optional<Mat2> noise;        ///< its own 2x2 covariance; the sensor's default when empty
  /// The id the data names for what was seen, for scoring an association only (simulator
  /// truth, a dataset's own ids when they are hidden from the filter); kUnknownLandmark
  /// when the data names none (clutter, an unmatched raw detection). No filter reads it.
  int truth = kUnknownLandmark;
};

/// Standard deviations of the control and measurement noise.
struct NoiseModel {
  double sigma_v = 0.01;        ///< forward velocity [m/s]
  double sigma_w = 0.0316;      ///< rotational velocity [rad/s]
  double sigma_range = 0.0447;  ///< [m]
  double sigma_bearing = 0.0548;  ///< [rad]
};

}  // namespace seif
