// The models behind the two seams (MotionModel, MeasurementModel): every Jacobian against
// central differences at 1000 seeded points plus edge cases, the noise forms, the sensor
// mount, and EKF = EIF with each model.
#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include "filters/eif_slam.hpp"
#include "filters/ekf_slam.hpp"
#include <seif/models/ackermann_model.hpp>
#include <seif/models/cartesian.hpp>
#include <seif/models/odometry_model.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/models/velocity_model.hpp>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "numeric_jacobian.hpp"

#include <functional>
#include <numbers>
#include <random>

namespace {

using namespace seif;
constexpr double kPi = std::numbers::pi;

template <int M, int N, typename F>
Eigen::Matrix<double, M, N> numeric(F f, const Eigen::Matrix<double, N, 1>& x, int wrapped_row = -1) {
  return test::numericJacobian<M, N>(f, x, wrapped_row);
}

::testing::AssertionResult near(const Eigen::MatrixXd& a, const Eigen::MatrixXd& n) {
  const double scale = std::max(1.0, n.cwiseAbs().maxCoeff());
  if ((a - n).cwiseAbs().maxCoeff() < 1e-6 * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\nanalytic\n" << a << "\nnumeric\n" << n;
}

/// predict's and inverse's Jacobians of `m` at (x, y) and at (x, z = h(x, y)).
void checkSensor(const MeasurementModel& m, const Pose2& x, const Vec2& y, int wrapped_row) {
  Mat23 J_z_x, J_y_x;
  Mat2 J_z_y, J_y_z;
  const Vec2 z = m.predict(x, y, &J_z_x, &J_z_y);
  EXPECT_TRUE(near(J_z_x, numeric<2, 3>([&](const Vec3& xx) { return m.predict(xx, y); }, x, wrapped_row))) << "J_z_x";
  EXPECT_TRUE(near(J_z_y, numeric<2, 2>([&](const Vec2& yy) { return m.predict(x, yy); }, y, wrapped_row))) << "J_z_y";
  const Vec2 back = m.inverse(x, z, &J_y_x, &J_y_z);
  EXPECT_LT((back - y).norm(), 1e-9 * std::max(1.0, y.norm())) << "inverse(predict(y)) = y";
  EXPECT_TRUE(near(J_y_x, numeric<2, 3>([&](const Vec3& xx) { return m.inverse(xx, z); }, x))) << "J_y_x";
  EXPECT_TRUE(near(J_y_z, numeric<2, 2>([&](const Vec2& zz) { return m.inverse(x, zz); }, z))) << "J_y_z";
}

void checkSensorAtRandomPoints(const MeasurementModel& m, int wrapped_row, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> pos(-10, 10), th(-kPi, kPi);
  for (int i = 0; i < 1000; ++i) {
    const Pose2 x(pos(rng), pos(rng), th(rng));
    Vec2 y(pos(rng), pos(rng));
    // Keep clear of the sensor itself (range-bearing is degenerate there).
    const Vec2 s = m.predict(x, y).x() > 0.1 || wrapped_row < 0 ? y : y + Vec2(1.0, 1.0);
    checkSensor(m, x, s, wrapped_row);
  }
}

const Pose2 kMount(3.78, 0.5, 0.1);

TEST(MeasurementModels, RangeBearingJacobiansWithAndWithoutAMount) {
  checkSensorAtRandomPoints(RangeBearingModel(0.1, 0.01), 1, 11);
  checkSensorAtRandomPoints(RangeBearingModel(0.1, 0.01, kMount), 1, 12);
}

TEST(MeasurementModels, CartesianJacobiansWithAndWithoutAMount) {
  checkSensorAtRandomPoints(CartesianModel(0.4 * Mat2::Identity()), -1, 13);
  checkSensorAtRandomPoints(CartesianModel(0.4 * Mat2::Identity(), kMount), -1, 14);
}

TEST(MeasurementModels, EdgeCasesAtTheHeadingSeamAndBehindTheSensor) {
  const RangeBearingModel rb(0.1, 0.01, kMount);
  const CartesianModel xy(Mat2::Identity(), kMount);
  for (double heading : {kPi, -kPi + 1e-9, kPi - 1e-9, 0.0}) {
    const Pose2 x(1.0, -2.0, heading);
    for (const Vec2& z : {Vec2(5.0, kPi - 1e-9), Vec2(5.0, -kPi + 1e-9), Vec2(0.05, 0.3)}) {  // 5 cm: nearer, central differences lose accuracy
      checkSensor(rb, x, rb.inverse(x, z), 1);
      checkSensor(xy, x, rb.inverse(x, z), -1);
    }
  }
}

TEST(MeasurementModels, AMountedSensorSeesFromItsOwnPose) {
  const Pose2 x(2.0, 1.0, 0.7);
  const Pose2 s(x.x() + std::cos(x.z()) * kMount.x() - std::sin(x.z()) * kMount.y(),
                x.y() + std::sin(x.z()) * kMount.x() + std::cos(x.z()) * kMount.y(), x.z() + kMount.z());
  const Vec2 y(10.0, -3.0);
  const RangeBearingModel mounted(0.1, 0.01, kMount), at_origin(0.1, 0.01);
  EXPECT_LT((mounted.predict(x, y) - at_origin.predict(s, y)).norm(), 1e-12);
  const CartesianModel c_mounted(Mat2::Identity(), kMount), c_origin(Mat2::Identity());
  EXPECT_LT((c_mounted.predict(x, y) - c_origin.predict(s, y)).norm(), 1e-12);
}

TEST(MeasurementModels, NoiseIsCheckedAndAnObservationMayCarryItsOwn) {
  EXPECT_THROW(RangeBearingModel(0.0, 0.1), ModelError);
  EXPECT_THROW(CartesianModel((Mat2() << 1, 2, 2, 1).finished()), ModelError);  // indefinite
  EXPECT_THROW(CartesianModel((Mat2() << 1, 0.1, 0.2, 1).finished()), ModelError);  // asymmetric
  const CartesianModel m(0.4 * Mat2::Identity());
  Observation z{1, Vec2(1, 1), std::nullopt};
  EXPECT_EQ(m.noise(z), 0.4 * Mat2::Identity());
  z.noise = 2.0 * Mat2::Identity();
  EXPECT_EQ(m.noise(z), 2.0 * Mat2::Identity());
}

// --- motion --------------------------------------------------------------------------------

/// J_delta_x against central differences, and U against V M V^T with V from central
/// differences over the control (M / dt for a rate).
template <class Input>
void checkMotion(const MotionModel& model, const Pose2& x, const Input& u,
                 const std::function<Input(const Eigen::Vector2d&)>& with_control, const Eigen::Vector2d& control,
                 const Eigen::Vector2d& variances, NoiseForm form, double dt) {
  const MotionIncrement m = model.linearize(x, u);
  EXPECT_TRUE(near(m.J_delta_x, numeric<3, 3>([&](const Vec3& xx) { return model.linearize(xx, u).delta; }, x))) << "J_delta_x";
  const Mat32 V = numeric<3, 2>([&](const Eigen::Vector2d& c) { return model.linearize(x, with_control(c)).delta; }, control);
  Mat3 U = V * variances.asDiagonal() * V.transpose();
  if (form == NoiseForm::Rate) U /= dt;
  EXPECT_TRUE(near(m.U, U)) << "U";
}

TEST(MotionModels, VelocityJacobiansAndNoiseInBothForms) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> pos(-10, 10), th(-kPi, kPi), v(-2, 2), w(-3, 3), dt(0.01, 2.0);
  for (const NoiseForm form : {NoiseForm::PerStep, NoiseForm::Rate}) {
    const VelocityModel model(0.1, 0.05, form);
    for (int i = 0; i < 1000; ++i) {
      const Pose2 x(pos(rng), pos(rng), th(rng));
      const VelocityControl u{v(rng), i % 10 == 0 ? 0.0 : w(rng), dt(rng)};
      checkMotion<VelocityControl>(model, x, u, [&](const Eigen::Vector2d& c) { return VelocityControl{c(0), c(1), u.dt}; },
                                   Eigen::Vector2d(u.v, u.w), Eigen::Vector2d(0.01, 0.0025), form, u.dt);
    }
  }
}

TEST(MotionModels, RateNoiseDoesNotDependOnHowAnIntervalIsSplit) {
  // Heading variance after one interval of 1 s, or the same interval in n pieces: with a
  // rate it is sigma_w^2 * 1 s whatever n; per step it shrinks like 1/n (the old defect).
  for (const int n : {1, 2, 7, 40}) {
    const VelocityControl piece{0.5, 0.2, 1.0 / n};
    double rate = 0.0, per_step = 0.0;
    for (int k = 0; k < n; ++k) {
      rate += VelocityModel(0.1, 0.05, NoiseForm::Rate).linearize(Pose2::Zero(), piece).U(2, 2);
      per_step += VelocityModel(0.1, 0.05, NoiseForm::PerStep).linearize(Pose2::Zero(), piece).U(2, 2);
    }
    EXPECT_NEAR(rate, 0.05 * 0.05, 1e-15) << n << " pieces";
    EXPECT_NEAR(per_step, 0.05 * 0.05 / n, 1e-15) << n << " pieces";
  }
  EXPECT_EQ(VelocityModel(0.1, 0.05, NoiseForm::Rate).linearize(Pose2::Zero(), VelocityControl{1, 1, 0}).U, Mat3::Zero());
}

TEST(MotionModels, AckermannJacobiansNoiseAndBodyVelocity) {
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> pos(-100, 100), th(-kPi, kPi), ve(-1, 8), steer(-0.5, 0.5), dt(0.005, 0.2);
  for (const NoiseForm form : {NoiseForm::PerStep, NoiseForm::Rate}) {
    const AckermannGeometry g{2.83, 0.76, form == NoiseForm::Rate ? Vec2(3.78, 0.5) : Vec2::Zero()};
    const AckermannModel model(g, 0.2, 0.03, form);
    for (int i = 0; i < 1000; ++i) {
      const Pose2 x(pos(rng), pos(rng), th(rng));
      const AckermannControl u{ve(rng), i % 10 == 0 ? 0.0 : steer(rng), dt(rng)};
      checkMotion<AckermannControl>(model, x, u,
                                    [&](const Eigen::Vector2d& c) { return AckermannControl{c(0), c(1), u.dt}; },
                                    Eigen::Vector2d(u.speed, u.steering), Eigen::Vector2d(0.04, 0.0009), form, u.dt);
      Eigen::Matrix2d J;
      model.bodyVelocity(u, &J);
      EXPECT_TRUE(near(J, numeric<2, 2>([&](const Eigen::Vector2d& c) { return model.bodyVelocity({c(0), c(1), u.dt}); },
                                        Eigen::Vector2d(u.speed, u.steering))));
    }
  }
  const AckermannModel model({2.83, 0.76}, 0.2, 0.03, NoiseForm::Rate);
  // Straight: the axle centre moves at the encoder's speed. Turning left, the encoder on the
  // left (inner) wheel is slower than the centre: vc = ve / (1 - tan(a) H / L).
  EXPECT_EQ(model.bodyVelocity({3.0, 0.0, 0.1}), Eigen::Vector2d(3.0, 0.0));
  const Eigen::Vector2d vw = model.bodyVelocity({3.0, 0.2, 0.1});
  EXPECT_NEAR(vw(0), 3.0 / (1.0 - std::tan(0.2) * 0.76 / 2.83), 1e-12);
  EXPECT_NEAR(vw(1), vw(0) * std::tan(0.2) / 2.83, 1e-12);
  EXPECT_THROW(model.bodyVelocity({3.0, std::atan(2.83 / 0.76), 0.1}), ModelError);  // encoder at the turn's centre
  EXPECT_THROW(model.bodyVelocity({3.0, kPi / 2, 0.1}), ModelError);
}

TEST(MotionModels, AckermannTrackingABodyPointMovesThatPointOfTheAxlesMotion) {
  const Vec2 p(3.78, 0.5);
  const AckermannModel axle({2.83, 0.76}, 0.2, 0.03, NoiseForm::Rate), laser({2.83, 0.76, p}, 0.2, 0.03, NoiseForm::Rate);
  const auto point = [&](const Pose2& a) {
    return Pose2(a.x() + std::cos(a.z()) * p.x() - std::sin(a.z()) * p.y(),
                 a.y() + std::sin(a.z()) * p.x() + std::cos(a.z()) * p.y(), a.z());
  };
  Pose2 a(10, -3, 2.5), l = point(a);
  for (int k = 0; k < 200; ++k) {
    const AckermannControl u{3.0 + std::sin(0.1 * k), 0.4 * std::sin(0.05 * k), 0.025};
    a = axle.apply(a, MotionInput(u));
    l = laser.apply(l, MotionInput(u));
  }
  EXPECT_LT((point(a) - l).head<2>().norm(), 1e-9);
  EXPECT_NEAR(wrapAngle(point(a).z() - l.z()), 0.0, 1e-12);
}

TEST(MotionModels, OdometryJacobiansAndNoise) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> pos(-10, 10), th(-kPi, kPi), d(-1, 1), s(0.01, 0.2);
  const OdometryModel model;
  for (int i = 0; i < 1000; ++i) {
    const Pose2 x(pos(rng), pos(rng), th(rng));
    Mat3 A = Mat3::Random();
    const Mat3 C = A * A.transpose() * s(rng) + 1e-4 * Mat3::Identity();
    const OdometryIncrement u{Vec3(d(rng), d(rng), d(rng)), C};
    const MotionIncrement m = model.linearize(x, u);
    EXPECT_TRUE(near(m.J_delta_x, numeric<3, 3>([&](const Vec3& xx) { return model.linearize(xx, u).delta; }, x)));
    const Mat3 J = numeric<3, 3>([&](const Vec3& dd) { return model.linearize(x, OdometryIncrement{dd, C}).delta; }, u.delta);
    EXPECT_TRUE(near(m.U, J * C * J.transpose()));
  }
  // The increment is expressed in the robot's frame.
  const MotionIncrement m = model.linearize(Pose2(0, 0, kPi / 2), OdometryIncrement{Vec3(1, 0, 0.1), Mat3::Identity()});
  EXPECT_LT((m.delta - Vec3(0, 1, 0.1)).norm(), 1e-15);
}

