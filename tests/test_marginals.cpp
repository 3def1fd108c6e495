// Marginal queries (SlamFilter::marginal, predictMeasurement) on every filter and mode
// against the dense inverse of the information matrix; the information-form motion update
// with a full 3x3 motion Jacobian against the EKF; update() all or nothing.
#include "rel_diff.hpp"
#include "scenario.hpp"

#include <seif/core/errors.hpp>
#include <seif/filters/factory.hpp>
#include <seif/filters/slam_filter.hpp>
#include "filters/information_ops.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace {

using namespace seif;

std::unique_ptr<SlamFilter> runFor(const std::string& spec, const test::Scenario& s, std::size_t steps) {
  auto f = makeFilter(spec, s.start, test::configFor(s));
  for (std::size_t k = 0; k < steps; ++k) f->step(s.steps[k].u, s.steps[k].observations);
  f->finish();
  return f;
}

/// Rows of the dense state for the pose and the landmarks `ids` (the filter's slot order).
std::vector<Eigen::Index> rowsOf(const SlamFilter& f, const std::vector<int>& ids) {
  std::vector<Eigen::Index> rows = {0, 1, 2};
  const std::vector<int>& all = f.landmarkIds();
  for (int id : ids) {
    const auto slot = std::find(all.begin(), all.end(), id) - all.begin();
    rows.push_back(3 + 2 * slot);
    rows.push_back(4 + 2 * slot);
  }
  return rows;
}

/// Variables (block indices: 0 the robot, 1 + slot a landmark) linked to block v in H.
std::vector<Eigen::Index> blanketRows(const Eigen::MatrixXd& H, const std::vector<Eigen::Index>& rows) {
  const auto blockOf = [](Eigen::Index r) { return r < 3 ? Eigen::Index(0) : 1 + (r - 3) / 2; };
  const auto rowsOfBlock = [](Eigen::Index b) {
    return b == 0 ? std::vector<Eigen::Index>{0, 1, 2} : std::vector<Eigen::Index>{3 + 2 * (b - 1), 4 + 2 * (b - 1)};
  };
  const Eigen::Index blocks = 1 + (H.rows() - 3) / 2;
  std::vector<bool> in(static_cast<std::size_t>(blocks), false);
  for (Eigen::Index r : rows) in[static_cast<std::size_t>(blockOf(r))] = true;
  std::vector<bool> blanket = in;
  for (Eigen::Index a = 0; a < blocks; ++a) {
    if (!in[static_cast<std::size_t>(a)]) continue;
    for (Eigen::Index c = 0; c < blocks; ++c) {
      for (Eigen::Index i : rowsOfBlock(a)) {
        for (Eigen::Index j : rowsOfBlock(c)) {
          if (H(i, j) != 0.0) blanket[static_cast<std::size_t>(c)] = true;
        }
      }
    }
  }
  std::vector<Eigen::Index> out = rows;  // the queried rows first, then the rest of the blanket
  for (Eigen::Index b = 0; b < blocks; ++b) {
    if (!blanket[static_cast<std::size_t>(b)] || in[static_cast<std::size_t>(b)]) continue;
    for (Eigen::Index r : rowsOfBlock(b)) out.push_back(r);
  }
  return out;
}

/// The bounded blanket, computed densely: from the queried blocks, repeatedly the block with
/// the strongest normalised link ||D_a^-1/2 H_ac D_c^-1/2||_F to the blanket so far, until
/// `budget` blocks have joined (SeifOptions::blanket). Rows: the queried first.
std::vector<Eigen::Index> greedyBlanketRows(const Eigen::MatrixXd& H, const std::vector<Eigen::Index>& rows,
                                            std::size_t budget) {
  const auto start = [](Eigen::Index b) { return b == 0 ? Eigen::Index(0) : 3 + 2 * (b - 1); };
  const auto size = [](Eigen::Index b) { return b == 0 ? Eigen::Index(3) : Eigen::Index(2); };
  const Eigen::Index blocks = 1 + (H.rows() - 3) / 2;
  const Eigen::VectorXd d = H.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd normalised = d.asDiagonal() * H * d.asDiagonal();
  std::vector<bool> in(static_cast<std::size_t>(blocks), false);
  for (Eigen::Index r : rows) in[static_cast<std::size_t>(r < 3 ? 0 : 1 + (r - 3) / 2)] = true;
  std::vector<Eigen::Index> out = rows;
  for (std::size_t joined = 0; joined < budget; ++joined) {
    double best = 0.0;
    Eigen::Index pick = -1;
    for (Eigen::Index a = 0; a < blocks; ++a) {
      if (!in[static_cast<std::size_t>(a)]) continue;
      for (Eigen::Index c = 0; c < blocks; ++c) {
        if (in[static_cast<std::size_t>(c)]) continue;
        const double strength = normalised.block(start(a), start(c), size(a), size(c)).squaredNorm();
        if (strength > best) {
          best = strength;
          pick = c;
        }
      }
    }
    if (pick < 0) break;  // nothing else is linked
    in[static_cast<std::size_t>(pick)] = true;
    for (Eigen::Index i = 0; i < size(pick); ++i) out.push_back(start(pick) + i);
  }
  return out;
}

