#pragma once
// The information-form steps shared by the EIF (on its whole matrix) and the SEIF (on the
// small dense block it gathers around the robot). One implementation of each equation.
#include <seif/core/types.hpp>

#include <Eigen/Core>

namespace seif {

/// Motion update in information form, paper Lemma 3 / algorithm.md §1, on a dense
/// symmetric matrix whose first three rows and columns are the robot pose:
///   Phi = G^-T H G^-1,  kappa = Phi S_x (U^-1 + S_x^T Phi S_x)^-1 S_x^T Phi,
///   H <- Phi - kappa,   b <- b + (Hbar - H) mu + Hbar S_x delta,   mu <- mu + S_x delta.
/// (U^-1 + A)^-1 is evaluated as U (I + A U)^-1, so a singular U (the two-dimensional
/// velocity noise) is fine. Exact when H holds every variable linked to the robot.
void informationMotionUpdate(Eigen::Ref<Eigen::MatrixXd> H, Eigen::Ref<Eigen::VectorXd> b,
                             Eigen::Ref<Eigen::VectorXd> mu, const Vec3& delta,
                             const Mat3& J_delta_x, const Mat3& U);

/// Information added by one range-bearing observation, paper eq. (21-22), ordered
/// [robot (3), landmark (2)]:  dH = J^T Z^-1 J,  db = J^T Z^-1 (z - zhat + J mu),
/// linearised at the robot mean x and landmark mean y; the bearing innovation is wrapped.
struct MeasurementInformation {
  Eigen::Matrix<double, 5, 5> H;
  Eigen::Matrix<double, 5, 1> b;
};
MeasurementInformation measurementInformation(const Pose2& x, const Vec2& y,
                                              const Observation& z, const Mat2& Z_inv);

/// Counts the links of a dense information matrix in the state order [robot, landmarks]:
/// non-zero off-diagonal blocks, the robot's links and the largest landmark degree.
struct FilterStats;
FilterStats denseLinkStats(const Eigen::MatrixXd& H);

}  // namespace seif
