// buildDataset: merging odometry rows and measurement stamps into filter steps; and
// interpolatePose of the ground truth.
#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/core/dataset.hpp>
#include <seif/io/mrclam.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

using namespace seif;
constexpr double kPi = std::numbers::pi;

namespace {

// Stamps and durations are binary fractions, so sums of dt are exact.
RobotLog threeRows() {
  RobotLog log;
  log.source = "synthetic";
  log.odometry = {{10.0, 1.0, 0.1}, {11.0, 2.0, 0.2}, {12.0, 3.0, 0.3}};
  return log;
}

void expectControl(const Step& s, double time, double v, double w, double dt, std::size_t n_obs) {
  EXPECT_EQ(s.time, time);
  EXPECT_EQ(std::get<VelocityControl>(s.u).v, v) << "step at " << time;
  EXPECT_EQ(std::get<VelocityControl>(s.u).w, w) << "step at " << time;
  EXPECT_EQ(std::get<VelocityControl>(s.u).dt, dt) << "step at " << time;
  EXPECT_EQ(s.observations.size(), n_obs) << "step at " << time;
}

double sumDt(const Dataset& d) {
  double sum = 0.0;
  for (const Step& s : d.steps) sum += std::get<VelocityControl>(s.u).dt;
  return sum;
}

}  // namespace

TEST(DatasetBuild, OdometryOnly) {
  const Dataset d = buildDataset(threeRows());
  EXPECT_EQ(d.start_time, 10.0);
  ASSERT_EQ(d.steps.size(), 2u);
  expectControl(d.steps[0], 11.0, 1.0, 0.1, 1.0, 0);
  expectControl(d.steps[1], 12.0, 2.0, 0.2, 1.0, 0);
}

TEST(DatasetBuild, MeasurementSplitsThePrediction) {
  RobotLog log = threeRows();
  log.measurements = {{10.25, 6, 1.0, 0.5}, {11.5, 7, 2.0, -0.5}};
  const Dataset d = buildDataset(log);
  ASSERT_EQ(d.steps.size(), 4u);
  expectControl(d.steps[0], 10.25, 1.0, 0.1, 0.25, 1);
  expectControl(d.steps[1], 11.0, 1.0, 0.1, 0.75, 0);
  expectControl(d.steps[2], 11.5, 2.0, 0.2, 0.5, 1);
  expectControl(d.steps[3], 12.0, 2.0, 0.2, 0.5, 0);
  EXPECT_EQ(sumDt(d), 12.0 - 10.0);
  // Per control row, the pieces add up to the row's interval.
  EXPECT_EQ(std::get<VelocityControl>(d.steps[0].u).dt + std::get<VelocityControl>(d.steps[1].u).dt, 1.0);
  EXPECT_EQ(std::get<VelocityControl>(d.steps[2].u).dt + std::get<VelocityControl>(d.steps[3].u).dt, 1.0);
}

TEST(DatasetBuild, MeasurementAtAControlStampComesBeforeTheNewControl) {
  RobotLog log = threeRows();
  log.measurements = {{11.0, 6, 1.0, 0.5}};
  const Dataset d = buildDataset(log);
  ASSERT_EQ(d.steps.size(), 2u) << "no zero-length step for the odometry row at 11";
  expectControl(d.steps[0], 11.0, 1.0, 0.1, 1.0, 1);  // row 0 up to 11, then the update
  expectControl(d.steps[1], 12.0, 2.0, 0.2, 1.0, 0);  // row 1 starts after it
}

TEST(DatasetBuild, MeasurementsBeforeFirstControlAreDroppedAndCounted) {
  RobotLog log = threeRows();
  log.dropped.robot_measurements = 4;
  log.dropped.unknown_barcodes = 2;
  log.measurements = {{9.0, 6, 1.0, 0.5}, {9.5, 7, 1.0, 0.5}, {9.5, 8, 1.0, 0.5}, {10.5, 6, 1.0, 0.5}};
  const Dataset d = buildDataset(log);
  EXPECT_EQ(d.dropped.before_first_control, 3u);
  EXPECT_EQ(d.dropped.robot_measurements, 4u);  // carried over from the log
  EXPECT_EQ(d.dropped.unknown_barcodes, 2u);
  ASSERT_EQ(d.steps.size(), 3u);
  expectControl(d.steps[0], 10.5, 1.0, 0.1, 0.5, 1);
  EXPECT_EQ(sumDt(d), 2.0);
}

