// The SEIF: exact where the paper is exact, the sparsification's guarantees, invariants
// after every step, and convergence of the amortised mean.
#include "rel_diff.hpp"
#include "scenario.hpp"
#include "seif_steps.hpp"

#include <seif/core/errors.hpp>
#include "filters/eif_slam.hpp"
#include "filters/ekf_slam.hpp"
#include "filters/information_ops.hpp"
#include "filters/seif_slam.hpp"
#include <seif/filters/factory.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <cmath>
#include <iostream>
#include <map>
#include <random>
#include <set>

namespace {

using namespace seif;

using test::relDiff;

using test::configFor;

double landmarkRmse(const SlamFilter& f, const test::Scenario& s) {
  double sum = 0;
  for (int id : f.landmarkIds()) {
    sum += (f.landmark(id) - s.landmarks[static_cast<std::size_t>(id - 100)]).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(f.landmarkIds().size()));
}

/// The free directions of a block [x, Y+, Y0] at random positions: translations and the rotation.
Eigen::MatrixXd randomGauge(int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> pos(-10.0, 10.0);
  Eigen::MatrixXd V = Eigen::MatrixXd::Zero(n, 3);
  for (int i = 0; i < n; i += (i == 0 ? 3 : 2)) {
    const double px = pos(rng), py = pos(rng);
    V.block(i, 0, 2, 2).setIdentity();
    V(i, 2) = -py;
    V(i + 1, 2) = px;
  }
  V(2, 2) = 1.0;
  return V;
}

}  // namespace

TEST(Seif, WithoutSparsificationAndExactMeanItIsTheEif) {
  for (std::uint64_t seed : {1u, 4u}) {
    const test::Scenario s = test::makeScenario(seed, 25, 200);
    SeifOptions o;
    o.active = kMaxLocalLandmarks - 1;  // larger than the map: never sparsifies
    o.mean = SeifOptions::Mean::Exact;
    SeifSlam seif(s.start, configFor(s), o);
    EifSlam eif(s.start, configFor(s));
    double worst_mean = 0, worst_info = 0, worst_b = 0;
    for (const Step& step : s.steps) {
      seif.step(step.u, step.observations);
      eif.step(step.u, step.observations);
      ASSERT_EQ(seif.landmarkIds(), eif.landmarkIds());
      worst_mean = std::max(worst_mean, relDiff(seif.mean(), eif.mean()));
      worst_info = std::max(worst_info, relDiff(seif.information(), eif.information()));
      worst_b = std::max(worst_b, relDiff(seif.informationVector(), eif.informationVector()));
    }
    EXPECT_GT(seif.landmarkIds().size(), 20u);
    EXPECT_LT(worst_mean, 1e-9) << "seed " << seed;
    EXPECT_LT(worst_info, 1e-9) << "seed " << seed;
    EXPECT_LT(worst_b, 1e-9) << "seed " << seed;
  }
}

// The blanket query ranks links by strength, so the packed 2x2 form must order them exactly
// as the general one: equal to the bit on random blocks and diagonals of any scale.
TEST(LinkStrength, ThePackedFormEqualsTheGeneralOneToTheBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), e(-12.0, 12.0);
  int differing_from_reciprocals = 0;
  for (int k = 0; k < 20000; ++k) {
    Mat2 H;
    H << u(rng), u(rng), u(rng), u(rng);
    H *= std::pow(10.0, e(rng));
    const Vec2 da(std::pow(10.0, e(rng)), std::pow(10.0, e(rng)));
    const Vec2 dc(std::pow(10.0, e(rng)), std::pow(10.0, e(rng)));
    const double general = linkStrength(da, H, dc);
    const double packed = linkStrength2(da, H.data(), dc);
    ASSERT_EQ(std::memcmp(&general, &packed, sizeof(double)), 0) << "block " << k << ": " << general << " vs " << packed;
    // A reformulation that is not the same arithmetic does differ: the check can tell.
    const double reciprocal = H.cwiseAbs2().cwiseProduct(da.cwiseInverse() * dc.cwiseInverse().transpose()).sum();
    if (reciprocal != general) ++differing_from_reciprocals;
  }
  EXPECT_GT(differing_from_reciprocals, 0);
}

