// FixedPartSolver (src/filters/fixed_part_solver.hpp), the SEIF's solves of one update with
// the rows it does not change factored once: the same solution as a Cholesky of the whole
// block, one factorisation per hold while only the held rows change, and a correct solution
// (refactored) whatever else changes - the block reordered, a landmark joining, a row that
// was not declared as changing.
#include "core/small_llt.hpp"
#include "filters/fixed_part_solver.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

namespace {

using seif::FixedPartSolver;
using seif::LocalMatrix;
using seif::LocalVector;

struct Block {
  LocalMatrix H;
  LocalVector r;
  std::vector<int> slots;  // landmark slot of rows 3 + 2i, 4 + 2i
};

Block randomBlock(int landmarks, std::mt19937& rng) {
  std::normal_distribution<double> g;
  const Eigen::Index n = 3 + 2 * landmarks;
  Eigen::MatrixXd A(n, n + 4);
  for (Eigen::Index i = 0; i < A.size(); ++i) A(i) = g(rng);
  Block b;
  b.H = A * A.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
  b.r = Eigen::VectorXd::NullaryExpr(n, [&] { return g(rng); });
  b.slots.resize(static_cast<std::size_t>(landmarks));
  std::iota(b.slots.begin(), b.slots.end(), 100);  // slots are not row numbers
  return b;
}

LocalVector direct(const Block& b) { return seif::SmallLLT<LocalMatrix>(b.H).solve(b.r); }

LocalVector viaFixedPart(FixedPartSolver& s, const Block& b) {
  LocalVector mu;
  EXPECT_TRUE(s.solve(b.H, b.r, b.slots, mu));
  return mu;
}

double relativeError(const LocalVector& x, const LocalVector& reference) { return (x - reference).norm() / reference.norm(); }

// Adds a random symmetric positive semidefinite change to the rows of the robot and the
// landmarks at `positions` (what a relinearisation changes).
void changeRows(Block& b, const std::vector<int>& positions, std::mt19937& rng) {
  std::normal_distribution<double> g;
  std::vector<Eigen::Index> rows = {0, 1, 2};
  for (int p : positions) {
    rows.push_back(3 + 2 * p);
    rows.push_back(4 + 2 * p);
  }
  const auto m = static_cast<Eigen::Index>(rows.size());
  Eigen::MatrixXd J(m, m);
  for (Eigen::Index i = 0; i < J.size(); ++i) J(i) = g(rng);
  const Eigen::MatrixXd D = J * J.transpose();
  for (Eigen::Index i = 0; i < m; ++i) {
    b.r(rows[static_cast<std::size_t>(i)]) += g(rng);
    for (Eigen::Index j = 0; j < m; ++j) b.H(rows[static_cast<std::size_t>(i)], rows[static_cast<std::size_t>(j)]) += D(i, j);
  }
}

TEST(FixedPartSolver, SolvesAsTheWholeBlocksCholeskyFactoringTheUnchangedRowsOnce) {
  std::mt19937 rng(3);
  for (int landmarks : {0, 1, 5, 30, 40}) {
    Block b = randomBlock(landmarks, rng);
    std::vector<int> observed;  // positions 0, 3, 6, ... change
    for (int p = 0; p < landmarks; p += 3) observed.push_back(p);
    std::vector<int> changing;
    for (int p : observed) changing.push_back(b.slots[static_cast<std::size_t>(p)]);
    FixedPartSolver s;
    s.hold(changing);
    for (int solve = 0; solve < 4; ++solve) {
      EXPECT_LT(relativeError(viaFixedPart(s, b), direct(b)), 1e-10) << landmarks << " landmarks, solve " << solve;
      changeRows(b, observed, rng);
    }
    EXPECT_EQ(s.factorizations(), 1u) << landmarks << " landmarks";
  }
}

TEST(FixedPartSolver, FollowsTheBlockReorderedAndALandmarkJoining) {
  std::mt19937 rng(5);
  Block b = randomBlock(12, rng);
  FixedPartSolver s;
  s.hold(std::vector<int>{b.slots[2], b.slots[7]});
  EXPECT_LT(relativeError(viaFixedPart(s, b), direct(b)), 1e-10);
  // The block reordered (the sparsification's [x, Y+, Y0]): rows permuted with their slots.
  std::vector<int> order(12);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  Block p = b;
  for (int i = 0; i < 12; ++i) {
    p.slots[static_cast<std::size_t>(i)] = b.slots[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])];
  }
  const auto row = [&](Eigen::Index r) { return r < 3 ? r : 3 + 2 * order[static_cast<std::size_t>((r - 3) / 2)] + (r - 3) % 2; };
  for (Eigen::Index i = 0; i < b.H.rows(); ++i) {
    p.r(i) = b.r(row(i));
    for (Eigen::Index j = 0; j < b.H.cols(); ++j) p.H(i, j) = b.H(row(i), row(j));
  }
  EXPECT_LT(relativeError(viaFixedPart(s, p), direct(p)), 1e-10);
  EXPECT_EQ(s.factorizations(), 1u);
  // A new landmark appended, linked to the robot only (a first sighting).
  Block grown = randomBlock(13, rng);
  grown.H.setZero();
  grown.H.topLeftCorner(p.H.rows(), p.H.cols()) = p.H;
  grown.H.bottomRightCorner<2, 2>() = 2.0 * Eigen::Matrix2d::Identity();
  grown.H.block<3, 2>(0, 27) << 0.1, 0.0, 0.0, 0.1, 0.05, 0.05;
  grown.H.block<2, 3>(27, 0) = grown.H.block<3, 2>(0, 27).transpose();
  grown.H.topLeftCorner<3, 3>() += Eigen::Matrix3d::Identity();
  grown.r.head(p.r.size()) = p.r;
  grown.slots = p.slots;
  grown.slots.push_back(999);
  EXPECT_LT(relativeError(viaFixedPart(s, grown), direct(grown)), 1e-10);
  EXPECT_EQ(s.factorizations(), 1u);
}

