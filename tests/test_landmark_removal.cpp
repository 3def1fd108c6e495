// Exact removal and merge of landmarks in every filter's form, against the dense
// computation on the same posterior: removal = the marginal over everything else (delete
// the landmark's rows of Sigma); merge = conditioning on y_keep = y_drop, then removal.
#include "rel_diff.hpp"
#include "scenario.hpp"

#include <seif/core/errors.hpp>
#include <seif/filters/factory.hpp>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

namespace {

using namespace seif;

using test::relDiff;

/// The state order after deleting slot `slot` the way the filters do (the last slot moves in).
std::vector<Eigen::Index> keptRows(Eigen::Index n, int slot) {
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < n - 2; ++i) rows.push_back(i);
  const Eigen::Index s = 3 + 2 * slot;
  if (s != n - 2) {
    rows[static_cast<std::size_t>(s)] = n - 2;
    rows[static_cast<std::size_t>(s + 1)] = n - 1;
  }
  return rows;
}

int slotOf(const SlamFilter& f, int id) {
  const auto& ids = f.landmarkIds();
  return static_cast<int>(std::find(ids.begin(), ids.end(), id) - ids.begin());
}

class LandmarkRemoval : public ::testing::TestWithParam<std::string> {};

TEST_P(LandmarkRemoval, RemovingIsMarginalising) {
  const test::Scenario s = test::makeScenario(4, 20, 150);
  auto f = makeFilter(GetParam(), s.start, test::configFor(s));
  for (std::size_t k = 0; k < 100; ++k) f->step(s.steps[k].u, s.steps[k].observations);
  const std::vector<int> ids = f->landmarkIds();
  ASSERT_GE(ids.size(), 6u);
  for (int victim : {ids[2], ids.back(), ids[0]}) {
    const Eigen::MatrixXd Sigma = f->covariance();
    const Eigen::VectorXd mu = f->mean();
    const int slot = slotOf(*f, victim);
    const std::vector<Eigen::Index> rows = keptRows(Sigma.rows(), slot);
    f->removeLandmark(victim);
    EXPECT_FALSE(f->hasLandmark(victim));
    EXPECT_EQ(f->landmarkIds().size() * 2 + 3, rows.size());
    EXPECT_LT(relDiff(f->covariance(), Sigma(rows, rows)), 1e-8) << GetParam() << " removing " << victim;
    const Eigen::VectorXd kept = mu(rows);
    EXPECT_LT((f->mean() - kept).norm(), 1e-8 * mu.norm()) << GetParam();
  }
  EXPECT_THROW(f->removeLandmark(ids[2]), UnknownLandmark);
  // It goes on: a removed landmark seen again enters the map as new.
  for (std::size_t k = 100; k < s.steps.size(); ++k) f->step(s.steps[k].u, s.steps[k].observations);
  EXPECT_TRUE(f->pose().allFinite());
}

TEST_P(LandmarkRemoval, MergingIsConditioningOnEquality) {
  const test::Scenario s = test::makeScenario(6, 20, 100);
  auto f = makeFilter(GetParam(), s.start, test::configFor(s));
  for (std::size_t k = 0; k < 100; ++k) f->step(s.steps[k].u, s.steps[k].observations);
  const std::vector<int> ids = f->landmarkIds();
  const int keep = ids[1], drop = ids[4];
  const Eigen::MatrixXd Sigma = f->covariance();
  const Eigen::VectorXd mu = f->mean();
  const Eigen::Index ik = 3 + 2 * slotOf(*f, keep), id = 3 + 2 * slotOf(*f, drop);
  // Dense conditioning on A x = y_keep - y_drop = 0.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2, Sigma.rows());
  A.block<2, 2>(0, ik).setIdentity();
  A.block<2, 2>(0, id) = -Eigen::Matrix2d::Identity();
  const Eigen::MatrixXd K = Sigma * A.transpose() * (A * Sigma * A.transpose()).inverse();
  const Eigen::MatrixXd Sigma_c = Sigma - K * A * Sigma;
  const Eigen::VectorXd mu_c = mu - K * (A * mu);
  const std::vector<Eigen::Index> rows = keptRows(Sigma.rows(), slotOf(*f, drop));
  f->mergeLandmarks(keep, drop);
  EXPECT_TRUE(f->hasLandmark(keep));
  EXPECT_FALSE(f->hasLandmark(drop));
  EXPECT_LT(relDiff(f->covariance(), Sigma_c(rows, rows)), 1e-7) << GetParam();
  if (GetParam().find("amortized") == std::string::npos) {  // amortised means are not exact
    const Eigen::VectorXd expected = mu_c(rows);
    EXPECT_LT((f->mean() - expected).norm(), 1e-7 * mu.norm()) << GetParam();
  }
  EXPECT_THROW(f->mergeLandmarks(keep, keep), InvalidArgument);
  EXPECT_THROW(f->mergeLandmarks(keep, drop), UnknownLandmark);
}

INSTANTIATE_TEST_SUITE_P(Filters, LandmarkRemoval,
                         ::testing::Values("ekf", "eif", "seif:mean=exact,active=30", "seif:mean=amortized,active=30",
                                           "seif:mean=amortized,active=30,coarse=rigid", "ekf:linearization=fej"),
                         [](const auto& param_info) {
                           std::string n = param_info.param;
                           for (char& c : n) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return n;
                         });

