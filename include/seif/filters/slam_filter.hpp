#pragma once
// The one interface of every SLAM filter in seif (EKF, EIF, SEIF). A filter consumes a
// linearised motion increment (models/motion_model.hpp) and observations with the sensor
// model that made them (models/measurement_model.hpp); it never names a concrete model.
// Known data association: observations carry landmark ids; an id seen for the first time
// is added to the map. Unknown association builds on predictMeasurement().
#include <seif/core/types.hpp>
#include <seif/filters/batch_options.hpp>
#include <seif/models/measurement_model.hpp>
#include <seif/models/motion_model.hpp>

#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace seif {

struct CheckpointExtras;  // filters/checkpoint.hpp

/// Where a filter evaluates its Jacobians (--linearization).
enum class Linearization {
  /// At the newest estimates (the textbook EKF): gains spurious information about the
  /// global heading, which is unobservable (Huang, Mourikis, Roumeliotis, IJRR 2010).
  Standard,
  /// First-estimates Jacobians (Huang et al. 2010, the FEJ-EKF): the motion Jacobian's
  /// heading column from the pose predictions, every landmark's Jacobian at its first
  /// estimate, so the linearised system keeps the unobservable directions of the real one.
  FirstEstimates,
  /// The right-invariant EKF (Barrau & Bonnabel 2015) in standard coordinates
  /// (algorithm.md, "anchors"): the covariance is anchored at the means and re-anchored
  /// (P <- M P M^T, M = I + dc e_theta^T; H <- M^-T H M^-1) whenever they move, and a
  /// correction is applied by the retraction chi = exp(xi) chi_hat. The linearised system
  /// keeps the three unobservable directions whatever the estimate.
  Invariant,
  /// The observability-constrained EKF (Huang, Mourikis, Roumeliotis, IJRR 2010, OC-EKF):
  /// the motion Jacobian's heading column from the pose predictions (as FirstEstimates), and
  /// every measurement Jacobian taken at the current estimates, then changed as little as
  /// possible (in the Frobenius norm) so that it annihilates the unobservable directions
  /// N = [I J p; 0 1; I J l] at the predicted position p and the landmark's first estimate l:
  /// J* = J - J N (N^T N)^-1 N^T.
  ObservabilityConstrained,
};

/// "standard" | "fej" | "invariant" | "oc". Throws InvalidArgument naming the valid names.
Linearization parseLinearization(std::string_view s);
std::string_view linearizationName(Linearization l);

struct FilterConfig {
  /// The models of the convenience calls predict(MotionInput) and update(observations):
  /// both required (a filter refuses a config without them; paperFilterConfig() builds the
  /// paper's, a dataset's DatasetInfo its own).
  std::shared_ptr<const MotionModel> motion;
  std::shared_ptr<const MeasurementModel> sensor;
  /// Initial pose standard deviations (x [m], y [m], theta [rad]). Information filters need
  /// a finite prior, so the start pose is anchored with this (small) uncertainty.
  Vec3 initial_pose_sigma = Vec3(1e-3, 1e-3, 1e-3);
  /// Gross-outlier gate in measurement standard deviations (OutlierGate); infinity disables it.
  double outlier_gate = 1000.0;
  Linearization linearization = Linearization::Standard;
  /// Gauss-Newton iterations of each measurement update (iterated EKF): 1 linearises once;
  /// N relinearises N - 1 times at the updated mean (a landmark's first sighting stays
  /// linearised where it initialised the landmark).
  int iterations = 1;
};

/// The paper's models with `noise`: VelocityModel(sigma_v, sigma_w, NoiseForm::PerStep) and
/// RangeBearingModel(sigma_range, sigma_bearing) at the vehicle's origin; the other fields
/// at their defaults.
FilterConfig paperFilterConfig(const NoiseModel& noise);

