// SLAM against dead reckoning on the simulator's worlds, with the worlds' own true noise:
// the aligned ATE of the EKF below dead reckoning's on every seed, the SEIF's on average.
// The corridor as preset is driven at 0.05 m per step so that the map grows by one landmark
// per step; each landmark is then in view for about 8 steps at ranges of 0.05-0.2 m with a
// range noise of 0.045 m, and without a loop nothing corrects the EKF's linearisation at
// such poorly known landmarks: there the EKF loses to dead reckoning on most seeds (README,
// "SLAM against dead reckoning"). With a sensor that sees twice as far (each landmark in
// view for about 16 steps, from more directions) the corridor is a SLAM world like the
// others: that case is asserted here, beside the presets where SLAM wins as they are.
#include <seif/eval/run.hpp>
#include <seif/filters/factory.hpp>
#include <seif/sim/world.hpp>

#include <gtest/gtest.h>

namespace {

using namespace seif;

struct Errors {
  double slam, dead_reckoning;
};

Errors run(const WorldConfig& world, const char* filter) {
  const RobotLog log = simulate(world);
  const Dataset data = buildDataset(log);
  FilterConfig config = paperFilterConfig(world.noise);
  auto f = makeFilter(filter, startPose(data), config);
  const RunOutput out = runFilter(*f, data);
  const auto dr = deadReckoning(data, startPose(data), f->motionModel());
  return {*ateRmse(out.trajectory, data.groundtruth, Alignment::Rigid),
          *ateRmse(dr, data.groundtruth, Alignment::Rigid)};
}

void expectSlamBeatsDeadReckoning(const std::function<WorldConfig(std::uint64_t)>& world, const std::string& name) {
  double seif_sum = 0.0, dr_sum = 0.0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const Errors ekf = run(world(seed), "ekf");
    EXPECT_LT(ekf.slam, ekf.dead_reckoning) << name << ", seed " << seed << ": EKF " << ekf.slam
                                             << " m against dead reckoning " << ekf.dead_reckoning << " m";
    const Errors seif = run(world(seed), "seif");
    seif_sum += seif.slam;
    dr_sum += seif.dead_reckoning;
  }
  EXPECT_LT(seif_sum, dr_sum) << name << ": SEIF mean ATE " << seif_sum / 5 << " m against " << dr_sum / 5 << " m";
}

TEST(SlamVsDeadReckoning, PaperWorldBothPaths) {
  for (const PaperPath path : {PaperPath::Lawnmower, PaperPath::Lissajous}) {
    expectSlamBeatsDeadReckoning([&](std::uint64_t seed) {
      WorldConfig w = presetConfig(WorldPreset::Paper, 0, 0, seed);
      w.paper_path = path;
      return w;
    }, std::string("paper/") + std::string(paperPathName(path)));
  }
}

TEST(SlamVsDeadReckoning, UniformWorld) {
  expectSlamBeatsDeadReckoning([](std::uint64_t seed) { return presetConfig(WorldPreset::Uniform, 200, 0, seed); },
                               "uniform, 200 landmarks");
}

TEST(SlamVsDeadReckoning, CorridorWithATwiceLongerSensorRange) {
  expectSlamBeatsDeadReckoning([](std::uint64_t seed) {
    WorldConfig w = presetConfig(WorldPreset::Corridor, 300, 0, seed);
    w.sensor_range = 0.4;  // the preset: 0.2 m
    return w;
  }, "corridor, sensor range 0.4 m");
}

}  // namespace
