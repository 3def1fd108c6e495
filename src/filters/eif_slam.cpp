#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/filters/eif_slam.hpp>
#include <seif/filters/information_ops.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/models/velocity_motion.hpp>

#include <Eigen/LU>
#include <sstream>

namespace seif {

EifSlam::EifSlam(const Pose2& initial_pose, const FilterConfig& config)
    : config_(config), gate_(config.outlier_gate), H_(Mat3::Zero()), b_(Vec3::Zero()), mu_(initial_pose) {
  H_.diagonal() = config.initial_pose_sigma.cwiseAbs2().cwiseInverse();
  b_ = H_ * mu_;
}

Pose2 EifSlam::pose() const { return wrapHeading(Pose2(mu_.head<3>())); }

Vec2 EifSlam::landmark(int id) const {
  return mu_.segment<2>(LandmarkIndex::stateIndex(index_.require(id, "eif")));
}

const Eigen::LLT<Eigen::MatrixXd>& EifSlam::factor() const {
  if (!llt_valid_) {
    llt_.compute(H_);
    if (llt_.info() != Eigen::Success) {
      throw NumericError("eif: the information matrix is not positive definite");
    }
    llt_valid_ = true;
  }
  return llt_;
}

Eigen::MatrixXd EifSlam::covariance() const {
  return factor().solve(Eigen::MatrixXd::Identity(H_.rows(), H_.cols()));
}

Mat3 EifSlam::poseCovariance() const {
  return factor().solve(Eigen::MatrixXd::Identity(H_.rows(), 3)).topRows<3>();
}

Mat2 EifSlam::landmarkCovariance(int id) const {
  const int i = LandmarkIndex::stateIndex(index_.require(id, "eif"));
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(H_.rows(), 2);
  E.middleRows<2>(i).setIdentity();
  return factor().solve(E).middleRows<2>(i);
}

FilterStats EifSlam::stats() const { return denseLinkStats(H_); }

std::size_t EifSlam::robotLinks() const {
  std::size_t n = 0;
  for (int s = 0; s < index_.size(); ++s) {
    if (H_.block<3, 2>(0, LandmarkIndex::stateIndex(s)).cwiseAbs().maxCoeff() > 0.0) ++n;
  }
  return n;
}

void EifSlam::predict(const VelocityControl& u) {
  Mat3 J_x;
  const Pose2 x = mu_.head<3>();
  const Vec3 delta = VelocityMotionModel::delta(x, u, &J_x);
  const Mat3 U = VelocityMotionModel::processNoise(x, u, config_.noise.sigma_v, config_.noise.sigma_w);
  Eigen::MatrixXd workspace(6, H_.cols());
  informationMotionUpdate(H_, b_, mu_, delta, J_x, U, workspace);
  llt_valid_ = false;
}

void EifSlam::recoverMean() {
  mu_ = factor().solve(b_);
}

void EifSlam::update(std::span<const Observation> observations) {
  if (observations.empty()) return;
  const Mat2 Z_inv =
      RangeBearingModel::noise(config_.noise.sigma_range, config_.noise.sigma_bearing).inverse();
  // New landmarks enter with no information and the inverse-model mean (algorithm.md).
  for (const Observation& z : observations) {
    if (index_.find(z.landmark) >= 0) continue;
    const Vec2 y = RangeBearingModel::inverse(mu_.head<3>(), Vec2(z.range, z.bearing));
    index_.add(z.landmark);
    const Eigen::Index n = H_.rows();
    H_.conservativeResize(n + 2, n + 2);
    H_.rightCols<2>().setZero();
    H_.bottomRows<2>().setZero();
    b_.conservativeResize(n + 2);
    b_.tail<2>().setZero();
    mu_.conservativeResize(n + 2);
    mu_.tail<2>() = y;
  }
  // Paper eq. (21-22), all observations linearised at the prior mean; gross outliers
  // (OutlierGate) are dropped.
  const Pose2 x = mu_.head<3>();
  for (const Observation& z : observations) {
    const Eigen::Index l = LandmarkIndex::stateIndex(index_.find(z.landmark));
    if (gate_.rejects(x, mu_.segment<2>(l), z, Z_inv)) continue;
    const MeasurementInformation info = measurementInformation(x, mu_.segment<2>(l), z, Z_inv);
    H_.topLeftCorner<3, 3>() += info.H.topLeftCorner<3, 3>();
    H_.block<3, 2>(0, l) += info.H.topRightCorner<3, 2>();
    H_.block<2, 3>(l, 0) += info.H.bottomLeftCorner<2, 3>();
    H_.block<2, 2>(l, l) += info.H.bottomRightCorner<2, 2>();
    b_.head<3>() += info.b.head<3>();
    b_.segment<2>(l) += info.b.tail<2>();
  }
  llt_valid_ = false;
  recoverMean();
}

}  // namespace seif
