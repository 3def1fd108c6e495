// Every Jacobian of the models against central differences, at 1000 seeded random points
// and at the edge cases: heading near +-pi, w -> 0, landmark straight ahead or behind.
#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/models/range_bearing.hpp>
#include "models/velocity_motion.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "numeric_jacobian.hpp"

#include <numbers>
#include <random>

namespace {

using namespace seif;
constexpr double kPi = std::numbers::pi;

void expectNear(const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& numeric,
                const std::string& what) {
  const double scale = std::max(1.0, numeric.cwiseAbs().maxCoeff());
  EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-6 * scale)
      << what << "\nanalytic\n" << analytic << "\nnumeric\n" << numeric;
}

void checkMotion(const Pose2& x, const VelocityControl& u) {
  Mat3 J_x;
  Mat32 J_u;
  VelocityMotionModel::delta(x, u, &J_x, &J_u);
  auto fx = [&](const Vec3& xx) { return VelocityMotionModel::delta(xx, u); };
  auto fu = [&](const Eigen::Vector2d& vw) {
    return VelocityMotionModel::delta(x, {vw(0), vw(1), u.dt});
  };
  expectNear(J_x, test::numericJacobian<3, 3>(fx, x), "J_delta_x");
  expectNear(J_u, test::numericJacobian<3, 2>(fu, Eigen::Vector2d(u.v, u.w)), "J_delta_u");
}

void checkMeasurement(const Pose2& x, const Vec2& y) {
  Mat23 J_x;
  Mat2 J_y;
  RangeBearingModel(1.0, 1.0).predict(x, y, &J_x, &J_y);
  auto fx = [&](const Vec3& xx) { return RangeBearingModel(1.0, 1.0).predict(xx, y); };
  auto fy = [&](const Vec2& yy) { return RangeBearingModel(1.0, 1.0).predict(x, yy); };
  expectNear(J_x, test::numericJacobian<2, 3>(fx, x, 1), "J_z_x");
  expectNear(J_y, test::numericJacobian<2, 2>(fy, y, 1), "J_z_y");
}

void checkInverse(const Pose2& x, const Vec2& z) {
  Mat23 J_x;
  Mat2 J_z;
  RangeBearingModel(1.0, 1.0).inverse(x, z, &J_x, &J_z);
  auto fx = [&](const Vec3& xx) { return RangeBearingModel(1.0, 1.0).inverse(xx, z); };
  auto fz = [&](const Vec2& zz) { return RangeBearingModel(1.0, 1.0).inverse(x, zz); };
  expectNear(J_x, test::numericJacobian<2, 3>(fx, x), "J_y_x");
  expectNear(J_z, test::numericJacobian<2, 2>(fz, z), "J_y_z");
}

}  // namespace

TEST(VelocityMotionModel, JacobiansMatchCentralDifferencesAtRandomPoints) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> pos(-10, 10), th(-kPi, kPi), v(-2, 2), w(-3, 3),
      dt(0.01, 2.0);
  for (int i = 0; i < 1000; ++i) {
    checkMotion(Pose2(pos(rng), pos(rng), th(rng)), {v(rng), w(rng), dt(rng)});
  }
}

TEST(VelocityMotionModel, JacobiansAtEdgeCases) {
  for (double heading : {kPi - 1e-9, -kPi + 1e-9, kPi, 0.0}) {
    for (double w : {0.0, 1e-12, -1e-7, 1e-4, 2e-3, 0.5}) {
      checkMotion(Pose2(1.0, -2.0, heading), {0.7, w, 1.0});
    }
  }
}

TEST(VelocityMotionModel, EqualsCircularArcAndStraightLineLimits) {
  const Pose2 x(0.3, -0.4, 2.9);
  for (double w : {0.8, -0.3, 0.05, 2e-3}) {  // circular arc formula of the book
    const VelocityControl u{1.3, w, 0.7};
    const double r = u.v / u.w;
    const Vec3 arc(-r * std::sin(x.z()) + r * std::sin(x.z() + w * u.dt),
                   r * std::cos(x.z()) - r * std::cos(x.z() + w * u.dt), w * u.dt);
    EXPECT_LT((VelocityMotionModel::delta(x, u) - arc).norm(), 1e-12) << "w=" << w;
  }
  for (double w : {0.0, 1e-10, -1e-6}) {  // straight-line branch
    const VelocityControl u{1.3, w, 0.7};
    const Vec3 line(u.v * u.dt * std::cos(x.z()), u.v * u.dt * std::sin(x.z()), w * u.dt);
    EXPECT_LT((VelocityMotionModel::delta(x, u) - line).norm(), 1e-6) << "w=" << w;
  }
  // Continuity across the series threshold |w dt / 2| = 1e-3.
  const Vec3 below = VelocityMotionModel::delta(x, {1.0, 2e-3 - 1e-12, 1.0});
  const Vec3 above = VelocityMotionModel::delta(x, {1.0, 2e-3 + 1e-12, 1.0});
  EXPECT_LT((below - above).norm(), 1e-11);
}

