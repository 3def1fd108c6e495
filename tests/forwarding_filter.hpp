// A SlamFilter that forwards every call to an EKF: tests derive from it to fail, count or
// record one call without writing the other thirty.
#pragma once

#include "filters/ekf_slam.hpp"
#include <seif/filters/slam_filter.hpp>

#include <string>
#include <vector>

namespace seif::test {

class ForwardingFilter : public SlamFilter {
 public:
  ForwardingFilter() : SlamFilter(paperFilterConfig(NoiseModel{})), ekf_(Pose2::Zero(), paperFilterConfig(NoiseModel{})) {}
  std::string name() const override { return "forwarding"; }
  using SlamFilter::predict;
  using SlamFilter::update;
  void predict(const MotionIncrement& m) override { ekf_.predict(m); }
  void update(std::span<const Observation> z, const MeasurementModel& sensor) override { ekf_.update(z, sensor); }
  Marginal marginal(std::span<const int> ids, bool pose, MarginalMode mode) const override {
    return ekf_.marginal(ids, pose, mode);
  }
  void removeLandmark(int id) override { ekf_.removeLandmark(id); }
  void mergeLandmarks(int keep, int drop) override { ekf_.mergeLandmarks(keep, drop); }
  Pose2 pose() const override { return ekf_.pose(); }
  Mat3 poseCovariance() const override { return ekf_.poseCovariance(); }
  const std::vector<int>& landmarkIds() const override { return ekf_.landmarkIds(); }
  bool hasLandmark(int id) const override { return ekf_.hasLandmark(id); }
  Vec2 landmark(int id) const override { return ekf_.landmark(id); }
  Mat2 landmarkCovariance(int id) const override { return ekf_.landmarkCovariance(id); }
  FilterStats stats() const override { return ekf_.stats(); }
  std::size_t robotLinks() const override { return ekf_.robotLinks(); }
  std::size_t blocksTouched() const override { return ekf_.blocksTouched(); }
  std::size_t rejectedObservations() const override { return ekf_.rejectedObservations(); }
  Eigen::VectorXd mean() const override { return ekf_.mean(); }
  Eigen::MatrixXd covariance() const override { return ekf_.covariance(); }
  Eigen::MatrixXd information() const override { return ekf_.information(); }

 private:
  EkfSlam ekf_;
};

}  // namespace seif::test
