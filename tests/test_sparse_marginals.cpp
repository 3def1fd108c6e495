// Selected inversion (Takahashi) against the dense inverse.
#include <seif/core/errors.hpp>
#include "core/sparse_marginals.hpp"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace seif {
namespace {

/// A random sparse SPD matrix: `links` random off-diagonal pairs of blocks of size
/// `block`, each block stored in full, plus a chain linking block k to k + 1 (a path
/// graph gives a tall elimination tree).
Eigen::SparseMatrix<double> randomInformation(int blocks, int block, int links, bool chain, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> pick(0, blocks - 1);
  const int n = blocks * block;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
  std::vector<std::pair<int, int>> pairs;
  for (int k = 0; k < links; ++k) pairs.emplace_back(pick(rng), pick(rng));
  if (chain) {
    for (int k = 0; k + 1 < blocks; ++k) pairs.emplace_back(k, k + 1);
  }
  // H = sum of J^T J over factors touching two blocks (PSD) + a diagonal prior (PD).
  for (const auto& [a, c] : pairs) {
    if (a == c) continue;
    Eigen::MatrixXd J(block, 2 * block);
    for (int i = 0; i < J.size(); ++i) J.data()[i] = normal(rng);
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const int ia = a * block, ic = c * block;
    dense.block(ia, ia, block, block) += JtJ.topLeftCorner(block, block);
    dense.block(ia, ic, block, block) += JtJ.topRightCorner(block, block);
    dense.block(ic, ia, block, block) += JtJ.bottomLeftCorner(block, block);
    dense.block(ic, ic, block, block) += JtJ.bottomRightCorner(block, block);
  }
  for (int b = 0; b < blocks; ++b) {
    Eigen::MatrixXd A(block, block);
    for (int i = 0; i < A.size(); ++i) A.data()[i] = normal(rng);
    dense.block(b * block, b * block, block, block) += 0.1 * A * A.transpose() + 0.01 * Eigen::MatrixXd::Identity(block, block);
  }
  // Store every entry of the touched blocks (explicit zeros included), as the SEIF does.
  std::vector<Eigen::Triplet<double>> t;
  for (int bi = 0; bi < blocks; ++bi) {
    for (int bj = 0; bj < blocks; ++bj) {
      const auto B = dense.block(bi * block, bj * block, block, block);
      if (bi != bj && B.cwiseAbs().maxCoeff() == 0.0) continue;
      for (int i = 0; i < block; ++i)
        for (int j = 0; j < block; ++j) t.emplace_back(bi * block + i, bj * block + j, B(i, j));
    }
  }
  Eigen::SparseMatrix<double> H(n, n);
  H.setFromTriplets(t.begin(), t.end());
  return H;
}

void expectSelectedInverseMatchesDense(const Eigen::SparseMatrix<double>& H) {
  const Eigen::MatrixXd dense(H);
  const Eigen::MatrixXd Sigma = dense.llt().solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
  const SparseMarginals marginals(H);
  const double scale = Sigma.cwiseAbs().maxCoeff();
  int checked = 0;
  for (int k = 0; k < H.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(H, k); it; ++it) {
      ASSERT_NEAR(marginals.covariance(it.row(), it.col()), Sigma(it.row(), it.col()), 1e-9 * scale)
          << "entry (" << it.row() << ", " << it.col() << ")";
      ++checked;
    }
  }
  EXPECT_EQ(checked, H.nonZeros());
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(H.rows(), -1.0, 2.0);
  EXPECT_LT((marginals.solve(b) - Sigma * b).cwiseAbs().maxCoeff(), 1e-9 * scale * b.size());
}

TEST(SparseMarginals, EveryStoredEntryEqualsTheDenseInverse) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    SCOPED_TRACE(seed);
    expectSelectedInverseMatchesDense(randomInformation(30, 2, 40, seed % 2 == 0, seed));
  }
}

TEST(SparseMarginals, ScalarAndBlockPatterns) {
  expectSelectedInverseMatchesDense(randomInformation(200, 1, 150, true, 7));    // scalar chain
  expectSelectedInverseMatchesDense(randomInformation(60, 3, 120, false, 8));    // 3x3 blocks
  expectSelectedInverseMatchesDense(randomInformation(1, 3, 0, false, 9));       // one block
  expectSelectedInverseMatchesDense(randomInformation(80, 2, 0, false, 10));     // block diagonal
}

TEST(SparseMarginals, DiagonalBlocksAndBadQueries) {
  const Eigen::SparseMatrix<double> H = randomInformation(50, 2, 60, true, 11);
  const Eigen::MatrixXd Sigma = Eigen::MatrixXd(H).llt().solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
  const SparseMarginals marginals(H);
  for (int b = 0; b < 50; ++b) {
    const Eigen::Matrix2d S = marginals.covarianceBlock<2>(2 * b);
    EXPECT_LT((S - Sigma.block<2, 2>(2 * b, 2 * b)).cwiseAbs().maxCoeff(), 1e-9 * Sigma.cwiseAbs().maxCoeff());
  }
  EXPECT_THROW(marginals.covariance(-1, 0), seif::InvalidArgument);
  EXPECT_THROW(marginals.covariance(0, H.rows()), seif::InvalidArgument);
  // Two blocks that share no factor and are far apart are not in the pattern of the factor.
  const SparseMarginals diagonal(randomInformation(80, 2, 0, false, 12));
  EXPECT_THROW(diagonal.covariance(0, 100), seif::InvalidArgument);
}

TEST(SparseMarginals, IndefiniteMatrixIsANumericError) {
  Eigen::SparseMatrix<double> H(2, 2);
  H.insert(0, 0) = 1.0;
  H.insert(1, 1) = -1.0;
  EXPECT_THROW(SparseMarginals{H}, NumericError);
}

}  // namespace
}  // namespace seif
