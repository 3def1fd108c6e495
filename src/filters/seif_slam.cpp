#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/core/sparse_marginals.hpp>
#include <seif/filters/seif_slam.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <array>

namespace seif {

namespace {
// ESEIF relocalisation (Walter et al. 2007): the largest condition number of z_beta's
// stacked pose information J_x^T R^-1 J_x it accepts.
constexpr double kMaxRelocalizationCondition = 1e6;
constexpr int kRelocalizationIterations = 20;
enum Role : unsigned char { kAlpha, kBeta, kRejected };

bool wellConditioned(const Mat3& A) {
  const Vec3 ev = Eigen::SelfAdjointEigenSolver<Mat3>(A, Eigen::EigenvaluesOnly).eigenvalues();
  return ev(0) > 0.0 && ev(2) < kMaxRelocalizationCondition * ev(0);
}
}  // namespace

SeifOptions::Mean SeifOptions::parseMean(std::string_view s) {
  if (s == "amortized") return Mean::Amortized;
  if (s == "exact") return Mean::Exact;
  throw InvalidArgument("unknown mean recovery '" + std::string(s) +
                              "' (expected amortized or exact)");
}

SeifOptions::Deactivate SeifOptions::parseDeactivate(std::string_view s) {
  if (s == "weakest") return Deactivate::Weakest;
  if (s == "oldest") return Deactivate::Oldest;
  throw InvalidArgument("unknown deactivation rule '" + std::string(s) +
                              "' (expected weakest or oldest)");
}

SeifOptions::Recovery SeifOptions::parseRecovery(std::string_view s) {
  if (s == "after-update") return Recovery::AfterMeasurement;
  if (s == "before-update") return Recovery::BeforeMeasurement;
  throw InvalidArgument("unknown recovery point '" + std::string(s) +
                              "' (expected after-update or before-update)");
}

SeifOptions::RelaxOrder SeifOptions::parseRelaxOrder(std::string_view s) {
  if (s == "random") return RelaxOrder::Random;
  if (s == "cyclic") return RelaxOrder::Cyclic;
  throw InvalidArgument("unknown relaxation order '" + std::string(s) +
                              "' (expected random or cyclic)");
}

SeifOptions::Sparsify SeifOptions::parseSparsify(std::string_view s) {
  if (s == "seif") return Sparsify::Seif;
  if (s == "eseif") return Sparsify::Eseif;
  throw InvalidArgument("unknown sparsification '" + std::string(s) + "' (expected seif or eseif)");
}

SeifOptions::Covariance SeifOptions::parseCovariance(std::string_view s) {
  if (s == "exact") return Covariance::Exact;
  if (s == "local") return Covariance::Local;
  throw InvalidArgument("unknown covariance recovery '" + std::string(s) + "' (expected exact or local)");
}

SeifSlam::SeifSlam(const Pose2& initial_pose, const FilterConfig& config, const SeifOptions& options)
    : SlamFilter(config),
      config_(config),
      book_("seif", initial_pose, config),
      options_(options),
      store_(config.initial_pose_sigma.cwiseAbs2().cwiseInverse().asDiagonal(), initial_pose),
      rng_(options.seed) {
  if (options.max_active < 1 || options.max_active >= kMaxLocalLandmarks) {
    throw InvalidArgument("seif: the number of active landmarks must be in 1.." +
                                std::to_string(kMaxLocalLandmarks - 1));
  }
  if (options.relax < 0) throw InvalidArgument("seif: --relax must be >= 0");
  if (options.eseif_beta < 2) throw InvalidArgument("seif: eseif beta must be >= 2");
  order_.reserve(kMaxLocalLandmarks + 1);
  ranking_.reserve(kMaxLocalLandmarks + 1);
  if (options.sparsify == SeifOptions::Sparsify::Eseif) {
    alpha_.reserve(kMaxLocalLandmarks + 1);
    beta_.reserve(static_cast<std::size_t>(options.max_active));
    beta_slots_.reserve(static_cast<std::size_t>(options.max_active));
    roles_.reserve(kMaxLocalLandmarks + 1);
  }
}

SeifSlam::~SeifSlam() = default;

void SeifSlam::invalidateFactor() { factor_.reset(); }

// ---------------------------------------------------------------- the four steps -------

void SeifSlam::predict(const MotionIncrement& increment) { motionUpdate(increment); }

void SeifSlam::motionUpdate(const MotionIncrement& increment) {
  const MotionIncrement m = book_.motionIncrement(increment, store_.robotMean().head<2>());
  store_.beginStep();
  last_sparsification_residual_ = 0.0;
  // §1: Lemma 3 on the {robot, active} block, the only part of H that motion changes.
  store_.gatherActive();
  workspace_.resize(6, store_.localH().cols());
  informationMotionUpdate(store_.localH(), store_.localB(), store_.localMean(), m.delta, m.J_delta_x, m.U,
                          workspace_);
  store_.scatter();
  invalidateFactor();
}

void SeifSlam::recoverMean() {
  // §2: one block Gauss-Seidel pass over the active landmarks, the robot and K others.
  // In a map much larger than the caches, relaxing a random landmark costs three dependent
  // cache misses (SeifStore::relaxLandmarks). The K landmarks are therefore drawn first (the
  // same draws in the same order: the result is unchanged) and prefetched in chunks, so
  // that their misses overlap instead of adding up: at 10^6 landmarks this phase then takes
  // ~20 % less (it is still the one part of a step whose time grows with the map, through
  // cache and TLB misses).
  constexpr int kChunk = 16;
  std::array<int, kChunk> picks{};
  const int n = store_.size();
  std::uniform_int_distribution<int> pick(0, std::max(0, n - 1));
  // K is capped at the map's size: relaxing a landmark twice in one pass is pointless.
  const int random = std::min(options_.relax, n);
  auto draw = [&](int count) {
    for (int i = 0; i < count; ++i) {
      const int slot = options_.relax_order == SeifOptions::RelaxOrder::Cyclic
                           ? static_cast<int>(relax_cursor_++ % static_cast<std::size_t>(n))
                           : pick(rng_);
      picks[static_cast<std::size_t>(i)] = slot;
      store_.prefetch(slot);
    }
  };
  int chunk = std::min(random, kChunk);
  draw(chunk);
  store_.relaxActive();
  for (int done = 0; done < random;) {
    store_.relaxLandmarks(std::span<const int>(picks.data(), static_cast<std::size_t>(chunk)));
    done += chunk;
    chunk = std::min(random - done, kChunk);
    draw(chunk);
  }
}

void SeifSlam::relaxMean(int sweeps) {
  for (int s = 0; s < sweeps; ++s) {
    store_.relaxRobot();
    for (int i = 0; i < store_.size(); ++i) store_.relaxLandmark(i);
  }
}

void SeifSlam::measurementUpdate(std::span<const Observation> observations, const MeasurementModel& sensor) {
  invalidateFactor();
  // §3, paper eq. (21-22): every observation linearised at the current mean (with FEJ:
  // each landmark's Jacobians at its first estimate, Huang et al. 2010, the FEJ-EKF). A new
  // landmark enters without information at its inverse-model mean; the book leaves gross
  // outliers out.
  const Pose2 x = store_.robotMean();
  const std::span<const PlannedObservation> plan =
      book_.plan(observations, sensor, x, [&](int slot) { return store_.node(slot).mu; });
  for (const PlannedObservation& p : plan) {
    if (p.first) store_.addLandmark(p.z->landmark, p.initial);
    const MeasurementInformation info = measurementInformation(sensor, x, store_.node(p.slot).mu, *p.z,
                                                               sensor.noise(*p.z).inverse(), p.jacobian_landmark);
    store_.addObservation(p.slot, info.H, info.b);  // links it to the robot: active
    // A batch larger than the local block would allow is sparsified as it comes.
    if (static_cast<int>(store_.robotLinks().size()) >= kMaxLocalLandmarks) sparsify();
  }
  book_.commit();
}

void SeifSlam::sparsify() { deactivateSurplus(false); }

void SeifSlam::deactivateSurplus(bool solve_active_mean_first) {
  // §4, paper eq. (44-51): deactivate the surplus Y0, keep Y+.
  const int k = static_cast<int>(store_.robotLinks().size());
  const int drop = k - options_.max_active;
  if (drop <= 0) return;
  if (options_.sparsify == SeifOptions::Sparsify::Eseif) ++eseif_fallbacks_;
  ranking_.clear();
  for (const SeifStore::RobotLink& l : store_.robotLinks()) {
    double score;
    if (options_.deactivate == SeifOptions::Deactivate::Oldest) {
      score = static_cast<double>(l.last_seen);
    } else {  // strength of the link on the normalised information matrix
      const Vec3 dx = store_.robotInformation().diagonal().cwiseSqrt().cwiseInverse();
      const Vec2 dl = store_.node(l.slot).H.diagonal().cwiseSqrt().cwiseInverse();
      score = (dx.asDiagonal() * l.H * dl.asDiagonal()).norm();
    }
    ranking_.emplace_back(score, l.slot);
  }
  std::sort(ranking_.begin(), ranking_.end());  // weakest (or oldest) first
  order_.clear();
  for (int i = drop; i < k; ++i) order_.push_back(ranking_[static_cast<std::size_t>(i)].second);  // Y+
  for (int i = 0; i < drop; ++i) order_.push_back(ranking_[static_cast<std::size_t>(i)].second);  // Y0
  store_.gather(order_);
  if (solve_active_mean_first) store_.solveLocalMean();
  LocalMatrix& H = store_.localH();
  const double residual = sparsifyInformation(H, store_.localB(), store_.localMean(), drop);
  last_sparsification_residual_ = std::max(last_sparsification_residual_, residual);
  const Eigen::Index y0 = H.rows() - 2 * drop;
  H.block(0, y0, 3, 2 * drop).setZero();
  H.block(y0, 0, 2 * drop, 3).setZero();
  store_.scatter();
  invalidateFactor();
  for (int i = 0; i < drop; ++i) store_.removeRobotLink(ranking_[static_cast<std::size_t>(i)].second);
}

void SeifSlam::update(std::span<const Observation> observations, const MeasurementModel& sensor) {
  book_.check(observations, sensor);  // bad input is refused before the state changes
  const bool amortized = options_.mean == SeifOptions::Mean::Amortized;
  const bool book_order = options_.recovery == SeifOptions::Recovery::BeforeMeasurement;
  if (amortized && book_order) recoverMean();
  if (options_.sparsify == SeifOptions::Sparsify::Eseif) {
    eseifUpdate(observations, sensor);
    return;
  }
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

// ---------------------------------------------------------------- ESEIF ---------------

void SeifSlam::eseifUpdate(std::span<const Observation> z, const MeasurementModel& sensor) {
  // Walter, Eustice, Leonard 2007: when z would activate more than max_active landmarks,
  // z_alpha updates the filter (eq. 21-22), the robot is marginalised out and relocalised
  // from z_beta alone. H stays exactly sparse; information is dropped, never invented.
  const bool triggered = exceedsActive(z);
  const bool split = triggered && partitionObservations(z, sensor);
  measurementUpdate(triggered ? std::span<const Observation>(alpha_) : z, sensor);
  bool relocalized = false;
  if (split) {
    relocalized = relocalizeRobot(sensor);
    if (relocalized) {
      ++eseif_relocalizations_;
    } else {
      measurementUpdate(beta_, sensor);  // no pose from z_beta: an ordinary update
    }
  }
  if (options_.mean == SeifOptions::Mean::Exact) {
    recoverExactMean();
  } else if (options_.recovery == SeifOptions::Recovery::AfterMeasurement) {
    recoverMean();
  }
  // Without a relocalisation the surplus stays active until one is possible (measurementUpdate()
  // conditions it away, counted in eseifFallbacks(), only when the local block is full).
  if (static_cast<int>(store_.robotLinks().size()) > options_.max_active) ++eseif_deferrals_;
}

bool SeifSlam::exceedsActive(std::span<const Observation> z) const {
  int active = static_cast<int>(store_.robotLinks().size());
  for (std::size_t i = 0; i < z.size(); ++i) {
    const int slot = book_.find(z[i].landmark);
    if (slot >= 0 && store_.node(slot).active >= 0) continue;
    const bool repeated = std::any_of(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(i),
                                      [&](const Observation& o) { return o.landmark == z[i].landmark; });
    if (!repeated) ++active;
  }
  return active > options_.max_active;
}

bool SeifSlam::partitionObservations(std::span<const Observation> z, const MeasurementModel& sensor) {
  // Candidates for z_beta: observations of mapped landmarks, the best informed (largest
  // trace of H_ll) first. z_beta takes eseif_beta of them, or more until their stacked
  // sum J_x^T R^-1 J_x fixes all three pose dof, well conditioned; at most max_active, so
  // that the relocalised robot's active set is within bounds.
  alpha_.clear();
  beta_.clear();
  beta_slots_.clear();
  ranking_.clear();
  roles_.assign(z.size(), kAlpha);
  for (std::size_t i = 0; i < z.size(); ++i) {
    const int slot = book_.find(z[i].landmark);
    if (slot >= 0) ranking_.emplace_back(-store_.node(slot).H.trace(), static_cast<int>(i));
  }
  std::sort(ranking_.begin(), ranking_.end());
  const auto max_beta = static_cast<std::size_t>(options_.max_active);
  const auto target = std::min(static_cast<std::size_t>(options_.eseif_beta), max_beta);
  const Pose2 x = store_.robotMean();
  Mat3 A = Mat3::Zero();
  bool found = false;
  for (const auto& [score, i] : ranking_) {
    if ((found && beta_.size() >= target) || beta_.size() == max_beta) break;
    const Observation& o = z[static_cast<std::size_t>(i)];
    const int slot = book_.find(o.landmark);
    if (std::find(beta_slots_.begin(), beta_slots_.end(), slot) != beta_slots_.end()) continue;
    const Mat2 Z_inv = sensor.noise(o).inverse();
    if (book_.rejects(sensor, x, store_.node(slot).mu, o)) {
      roles_[static_cast<std::size_t>(i)] = kRejected;
      continue;
    }
    Mat23 J_x;
    sensor.predict(x, store_.node(slot).mu, &J_x);
    A.noalias() += J_x.transpose() * Z_inv * J_x;
    roles_[static_cast<std::size_t>(i)] = kBeta;
    beta_.push_back(o);
    beta_slots_.push_back(slot);
    found = beta_.size() >= 2 && wellConditioned(A);
  }
  for (std::size_t i = 0; i < z.size(); ++i) {
    if (roles_[i] == kAlpha || (roles_[i] == kBeta && !found)) alpha_.push_back(z[i]);
  }
  if (!found) {
    beta_.clear();
    beta_slots_.clear();
  }
  return found;
}

bool SeifSlam::relocalizeRobot(const MeasurementModel& sensor) {
  // The robot's mean given z_alpha (re-solved on the block the marginalisation gathers) is
  // the start of a Gauss-Newton fit of the pose to z_beta and the landmarks' means.
  store_.gatherActive();
  store_.solveLocalMean();
  Pose2 x = store_.robotMean();
  Mat3 A = Mat3::Zero();
  bool converged = false;
  for (int it = 0; it < kRelocalizationIterations && !converged; ++it) {
    A.setZero();
    Vec3 g = Vec3::Zero();
    for (std::size_t k = 0; k < beta_.size(); ++k) {
      Mat23 J_x;
      const Vec2 zhat = sensor.predict(x, store_.node(beta_slots_[k]).mu, &J_x);
      const Eigen::Matrix<double, 3, 2> JtZ = J_x.transpose() * sensor.noise(beta_[k]).inverse();
      A.noalias() += JtZ * J_x;
      g.noalias() += JtZ * sensor.residual(beta_[k].z, zhat);
    }
    const Vec3 dx = A.ldlt().solve(g);
    if (!dx.allFinite()) return false;
    x += dx;
    converged = dx.norm() < 1e-9 * (1.0 + x.head<2>().norm());
  }
  if (!converged || !wellConditioned(A)) return false;
  // Marginalisation: the Schur complement over the robot's Markov blanket, the active set.
  marginalizeRobot(store_.localH(), store_.localB());
  store_.scatter();
  store_.detachRobot(x);
  // Relocalisation: information over (x, m_beta) from z_beta alone, eq. (21-22) at the new
  // pose; the robot is then linked to m_beta only.
  for (std::size_t k = 0; k < beta_.size(); ++k) {
    const int slot = beta_slots_[k];
    const MeasurementInformation info =
        measurementInformation(sensor, x, store_.node(slot).mu, beta_[k], sensor.noise(beta_[k]).inverse());
    store_.addObservation(slot, info.H, info.b);
  }
  invalidateFactor();
  return true;
}

// ---------------------------------------------------------------- removal and merge ---

void SeifSlam::removeLandmark(int id) {
  const int slot = book_.require(id);
  store_.marginalizeLandmark(slot);
  book_.removeSlot(slot);
  invalidateFactor();
  deactivateSurplus(false);
}

void SeifSlam::mergeLandmarks(int keep, int drop) {
  const int k = book_.require(keep), d = book_.require(drop);
  if (k == d) throw InvalidArgument("seif: cannot merge landmark " + std::to_string(keep) + " with itself");
  store_.mergeLandmarks(k, d);
  book_.removeSlot(d);
  invalidateFactor();
  const int kept = book_.find(keep);  // keep may have moved into d's slot
  if (options_.mean == SeifOptions::Mean::Exact) {
    recoverExactMean();
  } else {
    store_.relaxLandmark(kept);
  }
  deactivateSurplus(false);
}

// ---------------------------------------------------------------- reading out ---------

Eigen::VectorXd SeifSlam::mean() const { return store_.mean(); }

const SparseMarginals& SeifSlam::factor() const {
  if (!factor_) {
    try {
      factor_ = std::make_unique<SparseMarginals>(store_.lowerInformation());
    } catch (const NumericError& e) {
      throw NumericError("seif: at step " + std::to_string(store_.step()) + ": " + e.what());
    }
  }
  return *factor_;
}

Eigen::VectorXd SeifSlam::exactMean() const { return factor().solve(informationVector()); }

void SeifSlam::recoverExactMean() { store_.setMean(exactMean()); }

Eigen::MatrixXd SeifSlam::information() const { return Eigen::MatrixXd(sparseInformation()); }

Eigen::MatrixXd SeifSlam::covariance() const {
  const Eigen::MatrixXd H = information();
  Eigen::LLT<Eigen::MatrixXd> llt(H);
  if (llt.info() != Eigen::Success) throw NumericError("seif: information matrix is not positive definite");
  return llt.solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
}

Pose2 SeifSlam::pose() const { return wrapHeading(Pose2(store_.robotMean())); }

Vec2 SeifSlam::landmark(int id) const { return store_.node(book_.require(id)).mu; }

// The marginals are read off the selected inverse of the cached factor (SparseMarginals):
// H stores every robot and landmark diagonal block in full, so each lies in its pattern.
Mat3 SeifSlam::poseCovariance() const {
  if (options_.covariance == SeifOptions::Covariance::Local) return localCovariance({-1});
  return factor().covarianceBlock<3>(0);
}

Mat2 SeifSlam::landmarkCovariance(int id) const {
  const int slot = book_.require(id);
  if (options_.covariance == SeifOptions::Covariance::Local) return localCovariance({slot});
  return factor().covarianceBlock<2>(StateLayout::landmark(slot));
}

Eigen::MatrixXd SeifSlam::localCovariance(std::initializer_list<int> vars) const {
  return localCovariance(std::span<const int>(vars.begin(), vars.size()));
}

Eigen::MatrixXd SeifSlam::localCovariance(std::span<const int> vars) const {
  // The Markov blanket from the store's links: the robot's are the active landmarks; a
  // landmark's are its linked landmarks, and the robot when it is active.
  return localMarginalCovariance(
      vars,
      [&](int v, std::vector<int>& out) {
        if (v < 0) {
          for (const SeifStore::RobotLink& l : store_.robotLinks()) out.push_back(l.slot);
          return;
        }
        if (store_.node(v).active >= 0) out.push_back(-1);
        for (const SeifStore::Link& l : store_.node(v).links) out.push_back(l.slot);
      },
      [&](int a, int c) -> Eigen::MatrixXd {
        if (a < 0 && c < 0) return store_.robotInformation();
        if (a < 0) return store_.robotLinks()[static_cast<std::size_t>(store_.node(c).active)].H;
        if (c < 0) return store_.robotLinks()[static_cast<std::size_t>(store_.node(a).active)].H.transpose();
        if (a == c) return store_.node(a).H;
        return *store_.findLink(a, c);
      },
      "seif (step " + std::to_string(store_.step()) + ")");
}

Marginal SeifSlam::marginal(std::span<const int> landmarks, bool pose, MarginalMode mode) const {
  std::vector<int> vars;
  if (pose) vars.push_back(-1);
  for (int id : landmarks) vars.push_back(book_.require(id));
  Marginal m;
  m.mean.resize(static_cast<Eigen::Index>(pose ? 3 + 2 * landmarks.size() : 2 * landmarks.size()));
  Eigen::Index r = 0;
  for (int v : vars) {
    if (v < 0) {
      m.mean.segment<3>(r) = store_.robotMean();
      r += 3;
    } else {
      m.mean.segment<2>(r) = store_.node(v).mu;
      r += 2;
    }
  }
  if (mode == MarginalMode::Local) {
    m.covariance = localCovariance(vars);
    return m;
  }
  // Exact: one solve with the cached sparse factor per column, H Sigma_{:,i} = e_i.
  const std::vector<Eigen::Index> rows = stateIndices(std::span<const int>(vars).subspan(pose ? 1 : 0), pose);
  m.covariance.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(rows.size()));
  Eigen::VectorXd e = Eigen::VectorXd::Zero(StateLayout::size(store_.size()));
  for (std::size_t k = 0; k < rows.size(); ++k) {
    e.setZero();
    e(rows[k]) = 1.0;
    m.covariance.col(static_cast<Eigen::Index>(k)) = factor().solve(e)(rows);
  }
  return m;
}

Eigen::Matrix<double, Eigen::Dynamic, 2> SeifSlam::landmarkCovarianceColumns(int id) const {
  const int i = StateLayout::landmark(book_.require(id));
  // Two solves with the cached factor: H Sigma_{:,i} = e_i.
  Eigen::VectorXd e = Eigen::VectorXd::Zero(3 + 2 * store_.size());
  Eigen::Matrix<double, Eigen::Dynamic, 2> cols(e.size(), 2);
  for (int c = 0; c < 2; ++c) {
    e.setZero();
    e(i + c) = 1.0;
    cols.col(c) = factor().solve(e);
  }
  return cols;
}

std::vector<int> SeifSlam::activeLandmarks() const {
  std::vector<int> ids;
  for (const SeifStore::RobotLink& l : store_.robotLinks()) ids.push_back(book_.ids()[static_cast<std::size_t>(l.slot)]);
  return ids;
}

FilterStats SeifSlam::stats() const { return store_.stats(); }

}  // namespace seif
