#pragma once
// Central-difference Jacobians for the model tests.
#include <seif/core/angles.hpp>

#include <Eigen/Core>

namespace seif::test {

inline constexpr double kStep = 1e-6;

// Central difference of f: R^n -> R^m at x; angle outputs wrapped so that a difference
// across the +-pi seam stays small.
template <int M, int N, typename F>
Eigen::Matrix<double, M, N> numericJacobian(F f, const Eigen::Matrix<double, N, 1>& x,
                                            int wrapped_row = -1) {
  Eigen::Matrix<double, M, N> J;
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(i) += kStep;
    xm(i) -= kStep;
    Eigen::Matrix<double, M, 1> d = f(xp) - f(xm);
    if (wrapped_row >= 0) d(wrapped_row) = wrapAngle(d(wrapped_row));
    J.col(i) = d / (2 * kStep);
  }
  return J;
}

}  // namespace seif::test
