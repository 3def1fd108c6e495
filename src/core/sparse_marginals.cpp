#include <seif/core/errors.hpp>
#include "core/sparse_marginals.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace seif {

struct SparseMarginals::Impl {
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
  Eigen::VectorXi position;     // position[i]: where variable i sits in the permuted order
  // The selected inverse on the pattern of L, filled column by column as reads need it.
  mutable std::vector<double> Z;
  mutable std::vector<char> done;  // done[j]: column j of Z is computed
  mutable std::vector<int> path;   // work buffers
  mutable std::vector<double> acc;

  const Eigen::SparseMatrix<double>& L() const { return llt.matrixL().nestedExpression(); }
};

SparseMarginals::SparseMarginals(const Eigen::SparseMatrix<double>& H) : impl_(std::make_unique<Impl>()) {
  impl_->llt.compute(H);
  if (impl_->llt.info() != Eigen::Success) {
    throw NumericError("the information matrix is not positive definite (sparse Cholesky failed)");
  }
  impl_->position = impl_->llt.permutationP().indices();
}

SparseMarginals::~SparseMarginals() = default;
SparseMarginals::SparseMarginals(SparseMarginals&&) noexcept = default;
SparseMarginals& SparseMarginals::operator=(SparseMarginals&&) noexcept = default;

Eigen::Index SparseMarginals::size() const { return impl_->L().rows(); }
Eigen::Index SparseMarginals::factorNonZeros() const { return impl_->L().nonZeros(); }

Eigen::VectorXd SparseMarginals::solve(const Eigen::VectorXd& b) const { return impl_->llt.solve(b); }

// Column j of Z needs the columns of the rows below its diagonal, which are all ancestors of
// j in the elimination tree (the parent of j is its first row below the diagonal). So one
// marginal needs only the columns on the path from its variable to the root, computed from
// the root down; a map of marginals shares those paths and costs one full pass at most.
void SparseMarginals::computeColumnsFor(int column) const {
  const Eigen::SparseMatrix<double>& L = impl_->L();
  const int* outer = L.outerIndexPtr();
  const int* rows = L.innerIndexPtr();
  const double* values = L.valuePtr();
  std::vector<double>& Z = impl_->Z;
  std::vector<char>& done = impl_->done;
  if (Z.empty()) {
    Z.assign(static_cast<std::size_t>(L.nonZeros()), 0.0);
    done.assign(static_cast<std::size_t>(L.cols()), 0);
    int widest = 0;
    for (Eigen::Index j = 0; j < L.cols(); ++j) widest = std::max(widest, outer[j + 1] - outer[j]);
    impl_->acc.reserve(static_cast<std::size_t>(widest));  // assign() below never reallocates
  }
  std::vector<int>& path = impl_->path;
  path.clear();
  for (int j = column; j >= 0 && !done[static_cast<std::size_t>(j)];) {
    path.push_back(j);
    j = outer[j + 1] - outer[j] > 1 ? rows[outer[j] + 1] : -1;  // parent, or -1 at a root
  }
  std::vector<double>& acc = impl_->acc;  // sum_k Z_{r_t k} L_kj for the rows r_t of column j
  for (auto it = path.rbegin(); it != path.rend(); ++it) {
    const int j = *it;
    const int begin = outer[j], end = outer[j + 1];  // rows[begin] == j: the diagonal first
    const int m = end - begin - 1;                   // rows below the diagonal
    const double Ljj = values[begin];
    acc.assign(static_cast<std::size_t>(m), 0.0);
    // Z_{r_t r_s} for r_t >= r_s lies in column r_s, whose rows below r_s include every r_t
    // of this column below r_s (the clique property): one merge walk per column r_s.
    for (int s = 0; s < m; ++s) {
      const int k = rows[begin + 1 + s];
      const double Lkj = values[begin + 1 + s];
      int p = outer[k];  // Z_kk
      acc[static_cast<std::size_t>(s)] += Z[static_cast<std::size_t>(p)] * Lkj;
      for (int t = s + 1; t < m; ++t) {
        const int r = rows[begin + 1 + t];
        while (rows[p] < r) ++p;  // struct(j) below k is a subset of struct(k): r is found
        const double Zrk = Z[static_cast<std::size_t>(p)];
        acc[static_cast<std::size_t>(t)] += Zrk * Lkj;                    // row r_t, term k
        acc[static_cast<std::size_t>(s)] += Zrk * values[begin + 1 + t];  // row k, term r_t
      }
    }
    double diag = 1.0 / (Ljj * Ljj);
    for (int t = 0; t < m; ++t) {
      const double Zrj = -acc[static_cast<std::size_t>(t)] / Ljj;  // (T1)
      Z[static_cast<std::size_t>(begin + 1 + t)] = Zrj;
      diag -= values[begin + 1 + t] * Zrj / Ljj;                    // (T2)
    }
    Z[static_cast<std::size_t>(begin)] = diag;
    done[static_cast<std::size_t>(j)] = 1;
  }
}

double SparseMarginals::covariance(Eigen::Index i, Eigen::Index j) const {
  const Eigen::Index n = size();
  if (i < 0 || j < 0 || i >= n || j >= n) {
    throw InvalidArgument("SparseMarginals: entry (" + std::to_string(i) + ", " + std::to_string(j) +
                            ") outside a " + std::to_string(n) + "-variable system");
  }
  const int a = impl_->position[i], c = impl_->position[j];
  const int col = std::min(a, c), row = std::max(a, c);
  if (impl_->Z.empty() || !impl_->done[static_cast<std::size_t>(col)]) computeColumnsFor(col);
  const Eigen::SparseMatrix<double>& L = impl_->L();
  const int* rows = L.innerIndexPtr();
  const int* first = rows + L.outerIndexPtr()[col];
  const int* last = rows + L.outerIndexPtr()[col + 1];
  const int* hit = std::lower_bound(first, last, row);
  if (hit == last || *hit != row) {
    throw InvalidArgument("SparseMarginals: entry (" + std::to_string(i) + ", " + std::to_string(j) +
                            ") is not in the pattern of the factor");
  }
  return impl_->Z[static_cast<std::size_t>(hit - rows)];
}

}  // namespace seif
