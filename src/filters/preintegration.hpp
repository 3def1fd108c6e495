#pragma once
// Motion preintegration for the batch MAP: the steps between two kept poses composed into one
// motion in the frame of the first, with its full covariance, so that the batch keeps a pose
// only where an observation is made.
//
// Each step is a motion in the robot's frame, x' = x + Rot(theta) b + w, w ~ N(0, Rot U_b Rot^T)
// (the velocity, Ackermann and odometry models are all of this form: MotionModel::equivariant).
// In the frame of the segment's start a (x_a fixed), with p the relative pose after the steps
// so far and P its covariance, one more step gives (linearised at the noise-free path):
//   p' = p + Rot(phi) b,           phi = p_theta
//   P' = F P F^T + Rot(phi) U_b Rot(phi)^T,   F = I + [e_theta x (Rot(phi) b)_xy]   (dp'/dp)
// so that x_b = x_a + Rot(theta_a) B + w_B, w_B ~ N(0, Rot(theta_a) U_B Rot(theta_a)^T) with
// B = p, U_B = P after the last step: what stepping the EKF's prediction through the same steps
// from a certain x_a gives (tested). A single step is returned unchanged (U_B = U_b, of rank 2
// for the velocity model: the batch keeps its null space as a constraint, exactly).
#include <seif/core/types.hpp>

namespace seif {

/// The planar rotation by theta acting on a pose increment (x, y rotate, the heading stays).
Mat3 poseRotation(double theta);

/// dp_B/dp_k for a composed motion B and the relative pose p_k after one of its steps: a pose
/// error at that step carried rigidly to the end, [[1, 0, -(y_B - y_k)], [0, 1, x_B - x_k], [0, 0, 1]].
Mat3 preintegrationTransition(const Vec3& B, const Vec3& p_k);

class Preintegration {
 public:
  /// One step's motion b and covariance U_b, both in the robot's frame before the step.
  void add(const Vec3& b, const Mat3& U_b);
  void reset() { *this = Preintegration(); }

  const Vec3& delta() const { return delta_; }       ///< B: the relative pose (heading unwrapped)
  const Mat3& covariance() const { return U_; }      ///< U_B
  int steps() const { return steps_; }

 private:
  Vec3 delta_ = Vec3::Zero();
  Mat3 U_ = Mat3::Zero();
  int steps_ = 0;
};

}  // namespace seif
