#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/core/sparse_marginals.hpp>
#include <seif/filters/seif_slam.hpp>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <sstream>

namespace seif {

SeifOptions::Mean SeifOptions::parseMean(std::string_view s) {
  if (s == "amortized") return Mean::Amortized;
  if (s == "exact") return Mean::Exact;
  throw std::invalid_argument("unknown mean recovery '" + std::string(s) +
                              "' (expected amortized or exact)");
}

SeifOptions::Deactivate SeifOptions::parseDeactivate(std::string_view s) {
  if (s == "weakest") return Deactivate::Weakest;
  if (s == "oldest") return Deactivate::Oldest;
  throw std::invalid_argument("unknown deactivation rule '" + std::string(s) +
                              "' (expected weakest or oldest)");
}

SeifOptions::Recovery SeifOptions::parseRecovery(std::string_view s) {
  if (s == "after-update") return Recovery::AfterMeasurement;
  if (s == "before-update") return Recovery::BeforeMeasurement;
  throw std::invalid_argument("unknown recovery point '" + std::string(s) +
                              "' (expected after-update or before-update)");
}

SeifOptions::RelaxOrder SeifOptions::parseRelaxOrder(std::string_view s) {
  if (s == "random") return RelaxOrder::Random;
  if (s == "cyclic") return RelaxOrder::Cyclic;
  throw std::invalid_argument("unknown relaxation order '" + std::string(s) +
                              "' (expected random or cyclic)");
}


SeifSlam::SeifSlam(const Pose2& initial_pose, const FilterConfig& config, const SeifOptions& options)
    : SlamFilter(config),
      config_(config),
      gate_(config.outlier_gate),
      options_(options),
      H_xx_(config.initial_pose_sigma.cwiseAbs2().cwiseInverse().asDiagonal()),
      mu_x_(initial_pose),
      rng_(options.seed) {
  if (options.max_active < 1 || options.max_active >= kMaxLocalLandmarks) {
    throw std::invalid_argument("seif: the number of active landmarks must be in 1.." +
                                std::to_string(kMaxLocalLandmarks - 1));
  }
  if (options.relax < 0) throw std::invalid_argument("seif: --relax must be >= 0");
  b_x_ = H_xx_ * mu_x_;
  robot_links_.reserve(kMaxLocalLandmarks + 1);
  order_.reserve(kMaxLocalLandmarks + 1);
  ranking_.reserve(kMaxLocalLandmarks + 1);
}

SeifSlam::~SeifSlam() = default;

void SeifSlam::invalidateFactor() { factor_.reset(); }

// ---------------------------------------------------------------- block store ----------

Mat2* SeifSlam::findLink(int a, int c) {
  for (Link& l : nodes_[static_cast<std::size_t>(a)].links) {
    if (l.slot == c) return &l.H;
  }
  return nullptr;
}

void SeifSlam::addToLink(int a, int c, const Mat2& H_ac) {
  if (Mat2* h = findLink(a, c)) {
    *h += H_ac;
    *findLink(c, a) += H_ac.transpose();
    return;
  }
  Node& na = nodes_[static_cast<std::size_t>(a)];
  Node& nc = nodes_[static_cast<std::size_t>(c)];
  na.links.push_back({c, H_ac});
  nc.links.push_back({a, H_ac.transpose()});
  ++landmark_links_;
  max_landmark_links_ = std::max({max_landmark_links_, na.links.size() + (na.active >= 0 ? 1 : 0),
                                  nc.links.size() + (nc.active >= 0 ? 1 : 0)});
}

void SeifSlam::gather(const std::vector<int>& order) {
  const int k = static_cast<int>(order.size());
  const int n = 3 + 2 * k;
  local_H_.setZero(n, n);
  local_b_.resize(n);
  local_mu_.resize(n);
  local_H_.topLeftCorner<3, 3>() = H_xx_;
  local_b_.head<3>() = b_x_;
  local_mu_.head<3>() = mu_x_;
  for (int i = 0; i < k; ++i) {
    Node& node = nodes_[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])];
    const int r = 3 + 2 * i;
    local_H_.block<2, 2>(r, r) = node.H;
    local_b_.segment<2>(r) = node.b;
    local_mu_.segment<2>(r) = node.mu;
    if (node.active >= 0) {
      const Mat32& H_xl = robot_links_[static_cast<std::size_t>(node.active)].H;
      local_H_.block<3, 2>(0, r) = H_xl;
      local_H_.block<2, 3>(r, 0) = H_xl.transpose();
    }
    for (int j = i + 1; j < k; ++j) {
      if (const Mat2* h = findLink(order[static_cast<std::size_t>(i)], order[static_cast<std::size_t>(j)])) {
        const int c = 3 + 2 * j;
        local_H_.block<2, 2>(r, c) = *h;
        local_H_.block<2, 2>(c, r) = h->transpose();
      }
    }
  }
  blocks_touched_ += static_cast<std::size_t>((k + 1) * (k + 1));
}

