#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include "filters/batch_map.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace seif {

namespace {

constexpr int kMaxIterations = 100;
constexpr double kStepTolerance = 1e-10;     // max |delta| [m, rad]
constexpr double kRelativeDecrease = 1e-12;  // of the merit function
constexpr double kRankTolerance = 1e-12;     // eigenvalues below this * lambda_max are noise-free
constexpr int kMaxHalvings = 40;
constexpr double kFeasible = 1e-10;  // max |W^T r| of a converged solution
constexpr double kDifferenceStep = 1e-5;  // for dU/dx [m, rad]
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using Triplets = std::vector<Eigen::Triplet<double>>;

template <typename M>
void addBlock(Triplets& t, Eigen::Index row, Eigen::Index col, const M& m) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    for (Eigen::Index i = 0; i < m.rows(); ++i) {
      if (m(i, j) != 0.0) t.emplace_back(static_cast<int>(row + i), static_cast<int>(col + j), m(i, j));
    }
  }
}

/// x + alpha delta for every pose (heading wrapped) and landmark.
void applyStep(std::vector<Pose2>& poses, std::vector<Vec2>& landmarks, const Eigen::VectorXd& delta, double alpha) {
  Eigen::Index i = 0;
  for (Pose2& x : poses) {
    x = wrapHeading(Pose2(x + alpha * delta.segment<3>(i)));
    i += 3;
  }
  for (Vec2& y : landmarks) {
    y += alpha * delta.segment<2>(i);
    i += 2;
  }
}

}  // namespace

struct BatchMap::System {
  double cost = 0.0;
  Eigen::VectorXd c;  // constraint values W_k^T r_k
  Eigen::SparseMatrix<double> kkt;
  Eigen::VectorXd rhs;  // [-g; -c], g = J^T Omega r
};

struct BatchMap::Solution {
  std::vector<Pose2> poses;
  std::vector<Vec2> landmarks;
  Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu;  // of the KKT matrix
  Eigen::Index dim = 0;                                // KKT dimension (variables + constraints)
  mutable std::optional<Eigen::MatrixXd> covariance;  // of [x_T, landmarks]
};

BatchMap::BatchMap(const Pose2& initial_pose, const FilterConfig& config)
    : SlamFilter(config),
      config_(config),
      start_(initial_pose),
      inner_(initial_pose,
             [&] {
               FilterConfig c = config;  // the batch gates; its EKF sees only what passed
               c.outlier_gate = std::numeric_limits<double>::infinity();
               c.linearization = seif::Linearization::Standard;
               return c;
             }()),
      book_("batch", initial_pose, config),
      guess_{initial_pose},
      cost_(kNaN),
      violation_(kNaN) {}

BatchMap::~BatchMap() = default;

void BatchMap::invalidate() {
  solution_.reset();
  cost_ = kNaN;
  iterations_ = 0;
  violation_ = kNaN;
}

namespace {

/// The planar rotation by theta acting on a pose increment (x, y rotate, heading stays).
Mat3 poseRotation(double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  Mat3 R;
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  return R;
}

/// Its derivative in theta.
Mat3 poseRotationDerivative(double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  Mat3 D;
  D << -s, -c, 0, c, -s, 0, 0, 0, 0;
  return D;
}

}  // namespace

void BatchMap::predict(const MotionIncrement& increment) {
  const Mat3 Rt = poseRotation(inner_.pose()(2)).transpose();
  inner_.predict(increment);
  invalidate();
  inputs_.push_back({std::nullopt, Rt * increment.delta, Rt * increment.U * Rt.transpose()});
  guess_.push_back(inner_.pose());
  last_pose_links_ = 0;
}

void BatchMap::predict(const MotionInput& u) {
  inner_.predict(u);
  invalidate();
  inputs_.push_back({u, Vec3::Zero(), Mat3::Zero()});
  guess_.push_back(inner_.pose());
  last_pose_links_ = 0;
}

