// The streamed run loop: StepAssembler turns any event stream into the steps buildDataset()
// makes from a log in memory, and a streamed run equals the in-memory one.
#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include <seif/eval/run_dataset.hpp>
#include <seif/filters/factory.hpp>
#include "io/robot_log_source.hpp"
#include <seif/models/odometry_model.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/sim/world.hpp>

#include <gtest/gtest.h>

namespace {

using namespace seif;

std::vector<Step> assemble(EventSource& source, std::vector<TimedPose>* gt = nullptr, StepAssembler* used = nullptr) {
  StepAssembler own;
  StepAssembler& a = used ? *used : own;
  std::vector<Step> steps;
  Step s;
  while (a.next(source, s, gt, nullptr)) steps.push_back(s);
  return steps;
}

void expectSameSteps(const std::vector<Step>& a, const std::vector<Step>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    const auto& ua = std::get<VelocityControl>(a[k].u);
    const auto& ub = std::get<VelocityControl>(b[k].u);
    ASSERT_EQ(a[k].time, b[k].time) << "step " << k;
    ASSERT_EQ(ua.v, ub.v) << "step " << k;
    ASSERT_EQ(ua.w, ub.w) << "step " << k;
    ASSERT_EQ(ua.dt, ub.dt) << "step " << k;
    ASSERT_EQ(a[k].observations.size(), b[k].observations.size()) << "step " << k;
    for (std::size_t i = 0; i < a[k].observations.size(); ++i) {
      ASSERT_EQ(a[k].observations[i].landmark, b[k].observations[i].landmark);
      ASSERT_EQ(a[k].observations[i].z, b[k].observations[i].z);
    }
  }
}

TEST(StepAssembler, MakesTheStepsOfBuildDatasetOnEveryPreset) {
  for (const WorldPreset preset : {WorldPreset::Paper, WorldPreset::Uniform, WorldPreset::Corridor}) {
    const RobotLog log = simulate(presetConfig(preset, 0, 0, 3));
    RobotLogSource source(log, NoiseModel{});
    std::vector<TimedPose> gt;
    const std::vector<Step> steps = assemble(source, &gt);
    expectSameSteps(steps, buildDataset(log).steps);
    EXPECT_EQ(gt.size(), log.groundtruth.size());
  }
}

TEST(StepAssembler, SplitsAControlIntervalAtObservationStampsAndDropsEarlyOnes) {
  RobotLog log;
  log.odometry = {{10.0, 1.0, 0.1}, {11.0, 2.0, 0.2}, {12.0, 3.0, 0.3}};
  log.measurements = {{9.0, 7, 1.0, 0.0}, {10.5, 7, 2.0, 0.1}, {10.5, 8, 2.5, -0.2}, {11.0, 7, 3.0, 0.0},
                      {12.5, 8, 1.0, 0.0}};
  RobotLogSource source(log, NoiseModel{});
  StepAssembler a;
  expectSameSteps(assemble(source, nullptr, &a), buildDataset(log).steps);
  EXPECT_EQ(a.droppedBeforeFirstControl(), 1u);
  EXPECT_EQ(a.startTime(), 10.0);
}

/// A hand-made stream of events.
class ListSource final : public EventSource {
 public:
  ListSource(std::vector<Event> events, std::shared_ptr<const MotionModel> motion) : events_(std::move(events)) {
    info_.source = "list";
    info_.motion = std::move(motion);
    info_.sensor = std::make_shared<RangeBearingModel>(0.1, 0.01);
  }
  const DatasetInfo& info() const override { return info_; }
  bool next(Event& e) override {
    if (i_ == events_.size()) return false;
    e = events_[i_++];
    return true;
  }
  double progress() const override { return 0.0; }

 private:
  std::vector<Event> events_;
  std::size_t i_ = 0;
  DatasetInfo info_;
};

