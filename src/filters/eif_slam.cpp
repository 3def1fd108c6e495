#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include "filters/eif_slam.hpp"
#include "filters/information_ops.hpp"
#include "filters/invariant.hpp"
#include "filters/option_values.hpp"

#include <Eigen/LU>
#include <sstream>

namespace seif {

EifSlam::EifSlam(const Pose2& initial_pose, const FilterConfig& config)
    : SlamFilter(config), config_(config), book_("eif", initial_pose, config), H_(Mat3::Zero()), b_(Vec3::Zero()), mu_(initial_pose) {
  checkFilterOptions("eif", config);  // each range as its spec and flag have it
  H_.diagonal() = startInformation(config.initial_pose_sigma, "eif");
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

Marginal EifSlam::marginal(std::span<const int> landmarks, bool pose, MarginalMode mode) const {
  std::vector<int> slots;
  for (int id : landmarks) slots.push_back(book_.require(id));
  const std::vector<Eigen::Index> rows = stateIndices(slots, pose);
  Marginal m;
  m.mean = mu_(rows);
  if (mode == MarginalMode::Local) {
    std::vector<int> vars;
    if (pose) vars.push_back(-1);
    vars.insert(vars.end(), slots.begin(), slots.end());
    const auto at = [](int v) { return v < 0 ? Eigen::Index(0) : StateLayout::landmark(v); };
    const auto dim = [](int v) { return v < 0 ? Eigen::Index(3) : Eigen::Index(2); };
    m.covariance = localMarginalCovariance(
        vars,
        [&](int v, std::vector<BlanketLink>& out) {  // every variable with a non-zero block beside v
          const Eigen::VectorXd dv = H_.diagonal().segment(at(v), dim(v));
          for (int c = -1; c < book_.size(); ++c) {
            const auto B = H_.block(at(v), at(c), dim(v), dim(c));
            if (c != v && B.cwiseAbs().maxCoeff() > 0.0) {
              out.push_back({c, linkStrength(dv, B, H_.diagonal().segment(at(c), dim(c))), &H_(at(v), at(c)), H_.rows()});
            }
          }
        },
        [&](int v) { return Eigen::MatrixXd(H_.block(at(v), at(v), dim(v), dim(v))); }, "eif");
    return m;
  }
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(H_.rows(), static_cast<Eigen::Index>(rows.size()));
  for (std::size_t k = 0; k < rows.size(); ++k) E(rows[k], static_cast<Eigen::Index>(k)) = 1.0;
  m.covariance = factor().solve(E)(rows, Eigen::all);  // Sigma's columns of the variables
  return m;
}

void EifSlam::deleteSlot(int slot) {
  const Eigen::Index i = StateLayout::landmark(slot), n = H_.rows(), last = n - 2;
  if (i != last) {
    b_.segment<2>(i) = b_.tail<2>();
    mu_.segment<2>(i) = mu_.tail<2>();
    H_.middleRows<2>(i) = H_.bottomRows<2>();
    H_.middleCols<2>(i) = H_.rightCols<2>();
    H_.block<2, 2>(i, i) = H_.bottomRightCorner<2, 2>();
  }
  H_.conservativeResize(last, last);
  b_.conservativeResize(last);
  mu_.conservativeResize(last);
  book_.removeSlot(slot);
  llt_valid_ = false;
}

void EifSlam::removeLandmark(int id) {
  const int slot = book_.require(id);
  const Eigen::Index l = StateLayout::landmark(slot);
  // The Schur complement over y_l: H -= H_{:,l} H_ll^-1 H_{l,:}, b -= H_{:,l} H_ll^-1 b_l.
  const Eigen::LLT<Mat2> llt(H_.block<2, 2>(l, l));
  if (llt.info() != Eigen::Success) {
    throw NumericError("eif: information of landmark " + std::to_string(id) + " is not positive definite");
  }
  const Eigen::MatrixXd H_col = H_.middleCols<2>(l);
  const Eigen::MatrixXd W = llt.solve(H_col.transpose());  // H_ll^-1 H_{l,:}
  b_ -= H_col * llt.solve(b_.segment<2>(l));
  H_ -= H_col * W;
  H_ = (0.5 * (H_ + H_.transpose())).eval();
  deleteSlot(slot);  // its rows are zero now; the others' marginal mean is unchanged
}

void EifSlam::mergeLandmarks(int keep, int drop) {
  const int k = book_.require(keep), d = book_.require(drop);
  if (k == d) throw InvalidArgument("eif: cannot merge landmark " + std::to_string(keep) + " with itself");
  const Eigen::Index ik = StateLayout::landmark(k), id = StateLayout::landmark(d);
  // H' = T^T H T, b' = T^T b: drop's rows, then columns, added into keep's.
  H_.middleRows<2>(ik) += H_.middleRows<2>(id);
  H_.middleCols<2>(ik) += H_.middleCols<2>(id);
  b_.segment<2>(ik) += b_.segment<2>(id);
  deleteSlot(d);
  recoverMean();
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
  if (config_.iterations > 1 || config_.linearization == Linearization::Invariant) {
    applyIterated(plan, sensor);
    return;
  }
  // Paper eq. (21-22), all observations linearised at the prior mean (with FEJ: each
  // landmark's Jacobians at its first estimate); gross outliers are not in the plan.
  const Pose2 x = mu_.head<3>();
  for (const PlannedObservation& p : plan) {
    const Eigen::Index l = StateLayout::landmark(p.slot);
    const MeasurementInformation info = measurementInformation(sensor, x, mu_.segment<2>(l), *p.z,
                                                               sensor.noise(*p.z).inverse(), p.jacobian_landmark,
                                                               std::nullopt, p.constraint);
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

void EifSlam::applyIterated(std::span<const PlannedObservation> plan, const MeasurementModel& sensor) {
  // The iterated update in information form, the EKF's to rounding: iteration i linearises
  // at s_i = mu0 + delta_i (invariant: the retraction of delta_i) and solves
  // (H0 + sum J^T Z^-1 J) delta_{i+1} = sum J^T Z^-1 (z - h(s_i) + J delta_i). A first
  // sighting stays linearised at the prior, where the EKF initialises the landmark from it.
  const bool invariant = config_.linearization == Linearization::Invariant;
  const Eigen::MatrixXd H0 = H_;
  const Eigen::VectorXd mu0 = mu_;
  const Eigen::Index n = H_.rows();
  Eigen::VectorXd delta = Eigen::VectorXd::Zero(n), s = mu0, g(n);
  for (int it = 0; it < config_.iterations; ++it) {
    H_ = H0;
    g.setZero();
    for (const PlannedObservation& p : plan) {
      const Eigen::Index l = StateLayout::landmark(p.slot);
      const bool fixed = p.first || it == 0;
      const Eigen::VectorXd& at = fixed ? mu0 : s;
      Mat23 Jx;
      Mat2 Jy;
      const Vec2 zhat = sensor.predict(at.head<3>(), at.segment<2>(l), &Jx, &Jy);
      if (p.jacobian_landmark) sensor.predict(at.head<3>(), *p.jacobian_landmark, &Jx, &Jy);
      p.constrain(Jx, Jy);
      if (invariant && !fixed) Jx.col(2) = invariant::anchoredHeadingColumn(Jy, mu0.head<2>(), mu0.segment<2>(l));
      Vec2 nu = sensor.residual(p.z->z, zhat);
      if (!fixed) nu += Jx * delta.head<3>() + Jy * delta.segment<2>(l);
      const Mat2 Z_inv = sensor.noise(*p.z).inverse();
      const Eigen::Matrix<double, 3, 2> JxZ = Jx.transpose() * Z_inv;
      const Mat2 JyZ = Jy.transpose() * Z_inv;
      H_.topLeftCorner<3, 3>() += JxZ * Jx;
      H_.block<3, 2>(0, l) += JxZ * Jy;
      H_.block<2, 3>(l, 0) += JyZ * Jx;
      H_.block<2, 2>(l, l) += JyZ * Jy;
      g.head<3>() += JxZ * nu;
      g.segment<2>(l) += JyZ * nu;
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(H_);
    if (llt.info() != Eigen::Success) throw NumericError("eif: information is not positive definite after an update");
    delta = llt.solve(g);
    s = invariant ? invariant::retract(mu0, delta) : Eigen::VectorXd(mu0 + delta);
  }
  mu_ = s;
  if (invariant) invariant::reanchorInformation(H_, invariant::leverArms(mu_) - invariant::leverArms(mu0));
  b_ = H_ * mu_;
  llt_valid_ = false;
}

}  // namespace seif