void BatchMap::update(std::span<const Observation> observations, const MeasurementModel& sensor) {
  if (&sensor != &sensorModel()) throw ModelError("batch: only the config's sensor is supported");
  // The EKF's gate, at the inner EKF's estimate: a landmark first seen in this update is
  // gated at its initialisation from that first sighting, as the EKF does.
  const std::span<const PlannedObservation> plan = book_.plan(
      observations, sensor, inner_.pose(), [&](int slot) { return inner_.landmark(book_.ids()[static_cast<std::size_t>(slot)]); });
  invalidate();
  const int k = static_cast<int>(guess_.size()) - 1;
  std::vector<Observation> accepted;
  accepted.reserve(plan.size());
  for (const PlannedObservation& p : plan) {
    if (p.first) {
      last_linked_pose_.push_back(-1);
      pose_links_.push_back(0);
    }
    const auto s = static_cast<std::size_t>(p.slot);
    if (last_linked_pose_[s] != k) {
      last_linked_pose_[s] = k;
      ++pose_links_[s];
      ++pose_landmark_links_;
      ++last_pose_links_;
    }
    measurements_.push_back({k, p.slot, p.z->z, sensor.noise(*p.z).inverse()});
    accepted.push_back(*p.z);
  }
  book_.commit();
  inner_.update(accepted, sensor);
  guess_.back() = inner_.pose();
}

void BatchMap::finish() {
  std::vector<Vec2> landmarks;
  landmarks.reserve(book_.ids().size());
  for (int id : book_.ids()) landmarks.push_back(inner_.landmark(id));
  optimizeFrom(guess_, landmarks);
}

Eigen::Index BatchMap::landmarkVar(int slot) const {
  return 3 * static_cast<Eigen::Index>(inputs_.size() + 1) + 2 * static_cast<Eigen::Index>(slot);
}

