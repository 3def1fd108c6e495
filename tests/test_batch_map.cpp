// The batch MAP smoother: equal to the exact filter on a linear-Gaussian problem (with a
// rank-2 process noise), one optimum from any start on the paper's world, better maps than
// the EKF, and the smoother hooks of runFilter.
#include "rel_diff.hpp"
#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include "filters/batch_map.hpp"
#include "filters/eif_slam.hpp"
#include "filters/ekf_slam.hpp"
#include "filters/preintegration.hpp"
#include <seif/models/ackermann_model.hpp>
#include <seif/models/odometry_model.hpp>
#include <seif/models/velocity_model.hpp>
#include <seif/filters/factory.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/sim/world.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <variant>

namespace {

using namespace seif;

using test::relDiff;

/// delta = the OdometryIncrement's (dx, dy, dth) in the WORLD frame: J_delta_x = 0, U constant.
class LinearMotion final : public MotionModel {
 public:
  explicit LinearMotion(const Mat3& U) : U_(U) {}
  std::string describe() const override { return "linear world-frame displacement"; }
  MotionIncrement linearize(const Pose2&, const MotionInput& u) const override {
    const auto* o = std::get_if<OdometryIncrement>(&u);
    if (o == nullptr) throw ModelError("linear motion: needs an OdometryIncrement");
    return {o->delta, Mat3::Zero(), U_};
  }

 private:
  Mat3 U_;
};

/// z = y - (px, py), the landmark's world-frame offset: J_x = [-I 0], J_y = I.
class LinearSensor final : public MeasurementModel {
 public:
  explicit LinearSensor(const Mat2& R) : MeasurementModel(R, Pose2::Zero()) {}
  std::string describe() const override { return "linear world-frame offset"; }

