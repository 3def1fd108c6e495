// The batch MAP's least-squares problem and its Levenberg-Marquardt solver (batch_problem.hpp).
#include "filters/batch_problem.hpp"

#include "core/sparse_marginals.hpp"
#include "filters/preintegration.hpp"
#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace seif {

namespace {

// Eigenvalues of a U below this * its largest are noise-free (constraints): a standard deviation
// under 3e-5 of the largest, whose weight double-precision Gauss-Newton cannot use (Victoria
// Park's preintegrated straight runs reach 1e-15: as weights they stall the solve).
constexpr double kRankTolerance = 1e-9;
constexpr double kStepTolerance = 1e-10;   // max |delta| [m, rad]
constexpr double kFeasible = 1e-10;        // max |W^T r| of a converged solution
constexpr double kMeritStall = 1e-15;      // predicted relative decrease of the merit that ends the solve
constexpr double kFinalSteps = 1e-9;       // predicted relative decrease below which ...
constexpr double kRounding = 1e-11;        // ... a step is taken unless the merit rises by this
constexpr double kDifferenceStep = 1e-5;   // dU/dx of input-form factors [m, rad]
constexpr double kUzawaTolerance = 1e-13;  // max |C delta + c| of a solved KKT step (relative)
constexpr int kUzawaIterations = 200;
// rho / max diag(A + mu D): Uzawa contracts by about 1 / kRho per iteration, and M's condition
// grows by kRho (1e4 made the corridor's KKT factor inexact enough to stop early).
constexpr double kRho = 1e2;
constexpr double kUndamped = 1e-3;         // mu below which a step's multipliers are trusted

using Triplets = std::vector<Eigen::Triplet<double>>;
using Clock = std::chrono::steady_clock;
using SpMat = Eigen::SparseMatrix<double>;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// Every entry of m, zeros included: the matrix's pattern stays the same at every iterate,
/// so that the factorisation's symbolic analysis is done once.
template <typename M>
void addBlock(Triplets& t, Eigen::Index row, Eigen::Index col, const M& m) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    for (Eigen::Index i = 0; i < m.rows(); ++i) t.emplace_back(static_cast<int>(row + i), static_cast<int>(col + j), m(i, j));
  }
}

/// The derivative in theta of poseRotation(theta) (preintegration.hpp).
Mat3 poseRotationDerivative(double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  Mat3 D;
  D << -s, -c, 0, c, -s, 0, 0, 0, 0;
  return D;
}

/// F, the constraints and, if `system`, A, g and C at one point.
struct Linearization {
  double cost = 0.0;       // F (chi-square)
  std::vector<double> c;   // constraint values W^T r
  Eigen::VectorXd g;       // J^T Omega r: the gradient of F / 2
  SpMat A;                 // J^T Omega J
  SpMat C;                 // d c / d x
};