void BatchMap::linearize(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks,
                         System& out, bool system) const {
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(poses.size()) + 2 * static_cast<Eigen::Index>(landmarks.size());
  Triplets A, C;  // C: constraint rows, numbered from 0
  Eigen::VectorXd g = Eigen::VectorXd::Zero(system ? n : 0);
  std::vector<double> c;
  out.cost = 0.0;

  // A Gaussian term r ~ N(0, cov) on a pose-space residual r with Jacobian blocks J_i (3x3)
  // at variables v_i. cov = V diag(lambda) V^T: weight Omega = V_r diag(1/lambda_r) V_r^T
  // (the pseudo-inverse) on its range, hard constraints W^T r = 0 on its null space W.
  // When cov depends on the first variable (dcov: its derivatives), the gradient carries
  // d(r^T Omega r / 2) = -(Omega r)^T dcov (Omega r) / 2 and the constraint rows
  // d(W^T r) = W^T dr - W^T dcov Omega r (from dW = -cov^+ dcov W; exact where W^T r = 0),
  // so that the fixed point is the constrained optimum itself.
  const auto gaussian = [&](const Vec3& r, const Mat3& cov, const std::array<Mat3, 3>* dcov,
                            std::initializer_list<std::pair<Eigen::Index, Mat3>> J) {
    const Eigen::SelfAdjointEigenSolver<Mat3> eig(0.5 * (cov + cov.transpose()));
    const Vec3& lambda = eig.eigenvalues();
    const double tol = kRankTolerance * std::max(lambda.maxCoeff(), 1e-300);
    Mat3 omega = Mat3::Zero();
    std::vector<Vec3> null;
    for (int i = 0; i < 3; ++i) {
      const Vec3 v = eig.eigenvectors().col(i);
      if (lambda(i) > tol) {
        omega += v * v.transpose() / lambda(i);
      } else {
        null.push_back(v);
      }
    }
    const Vec3 omega_r = omega * r;
    out.cost += r.dot(omega_r);
    for (const Vec3& w : null) {
      c.push_back(w.dot(r));
      if (!system) continue;
      const auto row = static_cast<Eigen::Index>(c.size()) - 1;
      for (const auto& [var, Jv] : J) {
        Eigen::Matrix<double, 1, 3> d = w.transpose() * Jv;
        if (dcov && var == J.begin()->first) {
          for (int i = 0; i < 3; ++i) d(i) -= w.dot((*dcov)[static_cast<std::size_t>(i)] * omega_r);
        }
        addBlock(C, row, var, d);
      }
    }
    if (!system) return;
    for (const auto& [vi, Ji] : J) {
      g.segment<3>(vi) += Ji.transpose() * omega_r;
      for (const auto& [vj, Jj] : J) addBlock(A, vi, vj, Mat3(Ji.transpose() * omega * Jj));
    }
    if (dcov) {
      for (int i = 0; i < 3; ++i) {
        g(J.begin()->first + i) -= 0.5 * omega_r.dot((*dcov)[static_cast<std::size_t>(i)] * omega_r);
      }
    }
  };

  Vec3 r0 = poses.front() - start_;
  r0(2) = wrapAngle(r0(2));
  gaussian(r0, Mat3(config_.initial_pose_sigma.cwiseAbs2().asDiagonal()), nullptr, {{0, Mat3::Identity()}});

  // U_k depends on x_k; the MotionModel gives U, not its derivative: central differences.
  const MotionModel& motion = motionModel();
  std::array<Mat3, 3> dU;
  for (std::size_t k = 0; k < inputs_.size(); ++k) {
    const Motion& step = inputs_[k];
    MotionIncrement m;
    if (step.input) {
      m = motion.linearize(poses[k], *step.input);
      if (system) {
        for (int i = 0; i < 3; ++i) {
          const Vec3 e = kDifferenceStep * Vec3::Unit(i);
          dU[static_cast<std::size_t>(i)] = (motion.linearize(Pose2(poses[k] + e), *step.input).U -
                                             motion.linearize(Pose2(poses[k] - e), *step.input).U) /
                                            (2.0 * kDifferenceStep);
        }
      }
    } else {  // a body-frame motion: Delta = Rot(theta) body, U = Rot U_body Rot^T
      const Mat3 R = poseRotation(poses[k](2)), D = poseRotationDerivative(poses[k](2));
      m.delta = R * step.body;
      m.J_delta_x.col(2) = D * step.body;
      m.U = R * step.U_body * R.transpose();
      dU[0].setZero();
      dU[1].setZero();
      dU[2] = D * step.U_body * R.transpose() + R * step.U_body * D.transpose();
    }
    Vec3 r = poses[k + 1] - poses[k] - m.delta;
    r(2) = wrapAngle(r(2));
    const auto i = 3 * static_cast<Eigen::Index>(k);
    gaussian(r, m.U, system ? &dU : nullptr,
             {{i, Mat3(-(Mat3::Identity() + m.J_delta_x))}, {i + 3, Mat3::Identity()}});
  }

  const MeasurementModel& sensor = sensorModel();
  const Eigen::Index lm0 = 3 * static_cast<Eigen::Index>(poses.size());
  for (const Measurement& z : measurements_) {
    Mat23 Jx;
    Mat2 Jy;
    const Vec2 zhat = sensor.predict(poses[static_cast<std::size_t>(z.pose)],
                                     landmarks[static_cast<std::size_t>(z.slot)], &Jx, &Jy);
    const Vec2 r = sensor.residual(z.z, zhat);  // dr = -(Jx dx + Jy dy)
    out.cost += r.dot(z.R_inv * r);
    if (!system) continue;
    const Eigen::Index p = 3 * static_cast<Eigen::Index>(z.pose);
    const Eigen::Index l = lm0 + 2 * static_cast<Eigen::Index>(z.slot);
    g.segment<3>(p) -= Jx.transpose() * z.R_inv * r;
    g.segment<2>(l) -= Jy.transpose() * z.R_inv * r;
    const Mat32 xy = Jx.transpose() * z.R_inv * Jy;
    addBlock(A, p, p, Mat3(Jx.transpose() * z.R_inv * Jx));
    addBlock(A, p, l, xy);
    addBlock(A, l, p, Mat23(xy.transpose()));
    addBlock(A, l, l, Mat2(Jy.transpose() * z.R_inv * Jy));
  }

  out.c = Eigen::Map<const Eigen::VectorXd>(c.data(), static_cast<Eigen::Index>(c.size()));
  if (!system) return;
  const Eigen::Index m = out.c.size();
  A.reserve(A.size() + 2 * C.size());
  for (const auto& t : C) {
    A.emplace_back(static_cast<int>(n + t.row()), t.col(), t.value());
    A.emplace_back(t.col(), static_cast<int>(n + t.row()), t.value());
  }
  out.kkt.resize(n + m, n + m);
  out.kkt.setFromTriplets(A.begin(), A.end());
  out.rhs.resize(n + m);
  out.rhs << -g, -out.c;
}

