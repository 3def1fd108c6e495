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
#include <seif/filters/checkpoint.hpp>
#include <seif/filters/factory.hpp>
#include <seif/sim/world.hpp>
#include "association/scan.hpp"
#include "association/track_score.hpp"
#include "forwarding_filter.hpp"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <set>
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

TEST(Association, EvenChiSquareQuantilesHoldForScansOfManyPairings) {
  // Beyond about 650 pairings exp(-x/2) underflows and the sum overflows in a direct product.
  for (int k : {200, 650, 700, 1000, 2500}) {
    for (double p : {0.99, 0.9999}) {
      EXPECT_NEAR(chiSquareEvenQuantile(p, k), chiSquareQuantile(p, 2.0 * k), 1e-8 * 2 * k) << k << " " << p;
    }
  }
}

namespace {

/// One scan by hand: the pose at the origin, landmarks at `landmarks` (independent, with
/// covariance 0.01 I), observations `z` (range, bearing; sigma 0.1 m, 0.05 rad); every
/// pairing inside the 0.99 gate offered, in the observations' order.
struct HandScan {
  RangeBearingModel sensor{0.1, 0.05};
  std::vector<Observation> observations;
  std::vector<double> gates;
  ScanProblem scan;

  HandScan(const std::vector<Vec2>& landmarks, const std::vector<Vec2>& z) {
    for (const Vec2& v : z) observations.push_back({kUnknownLandmark, v, std::nullopt});
    const Eigen::Index n = 3 + 2 * static_cast<Eigen::Index>(landmarks.size());
    scan.joint.mean = Eigen::VectorXd::Zero(n);
    scan.joint.covariance = 0.01 * Eigen::MatrixXd::Identity(n, n);
    scan.joint.covariance.topLeftCorner<3, 3>() = Vec3(0.02, 0.02, 0.001).asDiagonal();
    for (std::size_t j = 0; j < landmarks.size(); ++j) {
      const Eigen::Index r = 3 + 2 * static_cast<Eigen::Index>(j);
      scan.joint.mean.segment<2>(r) = landmarks[j];
      scan.column[static_cast<int>(j)] = r;
    }
    scan.sensor = &sensor;
    scan.observations = &observations;
    scan.accept_d2 = chiSquareEvenQuantile(0.99, 1);
    scan.joint_gates = &gates;
    scan.compatible.resize(observations.size());
    for (std::size_t i = 0; i < observations.size(); ++i) {
      for (std::size_t j = 0; j < landmarks.size(); ++j) {
        const PredictedMeasurement pm = predictFromMarginal(sensor, scan.joint, scan.column.at(static_cast<int>(j)),
                                                            sensor.noise());
        const Vec2 nu = sensor.residual(observations[i].z, pm.z);
        const double d2 = nu.dot(pm.S.llt().solve(nu));
        if (d2 <= scan.accept_d2) scan.compatible[i].push_back({static_cast<int>(i), static_cast<int>(j), d2});
      }
    }
  }
};

}  // namespace

TEST(Association, JcbbGivesALandmarkToTheCloserObservationWhateverTheOrder) {
  // One landmark, two observations inside its gate: one pairing either way, and the closer
  // observation must get it, listed first or second. (Searched in the listed order with
  // ties never explored, the first kept it.)
  const std::vector<Vec2> landmark = {Vec2(5.0, 0.0)};
  const Vec2 close(5.02, 0.005), far(5.25, -0.04);
  for (bool close_first : {true, false}) {
    HandScan h(landmark, close_first ? std::vector<Vec2>{close, far} : std::vector<Vec2>{far, close});
    ASSERT_EQ(h.scan.compatible[0].size(), 1u);
    ASSERT_EQ(h.scan.compatible[1].size(), 1u);
    bool truncated = true;
    const std::vector<int> pairing = assignJcbb(h.scan, 1000, &truncated);
    EXPECT_FALSE(truncated);
    EXPECT_EQ(pairing, close_first ? (std::vector<int>{0, -1}) : (std::vector<int>{-1, 0})) << close_first;
  }
}

/// The joint distance of hypothesis `pairs` ((observation, landmark column) pairs) of a hand
/// scan, from the dense S_H = J_H Sigma J_H^T + R_H.
double jointD2(const HandScan& h, const std::vector<std::pair<std::size_t, int>>& pairs) {
  const Eigen::Index n = h.scan.joint.mean.size(), k = 2 * static_cast<Eigen::Index>(pairs.size());
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(k, n), R = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd nu(k);
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const auto [i, landmark] = pairs[p];
    const Eigen::Index r = 2 * static_cast<Eigen::Index>(p), col = h.scan.column.at(landmark);
    Mat23 J_x;
    Mat2 J_y;
    const PredictedMeasurement pm =
        predictFromMarginal(h.sensor, h.scan.joint, col, h.sensor.noise(), &J_x, &J_y);
    J.block<2, 3>(r, 0) = J_x;
    J.block<2, 2>(r, col) = J_y;
    R.block<2, 2>(r, r) = h.sensor.noise();
    nu.segment<2>(r) = h.sensor.residual(h.observations[i].z, pm.z);
  }
  const Eigen::MatrixXd S = J * h.scan.joint.covariance * J.transpose() + R;
  return nu.dot(S.llt().solve(nu));
}

