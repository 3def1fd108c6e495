#include <seif/core/errors.hpp>
#include "filters/outlier_gate.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace seif {

OutlierGate::OutlierGate(double sigmas) : sigmas_(sigmas), threshold_(sigmas * sigmas) {
  if (!(sigmas > 0.0)) {  // also NaN
    throw InvalidArgument("outlier gate must be > 0 standard deviations (infinity disables it), found " +
                                std::to_string(sigmas));
  }
}

bool OutlierGate::wouldReject(const MeasurementModel& sensor, const Pose2& x, const Vec2& y,
                              const Observation& z, const Mat2& Z_inv) const {
  if (std::isinf(sigmas_)) return false;
  const Vec2 nu = sensor.residual(z.z, sensor.predict(x, y));
  return !(nu.dot(Z_inv * nu) <= threshold_);  // NaN innovations are rejected too
}

bool OutlierGate::rejects(const MeasurementModel& sensor, const Pose2& x, const Vec2& y,
                          const Observation& z, const Mat2& Z_inv) {
  const bool reject = wouldReject(sensor, x, y, z, Z_inv);
  if (reject) ++rejected_;
  return reject;
}

}  // namespace seif
