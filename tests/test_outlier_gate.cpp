// The gross-outlier gate: rejects what no sensor could have read, nothing on clean data,
// and a rejected reading leaves the filter exactly as if it had never been made.
#include "scenario.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include <seif/filters/factory.hpp>
#include "filters/outlier_gate.hpp"
#include <seif/models/range_bearing.hpp>
#include <seif/sim/world.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace {

using namespace seif;

using test::configFor;

Dataset datasetOf(const test::Scenario& s) {
  Dataset d;
  d.steps = s.steps;
  return d;
}

TEST(OutlierGate, ThresholdIsInMeasurementStandardDeviations) {
  OutlierGate gate(1000.0);
  const RangeBearingModel sensor(0.2, 0.03);
  const Pose2 x(0.0, 0.0, 0.0);
  const Vec2 y(1.0, 0.0);
  const Mat2 Z_inv = Vec2(1.0 / (0.2 * 0.2), 1.0 / (0.03 * 0.03)).asDiagonal();
  EXPECT_FALSE(gate.rejects(sensor, x, y, {7, Vec2(1.0 + 199.0, 0.0), {}}, Z_inv));  // 995 sigma
  EXPECT_TRUE(gate.rejects(sensor, x, y, {7, Vec2(1.0 + 201.0, 0.0), {}}, Z_inv));   // 1005 sigma
  EXPECT_TRUE(gate.rejects(sensor, x, y, {7, Vec2(std::numeric_limits<double>::quiet_NaN(), 0.0), {}}, Z_inv));
  EXPECT_EQ(gate.rejected(), 2u);
  OutlierGate off(std::numeric_limits<double>::infinity());
  EXPECT_FALSE(off.rejects(sensor, x, y, {7, Vec2(1e6, 0.0), {}}, Z_inv));
  EXPECT_THROW(OutlierGate(0.0), seif::InvalidArgument);
  EXPECT_THROW(OutlierGate(std::nan("")), seif::InvalidArgument);
}

// One 1e6 m range among clean readings: rejected and counted, and every filter ends exactly
// where it ends on the same data without that reading.
TEST(OutlierGate, ARejectedReadingLeavesTheFilterAsIfItWereNeverMade) {
  const test::Scenario s = test::makeScenario(3, 20, 80);
  Dataset clean = datasetOf(s);
  Dataset dirty = clean;
  // A re-observation well into the run (the landmark is mapped by then).
  std::size_t k = 40;
  while (dirty.steps[k].observations.empty()) ++k;
  dirty.steps[k].observations.insert(dirty.steps[k].observations.begin() + 0,
                                     Observation{dirty.steps[k].observations[0].landmark, Vec2(1e6, 0.3), std::nullopt});
  for (const char* name : {"ekf", "eif", "seif"}) {
    SCOPED_TRACE(name);
    auto a = makeFilter(name, s.start, configFor(s));
    auto b = makeFilter(name, s.start, configFor(s));
    const RunOutput ra = runFilter(*a, clean);
    const RunOutput rb = runFilter(*b, dirty);
    EXPECT_EQ(ra.rejected_observations, 0u);
    EXPECT_EQ(rb.rejected_observations, 1u);
    EXPECT_EQ(a->mean(), b->mean());
  }
}

// The simulator's worlds are clean: with their true noise the gate rejects nothing.
TEST(OutlierGate, RejectsNothingOnTheSimulatorsWorlds) {
  struct Case {
    WorldPreset preset;
    PaperPath path;
    int landmarks;
    std::vector<const char*> filters;
  };
  const Case cases[] = {
      {WorldPreset::Paper, PaperPath::Lawnmower, 0, {"ekf", "eif", "seif"}},
      {WorldPreset::Paper, PaperPath::Lissajous, 0, {"ekf", "eif", "seif"}},
      {WorldPreset::Uniform, PaperPath::Lawnmower, 200, {"ekf", "seif"}},
      {WorldPreset::Corridor, PaperPath::Lawnmower, 200, {"ekf", "seif"}},
      {WorldPreset::Corridor, PaperPath::Lawnmower, 3000, {"seif"}},
  };
  for (const Case& c : cases) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      WorldConfig world = presetConfig(c.preset, c.landmarks, 0, seed);
      world.paper_path = c.path;
      const Dataset data = buildDataset(simulate(world));
      for (const char* name : c.filters) {
        SCOPED_TRACE(std::string(worldPresetName(c.preset)) + " seed " + std::to_string(seed) + " " + name);
        FilterConfig config = paperFilterConfig(*data.noise);
        auto filter = makeFilter(name, startPose(data), config);
        EXPECT_EQ(runFilter(*filter, data).rejected_observations, 0u);
      }
    }
  }
}

}  // namespace
