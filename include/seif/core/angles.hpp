#pragma once
#include <cmath>
#include <numbers>

namespace seif {

/// Wraps an angle to (-pi, pi]. Used for every heading and every bearing innovation.
inline double wrapAngle(double a) {
  a = std::remainder(a, 2.0 * std::numbers::pi);  // [-pi, pi]
  return a <= -std::numbers::pi ? a + 2.0 * std::numbers::pi : a;
}

/// The pose with its heading wrapped (filters keep the heading unwrapped internally).
template <typename Vector3>
Vector3 wrapHeading(Vector3 x) {
  x.z() = wrapAngle(x.z());
  return x;
}

}  // namespace seif
