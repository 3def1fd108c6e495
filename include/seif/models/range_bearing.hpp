#pragma once
// Range-bearing measurement of a 2-D point landmark (algorithm.md "Models").
// z = (sqrt(q), atan2(dy, dx) - th), d = y - (px, py), q = d^T d.
#include <seif/core/types.hpp>

namespace seif {

class RangeBearingModel {
 public:
  /// Ranges below this are degenerate (bearing undefined): predict() throws ModelError.
  static constexpr double kMinRange = 1e-9;

  /// Predicted measurement (range, bearing wrapped to (-pi, pi]) and optional Jacobians
  /// J_z_x = dz/dx (2x3), J_z_y = dz/dy (2x2).
  static Vec2 predict(const Pose2& x, const Vec2& y, Mat23* J_z_x = nullptr,
                      Mat2* J_z_y = nullptr);

  /// Inverse model: the landmark seen at z = (range, bearing) from pose x, with
  /// J_y_x = dy/dx (2x3) and J_y_z = dy/dz (2x2). Throws ModelError for range <= 0 or
  /// non-finite input.
  static Vec2 inverse(const Pose2& x, const Vec2& z, Mat23* J_y_x = nullptr,
                      Mat2* J_y_z = nullptr);

  /// Innovation z - zhat with the bearing wrapped to (-pi, pi].
  static Vec2 innovation(const Vec2& z, const Vec2& zhat);

  /// Measurement noise Z = diag(sigma_range^2, sigma_bearing^2).
  static Mat2 noise(double sigma_range, double sigma_bearing);
};

}  // namespace seif