TEST(StepAssembler, OdometryIncrementsTakeTheObservationsOfThePoseTheyReach) {
  const OdometryIncrement d1{Vec3(1, 0, 0), Mat3::Identity()}, d2{Vec3(0, 1, 0), Mat3::Identity()};
  const Observation z0{5, Vec2(1, 0), std::nullopt}, z1{6, Vec2(2, 0), std::nullopt};
  ListSource source({ObservationEvent{0.0, {z0}}, ControlEvent{1.0, d1}, ObservationEvent{1.0, {z1}},
                     ControlEvent{2.0, d2}, ObservationEvent{2.0, {z0, z1}}, ControlEvent{3.0, d1}},
                    std::make_shared<OdometryModel>());
  const std::vector<Step> steps = assemble(source);
  ASSERT_EQ(steps.size(), 4u);
  EXPECT_EQ(std::get<OdometryIncrement>(steps[0].u).delta, Vec3::Zero());  // from the start pose
  EXPECT_EQ(steps[0].observations.size(), 1u);
  EXPECT_EQ(steps[1].time, 1.0);
  EXPECT_EQ(std::get<OdometryIncrement>(steps[1].u).delta, d1.delta);
  ASSERT_EQ(steps[1].observations.size(), 1u);
  EXPECT_EQ(steps[1].observations[0].landmark, 6);
  EXPECT_EQ(steps[2].observations.size(), 2u);
  EXPECT_EQ(steps[3].time, 3.0);
  EXPECT_TRUE(steps[3].observations.empty());
}

TEST(StepAssembler, EventsGoingBackInTimeAreADataError) {
  ListSource source({ControlEvent{2.0, VelocityControl{1, 0, 0}}, ControlEvent{1.0, VelocityControl{1, 0, 0}}},
                    std::make_shared<VelocityModel>(0.1, 0.1, NoiseForm::Rate));
  EXPECT_THROW(assemble(source), DataError);
}

TEST(StepAssembler, AControlHeldOverAnHourIsADataError) {
  // Odometry stamped from 0 and observations from 1.2e9 (one stream shifted): the last control
  // would be held over 1.2e9 s. An hour is taken; more is refused, naming the source.
  const auto motion = std::make_shared<VelocityModel>(0.1, 0.1, NoiseForm::Rate);
  const Observation z{5, Vec2(1, 0), std::nullopt};
  ListSource hour({ControlEvent{0.0, VelocityControl{1, 0, 0}}, ObservationEvent{3600.0, {z}}}, motion);
  EXPECT_EQ(assemble(hour).size(), 1u);
  for (const Event& late : {Event(ObservationEvent{1.2e9, {z}}), Event(ControlEvent{3602.0, VelocityControl{1, 0, 0}})}) {
    ListSource shifted({ControlEvent{0.0, VelocityControl{1, 0, 0}}, ControlEvent{1.0, VelocityControl{1, 0, 0}}, late},
                       motion);
    try {
      assemble(shifted);
      ADD_FAILURE() << "assembled";
    } catch (const DataError& e) {
      EXPECT_NE(std::string(e.what()).find("list: an event at t = "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("held an hour at most"), std::string::npos) << e.what();
    }
  }
}

TEST(RunStream, EqualsTheInMemoryRunForEveryFilter) {
  const RobotLog log = simulate(presetConfig(WorldPreset::Paper, 0, 0, 5));
  const Dataset data = buildDataset(log);
  for (const char* name : {"ekf", "eif", "seif"}) {
    RobotLogSource source(log, NoiseModel{});
    FilterConfig config;
    config.motion = source.info().motion;
    config.sensor = source.info().sensor;
    auto streamed = makeFilter(name, source.info().start_pose, config);
    const RunOutput a = runFilter(*streamed, source);
    auto in_memory = makeFilter(name, startPose(data), paperFilterConfig(NoiseModel{}));
    const RunOutput b = runFilter(*in_memory, data);
    ASSERT_EQ(a.trajectory.size(), b.trajectory.size()) << name;
    for (std::size_t k = 0; k < a.trajectory.size(); ++k) {
      ASSERT_EQ(a.trajectory[k].time, b.trajectory[k].time) << name << " step " << k;
      ASSERT_EQ(a.trajectory[k].pose, b.trajectory[k].pose) << name << " step " << k;
    }
    EXPECT_EQ(a.dead_reckoning.size(), a.trajectory.size());
    const auto dr = deadReckoning(data, startPose(data), streamed->motionModel());
    EXPECT_EQ(a.dead_reckoning.back().pose, dr.back().pose) << name;
  }
}

}  // namespace

