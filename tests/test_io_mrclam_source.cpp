// The streaming MRCLAM source yields the events of the log readMrclam reads whole (same
// rows, same grouping, same drops), with its noise and start pose said and sourced.
#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include "io/mrclam_source.hpp"
#include "io/robot_log_source.hpp"
#include <seif/sim/world.hpp>

#include <gtest/gtest.h>

namespace {

using namespace seif;
namespace fs = std::filesystem;
const fs::path kReal = fs::path(SEIF_SHARED_DATA_DIR) / "mrclam" / "MRCLAM_Dataset6";

void expectSameEvents(EventSource& streamed, EventSource& whole) {
  Event a, b;
  std::size_t n = 0;
  while (whole.next(b)) {
    ASSERT_TRUE(streamed.next(a)) << "event " << n;
    ASSERT_EQ(a.index(), b.index()) << "event " << n;
    ASSERT_EQ(eventTime(a), eventTime(b)) << "event " << n;
    if (const auto* oa = std::get_if<ObservationEvent>(&a)) {
      const auto& ob = std::get<ObservationEvent>(b);
      ASSERT_EQ(oa->observations.size(), ob.observations.size()) << "event " << n;
      for (std::size_t i = 0; i < ob.observations.size(); ++i) {
        ASSERT_EQ(oa->observations[i].landmark, ob.observations[i].landmark);
        ASSERT_EQ(oa->observations[i].z, ob.observations[i].z);
      }
    } else if (const auto* ca = std::get_if<ControlEvent>(&a)) {
      const auto& ua = std::get<VelocityControl>(ca->input);
      const auto& ub = std::get<VelocityControl>(std::get<ControlEvent>(b).input);
      ASSERT_EQ(ua.v, ub.v);
      ASSERT_EQ(ua.w, ub.w);
    } else {
      ASSERT_EQ(std::get<TimedPose>(a).pose, std::get<TimedPose>(b).pose);
    }
    ++n;
  }
  EXPECT_FALSE(streamed.next(a));
  EXPECT_EQ(streamed.dropped(), whole.dropped());
  EXPECT_GT(n, 0u);
}

TEST(MrclamSource, StreamsTheEventsOfTheWholeLogOnEveryRealRobot) {
  if (!fs::exists(kReal / "Barcodes.dat")) GTEST_SKIP() << "MRCLAM dataset 6 not found at " << kReal.string();
  for (int robot = 1; robot <= 5; ++robot) {
    const RobotLog log = readMrclam(kReal, robot);
    RobotLogSource whole(log, NoiseModel{});
    DatasetOptions o;
    o.robot = robot;
    auto streamed = openMrclam(kReal, o);
    EXPECT_EQ(streamed->info().start_pose, interpolatePose(log.groundtruth, log.odometry.front().time)) << robot;
    EXPECT_EQ(streamed->info().landmarks, log.landmarks);
    expectSameEvents(*streamed, whole);
    EXPECT_EQ(streamed->progress(), 1.0);
  }
}

TEST(MrclamSource, ASimulatedFolderKeepsItsPerStepNoiseFromMetaJson) {
  const fs::path dir = fs::temp_directory_path() / "seif-mrclam-source";
  fs::remove_all(dir);
  RobotLog log = simulate(presetConfig(WorldPreset::Paper, 0, 40, 2));
  log.noise = NoiseModel{0.011, 0.022, 0.033, 0.044};
  writeMrclam(dir, log);
  auto s = openMrclam(dir, {});
  const RobotLog read_back = readMrclam(dir, 1);
  RobotLogSource whole(read_back, NoiseModel{});
  std::map<std::string, NoiseSetting> n;
  for (const NoiseSetting& x : s->info().noise) n[x.name] = x;
  EXPECT_EQ(n["sigma_v"].value, 0.011);
  EXPECT_EQ(n["sigma_bearing"].value, 0.044);
  EXPECT_EQ(n["sigma_v"].source, (dir / "meta.json").string());
  EXPECT_EQ(n["sigma_v"].unit, "m/s");  // per step
  expectSameEvents(*s, whole);
  // Without meta.json: the real robots' defaults, as a rate; a flag wins over both.
  fs::remove(dir / "meta.json");
  DatasetOptions o;
  o.noise["sigma_range"] = 0.5;
  auto d = openMrclam(dir, o);
  n.clear();
  for (const NoiseSetting& x : d->info().noise) n[x.name] = x;
  EXPECT_NEAR(n["sigma_v"].value.value(), 0.05 * std::sqrt(kMrclamOdometryPeriod), 1e-15);
  EXPECT_EQ(n["sigma_v"].unit, "m/s*sqrt(s)");
  EXPECT_EQ(n["sigma_v"].source, "default for mrclam");
  EXPECT_EQ(n["sigma_range"].value, 0.5);
  EXPECT_EQ(n["sigma_range"].source, "command line");
  fs::remove_all(dir);
}

TEST(MrclamSource, MalformedLinesAndMissingFilesNameTheFile) {
  MrclamFiles f;
  f.folder = "m";
  f.text["Barcodes.dat"] = "1 11\n6 16\n";
  f.text["Landmark_Groundtruth.dat"] = "6 1 2 0 0\n";
  f.text["Robot1_Odometry.dat"] = "1 0.1 0\n2 0.1\n";
  f.text["Robot1_Measurement.dat"] = "1.5 16 1 0\n";
  const auto expectError = [&](const MrclamFiles& files, const std::string& where) {
    try {
      auto s = openMrclam(files, {});
      Event e;
      while (s->next(e)) {
      }
      ADD_FAILURE() << "accepted";
    } catch (const DataError& e) {
      EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
    }
  };
  expectError(f, "m/Robot1_Odometry.dat:2: expected 3 fields");
  f.text["Robot1_Odometry.dat"] = "1 0.1 0\n0.5 0.1 0\n";
  expectError(f, "m/Robot1_Odometry.dat:2: time 0.5 goes backwards");
  f.text["Robot1_Odometry.dat"] = "1 0.1 0\n";
  f.text["Robot1_Measurement.dat"] = "1.5 16 nan 0\n";
  expectError(f, "m/Robot1_Measurement.dat:1: non-finite number 'nan'");
  f.text["Robot1_Measurement.dat"] = "1.5 16 one 0\n";
  expectError(f, "m/Robot1_Measurement.dat:1: bad number 'one'");
  f.text.erase("Robot1_Measurement.dat");
  expectError(f, "m/Robot1_Measurement.dat: missing required file");
}

}  // namespace
