// Data association (association/association.hpp): the correspondence test against the dense
// computation, the chi-square gates, provisional landmarks removed exactly, known
// association's refusal, and nn / jcbb scored against the simulator's truth on the park
// with clutter and missed detections.
#include "scenario.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include <seif/eval/run_loop.hpp>
#include <seif/eval/stats.hpp>
#include <seif/association/association.hpp>
#include <seif/filters/factory.hpp>
#include <seif/sim/world.hpp>
#include "association/scan.hpp"

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

TEST(Association, KnownDropsObservationsWithoutAnIdWhenAsked) {
  const test::Scenario s = test::makeScenario(1, 10, 5);
  auto f = makeFilter("ekf", s.start, test::configFor(s));
  AssociationOptions o;
  o.drop_unlabelled = true;
  Associator known(o);
  std::vector<Observation> z = {{kUnknownLandmark, Vec2(1.0, 0.1), std::nullopt}, {7, Vec2(2.0, 0.2), std::nullopt}};
  known.associate(*f, 0, z);
  ASSERT_EQ(z.size(), 1u);
  EXPECT_EQ(z[0].landmark, 7);
  EXPECT_EQ(known.counts().unlabelled_dropped, 1u);
  EXPECT_EQ(known.counts().observations, 2u);
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

namespace {

/// A run with one false detection at step 0, far from every landmark, and its twin without
/// it: the same filter spec and association options, on one scenario.
struct Twins {
  std::unique_ptr<SlamFilter> with, without;
  AssociationCounts counts_with, counts_without;
};

Twins runWithAndWithoutAFalseDetection(const std::string& spec, const AssociationOptions& o) {
  const test::Scenario s = test::makeScenario(5, 12, 40);
  Twins t{makeFilter(spec, s.start, test::configFor(s)), makeFilter(spec, s.start, test::configFor(s)), {}, {}};
  Associator a(o), b(o);
  for (std::size_t k = 0; k < s.steps.size(); ++k) {
    const Step& step = s.steps[k];
    t.with->predict(step.u);
    t.without->predict(step.u);
    std::vector<Observation> z = step.observations, zt = step.observations;
    if (k == 0) z.push_back({kUnknownLandmark, Vec2(2.9, -2.5), std::nullopt});
    a.associate(*t.with, k, z);
    b.associate(*t.without, k, zt);
    t.with->update(z);
    t.without->update(zt);
  }
  a.finish(*t.with);
  b.finish(*t.without);
  t.counts_with = a.counts();
  t.counts_without = b.counts();
  return t;
}

}  // namespace

TEST(Association, AnUnconfirmedLandmarkIsRemovedExactly) {
  // The false detection starts a provisional landmark that nothing confirms: after the
  // window the EKF is its twin that never saw it (a first sighting only places the new
  // landmark; removing it is marginalising it).
  AssociationOptions o;
  o.method = AssociationMethod::NearestNeighbour;
  o.window = 5;
  const Twins t = runWithAndWithoutAFalseDetection("ekf", o);
  EXPECT_GE(t.counts_with.provisional_removed, 1u);
  ASSERT_EQ(t.with->landmarkIds().size(), t.without->landmarkIds().size());
  EXPECT_LT((t.with->pose() - t.without->pose()).norm(), 1e-9);
  EXPECT_LT((t.with->poseCovariance() - t.without->poseCovariance()).norm(), 1e-9);
}

TEST(Association, AHeldProvisionalLandmarkNeverReachesTheFilter) {
  // Held outside the filter, a false detection that nothing confirms leaves the SEIF exactly
  // as if it had never been made - not even a removal's round-off.
  AssociationOptions o;
  o.method = AssociationMethod::NearestNeighbour;
  o.provisional = ProvisionalPlace::Held;
  o.window = 5;
  const Twins t = runWithAndWithoutAFalseDetection("seif", o);
  EXPECT_EQ(t.counts_with.provisional_removed, t.counts_without.provisional_removed + 1);
  // The same map under other ids (the held detection took one).
  const auto &ids = t.with->landmarkIds(), &twin_ids = t.without->landmarkIds();
  ASSERT_EQ(ids.size(), twin_ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) EXPECT_EQ(t.with->landmark(ids[i]), t.without->landmark(twin_ids[i]));
  EXPECT_EQ(t.with->pose(), t.without->pose());
  EXPECT_EQ(t.with->information(), t.without->information());
}

TEST(Association, AHeldLandmarkEntersAtItsConfirmingSightingWithEverySighting) {
  // A robot standing still sees one landmark four times: the first three sightings are held
  // (nothing reaches the filter), the fourth carries their fused estimate - the mean of the
  // four and a quarter of one sighting's covariance, as the pose does not move.
  const test::Scenario s = test::makeScenario(2, 3, 5);
  FilterConfig config = test::configFor(s);
  auto f = makeFilter("ekf", s.start, config);
  AssociationOptions o;
  o.method = AssociationMethod::NearestNeighbour;
  o.provisional = ProvisionalPlace::Held;
  Associator a(o);
  const Vec2 sightings[4] = {{3.00, 0.40}, {3.02, 0.41}, {2.98, 0.39}, {3.04, 0.40}};
  for (std::size_t k = 0; k < 4; ++k) {
    std::vector<Observation> z = {{kUnknownLandmark, sightings[k], std::nullopt}};
    a.associate(*f, k, z);
    if (k < 3) {
      EXPECT_TRUE(z.empty()) << "sighting " << k;
      continue;
    }
    ASSERT_EQ(z.size(), 1u);
    ASSERT_TRUE(z[0].noise.has_value());
    // The fused sighting against the average of the four, each mapped through the model.
    const MeasurementModel& sensor = f->sensorModel();
    Vec2 mean = Vec2::Zero();
    for (const Vec2& y : sightings) mean += sensor.inverse(f->pose(), y) / 4.0;
    EXPECT_LT((sensor.inverse(f->pose(), z[0].z) - mean).norm(), 2e-3);
    const Mat2 R = sensor.noise();
    EXPECT_NEAR(z[0].noise->trace(), R.trace() / 4.0, 0.05 * R.trace());
    f->update(z);
  }
  a.finish(*f);
  EXPECT_EQ(f->landmarkIds().size(), 1u);
  EXPECT_EQ(a.counts().new_landmarks, 1u);
  EXPECT_EQ(a.counts().provisional_removed, 0u);
}

namespace {

/// nn or jcbb on the park with one false detection per scan and 10 % missed detections.
AssociationCounts parkWithClutter(const std::string& filter, AssociationMethod method, std::uint64_t seed,
                                  double* landmark_rmse, ProvisionalPlace place = ProvisionalPlace::Filter) {
  WorldConfig world = presetConfig(WorldPreset::Park, 0, 0, seed);
  world.clutter = 1.0;
  world.detection_probability = 0.9;
  const Dataset data = buildDataset(simulate(world));
  FilterConfig config = paperFilterConfig(data.noise.value_or(world.noise));
  auto f = makeFilter(filter, startPose(data), config);
  AssociationOptions o;
  o.method = method;
  o.marginal = filter.rfind("seif", 0) == 0 ? MarginalMode::Local : MarginalMode::Exact;
  o.provisional = place;
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

/// nn and jcbb with `filter` on the park's `seed`: >= 99 % correct, at most 3 spurious and
/// 3 duplicate landmarks, the map within `max_rmse`.
void expectGoodAssociationOnThePark(const std::string& filter, std::uint64_t seed, double max_rmse,
                                    ProvisionalPlace place = ProvisionalPlace::Filter) {
  for (AssociationMethod method : {AssociationMethod::NearestNeighbour, AssociationMethod::Jcbb}) {
    double rmse = 0.0;
    const AssociationCounts c = parkWithClutter(filter, method, seed, &rmse, place);
    const double correct = static_cast<double>(c.correct) / static_cast<double>(c.scored);
    const std::string label = filter + " " + std::string(associationMethodName(method)) + ", provisional " +
                              std::string(provisionalPlaceName(place)) + ", seed " + std::to_string(seed);
    std::printf("%s: %.4f correct of %zu, %zu landmarks (%zu spurious, %zu duplicates), map %.3f m\n", label.c_str(),
                correct, c.scored, c.landmarks_final, c.spurious_landmarks, c.duplicate_landmarks, rmse);
    EXPECT_GE(correct, 0.99) << label;
    EXPECT_GT(c.scored, 10000u) << label;
    EXPECT_LE(c.spurious_landmarks, 3u) << label;
    EXPECT_LE(c.duplicate_landmarks, 3u) << label;
    EXPECT_LT(rmse, max_rmse) << label;
  }
}

}  // namespace

TEST(Association, NearestNeighbourAndJcbbOnTheParkWithClutter) {
  expectGoodAssociationOnThePark("ekf", 1, 0.4);
  expectGoodAssociationOnThePark("seif", 1, 0.4);
}

TEST(Association, TheRecommendedSeifOnTheParkWithClutter) {
  // seif:profile=consistent with its constant-time gates (the bounded blanket): every seed of
  // the README's five-seed study was >= 99.19 % correct; seed 2 is the worst of them.
  expectGoodAssociationOnThePark("seif:profile=consistent", 2, 0.4);
}

TEST(Association, HeldProvisionalLandmarksKeepClutterOutOfThePaperSeif) {
  // The paper's SEIF on the park's seed 5: with provisional landmarks in the filter, clutter
  // churns its six active links and it associates 94.5 % correctly (12 duplicates, map
  // 1.15 m); held outside the filter, 99.54 % and 0.44 m (known association: 0.38 m).
  expectGoodAssociationOnThePark("seif", 5, 0.6, ProvisionalPlace::Held);
}