Eigen::MatrixXd restrictedInverse(const Eigen::MatrixXd& H, const std::vector<Eigen::Index>& blanket, std::size_t n) {
  const Eigen::MatrixXd restricted = H(blanket, blanket);
  return restricted.llt()
      .solve(Eigen::MatrixXd::Identity(restricted.rows(), restricted.cols()))
      .topLeftCorner(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
}

using test::relDiff;

class MarginalsOfEveryFilter : public ::testing::TestWithParam<std::string> {};

TEST_P(MarginalsOfEveryFilter, ExactAndLocalAgreeWithTheDenseInverse) {
  const test::Scenario s = test::makeScenario(7, 25, 120);
  const auto f = runFor(GetParam(), s, 120);
  ASSERT_GE(f->landmarkIds().size(), 4u);
  const std::vector<int> ids = {f->landmarkIds()[0], f->landmarkIds()[3], f->landmarkIds().back()};
  const std::vector<Eigen::Index> rows = rowsOf(*f, ids);
  const Eigen::MatrixXd Sigma = f->covariance();
  const Eigen::VectorXd mu = f->mean();

  const Marginal exact = f->marginal(ids, true, MarginalMode::Exact);
  EXPECT_EQ(exact.mean, mu(rows)) << GetParam();
  EXPECT_LT(relDiff(exact.covariance, Sigma(rows, rows)), 1e-8) << GetParam();

  const Marginal without_pose = f->marginal(ids, false, MarginalMode::Exact);
  const std::vector<Eigen::Index> landmark_rows(rows.begin() + 3, rows.end());
  EXPECT_LT(relDiff(without_pose.covariance, Sigma(landmark_rows, landmark_rows)), 1e-8) << GetParam();

  const Marginal local = f->marginal(ids, true, MarginalMode::Local);
  EXPECT_EQ(local.mean, exact.mean);
  const std::string name = GetParam().substr(0, GetParam().find(':'));
  if (name == "ekf" || name == "batch") {  // these hold the marginal itself in every mode
    EXPECT_LT(relDiff(local.covariance, exact.covariance), 1e-12) << GetParam();
  } else {
    // The inverse of H restricted to the queried variables and a blanket around them: the
    // Markov blanket for the EIF and `seif:blanket=0`, else the SEIF's bounded blanket.
    const Eigen::MatrixXd H = f->information();
    const std::size_t budget = name == "eif" ? 0 : static_cast<std::size_t>(parseFilterSpec(GetParam()).seif.blanket);
    const std::vector<Eigen::Index> blanket = budget == 0 ? blanketRows(H, rows) : greedyBlanketRows(H, rows, budget);
    EXPECT_LT(relDiff(local.covariance, restrictedInverse(H, blanket, rows.size())), 1e-9) << GetParam();
    // Conditioning on the rest never adds uncertainty: exact - local is positive semidefinite.
    const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(exact.covariance - local.covariance).eigenvalues();
    EXPECT_GE(ev.minCoeff(), -1e-9 * exact.covariance.norm()) << GetParam();
  }
  EXPECT_THROW(f->marginal(std::vector<int>{12345}, true, MarginalMode::Exact), UnknownLandmark);
}

TEST(BoundedBlanket, IsTheGreedyBlanketOnAMapLargerThanTheBudget) {
  // The blanket is grown with a heap, each member offering only the links the budget still
  // has room for, and none weaker than what the frontier already guarantees. The result must
  // be the plain greedy blanket's (computed densely above) for every query.
  const test::Scenario s = test::makeScenario(11, 60, 200);
  std::mt19937_64 rng(3);
  for (int budget : {2, 5, 12, 24}) {
    const auto f = runFor("seif:blanket=" + std::to_string(budget), s, 200);
    const Eigen::MatrixXd H = f->information();
    const std::vector<int>& all = f->landmarkIds();
    ASSERT_GT(all.size(), static_cast<std::size_t>(budget) + 10);
    std::uniform_int_distribution<std::size_t> pick(0, all.size() - 1);
    for (int query = 0; query < 12; ++query) {
      std::vector<int> ids;
      for (int k = 0; k < 1 + query % 4; ++k) {
        const int id = all[pick(rng)];
        if (std::find(ids.begin(), ids.end(), id) == ids.end()) ids.push_back(id);
      }
      const bool pose = query % 3 != 0;
      std::vector<Eigen::Index> rows = rowsOf(*f, ids);
      if (!pose) rows.erase(rows.begin(), rows.begin() + 3);
      const Marginal local = f->marginal(ids, pose, MarginalMode::Local);
      const Eigen::MatrixXd expected = restrictedInverse(H, greedyBlanketRows(H, rows, static_cast<std::size_t>(budget)), rows.size());
      EXPECT_LT(relDiff(local.covariance, expected), 1e-9) << "budget " << budget << ", query " << query;
    }
  }
}

TEST(BoundedBlanket, IsTheGreedyBlanketWhereEachMemberHasMoreLinksThanTheBudget) {
  // A synthetic information matrix whose every variable has more links than the budget, so
  // that each queried member alone fills the budget and sets a floor for those after it (the
  // pruning the filters' small maps seldom reach). The blanket must still be the greedy one.
  const int landmarks = 90, links_each = 40;
  std::mt19937_64 rng(17);
  const Eigen::Index n = 3 + 2 * landmarks;
  const auto start = [](int v) { return v < 0 ? Eigen::Index(0) : Eigen::Index(3 + 2 * v); };
  const auto dim = [](int v) { return v < 0 ? Eigen::Index(3) : Eigen::Index(2); };
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  std::uniform_int_distribution<int> other(0, landmarks - 1);
  std::uniform_real_distribution<double> u(-1.0, 1.0), scale(-3.0, 1.0);
  const auto link = [&](int a, int c) {
    const Eigen::MatrixXd B = std::pow(10.0, scale(rng)) * Eigen::MatrixXd::NullaryExpr(dim(a), dim(c), [&] { return u(rng); });
    H.block(start(a), start(c), dim(a), dim(c)) = B;
    H.block(start(c), start(a), dim(c), dim(a)) = B.transpose();
  };
  for (int a = 0; a < landmarks; ++a) {
    for (int k = 0; k < links_each / 2; ++k) {
      const int c = other(rng);
      if (c != a) link(a, c);
    }
  }
  for (int k = 0; k < 30; ++k) link(-1, other(rng));
  for (Eigen::Index i = 0; i < n; ++i) H(i, i) = H.row(i).cwiseAbs().sum() + 0.1;  // diagonally dominant
  const auto neighbours = [&](int v, std::vector<BlanketLink>& out) {
    const Eigen::VectorXd dv = H.diagonal().segment(start(v), dim(v));
    for (int c = -1; c < landmarks; ++c) {
      if (c == v) continue;
      const auto B = H.block(start(v), start(c), dim(v), dim(c));
      if (B.cwiseAbs().maxCoeff() == 0.0) continue;
      out.push_back({c, linkStrength(dv, B, H.diagonal().segment(start(c), dim(c))), &H(start(v), start(c)), n});
    }
  };
  const auto diagonal = [&](int v) -> Eigen::MatrixXd { return H.block(start(v), start(v), dim(v), dim(v)); };
  std::size_t members_over_budget = 0;
  for (int budget : {4, 8, 16, 32}) {
    for (int query = 0; query < 16; ++query) {
      std::vector<int> vars;
      if (query % 2 == 0) vars.push_back(-1);
      while (vars.size() < static_cast<std::size_t>(1 + query % 8)) {
        const int v = other(rng);
        if (std::find(vars.begin(), vars.end(), v) == vars.end()) vars.push_back(v);
      }
      std::vector<Eigen::Index> rows;
      for (int v : vars) {
        for (Eigen::Index i = 0; i < dim(v); ++i) rows.push_back(start(v) + i);
        std::vector<BlanketLink> l;
        neighbours(v, l);
        members_over_budget += l.size() > static_cast<std::size_t>(budget) + vars.size();
      }
      const Eigen::MatrixXd local =
          localMarginalCovariance(vars, neighbours, diagonal, "test", static_cast<std::size_t>(budget), nullptr);
      const Eigen::MatrixXd expected = restrictedInverse(H, greedyBlanketRows(H, rows, static_cast<std::size_t>(budget)), rows.size());
      EXPECT_LT(relDiff(local, expected), 1e-9) << "budget " << budget << ", query " << query;
    }
  }
  EXPECT_GT(members_over_budget, 100u);  // the case this test is for did occur
}

TEST(BoundedBlanket, GrowsTowardsTheMarginalInTheLoewnerOrder) {
  // The blankets of growing bounds are nested, so each local marginal conditions on less than
  // the one before: P(1) <= P(2) <= ... <= exact, and a bound beyond the map is the marginal.
  const test::Scenario s = test::makeScenario(7, 25, 120);
  Eigen::MatrixXd previous;
  for (int budget : {1, 2, 4, 8, 16, 64}) {
    const auto f = runFor("seif:blanket=" + std::to_string(budget), s, 120);
    const std::vector<int> ids = {f->landmarkIds()[0], f->landmarkIds().back()};
    const Eigen::MatrixXd exact = f->marginal(ids, true, MarginalMode::Exact).covariance;
    const Eigen::MatrixXd local = f->marginal(ids, true, MarginalMode::Local).covariance;
    const auto minEigen = [](const Eigen::MatrixXd& M) {
      return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M).eigenvalues().minCoeff();
    };
    EXPECT_GE(minEigen(exact - local), -1e-9 * exact.norm()) << budget;
    if (previous.size() > 0) {
      EXPECT_GE(minEigen(local - previous), -1e-9 * exact.norm()) << budget;
    }
    if (budget == 1) {
      EXPECT_GT(relDiff(local, exact), 1e-3);  // a small blanket is visibly overconfident
    }
    if (budget == 64) {
      EXPECT_LT(relDiff(local, exact), 1e-9);
    }
    previous = local;
  }
}