TEST(DatasetBuild, MeasurementAtTheFirstStampIsKeptWithZeroDt) {
  RobotLog log = threeRows();
  log.measurements = {{10.0, 6, 1.0, 0.5}};
  const Dataset d = buildDataset(log);
  EXPECT_EQ(d.dropped.before_first_control, 0u);
  ASSERT_EQ(d.steps.size(), 3u);
  expectControl(d.steps[0], 10.0, 1.0, 0.1, 0.0, 1);
}

TEST(DatasetBuild, ObservationsAreGroupedByStamp) {
  RobotLog log = threeRows();
  log.measurements = {{10.5, 9, 1.5, 0.1}, {10.5, 6, 2.5, -0.2}, {10.5, 12, 3.5, 0.3},
                      {10.75, 6, 4.5, 0.4}};
  const Dataset d = buildDataset(log);
  ASSERT_EQ(d.steps.size(), 4u);
  const Step& s = d.steps[0];
  expectControl(s, 10.5, 1.0, 0.1, 0.5, 3);
  EXPECT_EQ(s.observations[0].landmark, 9);  // landmark = subject, log order kept
  EXPECT_EQ(s.observations[1].landmark, 6);
  EXPECT_EQ(s.observations[2].landmark, 12);
  EXPECT_EQ(s.observations[1].z, Vec2(2.5, -0.2));
  expectControl(d.steps[1], 10.75, 1.0, 0.1, 0.25, 1);
}

TEST(DatasetBuild, UnsortedMeasurementsAreSortedStably) {
  RobotLog log = threeRows();
  log.measurements = {{11.5, 7, 1.0, 0.0}, {10.5, 8, 1.0, 0.0}, {11.5, 9, 1.0, 0.0}};
  const Dataset d = buildDataset(log);
  ASSERT_EQ(d.steps.size(), 4u);
  EXPECT_EQ(d.steps[0].time, 10.5);
  ASSERT_EQ(d.steps[2].observations.size(), 2u);
  EXPECT_EQ(d.steps[2].observations[0].landmark, 7);
  EXPECT_EQ(d.steps[2].observations[1].landmark, 9);
}

TEST(DatasetBuild, MeasurementsAfterTheLastRowUseTheLastControl) {
  RobotLog log = threeRows();
  log.measurements = {{12.0, 6, 1.0, 0.0}, {12.5, 7, 1.0, 0.0}, {13.0, 8, 1.0, 0.0}};
  const Dataset d = buildDataset(log);
  ASSERT_EQ(d.steps.size(), 4u);
  expectControl(d.steps[1], 12.0, 2.0, 0.2, 1.0, 1);  // the update at 12 precedes row 2
  expectControl(d.steps[2], 12.5, 3.0, 0.3, 0.5, 1);
  expectControl(d.steps[3], 13.0, 3.0, 0.3, 0.5, 1);
  EXPECT_EQ(sumDt(d), 3.0);
}

TEST(DatasetBuild, DuplicateOdometryStampsEmitNoEmptySteps) {
  RobotLog log;
  log.odometry = {{1.0, 1.0, 0.0}, {1.0, 2.0, 0.0}, {2.0, 3.0, 0.0}, {2.0, 4.0, 0.0}, {3.0, 5.0, 0.0}};
  const Dataset d = buildDataset(log);
  ASSERT_EQ(d.steps.size(), 2u);
  // A row whose interval is empty never drives a prediction.
  expectControl(d.steps[0], 2.0, 2.0, 0.0, 1.0, 0);
  expectControl(d.steps[1], 3.0, 4.0, 0.0, 1.0, 0);
}

