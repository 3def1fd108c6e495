// First-estimates Jacobians (Linearization::FirstEstimates; Huang, Mourikis, Roumeliotis,
// IJRR 2010): the unobservable directions they keep, Standard unchanged, EKF == EIF with
// FEJ, and the consistency they buy on the paper's world (Monte-Carlo NEES).
#include "scenario.hpp"

#include <seif/eval/run.hpp>
#include <seif/eval/stats.hpp>
#include "filters/eif_slam.hpp"
#include "filters/ekf_slam.hpp"
#include <seif/filters/factory.hpp>
#include "filters/first_estimates.hpp"
#include "filters/seif_slam.hpp"
#include <seif/models/range_bearing.hpp>
#include <seif/sim/world.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace {

using namespace seif;

FilterConfig configFor(const test::Scenario& s, Linearization l) {
  FilterConfig c = paperFilterConfig(s.noise);
  c.linearization = l;
  return c;
}

Mat2 rot90() {
  Mat2 S;
  S << 0, -1, 1, 0;
  return S;
}

/// The robot's rows of the unobservable directions at position p (Huang et al. eq. 41):
/// translation [I2; 0] and rotation [S p; 1].
Mat3 robotNullspace(const Vec2& p) {
  Mat3 N = Mat3::Zero();
  N.topLeftCorner<2, 2>().setIdentity();
  N.block<2, 1>(0, 2) = rot90() * p;
  N(2, 2) = 1.0;
  return N;
}

/// Largest |Phi N_k - N_{k+1}| (transition) and |[J_x J_y] N| (measurement, relative to |J|)
/// over a run of an FEJ EKF, with N at the first estimates (p_{k|k-1}, m_first). The
/// Jacobians are FEJ's (from a FirstEstimates fed as the filter feeds its own) or, with
/// `standard`, the textbook ones at the newest estimates.
struct NullspaceResidual {
  double transition = 0.0;
  double measurement = 0.0;
  double robot_point = 0.0;  // |x_{k|k-1} - p_{k|k-1}|: the filter's pose at update time
};

NullspaceResidual nullspaceResidual(Linearization policy) {
  const bool standard = policy == Linearization::Standard;
  const test::Scenario s = test::makeScenario(5, 30, 200);
  EkfSlam ekf(s.start, configFor(s, policy));
  FirstEstimates fe(s.start);
  NullspaceResidual r;
  for (const Step& step : s.steps) {
    const Vec3 x0 = ekf.mean().head<3>();
    const MotionIncrement m = ekf.motionModel().linearize(x0, step.u);
    const Vec2 p_prev = fe.predictedPosition();
    const MotionIncrement fej = fe.fejIncrement(m, x0.head<2>());
    const Mat3 Phi = Mat3::Identity() + (standard ? m : fej).J_delta_x;
    r.transition = std::max(r.transition,
                            (Phi * robotNullspace(p_prev) - robotNullspace(fe.predictedPosition())).cwiseAbs().maxCoeff());
    ekf.predict(m);  // the filter applies its own FirstEstimates, as fe above
    const Vec3 x = ekf.mean().head<3>();
    r.robot_point = std::max(r.robot_point, (x.head<2>() - fe.predictedPosition()).norm());
    const MeasurementModel& sensor = ekf.sensorModel();
    std::vector<int> ids = ekf.landmarkIds();
    for (const Observation& z : step.observations) {
      const auto it = std::find(ids.begin(), ids.end(), z.landmark);
      if (it == ids.end()) {  // initialised now, at the inverse model (its first estimate)
        ids.push_back(z.landmark);
        fe.addLandmark(sensor.inverse(x, z.z));
        continue;
      }
      const int slot = static_cast<int>(it - ids.begin());
      const Vec2 m_first = fe.landmark(slot);
      Mat23 J_x;
      Mat2 J_y;
      const bool first = policy == Linearization::FirstEstimates;
      sensor.predict(x, first ? m_first : ekf.landmark(z.landmark), &J_x, &J_y);
      // the OC-EKF: the newest estimates' Jacobian, projected (what PlannedObservation::constrain does)
      if (policy == Linearization::ObservabilityConstrained) {
        ObservabilityConstraint{fe.predictedPosition(), m_first}.apply(J_x, J_y);
      }
      Eigen::Matrix<double, 2, 5> J;
      J << J_x, J_y;
      Eigen::Matrix<double, 5, 3> N;
      N.topRows<3>() = robotNullspace(fe.predictedPosition());
      N.bottomLeftCorner<2, 2>().setIdentity();
      N.block<2, 1>(3, 2) = rot90() * m_first;
      r.measurement = std::max(r.measurement, (J * N).cwiseAbs().maxCoeff() / J.cwiseAbs().maxCoeff());
    }
    ekf.update(step.observations);
  }
  EXPECT_EQ(fe.size(), static_cast<int>(ekf.landmarkIds().size()));
  return r;
}

}  // namespace

