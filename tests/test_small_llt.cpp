// SmallLLT (src/core/small_llt.hpp), the unblocked Cholesky of the filters' small dense
// blocks, against Eigen::LLT: the same solution on random SPD blocks of the sizes the SEIF
// gathers, and the same refusal of a matrix that is not positive definite.
#include "core/small_llt.hpp"
#include "filters/information_ops.hpp"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <random>

namespace {

using seif::LocalMatrix;
using seif::SmallLLT;

Eigen::MatrixXd randomSpd(Eigen::Index n, std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::MatrixXd A(n, n);
  for (Eigen::Index i = 0; i < A.size(); ++i) A(i) = g(rng);
  return A * A.transpose() + 1e-2 * Eigen::MatrixXd::Identity(n, n);
}

TEST(SmallLLT, SolvesAsEigensLltOnBlocksOfTheSeifsSizes) {
  std::mt19937 rng(7);
  for (Eigen::Index n : {3, 17, 31, 32, 33, 63, 83}) {  // Eigen::LLT blocks from 32 rows on
    const Eigen::MatrixXd H = randomSpd(n, rng);
    const Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, 4);
    const Eigen::LLT<Eigen::MatrixXd> reference(H);
    const SmallLLT<LocalMatrix> small(H);
    ASSERT_EQ(small.info(), Eigen::Success) << n;
    const Eigen::MatrixXd X = small.solve(B), X_ref = reference.solve(B);
    EXPECT_LT((X - X_ref).norm(), 1e-9 * X_ref.norm()) << n << " rows";
    EXPECT_LT((H * X - B).norm(), 1e-8 * B.norm()) << n << " rows";
    const Eigen::MatrixXd L = small.factor().triangularView<Eigen::Lower>();
    EXPECT_LT((L * L.transpose() - H).norm(), 1e-12 * H.norm()) << n << " rows";
  }
}

TEST(SmallLLT, RefusesAMatrixThatIsNotPositiveDefinite) {
  std::mt19937 rng(8);
  Eigen::MatrixXd H = randomSpd(40, rng);
  H(25, 25) = -1.0;
  EXPECT_NE(SmallLLT<Eigen::MatrixXd>(H).info(), Eigen::Success);
  EXPECT_NE(Eigen::LLT<Eigen::MatrixXd>(H).info(), Eigen::Success);
}

}  // namespace
