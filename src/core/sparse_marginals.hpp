#pragma once
// Marginal covariances of a sparse Gaussian in information form, H x = b, from one sparse
// Cholesky factorisation: the *selected inverse* of H, i.e. the entries of Sigma = H^-1 on
// the pattern of the factor, by the recurrences of Takahashi, Fagan and Chen (1973).
//
// With P H P^T = L L^T (fill-reducing permutation P, L lower triangular), Z = (L L^T)^-1
// satisfies Z = L^-T L^-1, hence Z L = L^-T, whose strictly upper part is zero. Read column
// by column from the last, for every j and every row i > j in the pattern of column j:
//   Z_ij = -(1 / L_jj) sum_{k > j, L_kj != 0} Z_ik L_kj                      (T1)
//   Z_jj = 1 / L_jj^2 - (1 / L_jj) sum_{k > j, L_kj != 0} Z_kj L_kj          (T2)
// Every Z_ik needed lies in the pattern of L (the rows of column j below the diagonal form
// a clique of the filled graph), so the recurrences never leave it: the cost is that of the
// factorisation, O(sum_j |L_*j|^2), with no dense N-row matrix anywhere. Column j needs
// only the columns of its ancestors in the elimination tree, so the columns are computed
// lazily, those of one marginal at a time.
#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>

namespace seif {

class SparseMarginals {
 public:
  /// Factorises H (symmetric positive definite; only its lower triangle is read). Throws
  /// NumericError when H is not positive definite.
  explicit SparseMarginals(const Eigen::SparseMatrix<double>& H);
  ~SparseMarginals();
  SparseMarginals(SparseMarginals&&) noexcept;
  SparseMarginals& operator=(SparseMarginals&&) noexcept;

  Eigen::Index size() const;
  /// Non-zeros of the factor L (lower triangle with its diagonal).
  Eigen::Index factorNonZeros() const;

  /// H^-1 b, from the factor.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;

  /// Sigma_ij. Requires (i, j) in the pattern of the factor, which holds every entry
  /// stored in H (explicit zeros included): e.g. the diagonal block of a variable whose
  /// block H stores in full. Computes (T1, T2) the columns of the selected inverse on the
  /// path from the entry's column to the root of the elimination tree, unless an earlier
  /// read did: reading every marginal costs one full pass, a single one only its path; an
  /// entry already computed costs a binary search. Throws InvalidArgument for an entry not
  /// in the pattern.
  double covariance(Eigen::Index i, Eigen::Index j) const;

  /// The n x n diagonal block of Sigma starting at `first`.
  template <int N>
  Eigen::Matrix<double, N, N> covarianceBlock(Eigen::Index first) const {
    Eigen::Matrix<double, N, N> S;
    for (int r = 0; r < N; ++r) {
      for (int c = 0; c <= r; ++c) S(r, c) = S(c, r) = covariance(first + r, first + c);
    }
    return S;
  }

 private:
  /// Computes the columns of Z that column `column` needs (its elimination-tree path).
  void computeColumnsFor(int column) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace seif