TEST(Sparsification, ZeroesTheRobotLinksAndKeepsTheMeanOnRandomBlocks) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 200; ++trial) {
    const int keep = 1 + trial % 6, drop = 1 + trial % 3;
    const int n = 3 + 2 * (keep + drop);
    Eigen::MatrixXd A(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) A(i, j) = n01(rng);
    Eigen::MatrixXd H = A * A.transpose() + n * Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd b(n);
    for (int i = 0; i < n; ++i) b(i) = n01(rng);
    const Eigen::VectorXd mu = H.llt().solve(b);
    Eigen::MatrixXd Hs = H;
    Eigen::VectorXd bs = b;
    const double residual = sparsifyInformation(Hs, bs, mu, drop);
    EXPECT_LT(residual, 1e-12);
    EXPECT_LT(Hs.block(0, n - 2 * drop, 3, 2 * drop).cwiseAbs().maxCoeff(), 1e-12 * H.cwiseAbs().maxCoeff());
    Eigen::LLT<Eigen::MatrixXd> llt(Hs);
    ASSERT_EQ(llt.info(), Eigen::Success) << "sparsified H is not positive definite";
    EXPECT_LT(relDiff(llt.solve(bs), mu), 1e-9);
    EXPECT_LT((Hs - Hs.transpose()).cwiseAbs().maxCoeff(), 1e-12 * H.cwiseAbs().maxCoeff());
  }
}

TEST(Sparsification, TheClosedFormIsThePapersThreeTerms) {
  // sparsifyInformation() computes eq. (44-51) as two rank-3 updates; here the three terms
  // are formed as the paper writes them, with dense inverses.
  std::mt19937_64 rng(4);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 200; ++trial) {
    const int keep = 1 + trial % 30, drop = 1 + trial % 3;
    const int n = 3 + 2 * (keep + drop), d = 2 * drop, y0 = n - d;
    Eigen::MatrixXd A(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) A(i, j) = n01(rng);
    Eigen::MatrixXd H = A * A.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
    H = (0.5 * (H + H.transpose())).eval();  // exactly symmetric
    Eigen::VectorXd mu(n);
    for (int i = 0; i < n; ++i) mu(i) = n01(rng);
    const Eigen::VectorXd b = H * mu + Eigen::VectorXd::Ones(n);  // any b: bs - b = (Hs - H) mu
    std::vector<Eigen::Index> xy0{0, 1, 2};
    for (Eigen::Index i = y0; i < n; ++i) xy0.push_back(i);
    const Eigen::MatrixXd H_cols = H(Eigen::all, xy0);
    const Eigen::MatrixXd T2 = H_cols * H(xy0, xy0).inverse() * H_cols.transpose();
    const Eigen::MatrixXd T1 = H.rightCols(d) * H.bottomRightCorner(d, d).inverse() * H.bottomRows(d);
    const Eigen::MatrixXd T3 = H.leftCols(3) * H.topLeftCorner(3, 3).inverse() * H.topRows(3);
    const Eigen::MatrixXd expected = H - T1 + T2 - T3;
    Eigen::MatrixXd Hs = H;
    Eigen::VectorXd bs = b;
    sparsifyInformation(Hs, bs, mu, drop);
    const double scale = H.cwiseAbs().maxCoeff();
    EXPECT_LT((Hs - expected).cwiseAbs().maxCoeff(), 1e-10 * scale) << "trial " << trial;
    EXPECT_LT((bs - b - (expected - H) * mu).cwiseAbs().maxCoeff(), 1e-10 * scale * mu.cwiseAbs().maxCoeff())
        << "trial " << trial;
    EXPECT_EQ(Hs, Hs.transpose()) << "trial " << trial;
  }
}