TEST(LandmarkRemoval, SparsifiedSeifRemovesExactlyInItsOwnInformation) {
  // With sparsification the SEIF's H is its own approximation; removal must still be the
  // exact Schur complement of that H (and the store's links stay consistent with it).
  const test::Scenario s = test::makeScenario(8, 30, 150);
  auto f = makeFilter("seif:active=4", s.start, test::configFor(s));
  for (std::size_t k = 0; k < 150; ++k) f->step(s.steps[k].u, s.steps[k].observations);
  const std::vector<int> ids = f->landmarkIds();
  // A passive landmark: its removal links only landmarks, so no sparsification follows.
  int victim = -1;
  for (int id : ids) {
    const Eigen::MatrixXd H = f->information();
    const Eigen::Index l = 3 + 2 * slotOf(*f, id);
    if (H.block(0, l, 3, 2).isZero(0.0)) {
      victim = id;
      break;
    }
  }
  ASSERT_GE(victim, 0);
  const Eigen::MatrixXd H = f->information();
  const Eigen::Index l = 3 + 2 * slotOf(*f, victim);
  const Eigen::MatrixXd Hcol = H.middleCols(l, 2);
  const Eigen::MatrixXd schur = H - Hcol * H.block(l, l, 2, 2).llt().solve(Hcol.transpose());
  const std::vector<Eigen::Index> rows = keptRows(H.rows(), slotOf(*f, victim));
  f->removeLandmark(victim);
  const Eigen::MatrixXd after = f->information();
  EXPECT_LT(relDiff(after, schur(rows, rows)), 1e-12);
  EXPECT_LE((after - after.transpose()).cwiseAbs().maxCoeff(), 1e-12 * after.cwiseAbs().maxCoeff())
      << "before: " << (H - H.transpose()).cwiseAbs().maxCoeff();
  std::size_t links = 0;  // the store's link count must be the pattern of H
  const Eigen::Index blocks = 1 + (after.rows() - 3) / 2;
  for (Eigen::Index a = 0; a < blocks; ++a) {
    for (Eigen::Index c = a + 1; c < blocks; ++c) {
      const Eigen::Index ra = a == 0 ? 0 : 3 + 2 * (a - 1), rc = 3 + 2 * (c - 1);
      if (!after.block(ra, rc, a == 0 ? 3 : 2, 2).isZero(0.0)) ++links;
    }
  }
  EXPECT_EQ(f->stats().links, links);
  for (std::size_t k = 0; k < 20; ++k) f->step(s.steps[k].u, s.steps[k].observations);
  EXPECT_TRUE(f->pose().allFinite());
}

TEST(LandmarkRemoval, AnInvariantSeifMergeThatCannotShareAnAnchorRemovesTheNewerLandmark) {
  // Re-anchoring one of two landmarks to the other's anchor links its neighbours to the robot;
  // when both carry more links than the robot's local block has room for, the merge removes
  // `drop` exactly instead (its Schur complement) and the filter goes on.
  const test::Scenario s = test::makeScenario(8, 40, 150);
  auto f = makeFilter("seif:linearization=invariant,active=30", s.start, test::configFor(s));
  for (std::size_t k = 0; k < 150; ++k) f->step(s.steps[k].u, s.steps[k].observations);
  const Eigen::MatrixXd H = f->information();
  const auto links = [&](int id) {
    const Eigen::Index l = 3 + 2 * slotOf(*f, id);
    int n = 0;
    for (Eigen::Index c = 3; c < H.cols(); c += 2) {
      if (c != l && !H.block(l, c, 2, 2).isZero(0.0)) ++n;
    }
    return n;
  };
  const auto passive = [&](int id) { return H.block(0, 3 + 2 * slotOf(*f, id), 3, 2).isZero(0.0); };
  std::vector<int> crowded;  // landmarks whose re-anchoring would overflow the local block
  for (int id : f->landmarkIds()) {
    if (30 + links(id) >= 39) crowded.push_back(id);
  }
  ASSERT_GE(crowded.size(), 2u) << "the scenario must link landmarks densely";
  const auto drop_it = std::find_if(crowded.begin() + 1, crowded.end(), passive);
  ASSERT_NE(drop_it, crowded.end());
  const int keep = crowded.front(), drop = *drop_it;
  const Eigen::Index l = 3 + 2 * slotOf(*f, drop);
  const Eigen::MatrixXd Hcol = H.middleCols(l, 2);
  const Eigen::MatrixXd schur = H - Hcol * H.block(l, l, 2, 2).llt().solve(Hcol.transpose());
  const std::vector<Eigen::Index> rows = keptRows(H.rows(), slotOf(*f, drop));
  f->mergeLandmarks(keep, drop);
  EXPECT_FALSE(f->hasLandmark(drop));
  EXPECT_TRUE(f->hasLandmark(keep));
  EXPECT_LT(relDiff(f->information(), schur(rows, rows)), 1e-12);
  for (std::size_t k = 0; k < 20; ++k) f->step(s.steps[k].u, s.steps[k].observations);
  EXPECT_TRUE(f->pose().allFinite());
}

TEST(LandmarkRemoval, TheBatchRefuses) {
  const test::Scenario s = test::makeScenario(4, 10, 20);
  auto f = makeFilter("batch", s.start, test::configFor(s));
  for (const Step& step : s.steps) f->step(step.u, step.observations);
  EXPECT_THROW(f->removeLandmark(f->landmarkIds()[0]), InvalidArgument);
}

}  // namespace
