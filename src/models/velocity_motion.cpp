#include <seif/core/angles.hpp>
#include "models/velocity_motion.hpp"

#include <cmath>

namespace seif {
namespace {

// sinc(a) = sin(a)/a and its derivative, with the Taylor series near 0 (the straight-line
// branch of the model). Series errors at |a| < 1e-3: a^6/5040 and a^5/840, below 1e-17.
struct Sinc {
  double value;
  double derivative;
};

Sinc sinc(double a) {
  if (std::abs(a) < 1e-3) {
    const double a2 = a * a;
    return {1.0 - a2 / 6.0 + a2 * a2 / 120.0, -a / 3.0 + a * a2 / 30.0};
  }
  const double s = std::sin(a);
  return {s / a, (a * std::cos(a) - s) / (a * a)};
}

}  // namespace

Vec3 VelocityMotionModel::delta(const Pose2& x, const VelocityControl& u, Mat3* J_delta_x,
                                Mat32* J_delta_u) {
  const double half = 0.5 * u.w * u.dt;  // a = w dt / 2
  const Sinc s = sinc(half);
  const double chord = u.v * u.dt * s.value;  // length of the chord from start to end
  const double c = std::cos(x.z() + half);
  const double sn = std::sin(x.z() + half);
  if (J_delta_x) {
    J_delta_x->setZero();
    (*J_delta_x)(0, 2) = -chord * sn;
    (*J_delta_x)(1, 2) = chord * c;
  }
  if (J_delta_u) {
    const double dchord_dw = u.v * u.dt * s.derivative * 0.5 * u.dt;
    (*J_delta_u) << u.dt * s.value * c, dchord_dw * c - chord * sn * 0.5 * u.dt,
        u.dt * s.value * sn, dchord_dw * sn + chord * c * 0.5 * u.dt,  //
        0.0, u.dt;
  }
  return {chord * c, chord * sn, u.w * u.dt};
}

Pose2 VelocityMotionModel::apply(const Pose2& x, const VelocityControl& u) {
  Pose2 next = x + delta(x, u);
  next.z() = wrapAngle(next.z());
  return next;
}

Mat3 VelocityMotionModel::processNoise(const Pose2& x, const VelocityControl& u,
                                       double sigma_v, double sigma_w) {
  Mat32 V;
  delta(x, u, nullptr, &V);
  const Eigen::Vector2d m(sigma_v * sigma_v, sigma_w * sigma_w);
  Mat3 U = V * m.asDiagonal() * V.transpose();
  return 0.5 * (U + U.transpose());
}

}  // namespace seif
