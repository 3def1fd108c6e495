#include "filters/fixed_part_solver.hpp"
#include "core/small_llt.hpp"

#include <algorithm>
#include <array>

namespace seif {

FixedPartSolver::FixedPartSolver() {
  // Room for a whole block up front: no allocation in the steady state.
  changing_.reserve(kMaxLocalLandmarks + 1);
  fixed_.reserve(kMaxLocalLandmarks + 1);
  fixed_rows_.reserve(kMaxLocalLandmarks + 1);
  w_keys_.reserve(kMaxLocalLandmarks + 2);
  c_rows_.reserve(kMaxLocalDim);
}

void FixedPartSolver::hold(std::span<const int> changing) {
  changing_.assign(changing.begin(), changing.end());
  held_ = true;
  factored_ = false;
}

void FixedPartSolver::release() {
  held_ = false;
  factored_ = false;
}

bool FixedPartSolver::factorFixed(const LocalMatrix& H, std::span<const int> slots) {
  fixed_.clear();
  fixed_rows_.clear();
  for (std::size_t i = 0; i < slots.size(); ++i) {
    if (std::find(changing_.begin(), changing_.end(), slots[i]) != changing_.end()) continue;
    fixed_.push_back(slots[i]);
    fixed_rows_.push_back(3 + 2 * static_cast<Eigen::Index>(i));
  }
  const auto nu = 2 * static_cast<Eigen::Index>(fixed_.size());
  H_uu_.resize(nu, nu);
  for (std::size_t j = 0; j < fixed_.size(); ++j) {
    for (std::size_t i = 0; i < fixed_.size(); ++i) {
      H_uu_.block<2, 2>(2 * static_cast<Eigen::Index>(i), 2 * static_cast<Eigen::Index>(j)) =
          H.block<2, 2>(fixedRow(i), fixedRow(j));
    }
  }
  L_ = H_uu_;
  w_keys_.clear();
  W_.resize(nu, 0);
  H_uc_.resize(nu, 0);
  ++factorizations_;
  factored_ = choleskyInPlace(L_);
  return factored_;
}

void FixedPartSolver::forwardSubstitute(Eigen::Index col) {
  // L w = h in place on W's column `col` (Eigen's triangular solver for a vector).
  auto w = W_.col(col);
  L_.triangularView<Eigen::Lower>().solveInPlace(w);
}

bool FixedPartSolver::fixedPartCurrent(const LocalMatrix& H) const {
  for (std::size_t j = 0; j < fixed_.size(); ++j) {
    for (std::size_t i = j; i < fixed_.size(); ++i) {  // the lower triangle: the one factored
      if (H_uu_.block<2, 2>(2 * static_cast<Eigen::Index>(i), 2 * static_cast<Eigen::Index>(j)) !=
          H.block<2, 2>(fixedRow(i), fixedRow(j))) {
        return false;
      }
    }
  }
  return true;
}

bool FixedPartSolver::solve(const LocalMatrix& H, const LocalVector& r, std::span<const int> slots,
                            LocalVector& mu) {
  if (factored_) {  // U must still be in the block, H_UU as factored
    fixed_rows_.clear();
    for (int s : fixed_) {
      const auto at = std::find(slots.begin(), slots.end(), s);
      if (at == slots.end()) break;
      fixed_rows_.push_back(3 + 2 * static_cast<Eigen::Index>(at - slots.begin()));
    }
    factored_ = fixed_rows_.size() == fixed_.size() && fixedPartCurrent(H);
  }
  if (!factored_ && !factorFixed(H, slots)) return false;
  const auto nu = 2 * static_cast<Eigen::Index>(fixed_.size());

  // C: the robot, then the block's landmarks outside U, in block order; W over them from
  // the cached column blocks, each checked against H_Uc and recomputed when it changed.
  c_rows_.clear();
  Wc_.resize(nu, H.rows() - nu);
  Eigen::Index nc = 0;
  const auto addChanging = [&](int key, Eigen::Index row, Eigen::Index width) {
    std::size_t k = 0;
    Eigen::Index col = 0;
    for (; k < w_keys_.size() && w_keys_[k] != key; ++k) col += w_keys_[k] < 0 ? 3 : 2;
    const bool known = k < w_keys_.size();
    if (!known && col + width > W_.MaxColsAtCompileTime) {
      // More changing variables in one hold than a block holds (a batch sparsified as it
      // came): the cache starts again (this solve's columns are already in Wc_).
      w_keys_.clear();
      col = 0;
    }
    if (!known) {
      w_keys_.push_back(key);
      W_.conservativeResize(nu, col + width);
      H_uc_.conservativeResize(nu, col + width);
    }
    // Column by column: the robot's re-anchoring changes its heading column alone.
    for (Eigen::Index c = col; c < col + width; ++c) {
      bool current = known;
      for (std::size_t i = 0; current && i < fixed_.size(); ++i) {
        current = H_uc_.col(c).segment<2>(2 * static_cast<Eigen::Index>(i)) == H.col(row + c - col).segment<2>(fixedRow(i));
      }
      if (current) continue;
      for (std::size_t i = 0; i < fixed_.size(); ++i) {
        H_uc_.col(c).segment<2>(2 * static_cast<Eigen::Index>(i)) = H.col(row + c - col).segment<2>(fixedRow(i));
      }
      W_.col(c) = H_uc_.col(c);
      if (!W_.col(c).isZero(0.0)) forwardSubstitute(c);  // a new landmark: no links to U
    }
    Wc_.middleCols(nc, width) = W_.middleCols(col, width);
    for (Eigen::Index c = 0; c < width; ++c) c_rows_.push_back(row + c);
    nc += width;
  };
  std::array<bool, kMaxLocalLandmarks> in_fixed{};
  for (Eigen::Index row : fixed_rows_) in_fixed[static_cast<std::size_t>((row - 3) / 2)] = true;
  addChanging(-1, 0, 3);
  for (std::size_t i = 0; i < slots.size(); ++i) {
    if (!in_fixed[i]) addChanging(slots[i], 3 + 2 * static_cast<Eigen::Index>(i), 2);
  }
  Wc_.conservativeResize(nu, nc);

  // S = H_CC - W^T W (its lower triangle), factored.
  S_.resize(nc, nc);
  for (Eigen::Index j = 0; j < nc; ++j) {
    for (Eigen::Index i = j; i < nc; ++i) {
      S_(i, j) = H(c_rows_[static_cast<std::size_t>(i)], c_rows_[static_cast<std::size_t>(j)]);
    }
  }
  for (Eigen::Index j = 0; j < nc; ++j) {  // W's columns are contiguous: one dot product each
    for (Eigen::Index i = j; i < nc; ++i) S_(i, j) -= Wc_.col(i).dot(Wc_.col(j));
  }
  if (!choleskyInPlace(S_)) return false;

  // L y_U = r_U;  S mu_C = r_C - W^T y_U;  L^T mu_U = y_U - W mu_C.
  y_u_.resize(nu);
  for (std::size_t i = 0; i < fixed_.size(); ++i) y_u_.segment<2>(2 * static_cast<Eigen::Index>(i)) = r.segment<2>(fixedRow(i));
  const LocalMatrix& L = L_;
  L.triangularView<Eigen::Lower>().solveInPlace(y_u_);
  y_c_.resize(nc);
  for (Eigen::Index i = 0; i < nc; ++i) y_c_(i) = r(c_rows_[static_cast<std::size_t>(i)]);
  if (nu > 0) y_c_.noalias() -= Wc_.transpose() * y_u_;
  S_.triangularView<Eigen::Lower>().solveInPlace(y_c_);
  S_.triangularView<Eigen::Lower>().transpose().solveInPlace(y_c_);
  if (nu > 0) y_u_.noalias() -= Wc_ * y_c_;
  L.triangularView<Eigen::Lower>().transpose().solveInPlace(y_u_);

  mu.resize(H.rows());
  for (Eigen::Index i = 0; i < nc; ++i) mu(c_rows_[static_cast<std::size_t>(i)]) = y_c_(i);
  for (std::size_t i = 0; i < fixed_.size(); ++i) mu.segment<2>(fixedRow(i)) = y_u_.segment<2>(2 * static_cast<Eigen::Index>(i));
  return true;
}

}  // namespace seif