TEST(Association, JcbbPrefersTheSmallerJointDistanceAmongAsManyPairings) {
  // A and B both fit L1 best, A best; B also fits L2, poorly; C fits only L2. Two pairings
  // at most: the first dive finds {A-L1, B-L2}; {A-L1, C-L2} and {B-L1, C-L2} pair as many
  // at a smaller joint distance. JCBB must answer the smallest (the dense computation), in
  // whatever order the observations come. (Never exploring "leave B unpaired" when it
  // could only tie kept the first dive's.)
  const std::vector<Vec2> landmarks = {Vec2(5.0, 0.0), Vec2(5.65, 0.0)};
  const std::vector<Vec2> z = {Vec2(5.0, 0.0), Vec2(5.08, 0.0), Vec2(5.75, 0.0)};  // A, B, C
  const HandScan listed(landmarks, z);
  ASSERT_EQ(listed.scan.compatible[0].size(), 1u);
  ASSERT_EQ(listed.scan.compatible[1].size(), 2u);
  ASSERT_EQ(listed.scan.compatible[2].size(), 1u);
  const double first_dive = jointD2(listed, {{0, 0}, {1, 1}});
  const std::vector<std::pair<double, std::vector<int>>> others = {
      {jointD2(listed, {{0, 0}, {2, 1}}), {0, -1, 1}}, {jointD2(listed, {{1, 0}, {2, 1}}), {-1, 0, 1}}};
  const auto best = std::min_element(others.begin(), others.end());
  ASSERT_LT(best->first, first_dive) << "the case needs the first dive not to be the answer";
  std::vector<std::size_t> order = {0, 1, 2};
  do {
    std::vector<Vec2> zs;
    for (std::size_t i : order) zs.push_back(z[i]);
    HandScan h(landmarks, zs);
    std::vector<int> expected(3);
    for (std::size_t i = 0; i < 3; ++i) expected[i] = best->second[order[i]];
    bool truncated = true;
    EXPECT_EQ(assignJcbb(h.scan, 1000, &truncated), expected) << order[0] << order[1] << order[2];
    EXPECT_FALSE(truncated);
  } while (std::next_permutation(order.begin(), order.end()));
}

