// The reference filters: EKF == EIF over whole runs, invariants after every step,
// bearing wrapping, information <-> moments round trips.
#include "rel_diff.hpp"
#include "scenario.hpp"

#include <seif/core/errors.hpp>
#include "filters/eif_slam.hpp"
#include "filters/ekf_slam.hpp"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <numbers>

namespace {

using namespace seif;

using test::relDiff;

void expectSymmetricPositiveDefinite(const Eigen::MatrixXd& M, const std::string& what) {
  EXPECT_LE((M - M.transpose()).cwiseAbs().maxCoeff(), 1e-12 * M.cwiseAbs().maxCoeff()) << what;
  Eigen::LLT<Eigen::MatrixXd> llt(M);
  EXPECT_EQ(llt.info(), Eigen::Success) << what << " is not positive definite";
}

using test::configFor;

}  // namespace

TEST(EkfEifEquivalence, MeansAndCovariancesAgreeOverWholeRuns) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const test::Scenario s = test::makeScenario(seed, 30, 200);
    EkfSlam ekf(s.start, configFor(s));
    EifSlam eif(s.start, configFor(s));
    double worst_mean = 0, worst_cov = 0;
    for (const Step& step : s.steps) {
      ekf.step(step.u, step.observations);
      eif.step(step.u, step.observations);
      ASSERT_EQ(ekf.landmarkIds(), eif.landmarkIds());
      worst_mean = std::max(worst_mean, relDiff(eif.mean(), ekf.mean()));
      worst_cov = std::max(worst_cov, relDiff(eif.covariance(), ekf.covariance()));
    }
    EXPECT_GT(ekf.landmarkIds().size(), 20u);
    EXPECT_LT(worst_mean, 1e-9) << "seed " << seed;
    EXPECT_LT(worst_cov, 1e-9) << "seed " << seed;
  }
}

TEST(EkfEifEquivalence, ListedMomentsAgreeLandmarkByLandmark) {
  const test::Scenario s = test::makeScenario(11, 20, 120);
  EkfSlam ekf(s.start, configFor(s));
  EifSlam eif(s.start, configFor(s));
  for (const Step& step : s.steps) {
    ekf.step(step.u, step.observations);
    eif.step(step.u, step.observations);
  }
  EXPECT_LT((ekf.pose() - eif.pose()).norm(), 1e-9);
  EXPECT_LT(relDiff(eif.poseCovariance(), ekf.poseCovariance()), 1e-9);
  for (int id : ekf.landmarkIds()) {
    EXPECT_LT((ekf.landmark(id) - eif.landmark(id)).norm(), 1e-9);
    EXPECT_LT(relDiff(eif.landmarkCovariance(id), ekf.landmarkCovariance(id)), 1e-9);
  }
}

TEST(DenseFilters, InformationAndCovarianceStaySymmetricPositiveDefinite) {
  const test::Scenario s = test::makeScenario(5, 40, 300);
  EkfSlam ekf(s.start, configFor(s));
  EifSlam eif(s.start, configFor(s));
  int k = 0;
  for (const Step& step : s.steps) {
    ekf.predict(step.u);
    eif.predict(step.u);
    expectSymmetricPositiveDefinite(ekf.covariance(), "EKF Sigma after predict " + std::to_string(k));
    expectSymmetricPositiveDefinite(eif.information(), "EIF H after predict " + std::to_string(k));
    ekf.update(step.observations);
    eif.update(step.observations);
    expectSymmetricPositiveDefinite(ekf.covariance(), "EKF Sigma after update " + std::to_string(k));
    expectSymmetricPositiveDefinite(eif.information(), "EIF H after update " + std::to_string(k));
    ++k;
    if (::testing::Test::HasFailure()) break;
  }
}

TEST(DenseFilters, InformationMomentsRoundTrip) {
  const test::Scenario s = test::makeScenario(6, 15, 80);
  EkfSlam ekf(s.start, configFor(s));
  EifSlam eif(s.start, configFor(s));
  for (const Step& step : s.steps) {
    ekf.step(step.u, step.observations);
    eif.step(step.u, step.observations);
  }
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(eif.information().rows(), eif.information().cols());
  EXPECT_LT((eif.information() * eif.covariance() - I).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((ekf.information() * ekf.covariance() - I).cwiseAbs().maxCoeff(), 1e-8);
  // mu = H^-1 b for the EIF, and the EKF's moments in information form are the EIF's.
  EXPECT_LT(relDiff(eif.covariance() * eif.informationVector(), eif.mean()), 1e-10);
  EXPECT_LT(relDiff(ekf.information(), eif.information()), 1e-8);
}

TEST(DenseFilters, BearingInnovationIsWrappedForALandmarkBehind) {
  // The robot faces +x; the landmark is straight behind it, so the predicted bearing is
  // +pi and measurements fall on both sides of the seam. Without wrapping, a measurement
  // at -pi + 0.01 would be a 2 pi innovation and throw the pose off.
  constexpr double kPi = std::numbers::pi;
  FilterConfig config = paperFilterConfig({0.01, 0.01, 0.05, 0.02});
  for (int which = 0; which < 2; ++which) {
    std::unique_ptr<SlamFilter> f;
    if (which == 0) f = std::make_unique<EkfSlam>(Pose2::Zero(), config);
    else f = std::make_unique<EifSlam>(Pose2::Zero(), config);
    const Observation first[] = {{1, Vec2(2.0, kPi - 0.001), std::nullopt}};
    f->update(first);
    for (int i = 0; i < 20; ++i) {
      const Observation z[] = {{1, Vec2(2.0, i % 2 ? kPi - 0.01 : -kPi + 0.01), std::nullopt}};
      f->update(z);
    }
    EXPECT_LT(std::abs(f->pose().z()), 0.02) << f->name();
    EXPECT_LT((f->landmark(1) - Vec2(-2.0, 0.0)).norm(), 0.05) << f->name();
  }
}

TEST(DenseFilters, StatsCountTheFullGraphOfTheDenseFilters) {
  const test::Scenario s = test::makeScenario(3, 12, 150, 20.0);  // sees everything
  EkfSlam ekf(s.start, configFor(s));
  EifSlam eif(s.start, configFor(s));
  for (const Step& step : s.steps) {
    ekf.step(step.u, step.observations);
    eif.step(step.u, step.observations);
  }
  const std::size_t n = ekf.landmarkIds().size();
  ASSERT_EQ(n, 12u);
  EXPECT_EQ(ekf.stats().links, (n + 1) * n / 2);
  EXPECT_EQ(eif.stats().links, (n + 1) * n / 2);
  EXPECT_EQ(eif.stats().robot_links, n);
}

TEST(DenseFilters, UnknownLandmarkQueriesThrow) {
  EkfSlam ekf(Pose2::Zero(), paperFilterConfig(NoiseModel{}));
  EifSlam eif(Pose2::Zero(), paperFilterConfig(NoiseModel{}));
  EXPECT_THROW(ekf.landmark(3), seif::UnknownLandmark);
  EXPECT_THROW(eif.landmarkCovariance(3), seif::UnknownLandmark);
}