TEST(Sparsification, WithTheGaugeKeptItClaimsNothingOnTheFreeDirections) {
  // Random blocks whose free directions V (translations and rotation of robot and map
  // together) carry no information (H V = 0) or only a prior's. The paper's rule claims
  // information on them; with the gauge kept, V^T (Hs - H) V <= 0, so Hs V = 0 when H V = 0,
  // and still: the robot-Y0 links zero, the mean kept, Hs positive (semi)definite.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01;
  double paper_claims = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const int keep = 2 + trial % 5, drop = 1 + trial % 3;
    const bool free = trial % 2 == 0;
    const int n = 3 + 2 * (keep + drop);
    const Eigen::MatrixXd V = randomGauge(n, rng);
    const Eigen::MatrixXd P = Eigen::MatrixXd::Identity(n, n) - V * (V.transpose() * V).ldlt().solve(V.transpose());
    Eigen::MatrixXd A(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) A(i, j) = n01(rng);
    Eigen::MatrixXd H = P * (A * A.transpose() + n * Eigen::MatrixXd::Identity(n, n)) * P;
    if (!free) H += 1e-2 * Eigen::MatrixXd::Identity(n, n);  // a prior on everything
    H = (0.5 * (H + H.transpose())).eval();
    Eigen::VectorXd mu(n);
    for (int i = 0; i < n; ++i) mu(i) = n01(rng);
    const Eigen::VectorXd b = H * mu;
    const double scale = H.cwiseAbs().maxCoeff();
    Eigen::MatrixXd Hp = H, Hs = H;
    Eigen::VectorXd bp = b, bs = b;
    sparsifyInformation(Hp, bp, mu, drop);
    sparsifyInformation(Hs, bs, mu, drop, V);
    paper_claims = std::max(paper_claims, (V.transpose() * (Hp - H) * V).eigenvalues().real().maxCoeff() / scale);
    const Eigen::MatrixXd claim = V.transpose() * (Hs - H) * V;
    EXPECT_LT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (claim + claim.transpose())).eigenvalues().maxCoeff(),
              1e-9 * scale) << "trial " << trial;
    if (free) {
      EXPECT_LT((Hs * V).cwiseAbs().maxCoeff(), 1e-9 * scale) << "trial " << trial;
    }
    EXPECT_LT(Hs.block(0, n - 2 * drop, 3, 2 * drop).cwiseAbs().maxCoeff(), 1e-12 * scale);
    EXPECT_LT((bs - Hs * mu - (b - H * mu)).cwiseAbs().maxCoeff(), 1e-9 * scale * mu.cwiseAbs().maxCoeff());
    EXPECT_LT((Hs - Hs.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale);
    const Eigen::VectorXd eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Hs).eigenvalues();
    EXPECT_GT(eig.minCoeff(), free ? -1e-9 * scale : 0.0) << "trial " << trial;
    // Only the robot's links to Y+ and the Y+ block change beyond the paper's rule.
    EXPECT_LT((Hs - Hp).bottomRows(2 * drop).cwiseAbs().maxCoeff(), 1e-12 * scale);
    EXPECT_LT((Hs - Hp).topLeftCorner(3, 3).cwiseAbs().maxCoeff(), 1e-12 * scale);
  }
  std::printf("largest information the paper's rule claimed on the free directions: %.3g of the block's scale\n",
              paper_claims);
  EXPECT_GT(paper_claims, 1e-4);
}

TEST(Sparsification, WithOneLandmarkKeptTheTranslationsAreKept) {
  // One landmark in Y+ cannot carry a rotation: the rule keeps what it can, the translations.
  std::mt19937_64 rng(6);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 50; ++trial) {
    const int drop = 1 + trial % 3, n = 3 + 2 * (1 + drop);
    const Eigen::MatrixXd V = randomGauge(n, rng);
    const Eigen::MatrixXd T = V.leftCols(2);
    const Eigen::MatrixXd P = Eigen::MatrixXd::Identity(n, n) - T * (T.transpose() * T).ldlt().solve(T.transpose());
    Eigen::MatrixXd A(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) A(i, j) = n01(rng);
    Eigen::MatrixXd H = P * (A * A.transpose() + n * Eigen::MatrixXd::Identity(n, n)) * P;
    H = (0.5 * (H + H.transpose())).eval();
    const Eigen::VectorXd mu = Eigen::VectorXd::Ones(n);
    Eigen::VectorXd b = H * mu;
    sparsifyInformation(H, b, mu, drop, V);
    EXPECT_LT((H * T).cwiseAbs().maxCoeff(), 1e-9 * H.cwiseAbs().maxCoeff()) << "trial " << trial;
  }
}

