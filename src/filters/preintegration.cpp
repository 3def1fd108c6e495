#include "filters/preintegration.hpp"

#include <cmath>

namespace seif {

void Preintegration::add(const Vec3& b, const Mat3& U_b) {
  if (steps_ == 0) {  // exactly the step itself
    delta_ = b;
    U_ = U_b;
    steps_ = 1;
    return;
  }
  const Mat3 R = poseRotation(delta_(2));
  const Vec3 step = R * b;
  Mat3 F = Mat3::Identity();
  F(0, 2) = -step(1);
  F(1, 2) = step(0);
  U_ = F * U_ * F.transpose() + R * U_b * R.transpose();
  U_ = 0.5 * (U_ + U_.transpose());
  delta_ += step;
  ++steps_;
}

Mat3 poseRotation(double theta) {
  const double c = std::cos(theta), s = std::sin(theta);
  Mat3 R;
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  return R;
}

Mat3 preintegrationTransition(const Vec3& B, const Vec3& p_k) {
  Mat3 T = Mat3::Identity();
  T(0, 2) = -(B(1) - p_k(1));
  T(1, 2) = B(0) - p_k(0);
  return T;
}

}  // namespace seif