void SeifSlam::scatter(const std::vector<int>& order) {
  invalidateFactor();  // H and b change
  const int k = static_cast<int>(order.size());
  H_xx_ = local_H_.topLeftCorner<3, 3>();
  b_x_ = local_b_.head<3>();
  mu_x_ = local_mu_.head<3>();
  for (int i = 0; i < k; ++i) {
    const int a = order[static_cast<std::size_t>(i)];
    Node& node = nodes_[static_cast<std::size_t>(a)];
    const int r = 3 + 2 * i;
    node.H = local_H_.block<2, 2>(r, r);
    node.b = local_b_.segment<2>(r);
    node.mu = local_mu_.segment<2>(r);
    if (node.active >= 0) robot_links_[static_cast<std::size_t>(node.active)].H = local_H_.block<3, 2>(0, r);
    for (int j = i + 1; j < k; ++j) {
      const int c = order[static_cast<std::size_t>(j)];
      const Mat2 block = local_H_.block<2, 2>(r, 3 + 2 * j);
      if (Mat2* h = findLink(a, c)) {
        *h = block;
        *findLink(c, a) = block.transpose();
      } else if (block.cwiseAbs().maxCoeff() > 0.0) {
        addToLink(a, c, block);  // motion creates links among the active landmarks (paper fig. 4)
      }
    }
  }
  blocks_touched_ += static_cast<std::size_t>((k + 1) * (k + 1));
}

void SeifSlam::removeRobotLink(int slot) {
  Node& node = nodes_[static_cast<std::size_t>(slot)];
  const std::size_t pos = static_cast<std::size_t>(node.active);
  node.active = -1;
  if (pos + 1 != robot_links_.size()) {
    robot_links_[pos] = robot_links_.back();
    nodes_[static_cast<std::size_t>(robot_links_[pos].slot)].active = static_cast<int>(pos);
  }
  robot_links_.pop_back();
}

// ---------------------------------------------------------------- the four steps -------

void SeifSlam::predict(const MotionIncrement& increment) { motionUpdate(increment); }

void SeifSlam::motionUpdate(const MotionIncrement& m) {
  ++step_;
  blocks_touched_ = 0;
  last_sparsification_residual_ = 0.0;
  // §1: Lemma 3 on the {robot, active} block, the only part of H that motion changes.
  order_.clear();
  for (const RobotLink& l : robot_links_) order_.push_back(l.slot);
  gather(order_);
  const Eigen::Index n = local_H_.rows();
  workspace_.resize(6, n);
  informationMotionUpdate(local_H_, local_b_, local_mu_, m.delta, m.J_delta_x, m.U, workspace_);
  scatter(order_);
}

void SeifSlam::relaxRobot() {
  // eq. (42): mu_x = H_xx^-1 (b_x - sum_l H_xl mu_l)
  Vec3 rhs = b_x_;
  for (const RobotLink& l : robot_links_) rhs.noalias() -= l.H * nodes_[static_cast<std::size_t>(l.slot)].mu;
  Eigen::LLT<Mat3> llt(H_xx_);
  if (llt.info() != Eigen::Success) {
    throw NumericError("seif: robot information block is not positive definite at step " +
                       std::to_string(step_));
  }
  mu_x_ = llt.solve(rhs);
  blocks_touched_ += 1 + robot_links_.size();
}

void SeifSlam::relaxLandmark(int slot) {
  Node& node = nodes_[static_cast<std::size_t>(slot)];
  Vec2 rhs = node.b;
  for (const Link& l : node.links) rhs.noalias() -= l.H * nodes_[static_cast<std::size_t>(l.slot)].mu;
  if (node.active >= 0) {
    rhs.noalias() -= robot_links_[static_cast<std::size_t>(node.active)].H.transpose() * mu_x_;
  }
  Eigen::LLT<Mat2> llt(node.H);
  if (llt.info() != Eigen::Success) {
    std::ostringstream msg;
    msg << "seif: information of landmark " << index_.ids()[static_cast<std::size_t>(slot)]
        << " is not positive definite at step " << step_;
    throw NumericError(msg.str());
  }
  node.mu = llt.solve(rhs);
  blocks_touched_ += 1 + node.links.size() + (node.active >= 0 ? 1 : 0);
}