TEST(Seif, InvariantsHoldAfterEveryStepOfALongRun) {
  const test::Scenario s = test::makeScenario(8, 60, 600);
  for (auto rule : {SeifOptions::Deactivate::Weakest, SeifOptions::Deactivate::Oldest}) {
    SeifOptions o;
    o.deactivate = rule;
    SeifSlam seif(s.start, configFor(s), o);
    int k = 0;
    for (const Step& step : s.steps) {
      seif.step(step.u, step.observations);
      const FilterStats st = seif.stats();
      ASSERT_LE(st.robot_links, static_cast<std::size_t>(o.active)) << "step " << k;
      ASSERT_LT(seif.lastSparsificationResidual(), 1e-9) << "step " << k;
      const Eigen::MatrixXd H = seif.information();
      ASSERT_LE((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-12 * H.cwiseAbs().maxCoeff()) << "step " << k;
      Eigen::LLT<Eigen::MatrixXd> llt(H);
      ASSERT_EQ(llt.info(), Eigen::Success) << "H not positive definite at step " << k;
      ++k;
    }
    EXPECT_GT(seif.landmarkIds().size(), 50u);
  }
}


TEST(Seif, SparsificationInsideTheFilterKeepsTheMeanAndZeroesTheLinks) {
  // The four steps run one by one: measurement update, exact mean, then sparsification,
  // whose result must have the same H^-1 b and no robot link beyond theta_x.
  const test::Scenario s = test::makeScenario(12, 40, 200);
  SeifOptions o;
  o.active = 3;
  SeifSlam seif(s.start, configFor(s), o);
  int sparsified = 0;
  for (const Step& step : s.steps) {
    SeifStepsForTests::motionUpdate(seif, seif.motionModel().linearize(seif.mean().head<3>(), step.u));
    SeifStepsForTests::recoverMean(seif);
    SeifStepsForTests::measurementUpdate(seif, step.observations);
    SeifStepsForTests::recoverExactMean(seif);
    const Eigen::VectorXd before = seif.exactMean();
    const std::size_t active = seif.activeLandmarks().size();
    SeifStepsForTests::sparsify(seif);
    EXPECT_LE(seif.activeLandmarks().size(), 3u);
    EXPECT_LT(relDiff(seif.exactMean(), before), 1e-9);
    EXPECT_LT(seif.lastSparsificationResidual(), 1e-9);
    if (active > 3) {
      ++sparsified;
      // the removed links are exactly zero in H
      const Eigen::MatrixXd H = seif.information();
      std::size_t robot_links = 0;
      for (int l = 0; l < static_cast<int>(seif.landmarkIds().size()); ++l) {
        if (H.block(0, 3 + 2 * l, 3, 2).cwiseAbs().maxCoeff() > 0.0) ++robot_links;
      }
      EXPECT_EQ(robot_links, seif.activeLandmarks().size());
    }
  }
  EXPECT_GT(sparsified, 50);
}

TEST(Seif, AMotionUpdateKeepsASolvedBlockSolved) {
  // After an update that solved the robot-active block before sparsifying it, b - H mu is zero
  // on the block's rows (the passive landmarks' terms included); the motion that follows
  // carries that residual through (informationMotionUpdate), so the next update need not
  // solve the block again. Immediate motion (the paper's SEIF) and deferred (the profile's,
  // applied by a query).
  const test::Scenario s = test::makeScenario(12, 40, 120);
  for (const char* spec : {"seif", "seif:profile=consistent"}) {
    auto f = makeFilter(spec, s.start, configFor(s));
    const auto& seif = dynamic_cast<const SeifSlam&>(*f);
    // The largest |b - H mu| on the robot's and the active landmarks' rows, relative to |b|.
    const auto blockResidual = [&] {
      const SeifStore& store = seif.store();
      const Eigen::VectorXd b = store.informationVector(), r = b - store.sparseInformation() * store.mean();
      double worst = r.head<3>().cwiseAbs().maxCoeff() / b.head<3>().cwiseAbs().maxCoeff();
      for (const SeifStore::RobotLink& l : store.robotLinks()) {
        const auto row = 3 + 2 * static_cast<Eigen::Index>(l.slot);
        worst = std::max(worst, r.segment<2>(row).cwiseAbs().maxCoeff() / b.segment<2>(row).cwiseAbs().maxCoeff());
      }
      return worst;
    };
    int solved = 0;
    for (std::size_t k = 0; k + 1 < s.steps.size(); ++k) {
      f->step(s.steps[k].u, s.steps[k].observations);
      if (seif.store().robotLinks().empty() || blockResidual() > 1e-9) continue;
      ++solved;
      f->predict(s.steps[k + 1].u);
      EXPECT_LT(blockResidual(), 1e-9) << spec << ", after the motion of step " << k + 1;
      f->update(s.steps[k + 1].observations);
      ++k;
    }
    EXPECT_GT(solved, 20) << spec;
  }
}

TEST(Seif, AmortizedMeanConvergesToTheExactMean) {
  const test::Scenario s = test::makeScenario(9, 40, 300);
  SeifSlam seif(s.start, configFor(s));
  for (const Step& step : s.steps) seif.step(step.u, step.observations);
  const Eigen::VectorXd exact = seif.exactMean();
  const double before = relDiff(seif.mean(), exact);
  seif.relaxMean(20000);
  const double after = relDiff(seif.mean(), exact);
  EXPECT_LT(after, 1e-9) << "before relaxation: " << before;
  EXPECT_LT(after, before);
}

// SeifOptions::omega: successive over-relaxation reaches the same mean, H^-1 b, as
// Gauss-Seidel (eq. 42) on the same information, in fewer sweeps.
int sweepsToExactMean(SeifStore store, const Eigen::VectorXd& exact, double omega) {
  for (int sweep = 1; sweep <= 20000; ++sweep) {
    store.relaxRobot();
    for (int slot = 0; slot < store.size(); ++slot) store.relaxLandmark(slot, omega);
    if (relDiff(store.mean(), exact) < 1e-6) return sweep;
  }
  return 20001;
}

TEST(Seif, OverRelaxationReachesTheExactMeanInFewerSweeps) {
  const test::Scenario s = test::makeScenario(9, 40, 300);
  SeifSlam seif(s.start, configFor(s));
  for (const Step& step : s.steps) seif.step(step.u, step.observations);
  const Eigen::VectorXd exact = seif.exactMean();
  const int gauss_seidel = sweepsToExactMean(seif.store(), exact, 1.0);
  const int over = sweepsToExactMean(seif.store(), exact, 1.7);
  std::cout << "sweeps to 1e-6 of H^-1 b: Gauss-Seidel " << gauss_seidel << ", omega = 1.7: " << over << "\n";
  EXPECT_LT(gauss_seidel, 20001);
  EXPECT_LT(3 * over, gauss_seidel);
}

// SlamFilter::posteriorMean: the amortised SEIF's is H^-1 b, computed densely here, and it is
// not the filter's own (lagging) mean; the query changes nothing. Filters whose mean is the
// posterior's answer none.
TEST(Seif, PosteriorMeanSolvesItsInformationAndLeavesTheFilterAsItWas) {
  const test::Scenario s = test::makeScenario(9, 40, 300);
  SeifSlam seif(s.start, configFor(s));
  SeifOptions exact_mean;
  exact_mean.mean = SeifOptions::Mean::Exact;
  SeifSlam exact(s.start, configFor(s), exact_mean);
  EkfSlam ekf(s.start, configFor(s));
  EifSlam eif(s.start, configFor(s));
  for (const Step& step : s.steps) {
    seif.step(step.u, step.observations);
    exact.step(step.u, step.observations);
    ekf.step(step.u, step.observations);
    eif.step(step.u, step.observations);
  }
  const Eigen::VectorXd own = seif.mean();
  const std::optional<Eigen::VectorXd> posterior = seif.posteriorMean();
  ASSERT_TRUE(posterior.has_value());
  const Eigen::VectorXd dense = seif.information().ldlt().solve(seif.informationVector());
  EXPECT_LT(relDiff(*posterior, dense), 1e-9);
  EXPECT_GT(relDiff(*posterior, own), 1e-6);  // the amortised mean lags it
  EXPECT_EQ(seif.mean(), own);                // a query, not a step
  EXPECT_FALSE(exact.posteriorMean().has_value());
  EXPECT_FALSE(ekf.posteriorMean().has_value());
  EXPECT_FALSE(eif.posteriorMean().has_value());
}

TEST(Seif, AccuracyIsCloseToTheEkf) {
  double ekf_sum = 0, seif_sum = 0, exact_sum = 0, after_sum = 0;
  for (std::uint64_t seed = 20; seed < 26; ++seed) {
    const test::Scenario s = test::makeScenario(seed, 40, 400);
    EkfSlam ekf(s.start, configFor(s));
    SeifSlam seif(s.start, configFor(s));
    SeifOptions after;
    after.recovery = SeifOptions::Recovery::AfterMeasurement;
    SeifSlam seif_after(s.start, configFor(s), after);
    SeifOptions exact_options;
    exact_options.mean = SeifOptions::Mean::Exact;
    SeifSlam seif_exact(s.start, configFor(s), exact_options);
    for (const Step& step : s.steps) {
      ekf.step(step.u, step.observations);
      seif.step(step.u, step.observations);
      seif_after.step(step.u, step.observations);
      seif_exact.step(step.u, step.observations);
    }
    ekf_sum += landmarkRmse(ekf, s);
    seif_sum += landmarkRmse(seif, s);
    after_sum += landmarkRmse(seif_after, s);
    exact_sum += landmarkRmse(seif_exact, s);
  }
  EXPECT_LT(exact_sum, 1.5 * ekf_sum) << "ekf " << ekf_sum << " seif(exact mean) " << exact_sum;
  EXPECT_LT(seif_sum, 2.0 * ekf_sum) << "ekf " << ekf_sum << " seif " << seif_sum;
  EXPECT_LT(after_sum, 2.0 * ekf_sum) << "ekf " << ekf_sum << " seif (relax after update) " << after_sum;
}

TEST(Seif, OptionsAreValidated) {
  SeifOptions o;
  o.active = 0;
  EXPECT_THROW(SeifSlam(Pose2::Zero(), paperFilterConfig(NoiseModel{}), o), seif::InvalidArgument);
  o.active = 6;
  o.relax = -1;
  EXPECT_THROW(SeifSlam(Pose2::Zero(), paperFilterConfig(NoiseModel{}), o), seif::InvalidArgument);
  EXPECT_EQ(SeifOptions::parseMean("exact"), SeifOptions::Mean::Exact);
  EXPECT_THROW(SeifOptions::parseDeactivate("random"), seif::InvalidArgument);
  EXPECT_EQ(SeifOptions::parseRecovery("after-update"), SeifOptions::Recovery::AfterMeasurement);
  EXPECT_THROW(SeifOptions::parseRecovery("sometimes"), seif::InvalidArgument);
  EXPECT_EQ(SeifOptions::parseGauge("kept"), SeifOptions::Gauge::Kept);
  EXPECT_THROW(SeifOptions::parseGauge("free"), seif::InvalidArgument);
  o.relax = 10;
  o.gauge = SeifOptions::Gauge::Kept;
  o.sparsify = SeifOptions::Sparsify::Conservative;
  EXPECT_THROW(SeifSlam(Pose2::Zero(), paperFilterConfig(NoiseModel{}), o), seif::InvalidArgument);
}

TEST(InformationMotionUpdate, IsTheLinearisedPredictionForAnyLinearisationPoint) {
  // State s ~ N(H^-1 b, H^-1); motion s' = s + S_x (delta + A (s_x - mu_x)) + S_x w, w ~ N(0, U),
  // linearised at an arbitrary mu (not the mean). The information update must give the
  // moments of s' exactly: Sigma' = G Sigma G^T + S_x U S_x^T, mean' = mean + S_x(delta + A(mean_x - mu_x)).
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 50; ++trial) {
    const int n = 3 + 2 * (1 + trial % 6);
    Eigen::MatrixXd M(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) M(i, j) = n01(rng);
    Eigen::MatrixXd H = M * M.transpose() + Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd b(n), mu(n);
    for (int i = 0; i < n; ++i) {
      b(i) = n01(rng);
      mu(i) = n01(rng);
    }
    Mat3 A = Mat3::Zero();
    A(0, 2) = n01(rng);
    A(1, 2) = n01(rng);
    const Vec3 delta(n01(rng), n01(rng), n01(rng));
    Eigen::Matrix<double, 3, 2> V;
    V << n01(rng), n01(rng), n01(rng), n01(rng), 0, n01(rng);
    const Mat3 U = V * V.transpose();  // rank 2, like the velocity model's noise
    // Expected, in moments.
    const Eigen::MatrixXd Sigma = H.inverse();
    const Eigen::VectorXd mean = Sigma * b;
    Eigen::MatrixXd G = Eigen::MatrixXd::Identity(n, n);
    G.topLeftCorner<3, 3>() += A;
    Eigen::MatrixXd Sigma_next = G * Sigma * G.transpose();
    Sigma_next.topLeftCorner<3, 3>() += U;
    Eigen::VectorXd mean_next = mean;
    mean_next.head<3>() += delta + A * (mean.head<3>() - mu.head<3>());
    // Information form.
    Eigen::MatrixXd Hn = H;
    Eigen::VectorXd bn = b, mun = mu;
    Eigen::MatrixXd workspace(6, n);
    informationMotionUpdate(Hn, bn, mun, delta, A, U, workspace);
    const Eigen::MatrixXd Sigma_info = Hn.inverse();
    EXPECT_LT(relDiff(Sigma_info, Sigma_next), 1e-8);
    EXPECT_LT(relDiff(Sigma_info * bn, mean_next), 1e-8);
    EXPECT_LT((mun.head<3>() - (mu.head<3>() + delta)).norm(), 1e-12);
  }
}

