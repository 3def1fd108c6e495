// The paper's sparsification (SeifOptions::Sparsify::Seif; algorithm.md §4, paper eq.
// 44-51): the surplus of active landmarks is conditioned away. One file per sparsifier:
// this one, seif_sparsify_eseif.cpp and seif_sparsify_conservative.cpp (this rule with the
// information scaled down after it); SeifSlam::update chooses by SeifOptions::sparsify.
// With SeifOptions::gauge = Kept the rule claims nothing on the posterior's free directions
// (information_ops.hpp, keepGauge).
#include "filters/seif_slam.hpp"

#include <algorithm>

namespace seif {

void SeifSlam::sparsify() { deactivateSurplus(false); }

void SeifSlam::deactivateSurplus(bool solve_active_mean_first, int slot, bool block_gathered) {
  // §4, paper eq. (44-51): deactivate the surplus Y0, keep Y+.
  const int k = static_cast<int>(store_.robotLinks().size());
  const int drop = slot >= 0 ? 1 : k - options_.active;
  if (drop <= 0) return;
  ++sparsifications_;
  if (options_.sparsify == SeifOptions::Sparsify::Eseif && slot < 0) ++eseif_fallbacks_;
  ranking_.clear();
  for (const SeifStore::RobotLink& l : store_.robotLinks()) {
    double score;
    if (slot >= 0) {
      score = l.slot == slot ? 0.0 : 1.0;  // `slot` alone is deactivated
    } else if (options_.deactivate == SeifOptions::Deactivate::Oldest) {
      score = static_cast<double>(l.last_seen);
    } else {  // strength of the link on the normalised information matrix
      const Vec3 dx = store_.robotInformation().diagonal().cwiseSqrt().cwiseInverse();
      const Vec2 dl = store_.node(l.slot).H.diagonal().cwiseSqrt().cwiseInverse();
      score = (dx.asDiagonal() * l.H * dl.asDiagonal()).norm();
    }
    // SeifOptions::stale: the landmarks unobserved for longer go first, the stalest first
    // (negative scores sort before every link strength and step count).
    const long unobserved = store_.step() - l.last_seen;
    if (slot < 0 && options_.stale > 0 && unobserved > options_.stale) score = -static_cast<double>(unobserved);
    ranking_.emplace_back(score, l.slot);
  }
  std::sort(ranking_.begin(), ranking_.end());  // stale, then weakest (or oldest) first
  order_.clear();
  for (int i = drop; i < k; ++i) order_.push_back(ranking_[static_cast<std::size_t>(i)].second);  // Y+
  for (int i = 0; i < drop; ++i) order_.push_back(ranking_[static_cast<std::size_t>(i)].second);  // Y0
  const bool conservative = options_.sparsify == SeifOptions::Sparsify::Conservative;
  if (conservative) beginConservativeSparsification();
  // The iterated update left the active block gathered and current: reordered, not read
  // again, with its passive terms.
  const bool reuse = block_gathered && slot < 0;
  if (reuse) {
    store_.reorderGathered(order_);
  } else {
    store_.gather(order_);
  }
  if (solve_active_mean_first) store_.solveLocalMean(reuse ? SeifStore::Passive::Reuse : SeifStore::Passive::Recompute);
  LocalMatrix& H = store_.localH();
  if (conservative) overclaim_h_ = H;
  if (options_.gauge == SeifOptions::Gauge::Kept) {
    gatherGauge(drop);
  } else {
    gauge_.resize(H.rows(), 0);  // none: eq. (44-51) as published
  }
  const double residual = sparsifyInformation(H, store_.localB(), store_.localMean(), drop, gauge_);
  last_sparsification_residual_ = std::max(last_sparsification_residual_, residual);
  const Eigen::Index y0 = H.rows() - 2 * drop;
  H.block(0, y0, 3, 2 * drop).setZero();
  H.block(y0, 0, 2 * drop, 3).setZero();
  if (conservative) endConservativeSparsification();
  store_.scatter();
  invalidateFactor();
  for (int i = 0; i < drop; ++i) store_.removeRobotLink(ranking_[static_cast<std::size_t>(i)].second);
  // The block's rows hold H mu = b before eq. (44-51) and so after (b~ = b + (H~ - H) mu
  // within the block): the solved mean stands (Y0's rows included), unless conservative's
  // kappa changed what the store holds.
  block_ = solve_active_mean_first && slot < 0 && options_.sparsify == SeifOptions::Sparsify::Seif ? ActiveBlock::Solved
                                                                                                      : ActiveBlock::Stale;
  if (options_.rho > 0.0) {  // SeifOptions::rho: H <- (1 - rho) H, kept as kappa (informationScale())
    information_scale_ /= 1.0 - options_.rho;
    ++scalings_;
  }
}

void SeifSlam::gatherGauge(int drop) {
  // The free directions over the gathered block [x, Y+, Y0]: the two translations and the
  // rotation, at the anchors H holds (invariant linearisation: H's own null space, exactly)
  // or at the means; the rotation about the centre of Y+ (better conditioned, same span).
  const bool anchored = config_.linearization == Linearization::Invariant;
  const LocalVector& mu = store_.localMean();
  const auto at = [&](Eigen::Index row) -> Vec2 {
    if (row == 0) return anchored ? store_.robotAnchor() : Vec2(mu.head<2>());
    const int s = store_.gathered()[static_cast<std::size_t>((row - 3) / 2)];
    return anchored ? store_.node(s).anchor : Vec2(mu.segment<2>(row));
  };
  const Eigen::Index n = store_.localH().rows(), y0 = n - 2 * drop;
  Vec2 centre = Vec2::Zero();
  for (Eigen::Index i = 3; i < y0; i += 2) centre += at(i);
  if (y0 > 3) centre /= static_cast<double>((y0 - 3) / 2);
  gauge_.setZero(n, 3);
  for (Eigen::Index i = 0; i < n; i += (i == 0 ? 3 : 2)) {
    gauge_.block<2, 2>(i, 0).setIdentity();
    const Vec2 r = at(i) - centre;
    gauge_.block<2, 1>(i, 2) = Vec2(-r.y(), r.x());  // J r
  }
  gauge_(2, 2) = 1.0;
}

}  // namespace seif