void SeifSlam::relaxActiveBlock() {
  order_.clear();
  for (const RobotLink& l : robot_links_) order_.push_back(l.slot);
  gather(order_);
  solveGatheredMean();
}

void SeifSlam::solveGatheredMean() {
  // Block Gauss-Seidel on the robot and the active landmarks jointly (eq. 42 with S_i the
  // projection onto {x, Y+}): mu_L = H_LL^-1 (b_L - H_{L,rest} mu_rest). The robot is linked
  // only inside L; each active landmark's links to passive ones move to the right-hand side.
  local_rhs_ = local_b_;
  for (std::size_t i = 0; i < order_.size(); ++i) {
    const Node& node = nodes_[static_cast<std::size_t>(order_[i])];
    for (const Link& l : node.links) {
      const Node& other = nodes_[static_cast<std::size_t>(l.slot)];
      if (other.active < 0) local_rhs_.segment<2>(3 + 2 * static_cast<Eigen::Index>(i)).noalias() -= l.H * other.mu;
    }
    blocks_touched_ += node.links.size();
  }
  Eigen::LLT<LocalMatrix> llt(local_H_);
  if (llt.info() != Eigen::Success) {
    throw NumericError("seif: the information of the robot and its active landmarks is not "
                       "positive definite at step " + std::to_string(step_));
  }
  local_mu_ = llt.solve(local_rhs_);
  mu_x_ = local_mu_.head<3>();
  for (std::size_t i = 0; i < order_.size(); ++i) {
    nodes_[static_cast<std::size_t>(order_[i])].mu = local_mu_.segment<2>(3 + 2 * static_cast<Eigen::Index>(i));
  }
}

void SeifSlam::recoverMean() {
  // §2: one block Gauss-Seidel pass over the active landmarks, the robot and K random others.
  // In a map much larger than the caches, relaxing a random landmark chases three dependent
  // pointers, each a cache miss: its node, its links, its neighbours' means. The K landmarks
  // are therefore drawn first (the same draws in the same order: the result is unchanged)
  // and their memory prefetched in three rounds, so that their misses overlap instead of
  // adding up: at 10^6 landmarks this phase then takes ~20 % less (it is still the one part
  // of a step whose time grows with the map, through cache and TLB misses).
  constexpr int kChunk = 16;
  std::array<int, kChunk> picks{};
  std::uniform_int_distribution<int> pick(0, std::max(0, static_cast<int>(nodes_.size()) - 1));
  // K is capped at the map's size: relaxing a landmark twice in one pass is pointless.
  const int random = std::min(options_.relax, static_cast<int>(nodes_.size()));
  auto nodeAt = [this](int slot) -> const Node& { return nodes_[static_cast<std::size_t>(slot)]; };
  auto draw = [&](int count) {  // round 1: the nodes
    for (int i = 0; i < count; ++i) {
      const int slot = options_.relax_order == SeifOptions::RelaxOrder::Cyclic
                           ? static_cast<int>(relax_cursor_++ % nodes_.size())
                           : pick(rng_);
      picks[static_cast<std::size_t>(i)] = slot;
      const char* node = reinterpret_cast<const char*>(&nodeAt(slot));
      __builtin_prefetch(node);
      __builtin_prefetch(node + sizeof(Node) - 1);
    }
  };
  auto prefetchLinks = [&](int count) {  // rounds 2 and 3: their links, their neighbours
    for (int i = 0; i < count; ++i) {
      const std::vector<Link>& links = nodeAt(picks[static_cast<std::size_t>(i)]).links;
      const char* begin = reinterpret_cast<const char*>(links.data());
      const char* end = reinterpret_cast<const char*>(links.data() + links.size());
      for (const char* p = begin; p < end; p += 64) __builtin_prefetch(p);
    }
    for (int i = 0; i < count; ++i) {
      for (const Link& l : nodeAt(picks[static_cast<std::size_t>(i)]).links) __builtin_prefetch(&nodeAt(l.slot).mu);
    }
  };
  int chunk = std::min(random, kChunk);
  draw(chunk);
  relaxActiveBlock();
  for (int done = 0; done < random;) {
    prefetchLinks(chunk);
    for (int i = 0; i < chunk; ++i) relaxLandmark(picks[static_cast<std::size_t>(i)]);
    done += chunk;
    chunk = std::min(random - done, kChunk);
    draw(chunk);
  }
}