TEST_P(MarginalsOfEveryFilter, PredictedMeasurementIsTheLinearisedJointMarginal) {
  const test::Scenario s = test::makeScenario(11, 25, 80);
  const auto f = runFor(GetParam(), s, 80);
  const int id = f->landmarkIds()[1];
  const Mat2 R = f->sensorModel().noise();
  const std::vector<Eigen::Index> rows = rowsOf(*f, {id});
  const Eigen::VectorXd mu = f->mean();
  const Eigen::MatrixXd P = f->covariance()(rows, rows);
  Mat23 J_x;
  Mat2 J_y;
  const Vec2 z = f->sensorModel().predict(mu.head<3>(), mu(rows).tail<2>(), &J_x, &J_y);
  Eigen::Matrix<double, 2, 5> J;
  J << J_x, J_y;
  const Mat2 S = J * P * J.transpose() + R;
  for (MarginalMode mode : {MarginalMode::Exact, MarginalMode::Local}) {
    const PredictedMeasurement p = f->predictMeasurement(id, f->sensorModel(), R, mode);
    EXPECT_LT((p.z - z).norm(), 1e-12 * (1 + z.norm())) << GetParam();
    EXPECT_EQ(p.S, p.S.transpose());
    EXPECT_GT(p.S.determinant(), 0.0);
    if (mode == MarginalMode::Exact) {
      EXPECT_LT(relDiff(p.S, S), 1e-8) << GetParam();
    } else {  // Local: S from an overconfident marginal, but never below the sensor noise
      EXPECT_GE((p.S - R).eigenvalues().real().minCoeff(), -1e-12) << GetParam();
    }
  }
  EXPECT_THROW(f->predictMeasurement(-7, f->sensorModel(), R), UnknownLandmark);
}

