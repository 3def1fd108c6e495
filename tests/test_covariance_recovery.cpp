// Covariance recovery of the SEIF (SeifOptions::covariance): the exact marginals against the
// dense inverse of H, and the local (Markov-blanket) recovery against the exact one: it
// conditions on everything outside the blanket, so it can only be smaller.
#include "scenario.hpp"

#include "filters/seif_slam.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

namespace seif {
namespace {

double smallestEigenvalue(const Eigen::MatrixXd& A) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (A + A.transpose())).eigenvalues().minCoeff();
}

TEST(CovarianceRecovery, ExactEqualsTheDenseInverseAndLocalIsSmaller) {
  const test::Scenario s = test::makeScenario(4, 40, 150);
  FilterConfig c = paperFilterConfig(s.noise);
  SeifOptions exact_options, local_options;
  local_options.covariance = SeifOptions::Covariance::Local;
  SeifSlam exact(s.start, c, exact_options), local(s.start, c, local_options);
  int checked = 0;
  double largest_gap = 0.0;
  for (std::size_t k = 0; k < s.steps.size(); ++k) {
    exact.step(s.steps[k].u, s.steps[k].observations);
    local.step(s.steps[k].u, s.steps[k].observations);
    if (k % 15 != 14) continue;
    const Eigen::MatrixXd dense = exact.covariance();
    const Mat3 Pe = exact.poseCovariance(), Pl = local.poseCovariance();
    const Mat3 dense_pose = dense.topLeftCorner(3, 3);
    EXPECT_LT((Pe - dense_pose).norm(), 1e-9 * dense_pose.norm());
    // Same filter state (the option changes only the getters); local <= exact.
    EXPECT_GT(smallestEigenvalue(Pe - Pl), -1e-12 * Pe.norm()) << "step " << k;
    largest_gap = std::max(largest_gap, (Pe - Pl).norm() / Pe.norm());
    for (int id : exact.landmarkIds()) {
      const Mat2 Le = exact.landmarkCovariance(id), Ll = local.landmarkCovariance(id);
      EXPECT_GT(smallestEigenvalue(Le - Ll), -1e-12 * Le.norm()) << "step " << k << " landmark " << id;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
  EXPECT_GT(largest_gap, 1e-3);  // the approximation is not the marginal (the check could fail)
}

}  // namespace
}  // namespace seif