void linearize(const BatchProblem& p, const std::vector<Pose2>& nodes, const std::vector<Vec2>& landmarks,
               Linearization& out, bool system) {
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(nodes.size()) + 2 * static_cast<Eigen::Index>(landmarks.size());
  Triplets A, C;
  if (system) {
    A.reserve(36 * p.motions.size() + 25 * p.measurements.size() + 9);
    out.g = Eigen::VectorXd::Zero(n);
  }
  out.c.clear();
  out.cost = 0.0;

  // A Gaussian term r ~ N(0, cov) on a pose-space residual with Jacobian blocks J_i at
  // variables v_i. cov = V diag(lambda) V^T: weight Omega = V_r diag(1/lambda_r) V_r^T on its
  // range, constraints W^T r = 0 on its null space. When cov depends on the first variable
  // (dcov: its derivatives), the gradient carries -(Omega r)^T dcov (Omega r) / 2 and the
  // constraint rows d(W^T r) = W^T dr - W^T dcov Omega r (from dW = -cov^+ dcov W; exact
  // where W^T r = 0), so that the fixed point is the constrained optimum itself.
  const auto gaussian = [&](const Vec3& r, const Mat3& cov, const std::array<Mat3, 3>* dcov, Eigen::Index v0,
                            const Mat3& J0, Eigen::Index v1, const Mat3& J1) {
    const Eigen::SelfAdjointEigenSolver<Mat3> eig(0.5 * (cov + cov.transpose()));
    const Vec3& eigenvalues = eig.eigenvalues();
    const double tol = kRankTolerance * std::max(eigenvalues.maxCoeff(), 1e-300);
    Mat3 omega = Mat3::Zero();
    std::array<Vec3, 3> null;
    int nulls = 0;
    for (int i = 0; i < 3; ++i) {
      const Vec3 v = eig.eigenvectors().col(i);
      if (eigenvalues(i) > tol) {
        omega += v * v.transpose() / eigenvalues(i);
      } else {
        null[static_cast<std::size_t>(nulls++)] = v;
      }
    }
    const Vec3 omega_r = omega * r;
    out.cost += r.dot(omega_r);
    for (int k = 0; k < nulls; ++k) {
      const Vec3& w = null[static_cast<std::size_t>(k)];
      out.c.push_back(w.dot(r));
      if (!system) continue;
      const auto row = static_cast<Eigen::Index>(out.c.size()) - 1;
      Eigen::Matrix<double, 1, 3> d0 = w.transpose() * J0;
      if (dcov) {
        for (int i = 0; i < 3; ++i) d0(i) -= w.dot((*dcov)[static_cast<std::size_t>(i)] * omega_r);
      }
      addBlock(C, row, v0, d0);
      if (v1 >= 0) addBlock(C, row, v1, Eigen::Matrix<double, 1, 3>(w.transpose() * J1));
    }
    if (!system) return;
    out.g.segment<3>(v0) += J0.transpose() * omega_r;
    addBlock(A, v0, v0, Mat3(J0.transpose() * omega * J0));
    if (v1 >= 0) {
      out.g.segment<3>(v1) += J1.transpose() * omega_r;
      const Mat3 cross = J0.transpose() * omega * J1;
      addBlock(A, v0, v1, cross);
      addBlock(A, v1, v0, Mat3(cross.transpose()));
      addBlock(A, v1, v1, Mat3(J1.transpose() * omega * J1));
    }
    if (dcov) {
      for (int i = 0; i < 3; ++i) out.g(v0 + i) -= 0.5 * omega_r.dot((*dcov)[static_cast<std::size_t>(i)] * omega_r);
    }
  };

  Vec3 r0 = nodes.front() - p.start;
  r0(2) = wrapAngle(r0(2));
  gaussian(r0, p.start_covariance, nullptr, 0, Mat3::Identity(), -1, Mat3::Zero());

  std::array<Mat3, 3> dU;
  for (const BatchProblem::Motion& m : p.motions) {
    const Pose2& xa = nodes[static_cast<std::size_t>(m.from)];
    const Pose2& xb = nodes[static_cast<std::size_t>(m.to)];
    const Eigen::Index va = 3 * static_cast<Eigen::Index>(m.from), vb = 3 * static_cast<Eigen::Index>(m.to);
    if (m.input) {  // r = x_b - x_a - Delta(x_a, u), U(x_a): dU by central differences
      const MotionIncrement inc = p.motion->linearize(xa, *m.input);
      if (system) {
        for (int i = 0; i < 3; ++i) {
          const Vec3 e = kDifferenceStep * Vec3::Unit(i);
          dU[static_cast<std::size_t>(i)] =
              (p.motion->linearize(Pose2(xa + e), *m.input).U - p.motion->linearize(Pose2(xa - e), *m.input).U) /
              (2.0 * kDifferenceStep);
        }
      }
      Vec3 r = xb - xa - inc.delta;
      r(2) = wrapAngle(r(2));
      gaussian(r, inc.U, system ? &dU : nullptr, va, Mat3(-(Mat3::Identity() + inc.J_delta_x)), vb, Mat3::Identity());
      continue;
    }
    // The body form in the frame of x_a, where U_B and its null space are constant:
    //   r = Rot(theta_a)^T (x_b - x_a) - B  (the same cost as x_b - x_a - Rot B weighted by
    //   (Rot U_B Rot^T)^+, and the same constraints), as iSAM's and g2o's odometry factors.
    const Mat3 R = poseRotation(xa(2)), D = poseRotationDerivative(xa(2));
    const Vec3 d = xb - xa;
    Vec3 r = R.transpose() * d - m.body;
    r(2) = wrapAngle(d(2) - m.body(2));
    Mat3 Ja = -R.transpose();
    Ja.col(2) += D.transpose() * d;
    Ja(2, 2) = -1.0;
    gaussian(r, m.U_body, nullptr, va, Ja, vb, Mat3(R.transpose()));
  }

  const Eigen::Index lm0 = 3 * static_cast<Eigen::Index>(nodes.size());
  for (const BatchProblem::Measurement& z : p.measurements) {
    Mat23 Jx;
    Mat2 Jy;
    const Vec2 zhat = p.sensor->predict(nodes[static_cast<std::size_t>(z.node)],
                                        landmarks[static_cast<std::size_t>(z.slot)], &Jx, &Jy);
    const Vec2 r = p.sensor->residual(z.z, zhat);  // dr = -(Jx dx + Jy dy)
    out.cost += r.dot(z.R_inv * r);
    if (!system) continue;
    const Eigen::Index x = 3 * static_cast<Eigen::Index>(z.node);
    const Eigen::Index l = lm0 + 2 * static_cast<Eigen::Index>(z.slot);
    out.g.segment<3>(x) -= Jx.transpose() * z.R_inv * r;
    out.g.segment<2>(l) -= Jy.transpose() * z.R_inv * r;
    const Mat32 xy = Jx.transpose() * z.R_inv * Jy;
    addBlock(A, x, x, Mat3(Jx.transpose() * z.R_inv * Jx));
    addBlock(A, x, l, xy);
    addBlock(A, l, x, Mat23(xy.transpose()));
    addBlock(A, l, l, Mat2(Jy.transpose() * z.R_inv * Jy));
  }
  if (!system) return;
  out.A.resize(n, n);
  out.A.setFromTriplets(A.begin(), A.end());
  out.C.resize(static_cast<Eigen::Index>(out.c.size()), n);
  out.C.setFromTriplets(C.begin(), C.end());
}

