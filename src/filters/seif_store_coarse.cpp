// The amortised mean's coarse level (SeifOptions::coarse, seif_store.hpp): a Galerkin
// correction of the mean over the rigid motions V of robot and map, kept in O(1) per change.
//
// Gauss-Seidel (paper eq. 42) removes the error where H changed within a few steps, but an
// error that moves or turns the whole map against the posterior decays at the rate of the
// slowest mode of H: the map's frame is held only by the weak start prior at its far end.
// The coarse step minimises the error in the H-norm over that three-dimensional space:
//   alpha = (V^T H V)^-1 V^T (b - H mu),   mu <- mu + V alpha
// (a two-level method, Saad, "Iterative Methods for Sparse Linear Systems" §13.4).
// V^T r = sum_k V_k^T b_k - w_k^T mu_k with w = H V sums terms each of one variable's own
// data, so a change of one row or mean changes one term.
#include "filters/seif_store.hpp"

#include <Eigen/Cholesky>

namespace seif {

namespace {
Vec2 quarterTurn(const Vec2& v) { return Vec2(-v.y(), v.x()); }  // J v
}  // namespace

Mat3 SeifStore::robotBasis() const {
  Mat3 V = Mat3::Identity();
  V.block<2, 1>(0, 2) = quarterTurn(mu_x_.head<2>() - coarse_origin_);
  return V;
}

Mat23 SeifStore::landmarkBasis(const Vec2& ref) const {
  Mat23 V;  // V_i = [I, J (ref_i - o)]
  V.leftCols<2>().setIdentity();
  V.col(2) = quarterTurn(ref - coarse_origin_);
  return V;
}

Mat23 SeifStore::coarseRow(int slot) const {
  // The map's part of (H V)_i: w_i = H_ii V_i + sum_j H_ij V_j. Its robot term H_ix V_x moves
  // with the robot's mean every step; robotCoarseTerms() adds it fresh for the active
  // landmarks, so a row is recomputed only when its own blocks change.
  const Node& n = node(slot);
  Mat23 w = n.H * landmarkBasis(n.ref);
  for (const Link& l : n.links) w.noalias() += l.H * landmarkBasis(node(l.slot).ref);
  return w;
}

void SeifStore::coarseTerms(int slot, const Mat23& w, Vec3& g, Mat3& A) const {
  // V_i^T b_i - w_i^T mu_i and V_i^T w_i
  const Node& n = node(slot);
  const Mat23 V = landmarkBasis(n.ref);
  g = V.transpose() * n.b - w.transpose() * mean(slot);
  A = V.transpose() * w;
}

void SeifStore::touchCoarse(int slot) {
  if (!coarse_) return;
  Node& n = nodes_[static_cast<std::size_t>(slot)];
  if (n.coarse_dirty) return;
  Vec3 g;
  Mat3 A;
  coarseTerms(slot, n.w, g, A);
  coarse_g_ -= g;
  coarse_A_ -= A;
  n.coarse_dirty = true;
  coarse_dirty_.push_back(slot);
}

void SeifStore::settleCoarse() {
  for (int slot : coarse_dirty_) {
    Node& n = nodes_[static_cast<std::size_t>(slot)];
    if (!n.coarse_dirty) continue;  // deleted meanwhile (deleteLandmark())
    n.w = coarseRow(slot);
    restoreCoarse(slot);
    blocks_touched_ += 1 + n.links.size();
  }
  coarse_dirty_.clear();
}

void SeifStore::restoreCoarse(int slot) {
  Node& n = nodes_[static_cast<std::size_t>(slot)];
  Vec3 g;
  Mat3 A;
  coarseTerms(slot, n.w, g, A);
  coarse_g_ += g;
  coarse_A_ += A;
  n.coarse_dirty = false;
}

void SeifStore::robotCoarseTerms(Vec3& g, Mat3& A) const {
  // The terms of the robot's links, fresh, O(active): the robot's row
  // w_x = H_xx V_x + sum_j H_xj V_j, and each active landmark's robot term H_jx V_x (not in
  // its kept row, coarseRow()):
  //   g = V_x^T b_x - w_x^T mu_x - sum_j (H_jx V_x)^T mu_j,
  //   A = V_x^T w_x + sum_j V_j^T H_jx V_x.
  Mat3 w = H_xx_ * coarse_Vx_;
  A.setZero();
  g.setZero();
  for (const RobotLink& l : robot_links_) {
    const Mat23 V = landmarkBasis(node(l.slot).ref);
    w.noalias() += l.H * V;
    const Mat23 HV = l.H.transpose() * coarse_Vx_;  // H_jx V_x
    A.noalias() += V.transpose() * HV;
    g.noalias() -= HV.transpose() * mean(l.slot);
  }
  g.noalias() += coarse_Vx_.transpose() * b_x_ - w.transpose() * mu_x_;
  A.noalias() += coarse_Vx_.transpose() * w;
}

void SeifStore::enableCoarse() {
  // The sums from scratch (O(N)): at construction (an empty map) and after setMean().
  if (!coarse_) {
    coarse_ = true;
    coarse_dirty_.reserve(1024);  // a step's changed rows: no allocation in the steady state
    coarse_origin_ = mu_x_.head<2>();
    for (Node& n : nodes_) n.ref = n.mu;  // frame_ is zero: mu is the mean
  }
  coarse_Vx_ = robotBasis();
  coarse_g_.setZero();
  coarse_A_.setZero();
  coarse_dirty_.clear();
  for (int s = 0; s < size(); ++s) {
    nodes_[static_cast<std::size_t>(s)].coarse_dirty = true;
    coarse_dirty_.push_back(s);
  }
  settleCoarse();
}

bool SeifStore::correctFrame() {
  if (!coarse_) return false;
  // V_x moves with the robot; the terms that hold it are robotCoarseTerms()'s, fresh.
  coarse_Vx_ = robotBasis();
  settleCoarse();
  Vec3 g_x;
  Mat3 A_x;
  robotCoarseTerms(g_x, A_x);
  Mat3 A = coarse_A_ + A_x;
  A = 0.5 * (A + A.transpose()).eval();  // V^T H V, symmetric up to rounding
  const Eigen::LLT<Mat3> llt(A);
  if (llt.info() != Eigen::Success) return false;
  const Vec3 alpha = llt.solve(coarse_g_ + g_x);
  if (!alpha.allFinite()) return false;
  // mu <- mu + V alpha: the robot's mean directly, the map's through the frame offset;
  // each landmark term of g changes by -w_i^T V_i alpha, in all -A_map^T alpha.
  mu_x_.noalias() += coarse_Vx_ * alpha;
  frame_ += alpha;
  coarse_g_.noalias() -= coarse_A_.transpose() * alpha;
  blocks_touched_ += 1 + 2 * robot_links_.size();
  return true;
}

std::pair<Vec3, Mat3> SeifStore::coarseSums() const {
  Vec3 g, g_k;
  Mat3 A, A_k;
  robotCoarseTerms(g, A);
  g += coarse_g_;
  A += coarse_A_;
  for (int slot : coarse_dirty_) {  // what settleCoarse() would add (each slot listed once)
    if (!node(slot).coarse_dirty) continue;
    coarseTerms(slot, coarseRow(slot), g_k, A_k);
    g += g_k;
    A += A_k;
  }
  return {g, A};
}

std::pair<Vec3, Mat3> SeifStore::coarseSumsFromScratch() const {
  // V^T (b - H mu) and V^T H V over the sparse H: the reference the kept sums are tested on.
  const Eigen::Index n = 3 + 2 * static_cast<Eigen::Index>(size());
  Eigen::MatrixXd V = Eigen::MatrixXd::Zero(n, 3);
  V.topLeftCorner<3, 3>() = coarse_Vx_;
  for (int s = 0; s < size(); ++s) V.block<2, 3>(StateLayout::landmark(s), 0) = landmarkBasis(node(s).ref);
  const Eigen::SparseMatrix<double> H = sparseInformation();
  const Eigen::VectorXd residual = informationVector() - H * mean();
  const Eigen::MatrixXd HV = H * V;
  return {V.transpose() * residual, V.transpose() * HV};
}

}  // namespace seif