INSTANTIATE_TEST_SUITE_P(Filters, MarginalsOfEveryFilter,
                         ::testing::Values("ekf", "eif", "seif", "seif:mean=exact", "seif:sparsify=eseif,beta=4",
                                           "seif:covariance=local", "seif:blanket=0", "seif:blanket=3", "batch"),
                         [](const auto& param_info) {
                           std::string n = param_info.param;
                           for (char& c : n) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return n;
                         });

TEST(GeneralMotionJacobian, InformationFiltersAgreeWithTheEkfForAFullJacobian) {
  // A made-up linearised motion with every entry of dDelta/dx non-zero: nothing in the
  // information form may assume the planar models' heading-only Jacobian.
  const test::Scenario s = test::makeScenario(3, 12, 60);
  auto ekf = makeFilter("ekf", s.start, test::configFor(s));
  auto eif = makeFilter("eif", s.start, test::configFor(s));
  auto seif = makeFilter("seif:mean=exact,active=30", s.start, test::configFor(s));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  for (std::size_t k = 0; k < s.steps.size(); ++k) {
    MotionIncrement m;
    m.delta = Vec3(0.3 + u(rng), u(rng), u(rng));
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) m.J_delta_x(i, j) = u(rng);
    }
    Mat3 A = Mat3::Random() * 0.05;
    m.U = A * A.transpose() + 1e-4 * Mat3::Identity();
    for (SlamFilter* f : {ekf.get(), eif.get(), seif.get()}) {
      f->predict(m);
      f->update(s.steps[k].observations);
    }
  }
  const Eigen::MatrixXd P = ekf->covariance();
  EXPECT_LT((eif->mean() - ekf->mean()).norm(), 1e-8 * ekf->mean().norm());
  EXPECT_LT(relDiff(eif->covariance(), P), 1e-7);
  EXPECT_LT((seif->mean() - ekf->mean()).norm(), 1e-8 * ekf->mean().norm());
  EXPECT_LT(relDiff(seif->covariance(), P), 1e-7);
}