void BatchMap::requireSizes(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks) const {
  if (poses.size() != inputs_.size() + 1 || landmarks.size() != book_.ids().size()) {
    throw InvalidArgument("batch: needs " + std::to_string(inputs_.size() + 1) + " poses and " +
                                std::to_string(book_.ids().size()) + " landmarks, got " +
                                std::to_string(poses.size()) + " and " + std::to_string(landmarks.size()));
  }
}

double BatchMap::costAt(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks,
                        double* violation) const {
  requireSizes(poses, landmarks);
  System at;
  linearize(poses, landmarks, at, false);
  if (violation) *violation = at.c.size() > 0 ? at.c.lpNorm<Eigen::Infinity>() : 0.0;
  return at.cost;
}

void BatchMap::optimizeFrom(const std::vector<Pose2>& poses_in, const std::vector<Vec2>& landmarks_in) {
  requireSizes(poses_in, landmarks_in);
  invalidate();
  auto sol = std::make_unique<Solution>();
  std::vector<Pose2>& poses = sol->poses;
  std::vector<Vec2>& landmarks = sol->landmarks;
  poses = poses_in;
  landmarks = landmarks_in;
  for (Pose2& x : poses) x = wrapHeading(x);
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(poses.size()) + 2 * static_cast<Eigen::Index>(landmarks.size());

  const auto fail = [&](const std::string& what, int it, double cost) {
    std::ostringstream msg;
    msg << "batch: " << what << " (Gauss-Newton iteration " << it << ", cost " << cost << ")";
    throw NumericError(msg.str());
  };
  // Merit F + mu |c|_1, an exact penalty for mu > 2 |lambda|_inf (the KKT multipliers are
  // those of F / 2); mu never decreases, so accepted steps decrease one function.
  double mu = 0.0;
  const auto merit = [&](const System& l) { return l.cost + mu * l.c.lpNorm<1>(); };

  System lin;
  linearize(poses, landmarks, lin, true);
  mu = 1e6 * std::max(1.0, lin.cost);
  bool done = false;
  int it = 0;
  for (;;) {
    sol->lu.compute(lin.kkt);
    if (sol->lu.info() != Eigen::Success) fail("the KKT matrix is singular: " + sol->lu.lastErrorMessage(), it, lin.cost);
    if (done) break;
    if (it == kMaxIterations) fail("no convergence", it, lin.cost);
    const Eigen::VectorXd x = sol->lu.solve(lin.rhs);
    ++it;
    const Eigen::VectorXd delta = x.head(n);
    if (!delta.allFinite()) fail("the step is not finite", it, lin.cost);
    if (delta.lpNorm<Eigen::Infinity>() < kStepTolerance) break;
    if (x.size() > n) mu = std::max(mu, 4.0 * x.tail(x.size() - n).lpNorm<Eigen::Infinity>());
    const double merit0 = merit(lin);

    // Step halving until the merit function does not increase.
    std::vector<Pose2> trial_poses;
    std::vector<Vec2> trial_landmarks;
    System trial;
    double alpha = 1.0, merit_full = kNaN;
    bool accepted = false;
    for (int h = 0; h < kMaxHalvings && !accepted; ++h, alpha *= 0.5) {
      trial_poses = poses;
      trial_landmarks = landmarks;
      applyStep(trial_poses, trial_landmarks, delta, alpha);
      try {
        linearize(trial_poses, trial_landmarks, trial, false);
      } catch (const ModelError&) {
        continue;  // a degenerate measurement geometry: a shorter step
      }
      const double m = merit(trial);
      if (h == 0) merit_full = m;
      accepted = m <= merit0;
    }
    if (!accepted) {
      // At the optimum to rounding the full step changes nothing measurable.
      if (std::abs(merit_full - merit0) <= kRelativeDecrease * merit0) break;
      fail("no step decreases the merit function", it, lin.cost);
    }
    poses = std::move(trial_poses);
    landmarks = std::move(trial_landmarks);
    const double cost0 = lin.cost;
    linearize(poses, landmarks, lin, true);
    // Converged when F stalls on the constraint surface (mu |c|_1 is rounding noise there).
    done = merit0 - merit(lin) <= kRelativeDecrease * merit0 ||
           (std::abs(cost0 - lin.cost) <= kRelativeDecrease * cost0 &&
            (lin.c.size() == 0 || lin.c.lpNorm<Eigen::Infinity>() < kFeasible));
  }
  iterations_ = it;
  cost_ = lin.cost;
  violation_ = lin.c.size() > 0 ? lin.c.lpNorm<Eigen::Infinity>() : 0.0;
  sol->dim = lin.kkt.rows();
  solution_ = std::move(sol);
}

