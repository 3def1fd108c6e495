#pragma once
// Cholesky factorisation H = L L^T of the small dense blocks the filters factor every step
// (the SEIF's robot-active block, a Markov blanket: up to ~100 rows), with Eigen's
// unblocked kernel.
//
// Eigen::LLT runs a blocked algorithm from 32 rows on (blocks of 8 there, each trailing
// update a matrix product). At these sizes the products' set-up dominates: on a 63-row
// block the unblocked kernel takes 5.6-6.7 us against Eigen::LLT's 14 us (Eigen 3.4, -O2
// and -O3). The arithmetic is the same column-by-column Cholesky; only the order in which
// the trailing sums are accumulated differs (results agree to rounding).
#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace seif {

/// A = L L^T in place with the unblocked kernel (below): L in A's lower triangle, the strict
/// upper one left as it was. False when A is not positive definite.
template <typename Derived>
bool choleskyInPlace(Eigen::MatrixBase<Derived>& A) {
  // Returns the first column whose pivot is not positive, or -1.
  return Eigen::internal::llt_inplace<double, Eigen::Lower>::unblocked(A.derived()) < 0;
}

template <typename Matrix>
class SmallLLT {
 public:
  SmallLLT() = default;
  template <typename Derived>
  explicit SmallLLT(const Eigen::MatrixBase<Derived>& H) {
    compute(H);
  }

  template <typename Derived>
  SmallLLT& compute(const Eigen::MatrixBase<Derived>& H) {
    L_ = H;
    ok_ = choleskyInPlace(L_);
    return *this;
  }

  /// Eigen::Success, or Eigen::NumericalIssue when the matrix is not positive definite.
  Eigen::ComputationInfo info() const { return ok_ ? Eigen::Success : Eigen::NumericalIssue; }

  /// H^-1 B.
  template <typename Derived>
  typename Derived::PlainObject solve(const Eigen::MatrixBase<Derived>& B) const {
    typename Derived::PlainObject X = B;
    solveInPlace(X);
    return X;
  }
  template <typename Derived>
  void solveInPlace(Eigen::MatrixBase<Derived>& X) const {
    L_.template triangularView<Eigen::Lower>().solveInPlace(X);
    L_.template triangularView<Eigen::Lower>().transpose().solveInPlace(X);
  }

  /// The factor L (its strictly upper triangle holds H's entries, unread).
  const Matrix& factor() const { return L_; }

 private:
  Matrix L_;
  bool ok_ = false;
};

}  // namespace seif