/// Structure of the information matrix, for tests, metrics.json and the paper's table.
struct FilterStats {
  std::size_t landmarks = 0;
  std::size_t links = 0;               ///< non-zero off-diagonal blocks of H (unordered pairs)
  std::size_t robot_links = 0;         ///< landmarks linked to the robot (the active set)
  std::size_t max_landmark_links = 0;  ///< most links any landmark has (SEIF: has had)
  std::size_t blocks_touched = 0;      ///< H blocks read or written by the last step
  /// The SEIF's kappa (SeifSlam::informationScale()): the factor by which SeifOptions::rho
  /// and Sparsify::Conservative have scaled its information down, so that what the first
  /// steps contributed, the start prior among it, weighs 1 / kappa of the newest. 1 otherwise.
  double information_scale = 1.0;
};

/// FilterStats::information_scale beyond which the first steps are as good as forgotten: on
/// Victoria Park, rho = 0.01 lost the map once kappa passed 4e6 (docs/consistency.md, "A fixed
/// scale"). `seif run` warns above it.
inline constexpr double kForgottenInformationScale = 1e6;

/// How a marginal is computed (SlamFilter::marginal).
enum class MarginalMode {
  /// The posterior's marginal.
  Exact,
  /// The inverse of the information restricted to the queried variables and a blanket
  /// around them: conditions on the rest, so never larger than Exact. The EIF's blanket is
  /// the Markov blanket (every variable linked to a queried one); the SEIF's grows along the
  /// strongest links up to SeifOptions::blanket variables, so it is constant time.
  Local,
  /// An upper bound on the marginal in the Loewner order, never smaller than Exact: for
  /// gates that must not reject the right landmark. The SEIF (with SeifOptions::bounds) keeps
  /// a bound per landmark, inverts H over the bounded blanket and bounds the share of the
  /// links leaving it by covariance intersection, in constant time (docs/consistency.md,
  /// "Conservative covariances"); the dense filters and the batch return the exact marginal,
  /// which bounds itself.
  Conservative,
};

/// "exact" | "local" | "conservative". Throws InvalidArgument naming the valid names.
MarginalMode parseMarginalMode(std::string_view s);
std::string_view marginalModeName(MarginalMode m);

/// A joint marginal: the pose (when asked) first, then the landmarks in the order asked.
struct Marginal {
  Eigen::VectorXd mean;
  Eigen::MatrixXd covariance;
};

/// A landmark's predicted measurement and its innovation covariance S = J Sigma J^T + R
/// (J over the pose and the landmark): what a data-association test needs.
struct PredictedMeasurement {
  Vec2 z = Vec2::Zero();
  Mat2 S = Mat2::Zero();
};

/// The same from a joint marginal already at hand (one query serving many landmarks): the
/// pose in its first 3 rows, the landmark's 2 rows from `landmark_row`; J = [J_x J_y] is
/// returned through J_x and J_y when given.
PredictedMeasurement predictFromMarginal(const MeasurementModel& sensor, const Marginal& joint,
                                         Eigen::Index landmark_row, const Mat2& R, Mat23* J_x = nullptr,
                                         Mat2* J_y = nullptr);

class SlamFilter {
 public:
  explicit SlamFilter(const FilterConfig& config);
  virtual ~SlamFilter() = default;

  virtual std::string name() const = 0;

  /// Motion update with an increment linearised at this filter's pose estimate.
  virtual void predict(const MotionIncrement& increment) = 0;

  /// Measurement update with all observations made at one instant (one linearisation
  /// point), each with `sensor.noise(z)`. All or nothing: bad input (InvalidArgument,
  /// UnknownLandmark, ...) and a NumericError leave every filter as it was before the call
  /// (the SEIF, which updates in place, journals what the step changes and undoes it).
  virtual void update(std::span<const Observation> observations, const MeasurementModel& sensor) = 0;

  /// predict() with the config's motion model linearised at linearizationPose(). A
  /// smoother, which relinearises every input, overrides it to keep the input itself.
  virtual void predict(const MotionInput& u) { predict(motion_->linearize(linearizationPose(), u)); }
  /// update() with the config's sensor model.
  void update(std::span<const Observation> observations) { update(observations, *sensor_); }
  /// predict(u) then update(z): one filter cycle with the config's models.
  void step(const MotionInput& u, std::span<const Observation> observations) {
    predict(u);
    update(observations);
  }

