#pragma once
// The right-invariant EKF of Barrau & Bonnabel (2015) in the filters' standard coordinates
// (algorithm.md, "The invariant filter in standard coordinates: anchors"). The state
// chi = (R, p, l_1..l_n) in SE_{1+n}(2) has the error xi, chi = exp(xi) chi_hat; to first
// order the standard additive error is delta = T(s) xi, T(s) = I + c(s) e_theta^T, where
// c(s) holds J p and J l_j (J = [[0, -1], [1, 0]]) and zero in the heading. The invariant
// EKF is the standard one whose covariance is re-anchored, P <- M P M^T with
// M = T(s_new) T(s_old)^-1 = I + (c(s_new) - c(s_old)) e_theta^T, whenever the mean moves,
// and whose corrections are applied by the retraction. States are laid out [x, y, theta,
// l_1, ...] (StateLayout).
#include <seif/core/types.hpp>

#include <Eigen/Core>

namespace seif::invariant {

/// c(s): J times every position of the state (robot and landmarks), zero in the heading.
Eigen::VectorXd leverArms(const Eigen::VectorXd& s);

/// B(t) = [[sin t / t, -(1 - cos t) / t], [(1 - cos t) / t, sin t / t]], the left Jacobian of
/// SO(2) acting on a translation; series near t = 0 (either sign).
Mat2 leftJacobian(double t);

/// exp(xi) s with xi = T(s)^-1 delta: theta + d_theta, p -> Rot(d_theta) p + B(d_theta) xi_p,
/// l_j -> Rot(d_theta) l_j + B(d_theta) xi_lj, where xi_p = d_p - d_theta J p (likewise l_j).
/// Equals s + delta to first order.
Eigen::VectorXd retract(const Eigen::VectorXd& s, const Eigen::VectorXd& delta);

/// P <- M P M^T with M = I + dc e_theta^T (dc = c(s_new) - c(s_old)): O(n^2).
void reanchorCovariance(Eigen::MatrixXd& P, const Eigen::VectorXd& dc);

/// H <- M^-T H M^-1 (the same re-anchoring of an information matrix): with q = H dc and
/// a = dc^T H dc, H - q e_theta^T - e_theta q^T + a e_theta e_theta^T; only the heading row
/// and column change. O(n^2).
void reanchorInformation(Eigen::MatrixXd& H, const Eigen::VectorXd& dc);

/// The heading column of an observation's pose Jacobian with the covariance anchored at
/// the robot position a_p and landmark position a_l: -J_y J (a_l - a_p) (for any sensor
/// whose prediction is invariant under a rigid motion of robot and landmark together).
Vec2 anchoredHeadingColumn(const Mat2& J_y, const Vec2& a_p, const Vec2& a_l);

}  // namespace seif::invariant
