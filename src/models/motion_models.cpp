// The motion models behind the MotionModel seam (include/seif/models/*_model.hpp).
#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/models/ackermann_model.hpp>
#include <seif/models/odometry_model.hpp>
#include <seif/models/velocity_model.hpp>
#include "models/velocity_motion.hpp"

#include <Eigen/LU>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace seif {
namespace {

template <class Input>
const Input& inputOf(const MotionInput& u, const char* model, const char* expected) {
  const Input* in = std::get_if<Input>(&u);
  if (!in) throw ModelError(std::string(model) + " motion model takes " + expected + " inputs");
  return *in;
}

void requireSigma(double sigma, const char* what) {
  if (!std::isfinite(sigma) || !(sigma >= 0.0)) {
    throw ModelError(std::string(what) + " must be finite and >= 0, found " + std::to_string(sigma));
  }
}

void requireDt(double dt) {
  if (!std::isfinite(dt) || dt < 0.0) throw ModelError("motion input: dt must be finite and >= 0, found " + std::to_string(dt));
}

}  // namespace

namespace {
/// The increment of a model's public linearize(): finite (a non-finite pose or input gives
/// none), its noise positive semi-definite.
MotionIncrement checked(const Pose2& x, MotionIncrement m, const char* who) {
  if (!x.allFinite()) throw ModelError(std::string(who) + ": the pose is not finite");
  checkIncrement(m, who);
  return m;
}
}  // namespace

void checkIncrement(const MotionIncrement& m, const std::string& who) {
  if (!m.delta.allFinite() || !m.J_delta_x.allFinite() || !m.U.allFinite()) {
    throw ModelError(who + ": the motion increment is not finite");
  }
  // U >= 0 iff every principal minor is >= 0; rounding may leave a singular U's slightly below.
  const Mat3& U = m.U;
  const double tol = 1e-9;
  bool psd = U.diagonal().minCoeff() >= 0.0 && (U - U.transpose()).cwiseAbs().maxCoeff() <= tol * U.cwiseAbs().maxCoeff();
  for (int i = 0; psd && i < 3; ++i) {
    for (int j = i + 1; j < 3; ++j) {
      psd = psd && U(i, i) * U(j, j) - U(i, j) * U(j, i) >= -tol * U(i, i) * U(j, j);
    }
  }
  psd = psd && U.determinant() >= -tol * U(0, 0) * U(1, 1) * U(2, 2);
  if (!psd) throw ModelError(who + ": the motion increment's process noise U is not positive semidefinite");
}

MotionIncrement compose(const MotionIncrement& first, const MotionIncrement& second) {
  const Mat3 G2 = Mat3::Identity() + second.J_delta_x;
  MotionIncrement c;
  c.delta = first.delta + second.delta;
  c.J_delta_x = G2 * (Mat3::Identity() + first.J_delta_x) - Mat3::Identity();
  c.U = G2 * first.U * G2.transpose() + second.U;
  return c;
}

Pose2 MotionModel::apply(const Pose2& x, const MotionInput& u) const {
  Pose2 next = x + linearize(x, u).delta;
  next.z() = wrapAngle(next.z());
  return next;
}

NoiseForm parseNoiseForm(std::string_view s) {
  if (s == "per-step") return NoiseForm::PerStep;
  if (s == "rate") return NoiseForm::Rate;
  throw InvalidArgument("unknown noise form '" + std::string(s) + "' (expected per-step or rate)");
}

std::string_view noiseFormName(NoiseForm form) { return form == NoiseForm::Rate ? "rate" : "per-step"; }

Mat3 controlNoiseToPose(const Mat32& V, double var_1, double var_2, NoiseForm form, double dt) {
  if (form == NoiseForm::Rate) {
    if (!(dt > 0.0)) return Mat3::Zero();  // no time, no noise
    var_1 /= dt;
    var_2 /= dt;
  }
  const Eigen::Vector2d m(var_1, var_2);
  const Mat3 U = V * m.asDiagonal() * V.transpose();
  return 0.5 * (U + U.transpose());
}

// --- velocity ------------------------------------------------------------------------------

VelocityModel::VelocityModel(double sigma_v, double sigma_w, NoiseForm form)
    : sigma_v_(sigma_v), sigma_w_(sigma_w), form_(form) {
  requireSigma(sigma_v, "velocity model: sigma_v");
  requireSigma(sigma_w, "velocity model: sigma_w");
}

std::string VelocityModel::describe() const {
  std::ostringstream s;
  const char* unit = form_ == NoiseForm::Rate ? "*sqrt(s)" : " per step";
  s << "velocity (v, w): sigma_v " << sigma_v_ << " m/s" << unit << ", sigma_w " << sigma_w_
    << " rad/s" << unit << " (" << noiseFormName(form_) << " noise)";
  return s.str();
}

MotionIncrement VelocityModel::linearize(const Pose2& x, const VelocityControl& u) const {
  requireDt(u.dt);
  MotionIncrement m;
  Mat32 V;
  m.delta = VelocityMotionModel::delta(x, u, &m.J_delta_x, &V);
  m.U = controlNoiseToPose(V, sigma_v_ * sigma_v_, sigma_w_ * sigma_w_, form_, u.dt);
  return m;
}

MotionIncrement VelocityModel::linearize(const Pose2& x, const MotionInput& u) const {
  return checked(x, linearize(x, inputOf<VelocityControl>(u, "the velocity", "velocity (v, w)")), "velocity model");
}

// --- Ackermann -----------------------------------------------------------------------------

