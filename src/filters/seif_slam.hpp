#pragma once
// The Sparse Extended Information Filter (Thrun et al. 2002; algorithm.md §1-4): the
// paper's four steps on the block-sparse store of H, b and mu (SeifStore). One step touches
// only the robot, the active landmarks and K relaxed landmarks, so its cost does not grow
// with the map:
//   predict(u)  : motion update on the {robot, active} block (paper Lemma 3);
//   update(z)   : mean recovery (amortised coordinate descent, eq. 42), measurement update
//                 (Lemma 1, eq. 21-22), sparsification (eq. 44-51) when more than
//                 landmarks are active (options.active, the paper's theta_x).
#include "filters/landmark_book.hpp"
#include <seif/filters/seif_options.hpp>
#include "filters/information_ops.hpp"
#include "filters/seif_bounds.hpp"
#include "filters/seif_relax_frontier.hpp"
#include "filters/seif_store.hpp"
#include <seif/filters/slam_filter.hpp>

#include <Eigen/SparseCore>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string_view>

namespace seif {

class SparseMarginals;

class SeifSlam final : public SlamFilter {
 public:
  SeifSlam(const Pose2& initial_pose, const FilterConfig& config, const SeifOptions& options = {});
  ~SeifSlam() override;

  std::string name() const override { return "seif"; }
  using SlamFilter::predict;
  using SlamFilter::update;
  void predict(const MotionIncrement& increment) override;
  void update(std::span<const Observation> observations, const MeasurementModel& sensor) override;
  /// Exact: one solve with the cached sparse factor per column (one factorisation per
  /// state, O(N) at the paper's sparsity). Local: the blanket's dense inverse, O(1).
  Marginal marginal(std::span<const int> landmarks, bool pose = true,
                    MarginalMode mode = MarginalMode::Exact) const override;
  /// Local: as good as Exact for gating (docs/association.md), in constant time.
  MarginalMode gateMarginal() const override { return MarginalMode::Local; }

  /// SeifStore::marginalizeLandmark (exact; O(d^2) in its d neighbours). Landmarks linked to
  /// it that become linked to the robot count as active: past the bound they are sparsified.
  void removeLandmark(int id) override;
  /// SeifStore::mergeLandmarks (exact, O(d)); then as removeLandmark. The mean of `keep` is
  /// relaxed once (exact mean: solved).
  void mergeLandmarks(int keep, int drop) override;
  Pose2 pose() const override;
  Mat3 poseCovariance() const override;
  const std::vector<int>& landmarkIds() const override { return book_.ids(); }
  bool hasLandmark(int id) const override { return book_.find(id) >= 0; }
  Vec2 landmark(int id) const override;
  Mat2 landmarkCovariance(int id) const override;
  Eigen::Matrix<double, Eigen::Dynamic, 2> landmarkCovarianceColumns(int id) const override;
  /// H as stored: with deferred motion, without the links the held controls will add.
  FilterStats stats() const override;
  /// Applies the controls deferred motion holds (SeifOptions::Motion::Deferred).
  void finish() override { settleMotion(); }
  void settle() override { settleMotion(); }
  /// Motion::Deferred: the controls held since the last motion update (0 when settled).
  std::size_t heldControls() const { return pending_controls_; }
  /// Motion::Deferred: the controls since the last update with observations, held or applied
  /// by a query since (an update without observations solves the block while it is <= 1).
  std::size_t controlsSinceObservation() const { return controls_since_observation_; }
  std::size_t robotLinks() const override { return store_.robotLinks().size(); }
  std::size_t rejectedObservations() const override { return book_.rejected(); }
  std::size_t blocksTouched() const override { return store_.blocksTouched(); }

  Eigen::VectorXd mean() const override;
  Eigen::MatrixXd covariance() const override;
  Eigen::MatrixXd information() const override;
  /// exactMean() with the amortised mean; empty with SeifOptions::mean = Exact.
  std::optional<Eigen::VectorXd> posteriorMean() const override;