void SeifSlam::relaxMean(int sweeps) {
  for (int s = 0; s < sweeps; ++s) {
    relaxRobot();
    for (int i = 0; i < static_cast<int>(nodes_.size()); ++i) relaxLandmark(i);
  }
}

void SeifSlam::measurementUpdate(std::span<const Observation> observations, const MeasurementModel& sensor) {
  invalidateFactor();
  // §3, paper eq. (21-22): every observation linearised at the current mean.
  for (const Observation& z : observations) {
    requireAssociated(z, "seif");
    const Mat2 Z_inv = sensor.noise(z).inverse();
    int slot = index_.find(z.landmark);
    if (slot < 0) {  // a new landmark: no information yet, mean from the inverse model
      slot = index_.add(z.landmark);
      nodes_.emplace_back();
      nodes_.back().mu = sensor.inverse(mu_x_, z.z);
    } else if (gate_.rejects(sensor, mu_x_, nodes_[static_cast<std::size_t>(slot)].mu, z, Z_inv)) {
      continue;  // a gross outlier (OutlierGate)
    }
    Node& node = nodes_[static_cast<std::size_t>(slot)];
    const MeasurementInformation info = measurementInformation(sensor, mu_x_, node.mu, z, Z_inv);
    H_xx_ += info.H.topLeftCorner<3, 3>();
    b_x_ += info.b.head<3>();
    node.H += info.H.bottomRightCorner<2, 2>();
    node.b += info.b.tail<2>();
    if (node.active < 0) {  // observing a passive landmark activates it
      node.active = static_cast<int>(robot_links_.size());
      robot_links_.push_back({slot, Mat32::Zero(), step_});
      max_landmark_links_ = std::max(max_landmark_links_, node.links.size() + 1);
    }
    RobotLink& link = robot_links_[static_cast<std::size_t>(node.active)];
    link.H += info.H.topRightCorner<3, 2>();
    link.last_seen = step_;
    blocks_touched_ += 3;
    // A batch larger than the local block would allow is sparsified as it comes.
    if (static_cast<int>(robot_links_.size()) >= kMaxLocalLandmarks) sparsify();
  }
}

void SeifSlam::sparsify() { deactivateSurplus(false); }

void SeifSlam::deactivateSurplus(bool solve_active_mean_first) {
  // §4, paper eq. (44-51): deactivate the surplus Y0, keep Y+.
  const int k = static_cast<int>(robot_links_.size());
  const int drop = k - options_.max_active;
  if (drop <= 0) return;
  ranking_.clear();
  for (const RobotLink& l : robot_links_) {
    double score;
    if (options_.deactivate == SeifOptions::Deactivate::Oldest) {
      score = static_cast<double>(l.last_seen);
    } else {  // strength of the link on the normalised information matrix
      const Node& node = nodes_[static_cast<std::size_t>(l.slot)];
      const Vec3 dx = H_xx_.diagonal().cwiseSqrt().cwiseInverse();
      const Vec2 dl = node.H.diagonal().cwiseSqrt().cwiseInverse();
      score = (dx.asDiagonal() * l.H * dl.asDiagonal()).norm();
    }
    ranking_.emplace_back(score, l.slot);
  }
  std::sort(ranking_.begin(), ranking_.end());  // weakest (or oldest) first
  order_.clear();
  for (int i = drop; i < k; ++i) order_.push_back(ranking_[static_cast<std::size_t>(i)].second);  // Y+
  for (int i = 0; i < drop; ++i) order_.push_back(ranking_[static_cast<std::size_t>(i)].second);  // Y0
  gather(order_);
  if (solve_active_mean_first) solveGatheredMean();
  const double residual = sparsifyInformation(local_H_, local_b_, local_mu_, drop);
  last_sparsification_residual_ = std::max(last_sparsification_residual_, residual);
  const Eigen::Index y0 = local_H_.rows() - 2 * drop;
  local_H_.block(0, y0, 3, 2 * drop).setZero();
  local_H_.block(y0, 0, 2 * drop, 3).setZero();
  scatter(order_);
  for (int i = 0; i < drop; ++i) removeRobotLink(ranking_[static_cast<std::size_t>(i)].second);
}