AckermannModel::AckermannModel(const AckermannGeometry& geometry, double sigma_speed,
                               double sigma_steering, NoiseForm form)
    : geometry_(geometry), sigma_speed_(sigma_speed), sigma_steering_(sigma_steering), form_(form) {
  if (!std::isfinite(geometry.wheelbase) || !(geometry.wheelbase > 0.0) || !std::isfinite(geometry.encoder_offset) ||
      !geometry.tracked_point.allFinite()) {
    throw ModelError("Ackermann model: the wheelbase must be finite and > 0, the offsets finite");
  }
  requireSigma(sigma_speed, "Ackermann model: sigma_speed");
  requireSigma(sigma_steering, "Ackermann model: sigma_steering");
}

std::string AckermannModel::describe() const {
  std::ostringstream s;
  const char* unit = form_ == NoiseForm::Rate ? "*sqrt(s)" : " per step";
  s << "Ackermann (encoder speed, steering): L " << geometry_.wheelbase << " m, H "
    << geometry_.encoder_offset << " m, state at (" << geometry_.tracked_point.x() << ", "
    << geometry_.tracked_point.y() << ") m from the rear axle, sigma_speed " << sigma_speed_ << " m/s" << unit
    << ", sigma_steering " << sigma_steering_ << " rad" << (form_ == NoiseForm::Rate ? "*sqrt(s)" : " per step")
    << " (" << noiseFormName(form_) << " noise)";
  return s.str();
}

Eigen::Vector2d AckermannModel::bodyVelocity(const AckermannControl& u, Eigen::Matrix2d* J) const {
  const double L = geometry_.wheelbase, H = geometry_.encoder_offset;
  if (!std::isfinite(u.speed) || !std::isfinite(u.steering) || std::abs(u.steering) >= 0.5 * M_PI) {
    throw ModelError("Ackermann model: speed and steering must be finite, |steering| < pi/2");
  }
  const double t = std::tan(u.steering);
  const double k = 1.0 - t * H / L;  // vc = ve / k
  if (!(k > 1e-9)) throw ModelError("Ackermann model: steering " + std::to_string(u.steering) + " rad puts the encoder wheel on the turn's centre");
  const double vc = u.speed / k;
  const double w = vc * t / L;
  if (J) {
    const double dt_da = 1.0 + t * t;            // d tan / d alpha
    const double dvc_da = u.speed * (H / L) * dt_da / (k * k);
    (*J) << 1.0 / k, dvc_da,                     // d vc / d(ve, alpha)
        t / (L * k), (dvc_da * t + vc * dt_da) / L;  // d w / d(ve, alpha)
  }
  return {vc, w};
}

MotionIncrement AckermannModel::linearize(const Pose2& x, const AckermannControl& u) const {
  requireDt(u.dt);
  Eigen::Matrix2d J_body;
  const Eigen::Vector2d vw = bodyVelocity(u, &J_body);
  MotionIncrement m;
  Mat32 V;
  m.delta = VelocityMotionModel::delta(x, {vw(0), vw(1), u.dt}, &m.J_delta_x, &V);
  const Vec2& p = geometry_.tracked_point;
  if (!p.isZero(0.0)) {  // + (R(th + w dt) - R(th)) p: the point turns about the axle
    const double th0 = x.z(), th1 = x.z() + vw(1) * u.dt;
    const Vec2 r0(std::cos(th0) * p.x() - std::sin(th0) * p.y(), std::sin(th0) * p.x() + std::cos(th0) * p.y());
    const Vec2 r1(std::cos(th1) * p.x() - std::sin(th1) * p.y(), std::sin(th1) * p.x() + std::cos(th1) * p.y());
    const Vec2 dr1(-r1.y(), r1.x()), dr0(-r0.y(), r0.x());  // d/dth of R(th) p
    m.delta.head<2>() += r1 - r0;
    m.J_delta_x.block<2, 1>(0, 2) += dr1 - dr0;
    V.block<2, 1>(0, 1) += dr1 * u.dt;  // d/dw
  }
  m.U = controlNoiseToPose(V * J_body, sigma_speed_ * sigma_speed_, sigma_steering_ * sigma_steering_, form_, u.dt);
  return m;
}

MotionIncrement AckermannModel::linearize(const Pose2& x, const MotionInput& u) const {
  return checked(x, linearize(x, inputOf<AckermannControl>(u, "the Ackermann", "Ackermann (speed, steering)")), "Ackermann model");
}

// --- relative odometry ---------------------------------------------------------------------

std::string OdometryModel::describe() const {
  return "relative odometry (dx, dy, dtheta) with the covariance of each record";
}

MotionIncrement OdometryModel::linearize(const Pose2& x, const OdometryIncrement& u) const {
  if (!u.delta.allFinite() || !u.covariance.allFinite()) throw ModelError("odometry increment is not finite");
  const double c = std::cos(x.z()), s = std::sin(x.z());
  const double dx = u.delta.x(), dy = u.delta.y();
  MotionIncrement m;
  m.delta << c * dx - s * dy, s * dx + c * dy, u.delta.z();
  m.J_delta_x(0, 2) = -s * dx - c * dy;
  m.J_delta_x(1, 2) = c * dx - s * dy;
  Mat3 J = Mat3::Identity();
  J.topLeftCorner<2, 2>() << c, -s, s, c;
  const Mat3 U = J * u.covariance * J.transpose();
  m.U = 0.5 * (U + U.transpose());
  return m;
}

MotionIncrement OdometryModel::linearize(const Pose2& x, const MotionInput& u) const {
  return checked(x, linearize(x, inputOf<OdometryIncrement>(u, "the relative-odometry", "odometry (dx, dy, dtheta)")),
                 "odometry model");
}

}  // namespace seif
