#pragma once
// The one interface of every SLAM filter in seif (EKF, EIF, SEIF). A filter consumes a
// linearised motion increment (models/motion_model.hpp) and observations with the sensor
// model that made them (models/measurement_model.hpp); it never names a concrete model.
// Known data association: observations carry landmark ids; an id seen for the first time
// is added to the map. Unknown association builds on predictMeasurement().
#include <seif/core/types.hpp>
#include <seif/models/measurement_model.hpp>
#include <seif/models/motion_model.hpp>

#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <memory>
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
};

/// "standard" | "fej". Throws std::invalid_argument naming the valid names.
Linearization parseLinearization(std::string_view s);
std::string_view linearizationName(Linearization l);

struct FilterConfig {
  /// The models of the convenience calls predict(MotionInput) and update(observations).
  /// When empty, the paper's: VelocityModel(noise.sigma_v, noise.sigma_w, PerStep) and
  /// RangeBearingModel(noise.sigma_range, noise.sigma_bearing) at the vehicle's origin.
  std::shared_ptr<const MotionModel> motion;
  std::shared_ptr<const MeasurementModel> sensor;
  NoiseModel noise;
  /// Initial pose standard deviations (x [m], y [m], theta [rad]). Information filters need
  /// a finite prior, so the start pose is anchored with this (small) uncertainty.
  Vec3 initial_pose_sigma = Vec3(1e-3, 1e-3, 1e-3);
  /// Gross-outlier gate in measurement standard deviations (OutlierGate); infinity disables it.
  double outlier_gate = 1000.0;
  Linearization linearization = Linearization::Standard;
};

/// Structure of the information matrix, for tests, metrics.json and the paper's table.
struct FilterStats {
  std::size_t landmarks = 0;
  std::size_t links = 0;               ///< non-zero off-diagonal blocks of H (unordered pairs)
  std::size_t robot_links = 0;         ///< landmarks linked to the robot (the active set)
  std::size_t max_landmark_links = 0;  ///< most links any landmark has (SEIF: has had)
  std::size_t blocks_touched = 0;      ///< H blocks read or written by the last step
};

/// A landmark's predicted measurement and its innovation covariance S = J Sigma J^T + R
/// (J over the pose and the landmark): what a data-association test needs.
struct PredictedMeasurement {
  Vec2 z = Vec2::Zero();
  Mat2 S = Mat2::Zero();
};

class SlamFilter {
 public:
  explicit SlamFilter(const FilterConfig& config);
  virtual ~SlamFilter() = default;

  virtual std::string name() const = 0;

  /// Motion update with an increment linearised at this filter's pose estimate.
  virtual void predict(const MotionIncrement& increment) = 0;

  /// Measurement update with all observations made at one instant (one linearisation
  /// point), each with `sensor.noise(z)`.
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

  /// Called once after the last step. A filter has nothing left to do; a smoother (the
  /// batch MAP) solves here, and its estimates before finish() are only its initial guess.
  virtual void finish() {}
  /// The smoothed pose of every step (the start pose first, then one per step), for a
  /// smoother after finish(); empty for a filter, whose trajectory is the pose after each step.
  virtual std::vector<Pose2> smoothedTrajectory() const { return {}; }
  /// The marginal covariance of each smoothed pose, as smoothedTrajectory(); empty for a filter.
  virtual std::vector<Mat3> smoothedTrajectoryCovariances() const { return {}; }
  /// True for a smoother: its estimates mean something only after finish().
  virtual bool smoother() const { return false; }

  /// Writes this filter's whole state to a checkpoint (filters/checkpoint.hpp: saveCheckpoint;
  /// seif::load reads it back). Throws std::invalid_argument for the batch MAP smoother.
  void save(const std::filesystem::path& path) const;
  void save(const std::filesystem::path& path, const CheckpointExtras& extras) const;

  const MotionModel& motionModel() const { return *motion_; }
  const MeasurementModel& sensorModel() const { return *sensor_; }

  /// The measurement `sensor` would predict for landmark `id` at the current estimate, and
  /// its innovation covariance with measurement noise R. EKF: O(1) reads of its covariance;
  /// EIF: one solve with its dense factor; SEIF: exact, two solves with the sparse factor
  /// (O(N) once per state; constant-time local forms come with covariance recovery).
  /// Throws std::out_of_range for an id not in the map.
  virtual PredictedMeasurement predictMeasurement(int id, const MeasurementModel& sensor,
                                                  const Mat2& R) const = 0;

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

 protected:
  /// The pose the convenience predict() linearises at (the filter's own, unwrapped).
  virtual Pose2 linearizationPose() const { return pose(); }
  /// S = J_x Sxx J_x^T + J_x Sxy J_y^T + (..)^T + J_y Syy J_y^T + R, and zhat.
  static PredictedMeasurement innovation(const MeasurementModel& sensor, const Pose2& x,
                                         const Vec2& y, const Mat3& Sxx, const Mat32& Sxy,
                                         const Mat2& Syy, const Mat2& R);
  /// Throws ModelError for an observation without a landmark id (known association only).
  static void requireAssociated(const Observation& z, const char* filter);

 private:
  std::shared_ptr<const MotionModel> motion_;
  std::shared_ptr<const MeasurementModel> sensor_;
};

}  // namespace seif
