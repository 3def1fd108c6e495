// The measurement models behind the MeasurementModel seam (include/seif/models/).
#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/models/cartesian.hpp>
#include <seif/models/range_bearing.hpp>

#include <Eigen/Cholesky>
#include <cmath>
#include <numbers>
#include <sstream>

namespace seif {

Mat2 diagonalNoise(double sigma_1, double sigma_2) {
  // A negative sigma would pass squared: refused here, as the motion models refuse theirs.
  if (!(std::isfinite(sigma_1) && sigma_1 > 0.0 && std::isfinite(sigma_2) && sigma_2 > 0.0)) {
    std::ostringstream msg;
    msg << "noise standard deviations must be finite and > 0, found " << sigma_1 << " and " << sigma_2;
    throw ModelError(msg.str());
  }
  return Eigen::Vector2d(sigma_1 * sigma_1, sigma_2 * sigma_2).asDiagonal();
}

MeasurementModel::MeasurementModel(const Mat2& noise, const Pose2& mount)
    : noise_(noise), mount_(mount), mounted_(!mount.isZero(0.0)) {
  if (!noise.allFinite() || noise(0, 1) != noise(1, 0) || Eigen::LLT<Mat2>(noise).info() != Eigen::Success) {
    std::ostringstream msg;
    msg << "measurement noise must be a finite symmetric positive definite 2x2 matrix, found ["
        << noise(0, 0) << ", " << noise(0, 1) << "; " << noise(1, 0) << ", " << noise(1, 1) << "]";
    throw ModelError(msg.str());
  }
  if (!mount.allFinite()) throw ModelError("sensor mount must be finite");
}

std::string MeasurementModel::describeMount() const {
  if (!mounted_) return "at the vehicle's origin";
  std::ostringstream s;
  s << "mounted at (" << mount_.x() << ", " << mount_.y() << ") m, " << mount_.z() << " rad";
  return s.str();
}

Pose2 MeasurementModel::sensorPose(const Pose2& x, Mat3* J_s_x) const {
  const double c = std::cos(x.z()), s = std::sin(x.z());
  const double mx = mount_.x(), my = mount_.y();
  if (J_s_x) {
    *J_s_x << 1.0, 0.0, -s * mx - c * my,  //
        0.0, 1.0, c * mx - s * my,         //
        0.0, 0.0, 1.0;
  }
  return {x.x() + c * mx - s * my, x.y() + s * mx + c * my, x.z() + mount_.z()};
}

Vec2 MeasurementModel::predict(const Pose2& x, const Vec2& y, Mat23* J_z_x, Mat2* J_z_y) const {
  if (!mounted_) return predictFromSensor(x, y, J_z_x, J_z_y);
  Mat3 J_s_x;
  Mat23 J_z_s;
  const Vec2 z = predictFromSensor(sensorPose(x, &J_s_x), y, J_z_x ? &J_z_s : nullptr, J_z_y);
  if (J_z_x) *J_z_x = J_z_s * J_s_x;
  return z;
}

Vec2 MeasurementModel::inverse(const Pose2& x, const Vec2& z, Mat23* J_y_x, Mat2* J_y_z) const {
  if (!mounted_) return inverseFromSensor(x, z, J_y_x, J_y_z);
  Mat3 J_s_x;
  Mat23 J_y_s;
  const Vec2 y = inverseFromSensor(sensorPose(x, &J_s_x), z, J_y_x ? &J_y_s : nullptr, J_y_z);
  if (J_y_x) *J_y_x = J_y_s * J_s_x;
  return y;
}

// --- range-bearing -------------------------------------------------------------------------

RangeBearingModel::RangeBearingModel(double sigma_range, double sigma_bearing, const Pose2& mount)
    : MeasurementModel(diagonalNoise(sigma_range, sigma_bearing), mount) {}

RangeBearingModel::RangeBearingModel(const Mat2& noise, const Pose2& mount) : MeasurementModel(noise, mount) {}

std::string RangeBearingModel::describe() const {
  std::ostringstream s;
  s << "range-bearing: sigma_range " << std::sqrt(noise()(0, 0)) << " m, sigma_bearing "
    << std::sqrt(noise()(1, 1)) << " rad (default), " << describeMount();
  return s.str();
}

Vec2 RangeBearingModel::predictFromSensor(const Pose2& x, const Vec2& y, Mat23* J_z_x, Mat2* J_z_y) const {
  const Vec2 d = y - x.head<2>();
  const double q = d.squaredNorm();
  const double r = std::sqrt(q);
  if (!(r >= kMinRange)) {
    std::ostringstream msg;
    msg << "range-bearing prediction is degenerate: landmark at (" << y.x() << ", " << y.y()
        << ") coincides with the sensor (range " << r << ")";
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

Vec2 RangeBearingModel::inverseFromSensor(const Pose2& x, const Vec2& z, Mat23* J_y_x, Mat2* J_y_z) const {
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

Vec2 RangeBearingModel::residual(const Vec2& z, const Vec2& zhat) const {
  return {z.x() - zhat.x(), wrapAngle(z.y() - zhat.y())};
}

Vec2 RangeBearingModel::period() const { return {0.0, 2.0 * std::numbers::pi}; }

// --- Cartesian -----------------------------------------------------------------------------

CartesianModel::CartesianModel(const Mat2& noise, const Pose2& mount) : MeasurementModel(noise, mount) {}

std::string CartesianModel::describe() const {
  std::ostringstream s;
  s << "Cartesian (x, y): default covariance [" << noise()(0, 0) << ", " << noise()(0, 1) << "; "
    << noise()(1, 0) << ", " << noise()(1, 1) << "] m^2, " << describeMount();
  return s.str();
}

Vec2 CartesianModel::predictFromSensor(const Pose2& s, const Vec2& y, Mat23* J_z_s, Mat2* J_z_y) const {
  if (!s.allFinite() || !y.allFinite()) throw ModelError("Cartesian prediction: pose or landmark is not finite");
  const double c = std::cos(s.z()), sn = std::sin(s.z());
  const Vec2 d = y - s.head<2>();
  Mat2 Rt;
  Rt << c, sn, -sn, c;  // R(th)^T
  if (J_z_s) {
    J_z_s->leftCols<2>() = -Rt;
    J_z_s->col(2) << -sn * d.x() + c * d.y(), -c * d.x() - sn * d.y();
  }
  if (J_z_y) *J_z_y = Rt;
  return Rt * d;
}

Vec2 CartesianModel::inverseFromSensor(const Pose2& s, const Vec2& z, Mat23* J_y_s, Mat2* J_y_z) const {
  if (!s.allFinite() || !z.allFinite()) throw ModelError("cannot place a landmark from a non-finite Cartesian measurement");
  const double c = std::cos(s.z()), sn = std::sin(s.z());
  Mat2 R;
  R << c, -sn, sn, c;
  if (J_y_s) {
    J_y_s->leftCols<2>().setIdentity();
    J_y_s->col(2) << -sn * z.x() - c * z.y(), c * z.x() - sn * z.y();
  }
  if (J_y_z) *J_y_z = R;
  return s.head<2>() + R * z;
}

}  // namespace seif
