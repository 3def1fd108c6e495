#pragma once
// The relative difference the tests compare states with: ||a - b|| / ||b|| (Frobenius).
#include <Eigen/Core>

#include <algorithm>

namespace seif::test {

inline double relDiff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max(1e-300, b.norm());
}

}  // namespace seif::test