TEST(FirstEstimates, JacobiansAnnihilateTheUnobservableDirections) {
  // Huang et al. eq. (41-44): with FEJ, Phi_k N_k = N_{k+1} and H_k N_k = 0 at every step,
  // so the observability matrix keeps the three-dimensional nullspace of the real system.
  const NullspaceResidual fej = nullspaceResidual(Linearization::FirstEstimates);
  EXPECT_EQ(fej.robot_point, 0.0);  // the filter's pose at update time is p_{k|k-1}
  EXPECT_LT(fej.transition, 1e-12);
  EXPECT_LT(fej.measurement, 1e-12);
  // The textbook Jacobians (at the newest estimates) do not: this is the spurious heading
  // information of Huang et al. §4.
  const NullspaceResidual standard = nullspaceResidual(Linearization::Standard);
  EXPECT_GT(standard.transition, 1e-3);
  EXPECT_GT(standard.measurement, 1e-3);
}

TEST(ObservabilityConstrained, JacobiansAnnihilateTheUnobservableDirections) {
  // The OC-EKF (Huang et al. 2010): the same transition as FEJ, and measurement Jacobians at
  // the newest estimates projected so that H N_k = 0 with N_k at the first estimates.
  const NullspaceResidual oc = nullspaceResidual(Linearization::ObservabilityConstrained);
  EXPECT_EQ(oc.robot_point, 0.0);
  EXPECT_LT(oc.transition, 1e-12);
  EXPECT_LT(oc.measurement, 1e-12);
}