TEST(VelocityMotionModel, ProcessNoiseIsSymmetricPositiveSemidefinite) {
  const Mat3 U = VelocityMotionModel::processNoise(Pose2(0, 0, 1), {1.0, 0.3, 0.5}, 0.1, 0.05);
  EXPECT_LT((U - U.transpose()).norm(), 1e-15);
  Eigen::SelfAdjointEigenSolver<Mat3> es(U);
  EXPECT_GE(es.eigenvalues().minCoeff(), -1e-15);
  EXPECT_NEAR(U(2, 2), 0.05 * 0.05 * 0.25, 1e-15);  // heading variance = (sigma_w dt)^2
}

TEST(RangeBearingModel, JacobiansMatchCentralDifferencesAtRandomPoints) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> pos(-10, 10), th(-kPi, kPi);
  for (int i = 0; i < 1000; ++i) {
    const Pose2 x(pos(rng), pos(rng), th(rng));
    Vec2 y(pos(rng), pos(rng));
    if ((y - x.head<2>()).norm() < 0.05) y.x() += 1.0;
    checkMeasurement(x, y);
  }
}

TEST(RangeBearingModel, InverseJacobiansMatchCentralDifferencesAtRandomPoints) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> pos(-10, 10), th(-kPi, kPi), r(0.01, 20);
  for (int i = 0; i < 1000; ++i) {
    checkInverse(Pose2(pos(rng), pos(rng), th(rng)), Vec2(r(rng), th(rng)));
  }
}

TEST(RangeBearingModel, EdgeCasesAheadBehindAndAcrossTheSeam) {
  for (double heading : {0.0, kPi - 1e-9, -kPi + 1e-9, kPi / 2}) {
    const Pose2 x(1.0, 2.0, heading);
    const Vec2 ahead = x.head<2>() + 3.0 * Vec2(std::cos(heading), std::sin(heading));
    const Vec2 behind = x.head<2>() - 3.0 * Vec2(std::cos(heading), std::sin(heading));
    checkMeasurement(x, ahead);
    checkMeasurement(x, behind);  // bearing at +-pi: the wrapped difference is used
    EXPECT_NEAR(RangeBearingModel(1.0, 1.0).predict(x, ahead).y(), 0.0, 1e-9);
    EXPECT_NEAR(std::abs(RangeBearingModel(1.0, 1.0).predict(x, behind).y()), kPi, 1e-8);
    checkInverse(x, Vec2(2.0, kPi - 1e-9));
    checkInverse(x, Vec2(2.0, 0.0));
  }
}

TEST(RangeBearingModel, InverseIsTheInverseOfPredict) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> pos(-5, 5), th(-kPi, kPi), r(0.1, 10);
  for (int i = 0; i < 200; ++i) {
    const Pose2 x(pos(rng), pos(rng), th(rng));
    const Vec2 z(r(rng), th(rng));
    const Vec2 back = RangeBearingModel(1.0, 1.0).predict(x, RangeBearingModel(1.0, 1.0).inverse(x, z));
    EXPECT_NEAR(back.x(), z.x(), 1e-9);
    EXPECT_NEAR(wrapAngle(back.y() - z.y()), 0.0, 1e-9);
  }
}

TEST(RangeBearingModel, RangeToZeroThrows) {
  const Pose2 x(1.0, 1.0, 0.3);
  EXPECT_THROW(RangeBearingModel(1.0, 1.0).predict(x, Vec2(1.0, 1.0)), ModelError);
  EXPECT_THROW(RangeBearingModel(1.0, 1.0).inverse(x, Vec2(0.0, 0.1)), ModelError);
  EXPECT_THROW(RangeBearingModel(1.0, 1.0).inverse(x, Vec2(-1.0, 0.1)), ModelError);
  EXPECT_THROW(RangeBearingModel(1.0, 1.0).inverse(x, Vec2(std::nan(""), 0.1)), ModelError);
  EXPECT_NO_THROW(RangeBearingModel(1.0, 1.0).predict(x, Vec2(1.0 + 1e-6, 1.0)));
}

TEST(RangeBearingModel, BearingInnovationIsWrapped) {
  const Vec2 nu = RangeBearingModel(1.0, 1.0).residual(Vec2(1.0, kPi - 0.01), Vec2(1.0, -kPi + 0.01));
  EXPECT_NEAR(nu.y(), -0.02, 1e-12);
}