 protected:
  Vec2 predictFromSensor(const Pose2& s, const Vec2& y, Mat23* J_s, Mat2* J_y) const override {
    if (J_s) *J_s << -1, 0, 0, 0, -1, 0;
    if (J_y) J_y->setIdentity();
    return y - s.head<2>();
  }
  Vec2 inverseFromSensor(const Pose2& s, const Vec2& z, Mat23* J_y_s, Mat2* J_y_z) const override {
    if (J_y_s) *J_y_s << 1, 0, 0, 0, 1, 0;
    if (J_y_z) J_y_z->setIdentity();
    return s.head<2>() + z;
  }
};

TEST(BatchMap, EqualsTheExactFilterOnALinearGaussianProblemWithRank2ProcessNoise) {
  // U = V diag(s1^2, s2^2, 0) V^T with V a rotation about a skew axis: the noise-free
  // direction mixes x, y and theta.
  const Mat3 V = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Mat3 U = V * Vec3(0.04, 0.01, 0.0).asDiagonal() * V.transpose();
  Mat2 R;
  R << 0.02, 0.005, 0.005, 0.01;
  FilterConfig config;
  config.motion = std::make_shared<LinearMotion>(U);
  config.sensor = std::make_shared<LinearSensor>(R);
  config.initial_pose_sigma = Vec3(0.1, 0.2, 0.05);

  std::mt19937_64 rng(7);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> place(-4.0, 4.0);
  std::vector<Vec2> landmarks;
  for (int i = 0; i < 8; ++i) landmarks.emplace_back(place(rng), place(rng));
  const Pose2 start(0.5, -1.0, 0.1);
  Pose2 truth = start;
  const Eigen::LLT<Mat2> chol_R(R);

  EifSlam eif(start, config);
  BatchMap batch(start, config);
  for (int k = 0; k < 30; ++k) {
    OdometryIncrement u;
    u.delta = Vec3(0.3 * std::cos(0.2 * k), 0.3 * std::sin(0.2 * k), 0.02 * std::sin(0.5 * k));
    truth += u.delta + V.leftCols<2>() * Vec2(0.2 * n01(rng), 0.1 * n01(rng));
    std::vector<Observation> obs;
    for (int i = 0; i < 8; ++i) {
      if (((k + i) % 3) == 0) continue;  // each step sees a changing subset
      const Vec2 noise = chol_R.matrixL() * Vec2(n01(rng), n01(rng));
      obs.push_back({10 + i, Vec2(landmarks[static_cast<std::size_t>(i)] - truth.head<2>() + noise), std::nullopt});
    }
    eif.step(u, obs);
    batch.step(u, obs);
  }
  batch.finish();
  ASSERT_EQ(batch.landmarkIds(), eif.landmarkIds());
  EXPECT_EQ(batch.landmarkIds().size(), 8u);
  EXPECT_LT(batch.constraintViolation(), 1e-10);
  EXPECT_LE(batch.iterations(), 3);
  EXPECT_LT(relDiff(batch.pose(), eif.pose()), 1e-8);
  EXPECT_LT(relDiff(batch.poseCovariance(), eif.poseCovariance()), 1e-8);
  for (int id : eif.landmarkIds()) {
    EXPECT_LT(relDiff(batch.landmark(id), eif.landmark(id)), 1e-8) << "landmark " << id;
    EXPECT_LT(relDiff(batch.landmarkCovariance(id), eif.landmarkCovariance(id)), 1e-8) << "landmark " << id;
  }
  EXPECT_LT(relDiff(batch.mean(), eif.mean()), 1e-8);
  EXPECT_LT(relDiff(batch.covariance(), eif.covariance()), 1e-8);
  EXPECT_LT(relDiff(batch.information(), eif.information()), 1e-8);
  const PredictedMeasurement a = batch.predictMeasurement(12, batch.sensorModel(), R);
  const PredictedMeasurement b = eif.predictMeasurement(12, eif.sensorModel(), R);
  EXPECT_LT(relDiff(a.z, b.z), 1e-8);
  EXPECT_LT(relDiff(a.S, b.S), 1e-8);
  // The smoothed pose at the start is not the filter's (it has seen the whole run), but
  // its covariance is bounded by the prior's.
  const std::vector<Mat3> P = batch.trajectoryCovariances();
  ASSERT_EQ(P.size(), 31u);
  EXPECT_LT(relDiff(P.back(), eif.poseCovariance()), 1e-8);
  EXPECT_LE(P.front()(0, 0), 0.1 * 0.1 * (1 + 1e-12));
}

struct PaperData {
  Dataset data;
  FilterConfig config;
  Pose2 start;
};

PaperData paperData(std::uint64_t seed, PaperPath path) {
  WorldConfig world = presetConfig(WorldPreset::Paper, 0, 0, seed);
  world.paper_path = path;
  PaperData p;
  p.data = buildDataset(simulate(world));
  p.config = paperFilterConfig(p.data.noise.value_or(world.noise));
  p.start = startPose(p.data);
  return p;
}

std::vector<Pose2> truePoses(const Dataset& data) {
  std::vector<Pose2> poses{interpolatePose(data.groundtruth, data.start_time)};
  for (const Step& s : data.steps) poses.push_back(interpolatePose(data.groundtruth, s.time));
  return poses;
}

std::vector<Vec2> trueLandmarks(const SlamFilter& filter, const Dataset& data) {
  std::vector<Vec2> out;
  for (int id : filter.landmarkIds()) out.push_back(data.landmarks.at(id));
  return out;
}

double landmarkMse(const SlamFilter& filter, const Dataset& data) {
  double sum = 0.0;
  for (int id : filter.landmarkIds()) sum += (filter.landmark(id) - data.landmarks.at(id)).squaredNorm();
  return sum / static_cast<double>(filter.landmarkIds().size());
}

TEST(BatchMap, ReachesTheSameOptimumFromTheEkfAndFromTheTruthOnThePaperWorld) {
  for (PaperPath path : {PaperPath::Lawnmower, PaperPath::Lissajous}) {
    const PaperData p = paperData(3, path);
    BatchMap batch(p.start, p.config);
    const auto t0 = std::chrono::steady_clock::now();
    runFilter(batch, p.data);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("paper world (%s): %zu steps, %zu landmarks, %d iterations, cost %.6g, %.3f s\n",
                std::string(paperPathName(path)).c_str(), p.data.steps.size(), batch.landmarkIds().size(),
                batch.iterations(), batch.cost(), seconds);
    const std::vector<Pose2> from_ekf = batch.smoothedTrajectory();
    std::vector<Vec2> map_from_ekf;
    for (int id : batch.landmarkIds()) map_from_ekf.push_back(batch.landmark(id));
    const double cost_from_ekf = batch.cost();
    EXPECT_LT(batch.constraintViolation(), 1e-10);

    batch.optimizeFrom(truePoses(p.data), trueLandmarks(batch, p.data));
    std::printf("  from the truth: %d iterations, cost %.6g\n", batch.iterations(), batch.cost());
    EXPECT_LT(batch.constraintViolation(), 1e-10);
    EXPECT_NEAR(batch.cost(), cost_from_ekf, 1e-9 * cost_from_ekf);
    const std::vector<Pose2> from_truth = batch.smoothedTrajectory();
    ASSERT_EQ(from_truth.size(), from_ekf.size());
    double worst = 0.0;
    for (std::size_t k = 0; k < from_ekf.size(); ++k) {
      Vec3 d = from_truth[k] - from_ekf[k];
      d(2) = wrapAngle(d(2));
      worst = std::max(worst, d.cwiseAbs().maxCoeff());
    }
    for (std::size_t s = 0; s < map_from_ekf.size(); ++s) {
      worst = std::max(worst, (batch.landmark(batch.landmarkIds()[s]) - map_from_ekf[s]).cwiseAbs().maxCoeff());
    }
    EXPECT_LT(worst, 1e-6) << paperPathName(path);
  }
}

TEST(BatchMap, BeatsTheEkfOnThePaperWorld) {
  double batch_mse = 0.0, ekf_mse = 0.0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const PaperData p = paperData(seed, PaperPath::Lawnmower);
    EkfSlam ekf(p.start, p.config);
    BatchMap batch(p.start, p.config);
    const RunOutput ekf_run = runFilter(ekf, p.data);
    runFilter(batch, p.data);
    batch_mse += landmarkMse(batch, p.data) / 5.0;
    ekf_mse += landmarkMse(ekf, p.data) / 5.0;
    // The cost at the EKF's filtered trajectory and map (which breaks the noise-free
    // directions of the motion) is higher than at the MAP.
    std::vector<Pose2> ekf_poses;
    for (const TimedPose& x : ekf_run.trajectory) ekf_poses.push_back(x.pose);
    std::vector<Vec2> ekf_map;
    for (int id : ekf.landmarkIds()) ekf_map.push_back(ekf.landmark(id));
    double violation = 0.0;
    const double ekf_cost = batch.costAt(ekf_poses, ekf_map, &violation);
    std::printf("seed %d: cost at the MAP %.6g, at the EKF's estimates %.6g (violation %.3g)\n",
                static_cast<int>(seed), batch.cost(), ekf_cost, violation);
    EXPECT_LE(batch.cost(), ekf_cost) << "seed " << seed;
  }
  std::printf("landmark MSE over 5 seeds: batch %.4g, ekf %.4g\n", batch_mse, ekf_mse);
  EXPECT_LT(batch_mse, ekf_mse);
}

