#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/filters/eif_slam.hpp>
#include <seif/filters/information_ops.hpp>

#include <Eigen/LU>
#include <sstream>

namespace seif {

EifSlam::EifSlam(const Pose2& initial_pose, const FilterConfig& config)
    : SlamFilter(config), config_(config), book_("eif", initial_pose, config), H_(Mat3::Zero()), b_(Vec3::Zero()), mu_(initial_pose) {
  H_.diagonal() = config.initial_pose_sigma.cwiseAbs2().cwiseInverse();
  b_ = H_ * mu_;
}

Pose2 EifSlam::pose() const { return wrapHeading(Pose2(mu_.head<3>())); }

Vec2 EifSlam::landmark(int id) const {
  return mu_.segment<2>(StateLayout::landmark(book_.require(id)));
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
  const int i = StateLayout::landmark(book_.require(id));
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(H_.rows(), 2);
  E.middleRows<2>(i).setIdentity();
  return factor().solve(E).middleRows<2>(i);
}

FilterStats EifSlam::stats() const { return denseLinkStats(H_); }

std::size_t EifSlam::robotLinks() const {
  std::size_t n = 0;
  for (int s = 0; s < book_.size(); ++s) {
    if (H_.block<3, 2>(0, StateLayout::landmark(s)).cwiseAbs().maxCoeff() > 0.0) ++n;
  }
  return n;
}

PredictedMeasurement EifSlam::predictMeasurement(int id, const MeasurementModel& sensor,
                                                const Mat2& R) const {
  const int i = StateLayout::landmark(book_.require(id));
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(H_.rows(), 5);
  E.topLeftCorner<3, 3>().setIdentity();
  E.block<2, 2>(i, 3).setIdentity();
  const Eigen::MatrixXd cols = factor().solve(E);  // Sigma's columns of the pose and landmark
  return innovation(sensor, mu_.head<3>(), mu_.segment<2>(i), cols.topLeftCorner<3, 3>(),
                    cols.block<3, 2>(0, 3), cols.block<2, 2>(i, 3), R);
}

void EifSlam::predict(const MotionIncrement& increment) {
  const MotionIncrement m = book_.motionIncrement(increment, mu_.head<2>());
  Eigen::MatrixXd workspace(6, H_.cols());
  informationMotionUpdate(H_, b_, mu_, m.delta, m.J_delta_x, m.U, workspace);
  llt_valid_ = false;
}

void EifSlam::recoverMean() {
  mu_ = factor().solve(b_);
}

void EifSlam::update(std::span<const Observation> observations, const MeasurementModel& sensor) {
  if (observations.empty()) return;
  const std::span<const PlannedObservation> plan = book_.plan(
      observations, sensor, mu_.head<3>(), [&](int slot) { return Vec2(mu_.segment<2>(StateLayout::landmark(slot))); });
  // All or nothing: a failure (an indefinite H) restores the state before the update.
  const Eigen::MatrixXd H0 = H_;
  const Eigen::VectorXd b0 = b_, mu0 = mu_;
  try {
    applyPlan(plan, sensor);
  } catch (...) {
    H_ = H0;
    b_ = b0;
    mu_ = mu0;
    llt_valid_ = false;
    throw;
  }
  book_.commit();
}

void EifSlam::applyPlan(std::span<const PlannedObservation> plan, const MeasurementModel& sensor) {
  // New landmarks enter with no information and the inverse-model mean (algorithm.md).
  for (const PlannedObservation& p : plan) {
    if (!p.first) continue;
    const Eigen::Index n = H_.rows();
    H_.conservativeResize(n + 2, n + 2);
    H_.rightCols<2>().setZero();
    H_.bottomRows<2>().setZero();
    b_.conservativeResize(n + 2);
    b_.tail<2>().setZero();
    mu_.conservativeResize(n + 2);
    mu_.tail<2>() = p.initial;
  }
  // Paper eq. (21-22), all observations linearised at the prior mean (with FEJ: each
  // landmark's Jacobians at its first estimate); gross outliers are not in the plan.
  const Pose2 x = mu_.head<3>();
  for (const PlannedObservation& p : plan) {
    const Eigen::Index l = StateLayout::landmark(p.slot);
    const MeasurementInformation info = measurementInformation(sensor, x, mu_.segment<2>(l), *p.z,
                                                               sensor.noise(*p.z).inverse(), p.jacobian_landmark);
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