TEST(DatasetBuild, CopiesMetadata) {
  RobotLog log = threeRows();
  log.groundtruth = {{10.0, Pose2(1, 2, 3)}};
  log.landmarks = {{6, Vec2(1, 2)}};
  log.noise = NoiseModel{0.5, 0.25, 0.125, 0.0625};
  const Dataset d = buildDataset(log);
  EXPECT_EQ(d.source, "synthetic");
  ASSERT_EQ(d.groundtruth.size(), 1u);
  EXPECT_EQ(d.groundtruth[0].pose, Pose2(1, 2, 3));
  EXPECT_EQ(d.landmarks.at(6), Vec2(1, 2));
  ASSERT_TRUE(d.noise.has_value());
  EXPECT_EQ(d.noise->sigma_range, 0.125);
}

TEST(DatasetBuild, NoOdometryDropsEverything) {
  RobotLog log;
  log.measurements = {{1.0, 6, 1.0, 0.0}, {2.0, 6, 1.0, 0.0}};
  const Dataset d = buildDataset(log);
  EXPECT_TRUE(d.steps.empty());
  EXPECT_EQ(d.dropped.before_first_control, 2u);
}

TEST(DatasetBuild, OdometryGoingBackwardsThrows) {
  RobotLog log = threeRows();
  log.odometry[2].time = 10.5;
  EXPECT_THROW(buildDataset(log), DataError);
}

TEST(DatasetBuild, RealDataInvariants) {
  const std::filesystem::path dir =
      std::filesystem::path(SEIF_SHARED_DATA_DIR) / "mrclam" / "MRCLAM_Dataset6";
  if (!std::filesystem::exists(dir / "Barcodes.dat")) {
    GTEST_SKIP() << "real MRCLAM dataset 6 not found at " << dir.string();
  }
  for (int robot = 1; robot <= 5; ++robot) {
    SCOPED_TRACE("robot " + std::to_string(robot));
    const RobotLog log = readMrclam(dir, robot);
    const Dataset d = buildDataset(log);
    EXPECT_EQ(d.start_time, log.odometry.front().time);
    EXPECT_EQ(d.dropped.before_first_control, 0u);
    // One step per distinct stamp after the start.
    std::set<double> stamps;
    for (const auto& r : log.odometry) {
      if (r.time > d.start_time) stamps.insert(r.time);
    }
    for (const auto& m : log.measurements) stamps.insert(m.time);
    ASSERT_EQ(d.steps.size(), stamps.size());
    std::size_t observations = 0;
    double previous = d.start_time - 1.0;  // the first step may sit at start_time
    for (const Step& s : d.steps) {
      ASSERT_GT(s.time, previous) << "step times strictly increase";
      ASSERT_GE(std::get<VelocityControl>(s.u).dt, 0.0);
      ASSERT_TRUE(std::get<VelocityControl>(s.u).dt > 0.0 || !s.observations.empty());
      // The control is the last odometry row strictly before the step (or row 0).
      const auto row = std::lower_bound(log.odometry.begin(), log.odometry.end(), s.time,
                                        [](const OdometryRecord& r, double t) { return r.time < t; });
      const auto& ctl = row == log.odometry.begin() ? *row : *(row - 1);
      ASSERT_EQ(std::get<VelocityControl>(s.u).v, ctl.v);
      ASSERT_EQ(std::get<VelocityControl>(s.u).w, ctl.w);
      observations += s.observations.size();
      previous = s.time;
    }
    EXPECT_EQ(observations, log.measurements.size());
    const double span = d.steps.back().time - d.start_time;
    EXPECT_NEAR(sumDt(d), span, 1e-6);
    EXPECT_GT(span, 800.0);  // about 890 s per robot
  }
}

// --- interpolatePose ---------------------------------------------------------------------