// The marginals come from the selected inverse of the cached factor: after every step they
// equal the blocks of the dense inverse of H, for the pose and every landmark.
TEST(Seif, MarginalCovariancesAreTheBlocksOfTheInverseAfterEveryStep) {
  const test::Scenario s = test::makeScenario(5, 25, 60);
  SeifSlam seif(s.start, configFor(s));
  for (const Step& step : s.steps) {
    seif.step(step.u, step.observations);
    const Eigen::MatrixXd Sigma = seif.covariance();
    const double scale = Sigma.cwiseAbs().maxCoeff();
    ASSERT_LT((seif.poseCovariance() - Sigma.topLeftCorner<3, 3>()).cwiseAbs().maxCoeff(), 1e-9 * scale);
    for (std::size_t k = 0; k < seif.landmarkIds().size(); ++k) {
      const int id = seif.landmarkIds()[k];
      const Eigen::Index i = 3 + 2 * static_cast<Eigen::Index>(k);
      ASSERT_LT((seif.landmarkCovariance(id) - Sigma.block<2, 2>(i, i)).cwiseAbs().maxCoeff(), 1e-9 * scale)
          << "landmark " << id;
    }
  }
}

// K beyond the map's size relaxes every landmark once per step, no more: K = 1e9 is the
// same filter as K = N (it used to relax a 25-landmark map a billion times per step).
TEST(Seif, RelaxationIsCappedAtTheMapSize) {
  const test::Scenario s = test::makeScenario(8, 25, 60);
  SeifOptions all, huge;
  all.relax = 25;
  huge.relax = 1'000'000'000;
  SeifSlam a(s.start, configFor(s), all), b(s.start, configFor(s), huge);
  for (const Step& step : s.steps) {
    a.step(step.u, step.observations);
    b.step(step.u, step.observations);
    ASSERT_EQ(a.blocksTouched(), b.blocksTouched());
  }
  EXPECT_EQ(a.mean(), b.mean());
}

