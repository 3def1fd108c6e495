#include <seif/core/errors.hpp>
#include <seif/filters/information_ops.hpp>
#include <seif/filters/slam_filter.hpp>
#include <seif/models/range_bearing.hpp>

#include <Eigen/LU>
#include <algorithm>

namespace seif {

void informationMotionUpdate(Eigen::Ref<Eigen::MatrixXd> H, Eigen::Ref<Eigen::VectorXd> b,
                             Eigen::Ref<Eigen::VectorXd> mu, const Vec3& delta,
                             const Mat3& J_delta_x, const Mat3& U) {
  // G_x = I + A_x; A_x has only a heading column, so G_x^-1 = I - A_x exactly.
  const Mat3 G_inv = Mat3::Identity() - J_delta_x;
  const Eigen::MatrixXd H_old = H;  // (Hbar - H) mu needs the old matrix
  // Phi = G^-T H G^-1: G^-1 differs from I only in the robot block.
  H.topRows<3>() = (G_inv.transpose() * H.topRows<3>()).eval();
  H.leftCols<3>() = (H.leftCols<3>() * G_inv).eval();
  // kappa = Phi_{:,x} U (I + Phi_xx U)^-1 Phi_{x,:}
  const Mat3 Phi_xx = H.topLeftCorner<3, 3>();
  Mat3 C = U * (Mat3::Identity() + Phi_xx * U).partialPivLu().inverse();
  C = (0.5 * (C + C.transpose())).eval();
  const Eigen::Matrix<double, 3, Eigen::Dynamic> Phi_x = H.topRows<3>();
  H.noalias() -= Phi_x.transpose() * (C * Phi_x);
  // Symmetric by construction up to rounding: restore it exactly.
  H = (0.5 * (H + H.transpose())).eval();
  // b <- b + (Hbar - H) mu + Hbar S_x delta   (the mean need not satisfy H mu = b here:
  // the SEIF's amortised mean does not).
  b.noalias() += (H - H_old) * mu;
  b.noalias() += H.leftCols<3>() * delta;
  mu.head<3>() += delta;
}

MeasurementInformation measurementInformation(const Pose2& x, const Vec2& y,
                                              const Observation& z, const Mat2& Z_inv) {
  Mat23 J_x;
  Mat2 J_y;
  const Vec2 zhat = RangeBearingModel::predict(x, y, &J_x, &J_y);
  Eigen::Matrix<double, 2, 5> J;
  J << J_x, J_y;
  Eigen::Matrix<double, 5, 1> mu_local;
  mu_local << x, y;
  const Vec2 nu = RangeBearingModel::innovation(Vec2(z.range, z.bearing), zhat);
  const Eigen::Matrix<double, 5, 2> JtZ = J.transpose() * Z_inv;
  MeasurementInformation info;
  info.H = JtZ * J;
  info.b = JtZ * (nu + J * mu_local);
  return info;
}

FilterStats denseLinkStats(const Eigen::MatrixXd& H) {
  FilterStats s;
  const int landmarks = static_cast<int>((H.rows() - 3) / 2);
  s.landmarks = static_cast<std::size_t>(landmarks);
  auto offset = [](int v) { return v == 0 ? 0 : 3 + 2 * (v - 1); };
  auto size = [](int v) { return v == 0 ? 3 : 2; };
  std::vector<std::size_t> degree(static_cast<std::size_t>(landmarks) + 1, 0);
  for (int i = 0; i <= landmarks; ++i) {
    for (int j = i + 1; j <= landmarks; ++j) {
      if (H.block(offset(i), offset(j), size(i), size(j)).cwiseAbs().maxCoeff() > 0.0) {
        ++s.links;
        ++degree[static_cast<std::size_t>(i)];
        ++degree[static_cast<std::size_t>(j)];
      }
    }
  }
  s.robot_links = degree[0];
  for (int i = 1; i <= landmarks; ++i) {
    s.max_landmark_links = std::max(s.max_landmark_links, degree[static_cast<std::size_t>(i)]);
  }
  const std::size_t vars = static_cast<std::size_t>(landmarks) + 1;
  s.blocks_touched = vars * vars;
  return s;
}

}  // namespace seif