Eigen::VectorXd asVector(const std::vector<double>& c) {
  return Eigen::Map<const Eigen::VectorXd>(c.data(), static_cast<Eigen::Index>(c.size()));
}

double maxAbs(const std::vector<double>& c) {
  double m = 0.0;
  for (double v : c) m = std::max(m, std::abs(v));
  return m;
}

double sumAbs(const std::vector<double>& c) {
  double s = 0.0;
  for (double v : c) s += std::abs(v);
  return s;
}

void applyStep(std::vector<Pose2>& nodes, std::vector<Vec2>& landmarks, const Eigen::VectorXd& delta) {
  Eigen::Index i = 0;
  for (Pose2& x : nodes) {
    x = wrapHeading(Pose2(x + delta.segment<3>(i)));
    i += 3;
  }
  for (Vec2& y : landmarks) {
    y += delta.segment<2>(i);
    i += 2;
  }
}

/// Solves [[M, C^T], [C, 0]] [delta; lambda] = [rhs; -c] for one M: by its Cholesky factor and
/// Uzawa iterations on the multipliers (M holds rho C^T C, which makes them contract by about
/// |A| / rho per iteration), or by SparseLU of the whole saddle-point matrix. The symbolic
/// analysis of either is done on the first call.
class StepSolver {
 public:
  explicit StepSolver(BatchSolver kind) : kind_(kind) {}

