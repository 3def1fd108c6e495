#pragma once
// Conservative covariances of the SEIF (MarginalMode::Conservative, SeifOptions::Covariance::
// Conservative): upper bounds, in the Loewner order, on the marginal covariances of its
// information matrix H, in constant time (docs/consistency.md, "Conservative covariances").
//
// Every landmark carries a bound B_j >= Sigma_jj (SeifStore::Node::bound). For a set I of
// variables (the robot, the active landmarks and the queried ones: the robot's links all lie
// inside it) and the landmarks b just outside it, linked to I,
//   y_I = -H_II^-1 H_Ib y_b + v,   v ~ N(0, H_II^-1) independent of everything outside I,
// so, for the rows Q of y_I asked for (E_Q), with u_k = M_k y_c one term per link (a, c) from
// a member a to an outside landmark c, M_k = -E_Q^T H_II^-1 E_a H_ac,
//   Sigma_QQ = E_Q^T H_II^-1 E_Q + Cov(sum_k u_k)
//           <= E_Q^T H_II^-1 E_Q + sum_k M_k B_c M_k^T / w_k,   sum_k w_k = 1, w_k > 0,     (1)
// because Var(sum_k u_k) <= sum_k Var(u_k) / w_k for any random vectors, correlated or not
// (covariance intersection, Julier & Uhlmann 1997; Cauchy-Schwarz), and Var(u_k) <=
// M_k B_c M_k^T. w_k ~ sqrt(tr M_k B_c M_k^T) minimises the trace. The relative geometry of
// the robot and the landmarks in I is exact; only the links leaving I are bounded.
//
// What changes a landmark's marginal, and how its bound follows:
//   motion (the old pose marginalised out), either sparsification (the paper's keeps the
//   map's marginal, the ESEIF's marginalises the robot and adds information), removal
//   (a marginalisation), merge (conditioning on y_keep = y_drop): never larger, B_j kept;
//   a measurement update: [x; y_Q] had a covariance <= C (1) before it, and the update adds
//   information I on [x; y_Q] alone, so after it the covariance is <= (C^-1 + I)^-1;
//   a first sighting: the same with the new landmark's prior information zero;
//   re-anchoring (Linearization::Invariant, M = I + dc e_theta^T on the landmark's rows):
//   Sigma'_jj = [dc I] Sigma_(theta, y_j) [dc I]^T <= [dc I] C [dc I]^T.
#include "filters/information_ops.hpp"
#include "filters/seif_store.hpp"

#include <Eigen/Core>
#include <span>
#include <vector>

namespace seif {

/// Buffers of conservativeCovariance(), reused: with them it allocates nothing.
struct BoundWorkspace {
  BoundWorkspace();
  std::vector<int> members;  // I's landmarks: the active ones, then the queried passive ones
  LocalMatrix H;             // H_II
  LocalMatrix E;             // the columns of [x; y_Q] in I
  LocalMatrix Z;             // H_II^-1 E
};

/// Bound (1) on the joint covariance of the robot (rows 0-2) and the landmarks `slots` (two
/// rows each, in order; distinct) into `out`, which must be 3 + 2 |slots| square. Every
/// landmark linked to I must have its bound. False (out untouched) when the active and the
/// queried landmarks are more than a local block holds (kMaxLocalLandmarks). O(|I|^3).
/// Throws NumericError when H_II is not positive definite.
bool conservativeCovariance(const SeifStore& store, std::span<const int> slots, Eigen::Ref<Eigen::MatrixXd> out,
                            BoundWorkspace& ws);

/// Of two upper bounds A and B of one 2x2 covariance, the point of the segment between them
/// (every point of which is a bound too) with the least determinant: never larger than either.
Mat2 tighterBound(const Mat2& A, const Mat2& B);

/// Bound (1) on the robot's covariance alone (I: the robot and the active landmarks).
Mat3 conservativePoseCovariance(const SeifStore& store, BoundWorkspace& ws);

/// The bounds after information `added` over [x; y_slots] (3 + 2 |slots| square): `prior` is
/// conservativeCovariance() of the robot and the first slots before it, the slots after those
/// had no information before it (new landmarks). Each landmark's bound becomes its block of
/// (prior^-1 + added)^-1, the prior padded with zero information, or its bound before where
/// that is tighter (every bound before must hold after the update). Allocates nothing. The
/// bounds are left as they were when either matrix is too ill-conditioned to invert (they
/// still hold: an update only adds information).
void tightenBounds(SeifStore& store, std::span<const int> slots, const LocalMatrix& prior, const LocalMatrix& added);

/// The bound of a landmark whose only information is I over [x; y] (its first sighting; the
/// robot its only link): y = -I_yy^-1 I_yx x + v, so I_yy^-1 + G C_x G^T (G = I_yy^-1 I_yx)
/// for the robot's bound C_x. Allocates nothing.
Mat2 firstSightingBound(const Mat3& robot_bound, const Eigen::Matrix<double, 5, 5>& information);

/// Landmark `slot`'s bound after re-anchoring it at `to` (SeifStore::reanchorLandmark): with
/// dc = J (to - anchor), the tighter of [dc I] C [dc I]^T over (theta, y) of its joint bound C
/// with the robot and (1 + e) B + (1 + 1/e) dc C_tt dc^T. Allocates nothing.
Mat2 reanchoredBound(const SeifStore& store, int slot, const Vec2& to, BoundWorkspace& ws);

}  // namespace seif