const BatchMap::Solution& BatchMap::solution(const char* what) const {
  if (!solution_) throw InvalidArgument(std::string("batch: ") + what + " needs a solution (call finish())");
  return *solution_;
}

std::vector<Pose2> BatchMap::smoothedTrajectory() const {
  return solution_ ? solution_->poses : std::vector<Pose2>{};
}

Eigen::MatrixXd BatchMap::kktMarginal(const std::vector<Eigen::Index>& rows) const {
  // Columns of the KKT inverse by solves with unit right-hand sides, 256 at a time.
  const Solution& s = solution("a marginal");
  const auto m = static_cast<Eigen::Index>(rows.size());
  Eigen::MatrixXd out(m, m);
  constexpr Eigen::Index kChunk = 256;
  for (Eigen::Index j0 = 0; j0 < m; j0 += kChunk) {
    const Eigen::Index w = std::min(kChunk, m - j0);
    Eigen::MatrixXd E = Eigen::MatrixXd::Zero(s.dim, w);
    for (Eigen::Index j = 0; j < w; ++j) E(rows[static_cast<std::size_t>(j0 + j)], j) = 1.0;
    const Eigen::MatrixXd X = s.lu.solve(E);
    for (Eigen::Index i = 0; i < m; ++i) out.row(i).segment(j0, w) = X.row(rows[static_cast<std::size_t>(i)]);
  }
  return 0.5 * (out + out.transpose());
}

std::vector<Mat3> BatchMap::trajectoryCovariances() const {
  const Solution& s = solution("trajectoryCovariances()");
  std::vector<Mat3> out;
  out.reserve(s.poses.size());
  for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(s.poses.size()); ++k) {
    out.push_back(kktMarginal({3 * k, 3 * k + 1, 3 * k + 2}));
  }
  return out;
}

Pose2 BatchMap::pose() const { return solution_ ? wrapHeading(solution_->poses.back()) : inner_.pose(); }

Vec2 BatchMap::landmark(int id) const {
  if (!solution_) return inner_.landmark(id);
  return solution_->landmarks[static_cast<std::size_t>(book_.require(id))];
}