namespace {

TEST(GpsRmse, IsZeroForARigidlyMovedTrajectoryAndCountsTheFixesInside) {
  std::vector<TimedPose> traj;
  std::vector<GpsFix> gps;
  const double a = 0.6;
  const Eigen::Matrix2d R = (Eigen::Matrix2d() << std::cos(a), -std::sin(a), std::sin(a), std::cos(a)).finished();
  for (int k = 0; k <= 100; ++k) {
    const double t = k;
    const Vec2 p(0.1 * t * t, 3.0 * std::sin(0.2 * t));
    traj.push_back({t, Pose2(p.x(), p.y(), 0.0)});
    if (k % 10 == 5) gps.push_back({t + 0.5, R * Vec2(0.1 * (t + 0.5) * (t + 0.5), 0.0) + Vec2(100, -50)});
  }
  gps.push_back({500.0, Vec2(0, 0)});  // outside the trajectory: not compared
  std::size_t n = 0;
  // The GPS track is a rigid motion of a different curve: a positive error...
  const auto e = gpsRmse(traj, gps, &n);
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(n, 10u);
  EXPECT_GT(*e, 0.1);
  // ... and of the trajectory itself (interpolated linearly): zero up to interpolation.
  std::vector<GpsFix> exact;
  for (int k = 0; k <= 100; k += 7) exact.push_back({double(k), R * traj[k].pose.head<2>() + Vec2(100, -50)});
  std::optional<double> median;
  EXPECT_LT(*gpsRmse(traj, exact, nullptr, &median), 1e-9);
  EXPECT_LT(*median, 1e-9);
  EXPECT_FALSE(gpsRmse(traj, {}).has_value());
}

TEST(GpsJumps, FlagsAnIsolatedSpikeButNotAStepOrAFixAfterAGap) {
  // A fix every 0.2 s moving at 5 m/s along x, with: a spike of 100 m at fix 10; a step of
  // 10 m (a receiver that re-converged) from fix 20 on; a 60 s gap after fix 30, across
  // which the track moved 300 m (5 m/s, plausible); a spike at the last fix.
  std::vector<GpsFix> gps;
  double t = 0.0;
  for (int k = 0; k < 40; ++k) {
    Vec2 p(5.0 * t, 0.0);
    if (k == 10) p.y() += 100.0;
    if (k >= 20) p.y() += 10.0;
    if (k == 39) p.y() -= 50.0;
    gps.push_back({t, p});
    t += k == 30 ? 60.0 : 0.2;
  }
  const std::vector<bool> jump = gpsJumps(gps, kGpsJumpSpeed);
  for (int k = 0; k < 40; ++k) EXPECT_EQ(jump[k], k == 10 || k == 39) << "fix " << k;
  // Above the spike's 500 m/s nothing is a jump.
  for (const bool j : gpsJumps(gps, 600.0)) EXPECT_FALSE(j);
  // Too few fixes to judge.
  EXPECT_TRUE(gpsJumps({}).empty());
  EXPECT_EQ(gpsJumps({{0.0, Vec2(1e6, 0)}}), std::vector<bool>{false});
}

}  // namespace

namespace {
TEST(StepAssembler, ObservationsAtTheFirstControlsStampAreKeptAsBuildDatasetKeepsThem) {
  RobotLog log;
  log.odometry = {{10.0, 1.0, 0.1}, {11.0, 2.0, 0.2}};
  log.measurements = {{9.0, 7, 1.0, 0.0}, {10.0, 7, 2.0, 0.1}, {10.0, 8, 2.5, -0.2}, {10.5, 8, 1.0, 0.0}};
  RobotLogSource source(log, NoiseModel{});
  StepAssembler a;
  const std::vector<Step> steps = assemble(source, nullptr, &a);
  expectSameSteps(steps, buildDataset(log).steps);
  EXPECT_EQ(a.droppedBeforeFirstControl(), 1u);
  ASSERT_FALSE(steps.empty());
  EXPECT_EQ(steps[0].observations.size(), 2u);
}
}  // namespace
