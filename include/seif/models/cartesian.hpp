#pragma once
// A landmark measured as a point (x, y) in the sensor frame s (algorithm.md "Models";
// the LANDMARK records of iSAM files, EDGE_SE2_XY of g2o):  z = R(th_s)^T (y - s_xy).
#include <seif/models/measurement_model.hpp>

namespace seif {

class CartesianModel final : public MeasurementModel {
 public:
  explicit CartesianModel(const Mat2& noise, const Pose2& mount = Pose2::Zero());

  std::string describe() const override;

 protected:
  Vec2 predictFromSensor(const Pose2& s, const Vec2& y, Mat23* J_z_s, Mat2* J_z_y) const override;
  Vec2 inverseFromSensor(const Pose2& s, const Vec2& z, Mat23* J_y_s, Mat2* J_y_z) const override;
};

}  // namespace seif