TEST(BatchMap, TakesIncrementsLinearisedByTheCaller) {
  // The velocity model's increment is a motion in the robot's frame: the batch given
  // increments linearised at the inner EKF's poses rotates them with each iterate's heading
  // and reaches the optimum of the batch that relinearises the inputs.
  const PaperData p = paperData(3, PaperPath::Lawnmower);
  BatchMap relinearised(p.start, p.config), linearised(p.start, p.config);
  for (const Step& step : p.data.steps) {
    relinearised.step(step.u, step.observations);
    linearised.predict(p.config.motion->linearize(linearised.pose(), step.u));
    linearised.update(step.observations);
  }
  relinearised.finish();
  linearised.finish();
  ASSERT_EQ(linearised.landmarkIds(), relinearised.landmarkIds());
  double worst = 0.0;
  for (int id : relinearised.landmarkIds()) {
    worst = std::max(worst, (linearised.landmark(id) - relinearised.landmark(id)).norm());
  }
  std::printf("largest landmark difference, increments vs inputs: %.3g m\n", worst);
  EXPECT_LT(worst, 1e-8);
  EXPECT_NEAR(linearised.cost(), relinearised.cost(), 1e-9 * relinearised.cost());
  EXPECT_LT(relDiff(linearised.poseCovariance(), relinearised.poseCovariance()), 1e-6);
}

