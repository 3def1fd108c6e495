// Data association (filters/association.hpp): the correspondence test against the dense
// computation, the chi-square gates, provisional landmarks removed exactly, known
// association's refusal, and nn / jcbb scored against the simulator's truth on the park
// with clutter and missed detections.
#include "scenario.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include <seif/eval/run_loop.hpp>
#include <seif/eval/stats.hpp>
#include <seif/filters/association.hpp>
#include <seif/filters/factory.hpp>
#include <seif/sim/world.hpp>
#include "filters/association_scan.hpp"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <string>

namespace {

using namespace seif;

}  // namespace

TEST(Association, TheCorrespondenceTestIsTheDenseComputation) {
  // d2 = Delta^T (F Sigma F^T)^-1 Delta with F = [.. I .. -I ..] on the full covariance.
  const test::Scenario s = test::makeScenario(3, 20, 80);
  for (const char* spec : {"ekf", "eif", "seif:mean=exact"}) {
    auto f = makeFilter(spec, s.start, test::configFor(s));
    for (const Step& step : s.steps) f->step(step.u, step.observations);
    const std::vector<int>& ids = f->landmarkIds();
    ASSERT_GE(ids.size(), 10u);
    const Eigen::MatrixXd P = f->covariance();
    const Eigen::VectorXd mu = f->mean();
    for (std::size_t a = 0; a + 1 < 6; ++a) {
      const std::size_t b = a + 3;
      Eigen::MatrixXd F = Eigen::MatrixXd::Zero(2, mu.size());
      F.block<2, 2>(0, 3 + 2 * static_cast<Eigen::Index>(a)).setIdentity();
      F.block<2, 2>(0, 3 + 2 * static_cast<Eigen::Index>(b)) = -Mat2::Identity();
      const Vec2 delta = F * mu;
      const Mat2 S = F * P * F.transpose();
      const double dense = delta.dot(S.llt().solve(delta));
      const double d2 = correspondenceDistance(*f, ids[a], ids[b]);
      EXPECT_NEAR(d2, dense, 1e-6 * dense) << spec << " landmarks " << ids[a] << ", " << ids[b];
    }
  }
}

TEST(Association, EvenChiSquareQuantilesMatchTheGeneralOnes) {
  for (int k = 1; k <= 12; ++k) {
    for (double p : {0.9, 0.99, 0.9999}) {
      EXPECT_NEAR(chiSquareEvenQuantile(p, k), chiSquareQuantile(p, 2.0 * k), 1e-8 * (1 + 2 * k)) << k << " " << p;
    }
  }
}

TEST(Association, KnownRefusesAnObservationWithoutAnId) {
  const test::Scenario s = test::makeScenario(1, 10, 5);
  auto f = makeFilter("ekf", s.start, test::configFor(s));
  Associator known(AssociationOptions{});
  std::vector<Observation> z = {{kUnknownLandmark, Vec2(1.0, 0.1), std::nullopt}};
  EXPECT_THROW(known.associate(*f, 0, z), ModelError);
  std::vector<Observation> named = {{7, Vec2(1.0, 0.1), std::nullopt}};
  known.associate(*f, 0, named);
  EXPECT_EQ(named[0].landmark, 7);
}

TEST(Association, BadOptionsAreRefused) {
  AssociationOptions o;
  o.method = AssociationMethod::NearestNeighbour;
  o.new_landmark = 0.5;  // below the accept gate
  EXPECT_THROW(Associator{o}, InvalidArgument);
  o = AssociationOptions{};
  o.confirm = 0;
  EXPECT_THROW(Associator{o}, InvalidArgument);
  EXPECT_THROW(parseAssociationMethod("greedy"), InvalidArgument);
}

