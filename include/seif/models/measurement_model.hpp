#pragma once
// The measurement seam (docs/architecture.md): a sensor mounted at a pose on the vehicle
// observes 2-D point landmarks. A model predicts z = h(s, y) from the sensor pose
//   s = x (+) mount = (x_xy + R(th) m_xy, th + m_th)
// with its Jacobians, inverts it to initialise a landmark, and forms the residual
// z - zhat (the bearing wrap of range-bearing lives in its residual, not in the filters).
// Each observation may carry its own 2x2 noise; the model's noise() is the default.
// A new sensor is one new MeasurementModel; no filter changes.
#include <seif/core/types.hpp>

#include <string>

namespace seif {

class MeasurementModel {
 public:
  /// `noise`: default 2x2 covariance (symmetric positive definite); `mount`: the sensor's
  /// pose in the vehicle frame. Throws ModelError for a noise that is not SPD or a mount
  /// that is not finite.
  MeasurementModel(const Mat2& noise, const Pose2& mount);
  virtual ~MeasurementModel() = default;

  /// One line for the console and metrics.json, with the parameters.
  virtual std::string describe() const = 0;

  /// Predicted measurement of landmark y from vehicle pose x, with J_z_x = dz/dx (2x3) and
  /// J_z_y = dz/dy (2x2). Throws ModelError where the model is degenerate.
  Vec2 predict(const Pose2& x, const Vec2& y, Mat23* J_z_x = nullptr, Mat2* J_z_y = nullptr) const;
  /// The landmark seen as z from vehicle pose x, with J_y_x (2x3) and J_y_z (2x2).
  Vec2 inverse(const Pose2& x, const Vec2& z, Mat23* J_y_x = nullptr, Mat2* J_y_z = nullptr) const;
  /// z - zhat in the measurement space (angles wrapped where the model has them).
  virtual Vec2 residual(const Vec2& z, const Vec2& zhat) const { return z - zhat; }
  /// Per component, the period its residual wraps with (0: none), e.g. 2 pi for a bearing.
  virtual Vec2 period() const { return Vec2::Zero(); }

  const Mat2& noise() const { return noise_; }
  /// The observation's own noise, else the default.
  const Mat2& noise(const Observation& z) const { return z.noise ? *z.noise : noise_; }
  const Pose2& mount() const { return mount_; }

 protected:
  /// The model in the sensor frame: z = h(s, y) with J_z_s (2x3) and J_z_y.
  virtual Vec2 predictFromSensor(const Pose2& s, const Vec2& y, Mat23* J_z_s, Mat2* J_z_y) const = 0;
  virtual Vec2 inverseFromSensor(const Pose2& s, const Vec2& z, Mat23* J_y_s, Mat2* J_y_z) const = 0;
  std::string describeMount() const;

 private:
  /// s = x (+) mount and ds/dx.
  Pose2 sensorPose(const Pose2& x, Mat3* J_s_x) const;

  Mat2 noise_;
  Pose2 mount_;
  bool mounted_;  // mount != 0 (at the origin the Jacobians pass through unchanged)
};

/// Noise with independent components: diag(sigma_1^2, sigma_2^2). Throws ModelError unless
/// both are finite and > 0.
Mat2 diagonalNoise(double sigma_1, double sigma_2);

}  // namespace seif