TEST(Seif, LowerInformationIsTheLowerTriangleOfH) {
  const test::Scenario s = test::makeScenario(21, 60, 150);
  SeifSlam seif(s.start, configFor(s));
  for (const Step& step : s.steps) seif.step(step.u, step.observations);
  const Eigen::MatrixXd full = Eigen::MatrixXd(seif.sparseInformation());
  const Eigen::SparseMatrix<double> lower = seif.lowerInformation();
  EXPECT_EQ(Eigen::MatrixXd(lower), Eigen::MatrixXd(full.triangularView<Eigen::Lower>()));
  EXPECT_GT(seif.stats().links, seif.robotLinks());  // landmark-landmark links are in it
}

TEST(Seif, AStepThatFailsNumericallyLeavesTheFilterAsItWas) {
  // predict() and update() are all or nothing for numerical failures too: the store journals
  // what a step changes and rolls it back. A failed step leaves the filter bit-identical to a
  // twin that never saw it, and both go on identically. The failures: a singular motion
  // Jacobian (G = I + J = 0, not invertible in information form) and, in an update, an
  // observation whose noise is negative definite (the input checks refuse it, ModelError).
  for (const char* spec : {"seif", "seif:sparsify=eseif,beta=2", "seif:relax-order=random,linearization=invariant,iterations=2",
                           "seif:mean=exact", "seif:motion=deferred", "seif:profile=consistent,motion=deferred",
                           "seif:coarse=rigid,linearization=invariant,iterations=2"}) {
    const test::Scenario s = test::makeScenario(3, 40, 40);
    const FilterConfig config = configFor(s);
    auto seif = makeFilter(spec, s.start, config), twin = makeFilter(spec, s.start, config);
    const std::size_t half = s.steps.size() / 2;
    for (std::size_t k = 0; k < half; ++k) {
      seif->step(s.steps[k].u, s.steps[k].observations);
      twin->step(s.steps[k].u, s.steps[k].observations);
    }
    MotionIncrement singular;
    singular.J_delta_x = -Mat3::Identity();
    singular.U = 1e-4 * Mat3::Identity();
    EXPECT_THROW(seif->predict(singular), seif::NumericError) << spec;
    std::vector<Observation> bad = s.steps[half].observations;
    ASSERT_FALSE(bad.empty());
    Observation poison = bad.front();
    poison.noise = -1e-8 * Mat2::Identity();
    bad.push_back(poison);
    seif->predict(s.steps[half].u);
    twin->predict(s.steps[half].u);
    EXPECT_THROW(seif->update(bad), seif::ModelError) << spec;  // refused before any change
    EXPECT_EQ(seif->mean(), twin->mean()) << spec;
    const SeifStore& store = dynamic_cast<const SeifSlam&>(*seif).store();
    const SeifStore& twin_store = dynamic_cast<const SeifSlam&>(*twin).store();
    for (int slot = 0; slot < store.size(); ++slot) {  // the coarse level's rows (coarse=rigid)
      EXPECT_EQ(store.node(slot).w, twin_store.node(slot).w) << spec << ", slot " << slot;
    }
    EXPECT_EQ(store.coarseSums(), twin_store.coarseSums()) << spec;
    EXPECT_EQ(seif->information(), twin->information()) << spec;
    EXPECT_EQ(seif->landmarkIds(), twin->landmarkIds()) << spec;
    for (std::size_t k = half; k < s.steps.size(); ++k) {
      if (k > half) {
        seif->predict(s.steps[k].u);
        twin->predict(s.steps[k].u);
      }
      seif->update(s.steps[k].observations);
      twin->update(s.steps[k].observations);
    }
    EXPECT_EQ(seif->mean(), twin->mean()) << spec;
    EXPECT_EQ(seif->information(), twin->information()) << spec;
    EXPECT_EQ(seif->stats().links, twin->stats().links) << spec;
  }
}

