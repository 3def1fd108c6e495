#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include "filters/ekf_slam.hpp"
#include "filters/information_ops.hpp"
#include "filters/invariant.hpp"
#include "filters/option_values.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <sstream>

namespace seif {

EkfSlam::EkfSlam(const Pose2& initial_pose, const FilterConfig& config)
    : SlamFilter(config), config_(config), book_("ekf", initial_pose, config), mu_(initial_pose), sigma_(Mat3::Zero()) {
  checkFilterOptions("ekf", config);  // each range as its spec and flag have it
  sigma_.diagonal() = config.initial_pose_sigma.cwiseAbs2();
}

Pose2 EkfSlam::pose() const { return wrapHeading(Pose2(mu_.head<3>())); }

Vec2 EkfSlam::landmark(int id) const {
  return mu_.segment<2>(StateLayout::landmark(book_.require(id)));
}

Mat2 EkfSlam::landmarkCovariance(int id) const {
  const int i = StateLayout::landmark(book_.require(id));
  return sigma_.block<2, 2>(i, i);
}

Eigen::VectorXd EkfSlam::mean() const { return mu_; }

Eigen::MatrixXd EkfSlam::information() const {
  Eigen::LLT<Eigen::MatrixXd> llt(sigma_);
  return llt.solve(Eigen::MatrixXd::Identity(sigma_.rows(), sigma_.cols()));
}

FilterStats EkfSlam::stats() const { return denseLinkStats(information()); }

Marginal EkfSlam::marginal(std::span<const int> landmarks, bool pose, MarginalMode) const {
  std::vector<int> slots;
  for (int id : landmarks) slots.push_back(book_.require(id));
  const std::vector<Eigen::Index> rows = stateIndices(slots, pose);
  return {mu_(rows), sigma_(rows, rows)};
}

void EkfSlam::deleteSlot(int slot) {
  const Eigen::Index i = StateLayout::landmark(slot), n = sigma_.rows(), last = n - 2;
  if (i != last) {  // the last landmark's rows and columns move into slot's
    mu_.segment<2>(i) = mu_.tail<2>();
    sigma_.middleRows<2>(i) = sigma_.bottomRows<2>();
    sigma_.middleCols<2>(i) = sigma_.rightCols<2>();
    sigma_.block<2, 2>(i, i) = sigma_.bottomRightCorner<2, 2>();
  }
  mu_.conservativeResize(last);
  sigma_.conservativeResize(last, last);
  book_.removeSlot(slot);
}

void EkfSlam::removeLandmark(int id) { deleteSlot(book_.require(id)); }

void EkfSlam::mergeLandmarks(int keep, int drop) {
  const int k = book_.require(keep), d = book_.require(drop);
  if (k == d) throw InvalidArgument("ekf: cannot merge landmark " + std::to_string(keep) + " with itself");
  // Condition on A y = y_keep - y_drop = 0, a noiseless measurement: S = A Sigma A^T,
  // K = Sigma A^T S^-1, mu -= K A mu, Sigma -= K A Sigma.
  const Eigen::Index ik = StateLayout::landmark(k), id = StateLayout::landmark(d);
  const Eigen::MatrixXd SAt = sigma_.middleCols<2>(ik) - sigma_.middleCols<2>(id);  // Sigma A^T
  const Mat2 S = SAt.middleRows<2>(ik) - SAt.middleRows<2>(id);
  const Eigen::LLT<Mat2> llt(0.5 * (S + S.transpose()));
  if (llt.info() != Eigen::Success) {
    throw NumericError("ekf: landmarks " + std::to_string(keep) + " and " + std::to_string(drop) +
                       " cannot be merged: their difference has no uncertainty left");
  }
  const Eigen::MatrixXd K = llt.solve(SAt.transpose()).transpose();
  mu_ -= K * (mu_.segment<2>(ik) - mu_.segment<2>(id));
  sigma_ -= K * SAt.transpose();
  sigma_ = (0.5 * (sigma_ + sigma_.transpose())).eval();
  deleteSlot(d);
}

void EkfSlam::predict(const MotionIncrement& increment) {
  const MotionIncrement m = book_.motionIncrement(increment, mu_.head<2>());
  const Mat3& U = m.U;
  const Vec3& delta = m.delta;
  const Mat3 G = Mat3::Identity() + m.J_delta_x;
  const Eigen::Index n = sigma_.rows();
  // Sigma <- G Sigma G^T + S_x U S_x^T, G = I except the robot block.
  sigma_.topRightCorner(3, n - 3) = (G * sigma_.topRightCorner(3, n - 3)).eval();
  sigma_.bottomLeftCorner(n - 3, 3) = sigma_.topRightCorner(3, n - 3).transpose();
  sigma_.topLeftCorner<3, 3>() = G * sigma_.topLeftCorner<3, 3>() * G.transpose() + U;
  mu_.head<3>() += delta;
}

void EkfSlam::addLandmark(const Observation& z, const MeasurementModel& sensor) {
  // Inverse model y = g(x, z): Sigma_yy = Gx Sxx Gx^T + Gz Z Gz^T, Sigma_y* = Gx Sigma_x*.
  Mat23 G_x;
  Mat2 G_z;
  const Vec2 y = sensor.inverse(mu_.head<3>(), z.z, &G_x, &G_z);
  const Mat2& Z = sensor.noise(z);
  const Eigen::Index n = sigma_.rows();
  mu_.conservativeResize(n + 2);
  mu_.tail<2>() = y;
  const Eigen::MatrixXd cross = G_x * sigma_.topRows<3>();  // 2 x n
  sigma_.conservativeResize(n + 2, n + 2);
  sigma_.bottomLeftCorner(2, n) = cross;
  sigma_.topRightCorner(n, 2) = cross.transpose();
  Mat2 S_yy = G_x * sigma_.topLeftCorner<3, 3>() * G_x.transpose() + G_z * Z * G_z.transpose();
  sigma_.bottomRightCorner<2, 2>() = 0.5 * (S_yy + S_yy.transpose());
}

void EkfSlam::update(std::span<const Observation> observations, const MeasurementModel& sensor) {
  // A landmark's first observation initialises it (and carries no other information);
  // all other observations form one joint update linearised at the prior mean (with FEJ:
  // each landmark's Jacobians at its first estimate, Huang et al. 2010, the FEJ-EKF).
  // The book leaves out gross outliers (OutlierGate). All or nothing: a failure rolls the
  // new landmarks back (they only appended rows and columns).
  const std::span<const PlannedObservation> plan = book_.plan(
      observations, sensor, mu_.head<3>(), [&](int slot) { return Vec2(mu_.segment<2>(StateLayout::landmark(slot))); });
  const Eigen::Index n0 = sigma_.rows();
  try {
    applyPlan(plan, sensor);
  } catch (...) {
    mu_.conservativeResize(n0);
    sigma_.conservativeResize(n0, n0);
    throw;
  }
  book_.commit();
}

void EkfSlam::applyPlan(std::span<const PlannedObservation> plan, const MeasurementModel& sensor) {
  std::vector<const PlannedObservation*> updates;
  updates.reserve(plan.size());
  for (const PlannedObservation& p : plan) {
    if (p.first) {
      addLandmark(*p.z, sensor);
    } else {
      updates.push_back(&p);
    }
  }
  if (updates.empty()) return;

  const Eigen::Index n = sigma_.rows();
  const Eigen::Index m = 2 * static_cast<Eigen::Index>(updates.size());
  Eigen::MatrixXd PJt(n, m);  // Sigma J^T, using J's sparsity
  Eigen::VectorXd nu(m);
  Eigen::MatrixXd S(m, m);
  Eigen::MatrixXd K;
  std::vector<Mat23> Jx(updates.size());
  std::vector<Mat2> Jy(updates.size());
  std::vector<Eigen::Index> li(updates.size());
  // The iterated EKF (Gauss-Newton on the prior and these observations): iteration i
  // linearises at s_i = mu0 + delta_i (invariant: the retraction of delta_i) and solves
  // delta_{i+1} = K_i (z - h(s_i) + J_i delta_i), with Sigma the prior's throughout.
  const bool invariant = config_.linearization == Linearization::Invariant;
  const Eigen::VectorXd mu0 = mu_;
  Eigen::VectorXd delta, s = mu0;
  for (int it = 0; it < config_.iterations; ++it) {
    const Pose2 x = s.head<3>();
    for (std::size_t k = 0; k < updates.size(); ++k) {
      const PlannedObservation& p = *updates[k];
      const auto r = 2 * static_cast<Eigen::Index>(k);
      li[k] = StateLayout::landmark(p.slot);
      const Vec2 zhat = sensor.predict(x, s.segment<2>(li[k]), &Jx[k], &Jy[k]);
      if (p.jacobian_landmark) sensor.predict(x, *p.jacobian_landmark, &Jx[k], &Jy[k]);
      p.constrain(Jx[k], Jy[k]);
      if (invariant && it > 0) {  // the lever arm at the anchors (the prior mean)
        Jx[k].col(2) = invariant::anchoredHeadingColumn(Jy[k], mu0.head<2>(), mu0.segment<2>(li[k]));
      }
      nu.segment<2>(r) = sensor.residual(p.z->z, zhat);
      if (it > 0) nu.segment<2>(r) += Jx[k] * delta.head<3>() + Jy[k] * delta.segment<2>(li[k]);
      PJt.middleCols<2>(r) = sigma_.leftCols<3>() * Jx[k].transpose() + sigma_.middleCols<2>(li[k]) * Jy[k].transpose();
    }
    S.setZero();
    for (std::size_t k = 0; k < updates.size(); ++k) {
      // S = J Sigma J^T + R, row block k = Jx_k (Sigma J^T)_x + Jy_k (Sigma J^T)_l
      S.middleRows<2>(2 * static_cast<Eigen::Index>(k)) =
          Jx[k] * PJt.topRows<3>() + Jy[k] * PJt.middleRows<2>(li[k]);
      S.block<2, 2>(2 * static_cast<Eigen::Index>(k), 2 * static_cast<Eigen::Index>(k)) += sensor.noise(*updates[k]->z);
    }
    S = (0.5 * (S + S.transpose())).eval();
    Eigen::LLT<Eigen::MatrixXd> llt(S);
    if (llt.info() != Eigen::Success) {
      std::ostringstream msg;
      msg << "ekf: innovation covariance is not positive definite (landmark "
          << updates.front()->z->landmark << ")";
      throw NumericError(msg.str());
    }
    K = llt.solve(PJt.transpose()).transpose();  // n x m
    if (it + 1 < config_.iterations) {
      delta = K * nu;
      s = invariant ? invariant::retract(mu0, delta) : Eigen::VectorXd(mu0 + delta);
    }
  }
  if (invariant) {
    mu_ = invariant::retract(mu0, K * nu);
  } else {
    mu_.noalias() += K * nu;
  }
  sigma_.noalias() -= K * PJt.transpose();
  sigma_ = (0.5 * (sigma_ + sigma_.transpose())).eval();
  if (invariant) invariant::reanchorCovariance(sigma_, invariant::leverArms(mu_) - invariant::leverArms(mu0));
}

}  // namespace seif