  /// Factorises M (and the KKT matrix); false when it is not positive definite / singular.
  bool factorize(const SpMat& M, const SpMat& C, double rho) {
    C_ = &C;
    rho_ = rho;
    if (kind_ == BatchSolver::Cholesky || C.rows() == 0) {
      if (analysed_nonzeros_ != M.nonZeros()) {  // once: the pattern is the same at every iterate
        llt_.analyzePattern(M);
        analysed_nonzeros_ = M.nonZeros();
      }
      llt_.factorize(M);
      return llt_.info() == Eigen::Success;
    }
    const Eigen::Index n = M.rows(), m = C.rows();
    Triplets t;
    t.reserve(static_cast<std::size_t>(M.nonZeros() + 2 * C.nonZeros()));
    for (Eigen::Index j = 0; j < n; ++j) {
      for (SpMat::InnerIterator it(M, j); it; ++it) t.emplace_back(static_cast<int>(it.row()), static_cast<int>(j), it.value());
    }
    for (Eigen::Index j = 0; j < C.outerSize(); ++j) {
      for (SpMat::InnerIterator it(C, j); it; ++it) {
        t.emplace_back(static_cast<int>(n + it.row()), static_cast<int>(it.col()), it.value());
        t.emplace_back(static_cast<int>(it.col()), static_cast<int>(n + it.row()), it.value());
      }
    }
    SpMat K(n + m, n + m);
    K.setFromTriplets(t.begin(), t.end());
    if (analysed_nonzeros_ != K.nonZeros()) {
      lu_.analyzePattern(K);
      analysed_nonzeros_ = K.nonZeros();
    }
    lu_.factorize(K);
    return lu_.info() == Eigen::Success;
  }

  /// delta, and the multipliers in `lambda` (its value on entry: the Uzawa start).
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs, const Eigen::VectorXd& c, Eigen::VectorXd& lambda) const {
    const SpMat& C = *C_;
    if (C.rows() == 0) return llt_.solve(rhs);
    if (kind_ == BatchSolver::Kkt) {
      Eigen::VectorXd b(rhs.size() + c.size());
      b << rhs, -c;
      const Eigen::VectorXd x = lu_.solve(b);
      lambda = x.tail(c.size());
      return x.head(rhs.size());
    }
    const double tolerance = kUzawaTolerance * std::max(1.0, c.lpNorm<Eigen::Infinity>());
    Eigen::VectorXd delta;
    for (int it = 0; it < kUzawaIterations; ++it) {
      delta = llt_.solve(rhs - C.transpose() * lambda);
      const Eigen::VectorXd residual = C * delta + c;
      lambda += rho_ * residual;
      if (residual.lpNorm<Eigen::Infinity>() <= tolerance) return delta;
    }
    throw NumericError("batch: the constrained step did not converge (Uzawa iterations)");
  }

  long factorNonZeros() const {
    if (kind_ == BatchSolver::Kkt && C_ && C_->rows() > 0) return static_cast<long>(lu_.nnzL() + lu_.nnzU());
    return static_cast<long>(llt_.matrixL().nestedExpression().nonZeros());
  }

 private:
  BatchSolver kind_;
  double rho_ = 0.0;
  Eigen::Index analysed_nonzeros_ = -1;
  const SpMat* C_ = nullptr;
  Eigen::SimplicialLLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> llt_;
  Eigen::SparseLU<SpMat, Eigen::COLAMDOrdering<int>> lu_;
};

}  // namespace

// ---- the covariance of a solution --------------------------------------------------------

/// Sigma = the top-left block of the KKT inverse at the solution. With M = A + rho C^T C
/// (equal to A on the constraints' null space, positive definite):
///   Sigma = M^-1 - X S^-1 X^T,  X = M^-1 C^T,  S = C X,
/// read from the selected inverse of M (its diagonal blocks and neighbours) or by solves.
/// Built on the first read: M's factorisation, then m solves for X.
struct BatchSolution::Covariance {
  SpMat A_aug, C;
  mutable std::optional<SparseMarginals> M;
  mutable Eigen::MatrixXd X;              // M^-1 C^T (n x m)
  mutable Eigen::LLT<Eigen::MatrixXd> S;  // of C X

