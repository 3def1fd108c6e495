#pragma once
// The batch MAP's least-squares problem over a set of poses ("nodes") and landmarks, and its
// solver. The cost is the negative log-posterior (up to a constant), as chi-square:
//   F = |x_0 - start|^2_{P0^-1} + sum_m |r_m|^2_{U_m^+} + sum_j |z_j - h(x_k(j), y_l(j))|^2_{R_j^-1},
// a motion factor m between nodes a and b either
//   body:  r = Rot(theta_a)^T (x_b - x_a) - B,  U = U_B   (a motion in the robot's frame, e.g.
//          several steps preintegrated: preintegration.hpp; the same cost as x_b - x_a - Rot B
//          with covariance Rot U_B Rot^T, written in the frame where U_B is constant), or
//   input: r = x_b - x_a - Delta(x_a, u),  U = U(x_a, u)   (a motion model relinearised at x_a,
//          dU/dx by central differences: models that are not equivariant),
// heading wrapped. U may be singular: its range is weighted by U^+, its null space W (the
// eigenvectors of eigenvalues below 1e-9 of the largest) is a hard constraint W^T r = 0. Both forms have det U independent of x_a, so F is
// the exact negative log-likelihood.
//
// Solver: Levenberg-Marquardt on the Gauss-Newton model. Each iteration solves
//   (A + rho C^T C + mu D) delta + C^T lambda = -(g + rho C^T c),   C delta = -c
// (A = J^T Omega J, g = J^T Omega r, c the constraint values, C their Jacobian, D = diag of
// A clamped to [1e-6, 1e32], the largest so far). Without constraints this is the damped normal
// equations on a sparse Cholesky factor (symbolic analysis once per problem). With them, the
// Cholesky path solves the KKT system exactly by Uzawa iterations on the augmented
// Lagrangian's factor (rho makes them converge in a few solves); the KKT path (SparseLU of the
// whole saddle-point matrix) is the cross-check. Damping rule (Nielsen 1999, as Ceres and g2o):
// mu_0 = 1e-8 max diag; a step is accepted when the merit F/2 + nu |c|_1 decreases, then
// mu *= max(1/3, 1 - (2 gain - 1)^3), nu_mult = 2; a rejected step mu *= nu_mult, nu_mult *= 2.
// Near the optimum, where the merit's change is rounding, a step whose predicted gain is below
// 1e-9 relative is taken unless the merit rises by 1e-11 relative. Converged when the
// constraints hold to 1e-10 and the step is below 1e-10 (m, rad) or its predicted gain below
// 1e-15 relative.
#include <seif/core/types.hpp>
#include <seif/filters/batch_options.hpp>
#include <seif/models/measurement_model.hpp>
#include <seif/models/motion_model.hpp>

#include <Eigen/SparseCore>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace seif {

struct BatchProblem {
  struct Motion {
    int from = 0, to = 1;                  ///< node indices
    std::optional<MotionInput> input;      ///< set: relinearised with `motion` (the input form)
    Vec3 body = Vec3::Zero();              ///< the body form's B
    Mat3 U_body = Mat3::Zero();            ///< and U_B
  };
  struct Measurement {
    int node = 0;
    int slot = 0;  ///< landmark index
    Vec2 z = Vec2::Zero();
    Mat2 R_inv = Mat2::Identity();
  };
  Pose2 start = Pose2::Zero();
  Mat3 start_covariance = Mat3::Identity();
  std::vector<Motion> motions;
  std::vector<Measurement> measurements;
  int nodes = 1;
  int landmarks = 0;
  const MotionModel* motion = nullptr;        ///< for input-form factors
  const MeasurementModel* sensor = nullptr;
};

using BatchSolver = BatchOptions::Solver;

struct BatchSolveOptions {
  BatchSolver solver = BatchSolver::Cholesky;
  int max_iterations = 200;
};

/// What a solve did: costs as 0.5 chi-square (GTSAM's error()), times per phase.
struct BatchSolveReport {
  bool converged = false;      ///< false: stopped at max_iterations (the best point so far)
  int iterations = 0;          ///< linear solves (accepted and rejected steps)
  int accepted = 0;
  std::vector<double> costs;   ///< 0.5 F after each accepted step, the start first
  double gradient_norm = 0.0;  ///< |g + C^T lambda|_2 at the solution (0.5 F's gradient, projected)
  double initial_gradient_norm = 0.0;
  double violation = 0.0;      ///< max |c| at the solution
  double seconds_linearize = 0.0, seconds_factorize = 0.0, seconds_solve = 0.0;
  int constraints = 0;
  long factor_nonzeros = 0;
};

class BatchSolution {
 public:
  BatchSolution();
  ~BatchSolution();
  BatchSolution(BatchSolution&&) noexcept;
  BatchSolution& operator=(BatchSolution&&) noexcept;

  std::vector<Pose2> nodes;
  std::vector<Vec2> landmarks;
  BatchSolveReport report;

  /// The joint marginal covariance of variables `rows` (node k: 3k..3k+2; landmark s:
  /// 3 nodes + 2s..): unconstrained, the selected inverse of A at the solution (one sparse
  /// factorisation, the first read costs one pass over the factor's paths); constrained, the
  /// top-left block of the KKT inverse by solves with its LU factor (2 solves per variable).
  Eigen::MatrixXd marginal(const std::vector<Eigen::Index>& rows) const;

 private:
  friend BatchSolution solveBatch(const BatchProblem&, std::vector<Pose2>, std::vector<Vec2>, const BatchSolveOptions&);
  struct Covariance;
  std::unique_ptr<Covariance> covariance_;
};

/// U^+ with the solver's rank tolerance: the weight of a motion residual whose covariance is
/// U (its null space is held by constraints, not weighted).
Mat3 noiseWeight(const Mat3& U);

/// F (chi-square) at (nodes, landmarks), and in `violation` max |W^T r|. Throws ModelError
/// from the sensor for a degenerate geometry.
double batchCost(const BatchProblem& problem, const std::vector<Pose2>& nodes, const std::vector<Vec2>& landmarks,
                 double* violation = nullptr);

/// Levenberg-Marquardt from (nodes, landmarks); after max_iterations the best point so far,
/// with report.converged false. Throws NumericError when no step decreases the merit or a
/// factorisation fails.
BatchSolution solveBatch(const BatchProblem& problem, std::vector<Pose2> nodes, std::vector<Vec2> landmarks,
                         const BatchSolveOptions& options = {});

}  // namespace seif