TEST(Association, JcbbUnderItsNodeBoundAnswersWithTheBestFoundSoFar) {
  // Three observations of three landmarks. A bound below one dive's depth still returns the
  // pairings of the dive so far; a bound the whole search fits in is not "truncated".
  HandScan h({Vec2(4.0, 0.0), Vec2(4.0, 2.0), Vec2(4.0, -2.0)},
             {Vec2(4.0, 0.0), Vec2(std::hypot(4.0, 2.0), std::atan2(2.0, 4.0)),
              Vec2(std::hypot(4.0, 2.0), std::atan2(-2.0, 4.0))});
  bool truncated = false;
  const std::vector<int> whole = assignJcbb(h.scan, 1u << 20, &truncated);
  ASSERT_FALSE(truncated);
  EXPECT_EQ(whole, (std::vector<int>{0, 1, 2}));
  const std::vector<int> cut = assignJcbb(h.scan, 2, &truncated);
  EXPECT_TRUE(truncated);
  int paired = 0;
  for (std::size_t i = 0; i < cut.size(); ++i) {
    if (cut[i] < 0) continue;
    EXPECT_EQ(cut[i], whole[i]) << "observation " << i;
    ++paired;
  }
  EXPECT_GE(paired, 1) << "the pairings of the dive so far";
  // The smallest bound that is not truncated gives the whole search's answer.
  std::size_t bound = 1;
  while (assignJcbb(h.scan, bound, &truncated), truncated) ++bound;
  EXPECT_GE(bound, 4u) << "a root and a node per observation at least";
  EXPECT_EQ(assignJcbb(h.scan, bound, &truncated), whole);
  assignJcbb(h.scan, bound - 1, &truncated);
  EXPECT_TRUE(truncated);
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
  o = AssociationOptions{};
  o.method = AssociationMethod::NearestNeighbour;
  o.confirm_rule = ConfirmRule::Score;
  o.window = 0;  // nothing could ever be confirmed
  EXPECT_THROW(Associator{o}, InvalidArgument);
  o.window = 1;
  o.detection_probability = 1.0;  // log(1 - P_D): a miss would be -inf
  EXPECT_THROW(Associator{o}, InvalidArgument);
  o.detection_probability = 0.9;
  o.clutter_density = -1.0;
  EXPECT_THROW(Associator{o}, InvalidArgument);
  EXPECT_THROW(parseAssociationMethod("greedy"), InvalidArgument);
  EXPECT_THROW(parseConfirmRule("vote"), InvalidArgument);
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

namespace {

/// An EKF that says its gates should use `gate` and records every marginal mode asked of it.
class GateRecordingFilter : public test::ForwardingFilter {
 public:
  explicit GateRecordingFilter(MarginalMode gate) : gate_(gate) {}
  Marginal marginal(std::span<const int> ids, bool pose, MarginalMode mode) const override {
    asked.push_back(mode);
    return ForwardingFilter::marginal(ids, pose, mode);
  }
  MarginalMode gateMarginal() const override { return gate_; }

  mutable std::vector<MarginalMode> asked;

 private:
  MarginalMode gate_;
};

/// The marginal modes an associator asks of a filter whose gateMarginal() is `gate`, over
/// three scans of the same two landmarks.
std::set<MarginalMode> modesAsked(MarginalMode gate, std::optional<MarginalMode> option) {
  GateRecordingFilter f(gate);
  AssociationOptions o;
  o.method = AssociationMethod::NearestNeighbour;
  o.marginal = option;
  Associator a(o);
  for (std::size_t k = 0; k < 3; ++k) {
    std::vector<Observation> z = {{1, Vec2(1.0, 0.1), {}}, {2, Vec2(1.5, -0.4), {}}};
    a.associate(f, k, z);
    f.update(z);
  }
  EXPECT_GE(f.asked.size(), 3u);
  return {f.asked.begin(), f.asked.end()};
}

}  // namespace

TEST(Association, UnlessToldTheGatesUseTheFiltersOwnMarginal) {
  // --gate-marginal auto (AssociationOptions::marginal unset): the filter's gateMarginal().
  using M = MarginalMode;
  EXPECT_EQ(modesAsked(M::Local, std::nullopt), std::set<M>{M::Local});
  EXPECT_EQ(modesAsked(M::Exact, std::nullopt), std::set<M>{M::Exact});
  EXPECT_EQ(modesAsked(M::Local, M::Exact), std::set<M>{M::Exact});
  EXPECT_EQ(modesAsked(M::Exact, M::Conservative), std::set<M>{M::Conservative});
  // The SEIF's own is its constant-time local marginal; the others' the exact one.
  const FilterConfig config = paperFilterConfig(NoiseModel{});
  EXPECT_EQ(makeFilter("seif", Pose2::Zero(), config)->gateMarginal(), M::Local);
  EXPECT_EQ(makeFilter("seif:profile=consistent", Pose2::Zero(), config)->gateMarginal(), M::Local);
  for (const char* name : {"ekf", "eif", "batch"}) EXPECT_EQ(makeFilter(name, Pose2::Zero(), config)->gateMarginal(), M::Exact) << name;
  // The batch gates, before it solves, with the marginals of the filter it starts from.
  EXPECT_EQ(makeFilter("batch:init=seif", Pose2::Zero(), config)->gateMarginal(), M::Local);
  // The option's text: auto is the default and reads back unset.
  AssociationOptions o;
  for (const AssociationOption& row : associationOptions()) {
    if (row.key != "gate-marginal") continue;
    EXPECT_EQ(row.get(o), "auto");
    row.set(o, "local");
    EXPECT_EQ(o.marginal, M::Local);
    row.set(o, "auto");
    EXPECT_FALSE(o.marginal.has_value());
    EXPECT_THROW(row.set(o, "nearest"), InvalidArgument);
  }
}

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

TEST(Association, TheTrackScoresTermsAreTheClosedForms) {
  // log(P_D N(nu; 0, S) / lambda) for S = diag(4, 1) (|S| = 4), nu = (2, 1) (d^2 = 2):
  // log 0.9 - 1 - log(2 pi * 2) - log 0.5; a miss log 0.1; the thresholds log(0.99 / 0.001)
  // and log(0.01 / 0.999).
  const Mat2 S = Vec2(4.0, 1.0).asDiagonal();
  const double expected = std::log(0.9) - 1.0 - std::log(4.0 * 3.14159265358979323846) - std::log(0.5);
  EXPECT_NEAR(trackSightingScore(Vec2(2.0, 1.0), S, 0.9, std::log(0.5)), expected, 1e-12);
  Mat2 rotated;  // the same S seen in other axes: the density does not depend on them
  const double c = std::cos(0.7), s = std::sin(0.7);
  rotated << c, -s, s, c;
  EXPECT_NEAR(trackSightingScore(rotated * Vec2(2.0, 1.0), rotated * S * rotated.transpose(), 0.9, std::log(0.5)),
              expected, 1e-12);
  EXPECT_EQ(trackSightingScore(Vec2(1.0, 0.0), Mat2::Zero(), 0.9, 0.0), 0.0);  // no covariance: no evidence
  EXPECT_NEAR(trackMissScore(0.9), std::log(0.1), 1e-15);
  EXPECT_NEAR(trackConfirmScore(), std::log(0.99 / 0.001), 1e-12);
  EXPECT_NEAR(trackDeleteScore(), std::log(0.01 / 0.999), 1e-12);
  EXPECT_LE(2.0 * trackMissScore(0.9), trackDeleteScore());  // two misses in view remove (below)
}

TEST(Association, TheTrackScoreRemovesClutterItKeepsSeeingInViewUnseen) {
  // A false detection at step 20 starts a provisional landmark. Under the track score each
  // later scan in which it lies in the footprint unseen adds log(1 - P_D) = log 0.1, so two
  // such scans take it below log(beta / (1 - alpha)) = log(0.01 / 0.999) and it is removed at
  // the next scan: long before its window (1000 scans) would. The EKF is then its twin that
  // never saw it. Under the count rule with the same window it is still provisional.
  const test::Scenario s = test::makeScenario(5, 12, 40);
  for (ConfirmRule rule : {ConfirmRule::Score, ConfirmRule::Count}) {
    AssociationOptions o;
    o.method = AssociationMethod::NearestNeighbour;
    o.window = 1000;
    o.confirm_rule = rule;
    auto with = makeFilter("ekf", s.start, test::configFor(s));
    auto without = makeFilter("ekf", s.start, test::configFor(s));
    Associator a(o), b(o);
    Vec2 lo = Vec2::Constant(1e9), hi = Vec2::Constant(-1e9);
    for (std::size_t k = 0; k < s.steps.size(); ++k) {
      with->predict(s.steps[k].u);
      without->predict(s.steps[k].u);
      std::vector<Observation> z = s.steps[k].observations, zt = z;
      // At the centre of the footprint the earlier scans drew, which holds it as the robot drives on.
      if (k == 20) z.push_back({kUnknownLandmark, 0.5 * (lo + hi), std::nullopt});
      for (const Observation& real : zt) {
        lo = lo.cwiseMin(real.z);
        hi = hi.cwiseMax(real.z);
      }
      a.associate(*with, k, z);
      b.associate(*without, k, zt);
      // In the filter from step 20's update; two scans unseen in view are needed, so it is
      // there at least at 21 and 22 (every step here has a scan), and gone within ten scans
      // (as the robot turns, its prediction leaves the footprint on some of them).
      const std::size_t extra = with->landmarkIds().size() - without->landmarkIds().size();
      if (rule == ConfirmRule::Score && (k == 21 || k == 22)) {
        EXPECT_EQ(extra, 1u) << "step " << k;
      }
      if (rule == ConfirmRule::Score && k >= 31) {
        EXPECT_EQ(extra, 0u) << "step " << k;
      }
      with->update(z);
      without->update(zt);
    }
    const std::string label(confirmRuleName(rule));
    if (rule == ConfirmRule::Count) {
      EXPECT_EQ(a.counts().provisional_removed, b.counts().provisional_removed) << label;  // not yet
      continue;
    }
    EXPECT_EQ(a.counts().provisional_removed, b.counts().provisional_removed + 1) << label;
    ASSERT_EQ(with->landmarkIds().size(), without->landmarkIds().size()) << label;  // its id was taken: the rest shifted
    EXPECT_LT((with->pose() - without->pose()).norm(), 1e-9) << label;
    EXPECT_LT((with->poseCovariance() - without->poseCovariance()).norm(), 1e-9) << label;
  }
}

TEST(Association, AScanWhoseUpdateFailedLeavesNoLandmarkBehind) {
  // A false detection of one point P from step 3 on. The filter refuses the update that would
  // have started P's landmark in it - its first sighting in the filter, or with held
  // provisional landmarks the sighting that confirms it - and the caller goes on. The
  // associator must forget that landmark: no later query or expiry may look for it in the
  // filter (UnknownLandmark), and every landmark it counts as started was in the filter
  // (provisional in the filter) or held.
  // When the caller also discards the scan (Associator::discardScan), it counts as empty:
  // held (confirm 2), P is still provisional and the next sighting confirms it under the
  // same id; in the filter (confirm 4), the next scan starts P again under the same id; the
  // counts are those before the refused scan.
  const test::Scenario s = test::makeScenario(5, 12, 40);
  const Vec2 P(2.0, -7.0);
  for (const bool discard : {false, true}) {
    for (const ProvisionalPlace place : {ProvisionalPlace::Filter, ProvisionalPlace::Held}) {
      for (const char* spec : {"ekf", "seif"}) {
        const std::string label = std::string(spec) + ", " + std::string(provisionalPlaceName(place)) +
                                  (discard ? ", discarded" : "");
        auto f = makeFilter(spec, s.start, test::configFor(s));
        AssociationOptions o;
        o.method = AssociationMethod::NearestNeighbour;
        o.provisional = place;
        o.confirm = place == ProvisionalPlace::Held ? 2 : 4;
        o.window = 5;
        Associator a(o);
        const std::size_t refuse = place == ProvisionalPlace::Held ? 4 : 3;
        int id_p = kUnknownLandmark;
        std::set<int> in_filter;  // every landmark the filter held after an update
        for (std::size_t k = 0; k < s.steps.size(); ++k) {
          f->predict(s.steps[k].u);
          std::vector<Observation> z = s.steps[k].observations;
          if (k >= 3) z.push_back({kUnknownLandmark, f->sensorModel().predict(f->pose(), P), std::nullopt});
          const AssociationCounts before = a.counts();
          ASSERT_NO_THROW(a.associate(*f, k, z)) << label << ", step " << k;
          if (k == refuse) {
            ASSERT_FALSE(z.empty());
            id_p = z.back().landmark;  // P's (the held one's confirming sighting, or its first)
            z.back().noise = Mat2(Vec2(-1.0, 1.0).asDiagonal());  // the filter refuses the scan
            EXPECT_THROW(f->update(z), ModelError) << label;
            if (discard) {
              a.discardScan();
              EXPECT_EQ(a.counts().new_landmarks, before.new_landmarks) << label;
              EXPECT_EQ(a.counts().ambiguous_dropped, before.ambiguous_dropped) << label;
            }
            continue;
          }
          ASSERT_NO_THROW(f->update(z)) << label << ", step " << k;
          in_filter.insert(f->landmarkIds().begin(), f->landmarkIds().end());
          if (discard && k == refuse + 1) {
            ASSERT_FALSE(z.empty());
            EXPECT_EQ(z.back().landmark, id_p) << label;
            EXPECT_TRUE(f->hasLandmark(id_p)) << label;  // held: confirmed; in the filter: started again
          }
        }
        ASSERT_NO_THROW(a.finish(*f)) << label;
        EXPECT_EQ(a.counts().landmarks_final, f->landmarkIds().size()) << label;
        if (place == ProvisionalPlace::Filter) {
          EXPECT_EQ(a.counts().new_landmarks, in_filter.size()) << label;
        }
      }
    }
  }
}

TEST(Association, ADiscardedScanLeavesTheCallersLandmarksIndexed) {
  // The filter starts with landmark 1 (a caller's map). A scan starts two landmarks - ids 0
  // and 2, skipping 1 - and is discarded: landmark 1 stays indexed, and the next scan's
  // sighting of it is matched to it (no cyclic re-indexing, which would put it back in a
  // map this small).
  auto f = makeFilter("ekf", Pose2::Zero(), paperFilterConfig(NoiseModel{}));
  const Observation one{1, Vec2(3.0, 0.0), std::nullopt};
  f->update(std::vector<Observation>{one});
  AssociationOptions o;
  o.method = AssociationMethod::NearestNeighbour;
  o.refresh = 0;
  Associator a(o);
  std::vector<Observation> z = {{kUnknownLandmark, Vec2(3.0, 2.0), std::nullopt},
                                {kUnknownLandmark, Vec2(3.0, -2.0), std::nullopt}};
  a.associate(*f, 0, z);
  ASSERT_EQ(z.size(), 2u);
  EXPECT_EQ(z[0].landmark, 0);
  EXPECT_EQ(z[1].landmark, 2);
  a.discardScan();
  z = {{kUnknownLandmark, one.z, std::nullopt}};
  a.associate(*f, 1, z);
  ASSERT_EQ(z.size(), 1u);
  EXPECT_EQ(z[0].landmark, 1);
}

TEST(Association, ALandmarkMappedUncertainIsFoundFromAPoseThatIsNot) {
  // The robot maps landmark L while its pose is uncertain and 1.25 m off, comes back to the
  // landmark it started by (its pose becomes certain; L's mean stays ~0.6 m off, its
  // covariance large), drives out again seeing that landmark, and sees L from a pose known
  // to a few cm. The observed point is then ~0.6 m from L's mean (1.25 m from where the grid
  // indexed it), beyond the point's own reach, but L's covariance puts it inside the gate:
  // the grid must offer L. A query that left out the landmark's own spread started a
  // duplicate.
  NoiseModel noise;
  noise.sigma_v = 0.05;
  noise.sigma_w = 0.002;
  noise.sigma_range = 0.02;
  noise.sigma_bearing = 0.002;
  const Vec2 A(3.0, 0.0), L(10.5, 0.5);
  for (const char* spec : {"ekf", "seif:mean=exact"}) {
    auto f = makeFilter(spec, Pose2::Zero(), paperFilterConfig(noise));
    AssociationOptions o;
    o.method = AssociationMethod::NearestNeighbour;
    o.confirm = 1;
    o.merge = 0.0;   // the duplicate is not mended afterwards
    o.refresh = 0;   // L stays indexed where it was first seen, before the loop closed
    Associator a(o);
    const RangeBearingModel sensor(noise.sigma_range, noise.sigma_bearing);
    Pose2 truth = Pose2::Zero();
    std::size_t k = 0;
    const auto step = [&](double v, double true_v, const std::vector<Vec2>& seen) {
      const VelocityControl u{v, 0.0, 1.0};
      truth = VelocityMotionModel::apply(truth, VelocityControl{true_v, 0.0, 1.0});
      f->predict(u);
      std::vector<Observation> z;
      for (const Vec2& y : seen) z.push_back({kUnknownLandmark, sensor.predict(truth, y), std::nullopt});
      a.associate(*f, k++, z);
      f->update(z);
      return z;
    };
    step(0.0, 0.0, {A});
    for (int i = 0; i < 50; ++i) step(0.1, 0.125, {});  // out, 25 % further than commanded
    step(0.0, 0.0, {L});                                // L mapped from an uncertain pose
    for (int i = 0; i < 50; ++i) step(-0.1, -0.1, {});
    step(0.0, 0.0, {A});                                // back: the pose is certain again
    for (int i = 0; i < 50; ++i) step(0.1, 0.1, {A});   // out again, A in view
    const int l_id = f->landmarkIds().at(1);
    const Vec2 seen_from_here = sensor.inverse(f->pose(), sensor.predict(truth, L));
    ASSERT_GT((seen_from_here - f->landmark(l_id)).norm(), 0.5) << spec << ": the case needs L's mean off";
    const std::vector<Observation> z = step(0.0, 0.0, {L, A});
    ASSERT_EQ(z.size(), 2u) << spec;
    EXPECT_EQ(z[0].landmark, l_id) << spec << ": L seen again";
    EXPECT_EQ(a.counts().new_landmarks, 2u) << spec;
  }
}

TEST(Association, AHeldProvisionalLandmarkNeverReachesTheFilter) {
  // Held outside the filter, a false detection that nothing confirms leaves the SEIF exactly
  // as if it had never been made - not even a removal's round-off. With exact gates: the
  // SEIF's local marginal grows its blanket from every variable a scan queries, so the
  // detection's extra candidates change the grid's spreads, later scans' candidates and the
  // pose covariance a held estimate fuses with, in the last bits.
  AssociationOptions o;
  o.method = AssociationMethod::NearestNeighbour;
  o.marginal = MarginalMode::Exact;
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

/// The park's clutter: false detections per scan, the steps (0: the preset's) and the rule.
struct ParkClutter {
  double clutter = 1.0;
  int steps = 0;
  ConfirmRule rule = ConfirmRule::Count;
};

/// nn or jcbb on the park with false detections (one per scan unless told) and 10 % missed detections.
AssociationCounts parkWithClutter(const std::string& filter, AssociationMethod method, std::uint64_t seed,
                                  double* landmark_rmse, ProvisionalPlace place = ProvisionalPlace::Filter,
                                  const ParkClutter& park = {}) {
  WorldConfig world = presetConfig(WorldPreset::Park, 0, park.steps, seed);
  world.clutter = park.clutter;
  world.detection_probability = 0.9;
  const Dataset data = buildDataset(simulate(world));
  FilterConfig config = paperFilterConfig(data.noise.value_or(world.noise));
  auto f = makeFilter(filter, startPose(data), config);
  AssociationOptions o;
  o.method = method;
  o.marginal = filter.rfind("seif", 0) == 0 ? MarginalMode::Local : MarginalMode::Exact;
  o.provisional = place;
  o.confirm_rule = park.rule;
  Associator a(o);
  RunLoopOptions loop;
  loop.associate = [&](SlamFilter& filt, const Step&, std::size_t k, std::vector<Observation>& z) { a.associate(filt, k, z); };
  runLoop(*f, data, {}, loop);
  a.finish(*f);
  // A duplicate is exactly a landmark whose label an older (smaller id) one holds.
  std::vector<int> by_age = f->landmarkIds();
  std::sort(by_age.begin(), by_age.end());
  std::set<int> labels;
  std::size_t duplicates = 0;
  for (int id : by_age) {
    const int label = a.truthOf(id);
    const bool older_has_it = label >= 0 && !labels.insert(label).second;
    EXPECT_EQ(a.isDuplicate(id), older_has_it) << "landmark " << id << ", label " << label;
    duplicates += a.isDuplicate(id) ? 1 : 0;
  }
  EXPECT_EQ(duplicates, a.counts().duplicate_landmarks);
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

// lastScan(): one decision per observation given, each consistent with the gates, the
// observations left for the update, and the counts; every outcome met on the way.
TEST(Association, TheLastScanSaysWhatBecameOfEveryObservation) {
  const double accept_d2 = chiSquareQuantile(0.99, 2), new_d2 = chiSquareQuantile(0.9999, 2);
  for (AssociationMethod method : {AssociationMethod::NearestNeighbour, AssociationMethod::Jcbb}) {
    for (ProvisionalPlace place : {ProvisionalPlace::Filter, ProvisionalPlace::Held}) {
      const std::string label = std::string(associationMethodName(method)) + ", " + std::string(provisionalPlaceName(place));
      WorldConfig world = presetConfig(WorldPreset::Park, 0, 400, 3);
      world.clutter = 1.0;
      world.detection_probability = 0.9;
      const Dataset data = buildDataset(simulate(world));
      auto f = makeFilter("ekf", startPose(data), paperFilterConfig(data.noise.value_or(world.noise)));
      AssociationOptions o;
      o.method = method;
      o.provisional = place;
      Associator a(o);
      std::map<ScanDecision::Outcome, std::size_t> seen;
      std::size_t held_sightings = 0;
      RunLoopOptions loop;
      loop.associate = [&](SlamFilter& filter, const Step&, std::size_t k, std::vector<Observation>& z) {
        const std::size_t given = z.size();
        const AssociationCounts before = a.counts();
        a.associate(filter, k, z);
        const std::span<const ScanDecision> d = a.lastScan();
        ASSERT_EQ(d.size(), given) << label << ", step " << k;
        std::size_t applied = 0, started = 0, dropped = 0;
        std::set<int> paired;
        for (const ScanDecision& x : d) {
          switch (x.outcome) {
            case ScanDecision::Outcome::Matched:
              EXPECT_LE(x.d2, accept_d2) << label << ", step " << k;
              EXPECT_TRUE(paired.insert(x.landmark).second) << "two observations of landmark " << x.landmark;
              break;
            case ScanDecision::Outcome::New:
              EXPECT_GT(x.d2, new_d2) << label << ", step " << k;
              EXPECT_FALSE(filter.hasLandmark(x.landmark)) << label << ": started as " << x.landmark << ", an id in use";
              ++started;
              break;
            case ScanDecision::Outcome::Ambiguous:
              EXPECT_LE(x.d2, new_d2) << label << ", step " << k;
              EXPECT_EQ(x.landmark, kUnknownLandmark);
              EXPECT_FALSE(x.applied);
              ++dropped;
              break;
          }
          ++seen[x.outcome];
          if (x.outcome != ScanDecision::Outcome::Ambiguous) {
            EXPECT_NE(x.landmark, kUnknownLandmark);
          }
          if (x.outcome == ScanDecision::Outcome::Matched && !x.applied) ++held_sightings;
          if (x.applied) {  // the observations left for the update, in the same order
            ASSERT_LT(applied, z.size()) << label << ", step " << k;
            EXPECT_EQ(z[applied].landmark, x.landmark) << label << ", step " << k;
            ++applied;
          }
        }
        EXPECT_EQ(applied, z.size()) << label << ", step " << k;
        EXPECT_EQ(started, a.counts().new_landmarks - before.new_landmarks) << label << ", step " << k;
        EXPECT_EQ(dropped, a.counts().ambiguous_dropped - before.ambiguous_dropped) << label << ", step " << k;
      };
      runLoop(*f, data, {}, loop);
      for (ScanDecision::Outcome outcome : {ScanDecision::Outcome::Matched, ScanDecision::Outcome::New,
                                            ScanDecision::Outcome::Ambiguous}) {
        EXPECT_GT(seen[outcome], 0u) << label << ": no observation " << scanOutcomeName(outcome);
      }
      // Held: a provisional landmark's sightings before it is confirmed stay out of the filter.
      EXPECT_EQ(held_sightings > 0, place == ProvisionalPlace::Held) << label;
    }
  }
  // Known association decides nothing.
  const test::Scenario s = test::makeScenario(5, 12, 3);
  auto f = makeFilter("ekf", s.start, test::configFor(s));
  Associator known{AssociationOptions{}};
  std::vector<Observation> z = s.steps[0].observations;
  ASSERT_FALSE(z.empty());
  f->predict(s.steps[0].u);
  known.associate(*f, 0, z);
  EXPECT_TRUE(known.lastScan().empty());
}

TEST(Association, NearestNeighbourAndJcbbOnTheParkWithClutter) {
  expectGoodAssociationOnThePark("ekf", 1, 0.4);
  expectGoodAssociationOnThePark("seif", 1, 0.4);
}

TEST(Association, TheRecommendedSeifOnTheParkWithClutter) {
  // seif:profile=consistent with its constant-time gates (the bounded blanket): every seed of
  // the README's five-seed study was >= 99.21 % correct; seed 2 is the worst of them.
  expectGoodAssociationOnThePark("seif:profile=consistent", 2, 0.4);
}

TEST(Association, TheTrackScoreKeepsDenseClutterOutOfTheMap) {
  // 20 false detections a scan on the park (300 steps, seed 1, 10 % missed), EKF and nn.
  // Counted (4 sightings in 20 scans), clutter confirms itself: 271 spurious landmarks of 312,
  // 97.2 % correct. Scored against the clutter density it does not (docs/association.md,
  // "Provisional landmarks").
  for (ConfirmRule rule : {ConfirmRule::Count, ConfirmRule::Score}) {
    double rmse = 0.0;
    const AssociationCounts c = parkWithClutter("ekf", AssociationMethod::NearestNeighbour, 1, &rmse,
                                                ProvisionalPlace::Filter, ParkClutter{20.0, 300, rule});
    const double correct = static_cast<double>(c.correct) / static_cast<double>(c.scored);
    std::printf("%s: %.4f correct of %zu, %zu landmarks (%zu spurious, %zu duplicates), map %.3f m\n",
                std::string(confirmRuleName(rule)).c_str(), correct, c.scored, c.landmarks_final, c.spurious_landmarks,
                c.duplicate_landmarks, rmse);
    if (rule == ConfirmRule::Count) {
      EXPECT_GT(c.spurious_landmarks, 100u);  // what the score is there to cure
      continue;
    }
    EXPECT_GE(correct, 0.99);
    EXPECT_GT(c.scored, 1500u);
    EXPECT_LE(c.spurious_landmarks, 5u);
    EXPECT_LE(c.duplicate_landmarks, 3u);
    EXPECT_LT(rmse, 0.6);  // known association on this log: 0.46 m
  }
}

TEST(Association, HeldProvisionalLandmarksKeepClutterOutOfThePaperSeif) {
  // The paper's SEIF on the park's seed 5: with provisional landmarks in the filter, clutter
  // churns its six active links and it associates 94.5 % correctly (12 duplicates, map
  // 1.15 m); held outside the filter, 99.54 % and 0.44 m (known association: 0.38 m).
  expectGoodAssociationOnThePark("seif", 5, 0.6, ProvisionalPlace::Held);
}

// The associator's checkpoint state (Associator::saveState): restored, it writes the same
// bytes and associates the next scans as the original does; damaged bytes are refused.
// Both confirmation rules (the track score's scores and footprint are state too).
class AssociatorState : public ::testing::TestWithParam<ConfirmRule> {};

TEST_P(AssociatorState, RestoresBitForBitAndDamagedStateIsRefused) {
  WorldConfig world = presetConfig(WorldPreset::Park, 0, 600, 3);
  world.clutter = GetParam() == ConfirmRule::Score ? 5.0 : 1.0;
  world.detection_probability = 0.9;
  const Dataset data = buildDataset(simulate(world));
  const FilterConfig config = paperFilterConfig(data.noise.value_or(world.noise));
  auto f = makeFilter("ekf", startPose(data), config);
  AssociationOptions o;
  o.method = AssociationMethod::Jcbb;
  o.provisional = ProvisionalPlace::Held;
  o.confirm_rule = GetParam();
  Associator a(o);
  const std::size_t half = data.steps.size() / 2;
  for (std::size_t k = 0; k < half; ++k) {
    std::vector<Observation> z = data.steps[k].observations;
    f->predict(data.steps[k].u);
    a.associate(*f, k, z);
    f->update(z);
  }
  const std::string bytes = a.saveState();
  Associator b = Associator::restoreState(bytes, "state");
  EXPECT_TRUE(b.saveState() == bytes);  // (not printed: binary)
  ASSERT_GT(a.counts().new_landmarks, 0u);
  // The rest of the run from the two, each with its own copy of the filter.
  auto g = loadFromBytes(saveToBytes(*f), "filter");
  for (std::size_t k = half; k < data.steps.size(); ++k) {
    std::vector<Observation> z = data.steps[k].observations, w = z;
    f->predict(data.steps[k].u);
    g->predict(data.steps[k].u);
    a.associate(*f, k, z);
    b.associate(*g, k, w);
    ASSERT_EQ(z.size(), w.size()) << k;
    for (std::size_t i = 0; i < z.size(); ++i) ASSERT_EQ(z[i].landmark, w[i].landmark) << k;
    f->update(z);
    g->update(w);
  }
  // The same counts (the time spent associating aside) and the same map.
  const AssociationCounts &ca = a.counts(), &cb = b.counts();
  EXPECT_EQ(ca.observations, cb.observations);
  EXPECT_EQ(ca.new_landmarks, cb.new_landmarks);
  EXPECT_EQ(ca.ambiguous_dropped, cb.ambiguous_dropped);
  EXPECT_EQ(ca.provisional_removed, cb.provisional_removed);
  EXPECT_EQ(ca.merged, cb.merged);
  EXPECT_EQ(f->landmarkIds(), g->landmarkIds());
  EXPECT_TRUE(f->mean() == g->mean());

  // Damaged: cut short, a byte changed (the checksum), a filter's checkpoint instead.
  EXPECT_THROW(Associator::restoreState(bytes.substr(0, bytes.size() - 5), "state"), DataError);
  std::string flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x20;
  EXPECT_THROW(Associator::restoreState(flipped, "state"), DataError);
  try {
    Associator::restoreState(saveToBytes(*f), "filter.ckpt");
    ADD_FAILURE() << "a filter's checkpoint restored as an associator";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("filter.ckpt"), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Association, AssociatorState, ::testing::Values(ConfirmRule::Count, ConfirmRule::Score),
                         [](const ::testing::TestParamInfo<ConfirmRule>& rule) { return std::string(confirmRuleName(rule.param) == "score" ? "Score" : "Count"); });
