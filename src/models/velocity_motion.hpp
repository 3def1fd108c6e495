#pragma once
// Velocity motion model (Probabilistic Robotics §5.3; algorithm.md "Models").
// The pose increment is written in its exact, branch-free chord form
//   Delta = ( v dt sinc(w dt/2) cos(th + w dt/2),  v dt sinc(w dt/2) sin(th + w dt/2),  w dt ),
// which equals the circular-arc formula -(v/w) sin th + (v/w) sin(th + w dt), ... for w != 0
// and reduces to the straight line (v dt cos th, v dt sin th, w dt) as w -> 0. The only
// branch is the series of sinc for |w dt/2| < 1e-3 (the straight-line limit, tested).
#include <seif/core/types.hpp>

namespace seif {

class VelocityMotionModel {
 public:
  /// Pose increment Delta(x, u); optional Jacobians J_delta_x = dDelta/dx (3x3, only the
  /// heading column is non-zero) and J_delta_u = dDelta/d(v, w) (3x2).
  static Vec3 delta(const Pose2& x, const VelocityControl& u, Mat3* J_delta_x = nullptr,
                    Mat32* J_delta_u = nullptr);

  /// x + Delta(x, u), heading wrapped to (-pi, pi].
  static Pose2 apply(const Pose2& x, const VelocityControl& u);

  /// Process noise in pose space U = V M V^T, V = dDelta/d(v, w), M = diag(sv^2, sw^2).
  static Mat3 processNoise(const Pose2& x, const VelocityControl& u, double sigma_v,
                           double sigma_w);
};

}  // namespace seif