  /// Called once after the last step. A filter has nothing left to do (a SEIF with deferred
  /// motion applies the controls it holds); a smoother (the batch MAP) solves here, and its
  /// estimates before finish() are only its initial guess.
  virtual void finish() {}
  /// Brings the stored form up to date for queries without changing the posterior (a SEIF
  /// with deferred motion applies the controls it holds); a query does it when needed. The
  /// run loop calls it before association, so that this work is timed as the filter's.
  virtual void settle() {}
  /// The smoothed pose of every step (the start pose first, then one per step), for a
  /// smoother after finish(); empty for a filter, whose trajectory is the pose after each step.
  virtual std::vector<Pose2> smoothedTrajectory() const { return {}; }
  /// The marginal covariance of each smoothed pose, as smoothedTrajectory(); empty for a filter.
  virtual std::vector<Mat3> smoothedTrajectoryCovariances() const { return {}; }
  /// True for a smoother: its estimates mean something only after finish().
  virtual bool smoother() const { return false; }
  /// A smoother's last solve (after finish()); null for a filter or before a solve.
  virtual const SmootherReport* smootherReport() const { return nullptr; }

  /// Writes this filter's whole state to a checkpoint (filters/checkpoint.hpp: saveCheckpoint;
  /// seif::load reads it back). Throws InvalidArgument for the batch MAP smoother.
  void save(const std::filesystem::path& path) const;
  void save(const std::filesystem::path& path, const CheckpointExtras& extras) const;

  const MotionModel& motionModel() const { return *motion_; }
  const MeasurementModel& sensorModel() const { return *sensor_; }

  /// The marginal of the pose (when `pose`) and of `landmarks` (ids), in that order: their
  /// mean and joint covariance, computed as `mode` says. Costs, with N landmarks:
  ///   EKF   any mode: a read of its covariance, O(k^2) for k variables.
  ///   EIF   Exact (and Conservative): solves with its cached dense factor, O(N^2) per
  ///         variable (one O(N^3) factorisation per state). Local: a dense inverse of the
  ///         blanket, O(b^3).
  ///   SEIF  Exact: solves with its cached sparse factor, O(nnz(L)) per column (one sparse
  ///         factorisation per state). Local: O(b^3), b <= k + SeifOptions::blanket the
  ///         size of the blanket: constant time. Conservative: the same blanket plus the
  ///         bounded share of the variables linked to it, O(b^3): constant time.
  ///   batch Exact (Local is Exact): solves with the KKT factor after finish(); before it
  ///         the initial guess's (an EKF's).
  /// Local conditions on everything outside the blanket, so it is never larger than the
  /// marginal; Conservative is never smaller. On the simulated worlds the SEIF's local S of a
  /// measurement is within 6 % of the exact one at the median, and rejects as many true
  /// pairings (docs/association.md).
  /// Throws UnknownLandmark for an id not in the map.
  virtual Marginal marginal(std::span<const int> landmarks, bool pose = true,
                            MarginalMode mode = MarginalMode::Exact) const = 0;

  /// The marginal a gate uses when not told which (AssociationOptions::marginal unset): the
  /// cheapest that gates as well as the exact one. Exact here (the EKF reads it off its
  /// covariance); the SEIF's is Local, constant time where Exact is a sparse factorisation
  /// per scan (docs/association.md, "Local against exact").
  virtual MarginalMode gateMarginal() const { return MarginalMode::Exact; }

  /// The measurement `sensor` would predict for landmark `id` at the current estimate, and
  /// its innovation covariance S = J Sigma J^T + R over the joint marginal of the pose and the
  /// landmark (marginal(), with its cost). Throws UnknownLandmark for an id not in the map.
  PredictedMeasurement predictMeasurement(int id, const MeasurementModel& sensor, const Mat2& R,
                                          MarginalMode mode = MarginalMode::Exact) const;