Mat3 BatchMap::poseCovariance() const {
  if (!solution_) return inner_.poseCovariance();
  if (solution_->covariance) return solution_->covariance->topLeftCorner<3, 3>();
  const Eigen::Index T = 3 * static_cast<Eigen::Index>(inputs_.size());
  return kktMarginal({T, T + 1, T + 2});
}

Mat2 BatchMap::landmarkCovariance(int id) const {
  if (!solution_) return inner_.landmarkCovariance(id);
  const int slot = book_.require(id);
  if (solution_->covariance) return solution_->covariance->block<2, 2>(3 + 2 * slot, 3 + 2 * slot);
  const Eigen::Index l = landmarkVar(slot);
  return kktMarginal({l, l + 1});
}

void BatchMap::removeLandmark(int) {
  throw InvalidArgument("batch: landmarks cannot be removed from the batch MAP (it keeps every measurement)");
}

void BatchMap::mergeLandmarks(int, int) {
  throw InvalidArgument("batch: landmarks cannot be merged in the batch MAP (it keeps every measurement)");
}

Marginal BatchMap::marginal(std::span<const int> landmarks, bool pose, MarginalMode mode) const {
  if (!solution_) return inner_.marginal(landmarks, pose, mode);
  std::vector<Eigen::Index> rows;
  Marginal m;
  m.mean.resize(static_cast<Eigen::Index>(pose ? 3 + 2 * landmarks.size() : 2 * landmarks.size()));
  Eigen::Index r = 0;
  if (pose) {
    const Eigen::Index T = 3 * static_cast<Eigen::Index>(inputs_.size());
    for (Eigen::Index i = 0; i < 3; ++i) rows.push_back(T + i);
    m.mean.head<3>() = solution_->poses.back();
    r = 3;
  }
  for (int id : landmarks) {
    const int slot = book_.require(id);
    const Eigen::Index l = landmarkVar(slot);
    rows.push_back(l);
    rows.push_back(l + 1);
    m.mean.segment<2>(r) = solution_->landmarks[static_cast<std::size_t>(slot)];
    r += 2;
  }
  m.covariance = kktMarginal(rows);
  return m;
}

FilterStats BatchMap::stats() const {
  FilterStats s;
  s.landmarks = book_.ids().size();
  s.links = inputs_.size() + pose_landmark_links_;
  s.robot_links = last_pose_links_;
  for (std::size_t n : pose_links_) s.max_landmark_links = std::max(s.max_landmark_links, n);
  return s;
}

Eigen::VectorXd BatchMap::mean() const {
  if (!solution_) return inner_.mean();
  Eigen::VectorXd mu(3 + 2 * static_cast<Eigen::Index>(solution_->landmarks.size()));
  mu.head<3>() = wrapHeading(solution_->poses.back());
  for (std::size_t s = 0; s < solution_->landmarks.size(); ++s) {
    mu.segment<2>(3 + 2 * static_cast<Eigen::Index>(s)) = solution_->landmarks[s];
  }
  return mu;
}

Eigen::MatrixXd BatchMap::covariance() const {
  if (!solution_) return inner_.covariance();
  if (!solution_->covariance) {
    std::vector<Eigen::Index> rows;
    const Eigen::Index T = 3 * static_cast<Eigen::Index>(inputs_.size());
    for (Eigen::Index i = 0; i < 3; ++i) rows.push_back(T + i);
    for (int s = 0; s < book_.size(); ++s) {
      rows.push_back(landmarkVar(s));
      rows.push_back(landmarkVar(s) + 1);
    }
    solution_->covariance = kktMarginal(rows);
  }
  return *solution_->covariance;
}

Eigen::MatrixXd BatchMap::information() const {
  if (!solution_) return inner_.information();
  const Eigen::MatrixXd P = covariance();
  const Eigen::LLT<Eigen::MatrixXd> llt(P);
  if (llt.info() != Eigen::Success) throw NumericError("batch: the marginal covariance is not positive definite");
  return llt.solve(Eigen::MatrixXd::Identity(P.rows(), P.cols()));
}

}  // namespace seif