TEST(FixedPartSolver, RefactorsWhenARowItWasNotToldOfChanges) {
  std::mt19937 rng(11);
  Block b = randomBlock(10, rng);
  FixedPartSolver s;
  s.hold(std::vector<int>{b.slots[0]});
  EXPECT_LT(relativeError(viaFixedPart(s, b), direct(b)), 1e-10);
  changeRows(b, {4}, rng);  // landmark 4 was held as fixed: H_UU changed
  EXPECT_LT(relativeError(viaFixedPart(s, b), direct(b)), 1e-10);
  EXPECT_EQ(s.factorizations(), 2u);
  // Only a link between a fixed and a held landmark: H_UC changed, H_UU did not.
  b.H(3 + 2 * 5, 3) += 0.01;
  b.H(3, 3 + 2 * 5) += 0.01;
  EXPECT_LT(relativeError(viaFixedPart(s, b), direct(b)), 1e-10);
  EXPECT_EQ(s.factorizations(), 2u);
  // A landmark of the fixed part left the block: factored again without it.
  Block smaller = b;
  smaller.H = b.H.topLeftCorner(b.H.rows() - 2, b.H.cols() - 2);
  smaller.r = b.r.head(b.r.size() - 2);
  smaller.slots.pop_back();
  EXPECT_LT(relativeError(viaFixedPart(s, smaller), direct(smaller)), 1e-10);
  EXPECT_EQ(s.factorizations(), 3u);
}

TEST(FixedPartSolver, OneHoldOverMoreChangingLandmarksThanABlockHolds) {
  // A batch of observations larger than the block, sparsified as it comes: one hold sees
  // blocks of thirty fixed landmarks and ten changing ones, a different ten each time (more
  // column blocks of W than fit at once).
  std::mt19937 rng(17);
  constexpr int kRounds = 8;
  FixedPartSolver s;
  std::vector<int> changing;
  for (int k = 0; k < kRounds; ++k) {
    for (int i = 0; i < 10; ++i) changing.push_back(1000 * (k + 1) + i);
  }
  s.hold(changing);
  const Block fixed_part = randomBlock(40, rng);
  for (int k = 0; k < kRounds; ++k) {
    Block b = fixed_part;
    for (int i = 0; i < 10; ++i) b.slots[static_cast<std::size_t>(30 + i)] = 1000 * (k + 1) + i;
    std::vector<int> positions(10);
    std::iota(positions.begin(), positions.end(), 30);
    changeRows(b, positions, rng);  // H_UU unchanged; H_CC differs from round to round
    EXPECT_LT(relativeError(viaFixedPart(s, b), direct(b)), 1e-10) << "round " << k;
  }
  EXPECT_EQ(s.factorizations(), 1u);
}

TEST(FixedPartSolver, RefusesABlockThatIsNotPositiveDefinite) {
  std::mt19937 rng(13);
  for (int where : {0, 3, 8}) {  // the robot (changing), a held landmark, a fixed one
    Block b = randomBlock(6, rng);
    b.H(where, where) = -1.0;
    FixedPartSolver s;
    s.hold(std::vector<int>{b.slots[0]});
    LocalVector mu;
    EXPECT_FALSE(s.solve(b.H, b.r, b.slots, mu)) << "row " << where;
  }
}

}  // namespace
