#pragma once
// The motion seam (docs/architecture.md): a motion model linearises one input at a pose to
// a MotionIncrement, which is all a filter consumes (algorithm.md "Models"):
//   s_t = s_{t-1} + S_x (delta + w),  w ~ N(0, U),  G_x = I_3 + J_delta_x.
// A new vehicle is one new MotionModel; no filter changes.
#include <seif/core/types.hpp>

#include <string>

namespace seif {

struct MotionIncrement {
  Vec3 delta = Vec3::Zero();      ///< pose increment Delta(x, u)
  Mat3 J_delta_x = Mat3::Zero();  ///< dDelta/dx
  Mat3 U = Mat3::Zero();          ///< process noise in pose space (may be singular)
};

/// Throws ModelError "<who>: ..." unless every entry of `m` is finite and its process noise U
/// is positive semidefinite (principal minors >= 0 up to rounding): what a filter's predict
/// checks before it changes anything.
void checkIncrement(const MotionIncrement& m, const std::string& who);

/// `first` then `second` (linearised at the pose `first` predicts) as one increment: with
/// x' = x + Delta + J (x - mu) + w, w ~ N(0, U), and G = I + J,
/// Delta = Delta_1 + Delta_2, G = G_2 G_1, U = G_2 U_1 G_2^T + U_2 (heading not wrapped).
MotionIncrement compose(const MotionIncrement& first, const MotionIncrement& second);

class MotionModel {
 public:
  virtual ~MotionModel() = default;
  /// One line for the console and metrics.json, with the parameters.
  virtual std::string describe() const = 0;
  /// The increment of input u at pose x. Throws ModelError when u is not this model's
  /// input type, or x, u or the increment is not finite.
  virtual MotionIncrement linearize(const Pose2& x, const MotionInput& u) const = 0;
  /// True when every increment is a fixed motion in the robot's frame: Delta(x, u) =
  /// Rot(theta) Delta_body(u) and U(x, u) = Rot(theta) U_body(u) Rot(theta)^T, whatever x
  /// (the velocity, Ackermann and odometry models). The batch MAP then composes the steps
  /// between observations into one (preintegration) instead of keeping a pose per step.
  virtual bool equivariant() const { return false; }
  /// x + Delta(x, u), heading wrapped to (-pi, pi] (dead reckoning).
  Pose2 apply(const Pose2& x, const MotionInput& u) const;
};

}  // namespace seif