  const SeifOptions& options() const { return options_; }
  /// The store, with any deferred motion applied first (SeifOptions::motion).
  const SeifStore& store() const {
    settleMotion();
    return store_;
  }
  /// H as a sparse matrix and b, in the state order [x, y, th, landmarks...] (the store's
  /// divided by informationScale()).
  Eigen::SparseMatrix<double> sparseInformation() const { return store().sparseInformation() / information_scale_; }
  /// Its lower triangle, what the factorisation reads (SeifStore::lowerInformation).
  Eigen::SparseMatrix<double> lowerInformation() const { return store().lowerInformation() / information_scale_; }
  Eigen::VectorXd informationVector() const { return store().informationVector() / information_scale_; }
  /// kappa: the store holds kappa H and kappa b (Sparsify::Conservative and SeifOptions::rho
  /// scale the posterior's information down by raising kappa, in O(1): every later step's
  /// information enters the store times kappa, every covariance leaves it times kappa). 1
  /// without them.
  double informationScale() const { return information_scale_; }
  /// RelaxOrder::Wildfire: the landmarks queued for relaxation (0 with the other orders).
  std::size_t wildfireQueued() const { return frontier_.queued(); }
  /// Sparsifications that raised kappa (Sparsify::Conservative, SeifOptions::rho).
  std::size_t informationScalings() const { return scalings_; }
  /// The exact mean H^-1 b (sparse Cholesky), without changing the filter.
  Eigen::VectorXd exactMean() const;
  /// Runs `sweeps` full Gauss-Seidel sweeps of the mean over every variable (the landmarks
  /// over-relaxed by SeifOptions::omega).
  void relaxMean(int sweeps);
  /// The upper bound kept on landmark `id`'s marginal covariance (seif_bounds.hpp;
  /// SeifOptions::bounds, else InvalidArgument).
  Mat2 covarianceBound(int id) const {
    requireBounds();
    return information_scale_ * store_.node(book_.require(id)).bound;
  }
  /// Sets every landmark's bound to its exact marginal covariance, the tightest bound: one
  /// sparse factorisation, O(N) at the paper's sparsity (a checkpoint without bounds; a
  /// refresh when the filter has time, e.g. after a loop closure).
  void refreshCovarianceBounds();
  /// Ids of the active landmarks (linked to the robot).
  std::vector<int> activeLandmarks() const;
  /// Largest relative magnitude the sparsification formula left in a removed robot link
  /// during the last step (zero up to rounding, by paper eq. 44-51); 0 when none removed.
  double lastSparsificationResidual() const { return last_sparsification_residual_; }

  // Sparsify::Eseif counters, over the filter's life.
  /// Steps whose robot was marginalised out and relocalised from z_beta.
  std::size_t eseifRelocalizations() const { return eseif_relocalizations_; }
  /// Steps that left more than options.active landmarks active: no usable z_beta.
  std::size_t eseifDeferrals() const { return eseif_deferrals_; }
  /// SEIF conditioning sparsifications (eq. 44-51) under Eseif: the active set reached
  /// kMaxLocalLandmarks while deferred, or within one batch.
  std::size_t eseifFallbacks() const { return eseif_fallbacks_; }

 protected:
  Pose2 linearizationPose() const override { return robotMean(); }