  /// Takes landmark `id` out of the map exactly: the posterior's marginal over everything
  /// else (EKF: its rows and columns deleted; information form: the Schur complement over it,
  /// which links its neighbours). The landmark in the last slot takes its place in
  /// landmarkIds(). The SEIF first deactivates the landmark when it is active (the paper's
  /// sparsification of its robot link), so the robot does not inherit all its neighbours.
  /// Throws UnknownLandmark. The batch MAP does not remove (InvalidArgument).
  virtual void removeLandmark(int id) = 0;
  /// Merges landmark `drop` into `keep` when both turn out to be one landmark: the posterior
  /// conditioned on y_keep = y_drop (information form: H' = T^T H T, b' = T^T b, drop's rows
  /// and columns added into keep's), then `drop` leaves the map as removeLandmark() says.
  /// keep's first estimate stays. The invariant SEIF first re-anchors one of the two to the
  /// other's anchor; when that would link the robot to more landmarks than its local block
  /// holds, `drop` is removed (removeLandmark) instead. Throws UnknownLandmark,
  /// InvalidArgument when keep == drop.
  virtual void mergeLandmarks(int keep, int drop) = 0;

  virtual Pose2 pose() const = 0;
  /// Marginal covariances. EKF: read off its covariance, O(1). EIF: a solve with its cached
  /// dense factor, O(N^2). SEIF: exact, from the sparse Cholesky factor of H and its selected
  /// inverse (SparseMarginals), computed on the first call after H changed at the cost of
  /// one factorisation, then cached: every marginal of one state costs that once, and each
  /// call afterwards a lookup.
  virtual Mat3 poseCovariance() const = 0;
  /// Landmark ids in the order they entered the map (= their order in the state vector).
  virtual const std::vector<int>& landmarkIds() const = 0;
  virtual bool hasLandmark(int id) const = 0;
  virtual Vec2 landmark(int id) const = 0;
  virtual Mat2 landmarkCovariance(int id) const = 0;
  /// The two columns of the joint covariance that belong to landmark `id`, in the state
  /// order: its cross-covariance with the pose and every landmark (relative NEES, data
  /// association). Default: two columns of covariance() (dense). EKF: a read, O(N);
  /// SEIF: two solves with its cached sparse factor.
  virtual Eigen::Matrix<double, Eigen::Dynamic, 2> landmarkCovarianceColumns(int id) const;
  /// Structure of H. O(1) for the SEIF; dense filters count their whole matrix.
  virtual FilterStats stats() const = 0;
  /// Landmarks linked to the robot now, and H blocks touched by the last step: both cheap
  /// enough to read after every step.
  virtual std::size_t robotLinks() const = 0;
  virtual std::size_t blocksTouched() const = 0;
  /// Observations rejected by the gross-outlier gate so far (FilterConfig::outlier_gate).
  virtual std::size_t rejectedObservations() const = 0;

  /// Full-state moments and information in the state order [x, y, th, landmarks...].
  /// Dense and O(N^3) for information filters: for tests and figures, not for the loop.
  virtual Eigen::VectorXd mean() const = 0;
  virtual Eigen::MatrixXd covariance() const = 0;
  virtual Eigen::MatrixXd information() const = 0;

  /// The posterior's mean over the whole state (state order), for a filter whose own
  /// estimate (pose(), landmark(), mean()) is not it: the amortised SEIF, whose mean is
  /// relaxed a few landmarks per step and lags its information after a loop closure, gives
  /// H^-1 b, one solve with its cached sparse factor (the factorisation exact marginals
  /// share, O(N) at the paper's sparsity). Empty for the EKF, the EIF, the batch MAP and a
  /// SEIF with SeifOptions::mean = Exact, whose estimate is the posterior's mean. The filter
  /// is not changed: its steps keep linearising at its own mean.
  virtual std::optional<Eigen::VectorXd> posteriorMean() const { return std::nullopt; }

  /// The pose the convenience predict() linearises at (the filter's own, unwrapped).
  virtual Pose2 linearizationPose() const { return pose(); }

 protected:
  /// Indices into the state vector of the pose (when `pose`) and of the landmark slots.
  static std::vector<Eigen::Index> stateIndices(std::span<const int> slots, bool pose);

 private:
  std::shared_ptr<const MotionModel> motion_;
  std::shared_ptr<const MeasurementModel> sensor_;
};

}  // namespace seif
