#pragma once
// Car-like (Ackermann) vehicle (../shared/data/README.md, Victoria Park; Guivant & Nebot
// 2001). The input is the speed ve measured by an encoder on a rear wheel H metres left of
// the centre line and the steering angle alpha of the front wheels; the wheelbase is L:
//   vc = ve / (1 - tan(alpha) H / L),   w = vc tan(alpha) / L,
// and the rear axle's centre moves on the exact arc of (vc, w) for dt (velocity model).
// The state is the pose of a point p = (a, b) fixed on the body, in the axle's frame
// (`tracked_point`; 0 = the axle itself). Guivant and Nebot track the laser, so that
//   Delta = chord(th) + (R(th + w dt) - R(th)) p,
// the first-order form of which is their x' = x + dt vc (cos th - tan(alpha)(a sin th +
// b cos th) / L), .... Noise on (ve, alpha) in the given form (velocity_model.hpp).
#include <seif/models/velocity_model.hpp>

namespace seif {

struct AckermannGeometry {
  double wheelbase = 2.83;       ///< L [m]
  double encoder_offset = 0.76;  ///< H [m], encoder wheel left of the centre line
  Vec2 tracked_point = Vec2::Zero();  ///< (a, b) [m]: the point whose pose is the state
};

class AckermannModel final : public MotionModel {
 public:
  AckermannModel(const AckermannGeometry& geometry, double sigma_speed, double sigma_steering,
                 NoiseForm form);

  std::string describe() const override;
  MotionIncrement linearize(const Pose2& x, const MotionInput& u) const override;
  bool equivariant() const override { return true; }
  MotionIncrement linearize(const Pose2& x, const AckermannControl& u) const;

  /// (vc, w) of input u, with d(vc, w)/d(ve, alpha) when J is given. Throws ModelError where
  /// 1 - tan(alpha) H / L <= 0 or |alpha| >= pi/2.
  Eigen::Vector2d bodyVelocity(const AckermannControl& u, Eigen::Matrix2d* J = nullptr) const;

  const AckermannGeometry& geometry() const { return geometry_; }
  double sigmaSpeed() const { return sigma_speed_; }
  double sigmaSteering() const { return sigma_steering_; }
  NoiseForm form() const { return form_; }

 private:
  AckermannGeometry geometry_;
  double sigma_speed_;
  double sigma_steering_;
  NoiseForm form_;
};

}  // namespace seif