namespace {

// Steps at which a landmark observed within the last `threshold` steps left the active set
// while one unobserved for longer stayed in it (the ages of the landmarks linked before the
// step, and of those observed in it, against the links after it).
int staleKeptOverFresh(const test::Scenario& s, long stale, long threshold, int active) {
  SeifOptions o;
  o.active = active;
  o.stale = stale;
  SeifSlam f(s.start, configFor(s), o);
  int steps = 0;
  for (const Step& step : s.steps) {
    std::map<int, long> seen;  // slot -> last observed
    for (const SeifStore::RobotLink& l : f.store().robotLinks()) seen[l.slot] = l.last_seen;
    f.step(step.u, step.observations);
    const long now = f.store().step();
    const std::vector<int>& ids = f.store().ids();
    for (const Observation& z : step.observations) {
      const auto it = std::find(ids.begin(), ids.end(), z.landmark);
      if (it != ids.end()) seen[static_cast<int>(it - ids.begin())] = now;
    }
    std::set<int> kept;
    for (const SeifStore::RobotLink& l : f.store().robotLinks()) kept.insert(l.slot);
    bool fresh_left = false, stale_kept = false;
    for (const auto& [slot, last] : seen) {
      const bool is_stale = now - last > threshold;
      if (kept.count(slot) > 0) stale_kept = stale_kept || is_stale;
      else fresh_left = fresh_left || !is_stale;
    }
    steps += fresh_left && stale_kept ? 1 : 0;
  }
  return steps;
}

}  // namespace

