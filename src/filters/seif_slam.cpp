#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include "core/sparse_marginals.hpp"
#include "filters/seif_slam.hpp"
#include "filters/option_values.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace seif {


SeifSlam::SeifSlam(const Pose2& initial_pose, const FilterConfig& config, const SeifOptions& options)
    : SlamFilter(config),
      config_(config),
      book_("seif", initial_pose, config),
      options_(options),
      store_(startInformation(config.initial_pose_sigma, "seif").asDiagonal(), initial_pose),
      rng_(options.seed),
      frontier_(options.wildfire, options.relax, kMaxLocalLandmarks) {
  checkFilterOptions("seif", config, &options);  // each range as its spec and flag have it
  if (options.rho > 0.0 && options.sparsify == SeifOptions::Sparsify::Eseif) {
    throw InvalidArgument("seif: rho scales the paper's sparsification; sparsify=eseif conditions nothing away");
  }
  if (options.gauge == SeifOptions::Gauge::Kept && options.sparsify == SeifOptions::Sparsify::Conservative) {
    // The correction moves the robot's information on Y0 onto Y+; measured against the block's
    // local covariance that reads as a large claim, and the scale ran away (10^14 in 100 steps).
    throw InvalidArgument("seif: gauge=kept does not combine with sparsify=conservative (its scale runs away); "
                          "use one of them");
  }
  // The coarse level corrects the amortized mean; mean=exact solves it (coarse unused).
  if (options.coarse == SeifOptions::Coarse::Rigid && options.mean == SeifOptions::Mean::Amortized) {
    store_.enableCoarse();
  }
  if (options_.covariance == SeifOptions::Covariance::Conservative) options_.bounds = true;
  order_.reserve(kMaxLocalLandmarks + 1);
  observed_slots_.reserve(64);
  bound_slots_.reserve(kMaxLocalLandmarks + 1);
  ranking_.reserve(kMaxLocalLandmarks + 1);
  if (options.sparsify == SeifOptions::Sparsify::Eseif) {
    alpha_.reserve(kMaxLocalLandmarks + 1);
    beta_.reserve(static_cast<std::size_t>(options.active));
    beta_slots_.reserve(static_cast<std::size_t>(options.active));
    roles_.reserve(kMaxLocalLandmarks + 1);
  }
}

SeifSlam::~SeifSlam() = default;

void SeifSlam::invalidateFactor() { factor_.reset(); }

// ---------------------------------------------------------------- the four steps -------

void SeifSlam::predict(const MotionIncrement& increment) {
  guarded([&] { motionUpdate(increment); });
}

template <typename Step>
void SeifSlam::guarded(const Step& step) {
  // All or nothing: the store journals what the step changes (O(what it touches)); the
  // book, the counters and the random engine are saved whole. Any exception undoes it.
  const LandmarkBook::Mark book = book_.mark();
  const std::size_t relax_cursor = relax_cursor_, sparsifications = sparsifications_;
  const double residual = last_sparsification_residual_;
  const std::size_t relocalizations = eseif_relocalizations_, deferrals = eseif_deferrals_,
                    fallbacks = eseif_fallbacks_;
  std::optional<std::mt19937_64> rng;
  if (options_.relax_order == SeifOptions::RelaxOrder::Random) rng = rng_;
  const std::optional<MotionIncrement> pending = pending_motion_;
  const std::size_t pending_controls = pending_controls_, controls_since_observation = controls_since_observation_;
  const double information_scale = information_scale_;
  const std::size_t scalings = scalings_;
  const ActiveBlock block = block_;
  store_.beginTransaction();
  frontier_.begin();
  try {
    step();
    store_.settleCoarse();  // between steps every row is in the coarse sums (checkpoints)
  } catch (...) {
    store_.rollbackTransaction();
    frontier_.rollback();
    book_.undo(book);
    relax_cursor_ = relax_cursor;
    sparsifications_ = sparsifications;
    last_sparsification_residual_ = residual;
    eseif_relocalizations_ = relocalizations;
    eseif_deferrals_ = deferrals;
    eseif_fallbacks_ = fallbacks;
    if (rng) rng_ = *rng;
    pending_motion_ = pending;
    pending_controls_ = pending_controls;
    controls_since_observation_ = controls_since_observation;
    information_scale_ = information_scale;
    scalings_ = scalings;
    // The store is as it was; the local block's buffers are not (a Solved block is a state of
    // the store, a Gathered one of the buffers).
    block_ = block == ActiveBlock::Solved ? block : ActiveBlock::Stale;
    invalidateFactor();
    throw;
  }
  store_.commitTransaction();
  frontier_.commit();
}

