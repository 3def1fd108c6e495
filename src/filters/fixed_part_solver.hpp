#pragma once
// Solves the SEIF's robot-active block H mu = r several times in one update, factoring once
// the part that the update does not change (SeifStore::solveLocalMean while a hold is on).
//
// One update solves the block four times (before the measurement in the book's order, after
// each relinearisation, before the sparsification). Between those solves only the rows of
// the robot and of the landmarks the scan observes change; the other active landmarks, U,
// keep H_UU and their links to the rest. With L L^T = H_UU and W = L^-1 H_UC for the
// changing rows C, block elimination gives
//   S = H_CC - W^T W,   L y_U = r_U,   S mu_C = r_C - W^T y_U,   L^T mu_U = y_U - W mu_C,
// so after the first solve each costs a Cholesky factor of S (|C| rows, 3 + 2 x observed)
// and products with W, instead of a factor of the whole block (Golub & Van Loan, Matrix
// Computations, §4.2 and §3.2.9; the Schur complement). The result is the same solution,
// rounded differently.
//
// Nothing is assumed about which entries changed: each solve compares H_UU and each cached
// column block of H_UC with the copies it was factored from, and refactors what differs.
#include "filters/information_ops.hpp"

#include <span>
#include <vector>

namespace seif {

class FixedPartSolver {
 public:
  FixedPartSolver();

  /// The landmarks (slots) whose rows the coming solves may change; the block's other
  /// landmarks are factored once. Drops what was factored before.
  void hold(std::span<const int> changing);
  /// Ends the hold: solve() is not to be called until the next hold().
  void release();
  bool held() const { return held_; }
  /// How many times the fixed part has been factored (each hold's first solve, and each solve
  /// that found H_UU changed).
  std::size_t factorizations() const { return factorizations_; }

  /// mu = H^-1 r for the block of the robot (rows 0-2) and `slots` (two rows each, in
  /// order). False when H is not positive definite (mu then undefined).
  bool solve(const LocalMatrix& H, const LocalVector& r, std::span<const int> slots, LocalVector& mu);

 private:
  using Panel = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxLocalDim - 3, kMaxLocalDim>;
  /// Factors H_UU with U = the block's landmarks not held as changing, in block order.
  bool factorFixed(const LocalMatrix& H, std::span<const int> slots);
  /// W's column `col` <- L^-1 (that column).
  void forwardSubstitute(Eigen::Index col);
  /// Whether the block holds every landmark of U with H_UU as it was factored.
  bool fixedPartCurrent(const LocalMatrix& H) const;
  /// Row of U's k-th landmark in the block (fixed_rows_, filled by solve()).
  Eigen::Index fixedRow(std::size_t k) const { return fixed_rows_[k]; }

  bool held_ = false;
  std::size_t factorizations_ = 0;
  std::vector<int> changing_;
  bool factored_ = false;
  std::vector<int> fixed_;                // U's slots, in factor order
  std::vector<Eigen::Index> fixed_rows_;  // their rows in the block being solved
  LocalMatrix H_uu_;                      // H_UU as factored
  LocalMatrix L_;                         // its Cholesky factor (lower)
  // W's column blocks, one per changing variable (-1: the robot), with H_Uc as computed from.
  std::vector<int> w_keys_;
  Panel W_, H_uc_;
  // Per solve: the changing rows in block order, W over them, S, right-hand sides.
  std::vector<Eigen::Index> c_rows_;
  Panel Wc_;
  LocalMatrix S_;
  LocalVector y_u_, y_c_;
};

}  // namespace seif