 private:
  friend struct CheckpointAccess;  // checkpoints: src/filters/*_state.cpp
  friend struct SeifStepsForTests;
  // The paper's four steps, in the order update() runs them (private: out of order they
  // break the filter's invariants; tests reach them through SeifStepsForTests).
  // predict(u) = motionUpdate(u); update(z) = recoverMean(); measurementUpdate(z); sparsify(),
  // the sparsification first re-solving the robot-active block's mean on the block it gathers
  // (Recovery::AfterMeasurement: recoverMean() after measurementUpdate(), no re-solve; exact
  // mean: measurementUpdate(z); recoverExactMean(); sparsify()).
  void motionUpdate(const MotionIncrement& increment);      ///< §1, Lemma 3 (or deferred)
  /// Lemma 3 on the robot-active block with one (possibly composed) increment.
  void applyMotion(const MotionIncrement& m);
  /// Motion::Deferred: applies the increment held since the last observation, if any.
  void flushMotion();
  /// flushMotion() all or nothing, for the queries that read H or the robot's information:
  /// the posterior is the same, only its representation changes (hence const).
  void settleMotion() const;
  /// The robot's mean with any deferred motion: the store's plus the held increment.
  Vec3 robotMean() const;
  /// What the store's robot-active block is at the start of an update (block_):
  /// Stale - read it again; Gathered - applyMotion() left it gathered as the store holds it
  /// (its solve needs no gather); Solved - the last update's sparsification solved its mean
  /// and keeps it (b~ = b + (H~ - H) mu within the block), as the motion since keeps it, so
  /// solving it again would give the mean back up to rounding.
  enum class ActiveBlock { Stale, Gathered, Solved };
  /// §2, amortised, eq. (42); without `with_active` the robot alone and the K landmarks
  /// (updates without observations while motion is deferred, after the first); with the
  /// block Solved the K landmarks alone.
  void recoverMean(bool with_active = true, ActiveBlock block = ActiveBlock::Stale);
  void recoverExactMean();                                 ///< mu = H^-1 b, sparse Cholesky
  /// §3, eq. (21-22). Returns whether its iterations left the store's gathered block
  /// holding the active set, current (deactivateSurplus() can then reorder it).
  bool measurementUpdate(std::span<const Observation> z, const MeasurementModel& sensor);
  /// R^-1 of z, times kappa (informationScale()): the information it adds to the store.
  Mat2 scaledNoiseInverse(const MeasurementModel& sensor, const Observation& z) const;
  void sparsify();                                         ///< §4, eq. (44-51)
  /// The joint covariance of `vars` (-1: the robot, else slots) from H restricted to a
  /// blanket around them of at most options_.blanket more variables (MarginalMode::Local);
  /// `conservative`: plus the bounded share of the variables outside it (Conservative).
  Eigen::MatrixXd localCovariance(std::span<const int> vars, bool conservative = false) const;
  Eigen::MatrixXd localCovariance(std::initializer_list<int> vars, bool conservative = false) const;
  /// sparsify(), optionally re-solving the gathered block's mean before eq. (44-51).
  /// With `slot` >= 0 (an active landmark), deactivates that landmark alone. With
  /// `block_gathered` (measurementUpdate()'s result, nothing changed since) the gathered
  /// block is reordered instead of read again (SeifStore::reorderGathered()).
  void deactivateSurplus(bool solve_active_mean_first, int slot = -1, bool block_gathered = false);
  /// Gauge::Kept: the free directions of the block deactivateSurplus() gathered (gauge_).
  void gatherGauge(int drop);
  /// update() with Sparsify::Eseif (Walter, Eustice, Leonard 2007).
  void eseifUpdate(std::span<const Observation> z, const MeasurementModel& sensor);
  /// Whether z would leave more than options.active landmarks active.
  bool exceedsActive(std::span<const Observation> z) const;
  /// Splits z into z_alpha (alpha_, gross outliers dropped) and z_beta (beta_): the fewest
  /// observations of mapped landmarks, best informed first, whose stacked pose Jacobian
  /// is well conditioned. False (z_beta empty, alpha_ all of z) when there is none.
  bool partitionObservations(std::span<const Observation> z, const MeasurementModel& sensor);
  /// Marginalises the robot out and relocalises it from z_beta alone; false (nothing
  /// changed) when the pose does not converge.
  bool relocalizeRobot(const MeasurementModel& sensor);
  void invalidateFactor();
  /// update() after its input checks.
  void applyUpdate(std::span<const Observation> observations, const MeasurementModel& sensor);
  /// Runs a step all or nothing: any exception from it leaves the filter exactly as it was
  /// (the store's transaction, the book's mark, the counters and the random engine).
  template <typename Step>
  void guarded(const Step& step);
  /// Linearization::Invariant, at the start of update(): re-anchors the robot, and each
  /// observed landmark with reanchorIfMoved().
  void reanchor(std::span<const Observation> observations);
  /// Linearization::Invariant: re-anchors landmark `slot` when its mean has moved more than
  /// options.reanchor from its anchor (sparsifying first when its neighbours would
  /// overflow the local block).
  void reanchorIfMoved(int slot);
  /// SeifStore::reanchorLandmark, the landmark's covariance bound carried along first
  /// (seif_bounds.hpp: reanchoredBound).
  void reanchorLandmark(int slot, const Vec2& to);
  /// InvalidArgument unless SeifOptions::bounds.
  void requireBounds() const;
  /// Sparsify::Conservative (seif_sparsify_conservative.cpp), around deactivateSurplus()'s
  /// eq. (44-51) on the gathered block [x, order_]: before, the block's local marginal
  /// covariance and its information; after, raises kappa so that H / kappa claims no more
  /// than before over the block's blanket.
  void beginConservativeSparsification();
  void endConservativeSparsification();