void SeifSlam::motionUpdate(const MotionIncrement& increment) {
  const MotionIncrement m = book_.motionIncrement(increment, robotMean().head<2>());
  store_.beginStep();
  last_sparsification_residual_ = 0.0;
  if (options_.motion == SeifOptions::Motion::Deferred) {
    (void)invertibleMotionJacobian(m.J_delta_x);  // refused now, not at the next observation
    pending_motion_ = pending_motion_ ? compose(*pending_motion_, m) : m;
    ++pending_controls_;
    ++controls_since_observation_;
    return;
  }
  applyMotion(m);
}

void SeifSlam::applyMotion(const MotionIncrement& m) {
  // §1: Lemma 3 on the {robot, active} block, the only part of H that motion changes.
  store_.gatherActive();
  workspace_.resize(6, store_.localH().cols());
  // The store holds kappa H: the motion noise enters it as U / kappa (informationScale()).
  const Mat3 U = information_scale_ == 1.0 ? m.U : Mat3(m.U / information_scale_);
  informationMotionUpdate(store_.localH(), store_.localB(), store_.localMean(), m.delta, m.J_delta_x, U,
                          workspace_);
  store_.scatter();
  store_.moveRobotAnchor(m.delta.head<2>());  // T(a + d) T(a)^-1 is the standard G (invariant.hpp)
  invalidateFactor();
  // The buffers hold what scatter() wrote. A block Solved before stays solved: the motion
  // carries the residual b - H mu through (informationMotionUpdate), zero on the robot's rows
  // and the passive terms on the landmarks', and moves the robot's mean by delta, so a solve
  // would give the same mean back up to rounding.
  block_ = block_ == ActiveBlock::Solved ? ActiveBlock::Solved : ActiveBlock::Gathered;
}

void SeifSlam::flushMotion() {
  if (!pending_motion_) return;
  const MotionIncrement m = *pending_motion_;
  pending_motion_.reset();
  pending_controls_ = 0;
  applyMotion(m);
}

void SeifSlam::settleMotion() const {
  if (!pending_motion_) return;
  // The one place a query changes the representation (not the posterior): the object is
  // never const itself (makeFilter, load), and a failure leaves it as it was (guarded).
  auto& self = const_cast<SeifSlam&>(*this);
  self.guarded([&] { self.flushMotion(); });
}

Vec3 SeifSlam::robotMean() const {
  return pending_motion_ ? Vec3(store_.robotMean() + pending_motion_->delta) : store_.robotMean();
}

Mat2 SeifSlam::scaledNoiseInverse(const MeasurementModel& sensor, const Observation& z) const {
  const Mat2 R_inv = sensor.noise(z).inverse();
  return information_scale_ == 1.0 ? R_inv : Mat2(information_scale_ * R_inv);  // the store holds kappa H
}