  void build() const {
    if (M) return;
    M.emplace(A_aug);  // NumericError when not positive definite
    const Eigen::Index n = A_aug.rows(), m = C.rows();
    if (m == 0) return;
    if (static_cast<double>(n) * static_cast<double>(m) > 2e8) {
      throw NumericError("batch: marginals with " + std::to_string(m) + " constraints on " + std::to_string(n) +
                         " variables need a dense " + std::to_string(n) + " x " + std::to_string(m) +
                         " correction (over 1.6 GB)");
    }
    const Eigen::MatrixXd Ct = Eigen::MatrixXd(C.transpose());
    X.resize(n, m);
    for (Eigen::Index j = 0; j < m; ++j) X.col(j) = M->solve(Ct.col(j));
    S.compute(Eigen::MatrixXd(C * X));
    if (S.info() != Eigen::Success) throw NumericError("batch: the constraints at the solution are not independent");
  }
  double entry(Eigen::Index i, Eigen::Index j) const {
    double v = M->covariance(i, j);
    if (X.cols() > 0) v -= X.row(i).dot(S.solve(X.row(j).transpose()));
    return v;
  }
};

BatchSolution::BatchSolution() = default;
BatchSolution::~BatchSolution() = default;
BatchSolution::BatchSolution(BatchSolution&&) noexcept = default;
BatchSolution& BatchSolution::operator=(BatchSolution&&) noexcept = default;

Eigen::MatrixXd BatchSolution::marginal(const std::vector<Eigen::Index>& rows) const {
  if (!covariance_) throw InvalidArgument("batch: a marginal needs a solution");
  const Covariance& cov = *covariance_;
  cov.build();
  const auto k = static_cast<Eigen::Index>(rows.size());
  Eigen::MatrixXd out(k, k);
  try {  // entries in the factor's pattern (a variable's block, neighbours): selected inversion
    for (Eigen::Index a = 0; a < k; ++a) {
      for (Eigen::Index b = 0; b <= a; ++b) out(a, b) = out(b, a) = cov.entry(rows[static_cast<std::size_t>(a)], rows[static_cast<std::size_t>(b)]);
    }
    return out;
  } catch (const InvalidArgument&) {
  }
  // Otherwise one solve per variable.
  const Eigen::Index n = cov.M->size();
  Eigen::MatrixXd cols(n, k);
  for (Eigen::Index b = 0; b < k; ++b) cols.col(b) = cov.M->solve(Eigen::VectorXd::Unit(n, rows[static_cast<std::size_t>(b)]));
  for (Eigen::Index a = 0; a < k; ++a) out.row(a) = cols.row(rows[static_cast<std::size_t>(a)]);
  if (cov.X.cols() > 0) {
    Eigen::MatrixXd Xr(k, cov.X.cols());
    for (Eigen::Index a = 0; a < k; ++a) Xr.row(a) = cov.X.row(rows[static_cast<std::size_t>(a)]);
    out -= Xr * cov.S.solve(Xr.transpose());
  }
  return 0.5 * (out + out.transpose());
}

Mat3 noiseWeight(const Mat3& U) {
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(0.5 * (U + U.transpose()));
  const double tol = kRankTolerance * std::max(eig.eigenvalues().maxCoeff(), 1e-300);
  Mat3 out = Mat3::Zero();
  for (int i = 0; i < 3; ++i) {
    const Vec3 v = eig.eigenvectors().col(i);
    if (eig.eigenvalues()(i) > tol) out += v * v.transpose() / eig.eigenvalues()(i);
  }
  return out;
}

double batchCost(const BatchProblem& problem, const std::vector<Pose2>& nodes, const std::vector<Vec2>& landmarks,
                 double* violation) {
  Linearization l;
  linearize(problem, nodes, landmarks, l, false);
  if (violation) *violation = maxAbs(l.c);
  return l.cost;
}

