#pragma once
// Core vocabulary of seif. Conventions (docs/conventions.md): SI units, state order
// [x, y, theta, l1x, l1y, l2x, ...], angles in radians wrapped to (-pi, pi].
#include <Eigen/Core>

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

/// One range-bearing observation of a landmark with a known identity.
struct Observation {
  int landmark = -1;     ///< landmark id (data association is known)
  double range = 0.0;    ///< [m]
  double bearing = 0.0;  ///< [rad], robot frame, x forward, left positive
};

/// Standard deviations of the control and measurement noise.
struct NoiseModel {
  double sigma_v = 0.01;        ///< forward velocity [m/s]
  double sigma_w = 0.0316;      ///< rotational velocity [rad/s]
  double sigma_range = 0.0447;  ///< [m]
  double sigma_bearing = 0.0548;  ///< [rad]
};

}  // namespace seif