bool SeifSlam::measurementUpdate(std::span<const Observation> observations, const MeasurementModel& sensor) {
  invalidateFactor();
  // §3, paper eq. (21-22): every observation linearised at the current mean (with FEJ:
  // each landmark's Jacobians at its first estimate, Huang et al. 2010, the FEJ-EKF). A new
  // landmark enters without information at its inverse-model mean; the book leaves gross
  // outliers out.
  const Pose2 x = store_.robotMean();
  const std::span<const PlannedObservation> plan =
      book_.plan(observations, sensor, x, [&](int slot) { return store_.mean(slot); });
  // Invariant (update() has re-anchored): the Jacobians' heading lever arm at the anchors.
  const bool invariant = config_.linearization == Linearization::Invariant;
  const std::size_t sparsified = sparsifications_;
  infos_.clear();
  anchors_.clear();
  // The covariance bounds (seif_bounds.hpp): the joint bound of the robot and the observed
  // mapped landmarks before any of the step's information, while it fits a local block.
  const bool bounds = options_.bounds;
  bound_slots_.clear();
  for (const PlannedObservation& p : plan) {
    if (bounds && !p.first && std::find(bound_slots_.begin(), bound_slots_.end(), p.slot) == bound_slots_.end()) {
      bound_slots_.push_back(p.slot);
    }
  }
  const std::size_t known = bound_slots_.size();
  bool tighten = bounds && known < static_cast<std::size_t>(kMaxLocalLandmarks);
  if (tighten) {
    bound_prior_.resize(3 + 2 * static_cast<Eigen::Index>(known), 3 + 2 * static_cast<Eigen::Index>(known));
    tighten = conservativeCovariance(store_, bound_slots_, bound_prior_, bound_ws_);
  }
  for (const PlannedObservation& p : plan) {
    if (p.first) {
      const int slot = store_.addLandmark(p.z->landmark, p.initial);
      if (wildfire()) frontier_.addLandmark(store_.node(slot).mu);
    }
    std::optional<Anchors> anchors;
    if (invariant) anchors = Anchors{store_.robotAnchor(), store_.node(p.slot).anchor};
    const MeasurementInformation info = measurementInformation(sensor, x, store_.mean(p.slot), *p.z,
                                                               scaledNoiseInverse(sensor, *p.z), p.jacobian_landmark,
                                                               anchors, p.constraint);
    // A new landmark's bound from its first observation and the robot's bound now.
    const bool fresh = bounds && p.first;
    const Mat2 bound = fresh ? firstSightingBound(conservativePoseCovariance(store_, bound_ws_), info.H) : Mat2::Zero();
    store_.addObservation(p.slot, info.H, info.b);  // links it to the robot: active
    if (fresh) {
      store_.setBound(p.slot, bound);
      bound_slots_.push_back(p.slot);
    }
    infos_.push_back(info);
    anchors_.push_back(anchors);
    // A batch larger than the local block would allow is sparsified as it comes.
    if (static_cast<int>(store_.robotLinks().size()) >= kMaxLocalLandmarks) sparsify();
  }
  // The iterated update (FilterConfig::iterations): relinearise at the local posterior mean
  // - the robot and the active landmarks solved jointly, the rest held (solveLocalMean) -
  // replacing each observation's information by the new linearisation's, with the same
  // anchors; a first sighting keeps the linearisation that initialised its landmark. Not
  // after a sparsification within the batch (it has conditioned the links the first
  // linearisation made).
  // The block is gathered once: a relinearisation changes only blocks inside it (the robot's,
  // the observed landmarks', their robot links), which addObservationInBlock() applies to the
  // store and the block alike, and the links to the passive landmarks are summed once.
  bool block_gathered = false;
  for (int it = 1; it < config_.iterations && sparsifications_ == sparsified; ++it) {
    if (it == 1) store_.gatherActive();
    store_.solveLocalMean(it == 1 ? SeifStore::Passive::Recompute : SeifStore::Passive::Reuse);
    const Pose2 xi = store_.robotMean();
    for (std::size_t k = 0; k < plan.size(); ++k) {
      const PlannedObservation& p = plan[k];
      if (p.first) continue;
      store_.addObservationInBlock(p.slot, -infos_[k].H, -infos_[k].b);
      infos_[k] = measurementInformation(sensor, xi, store_.mean(p.slot), *p.z, scaledNoiseInverse(sensor, *p.z),
                                         p.jacobian_landmark, anchors_[k], p.constraint);
      store_.addObservationInBlock(p.slot, infos_[k].H, infos_[k].b);
    }
    block_gathered = true;
  }
  // Every bound tightened by the step's information (C^-1 + I)^-1, unless a sparsification
  // within the batch changed the robot's conditional between the prior and the information.
  tighten = tighten && sparsifications_ == sparsified && bound_slots_.size() < static_cast<std::size_t>(kMaxLocalLandmarks);
  if (bounds && config_.iterations > 1 && sparsifications_ == sparsified) {
    // The iterations replaced information that entered before a new landmark's first
    // sighting, so its bound from then may not hold: from the robot's bound now (the new
    // landmark's only link is still the robot).
    const Mat3 C_x = conservativePoseCovariance(store_, bound_ws_);
    for (std::size_t j = known; j < bound_slots_.size(); ++j) {
      Eigen::Matrix<double, 5, 5> I = Eigen::Matrix<double, 5, 5>::Zero();
      for (std::size_t k = 0; k < plan.size(); ++k) {
        if (plan[k].slot == bound_slots_[j]) I += infos_[k].H;
      }
      store_.setBound(bound_slots_[j], firstSightingBound(C_x, I));
    }
  }
  if (tighten) {
    const auto n = 3 + 2 * static_cast<Eigen::Index>(bound_slots_.size());
    bound_added_.setZero(n, n);
    for (std::size_t k = 0; k < plan.size(); ++k) {
      const auto r = 3 + 2 * static_cast<Eigen::Index>(
                             std::find(bound_slots_.begin(), bound_slots_.end(), plan[k].slot) - bound_slots_.begin());
      const Eigen::Matrix<double, 5, 5>& I = infos_[k].H;
      bound_added_.topLeftCorner<3, 3>() += I.topLeftCorner<3, 3>();
      bound_added_.block<3, 2>(0, r) += I.topRightCorner<3, 2>();
      bound_added_.block<2, 3>(r, 0) += I.bottomLeftCorner<2, 3>();
      bound_added_.block<2, 2>(r, r) += I.bottomRightCorner<2, 2>();
    }
    tightenBounds(store_, bound_slots_, bound_prior_, bound_added_);
  }
  book_.commit();
  return block_gathered;
}

