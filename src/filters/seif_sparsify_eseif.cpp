// The ESEIF's sparsification (SeifOptions::Sparsify::Eseif; Walter, Eustice, Leonard 2007):
// when the step would activate too many landmarks, part of its observations (z_alpha)
// update the filter, the robot is marginalised out and relocalised from the rest (z_beta).
// H stays exactly sparse; nothing is conditioned away.
#include <seif/core/errors.hpp>
#include "filters/seif_slam.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>

namespace seif {

namespace {
// ESEIF relocalisation (Walter et al. 2007): the largest condition number of z_beta's
// stacked pose information J_x^T R^-1 J_x it accepts.
constexpr double kMaxRelocalizationCondition = 1e6;
constexpr int kRelocalizationIterations = 20;
enum Role : unsigned char { kAlpha, kBeta, kRejected };

bool wellConditioned(const Mat3& A) {
  const Vec3 ev = Eigen::SelfAdjointEigenSolver<Mat3>(A, Eigen::EigenvaluesOnly).eigenvalues();
  return ev(0) > 0.0 && ev(2) < kMaxRelocalizationCondition * ev(0);
}
}  // namespace
// ---------------------------------------------------------------- ESEIF ---------------

void SeifSlam::eseifUpdate(std::span<const Observation> z, const MeasurementModel& sensor) {
  // Walter, Eustice, Leonard 2007: when z would activate more than options.active landmarks,
  // z_alpha updates the filter (eq. 21-22), the robot is marginalised out and relocalised
  // from z_beta alone. H stays exactly sparse; information is dropped, never invented.
  const bool triggered = exceedsActive(z);
  const bool split = triggered && partitionObservations(z, sensor);
  measurementUpdate(triggered ? std::span<const Observation>(alpha_) : z, sensor);
  bool relocalized = false;
  if (split) {
    relocalized = relocalizeRobot(sensor);
    if (relocalized) {
      ++eseif_relocalizations_;
    } else {
      measurementUpdate(beta_, sensor);  // no pose from z_beta: an ordinary update
    }
  }
  if (options_.mean == SeifOptions::Mean::Exact) {
    recoverExactMean();
  } else if (options_.recovery == SeifOptions::Recovery::AfterMeasurement) {
    recoverMean();
  }
  // Without a relocalisation the surplus stays active until one is possible (measurementUpdate()
  // conditions it away, counted in eseifFallbacks(), only when the local block is full).
  if (static_cast<int>(store_.robotLinks().size()) > options_.active) ++eseif_deferrals_;
}

bool SeifSlam::exceedsActive(std::span<const Observation> z) const {
  int active = static_cast<int>(store_.robotLinks().size());
  for (std::size_t i = 0; i < z.size(); ++i) {
    const int slot = book_.find(z[i].landmark);
    if (slot >= 0 && store_.node(slot).active >= 0) continue;
    const bool repeated = std::any_of(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(i),
                                      [&](const Observation& o) { return o.landmark == z[i].landmark; });
    if (!repeated) ++active;
  }
  return active > options_.active;
}

bool SeifSlam::partitionObservations(std::span<const Observation> z, const MeasurementModel& sensor) {
  // Candidates for z_beta: observations of mapped landmarks, the best informed (largest
  // trace of H_ll) first. z_beta takes beta of them, or more until their stacked
  // sum J_x^T R^-1 J_x fixes all three pose dof, well conditioned; at most options.active, so
  // that the relocalised robot's active set is within bounds. Fewer than beta: no z_beta
  // (the step defers; relocalising from too few discards the odometry for a poor pose).
  alpha_.clear();
  beta_.clear();
  beta_slots_.clear();
  ranking_.clear();
  roles_.assign(z.size(), kAlpha);
  for (std::size_t i = 0; i < z.size(); ++i) {
    const int slot = book_.find(z[i].landmark);
    if (slot >= 0) ranking_.emplace_back(-store_.node(slot).H.trace(), static_cast<int>(i));
  }
  std::sort(ranking_.begin(), ranking_.end());
  const auto max_beta = static_cast<std::size_t>(options_.active);
  const auto target = std::min(static_cast<std::size_t>(options_.beta), max_beta);
  const Pose2 x = store_.robotMean();
  Mat3 A = Mat3::Zero();
  bool found = false;
  for (const auto& [score, i] : ranking_) {
    if ((found && beta_.size() >= target) || beta_.size() == max_beta) break;
    const Observation& o = z[static_cast<std::size_t>(i)];
    const int slot = book_.find(o.landmark);
    if (std::find(beta_slots_.begin(), beta_slots_.end(), slot) != beta_slots_.end()) continue;
    const Mat2 Z_inv = sensor.noise(o).inverse();
    if (book_.rejects(sensor, x, store_.mean(slot), o)) {
      roles_[static_cast<std::size_t>(i)] = kRejected;
      continue;
    }
    Mat23 J_x;
    sensor.predict(x, store_.mean(slot), &J_x);
    A.noalias() += J_x.transpose() * Z_inv * J_x;
    roles_[static_cast<std::size_t>(i)] = kBeta;
    beta_.push_back(o);
    beta_slots_.push_back(slot);
    found = beta_.size() >= std::max<std::size_t>(2, target) && wellConditioned(A);
  }
  for (std::size_t i = 0; i < z.size(); ++i) {
    if (roles_[i] == kAlpha || (roles_[i] == kBeta && !found)) alpha_.push_back(z[i]);
  }
  if (!found) {
    beta_.clear();
    beta_slots_.clear();
  }
  return found;
}

bool SeifSlam::relocalizeRobot(const MeasurementModel& sensor) {
  // The robot's mean given z_alpha (re-solved on the block the marginalisation gathers) is
  // the start of a Gauss-Newton fit of the pose to z_beta and the landmarks' means.
  const bool invariant = config_.linearization == Linearization::Invariant;  // anchored in update()
  store_.gatherActive();
  store_.solveLocalMean();
  Pose2 x = store_.robotMean();
  Mat3 A = Mat3::Zero();
  bool converged = false;
  for (int it = 0; it < kRelocalizationIterations && !converged; ++it) {
    A.setZero();
    Vec3 g = Vec3::Zero();
    for (std::size_t k = 0; k < beta_.size(); ++k) {
      Mat23 J_x;
      const Vec2 zhat = sensor.predict(x, store_.mean(beta_slots_[k]), &J_x);
      const Eigen::Matrix<double, 3, 2> JtZ = J_x.transpose() * sensor.noise(beta_[k]).inverse();
      A.noalias() += JtZ * J_x;
      g.noalias() += JtZ * sensor.residual(beta_[k].z, zhat);
    }
    const Vec3 dx = A.ldlt().solve(g);
    if (!dx.allFinite()) return false;
    x += dx;
    converged = dx.norm() < 1e-9 * (1.0 + x.head<2>().norm());
  }
  if (!converged || !wellConditioned(A)) return false;
  // Marginalisation: the Schur complement over the robot's Markov blanket, the active set.
  marginalizeRobot(store_.localH(), store_.localB());
  store_.scatter();
  store_.detachRobot(x);
  // Relocalisation: information over (x, m_beta) from z_beta alone, eq. (21-22) at the new
  // pose; the robot is then linked to m_beta only.
  for (std::size_t k = 0; k < beta_.size(); ++k) {
    const int slot = beta_slots_[k];
    const std::optional<Anchors> anchors =
        invariant ? std::optional<Anchors>(Anchors{store_.robotAnchor(), store_.node(slot).anchor}) : std::nullopt;
    const MeasurementInformation info = measurementInformation(sensor, x, store_.mean(slot), beta_[k],
                                                               sensor.noise(beta_[k]).inverse(), std::nullopt, anchors);
    store_.addObservation(slot, info.H, info.b);
  }
  invalidateFactor();
  return true;
}

}  // namespace seif
