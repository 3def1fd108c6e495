// Joint compatibility branch and bound (Neira & Tardos, IEEE T-RA 17(6), 2001): depth first
// over the observations, each paired with one of its individually compatible landmarks or
// with none; a pairing is kept only if the joint innovation of the whole hypothesis passes
// the chi-square(2k) gate - tested at every node, not only at the leaves. The answer is the
// jointly compatible hypothesis with the most pairings and, among those, the smallest joint
// distance: a branch is cut when it cannot pair more than the best found, or as many at a
// smaller distance (the distance only grows as pairings are added). The observations are
// searched in the order of their nearest candidate's distance, so good hypotheses come
// first and the answer does not depend on the order the data lists them in. The joint
// innovation covariance S_H = J_H Sigma J_H^T + R_H uses one joint marginal Sigma of the
// pose and every candidate of the scan; its Cholesky factor grows by one 2x2 block per
// pairing (O(k^2) per node).
#include "association/scan.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

namespace seif {

double chiSquareEvenQuantile(double p, int k) {
  // CDF of chi-square(2k): 1 - sum_{i<k} exp(-x/2) (x/2)^i / i!, each term in logs (the
  // product of exp(-h) and the sum overflows or underflows beyond h of about 700).
  const auto cdf = [k](double x) {
    const double h = 0.5 * x;
    if (h <= 0.0) return 0.0;
    const double log_h = std::log(h);
    double log_term = -h, upper = 0.0;  // log of exp(-h) h^i / i!
    for (int i = 0; i < k; ++i) {
      if (i > 0) log_term += log_h - std::log(static_cast<double>(i));
      upper += std::exp(log_term);
    }
    return 1.0 - upper;
  };
  double lo = 0.0, hi = 2.0 * k + 10.0;
  while (cdf(hi) < p) hi *= 2.0;
  for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (cdf(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

/// One candidate pairing with what the joint test needs: its innovation, noise, Jacobian
/// columns, and A = J Sigma (2 x dim of the joint marginal).
struct Candidate {
  Pairing pairing;
  Eigen::Index column = 0;  // first column of its landmark in the joint marginal
  Vec2 nu = Vec2::Zero();
  Mat2 R = Mat2::Zero();
  Mat23 J_x = Mat23::Zero();
  Mat2 J_y = Mat2::Zero();
  Eigen::MatrixXd A;
};

class Search {
 public:
  Search(const ScanProblem& scan, std::size_t max_nodes) : max_nodes_(max_nodes) {
    const std::size_t m = scan.compatible.size();
    candidates_.resize(m);
    // The scan's joint marginal of the pose and every candidate (associator.cpp).
    const Marginal& joint = scan.joint;
    for (std::size_t i = 0; i < m; ++i) {
      for (const Pairing& p : scan.compatible[i]) {
        Candidate c;
        c.pairing = p;
        c.column = scan.column.at(p.landmark);
        const Observation& z = (*scan.observations)[static_cast<std::size_t>(p.observation)];
        c.R = scan.sensor->noise(z);
        const PredictedMeasurement pm = predictFromMarginal(*scan.sensor, joint, c.column, c.R, &c.J_x, &c.J_y);
        c.nu = scan.sensor->residual(z.z, pm.z);
        c.A = c.J_x * joint.covariance.topRows<3>() + c.J_y * joint.covariance.middleRows<2>(c.column);
        candidates_[i].push_back(std::move(c));
      }
      std::sort(candidates_[i].begin(), candidates_[i].end(),
                [](const Candidate& a, const Candidate& b) { return a.pairing.d2 < b.pairing.d2; });
    }
    // Search order: by the nearest candidate's distance (none: last), then as listed.
    const auto nearest = [](const std::vector<Candidate>& list) {
      return list.empty() ? std::numeric_limits<double>::infinity() : list.front().pairing.d2;
    };
    std::stable_sort(candidates_.begin(), candidates_.end(),
                     [&](const auto& a, const auto& b) { return nearest(a) < nearest(b); });
    // gates[k]: the chi-square(2k) quantile, computed once per k over the run
    std::vector<double>& gates = *scan.joint_gates;
    for (std::size_t k = gates.size(); k <= m; ++k) {
      gates.push_back(k == 0 ? 0.0 : chiSquareEvenQuantile(scan.accept_probability, static_cast<int>(k)));
    }
    gates_ = &gates;
  }

  std::vector<int> run(bool* truncated) {
    const std::size_t m = candidates_.size();
    chosen_.assign(m, nullptr);
    best_.assign(m, -1);
    L_ = Eigen::MatrixXd::Zero(2 * static_cast<Eigen::Index>(m), 2 * static_cast<Eigen::Index>(m));
    y_ = Eigen::VectorXd::Zero(2 * static_cast<Eigen::Index>(m));
    recurse(0, 0, 0.0);
    if (truncated) *truncated = truncated_;
    return best_;
  }

 private:
  // Depth-first over observation i with k pairings so far (their factor in L_, y_) and
  // joint distance d2. A node is cut when the rest cannot beat the best hypothesis: fewer
  // pairings, or as many at no smaller distance (pairing more only adds to d2).
  void recurse(std::size_t i, int k, double d2) {
    const std::size_t m = candidates_.size();
    const int most = k + static_cast<int>(m - i);
    if (most < best_pairings_ || (most == best_pairings_ && d2 >= best_d2_)) return;  // offer() would refuse all
    if (nodes_ >= max_nodes_) {
      // The bound: the hypothesis so far (jointly compatible, the rest unpaired) competes
      // with the best found, so even a bound below the depth of one dive answers.
      truncated_ = true;
      offer(k, d2);
      return;
    }
    ++nodes_;
    if (i == m) {
      offer(k, d2);
      return;
    }
    for (const Candidate& c : candidates_[i]) {
      if (used(c.pairing.landmark, i)) continue;
      double d2_new;
      if (!extend(c, k, d2, &d2_new)) continue;
      chosen_[i] = &c;
      recurse(i + 1, k + 1, d2_new);
      chosen_[i] = nullptr;
      if (truncated_) return;
    }
    recurse(i + 1, k, d2);  // observation i unpaired (cut on entry if it cannot beat the best)
  }

  /// The hypothesis in chosen_ (k pairings, joint distance d2) becomes the best if it has
  /// more pairings, or as many at a smaller distance.
  void offer(int k, double d2) {
    if (k > best_pairings_ || (k == best_pairings_ && d2 < best_d2_)) {
      best_pairings_ = k;
      best_d2_ = d2;
      std::fill(best_.begin(), best_.end(), -1);
      for (const Candidate* c : chosen_) {
        if (c) best_[static_cast<std::size_t>(c->pairing.observation)] = c->pairing.landmark;
      }
    }
  }

  bool used(int landmark, std::size_t i) const {
    for (std::size_t o = 0; o < i; ++o) {
      if (chosen_[o] && chosen_[o]->pairing.landmark == landmark) return true;
    }
    return false;
  }

  /// Appends c's block to the factor of S_H (rows 2k, 2k+1) and returns whether the joint
  /// distance d2 + |y_new|^2 passes the chi-square(2(k+1)) gate.
  bool extend(const Candidate& c, int k, double d2, double* d2_new) {
    const Eigen::Index r = 2 * static_cast<Eigen::Index>(k);
    // C = J_c Sigma J_H^T, one 2x2 block per pairing already in H, in the order of L_.
    Eigen::MatrixXd C(2, r);
    Eigen::VectorXd nu_h(r);
    Eigen::Index col = 0;
    for (const Candidate* p : chosen_) {
      if (!p) continue;
      C.middleCols<2>(col) = c.A.leftCols<3>() * p->J_x.transpose() + c.A.middleCols<2>(p->column) * p->J_y.transpose();
      col += 2;
    }
    Mat2 D = c.A.leftCols<3>() * c.J_x.transpose() + c.A.middleCols<2>(c.column) * c.J_y.transpose() + c.R;
    Eigen::Matrix<double, 2, Eigen::Dynamic> L21(2, r);
    if (r > 0) {
      L21 = L_.topLeftCorner(r, r).triangularView<Eigen::Lower>().solve(C.transpose()).transpose();
      D -= L21 * L21.transpose();
    }
    Eigen::LLT<Mat2> llt(0.5 * (D + D.transpose()));
    if (llt.info() != Eigen::Success) return false;
    Vec2 rhs = c.nu;
    if (r > 0) rhs -= L21 * y_.head(r);
    const Vec2 y = llt.matrixL().solve(rhs);
    *d2_new = d2 + y.squaredNorm();
    if (!(*d2_new <= (*gates_)[static_cast<std::size_t>(k + 1)])) return false;
    if (r > 0) L_.block(r, 0, 2, r) = L21;
    L_.block<2, 2>(r, r) = llt.matrixL();
    y_.segment<2>(r) = y;
    return true;
  }

  std::size_t max_nodes_;
  std::vector<std::vector<Candidate>> candidates_;
  const std::vector<double>* gates_ = nullptr;
  std::vector<const Candidate*> chosen_;
  std::vector<int> best_;
  int best_pairings_ = -1;
  double best_d2_ = std::numeric_limits<double>::infinity();
  std::size_t nodes_ = 0;
  bool truncated_ = false;  // the node bound refused a node
  Eigen::MatrixXd L_;
  Eigen::VectorXd y_;
};

}  // namespace

std::vector<int> assignJcbb(const ScanProblem& scan, std::size_t max_nodes, bool* truncated) {
  Search search(scan, max_nodes);
  return search.run(truncated);
}

}  // namespace seif