void SeifSlam::update(std::span<const Observation> observations, const MeasurementModel& sensor) {
  book_.check(observations, sensor);  // bad input is refused before the state changes
  guarded([&] { applyUpdate(observations, sensor); });
}

void SeifSlam::applyUpdate(std::span<const Observation> observations, const MeasurementModel& sensor) {
  const bool amortized = options_.mean == SeifOptions::Mean::Amortized;
  const bool book_order = options_.recovery == SeifOptions::Recovery::BeforeMeasurement;
  if (options_.motion == SeifOptions::Motion::Deferred) {
    if (observations.empty()) {
      // Nothing observed: the robot's motion stays held; the mean keeps relaxing in the
      // system before it, which has the same posterior but for the robot's motion. The first
      // such update after an observation solves the robot-active block with K landmarks (the
      // book's order relaxes before the measurement: the pose and the active landmarks take
      // the last correction here, not at the next observation; relaxing them one by one
      // instead left MRCLAM's pose NEES at 33 against 21), later ones the robot alone and K
      // landmarks. "First" counts the controls since the observation, not those still held:
      // a query that applied them (settleMotion(), as association's does before each scan)
      // does not make the next empty update solve the block again (on Victoria Park's raw
      // detections that was 6 000 of the 18 000 block solves, 8 % of the filter's work).
      // Invariant: then the robot is re-anchored, as immediate motion re-anchors it (every
      // update, after the relaxation), at its mean before the held controls, so their noise
      // enters at a fresh anchor.
      const ActiveBlock block = std::exchange(block_, ActiveBlock::Stale);
      if (amortized) recoverMean(controls_since_observation_ <= 1, block);
      if (config_.linearization == Linearization::Invariant) {
        store_.reanchorRobot();
        invalidateFactor();  // H changed (a query settles the held motion first anyway)
      }
      return;
    }
    flushMotion();
    controls_since_observation_ = 0;
  }
  // The step's solves of the robot-active block differ only in the rows of the robot and the
  // observed landmarks (motion is in, the relinearisations and sparsification change no
  // other): the rest is factored once (SeifStore::holdFixedPart).
  observed_slots_.clear();
  for (const Observation& z : observations) {
    if (const int slot = book_.find(z.landmark); slot >= 0) observed_slots_.push_back(slot);
  }
  store_.holdFixedPart(observed_slots_);
  const ActiveBlock block = std::exchange(block_, ActiveBlock::Stale);
  if (amortized && book_order) recoverMean(true, block);
  if (config_.linearization == Linearization::Invariant) reanchor(observations);
  if (options_.sparsify == SeifOptions::Sparsify::Eseif) {
    eseifUpdate(observations, sensor);
    return;
  }
  const bool block_gathered = measurementUpdate(observations, sensor);
  if (!amortized) {
    recoverExactMean();  // sparsification then keeps this mean exactly
  } else if (!book_order) {
    recoverMean();
  }
  // With the book's order the measurements have just moved the mean of the robot and the
  // active landmarks, and the sparsification's b~ = b + (H~ - H) mu is right only for their
  // exact mean: it re-solves that block first, on the block it gathers anyway.
  deactivateSurplus(amortized && book_order, -1, amortized && book_order && block_gathered);
}

