#include "filters/first_estimates.hpp"

#include <Eigen/Cholesky>

namespace seif {

MotionIncrement FirstEstimates::fejIncrement(const MotionIncrement& m, const Vec2& position) {
  const Vec2 next = position + m.delta.head<2>();  // p_{k+1|k}
  const Vec2 d = next - predicted_;                // p_{k+1|k} - p_{k|k-1}
  MotionIncrement fej = m;
  fej.J_delta_x.block<2, 1>(0, 2) = Vec2(-d.y(), d.x());  // S d (the FEJ-EKF state Jacobian)
  predicted_ = next;
  return fej;
}

void ObservabilityConstraint::apply(Mat23& J_x, Mat2& J_y) const {
  Eigen::Matrix<double, 5, 3> N = Eigen::Matrix<double, 5, 3>::Zero();
  N.block<2, 2>(0, 0).setIdentity();
  N.block<2, 1>(0, 2) = Vec2(-robot.y(), robot.x());  // J p
  N(2, 2) = 1.0;
  N.block<2, 2>(3, 0).setIdentity();
  N.block<2, 1>(3, 2) = Vec2(-landmark.y(), landmark.x());  // J l
  Eigen::Matrix<double, 2, 5> J;
  J << J_x, J_y;
  const Eigen::Matrix<double, 2, 3> JN = J * N;
  J.noalias() -= JN * (N.transpose() * N).ldlt().solve(N.transpose());
  J_x = J.leftCols<3>();
  J_y = J.rightCols<2>();
}

}  // namespace seif