BatchSolution solveBatch(const BatchProblem& problem, std::vector<Pose2> nodes, std::vector<Vec2> landmarks,
                         const BatchSolveOptions& options) {
  BatchSolution sol;
  BatchSolveReport& rep = sol.report;
  for (Pose2& x : nodes) x = wrapHeading(x);
  const auto fail = [&](const std::string& what, double cost) {
    std::ostringstream msg;
    msg << "batch: " << what << " (Levenberg-Marquardt iteration " << rep.iterations << ", 0.5 chi2 " << 0.5 * cost << ")";
    throw NumericError(msg.str());
  };

  auto t = Clock::now();
  Linearization lin;
  linearize(problem, nodes, landmarks, lin, true);
  rep.seconds_linearize += secondsSince(t);
  const Eigen::Index n = lin.A.rows();
  const auto m = static_cast<Eigen::Index>(lin.c.size());  // the rank of every U is the same at every iterate
  rep.constraints = static_cast<int>(m);

  // rho (per iteration): far above the curvature of A + mu D, so that Uzawa contracts fast;
  // rho C^T C keeps the constrained directions of the left-hand side positive definite.
  StepSolver solver(options.solver);
  const auto augmented = [&](const Linearization& l, double rho) {
    SpMat M = l.A;
    if (m > 0) M += rho * SpMat(l.C.transpose() * l.C);
    return M;
  };
  const auto rhoFor = [&](const SpMat& A) { return m > 0 ? kRho * std::max(A.diagonal().maxCoeff(), 1e-300) : 0.0; };

  double nu = 0.0;  // exact-penalty weight of |c|_1 in the merit (F/2 + nu |c|_1)
  const auto merit = [&](const Linearization& l) { return 0.5 * l.cost + nu * sumAbs(l.c); };
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(m);
  // Marquardt's scaling: D = diag(A) (not rho C^T C: the constrained directions are fixed by
  // C delta = -c, not damped), kept at its largest so far; mu is dimensionless.
  Eigen::VectorXd diag = lin.A.diagonal().cwiseMax(1e-6).cwiseMin(1e32);
  double mu = 1e-8;
  double mu_growth = 2.0;
  rep.costs.push_back(0.5 * lin.cost);
  rep.initial_gradient_norm = (lin.g).norm();

  bool converged = false;
  while (!converged) {
    if (rep.iterations >= options.max_iterations) break;  // reported: rep.converged stays false
    ++rep.iterations;
    t = Clock::now();
    SpMat Md = lin.A;
    for (Eigen::Index i = 0; i < n; ++i) Md.coeffRef(i, i) += mu * diag(i);
    const double rho = rhoFor(Md);
    if (m > 0) Md += rho * SpMat(lin.C.transpose() * lin.C);
    const bool ok = solver.factorize(Md, lin.C, rho);
    rep.seconds_factorize += secondsSince(t);
    if (!ok) {  // lost positive definiteness to rounding: more damping
      mu *= mu_growth;
      mu_growth *= 2.0;
      if (!std::isfinite(mu) || mu > 1e32) fail("the normal equations cannot be factorised", lin.cost);
      continue;
    }
    t = Clock::now();
    if (static_cast<Eigen::Index>(lin.c.size()) != m) fail("a process noise changed its rank during the solve", lin.cost);
    const Eigen::VectorXd c = asVector(lin.c);
    Eigen::VectorXd g_aug = lin.g;  // of F/2 + rho/2 |c|^2
    if (m > 0) g_aug += rho * (lin.C.transpose() * c);
    Eigen::VectorXd lambda_step = lambda;
    const Eigen::VectorXd delta = solver.solve(-g_aug, c, lambda_step);
    rep.seconds_solve += secondsSince(t);
    if (!delta.allFinite()) fail("the step is not finite", lin.cost);
    // Heavy damping inflates the multipliers (the step's restoration is made expensive): the
    // penalty weight and the Newton curvature take them only from nearly undamped steps.
    const bool undamped = mu <= kUndamped;
    if (m > 0 && undamped) nu = std::max(nu, 2.0 * lambda_step.lpNorm<Eigen::Infinity>());
    const double merit0 = merit(lin);

    // Predicted decrease of the merit under the Gauss-Newton model (the step meets the
    // linearised constraints, so |c|_1 drops to 0 in the model).
    const double predicted = -(lin.g.dot(delta) + 0.5 * delta.dot(lin.A * delta)) + nu * sumAbs(lin.c);
    std::vector<Pose2> trial_nodes = nodes;
    std::vector<Vec2> trial_landmarks = landmarks;
    applyStep(trial_nodes, trial_landmarks, delta);
    Linearization trial;
    bool valid = true;
    t = Clock::now();
    try {
      linearize(problem, trial_nodes, trial_landmarks, trial, false);
    } catch (const ModelError&) {
      valid = false;  // a degenerate measurement geometry: a shorter step
    }
    rep.seconds_linearize += secondsSince(t);
    const double actual = valid ? merit0 - merit(trial) : -1.0;
    const bool tiny = delta.lpNorm<Eigen::Infinity>() < kStepTolerance;
    // Near the optimum the merit's change is rounding (its terms sum to ~1e-13 relative), so
    // a step the model says gains almost nothing is taken unless the merit clearly rises.
    const bool final_steps = predicted <= kFinalSteps * merit0 && actual >= -kRounding * merit0;
    if (valid && (actual > 0.0 || final_steps)) {
      const double gain = predicted > 0.0 ? actual / predicted : 1.0;
      mu *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * gain - 1.0, 3));
      mu_growth = 2.0;
      nodes = std::move(trial_nodes);
      landmarks = std::move(trial_landmarks);
      if (undamped) lambda = lambda_step;
      t = Clock::now();
      linearize(problem, nodes, landmarks, lin, true);
      rep.seconds_linearize += secondsSince(t);
      diag = diag.cwiseMax(lin.A.diagonal().cwiseMax(1e-6).cwiseMin(1e32));
      ++rep.accepted;
      rep.costs.push_back(0.5 * lin.cost);
      const bool feasible = maxAbs(lin.c) < kFeasible;
      converged = feasible && (tiny || predicted <= kMeritStall * merit0);
    } else {
      if (tiny) {  // at the optimum to rounding: the full step changes nothing measurable
        converged = maxAbs(lin.c) < kFeasible;
        if (!converged) fail("the constraints cannot be met", lin.cost);
        break;
      }
      mu *= mu_growth;
      mu_growth *= 2.0;
      if (!std::isfinite(mu) || mu > 1e32) fail("no step decreases the merit function", lin.cost);
    }
  }
  rep.converged = converged;
  rep.violation = maxAbs(lin.c);

  // The gradient of F/2 at the solution, projected on the constraints (minus C^T lambda); the
  // covariance (built when first read) from M = A + rho C^T C, corrected for the constraints.
  Eigen::VectorXd projected = lin.g;
  if (m > 0) {
    // lambda of the KKT conditions g + C^T lambda = 0 in least squares
    const Eigen::VectorXd Cg = lin.C * lin.g;
    const SpMat CCt = lin.C * lin.C.transpose();
    Eigen::SimplicialLDLT<SpMat> ccT(CCt);
    if (ccT.info() == Eigen::Success) projected -= lin.C.transpose() * ccT.solve(Cg);
  }
  rep.gradient_norm = projected.norm();
  sol.covariance_ = std::make_unique<BatchSolution::Covariance>();
  // rho of the order of A: any rho > 0 gives the same Sigma; a large one would only make
  // M^-1 - X S^-1 X^T cancel more digits.
  sol.covariance_->A_aug = augmented(lin, rhoFor(lin.A) / kRho);
  sol.covariance_->C = std::move(lin.C);
  rep.factor_nonzeros = solver.factorNonZeros();
  sol.nodes = std::move(nodes);
  sol.landmarks = std::move(landmarks);
  return sol;
}

}  // namespace seif