TEST(BatchMap, NeedsTheConfigSensor) {
  BatchMap batch(Pose2::Zero(), paperFilterConfig(NoiseModel{}));
  const RangeBearingModel other(0.1, 0.1);
  const std::vector<Observation> obs{{1, Vec2(1.0, 0.2), std::nullopt}};
  EXPECT_THROW(batch.update(obs, other), ModelError);
  EXPECT_THROW(batch.trajectoryCovariances(), seif::InvalidArgument);
  EXPECT_TRUE(batch.smoothedTrajectory().empty());
}

TEST(BatchMap, RunFilterReportsTheSmoothedTrajectory) {
  const PaperData p = paperData(2, PaperPath::Lawnmower);
  auto filter = makeFilter("batch", p.start, p.config);
  EXPECT_EQ(filter->name(), "batch");
  const RunOutput out = runFilter(*filter, p.data);
  const std::vector<Pose2> smoothed = filter->smoothedTrajectory();
  ASSERT_EQ(out.trajectory.size(), p.data.steps.size() + 1);
  ASSERT_EQ(smoothed.size(), out.trajectory.size());
  for (std::size_t k = 0; k < smoothed.size(); ++k) EXPECT_EQ(out.trajectory[k].pose, smoothed[k]) << k;
  EXPECT_EQ(filter->pose(), smoothed.back());
  EXPECT_EQ(out.final_stats.landmarks, filter->landmarkIds().size());
  EXPECT_GT(out.final_stats.links, p.data.steps.size());
}

}  // namespace

namespace {

Mat3 rotation(double theta) {
  Mat3 R = Mat3::Identity();
  R.topLeftCorner<2, 2>() = Eigen::Rotation2Dd(theta).toRotationMatrix();
  return R;
}

/// Each model with inputs that turn, speed up and stop.
struct ModelCase {
  std::string name;
  std::shared_ptr<MotionModel> model;
  std::vector<MotionInput> inputs;
};

std::vector<ModelCase> motionCases() {
  std::vector<ModelCase> cases;
  ModelCase v{"velocity", std::make_shared<VelocityModel>(0.05, 0.02, NoiseForm::PerStep), {}};
  ModelCase a{"ackermann", std::make_shared<AckermannModel>(AckermannGeometry{2.83, 0.76, Vec2(3.78, 0.5)}, 0.08, 0.005,
                                                            NoiseForm::Rate), {}};
  ModelCase o{"odometry", std::make_shared<OdometryModel>(), {}};
  for (int k = 0; k < 12; ++k) {
    v.inputs.emplace_back(VelocityControl{0.5 + 0.05 * k, 0.3 * std::sin(0.4 * k), 0.1});
    a.inputs.emplace_back(AckermannControl{k == 5 ? 0.0 : 3.0 + 0.2 * k, 0.2 * std::cos(0.3 * k), 0.025});
    OdometryIncrement u;
    u.delta = Vec3(0.2 + 0.01 * k, 0.02 * std::sin(k), 0.05 * std::cos(0.7 * k));
    u.covariance << 1e-4, 2e-6, 1e-6, 2e-6, 4e-6, 0.0, 1e-6, 0.0, 4e-6;
    o.inputs.emplace_back(u);
  }
  cases.push_back(v);
  cases.push_back(a);
  cases.push_back(o);
  return cases;
}

TEST(MotionModels, AreEquivariantWhereTheySaySo) {
  // Delta(x, u) = Rot(theta) Delta_body(u), U(x, u) = Rot U_body Rot^T at any pose: what lets
  // the batch compose the steps between observations.
  for (const ModelCase& c : motionCases()) {
    ASSERT_TRUE(c.model->equivariant()) << c.name;
    for (const MotionInput& u : c.inputs) {
      const Pose2 x1(0.0, 0.0, 0.0), x2(-3.0, 7.5, 2.4);
      const MotionIncrement m1 = c.model->linearize(x1, u), m2 = c.model->linearize(x2, u);
      const Mat3 R = rotation(x2(2));
      EXPECT_LT((R * m1.delta - m2.delta).norm(), 1e-12) << c.name;
      EXPECT_LT((R * m1.U * R.transpose() - m2.U).norm(), 1e-12 * (1.0 + m2.U.norm())) << c.name;
    }
  }
}

TEST(Preintegration, EqualsSteppingTheModelsPrediction) {
  // The composed increment and covariance against the EKF's prediction stepped through the
  // same inputs from a certain pose x_a: x_b = x_a + Rot(theta_a) B, P_b = Rot U_B Rot^T.
  for (const ModelCase& c : motionCases()) {
    const Pose2 xa(1.5, -2.0, 0.9);
    Pose2 x = xa;
    Mat3 P = Mat3::Zero();
    Preintegration pre;
    for (const MotionInput& u : c.inputs) {
      const MotionIncrement m = c.model->linearize(x, u);
      const Mat3 Rt = rotation(x(2)).transpose();
      pre.add(Rt * m.delta, Rt * m.U * Rt.transpose());
      const Mat3 G = Mat3::Identity() + m.J_delta_x;
      P = G * P * G.transpose() + m.U;
      x += m.delta;
    }
    const Mat3 Ra = rotation(xa(2));
    EXPECT_EQ(pre.steps(), static_cast<int>(c.inputs.size()));
    EXPECT_LT((xa + Ra * pre.delta() - x).norm(), 1e-12) << c.name;
    EXPECT_LT((Ra * pre.covariance() * Ra.transpose() - P).norm(), 1e-12 * P.norm()) << c.name;
    const Eigen::SelfAdjointEigenSolver<Mat3> eig(pre.covariance());
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0) << c.name << ": several steps of rank-2 noise are full rank";
  }
}