void SeifSlam::update(std::span<const Observation> observations, const MeasurementModel& sensor) {
  const bool amortized = options_.mean == SeifOptions::Mean::Amortized;
  const bool book_order = options_.recovery == SeifOptions::Recovery::BeforeMeasurement;
  if (amortized && book_order) recoverMean();
  measurementUpdate(observations, sensor);
  if (!amortized) {
    recoverExactMean();  // sparsification then keeps this mean exactly
  } else if (!book_order) {
    recoverMean();
  }
  // With the book's order the measurements have just moved the mean of the robot and the
  // active landmarks, and the sparsification's b~ = b + (H~ - H) mu is right only for their
  // exact mean: it re-solves that block first, on the block it gathers anyway.
  deactivateSurplus(amortized && book_order);
}

// ---------------------------------------------------------------- reading out ---------

Eigen::SparseMatrix<double> SeifSlam::sparseInformation() const {
  const int n = 3 + 2 * index_.size();
  std::vector<Eigen::Triplet<double>> t;
  auto addBlock = [&t](int r, int c, const auto& B) {
    for (int i = 0; i < B.rows(); ++i)
      for (int j = 0; j < B.cols(); ++j) t.emplace_back(r + i, c + j, B(i, j));
  };
  addBlock(0, 0, H_xx_);
  for (const RobotLink& l : robot_links_) {
    const int c = LandmarkIndex::stateIndex(l.slot);
    addBlock(0, c, l.H);
    addBlock(c, 0, Mat23(l.H.transpose()));
  }
  for (int s = 0; s < static_cast<int>(nodes_.size()); ++s) {
    const Node& node = nodes_[static_cast<std::size_t>(s)];
    const int r = LandmarkIndex::stateIndex(s);
    addBlock(r, r, node.H);
    for (const Link& l : node.links) addBlock(r, LandmarkIndex::stateIndex(l.slot), l.H);
  }
  Eigen::SparseMatrix<double> H(n, n);
  H.setFromTriplets(t.begin(), t.end());
  return H;
}

Eigen::SparseMatrix<double> SeifSlam::lowerInformation() const {
  // The lower triangle of H in compressed columns, written in place from the block store
  // (no triplets): the one copy of H a factorisation needs, at a third of the peak memory.
  const int n = 3 + 2 * index_.size();
  std::vector<int> count(static_cast<std::size_t>(n), 0);  // entries per column
  count[0] = 3 + 2 * static_cast<int>(robot_links_.size());
  count[1] = 2 + 2 * static_cast<int>(robot_links_.size());
  count[2] = 1 + 2 * static_cast<int>(robot_links_.size());
  for (int s = 0; s < static_cast<int>(nodes_.size()); ++s) {
    int below = 0;
    for (const Link& l : nodes_[static_cast<std::size_t>(s)].links) below += l.slot > s ? 2 : 0;
    count[static_cast<std::size_t>(LandmarkIndex::stateIndex(s))] = 2 + below;
    count[static_cast<std::size_t>(LandmarkIndex::stateIndex(s)) + 1] = 1 + below;
  }
  Eigen::SparseMatrix<double> H(n, n);
  H.reserve(Eigen::Map<const Eigen::VectorXi>(count.data(), n));
  std::vector<std::pair<int, const Mat2*>> below;  // a landmark's links to later slots, sorted
  for (int c = 0; c < 3; ++c) {
    for (int r = c; r < 3; ++r) H.insert(r, c) = H_xx_(r, c);
  }
  // Robot columns: rows of the active landmarks in any order (insert() keeps them sorted).
  for (const RobotLink& l : robot_links_) {
    const int r = LandmarkIndex::stateIndex(l.slot);
    for (int c = 0; c < 3; ++c) {
      H.insert(r, c) = l.H(c, 0);
      H.insert(r + 1, c) = l.H(c, 1);
    }
  }
  for (int s = 0; s < static_cast<int>(nodes_.size()); ++s) {
    const Node& node = nodes_[static_cast<std::size_t>(s)];
    const int c = LandmarkIndex::stateIndex(s);
    below.clear();
    for (const Link& l : node.links) {
      if (l.slot > s) below.emplace_back(l.slot, &l.H);
    }
    std::sort(below.begin(), below.end());
    for (int k = 0; k < 2; ++k) {
      for (int r = k; r < 2; ++r) H.insert(c + r, c + k) = node.H(r, k);
      for (const auto& [slot, block] : below) {
        const int r = LandmarkIndex::stateIndex(slot);
        H.insert(r, c + k) = (*block)(k, 0);  // H_{other, this} = H_{this, other}^T
        H.insert(r + 1, c + k) = (*block)(k, 1);
      }
    }
  }
  H.makeCompressed();
  return H;
}