TEST(Sparsification, StaleLandmarksAreDeactivatedFirst) {
  // SeifOptions::stale: the surplus comes first from the landmarks unobserved for longer
  // than `stale` steps. The weakest-link rule alone keeps such landmarks while it lets
  // fresher ones go, on the same data (so the check below can fail).
  constexpr long kStale = 5;
  constexpr int kActive = 8;
  int weakest = 0;
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const test::Scenario s = test::makeScenario(seed, 60, 600);
    weakest += staleKeptOverFresh(s, 0, kStale, kActive);
    EXPECT_EQ(staleKeptOverFresh(s, kStale, kStale, kActive), 0) << "seed " << seed;
  }
  EXPECT_GT(weakest, 10);  // 43 steps measured
  SeifOptions bad;
  bad.stale = -1;
  const test::Scenario s = test::makeScenario(1, 10, 10);
  EXPECT_THROW(SeifSlam(s.start, configFor(s), bad), InvalidArgument);
}

namespace seif {
namespace {

// A motion increment that is not finite, or whose process noise is not positive semidefinite,
// and an observation whose noise is not positive definite are refused by every filter before
// anything changes (a NaN never enters the estimate).
TEST(FilterInputs, BadIncrementsAndNoiseAreRefusedBeforeAnythingChanges) {
  const test::Scenario s = test::makeScenario(5, 30, 20);
  const FilterConfig config = test::configFor(s);
  for (const char* spec : {"ekf", "eif", "seif", "seif:profile=consistent", "batch"}) {
    auto f = makeFilter(spec, s.start, config);
    for (std::size_t k = 0; k < 10; ++k) f->step(s.steps[k].u, s.steps[k].observations);
    const Eigen::VectorXd before = f->mean();
    MotionIncrement nan;
    nan.delta = Vec3(std::nan(""), 0.0, 0.0);
    nan.U = 1e-4 * Mat3::Identity();
    EXPECT_THROW(f->predict(nan), ModelError) << spec;
    MotionIncrement negative;
    negative.delta = Vec3(0.01, 0.0, 0.0);
    negative.U = -1e-4 * Mat3::Identity();
    EXPECT_THROW(f->predict(negative), ModelError) << spec;
    MotionIncrement indefinite = negative;  // positive diagonal, a negative 2x2 minor
    indefinite.U << 1e-4, 2e-4, 0, 2e-4, 1e-4, 0, 0, 0, 1e-4;
    EXPECT_THROW(f->predict(indefinite), ModelError) << spec;
    if (std::string(spec) != "batch") {  // the batch checks its measurements when it solves
      std::vector<Observation> z = s.steps[10].observations;
      ASSERT_FALSE(z.empty());
      z.front().noise = -1e-4 * Mat2::Identity();
      EXPECT_THROW(f->update(z), ModelError) << spec;
    }
    EXPECT_EQ(f->mean(), before) << spec;
    MotionIncrement singular;  // a singular U is a valid one (noise-free directions)
    singular.delta = Vec3(0.01, 0.0, 0.0);
    singular.U = Vec3(1e-4, 1e-4, 0.0).asDiagonal();
    EXPECT_NO_THROW(f->predict(singular)) << spec;
  }
}

}  // namespace
}  // namespace seif
