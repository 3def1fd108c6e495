// The batch MAP's solve against the number of poses (10^3 to 10^5) on the corridor world (the
// paper's density and sensor along a strip, about one new landmark per step, observations on
// every step: one pose per step and, with the velocity model's rank-2 noise, one constraint
// per step). The filter run that starts it (the SEIF's, constant time per step) is outside
// the timing; finish() - every Levenberg-Marquardt iteration - is timed, and the counters
// split its time per iteration into linearise, factorise and solve (seconds).
#include <seif/eval/run.hpp>
#include <seif/filters/factory.hpp>
#include <seif/sim/world.hpp>

#include <benchmark/benchmark.h>

#include <map>
#include <memory>

namespace {

using namespace seif;

struct Corridor {
  Dataset data;
  FilterConfig config;
  Pose2 start;
};

const Corridor& corridor(int steps) {
  static std::map<int, Corridor> cache;
  auto it = cache.find(steps);
  if (it == cache.end()) {
    const WorldConfig world = presetConfig(WorldPreset::Corridor, steps, steps, 1);
    Corridor c;
    c.data = buildDataset(simulate(world));
    c.config = paperFilterConfig(c.data.noise.value_or(world.noise));
    c.start = startPose(c.data);
    it = cache.emplace(steps, std::move(c)).first;
  }
  return it->second;
}

void BM_BatchCorridor(benchmark::State& state) {
  const Corridor& c = corridor(static_cast<int>(state.range(0)));
  SmootherReport report;
  for (auto _ : state) {
    state.PauseTiming();
    auto batch = makeFilter("batch:init=seif", c.start, c.config);
    for (const Step& s : c.data.steps) batch->step(s.u, s.observations);
    state.ResumeTiming();
    batch->finish();
    state.PauseTiming();
    report = *batch->smootherReport();
    state.ResumeTiming();
  }
  const double it = report.iterations;
  state.counters["poses"] = report.poses;
  state.counters["landmarks"] = report.landmarks;
  state.counters["constraints"] = report.constraints;
  state.counters["iterations"] = it;
  state.counters["linearize_s_per_it"] = report.linearize_seconds / it;
  state.counters["factorize_s_per_it"] = report.factorize_seconds / it;
  state.counters["solve_s_per_it"] = report.step_seconds / it;
  state.counters["us_per_pose_per_it"] = 1e6 * report.solve_seconds / it / report.poses;
}

BENCHMARK(BM_BatchCorridor)->Arg(1000)->Arg(10000)->Arg(100000)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
