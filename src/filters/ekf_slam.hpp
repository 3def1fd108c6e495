#pragma once
// EKF-SLAM with a dense covariance: the reference the SEIF is compared with (O(N^2) per
// update). New landmarks are initialised through the inverse-model Jacobians, and all
// observations of one instant are applied jointly at one linearisation point, so that the
// EKF and the EIF give the same posterior to rounding (algorithm.md "Models", "EIF").
#include "filters/landmark_book.hpp"
#include <seif/filters/slam_filter.hpp>

#include <Eigen/Core>
#include <optional>

namespace seif {

class EkfSlam final : public SlamFilter {
 public:
  EkfSlam(const Pose2& initial_pose, const FilterConfig& config);

  std::string name() const override { return "ekf"; }
  using SlamFilter::predict;
  using SlamFilter::update;
  void predict(const MotionIncrement& increment) override;
  void update(std::span<const Observation> observations, const MeasurementModel& sensor) override;
  /// Every mode reads the covariance: O(k^2).
  Marginal marginal(std::span<const int> landmarks, bool pose = true,
                    MarginalMode mode = MarginalMode::Exact) const override;

  void removeLandmark(int id) override;
  void mergeLandmarks(int keep, int drop) override;
  Pose2 pose() const override;
  Mat3 poseCovariance() const override { return sigma_.topLeftCorner<3, 3>(); }
  const std::vector<int>& landmarkIds() const override { return book_.ids(); }
  bool hasLandmark(int id) const override { return book_.find(id) >= 0; }
  Vec2 landmark(int id) const override;
  Mat2 landmarkCovariance(int id) const override;
  Eigen::Matrix<double, Eigen::Dynamic, 2> landmarkCovarianceColumns(int id) const override {
    return sigma_.middleCols<2>(StateLayout::landmark(book_.require(id)));
  }
  FilterStats stats() const override;
  std::size_t robotLinks() const override { return landmarkIds().size(); }  // Sigma^-1 is dense
  std::size_t rejectedObservations() const override { return book_.rejected(); }
  std::size_t blocksTouched() const override {
    return (landmarkIds().size() + 1) * (landmarkIds().size() + 1);
  }

  Eigen::VectorXd mean() const override;
  Eigen::MatrixXd covariance() const override { return sigma_; }
  Eigen::MatrixXd information() const override;

 protected:
  Pose2 linearizationPose() const override { return mu_.head<3>(); }

 private:
  friend struct CheckpointAccess;  // checkpoints: src/filters/*_state.cpp
  void addLandmark(const Observation& z, const MeasurementModel& sensor);
  /// Deletes slot `slot`'s rows and columns, the last slot's moving into them.
  void deleteSlot(int slot);
  void applyPlan(std::span<const PlannedObservation> plan, const MeasurementModel& sensor);

  FilterConfig config_;
  LandmarkBook book_;
  Eigen::VectorXd mu_;     // heading kept unwrapped in the state; pose() wraps it
  Eigen::MatrixXd sigma_;
};

}  // namespace seif