TEST(MotionModels, AModelRefusesAnotherModelsInput) {
  const VelocityModel v(0.1, 0.1, NoiseForm::Rate);
  const OdometryModel o;
  EXPECT_THROW(v.linearize(Pose2::Zero(), MotionInput(OdometryIncrement{})), ModelError);
  EXPECT_THROW(o.linearize(Pose2::Zero(), MotionInput(VelocityControl{1, 0, 1})), ModelError);
  EXPECT_THROW(v.linearize(Pose2::Zero(), MotionInput(VelocityControl{1, 0, -1})), ModelError);
  EXPECT_THROW(VelocityModel(-1.0, 0.1, NoiseForm::Rate), ModelError);
}

// --- filters with any model ----------------------------------------------------------------

TEST(FiltersWithAnyModel, EkfEqualsEifWithOdometryAndAMountedCartesianSensor) {
  FilterConfig config;
  config.motion = std::make_shared<OdometryModel>();
  config.sensor = std::make_shared<CartesianModel>(0.05 * Mat2::Identity(), kMount);
  EkfSlam ekf(Pose2(1, 2, 0.3), config);
  EifSlam eif(Pose2(1, 2, 0.3), config);
  std::mt19937_64 rng(31);
  std::normal_distribution<double> n01;
  for (int k = 0; k < 60; ++k) {
    Mat3 C = Mat3::Zero();
    C.diagonal() << 1e-3, 4e-4, 2e-4;
    const OdometryIncrement u{Vec3(0.5, 0.05 * n01(rng), 0.1), C};
    std::vector<Observation> z;
    for (int id = 0; id < 4; ++id) {
      const Vec2 y(5.0 * std::cos(id * 1.6), 5.0 * std::sin(id * 1.6));
      Observation o{id, config.sensor->predict(ekf.pose(), y) + 0.05 * Vec2(n01(rng), n01(rng)), std::nullopt};
      if (id == 3) o.noise = 0.2 * Mat2::Identity();  // its own noise
      z.push_back(o);
    }
    ekf.step(u, z);
    eif.step(u, z);
  }
  EXPECT_LT((ekf.mean() - eif.mean()).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((ekf.covariance() - eif.covariance()).cwiseAbs().maxCoeff(), 1e-8);
  // The association seam: the same predicted measurement and innovation covariance.
  const PredictedMeasurement a = ekf.predictMeasurement(2, *config.sensor, config.sensor->noise());
  const PredictedMeasurement b = eif.predictMeasurement(2, *config.sensor, config.sensor->noise());
  EXPECT_LT((a.z - b.z).norm(), 1e-8);
  EXPECT_LT((a.S - b.S).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_GT(a.S.determinant(), 0.0);
}

}  // namespace