/// The same model, declared not equivariant: the batch then keeps a pose per step.
class PerStepModel final : public MotionModel {
 public:
  explicit PerStepModel(std::shared_ptr<const MotionModel> m) : m_(std::move(m)) {}
  std::string describe() const override { return m_->describe(); }
  MotionIncrement linearize(const Pose2& x, const MotionInput& u) const override { return m_->linearize(x, u); }

 private:
  std::shared_ptr<const MotionModel> m_;
};

/// The composed and the one-pose-per-step batch on the paper world with the motion noise
/// scaled by `scale`, observations on every fourth step: their largest landmark and pose
/// differences, as a fraction of the smallest landmark standard deviation.
struct PreintegrationGap {
  double landmark = 0.0, pose = 0.0, covariance = 0.0;
};

PreintegrationGap preintegrationGap(double scale) {
  WorldConfig world = presetConfig(WorldPreset::Paper, 0, 0, 4);
  world.noise.sigma_v *= scale;
  world.noise.sigma_w *= scale;
  const Dataset data = buildDataset(simulate(world));
  const FilterConfig config = paperFilterConfig(data.noise.value_or(world.noise));
  FilterConfig per_step = config;
  per_step.motion = std::make_shared<PerStepModel>(config.motion);
  const Pose2 start = startPose(data);
  BatchMap composed(start, config), full(start, per_step);
  for (std::size_t k = 0; k < data.steps.size(); ++k) {
    const Step& s = data.steps[k];
    const std::span<const Observation> z = k % 4 == 3 ? std::span<const Observation>(s.observations) : std::span<const Observation>();
    composed.step(s.u, z);
    full.step(s.u, z);
  }
  composed.finish();
  full.finish();
  EXPECT_LT(composed.nodes(), static_cast<int>(data.steps.size()) / 3);
  EXPECT_EQ(full.nodes(), static_cast<int>(data.steps.size()) + 1);
  PreintegrationGap gap;
  double sigma_min = 1e300;
  for (int id : full.landmarkIds()) {
    gap.landmark = std::max(gap.landmark, (composed.landmark(id) - full.landmark(id)).norm());
    sigma_min = std::min(sigma_min, std::sqrt(full.landmarkCovariance(id).eigenvalues().real().minCoeff()));
  }
  const std::vector<Pose2> a = composed.smoothedTrajectory(), b = full.smoothedTrajectory();
  EXPECT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) gap.pose = std::max(gap.pose, (a[k] - b[k]).head<2>().norm());
  // The bridge's covariances: positive definite, near the per-step batch's marginals.
  const std::vector<Mat3> Pa = composed.trajectoryCovariances(), Pb = full.trajectoryCovariances();
  EXPECT_EQ(Pa.size(), Pb.size());
  for (std::size_t k = 0; k < Pa.size(); ++k) {
    EXPECT_GT(Pa[k].eigenvalues().real().minCoeff(), 0.0) << "step " << k;
    gap.covariance = std::max(gap.covariance, relDiff(Pa[k], Pb[k]));
  }
  gap.landmark /= sigma_min;
  gap.pose /= sigma_min;
  std::printf("motion noise x%g: %d nodes composed, %d one per step; largest difference landmark %.3g sigma, pose %.3g "
              "sigma, pose covariance %.3g relative\n",
              scale, composed.nodes(), full.nodes(), gap.landmark, gap.pose, gap.covariance);
  return gap;
}

