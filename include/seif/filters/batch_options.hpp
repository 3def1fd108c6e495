#pragma once
// The batch MAP smoother's options (filter specs "batch:init=seif,solver=kkt") and the report
// of its solve (SlamFilter::smootherReport(); metrics.json "batch").
#include <string>
#include <string_view>
#include <vector>

namespace seif {

struct BatchOptions {
  /// Where Levenberg-Marquardt starts: the poses and map of a filter run alongside (the EKF
  /// or the SEIF, which also gate the observations), or odometry alone (dead reckoning, each
  /// landmark from its first sighting; no gate).
  enum class Init { Ekf, Seif, Odometry };
  /// The linear solver: the damped normal equations on a sparse Cholesky factor (Uzawa
  /// iterations for the constraints of a singular process noise), or SparseLU of the whole
  /// KKT system (the cross-check).
  enum class Solver { Cholesky, Kkt };
  Init init = Init::Ekf;
  Solver solver = Solver::Cholesky;

  static Init parseInit(std::string_view v);
  static Solver parseSolver(std::string_view v);
};

std::string_view optionName(BatchOptions::Init v);
std::string_view optionName(BatchOptions::Solver v);

/// What a smoother's solve did. Costs are 0.5 chi-square: the sum of squared whitened
/// residuals over two, comparable to GTSAM's NonlinearFactorGraph::error().
struct SmootherReport {
  std::string init;            ///< ekf | seif | odometry, or the filter a --smooth run hands over from
  int poses = 0;               ///< poses solved for (one per observation instant, the start, the end)
  int landmarks = 0;
  int constraints = 0;         ///< noise-free directions held exactly
  bool converged = true;       ///< false: stopped at the iteration limit (200), the best point so far
  int iterations = 0;          ///< linear solves (Levenberg-Marquardt steps tried)
  double initial_cost = 0.0;
  double final_cost = 0.0;
  std::vector<double> costs;   ///< after each accepted step, the start first
  double gradient_norm = 0.0;  ///< |grad 0.5 chi2| at the solution, projected on the constraints
  double initial_gradient_norm = 0.0;
  double solve_seconds = 0.0;  ///< linearise + factorise + solve, all iterations
  double linearize_seconds = 0.0, factorize_seconds = 0.0, step_seconds = 0.0;
  long factor_nonzeros = 0;
};

}  // namespace seif