TEST(Association, AnUnconfirmedLandmarkIsRemovedExactly) {
  // One false detection at step 0 starts a provisional landmark that nothing confirms: after
  // the window the EKF is its twin that never saw it (a first sighting only places the new
  // landmark; removing it is marginalising it).
  const test::Scenario s = test::makeScenario(5, 12, 40);
  AssociationOptions o;
  o.method = AssociationMethod::NearestNeighbour;
  o.window = 5;
  auto f = makeFilter("ekf", s.start, test::configFor(s));
  auto twin = makeFilter("ekf", s.start, test::configFor(s));
  Associator a(o), b(o);
  for (std::size_t k = 0; k < s.steps.size(); ++k) {
    const Step& step = s.steps[k];
    f->predict(step.u);
    twin->predict(step.u);
    std::vector<Observation> z = step.observations, zt = step.observations;
    if (k == 0) z.push_back({kUnknownLandmark, Vec2(2.9, -2.5), std::nullopt});  // far from every landmark
    a.associate(*f, k, z);
    b.associate(*twin, k, zt);
    f->update(z);
    twin->update(zt);
  }
  a.finish(*f);
  b.finish(*twin);
  EXPECT_GE(a.counts().provisional_removed, 1u);
  ASSERT_EQ(f->landmarkIds().size(), twin->landmarkIds().size());
  EXPECT_LT((f->pose() - twin->pose()).norm(), 1e-9);
  EXPECT_LT((f->poseCovariance() - twin->poseCovariance()).norm(), 1e-9);
}

namespace {

/// nn or jcbb on the park with one false detection per scan and 10 % missed detections.
AssociationCounts parkWithClutter(const std::string& filter, AssociationMethod method, std::uint64_t seed,
                                  double* landmark_rmse) {
  WorldConfig world = presetConfig(WorldPreset::Park, 0, 0, seed);
  world.clutter = 1.0;
  world.detection_probability = 0.9;
  const Dataset data = buildDataset(simulate(world));
  FilterConfig config = paperFilterConfig(data.noise.value_or(world.noise));
  auto f = makeFilter(filter, startPose(data), config);
  AssociationOptions o;
  o.method = method;
  o.marginal = filter.rfind("seif", 0) == 0 ? MarginalMode::Local : MarginalMode::Exact;
  Associator a(o);
  RunLoopOptions loop;
  loop.associate = [&](SlamFilter& filt, const Step&, std::size_t k, std::vector<Observation>& z) { a.associate(filt, k, z); };
  runLoop(*f, data, {}, loop);
  a.finish(*f);
  std::map<int, Vec2> truth;
  for (int id : f->landmarkIds()) {
    if (const auto it = data.landmarks.find(a.truthOf(id)); it != data.landmarks.end()) truth[id] = it->second;
  }
  *landmark_rmse = landmarkRmse(*f, truth, Alignment::Rigid).value_or(1e9);
  return a.counts();
}

}  // namespace

TEST(Association, NearestNeighbourAndJcbbOnTheParkWithClutter) {
  for (const char* filter : {"ekf", "seif"}) {
    for (AssociationMethod method : {AssociationMethod::NearestNeighbour, AssociationMethod::Jcbb}) {
      double rmse = 0.0;
      const AssociationCounts c = parkWithClutter(filter, method, 1, &rmse);
      const double correct = static_cast<double>(c.correct) / static_cast<double>(c.scored);
      std::printf("%s %s: %.4f correct of %zu, %zu landmarks (%zu spurious, %zu duplicates), map %.3f m\n", filter,
                  std::string(associationMethodName(method)).c_str(), correct, c.scored, c.landmarks_final,
                  c.spurious_landmarks, c.duplicate_landmarks, rmse);
      EXPECT_GE(correct, 0.99) << filter;
      EXPECT_GT(c.scored, 10000u);
      EXPECT_LE(c.spurious_landmarks, 3u) << filter;
      EXPECT_LE(c.duplicate_landmarks, 3u) << filter;
      EXPECT_LT(rmse, 0.4) << filter;
    }
  }
}

TEST(Association, TheRecommendedSeifOnTheParkWithClutter) {
  // seif:profile=consistent with its constant-time gates (the bounded blanket): every seed of
  // the README's five-seed study was >= 99.19 % correct; seed 2 is the worst of them.
  for (AssociationMethod method : {AssociationMethod::NearestNeighbour, AssociationMethod::Jcbb}) {
    double rmse = 0.0;
    const AssociationCounts c = parkWithClutter("seif:profile=consistent", method, 2, &rmse);
    const double correct = static_cast<double>(c.correct) / static_cast<double>(c.scored);
    std::printf("seif:profile=consistent %s: %.4f correct of %zu, %zu landmarks (%zu spurious, %zu duplicates), map %.3f m\n",
                std::string(associationMethodName(method)).c_str(), correct, c.scored, c.landmarks_final,
                c.spurious_landmarks, c.duplicate_landmarks, rmse);
    EXPECT_GE(correct, 0.99);
    EXPECT_LE(c.spurious_landmarks, 3u);
    EXPECT_LE(c.duplicate_landmarks, 3u);
    EXPECT_LT(rmse, 0.4);
  }
}
