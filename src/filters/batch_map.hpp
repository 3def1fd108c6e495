#pragma once
// The batch maximum-a-posteriori smoother ("batch"): it records every motion and observation,
// and at finish() solves for the poses and landmarks at once (batch_problem.hpp: the cost, the
// Levenberg-Marquardt solver, the constraints of a singular process noise, the marginals).
//
// Poses only where they are needed: x_0, every pose at which observations are made, and the
// last pose are "nodes"; the steps between two nodes are composed into one motion with its
// full covariance (preintegration.hpp) when the motion model is equivariant (a fixed motion in
// the robot's frame: every model seif ships), else each step keeps its own pose and is
// relinearised at every iteration. The pose after every step (smoothedTrajectory()) is then
// the Gaussian bridge between its two nodes, E[x_k | x_a, x_b] in the linearised model:
//   x_k = x_a + Rot(theta_a) (p_k + P_k T_k^T U_B^+ (rel(x_b) - B)),  T_k = dp_b/dp_k,
// its covariance J Sigma_ab J^T + Rot (P_k - P_k T_k^T U_B^+ T_k P_k) Rot^T.
//
// While streaming, a filter run alongside (BatchOptions::init: EKF or SEIF; odometry alone
// for Init::Odometry) gives the estimates, the outlier gate and the start of the solve. After
// finish() the estimates refer, like the filters', to [x_T, landmarks in order of first
// sighting]; covariances are the MAP's marginals (selected inversion of the information at
// the solution). Observations the gate rejects are left out of the batch too.
#include "filters/batch_problem.hpp"
#include "filters/landmark_book.hpp"
#include "filters/preintegration.hpp"
#include <seif/filters/slam_filter.hpp>

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <vector>

namespace seif {

class BatchMap final : public SlamFilter {
 public:
  BatchMap(const Pose2& initial_pose, const FilterConfig& config, const BatchOptions& options = {});
  /// Smooths after `filter` (a --smooth run): the filter runs alongside, gates, and starts
  /// the solve; filtered() is it.
  BatchMap(const Pose2& initial_pose, const FilterConfig& config, std::unique_ptr<SlamFilter> filter,
           const BatchOptions& options = {});
  ~BatchMap() override;

  std::string name() const override { return "batch"; }
  using SlamFilter::update;
  /// Records an increment linearised by the caller at pose() as a motion in the robot's
  /// frame, rotated with each iterate's heading (exact for an equivariant model).
  void predict(const MotionIncrement& increment) override;
  /// Records u (config's motion model): as a motion in the robot's frame for an equivariant
  /// model, else relinearised at every iteration.
  void predict(const MotionInput& u) override;
  /// Records the observations with the pose of this step. Only the config's sensor is
  /// supported (ModelError otherwise).
  void update(std::span<const Observation> observations, const MeasurementModel& sensor) override;
  /// Levenberg-Marquardt from the filter's (or odometry's) estimate. Throws NumericError when
  /// it does not converge. A later step invalidates the solution.
  void finish() override;
  /// The T + 1 smoothed poses (heading wrapped); empty before finish().
  std::vector<Pose2> smoothedTrajectory() const override;
  /// trajectoryCovariances().
  std::vector<Mat3> smoothedTrajectoryCovariances() const override { return trajectoryCovariances(); }
  bool smoother() const override { return true; }
  const SmootherReport* smootherReport() const override { return solution_ ? &report_ : nullptr; }

  /// The filter run alongside (null for Init::Odometry).
  const SlamFilter* filtered() const { return inner_.get(); }

  /// Solves from any initial guess: one pose per step plus the start, landmarks in state
  /// order (the nodes' poses are taken from it). Throws InvalidArgument for wrong sizes.
  void optimizeFrom(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks);
  /// F (chi-square) at the solution (NaN before a solve).
  double cost() const { return solution_ ? 2.0 * report_.final_cost : kNaN; }
  /// F at any point (one pose per step plus the start, landmarks in state order; the nodes'
  /// poses are read), and in `violation` the largest constraint value there.
  double costAt(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks,
                double* violation = nullptr) const;
  int iterations() const { return solution_ ? report_.iterations : 0; }
  /// max |W^T r| at the solution: the violation of the noise-free directions.
  double constraintViolation() const { return solution_ ? solution_->report.violation : kNaN; }
  /// Poses solved for.
  int nodes() const { return static_cast<int>(node_step_.size()) + (pre_.steps() > 0 ? 1 : 0); }
  /// Marginal covariance of every pose x_0..x_T: the nodes' by selected inversion, the others
  /// by the bridge. Throws InvalidArgument before a solve.
  std::vector<Mat3> trajectoryCovariances() const;