Eigen::VectorXd SeifSlam::informationVector() const {
  Eigen::VectorXd b(3 + 2 * index_.size());
  b.head<3>() = b_x_;
  for (int s = 0; s < index_.size(); ++s) b.segment<2>(LandmarkIndex::stateIndex(s)) = nodes_[static_cast<std::size_t>(s)].b;
  return b;
}

Eigen::VectorXd SeifSlam::mean() const {
  Eigen::VectorXd mu(3 + 2 * index_.size());
  mu.head<3>() = mu_x_;
  for (int s = 0; s < index_.size(); ++s) mu.segment<2>(LandmarkIndex::stateIndex(s)) = nodes_[static_cast<std::size_t>(s)].mu;
  return mu;
}

const SparseMarginals& SeifSlam::factor() const {
  if (!factor_) {
    try {
      factor_ = std::make_unique<SparseMarginals>(lowerInformation());
    } catch (const NumericError& e) {
      throw NumericError("seif: at step " + std::to_string(step_) + ": " + e.what());
    }
  }
  return *factor_;
}

Eigen::VectorXd SeifSlam::exactMean() const { return factor().solve(informationVector()); }

void SeifSlam::recoverExactMean() {
  const Eigen::VectorXd mu = exactMean();
  mu_x_ = mu.head<3>();
  for (int s = 0; s < index_.size(); ++s) nodes_[static_cast<std::size_t>(s)].mu = mu.segment<2>(LandmarkIndex::stateIndex(s));
}

Eigen::MatrixXd SeifSlam::information() const { return Eigen::MatrixXd(sparseInformation()); }

Eigen::MatrixXd SeifSlam::covariance() const {
  const Eigen::MatrixXd H = information();
  Eigen::LLT<Eigen::MatrixXd> llt(H);
  if (llt.info() != Eigen::Success) throw NumericError("seif: information matrix is not positive definite");
  return llt.solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
}

Pose2 SeifSlam::pose() const { return wrapHeading(Pose2(mu_x_)); }

Vec2 SeifSlam::landmark(int id) const { return nodes_[static_cast<std::size_t>(index_.require(id, "seif"))].mu; }

// The marginals are read off the selected inverse of the cached factor (SparseMarginals):
// H stores every robot and landmark diagonal block in full, so each lies in its pattern.
Mat3 SeifSlam::poseCovariance() const { return factor().covarianceBlock<3>(0); }

Mat2 SeifSlam::landmarkCovariance(int id) const {
  return factor().covarianceBlock<2>(LandmarkIndex::stateIndex(index_.require(id, "seif")));
}

PredictedMeasurement SeifSlam::predictMeasurement(int id, const MeasurementModel& sensor,
                                                 const Mat2& R) const {
  const int slot = index_.require(id, "seif");
  const int i = LandmarkIndex::stateIndex(slot);
  // The landmark's two columns of Sigma (two solves with the cached factor) give its
  // block and its cross-covariance with the pose.
  Eigen::VectorXd e = Eigen::VectorXd::Zero(3 + 2 * index_.size());
  Eigen::Matrix<double, Eigen::Dynamic, 2> cols(e.size(), 2);
  for (int c = 0; c < 2; ++c) {
    e.setZero();
    e(i + c) = 1.0;
    cols.col(c) = factor().solve(e);
  }
  return innovation(sensor, mu_x_, nodes_[static_cast<std::size_t>(slot)].mu, poseCovariance(),
                    cols.topRows<3>(), cols.middleRows<2>(i), R);
}

std::vector<int> SeifSlam::activeLandmarks() const {
  std::vector<int> ids;
  for (const RobotLink& l : robot_links_) ids.push_back(index_.ids()[static_cast<std::size_t>(l.slot)]);
  return ids;
}

FilterStats SeifSlam::stats() const {
  FilterStats s;  // O(1): counters kept by the store
  s.landmarks = nodes_.size();
  s.robot_links = robot_links_.size();
  s.links = s.robot_links + landmark_links_;
  s.max_landmark_links = max_landmark_links_;
  s.blocks_touched = blocks_touched_;
  return s;
}

}  // namespace seif