  FilterConfig config_;
  LandmarkBook book_;
  SeifOptions options_;
  SeifStore store_;
  std::mt19937_64 rng_;
  std::size_t relax_cursor_ = 0;  // next landmark of a cyclic relaxation
  RelaxFrontier frontier_;        // RelaxOrder::Wildfire's queue (empty otherwise)
  bool wildfire() const { return options_.relax_order == SeifOptions::RelaxOrder::Wildfire; }
  double last_sparsification_residual_ = 0.0;
  std::size_t eseif_relocalizations_ = 0;
  std::size_t eseif_deferrals_ = 0;
  std::size_t eseif_fallbacks_ = 0;
  /// Motion::Deferred: the increments since the last motion update, composed (compose()),
  /// and how many controls they hold.
  std::optional<MotionIncrement> pending_motion_;
  std::size_t pending_controls_ = 0;
  /// Motion::Deferred: the controls since the last update with observations, whether or not
  /// a query has applied them since (pending_controls_ counts only those still held). An
  /// update without observations solves the robot-active block when this is at most 1.
  std::size_t controls_since_observation_ = 0;
  double information_scale_ = 1.0;  // kappa (informationScale())
  std::size_t scalings_ = 0;        // sparsifications that raised kappa

  // Work buffers, reused every step (no allocation in the steady state).
  Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, kMaxLocalDim> workspace_;
  std::vector<int> order_;
  std::vector<std::pair<double, int>> ranking_;
  std::vector<Observation> alpha_;  // ESEIF's z_alpha
  std::vector<Observation> beta_;   // ESEIF's z_beta
  std::vector<int> beta_slots_;     // their landmarks
  std::vector<unsigned char> roles_;  // per observation of a step: alpha, beta or rejected
  std::vector<MeasurementInformation> infos_;  // measurementUpdate()'s, for iterations
  std::vector<std::optional<Anchors>> anchors_;
  // measurementUpdate()'s covariance bounds (seif_bounds.hpp): the observed landmarks (the
  // known ones first), their joint bound with the robot before the update, the information added.
  std::vector<int> bound_slots_;
  LocalMatrix bound_prior_;
  LocalMatrix bound_added_;
  Eigen::MatrixXd overclaim_sigma_;  // Sparsify::Conservative: the block's marginal before
  LocalMatrix overclaim_h_;          // and its information before eq. (44-51)
  LocalGauge gauge_;                 // the block's free directions (keepGauge)
  BoundWorkspace bound_ws_;
  std::vector<int> observed_slots_;  // an update's observed mapped landmarks (holdFixedPart())
  std::size_t sparsifications_ = 0;  // deactivateSurplus() calls that deactivated landmarks
  /// The robot-active block as the next update finds it (ActiveBlock). Every change of the
  /// store but the two that set it makes it Stale.
  ActiveBlock block_ = ActiveBlock::Stale;

  /// The sparse Cholesky factor of H and its selected inverse, built on first use after H
  /// changed: exact means and marginal covariances.
  const SparseMarginals& factor() const;
  mutable std::unique_ptr<SparseMarginals> factor_;
};

}  // namespace seif