  Marginal marginal(std::span<const int> landmarks, bool pose = true,
                    MarginalMode mode = MarginalMode::Exact) const override;
  /// Before finish(): the filter the batch starts from (its marginals answer); then Exact.
  MarginalMode gateMarginal() const override;
  /// Not supported: the batch keeps every measurement (InvalidArgument).
  void removeLandmark(int id) override;
  void mergeLandmarks(int keep, int drop) override;
  Pose2 pose() const override;
  Mat3 poseCovariance() const override;
  const std::vector<int>& landmarkIds() const override { return book_.ids(); }
  bool hasLandmark(int id) const override { return book_.find(id) >= 0; }
  Vec2 landmark(int id) const override;
  Mat2 landmarkCovariance(int id) const override;
  /// The structure of the smoothing information matrix over the nodes and landmarks:
  /// links = motion factors + distinct (pose, landmark) pairs; robot_links = landmarks seen
  /// from the last pose; max_landmark_links = most poses that saw one landmark.
  FilterStats stats() const override;
  std::size_t robotLinks() const override { return last_pose_links_; }
  /// 0: the batch touches no information block per step (its filter does).
  std::size_t blocksTouched() const override { return 0; }
  std::size_t rejectedObservations() const override { return book_.rejected(); }

  /// [x_T, landmarks]. The covariance is the joint marginal (3 + 2N solves with the factor,
  /// cached); the information its inverse, O(N^3).
  Eigen::VectorXd mean() const override;
  Eigen::MatrixXd covariance() const override;
  Eigen::MatrixXd information() const override;

 private:
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  /// Where the pose after a step sits: a node, or inside motion `motion` at relative pose p
  /// with covariance P (preintegration.hpp).
  struct StepPose {
    int node = -1;
    int motion = -1;
    Vec3 p = Vec3::Zero();
    Mat3 P = Mat3::Zero();
  };

  Pose2 currentGuess() const;
  Vec2 landmarkGuess(int slot) const;
  /// Makes the current pose a node (closing the preintegrated motion to it); its index.
  int closeSegment();
  /// One step's motion in the robot's frame: into the open motion and the odometry guess.
  void addBodyStep(const Vec3& body, const Mat3& U_body);
  /// The node poses read from one pose per step.
  std::vector<Pose2> nodePoses(const std::vector<Pose2>& poses) const;
  void requireSizes(const std::vector<Pose2>& poses, const std::vector<Vec2>& landmarks) const;
  void solve(std::vector<Pose2> nodes, std::vector<Vec2> landmarks);
  /// The bridge's pose of step k from its nodes' poses.
  Pose2 bridge(const StepPose& s, const Pose2& xa, const Pose2& xb) const;
  Eigen::Index landmarkVar(int slot) const;
  const BatchSolution& solution(const char* what) const;
  void invalidate();

  FilterConfig config_;
  BatchOptions options_;
  std::string init_name_;
  std::unique_ptr<SlamFilter> inner_;  // null: odometry
  LandmarkBook book_;
  BatchProblem problem_;
  Preintegration pre_;                 // the open motion from the last node
  std::vector<StepPose> steps_;        // the pose after each step, x_0 first
  std::vector<int> node_step_;         // per closed node: its step index
  std::vector<Pose2> node_guess_;      // per closed node: the initial guess
  Pose2 guess_;                        // the current pose's guess (odometry: dead reckoning)
  std::vector<Vec2> landmark_guess_;   // odometry: each landmark from its first sighting
  // Structure (stats()).
  std::vector<int> last_linked_node_;
  std::vector<std::size_t> pose_links_;
  std::size_t pose_landmark_links_ = 0;
  std::size_t last_pose_links_ = 0;

  std::unique_ptr<BatchSolution> solution_;
  SmootherReport report_;
  mutable std::optional<Eigen::MatrixXd> covariance_;  // of [x_T, landmarks]
};

}  // namespace seif