TEST(ObservabilityConstrained, TheProjectionIsTheClosestJacobianThatAnnihilatesN) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 100; ++trial) {
    Mat23 J_x;
    Mat2 J_y;
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 3; ++j) J_x(i, j) = n01(rng);
      for (int j = 0; j < 2; ++j) J_y(i, j) = n01(rng);
    }
    const ObservabilityConstraint c{Vec2(n01(rng), n01(rng)), Vec2(n01(rng), n01(rng))};
    Mat23 Px = J_x;
    Mat2 Py = J_y;
    c.apply(Px, Py);
    Eigen::Matrix<double, 5, 3> N = Eigen::Matrix<double, 5, 3>::Zero();
    N.topRows<3>() = robotNullspace(c.robot);
    N.bottomLeftCorner<2, 2>().setIdentity();
    N.block<2, 1>(3, 2) = rot90() * c.landmark;
    Eigen::Matrix<double, 2, 5> J, P;
    J << J_x, J_y;
    P << Px, Py;
    EXPECT_LT((P * N).cwiseAbs().maxCoeff(), 1e-12);
    // the change J - P lies in N's column space (row-wise), so no closer Jacobian exists:
    // any other Q with Q N = 0 differs from P by rows orthogonal to it.
    const Eigen::Matrix<double, 2, 5> D = J - P;
    const Eigen::Matrix<double, 2, 3> coeff = (N.transpose() * N).ldlt().solve(N.transpose() * D.transpose()).transpose();
    EXPECT_LT((D - coeff * N.transpose()).cwiseAbs().maxCoeff(), 1e-12);
    // applying it twice changes nothing
    c.apply(Px, Py);
    Eigen::Matrix<double, 2, 5> P2;
    P2 << Px, Py;
    EXPECT_LT((P2 - P).cwiseAbs().maxCoeff(), 1e-14);
  }
  // A range-bearing Jacobian at the constraint's own points already annihilates N: unchanged.
  const RangeBearingModel rb(0.1, 0.1);
  Mat23 J_x;
  Mat2 J_y;
  rb.predict(Pose2(0.3, -0.2, 0.7), Vec2(1.1, 0.4), &J_x, &J_y);
  Mat23 Px = J_x;
  Mat2 Py = J_y;
  ObservabilityConstraint{Vec2(0.3, -0.2), Vec2(1.1, 0.4)}.apply(Px, Py);
  EXPECT_LT((Px - J_x).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((Py - J_y).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(FirstEstimates, IncrementChangesOnlyTheHeadingColumn) {
  FirstEstimates fe(Pose2(1.0, 2.0, 0.3));
  MotionIncrement m;
  m.delta = Vec3(0.5, -0.25, 0.1);
  m.J_delta_x << 0, 0, 0.25, 0, 0, 0.5, 0, 0, 0;
  m.U = Vec3(1, 2, 3).asDiagonal();
  // After an update moved the robot to (1.5, 2.5): p_{1|0} = (2, 2.25), p_{0|-1} = (1, 2).
  const MotionIncrement f = fe.fejIncrement(m, Vec2(1.5, 2.5));
  EXPECT_TRUE(f.delta == m.delta);
  EXPECT_TRUE(f.U == m.U);
  EXPECT_TRUE(f.J_delta_x.leftCols<2>() == m.J_delta_x.leftCols<2>());
  EXPECT_TRUE(f.J_delta_x.row(2) == m.J_delta_x.row(2));
  EXPECT_TRUE((f.J_delta_x.block<2, 1>(0, 2) == Vec2(-0.25, 1.0)));  // S (2 - 1, 2.25 - 2)
  EXPECT_TRUE(fe.predictedPosition() == Vec2(2.0, 2.25));
}

TEST(FirstEstimates, StandardIsBitIdenticalToTheDefault) {
  const test::Scenario s = test::makeScenario(7, 30, 150);
  FilterConfig plain = paperFilterConfig(s.noise);
  for (const std::string name : {"ekf", "eif", "seif", "seif:mean=exact"}) {
    std::unique_ptr<SlamFilter> a = makeFilter(name, s.start, plain);
    const std::string spec = name + (name.find(':') == std::string::npos ? ":" : ",");
    std::unique_ptr<SlamFilter> b = makeFilter(spec + "linearization=standard", s.start, plain);
    std::unique_ptr<SlamFilter> f = makeFilter(spec + "linearization=fej", s.start, plain);
    bool identical = true;
    for (const Step& step : s.steps) {
      a->step(step.u, step.observations);
      b->step(step.u, step.observations);
      f->step(step.u, step.observations);
      identical = identical && a->mean().size() == b->mean().size() && a->mean() == b->mean();
    }
    EXPECT_TRUE(identical) << name;
    // ... and FEJ is not (the comparison can fail).
    ASSERT_EQ(a->mean().size(), f->mean().size()) << name;
    EXPECT_GT((a->mean() - f->mean()).cwiseAbs().maxCoeff(), 1e-6) << name;
  }
}

TEST(FirstEstimates, EkfAndEifAgreeToRounding) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const test::Scenario s = test::makeScenario(seed, 30, 200);
    EkfSlam ekf(s.start, configFor(s, Linearization::FirstEstimates));
    EifSlam eif(s.start, configFor(s, Linearization::FirstEstimates));
    double worst_mean = 0, worst_cov = 0;
    for (const Step& step : s.steps) {
      ekf.step(step.u, step.observations);
      eif.step(step.u, step.observations);
      ASSERT_EQ(ekf.landmarkIds(), eif.landmarkIds());
      worst_mean = std::max(worst_mean, (eif.mean() - ekf.mean()).norm() / ekf.mean().norm());
      worst_cov = std::max(worst_cov, (eif.covariance() - ekf.covariance()).norm() / ekf.covariance().norm());
    }
    EXPECT_LT(worst_mean, 1e-8) << "seed " << seed;
    EXPECT_LT(worst_cov, 1e-8) << "seed " << seed;
  }
}

