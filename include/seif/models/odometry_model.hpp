#pragma once
// Relative odometry (algorithm.md "Models"): u = (dx, dy, dth) in the robot frame with its
// own covariance C per record (iSAM, g2o, DLR-style logs):
//   Delta = (R(th) (dx, dy), dth),   U = J C J^T,  J = blockdiag(R(th), 1).
#include <seif/models/motion_model.hpp>

namespace seif {

class OdometryModel final : public MotionModel {
 public:
  std::string describe() const override;
  MotionIncrement linearize(const Pose2& x, const MotionInput& u) const override;
  bool equivariant() const override { return true; }
  MotionIncrement linearize(const Pose2& x, const OdometryIncrement& u) const;
};

}  // namespace seif
