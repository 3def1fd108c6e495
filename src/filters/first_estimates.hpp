#pragma once
// First-estimates Jacobians (FEJ; Huang, Mourikis, Roumeliotis, "Observability-based rules
// for designing consistent EKF SLAM estimators", IJRR 2010, §5): what a filter remembers to
// linearise every Jacobian at the first estimate of each quantity, so that the linearised
// system keeps the unobservable directions (global translation and rotation) of the real
// one. One instance per filter with Linearization::FirstEstimates; EKF, EIF and SEIF share it.
#include <seif/core/types.hpp>
#include <seif/models/motion_model.hpp>

#include <vector>

namespace seif {

/// Where the observability-constrained EKF (Linearization::ObservabilityConstrained) takes
/// the unobservable directions of one observation's Jacobian: N = [I J p; 0 1; I J l] over
/// (x, y, th, lx, ly), p the predicted robot position p_{k|k-1}, l the landmark's first
/// estimate, J the quarter turn (Huang, Mourikis, Roumeliotis, IJRR 2010).
struct ObservabilityConstraint {
  Vec2 robot = Vec2::Zero();
  Vec2 landmark = Vec2::Zero();
  /// J* = J - J N (N^T N)^-1 N^T on [J_x | J_y]: the closest Jacobian (Frobenius norm) with
  /// J* N = 0.
  void apply(Mat23& J_x, Mat2& J_y) const;
};

class FirstEstimates {
 public:
  /// p_{0|-1} = the start position (there is no earlier prediction).
  explicit FirstEstimates(const Pose2& start) : predicted_(start.head<2>()) {}

  /// The motion increment with the FEJ-EKF's state Jacobian (Huang et al. 2010): its
  /// heading column (dDelta/dth = S delta_xy, S = [0 -1; 1 0], for every planar model) becomes
  /// S (p_{k+1|k} - p_{k|k-1}), with p_{k+1|k} = `position` + delta_xy and `position` the
  /// filter's position p_{k|k} the increment was linearised at. delta and U are unchanged.
  /// Records p_{k+1|k} as the next step's p_{k|k-1}.
  MotionIncrement fejIncrement(const MotionIncrement& m, const Vec2& position);

  /// p_{k|k-1}: the position the last fejIncrement() predicted (before any update), where
  /// the measurement Jacobians of this step take the robot.
  const Vec2& predictedPosition() const { return predicted_; }
  /// Back to an earlier state: the prediction, and the first `landmarks` landmarks (a step undone).
  void restore(const Vec2& predicted, int landmarks) {
    predicted_ = predicted;
    landmarks_.resize(static_cast<std::size_t>(landmarks));
  }

  /// Records a new landmark's first estimate (its mean when initialised), in slot order.
  void addLandmark(const Vec2& first) { landmarks_.push_back(first); }
  /// The first estimate of the landmark in `slot`, where its measurement Jacobians are
  /// evaluated (the FEJ-EKF's measurement Jacobian).
  const Vec2& landmark(int slot) const { return landmarks_[static_cast<std::size_t>(slot)]; }
  int size() const { return static_cast<int>(landmarks_.size()); }
  /// Removes slot `slot`; the last takes its place (LandmarkBook::removeSlot).
  void removeSlot(int slot) {
    landmarks_[static_cast<std::size_t>(slot)] = landmarks_.back();
    landmarks_.pop_back();
  }

 private:
  Vec2 predicted_;
  std::vector<Vec2> landmarks_;
};

}  // namespace seif
