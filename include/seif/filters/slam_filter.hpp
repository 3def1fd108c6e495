#pragma once
// The one interface of every SLAM filter in seif (EKF, EIF, SEIF). Known data association:
// observations carry landmark ids; an id seen for the first time is added to the map.
#include <seif/core/types.hpp>

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace seif {

struct FilterConfig {
  NoiseModel noise;
  /// Initial pose standard deviations (x [m], y [m], theta [rad]). Information filters need
  /// a finite prior, so the start pose is anchored with this (small) uncertainty.
  Vec3 initial_pose_sigma = Vec3(1e-3, 1e-3, 1e-3);
  /// Gross-outlier gate in measurement standard deviations (OutlierGate); infinity disables it.
  double outlier_gate = 1000.0;
};

/// Structure of the information matrix, for tests, metrics.json and the paper's table.
struct FilterStats {
  std::size_t landmarks = 0;
  std::size_t links = 0;               ///< non-zero off-diagonal blocks of H (unordered pairs)
  std::size_t robot_links = 0;         ///< landmarks linked to the robot (the active set)
  std::size_t max_landmark_links = 0;  ///< most links any landmark has (SEIF: has had)
  std::size_t blocks_touched = 0;      ///< H blocks read or written by the last step
};

class SlamFilter {
 public:
  virtual ~SlamFilter() = default;

  virtual std::string name() const = 0;

  /// Motion update with the velocity model.
  virtual void predict(const VelocityControl& u) = 0;

  /// Measurement update with all observations made at one instant (one linearisation point).
  virtual void update(std::span<const Observation> observations) = 0;

  /// predict(u) then update(z): one filter cycle.
  void step(const VelocityControl& u, std::span<const Observation> observations) {
    predict(u);
    update(observations);
  }

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
};

}  // namespace seif