TEST(GeneralMotionJacobian, ASingularJacobianIsANumericError) {
  const test::Scenario s = test::makeScenario(3, 5, 5);
  auto eif = makeFilter("eif", s.start, test::configFor(s));
  MotionIncrement m;
  m.J_delta_x = -Mat3::Identity();  // G = I + J = 0
  m.U = 1e-4 * Mat3::Identity();
  EXPECT_THROW(eif->predict(m), NumericError);
}

class UpdateIsAllOrNothing : public ::testing::TestWithParam<std::string> {};

TEST_P(UpdateIsAllOrNothing, ABadObservationLeavesTheFilterAsItWas) {
  const test::Scenario s = test::makeScenario(2, 20, 40);
  auto f = runFor(GetParam(), s, 40);
  const Eigen::VectorXd mu = f->mean();
  const Eigen::MatrixXd H = f->information();
  const std::vector<int> ids = f->landmarkIds();
  const std::size_t rejected = f->rejectedObservations();
  const Observation known{ids[0], Vec2(1.0, 0.1), std::nullopt};
  const Observation fresh{999, Vec2(1.0, 0.2), std::nullopt};
  const std::vector<std::vector<Observation>> bad = {
      {known, fresh, Observation{-1, Vec2(1.0, 0.0), std::nullopt}},                  // no id
      {fresh, known, Observation{ids[1], Vec2(std::nan(""), 0.0), std::nullopt}},     // NaN
      {known, Observation{ids[1], Vec2(1.0, 0.0), Mat2::Constant(std::numeric_limits<double>::infinity())}},
  };
  for (const auto& z : bad) {
    EXPECT_THROW(f->update(z), ModelError) << GetParam();
    EXPECT_EQ(f->mean(), mu) << GetParam();
    EXPECT_EQ(f->information(), H) << GetParam();
    EXPECT_EQ(f->landmarkIds(), ids) << GetParam();
    EXPECT_EQ(f->rejectedObservations(), rejected) << GetParam();
  }
  f->update(std::vector<Observation>{known, fresh});  // and it goes on
  EXPECT_TRUE(f->hasLandmark(999));
}

INSTANTIATE_TEST_SUITE_P(Filters, UpdateIsAllOrNothing,
                         ::testing::Values("ekf", "eif", "seif", "seif:sparsify=eseif,beta=4"),
                         [](const auto& param_info) {
                           std::string n = param_info.param;
                           for (char& c : n) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return n;
                         });

}  // namespace

TEST(FilterSpecs, SeedsAreUnsigned64BitIntegers) {
  EXPECT_EQ(parseFilterSpec("seif:seed=18446744073709551615").seif.seed, 18446744073709551615ull);
  EXPECT_THROW(parseFilterSpec("seif:seed=-1"), InvalidArgument);
  EXPECT_THROW(parseFilterSpec("seif:seed=18446744073709551616"), InvalidArgument);
  EXPECT_EQ(SeifOptions{}.beta, 4);  // the CLI's --beta default too
}
