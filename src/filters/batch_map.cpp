#include "filters/batch_map.hpp"

#include "filters/ekf_slam.hpp"
#include "filters/seif_slam.hpp"
#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace seif {

namespace {

FilterConfig innerConfig(const FilterConfig& config) {
  FilterConfig c = config;  // the batch gates; its filter sees only what passed
  c.outlier_gate = std::numeric_limits<double>::infinity();
  return c;
}

std::unique_ptr<SlamFilter> makeInner(const Pose2& start, const FilterConfig& config, BatchOptions::Init init) {
  FilterConfig c = innerConfig(config);
  c.linearization = Linearization::Standard;
  c.iterations = 1;
  switch (init) {
    case BatchOptions::Init::Ekf: return std::make_unique<EkfSlam>(start, c);
    case BatchOptions::Init::Seif: return std::make_unique<SeifSlam>(start, c, SeifOptions{});
    case BatchOptions::Init::Odometry: return nullptr;
  }
  return nullptr;
}

}  // namespace

BatchMap::BatchMap(const Pose2& initial_pose, const FilterConfig& config, const BatchOptions& options)
    : BatchMap(initial_pose, config, makeInner(initial_pose, config, options.init), options) {
  init_name_ = std::string(optionName(options.init));
}

BatchMap::BatchMap(const Pose2& initial_pose, const FilterConfig& config, std::unique_ptr<SlamFilter> filter,
                   const BatchOptions& options)
    : SlamFilter(config),
      config_(config),
      options_(options),
      init_name_(filter ? filter->name() : "odometry"),
      inner_(std::move(filter)),
      book_("batch", initial_pose, inner_ ? config : innerConfig(config)),  // no gate for odometry alone
      steps_{StepPose{0, -1, Vec3::Zero(), Mat3::Zero()}},
      node_step_{0},
      node_guess_{initial_pose},
      guess_(initial_pose) {
  problem_.start = initial_pose;
  problem_.start_covariance = Mat3(config.initial_pose_sigma.cwiseAbs2().asDiagonal());
  problem_.motion = &motionModel();
  problem_.sensor = &sensorModel();
  problem_.nodes = 1;
}

BatchMap::~BatchMap() = default;

void BatchMap::invalidate() {
  solution_.reset();
  covariance_.reset();
}

Pose2 BatchMap::currentGuess() const { return inner_ ? inner_->pose() : guess_; }

Vec2 BatchMap::landmarkGuess(int slot) const {
  if (inner_) return inner_->landmark(book_.ids()[static_cast<std::size_t>(slot)]);
  return landmark_guess_[static_cast<std::size_t>(slot)];
}

int BatchMap::closeSegment() {
  const int k = static_cast<int>(steps_.size()) - 1;
  if (steps_.back().node >= 0) return steps_.back().node;  // already a node
  // the open motion ends here: the pose after step k becomes a node
  const int node = static_cast<int>(node_step_.size());
  BatchProblem::Motion m;
  m.from = node_step_.empty() ? 0 : static_cast<int>(node_step_.size()) - 1;
  m.to = node;
  m.body = pre_.delta();
  m.U_body = pre_.covariance();
  problem_.motions.push_back(m);
  pre_.reset();
  steps_.back() = StepPose{node, -1, Vec3::Zero(), Mat3::Zero()};
  node_step_.push_back(k);
  node_guess_.push_back(currentGuess());
  problem_.nodes = static_cast<int>(node_step_.size());
  return node;
}

void BatchMap::addBodyStep(const Vec3& body, const Mat3& U_body) {
  guess_ = wrapHeading(Pose2(guess_ + poseRotation(guess_(2)) * body));
  pre_.add(body, U_body);
  steps_.push_back({-1, static_cast<int>(problem_.motions.size()), pre_.delta(), pre_.covariance()});
}

void BatchMap::predict(const MotionIncrement& increment) {
  checkIncrement(increment, name());
  const Mat3 Rt = poseRotation(pose()(2)).transpose();  // linearised by the caller at pose()
  invalidate();
  const Vec3 body = Rt * increment.delta;
  const Mat3 U_body = Rt * increment.U * Rt.transpose();
  if (inner_) inner_->predict(increment);
  addBodyStep(body, U_body);
  last_pose_links_ = 0;
}

