#pragma once
// Velocity (v, w) motion model as a value (algorithm.md "Models"; kinematics in
// velocity_motion.hpp). Its noise, M = diag(sigma_v^2, sigma_w^2) in control space, maps to
// U = V M' V^T with V = dDelta/d(v, w), in one of two forms:
//   PerStep: M' = M for every input, whatever its dt - the paper's experiment, whose steps
//            all last dt = 1 (Thrun et al. 2002; `seif paper`, `seif simulate` worlds);
//   Rate:    M' = M / dt: sigma_v [m/s*sqrt(s)] and sigma_w [rad/s*sqrt(s)] are noise
//            densities, so U grows like dt and splitting an interval at a measurement stamp
//            injects the same noise as not splitting it (real logs: MRCLAM).
#include <seif/core/types.hpp>
#include <seif/models/motion_model.hpp>

#include <string_view>

namespace seif {

enum class NoiseForm { PerStep, Rate };

/// "per-step" | "rate"; throws InvalidArgument otherwise.
NoiseForm parseNoiseForm(std::string_view s);
std::string_view noiseFormName(NoiseForm form);

class VelocityModel final : public MotionModel {
 public:
  VelocityModel(double sigma_v, double sigma_w, NoiseForm form);

  std::string describe() const override;
  MotionIncrement linearize(const Pose2& x, const MotionInput& u) const override;
  bool equivariant() const override { return true; }
  MotionIncrement linearize(const Pose2& x, const VelocityControl& u) const;

  double sigmaV() const { return sigma_v_; }
  double sigmaW() const { return sigma_w_; }
  NoiseForm form() const { return form_; }

 private:
  double sigma_v_;
  double sigma_w_;
  NoiseForm form_;
};

/// Control-space noise M mapped to pose space by V (3x2), in the given form: V M V^T, or
/// V M V^T / dt for a rate (zero for dt = 0). Shared by every rate-driven model.
Mat3 controlNoiseToPose(const Mat32& V, double var_1, double var_2, NoiseForm form, double dt);

}  // namespace seif
