#pragma once
// The batch maximum-a-posteriori smoother ("batch"): it records every motion input and
// observation, and at finish() solves for ALL poses x_0..x_T and landmarks at once by
// Gauss-Newton on
//   F = |x_0 - start|^2_{P0^-1} + sum_k |r_k|^2_{U_k^+} + sum_j |z_j - h(x_k(j), y_l(j))|^2_{R_j^-1},
//   r_k = x_{k+1} - x_k - Delta(x_k, u_k)  (heading wrapped),  P0 = diag(initial_pose_sigma^2),
// subject to W_k^T r_k = 0, where U_k = V diag(lambda) V^T and W_k spans its null space:
// a singular process noise (the velocity model's U has rank 2) is treated exactly, its
// noise-free directions as hard constraints and U^+ (the pseudo-inverse) as the weight.
// Each iteration solves the sparse KKT system [[A, C^T], [C, 0]] (A = J^T Omega J) with
// SparseLU; U_k, its derivative in x_k (central differences: the model gives U only) and
// dDelta/dx are evaluated at the current x_k.
//
// While streaming, an inner EKF (same config) gives the estimates and, per step, the
// Gauss-Newton start. After finish() the estimates refer, like the filters', to the state
// [x_T, landmarks in order of first sighting]; covariances are the MAP's marginals, the
// top-left block of the KKT inverse at the solution (columns by solves with the factor).
// Observations the outlier gate rejects (at the inner EKF's estimate, as the EKF would)
// are left out of the batch too.
#include "filters/ekf_slam.hpp"
#include "filters/landmark_book.hpp"
#include <seif/filters/slam_filter.hpp>

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <vector>

namespace seif {

class BatchMap final : public SlamFilter {
 public:
  BatchMap(const Pose2& initial_pose, const FilterConfig& config);
  ~BatchMap() override;

  std::string name() const override { return "batch"; }
  using SlamFilter::update;
  /// Records an increment already linearised by the caller at the inner EKF's pose (pose()):
  /// the batch keeps it as a motion in the robot's frame, rotated with the pose's heading at
  /// every iteration (exact for a model whose increment does not depend on where the robot
  /// is - the velocity, Ackermann and odometry models; predict(MotionInput) relinearises any
  /// model). Advances the inner EKF.
  void predict(const MotionIncrement& increment) override;
  /// Records u (config's motion model) and advances the inner EKF.
  void predict(const MotionInput& u) override;
  /// Records the observations with the pose of this step. Only the config's sensor is
  /// supported (ModelError otherwise).
  void update(std::span<const Observation> observations, const MeasurementModel& sensor) override;
  /// Gauss-Newton from the inner EKF's poses (after every step) and final landmarks.
  /// Throws NumericError when it does not converge. A later step invalidates the solution
  /// (the estimates are the EKF's again until the next finish()).
  void finish() override;
  /// The T + 1 smoothed poses (heading wrapped); empty before finish().
  std::vector<Pose2> smoothedTrajectory() const override;
  /// trajectoryCovariances(): O(T) solves.
  std::vector<Mat3> smoothedTrajectoryCovariances() const override { return trajectoryCovariances(); }
  bool smoother() const override { return true; }

  /// Gauss-Newton from any initial guess: one pose per step plus the start, landmarks in
  /// state order. Throws InvalidArgument for wrong sizes, NumericError as finish().
  void optimizeFrom(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks);
  /// F at the solution (NaN before a solve).
  double cost() const { return cost_; }
  /// F at any point (one pose per step plus the start, landmarks in state order), and in
  /// `violation` max |W_k^T r_k| there. Throws InvalidArgument for wrong sizes.
  double costAt(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks,
                double* violation = nullptr) const;
  /// Gauss-Newton iterations (KKT solves) of the last solve.
  int iterations() const { return iterations_; }
  /// max |W_k^T r_k| at the solution: the violation of the noise-free directions.
  double constraintViolation() const { return violation_; }
  /// Marginal covariance of every pose x_0..x_T: 3 solves with the factored KKT per pose,
  /// O(T) solves in all. Throws InvalidArgument before a solve.
  std::vector<Mat3> trajectoryCovariances() const;

  Marginal marginal(std::span<const int> landmarks, bool pose = true,
                    MarginalMode mode = MarginalMode::Exact) const override;
  /// Not supported: the batch keeps every measurement (InvalidArgument).
  void removeLandmark(int id) override;
  void mergeLandmarks(int keep, int drop) override;
  Pose2 pose() const override;
  Mat3 poseCovariance() const override;
  const std::vector<int>& landmarkIds() const override { return book_.ids(); }
  bool hasLandmark(int id) const override { return book_.find(id) >= 0; }
  Vec2 landmark(int id) const override;
  Mat2 landmarkCovariance(int id) const override;
  /// The structure of the smoothing information matrix over all poses and landmarks:
  /// links = T motion links + distinct (pose, landmark) pairs; robot_links = landmarks seen
  /// from the last pose; max_landmark_links = most poses that saw one landmark.
  FilterStats stats() const override;
  /// Landmarks seen from the last pose (stats().robot_links).
  std::size_t robotLinks() const override { return last_pose_links_; }
  /// 0: the batch touches no information block per step (its inner EKF does).
  std::size_t blocksTouched() const override { return 0; }
  std::size_t rejectedObservations() const override { return book_.rejected(); }

  /// [x_T, landmarks]. The covariance is the joint marginal: 3 + 2N solves with the factored
  /// KKT, once per solution (cached); the information is its inverse, O(N^3).
  Eigen::VectorXd mean() const override;
  Eigen::MatrixXd covariance() const override;
  Eigen::MatrixXd information() const override;

 private:
  struct Measurement {
    int pose;  // index k of x_k
    int slot;  // landmark slot
    Vec2 z;
    Mat2 R_inv;
  };
  struct System;
  struct Solution;

  /// F, the constraints and, if `system`, the KKT matrix and right-hand side at (poses, landmarks).
  void linearize(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks, System& out,
                 bool system) const;
  /// Rows `rows` (variable indices) of the KKT inverse's columns `rows`: a marginal covariance.
  Eigen::MatrixXd kktMarginal(const std::vector<Eigen::Index>& rows) const;
  const Solution& solution(const char* what) const;
  Eigen::Index landmarkVar(int slot) const;
  void requireSizes(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks) const;
  void invalidate();

  FilterConfig config_;
  Pose2 start_;
  EkfSlam inner_;
  LandmarkBook book_;
  /// Step k's motion: an input u_k, relinearised at every iteration, or a MotionIncrement
  /// given already linearised (predict(MotionIncrement)), kept as a motion in the robot's
  /// frame: Delta(x_k) = Rot(theta_k) body, U(x_k) = Rot(theta_k) U_body Rot(theta_k)^T.
  struct Motion {
    std::optional<MotionInput> input;
    Vec3 body = Vec3::Zero();
    Mat3 U_body = Mat3::Zero();
  };
  std::vector<Motion> inputs_;  // step k moves x_k to x_{k+1}
  std::vector<Measurement> measurements_;
  std::vector<Pose2> guess_;             // the inner EKF's pose after every step (x_0 first)
  // Structure (stats()).
  std::vector<int> last_linked_pose_;    // per slot: the last pose that saw it
  std::vector<std::size_t> pose_links_;  // per slot: distinct poses that saw it
  std::size_t pose_landmark_links_ = 0;
  std::size_t last_pose_links_ = 0;

  std::unique_ptr<Solution> solution_;
  double cost_;
  int iterations_ = 0;
  double violation_;
};

}  // namespace seif