void SeifSlam::reanchor(std::span<const Observation> observations) {
  // Before any of the step's information enters (SeifStore::reanchorRobot: a change of
  // variables about the running mean). The robot every update; an observed landmark once it
  // has moved more than options.reanchor from its anchor.
  store_.reanchorRobot();
  for (const Observation& z : observations) {
    const int slot = book_.find(z.landmark);
    if (slot >= 0) reanchorIfMoved(slot);
  }
  invalidateFactor();
}

void SeifSlam::reanchorIfMoved(int slot) {
  const SeifStore::Node& n = store_.node(slot);
  if ((store_.mean(slot) - n.anchor).norm() <= options_.reanchor) return;
  // Its neighbours join the robot's links: make room first (the local block is bounded).
  const auto room = [&] {
    return static_cast<int>(store_.robotLinks().size() + n.links.size()) < kMaxLocalLandmarks - 1;
  };
  if (!room()) sparsify();
  if (!room()) return;  // a landmark with more links than a local block holds keeps its anchor
  reanchorLandmark(slot, store_.mean(slot));
}

void SeifSlam::reanchorLandmark(int slot, const Vec2& to) {
  if (options_.bounds) store_.setBound(slot, reanchoredBound(store_, slot, to, bound_ws_));
  store_.reanchorLandmark(slot, to);
  invalidateFactor();
}

// ---------------------------------------------------------------- removal and merge ---

void SeifSlam::removeLandmark(int id) {
  const int slot = book_.require(id);
  settleMotion();
  block_ = ActiveBlock::Stale;
  // An active landmark is deactivated first: marginalised while linked to the robot, it
  // would link the robot to all its neighbours (more than a local block holds, on a dense map).
  if (store_.node(slot).active >= 0) deactivateSurplus(false, slot);
  store_.marginalizeLandmark(slot);
  if (wildfire()) frontier_.removeSlot(slot);  // the last slot moved into its place
  book_.removeSlot(slot);
  invalidateFactor();
  deactivateSurplus(false);
}