TEST(BatchMap, PreintegratedEqualsOnePosePerStepToSecondOrder) {
  // Observations on every fourth step: the batch composes the steps between them, linearising
  // the motion noise about the nominal path, and bridges the poses between its nodes. Against
  // one pose per step the difference is second order in the noise: with the paper's heading
  // noise (0.03 rad per step) a tenth of a landmark's sigma, and a quarter of the noise cuts it
  // (relative to sigma) about fourfold.
  const PreintegrationGap paper = preintegrationGap(1.0), quarter = preintegrationGap(0.25);
  EXPECT_LT(paper.landmark, 0.25);
  EXPECT_LT(paper.pose, 0.5);
  EXPECT_LT(paper.covariance, 0.05);
  EXPECT_LT(quarter.landmark, paper.landmark / 2.5);
  EXPECT_LT(quarter.pose, paper.pose / 2.5);
}

TEST(BatchMap, CholeskyAndKktPathsReachTheSameOptimumOnThePaperWorld) {
  // The damped normal equations (Uzawa for the rank-2 motion's constraints) against SparseLU
  // of the whole KKT system; the gradient of the cost at the solution, projected on the
  // constraints, against the start's.
  for (PaperPath path : {PaperPath::Lawnmower, PaperPath::Lissajous}) {
    const PaperData p = paperData(11, path);
    BatchOptions kkt;
    kkt.solver = BatchOptions::Solver::Kkt;
    BatchMap a(p.start, p.config), b(p.start, p.config, kkt);
    runFilter(a, p.data);
    runFilter(b, p.data);
    const SmootherReport& r = *a.smootherReport();
    std::printf("%s: %d poses, %d constraints, 0.5 chi2 %.10g / %.10g, |gradient| %.3g of %.3g\n",
                std::string(paperPathName(path)).c_str(), r.poses, r.constraints, r.final_cost,
                b.smootherReport()->final_cost, r.gradient_norm, r.initial_gradient_norm);
    EXPECT_TRUE(r.converged);
    EXPECT_GT(r.constraints, 0);
    EXPECT_LT(r.gradient_norm, 1e-9 * r.initial_gradient_norm);
    EXPECT_LT(b.smootherReport()->gradient_norm, 1e-9 * b.smootherReport()->initial_gradient_norm);
    EXPECT_LT(a.constraintViolation(), 1e-10);
    double worst = 0.0;
    for (int id : a.landmarkIds()) worst = std::max(worst, (a.landmark(id) - b.landmark(id)).cwiseAbs().maxCoeff());
    const std::vector<Pose2> ta = a.smoothedTrajectory(), tb = b.smoothedTrajectory();
    for (std::size_t k = 0; k < ta.size(); ++k) worst = std::max(worst, (ta[k] - tb[k]).head<2>().cwiseAbs().maxCoeff());
    std::printf("  largest difference Cholesky - KKT: %.3g m\n", worst);
    EXPECT_LT(worst, 1e-8);
    EXPECT_LT(relDiff(a.covariance(), b.covariance()), 1e-8);
  }
}

TEST(BatchMap, StartsFromOdometryOrTheSeif) {
  const PaperData p = paperData(5, PaperPath::Lawnmower);
  BatchMap ekf(p.start, p.config);
  runFilter(ekf, p.data);
  for (BatchOptions::Init init : {BatchOptions::Init::Seif, BatchOptions::Init::Odometry}) {
    BatchOptions o;
    o.init = init;
    BatchMap batch(p.start, p.config, o);
    runFilter(batch, p.data);
    EXPECT_EQ(batch.smootherReport()->init, std::string(optionName(init)));
    EXPECT_TRUE(batch.smootherReport()->converged);
    EXPECT_NEAR(batch.cost(), ekf.cost(), 1e-9 * ekf.cost()) << optionName(init);
    EXPECT_LT(batch.smootherReport()->costs.back(), batch.smootherReport()->costs.front());
  }
  EXPECT_EQ(makeFilter("batch:init=odometry", p.start, p.config)->smootherReport(), nullptr);  // before a solve
}

}  // namespace
