#pragma once
// Range-bearing measurement of a 2-D point landmark (algorithm.md "Models"), in the sensor
// frame s: z = (sqrt(q), atan2(dy, dx) - th_s), d = y - s_xy, q = d^T d.
#include <seif/models/measurement_model.hpp>

namespace seif {

class RangeBearingModel final : public MeasurementModel {
 public:
  /// Ranges below this are degenerate (bearing undefined): predict() throws ModelError.
  static constexpr double kMinRange = 1e-9;

  RangeBearingModel(double sigma_range, double sigma_bearing, const Pose2& mount = Pose2::Zero());
  RangeBearingModel(const Mat2& noise, const Pose2& mount = Pose2::Zero());

  std::string describe() const override;
  /// z - zhat with the bearing wrapped to (-pi, pi].
  Vec2 residual(const Vec2& z, const Vec2& zhat) const override;
  /// The bearing's: 2 pi.
  Vec2 period() const override;

 protected:
  Vec2 predictFromSensor(const Pose2& s, const Vec2& y, Mat23* J_z_s, Mat2* J_z_y) const override;
  /// Throws ModelError for range <= 0 or non-finite input.
  Vec2 inverseFromSensor(const Pose2& s, const Vec2& z, Mat23* J_y_s, Mat2* J_y_z) const override;
};

}  // namespace seif