void SeifSlam::mergeLandmarks(int keep, int drop) {
  const int k = book_.require(keep), d = book_.require(drop);
  if (k == d) throw InvalidArgument("seif: cannot merge landmark " + std::to_string(keep) + " with itself");
  settleMotion();
  block_ = ActiveBlock::Stale;
  if (config_.linearization == Linearization::Invariant) {
    // One variable, one anchor: one of the two is re-anchored to the other's, which links
    // its neighbours to the robot. When neither fits in a local block even after a
    // sparsification, drop's information is marginalised out instead of merged (exact, but
    // its sightings' information is lost).
    const auto fits = [&](int slot) {
      return static_cast<int>(store_.robotLinks().size() + store_.node(slot).links.size()) < kMaxLocalLandmarks - 1;
    };
    if (!fits(d) && !fits(k)) sparsify();
    if (fits(d)) {
      reanchorLandmark(d, store_.node(k).anchor);
    } else if (fits(k)) {
      reanchorLandmark(k, store_.node(d).anchor);
    } else {
      removeLandmark(drop);
      return;
    }
  }
  // Conditioning on y_keep = y_drop leaves the merged landmark's covariance below either
  // one's: both bounds hold, and so does the tightest point between them.
  const Mat2 bound = tighterBound(store_.node(k).bound, store_.node(d).bound);
  store_.mergeLandmarks(k, d);
  if (wildfire()) frontier_.removeSlot(d);
  book_.removeSlot(d);
  invalidateFactor();
  const int kept = book_.find(keep);  // keep may have moved into d's slot
  if (options_.bounds) store_.setBound(kept, bound);
  if (options_.mean == SeifOptions::Mean::Exact) {
    recoverExactMean();
  } else {
    store_.relaxLandmark(kept, 1.0);  // the merged landmark, once: eq. (42) itself
    // Its neighbours, drop's among them, see a new landmark there: theirs go first.
    if (wildfire()) frontier_.spread(store_, kept);
  }
  deactivateSurplus(false);
}

// ---------------------------------------------------------------- reading out ---------

Eigen::VectorXd SeifSlam::mean() const { return store().mean(); }

const SparseMarginals& SeifSlam::factor() const {
  settleMotion();
  if (!factor_) {
    try {
      factor_ = std::make_unique<SparseMarginals>(store_.lowerInformation());
    } catch (const NumericError& e) {
      throw NumericError("seif: after " + std::to_string(store_.step()) + " motion updates: " + e.what());
    }
  }
  return *factor_;
}


Eigen::MatrixXd SeifSlam::information() const { return Eigen::MatrixXd(sparseInformation()); }

Eigen::MatrixXd SeifSlam::covariance() const {
  const Eigen::MatrixXd H = information();
  Eigen::LLT<Eigen::MatrixXd> llt(H);
  if (llt.info() != Eigen::Success) throw NumericError("seif: information matrix is not positive definite");
  return llt.solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
}

Pose2 SeifSlam::pose() const { return wrapHeading(Pose2(robotMean())); }

Vec2 SeifSlam::landmark(int id) const { return store_.mean(book_.require(id)); }

// The marginals are read off the selected inverse of the cached factor (SparseMarginals):
// H stores every robot and landmark diagonal block in full, so each lies in its pattern.
// Each covariance read from the store (kappa H) is multiplied by kappa (informationScale()).
Mat3 SeifSlam::poseCovariance() const {
  const bool local = options_.covariance != SeifOptions::Covariance::Exact;
  const Mat3 stored = local ? Mat3(localCovariance({-1}, options_.covariance == SeifOptions::Covariance::Conservative))
                            : factor().covarianceBlock<3>(0);
  return information_scale_ * stored;
}

Mat2 SeifSlam::landmarkCovariance(int id) const {
  const int slot = book_.require(id);
  const bool local = options_.covariance != SeifOptions::Covariance::Exact;
  const Mat2 stored = local ? Mat2(localCovariance({slot}, options_.covariance == SeifOptions::Covariance::Conservative))
                            : factor().covarianceBlock<2>(StateLayout::landmark(slot));
  return information_scale_ * stored;
}

Eigen::MatrixXd SeifSlam::localCovariance(std::initializer_list<int> vars, bool conservative) const {
  return localCovariance(std::span<const int>(vars.begin(), vars.size()), conservative);
}