void BatchMap::predict(const MotionInput& u) {
  invalidate();
  const MotionModel& motion = motionModel();
  if (motion.equivariant()) {  // a motion in the robot's frame, the same at any pose
    const Pose2 at = inner_ ? inner_->linearizationPose() : guess_;
    const MotionIncrement m = motion.linearize(at, u);
    const Mat3 Rt = poseRotation(at(2)).transpose();
    if (inner_) inner_->predict(u);
    addBodyStep(Rt * m.delta, Rt * m.U * Rt.transpose());
  } else {  // its own pose and a factor relinearised at every iteration
    const int from = closeSegment();
    if (inner_) inner_->predict(u);
    guess_ = motion.apply(guess_, u);
    BatchProblem::Motion m;
    m.from = from;
    m.to = static_cast<int>(node_step_.size());
    m.input = u;
    problem_.motions.push_back(m);
    steps_.push_back({m.to, -1, Vec3::Zero(), Mat3::Zero()});
    node_step_.push_back(static_cast<int>(steps_.size()) - 1);
    node_guess_.push_back(currentGuess());
    problem_.nodes = static_cast<int>(node_step_.size());
  }
  last_pose_links_ = 0;
}

void BatchMap::update(std::span<const Observation> observations, const MeasurementModel& sensor) {
  if (&sensor != &sensorModel()) throw ModelError("batch: only the config's sensor is supported");
  // The filter's gate at its estimate (none from odometry alone): a landmark first seen in
  // this update is gated at its initialisation from that first sighting, as the EKF does.
  const std::span<const PlannedObservation> plan =
      book_.plan(observations, sensor, currentGuess(), [&](int slot) { return landmarkGuess(slot); });
  invalidate();
  std::vector<Observation> accepted;
  accepted.reserve(plan.size());
  int node = -1;
  for (const PlannedObservation& p : plan) {
    if (node < 0) node = closeSegment();  // an observation: this pose is kept
    if (p.first) {
      last_linked_node_.push_back(-1);
      pose_links_.push_back(0);
      landmark_guess_.push_back(p.initial);
    }
    const auto s = static_cast<std::size_t>(p.slot);
    if (last_linked_node_[s] != node) {
      last_linked_node_[s] = node;
      ++pose_links_[s];
      ++pose_landmark_links_;
      ++last_pose_links_;
    }
    problem_.measurements.push_back({node, p.slot, p.z->z, sensor.noise(*p.z).inverse()});
    accepted.push_back(*p.z);
  }
  book_.commit();
  problem_.landmarks = book_.size();
  if (inner_) {
    inner_->update(accepted, sensor);
    if (node >= 0) node_guess_[static_cast<std::size_t>(node)] = inner_->pose();
  }
}

void BatchMap::finish() {
  closeSegment();  // the last pose is a node
  std::vector<Vec2> landmarks;
  landmarks.reserve(book_.ids().size());
  for (int s = 0; s < book_.size(); ++s) landmarks.push_back(landmarkGuess(s));
  solve(node_guess_, landmarks);
}

void BatchMap::solve(std::vector<Pose2> nodes, std::vector<Vec2> landmarks) {
  invalidate();
  BatchSolveOptions o;
  o.solver = options_.solver;
  auto sol = std::make_unique<BatchSolution>(solveBatch(problem_, std::move(nodes), std::move(landmarks), o));
  const BatchSolveReport& r = sol->report;
  report_ = SmootherReport{};
  report_.init = init_name_;
  report_.poses = static_cast<int>(sol->nodes.size());
  report_.landmarks = static_cast<int>(sol->landmarks.size());
  report_.constraints = r.constraints;
  report_.iterations = r.iterations;
  report_.converged = r.converged;
  report_.costs = r.costs;
  report_.initial_cost = r.costs.front();
  report_.final_cost = r.costs.back();
  report_.gradient_norm = r.gradient_norm;
  report_.initial_gradient_norm = r.initial_gradient_norm;
  report_.linearize_seconds = r.seconds_linearize;
  report_.factorize_seconds = r.seconds_factorize;
  report_.step_seconds = r.seconds_solve;
  report_.solve_seconds = r.seconds_linearize + r.seconds_factorize + r.seconds_solve;
  report_.factor_nonzeros = r.factor_nonzeros;
  solution_ = std::move(sol);
}

std::vector<Pose2> BatchMap::nodePoses(const std::vector<Pose2>& poses) const {
  std::vector<Pose2> nodes;
  nodes.reserve(node_step_.size() + 1);
  for (int k : node_step_) nodes.push_back(poses[static_cast<std::size_t>(k)]);
  if (steps_.back().node < 0) nodes.push_back(poses.back());  // the open motion's end
  return nodes;
}

void BatchMap::requireSizes(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks) const {
  if (poses.size() != steps_.size() || landmarks.size() != book_.ids().size()) {
    throw InvalidArgument("batch: needs " + std::to_string(steps_.size()) + " poses and " +
                          std::to_string(book_.ids().size()) + " landmarks, got " + std::to_string(poses.size()) +
                          " and " + std::to_string(landmarks.size()));
  }
}