namespace {

struct Consistency {
  double nees = 0.0;         // mean over landmarks and seeds of e^T P^-1 e (2 dof: 2 if consistent)
  double median_nees = 0.0;  // median over seeds of each run's mean landmark NEES
  double mse = 0.0;          // mean squared landmark error [m^2]
};

/// NEES and squared error of the landmarks of `spec` on the paper's world, 20 seeds, with
/// the world's sensor or (`sensor_sigma` > 0) one of that range [m] and bearing [rad] sigma.
Consistency paperConsistency(const std::string& spec, PaperPath path, double sensor_sigma = 0.0) {
  Consistency c;
  std::size_t n = 0;
  std::vector<double> per_seed;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    WorldConfig world = presetConfig(WorldPreset::Paper, 0, 0, seed);
    world.paper_path = path;
    if (sensor_sigma > 0.0) world.noise.sigma_range = world.noise.sigma_bearing = sensor_sigma;
    const Dataset data = buildDataset(simulate(world));
    FilterConfig config = paperFilterConfig(data.noise.value_or(world.noise));
    SeifOptions seif;
    seif.seed = seed;
    std::unique_ptr<SlamFilter> filter = makeFilter(spec, startPose(data), config, seif);
    runFilter(*filter, data);
    double run_nees = 0.0;
    for (int id : filter->landmarkIds()) {
      const Vec2 e = filter->landmark(id) - data.landmarks.at(id);
      run_nees += e.dot(filter->landmarkCovariance(id).ldlt().solve(e));
      c.mse += e.squaredNorm();
    }
    c.nees += run_nees;
    n += filter->landmarkIds().size();
    per_seed.push_back(run_nees / static_cast<double>(filter->landmarkIds().size()));
  }
  c.median_nees = median(per_seed);
  c.nees /= static_cast<double>(n);
  c.mse /= static_cast<double>(n);
  return c;
}

}  // namespace

TEST(FirstEstimates, EkfIsMoreConsistentOnThePaperWorld) {
  // FEJ needs good first estimates (Huang et al. §6). The paper world's sensor (range sigma
  // 0.045 m at ranges of 0.05-0.2 m) gives poor ones, and there FEJ is no better: some
  // seeds diverge (mean NEES in the thousands), lissajous is worse even in the median. With
  // a 0.01 m / 0.01 rad sensor, FEJ removes most of the inconsistency on the lawnmower
  // path, which is what is checked; the other figures are printed, not checked.
  for (double sensor_sigma : {0.0, 0.01}) {
    for (PaperPath path : {PaperPath::Lawnmower, PaperPath::Lissajous}) {
      const std::string p = std::string(paperPathName(path)) + (sensor_sigma > 0.0 ? "_sensor_0.01" : "");
      const Consistency standard = paperConsistency("ekf", path, sensor_sigma);
      const Consistency fej = paperConsistency("ekf:linearization=fej", path, sensor_sigma);
      std::printf("[ FEJ      ] %-21s ekf standard: NEES mean %.3f median %.3f MSE %.4e | "
                  "fej: NEES mean %.3f median %.3f MSE %.4e\n", p.c_str(), standard.nees,
                  standard.median_nees, standard.mse, fej.nees, fej.median_nees, fej.mse);
      RecordProperty("ekf_standard_nees_" + p, std::to_string(standard.nees));
      RecordProperty("ekf_fej_nees_" + p, std::to_string(fej.nees));
      RecordProperty("ekf_standard_mse_" + p, std::to_string(standard.mse));
      RecordProperty("ekf_fej_mse_" + p, std::to_string(fej.mse));
      if (sensor_sigma > 0.0 && path == PaperPath::Lawnmower) {
        EXPECT_LT(fej.nees, standard.nees) << p;
        EXPECT_LE(fej.mse, 1.10 * standard.mse) << p;
      }
    }
  }
}

// Not a check: standard vs FEJ for every filter on the paper's world, with its own sensor
// and with a 0.01 m / 0.01 rad one. Run with
// --gtest_also_run_disabled_tests --gtest_filter=*ConsistencyTable.
TEST(FirstEstimates, DISABLED_ConsistencyTable) {
  std::printf("| sensor | path | filter | NEES standard (median) | NEES fej (median) | MSE standard | MSE fej |\n");
  for (double sensor_sigma : {0.0, 0.01}) {
    for (PaperPath path : {PaperPath::Lawnmower, PaperPath::Lissajous}) {
      for (const std::string name : {"ekf", "eif", "seif", "seif:mean=exact"}) {
        const std::string spec = name + (name.find(':') == std::string::npos ? ":" : ",");
        const Consistency standard = paperConsistency(name, path, sensor_sigma);
        const Consistency fej = paperConsistency(spec + "linearization=fej", path, sensor_sigma);
        std::printf("| %s | %s | %s | %.3f (%.3f) | %.3f (%.3f) | %.4e | %.4e |\n",
                    sensor_sigma > 0 ? "0.01" : "world", std::string(paperPathName(path)).c_str(),
                    name.c_str(), standard.nees, standard.median_nees, fej.nees, fej.median_nees,
                    standard.mse, fej.mse);
        std::fflush(stdout);
      }
    }
  }
}
