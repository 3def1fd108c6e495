#pragma once
// EIF-SLAM: the exact extended information filter with a dense information matrix H and
// vector b (algorithm.md "The exact information filter"). Motion update in the closed
// form of paper Lemma 3 on the full matrix, measurement update paper eq. (21-22), and the
// mean recovered exactly by a Cholesky solve of H mu = b. Algebraically the EKF.
#include "filters/landmark_book.hpp"
#include <seif/filters/slam_filter.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <optional>

namespace seif {

class EifSlam final : public SlamFilter {
 public:
  EifSlam(const Pose2& initial_pose, const FilterConfig& config);

  std::string name() const override { return "eif"; }
  using SlamFilter::predict;
  using SlamFilter::update;
  void predict(const MotionIncrement& increment) override;
  void update(std::span<const Observation> observations, const MeasurementModel& sensor) override;
  /// Exact: solves with the cached dense factor; Local: the blanket's dense inverse.
  Marginal marginal(std::span<const int> landmarks, bool pose = true,
                    MarginalMode mode = MarginalMode::Exact) const override;

  void removeLandmark(int id) override;
  void mergeLandmarks(int keep, int drop) override;
  Pose2 pose() const override;
  Mat3 poseCovariance() const override;
  const std::vector<int>& landmarkIds() const override { return book_.ids(); }
  bool hasLandmark(int id) const override { return book_.find(id) >= 0; }
  Vec2 landmark(int id) const override;
  Mat2 landmarkCovariance(int id) const override;
  FilterStats stats() const override;
  std::size_t robotLinks() const override;
  std::size_t rejectedObservations() const override { return book_.rejected(); }
  std::size_t blocksTouched() const override {
    return (landmarkIds().size() + 1) * (landmarkIds().size() + 1);
  }

  Eigen::VectorXd mean() const override { return mu_; }
  Eigen::MatrixXd covariance() const override;
  Eigen::MatrixXd information() const override { return H_; }
  const Eigen::VectorXd& informationVector() const { return b_; }

 protected:
  Pose2 linearizationPose() const override { return mu_.head<3>(); }

 private:
  friend struct CheckpointAccess;  // checkpoints: src/filters/*_state.cpp
  void recoverMean();
  /// Deletes slot `slot`'s rows and columns of H, b, mu, the last slot's moving into them.
  void deleteSlot(int slot);
  void applyPlan(std::span<const PlannedObservation> plan, const MeasurementModel& sensor);
  /// applyPlan() for FilterConfig::iterations > 1 or the invariant linearisation.
  void applyIterated(std::span<const PlannedObservation> plan, const MeasurementModel& sensor);
  const Eigen::LLT<Eigen::MatrixXd>& factor() const;

  FilterConfig config_;
  LandmarkBook book_;
  Eigen::MatrixXd H_;
  Eigen::VectorXd b_;
  Eigen::VectorXd mu_;
  mutable Eigen::LLT<Eigen::MatrixXd> llt_;
  mutable bool llt_valid_ = false;
};

}  // namespace seif