void BatchMap::optimizeFrom(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks) {
  requireSizes(poses, landmarks);
  closeSegment();
  solve(nodePoses(poses), landmarks);
}

double BatchMap::costAt(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks, double* violation) const {
  requireSizes(poses, landmarks);
  if (steps_.back().node < 0) throw InvalidArgument("batch: costAt() needs the last pose kept (call finish())");
  return batchCost(problem_, nodePoses(poses), landmarks, violation);
}

const BatchSolution& BatchMap::solution(const char* what) const {
  if (!solution_) throw InvalidArgument(std::string("batch: ") + what + " needs a solution (call finish())");
  return *solution_;
}

Pose2 BatchMap::bridge(const StepPose& s, const Pose2& xa, const Pose2& xb) const {
  const BatchProblem::Motion& m = problem_.motions[static_cast<std::size_t>(s.motion)];
  const Mat3 Ra = poseRotation(xa(2));
  Vec3 rel_b = Ra.transpose() * (xb - xa);
  Vec3 e_b = rel_b - m.body;
  e_b(2) = wrapAngle(xb(2) - xa(2) - m.body(2));
  const Mat3 T = preintegrationTransition(m.body, s.p);
  const Vec3 e_k = s.P * T.transpose() * noiseWeight(m.U_body) * e_b;
  return wrapHeading(Pose2(xa + Ra * (s.p + e_k)));
}

std::vector<Pose2> BatchMap::smoothedTrajectory() const {
  if (!solution_) return {};
  const std::vector<Pose2>& nodes = solution_->nodes;
  std::vector<Pose2> out;
  out.reserve(steps_.size());
  for (const StepPose& s : steps_) {
    if (s.node >= 0) {
      out.push_back(wrapHeading(nodes[static_cast<std::size_t>(s.node)]));
    } else {
      const BatchProblem::Motion& m = problem_.motions[static_cast<std::size_t>(s.motion)];
      out.push_back(bridge(s, nodes[static_cast<std::size_t>(m.from)], nodes[static_cast<std::size_t>(m.to)]));
    }
  }
  return out;
}

std::vector<Mat3> BatchMap::trajectoryCovariances() const {
  const BatchSolution& sol = solution("trajectoryCovariances()");
  std::vector<Mat3> out;
  out.reserve(steps_.size());
  int joint_motion = -1;  // the motion whose nodes' joint marginal `joint` holds
  Eigen::Matrix<double, 6, 6> joint;
  for (const StepPose& s : steps_) {
    if (s.node >= 0) {
      const Eigen::Index v = 3 * static_cast<Eigen::Index>(s.node);
      out.push_back(sol.marginal({v, v + 1, v + 2}));
      continue;
    }
    const BatchProblem::Motion& m = problem_.motions[static_cast<std::size_t>(s.motion)];
    const Pose2& xa = sol.nodes[static_cast<std::size_t>(m.from)];
    const Pose2& xb = sol.nodes[static_cast<std::size_t>(m.to)];
    if (joint_motion != s.motion) {
      const Eigen::Index a = 3 * static_cast<Eigen::Index>(m.from), b = 3 * static_cast<Eigen::Index>(m.to);
      joint = sol.marginal({a, a + 1, a + 2, b, b + 1, b + 2});
      joint_motion = s.motion;
    }
    // J = d bridge / d(x_a, x_b) by central differences; plus the bridge's own spread.
    Eigen::Matrix<double, 3, 6> J;
    constexpr double h = 1e-6;
    for (int i = 0; i < 6; ++i) {
      Pose2 a1 = xa, a2 = xa, b1 = xb, b2 = xb;
      if (i < 3) {
        a1(i) += h;
        a2(i) -= h;
      } else {
        b1(i - 3) += h;
        b2(i - 3) -= h;
      }
      Vec3 d = bridge(s, a1, b1) - bridge(s, a2, b2);
      d(2) = wrapAngle(d(2));
      J.col(i) = d / (2.0 * h);
    }
    const Mat3 PT = s.P * preintegrationTransition(m.body, s.p).transpose();
    const Mat3 conditional = s.P - PT * noiseWeight(m.U_body) * PT.transpose();
    const Mat3 Ra = poseRotation(xa(2));
    Mat3 S = J * joint * J.transpose() + Ra * conditional * Ra.transpose();
    out.push_back(0.5 * (S + S.transpose()));
  }
  return out;
}

Eigen::Index BatchMap::landmarkVar(int slot) const {
  return 3 * static_cast<Eigen::Index>(solution_->nodes.size()) + 2 * static_cast<Eigen::Index>(slot);
}

Pose2 BatchMap::pose() const {
  if (solution_) return wrapHeading(solution_->nodes.back());
  return currentGuess();
}