Eigen::MatrixXd SeifSlam::localCovariance(std::span<const int> vars, bool conservative) const {
  settleMotion();
  // The blanket from the store's links: the robot's are the active landmarks; a landmark's
  // are its linked landmarks, and the robot when it is active. Bounded by options_.blanket.
  const Vec3 dx = store_.robotInformation().diagonal();
  const auto dl = [&](int slot) -> Vec2 { return store_.node(slot).H.diagonal(); };
  return localMarginalCovariance(
      vars,
      [&](int v, std::vector<BlanketLink>& out) {
        if (v < 0) {  // H_{x,l}: the robot's side holds the robot-landmark blocks
          for (const SeifStore::RobotLink& l : store_.robotLinks()) {
            out.push_back({l.slot, linkStrength(dx, l.H, dl(l.slot)), l.H.data(), 3});
          }
          return;
        }
        const SeifStore::Node& node = store_.node(v);
        if (node.active >= 0) {
          const Mat32& H = store_.robotLinks()[static_cast<std::size_t>(node.active)].H;
          out.push_back({-1, linkStrength(dx, H, dl(v)), nullptr, 0});
        }
        const Vec2 dv = dl(v);
        for (const SeifStore::Link& l : node.links) out.push_back({l.slot, linkStrength2(dv, l.H.data(), dl(l.slot)), l.H.data(), 2});
      },
      [&](int v) -> Eigen::MatrixXd {
        if (v < 0) return store_.robotInformation();
        return store_.node(v).H;
      },
      "seif (after " + std::to_string(store_.step()) + " motion updates)", static_cast<std::size_t>(options_.blanket),
      conservative ? std::function<Eigen::MatrixXd(int)>([&](int v) -> Eigen::MatrixXd {
        if (v < 0) {  // seif_bounds.hpp
          BoundWorkspace ws;
          return conservativePoseCovariance(store_, ws);
        }
        return store_.node(v).bound;
      })
                   : nullptr);
}

Marginal SeifSlam::marginal(std::span<const int> landmarks, bool pose, MarginalMode mode) const {
  std::vector<int> vars;
  if (pose) vars.push_back(-1);
  for (int id : landmarks) vars.push_back(book_.require(id));
  settleMotion();
  Marginal m;
  m.mean.resize(static_cast<Eigen::Index>(pose ? 3 + 2 * landmarks.size() : 2 * landmarks.size()));
  Eigen::Index r = 0;
  for (int v : vars) {
    if (v < 0) {
      m.mean.segment<3>(r) = store_.robotMean();
      r += 3;
    } else {
      m.mean.segment<2>(r) = store_.mean(v);
      r += 2;
    }
  }
  if (mode == MarginalMode::Local) {
    m.covariance = information_scale_ * localCovariance(vars);
    return m;
  }
  if (mode == MarginalMode::Conservative) {
    requireBounds();
    m.covariance = information_scale_ * localCovariance(vars, true);
    return m;
  }
  // Exact: one solve with the cached sparse factor per column, H Sigma_{:,i} = e_i.
  const std::vector<Eigen::Index> rows = stateIndices(std::span<const int>(vars).subspan(pose ? 1 : 0), pose);
  m.covariance.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(rows.size()));
  Eigen::VectorXd e = Eigen::VectorXd::Zero(StateLayout::size(store_.size()));
  for (std::size_t k = 0; k < rows.size(); ++k) {
    e.setZero();
    e(rows[k]) = 1.0;
    m.covariance.col(static_cast<Eigen::Index>(k)) = information_scale_ * factor().solve(e)(rows);
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
    cols.col(c) = information_scale_ * factor().solve(e);
  }
  return cols;
}

void SeifSlam::requireBounds() const {
  if (!options_.bounds) {
    throw InvalidArgument("seif: conservative marginals need the covariance bounds: seif:bounds=true "
                          "(or covariance=conservative)");
  }
}

void SeifSlam::refreshCovarianceBounds() {
  requireBounds();
  settleMotion();
  const SparseMarginals& f = factor();
  for (int s = 0; s < store_.size(); ++s) store_.setBound(s, f.covarianceBlock<2>(StateLayout::landmark(s)));
}

std::vector<int> SeifSlam::activeLandmarks() const {
  std::vector<int> ids;
  for (const SeifStore::RobotLink& l : store_.robotLinks()) ids.push_back(book_.ids()[static_cast<std::size_t>(l.slot)]);
  return ids;
}

FilterStats SeifSlam::stats() const {
  FilterStats s = store_.stats();
  s.information_scale = information_scale_;
  return s;
}

}  // namespace seif