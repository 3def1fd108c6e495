#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/models/range_bearing.hpp>

#include <cmath>
#include <sstream>

namespace seif {

Vec2 RangeBearingModel::predict(const Pose2& x, const Vec2& y, Mat23* J_z_x, Mat2* J_z_y) {
  const Vec2 d = y - x.head<2>();
  const double q = d.squaredNorm();
  const double r = std::sqrt(q);
  if (!(r >= kMinRange)) {
    std::ostringstream msg;
    msg << "range-bearing prediction is degenerate: landmark at (" << y.x() << ", " << y.y()
        << ") coincides with the robot (range " << r << ")";
    throw ModelError(msg.str());
  }
  if (J_z_x) {
    *J_z_x << -d.x() / r, -d.y() / r, 0.0,  //
        d.y() / q, -d.x() / q, -1.0;
  }
  if (J_z_y) {
    *J_z_y << d.x() / r, d.y() / r,  //
        -d.y() / q, d.x() / q;
  }
  return {r, wrapAngle(std::atan2(d.y(), d.x()) - x.z())};
}

Vec2 RangeBearingModel::inverse(const Pose2& x, const Vec2& z, Mat23* J_y_x, Mat2* J_y_z) {
  if (!(z.x() > 0.0) || !std::isfinite(z.x()) || !std::isfinite(z.y()) || !x.allFinite()) {
    std::ostringstream msg;
    msg << "cannot place a landmark from range " << z.x() << " and bearing " << z.y()
        << ": the range must be positive and finite";
    throw ModelError(msg.str());
  }
  const double a = x.z() + z.y();
  const double c = std::cos(a);
  const double s = std::sin(a);
  if (J_y_x) {
    *J_y_x << 1.0, 0.0, -z.x() * s,  //
        0.0, 1.0, z.x() * c;
  }
  if (J_y_z) {
    *J_y_z << c, -z.x() * s,  //
        s, z.x() * c;
  }
  return {x.x() + z.x() * c, x.y() + z.x() * s};
}

Vec2 RangeBearingModel::innovation(const Vec2& z, const Vec2& zhat) {
  return {z.x() - zhat.x(), wrapAngle(z.y() - zhat.y())};
}

Mat2 RangeBearingModel::noise(double sigma_range, double sigma_bearing) {
  return Eigen::Vector2d(sigma_range * sigma_range, sigma_bearing * sigma_bearing).asDiagonal();
}

}  // namespace seif