Vec2 BatchMap::landmark(int id) const {
  const int slot = book_.require(id);
  if (solution_) return solution_->landmarks[static_cast<std::size_t>(slot)];
  return landmarkGuess(slot);
}

Mat3 BatchMap::poseCovariance() const {
  if (!solution_) {
    if (inner_) return inner_->poseCovariance();
    throw InvalidArgument("batch: odometry alone has no covariance before finish()");
  }
  const Eigen::Index T = 3 * static_cast<Eigen::Index>(solution_->nodes.size() - 1);
  return solution_->marginal({T, T + 1, T + 2});
}

Mat2 BatchMap::landmarkCovariance(int id) const {
  const int slot = book_.require(id);
  if (!solution_) {
    if (inner_) return inner_->landmarkCovariance(id);
    throw InvalidArgument("batch: odometry alone has no covariance before finish()");
  }
  const Eigen::Index l = landmarkVar(slot);
  return solution_->marginal({l, l + 1});
}

void BatchMap::removeLandmark(int) {
  throw InvalidArgument("batch: landmarks cannot be removed from the batch MAP (it keeps every measurement)");
}

void BatchMap::mergeLandmarks(int, int) {
  throw InvalidArgument("batch: landmarks cannot be merged in the batch MAP (it keeps every measurement)");
}

MarginalMode BatchMap::gateMarginal() const {
  return !solution_ && inner_ ? inner_->gateMarginal() : MarginalMode::Exact;
}

Marginal BatchMap::marginal(std::span<const int> landmarks, bool pose, MarginalMode mode) const {
  if (!solution_) {
    if (inner_) return inner_->marginal(landmarks, pose, mode);
    throw InvalidArgument("batch: odometry alone has no marginal before finish()");
  }
  std::vector<Eigen::Index> rows;
  Marginal m;
  m.mean.resize(static_cast<Eigen::Index>(pose ? 3 + 2 * landmarks.size() : 2 * landmarks.size()));
  Eigen::Index r = 0;
  if (pose) {
    const Eigen::Index T = 3 * static_cast<Eigen::Index>(solution_->nodes.size() - 1);
    for (Eigen::Index i = 0; i < 3; ++i) rows.push_back(T + i);
    m.mean.head<3>() = wrapHeading(solution_->nodes.back());
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
  m.covariance = solution_->marginal(rows);
  return m;
}

FilterStats BatchMap::stats() const {
  FilterStats s;
  s.landmarks = book_.ids().size();
  s.links = problem_.motions.size() + (pre_.steps() > 0 ? 1 : 0) + pose_landmark_links_;
  s.robot_links = last_pose_links_;
  for (std::size_t n : pose_links_) s.max_landmark_links = std::max(s.max_landmark_links, n);
  return s;
}

Eigen::VectorXd BatchMap::mean() const {
  if (!solution_) {
    if (inner_) return inner_->mean();
    Eigen::VectorXd mu(3 + 2 * static_cast<Eigen::Index>(book_.size()));
    mu.head<3>() = guess_;
    for (int s = 0; s < book_.size(); ++s) mu.segment<2>(3 + 2 * s) = landmark_guess_[static_cast<std::size_t>(s)];
    return mu;
  }
  Eigen::VectorXd mu(3 + 2 * static_cast<Eigen::Index>(solution_->landmarks.size()));
  mu.head<3>() = wrapHeading(solution_->nodes.back());
  for (std::size_t s = 0; s < solution_->landmarks.size(); ++s) {
    mu.segment<2>(3 + 2 * static_cast<Eigen::Index>(s)) = solution_->landmarks[s];
  }
  return mu;
}

Eigen::MatrixXd BatchMap::covariance() const {
  if (!solution_) {
    if (inner_) return inner_->covariance();
    throw InvalidArgument("batch: odometry alone has no covariance before finish()");
  }
  if (!covariance_) {
    std::vector<Eigen::Index> rows;
    const Eigen::Index T = 3 * static_cast<Eigen::Index>(solution_->nodes.size() - 1);
    for (Eigen::Index i = 0; i < 3; ++i) rows.push_back(T + i);
    for (int s = 0; s < book_.size(); ++s) {
      rows.push_back(landmarkVar(s));
      rows.push_back(landmarkVar(s) + 1);
    }
    covariance_ = solution_->marginal(rows);
  }
  return *covariance_;
}

Eigen::MatrixXd BatchMap::information() const {
  if (!solution_ && inner_) return inner_->information();
  const Eigen::MatrixXd P = covariance();
  const Eigen::LLT<Eigen::MatrixXd> llt(P);
  if (llt.info() != Eigen::Success) throw NumericError("batch: the marginal covariance is not positive definite");
  return llt.solve(Eigen::MatrixXd::Identity(P.rows(), P.cols()));
}

}  // namespace seif