TEST(DatasetInterpolatePose, LinearInsideClampedOutside) {
  const std::vector<TimedPose> track = {{1.0, Pose2(0, 0, 0)}, {3.0, Pose2(2, -4, 1)}, {4.0, Pose2(3, -4, 1)}};
  const Pose2 mid = interpolatePose(track, 2.0);
  EXPECT_DOUBLE_EQ(mid.x(), 1.0);
  EXPECT_DOUBLE_EQ(mid.y(), -2.0);
  EXPECT_DOUBLE_EQ(mid.z(), 0.5);
  EXPECT_EQ(interpolatePose(track, 3.0), Pose2(2, -4, 1));
  EXPECT_DOUBLE_EQ(interpolatePose(track, 3.5).x(), 2.5);
  EXPECT_EQ(interpolatePose(track, -100.0), Pose2(0, 0, 0));
  EXPECT_EQ(interpolatePose(track, 1.0), Pose2(0, 0, 0));
  EXPECT_EQ(interpolatePose(track, 100.0), Pose2(3, -4, 1));
  EXPECT_EQ(interpolatePose({{5.0, Pose2(1, 2, 3)}}, 0.0), Pose2(1, 2, 3));
  EXPECT_THROW(interpolatePose({}, 0.0), seif::InvalidArgument);
}

TEST(DatasetInterpolatePose, AStartPoseOutsideTheGroundTruthSaysSo) {
  // The ground truth starting 150 s after the first control (or ending before it) gives the
  // run an end pose as its start: the source says so, with the gap; within a second it is
  // the interpolated pose.
  const std::vector<TimedPose> track = {{150.0, Pose2(0, 0, 0)}, {151.0, Pose2(1, 0, 0)}};
  EXPECT_EQ(timeOutsideTrack(track, 0.0), 150.0);
  EXPECT_EQ(timeOutsideTrack(track, 150.5), 0.0);
  EXPECT_EQ(timeOutsideTrack(track, 160.0), 9.0);
  EXPECT_EQ(startPoseFromGroundTruth(track, 150.5), "ground truth at the first control");
  EXPECT_EQ(startPoseFromGroundTruth(track, 149.5), "ground truth at the first control");
  const std::string late = startPoseFromGroundTruth(track, 0.0);
  EXPECT_NE(late.find("ground truth's first pose, 150 s from the first control"), std::string::npos) << late;
  EXPECT_NE(late.find("does not cover it"), std::string::npos) << late;
  EXPECT_NE(startPoseFromGroundTruth(track, 160.0).find("ground truth's last pose, 9 s"), std::string::npos);
}

TEST(DatasetInterpolatePose, HeadingTakesTheShortArcAcrossPi) {
  const std::vector<TimedPose> track = {{0.0, Pose2(0, 0, kPi - 0.1)}, {1.0, Pose2(0, 0, -kPi + 0.1)}};
  // Half way: through pi, not through 0.
  EXPECT_NEAR(std::abs(interpolatePose(track, 0.5).z()), kPi, 1e-12);
  EXPECT_NEAR(interpolatePose(track, 0.25).z(), kPi - 0.05, 1e-12);
  EXPECT_NEAR(interpolatePose(track, 0.75).z(), -kPi + 0.05, 1e-12);
  // And the other way round.
  const std::vector<TimedPose> back = {{0.0, Pose2(0, 0, -3.0)}, {2.0, Pose2(0, 0, 3.0)}};
  const double expected = wrapAngle(-3.0 - 0.5 * (2 * kPi - 6.0));
  EXPECT_NEAR(interpolatePose(back, 1.0).z(), expected, 1e-12);
  EXPECT_NEAR(std::abs(interpolatePose(back, 1.0).z()), kPi, 1e-12);
  EXPECT_NEAR(interpolatePose(back, 0.5).z(), -3.0 - 0.25 * (2 * kPi - 6.0), 1e-12);  // below -3
  EXPECT_NEAR(interpolatePose(back, 1.5).z(), 3.0 + 0.25 * (2 * kPi - 6.0), 1e-12);   // above 3
  for (double t = 0.0; t <= 2.0; t += 0.01) {
    const double z = interpolatePose(back, t).z();
    EXPECT_GT(z, -kPi);
    EXPECT_LE(z, kPi);
    EXPECT_GT(std::abs(z), 3.0 - 1e-12) << "never swings through zero (t = " << t << ")";
  }
}
