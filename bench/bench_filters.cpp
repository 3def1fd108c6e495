// One filter cycle (predict + update with 6 observations of mapped landmarks) against the
// map size N, for the EKF, the EIF and the SEIF. Each filter is prepared once per N, outside
// the timing loop, and cached; the timed steps keep the robot still (v = w = 0, dt = 1) and
// re-observe mapped landmarks, six at a time in turn, with the range and bearing their
// current estimates predict, so the data stay consistent however long the loop runs (the
// state still changes every iteration, which does not change the cost of a step).
//
//   EKF, EIF: N landmarks in a ring 0.05-0.2 around the start pose, all entered by one
//             update. Their step is dense algebra on the whole (3+2N)^2 matrix whatever
//             its sparsity, and building the map step by step would cost O(N^3) (EKF) or
//             O(N^4) (EIF) - minutes at N = 800.
//   SEIF:     the corridor world with N landmarks driven to its end (simulator, about one
//             new landmark per step), because a SEIF step depends on the structure of H.
//             The observed landmarks are the 36 mapped last (around the robot); each
//             iteration activates six of them, so it sparsifies as in a real run.
//
// `seif bench` measures the same thing on whole runs (time per step at the end of the
// corridor, peak memory); this file is the quick microbenchmark (`make bench`).
#include <seif/eval/run.hpp>
#include <seif/filters/factory.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/sim/world.hpp>

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace seif;

constexpr int kObservationsPerStep = 6;
constexpr int kBatches = 6;

struct Prepared {
  std::unique_ptr<SlamFilter> filter;
  std::vector<std::vector<Observation>> batches;  // kBatches x kObservationsPerStep ids
  std::size_t next = 0;
};

NoiseModel paperNoise() { return presetConfig(WorldPreset::Paper).noise; }

/// Range and bearing of each landmark of `ids` as the filter's estimates predict them.
std::vector<Observation> predicted(const SlamFilter& f, const std::vector<int>& ids) {
  std::vector<Observation> z;
  for (int id : ids) {
    const Vec2 rb = RangeBearingModel(1.0, 1.0).predict(f.pose(), f.landmark(id));
    z.push_back({id, rb, std::nullopt});
  }
  return z;
}

/// Cuts `ids` into kBatches batches of kObservationsPerStep (fewer when the map is small).
void makeBatches(Prepared& p, const std::vector<int>& ids) {
  for (int b = 0; b < kBatches; ++b) {
    std::vector<int> batch;
    for (int i = 0; i < kObservationsPerStep; ++i) {
      const std::size_t k = static_cast<std::size_t>(b * kObservationsPerStep + i);
      if (k < ids.size()) batch.push_back(ids[k]);
    }
    if (!batch.empty()) p.batches.push_back(predicted(*p.filter, batch));
  }
}

Prepared prepareDense(const std::string& name, int n) {
  FilterConfig config = paperFilterConfig(paperNoise());
  const Pose2 start(0.0, 0.0, 0.0);
  Prepared p;
  p.filter = makeFilter(name, start, config);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> radius(0.05, 0.2), angle(-3.0, 3.0);
  std::vector<Observation> all;
  std::vector<int> ids;
  for (int i = 0; i < n; ++i) {
    all.push_back({100 + i, Vec2(radius(rng), angle(rng)), std::nullopt});
    ids.push_back(100 + i);
  }
  p.filter->update(all);
  makeBatches(p, ids);
  return p;
}

Prepared prepareSeif(int n) {
  const WorldConfig world = presetConfig(WorldPreset::Corridor, n, 0, 1);
  const Dataset data = buildDataset(simulate(world));
  FilterConfig config = paperFilterConfig(world.noise);
  Prepared p;
  p.filter = makeFilter("seif", startPose(data), config);
  for (const Step& step : data.steps) p.filter->step(step.u, step.observations);
  const std::vector<int>& mapped = p.filter->landmarkIds();
  const std::size_t last = std::min<std::size_t>(mapped.size(), kBatches * kObservationsPerStep);
  makeBatches(p, std::vector<int>(mapped.end() - static_cast<std::ptrdiff_t>(last), mapped.end()));
  return p;
}

Prepared& prepared(const std::string& name, int n) {
  static std::map<std::pair<std::string, int>, Prepared> cache;  // built once per (filter, N)
  auto it = cache.find({name, n});
  if (it == cache.end()) {
    it = cache.emplace(std::make_pair(name, n), name == "seif" ? prepareSeif(n) : prepareDense(name, n)).first;
  }
  return it->second;
}

void filterStep(benchmark::State& state, const std::string& name) {
  const int n = static_cast<int>(state.range(0));
  Prepared& p = prepared(name, n);
  const VelocityControl still{0.0, 0.0, 1.0};
  for (auto _ : state) {
    const std::vector<Observation>& z = p.batches[p.next];
    p.next = (p.next + 1) % p.batches.size();
    p.filter->step(still, z);
    benchmark::ClobberMemory();
  }
  state.counters["landmarks"] = static_cast<double>(p.filter->landmarkIds().size());
  state.counters["blocks_touched"] = static_cast<double>(p.filter->blocksTouched());
}

/// One SEIF step, then the marginal covariance of the pose and, with `every_landmark`, of
/// every landmark too: the cost of a map.csv. The first read after the step factors H and
/// computes its selected inverse's columns on the read's elimination-tree path
/// (SparseMarginals); all of a map cost one full pass, linear in N on the corridor (the
/// landed per-landmark solve was O(N) per landmark). The pose alone is a library user reading
/// a covariance after every step: a factorisation, O(N), not constant time.
void seifStepAndMarginals(benchmark::State& state, bool every_landmark) {
  Prepared& p = prepared("seif", static_cast<int>(state.range(0)));
  const VelocityControl still{0.0, 0.0, 1.0};
  double trace = 0.0;
  for (auto _ : state) {
    p.filter->step(still, p.batches[p.next]);
    p.next = (p.next + 1) % p.batches.size();
    trace += p.filter->poseCovariance().trace();
    if (!every_landmark) continue;
    for (int id : p.filter->landmarkIds()) trace += p.filter->landmarkCovariance(id).trace();
  }
  benchmark::DoNotOptimize(trace);
  const double n = static_cast<double>(p.filter->landmarkIds().size());
  state.counters["landmarks"] = n;
  if (every_landmark) {
    state.counters["per_landmark"] = benchmark::Counter(
        n * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  }
}

void BM_SeifStepAndAllMarginals(benchmark::State& state) { seifStepAndMarginals(state, true); }
void BM_SeifStepAndOneMarginal(benchmark::State& state) { seifStepAndMarginals(state, false); }

void BM_EkfStep(benchmark::State& state) { filterStep(state, "ekf"); }
void BM_EifStep(benchmark::State& state) { filterStep(state, "eif"); }
void BM_SeifStep(benchmark::State& state) { filterStep(state, "seif"); }

}  // namespace

void denseSizes(benchmark::internal::Benchmark* b) {
  for (int n : {50, 100, 200, 400, 800}) b->Arg(n);
  b->Unit(benchmark::kMicrosecond);
}
void seifSizes(benchmark::internal::Benchmark* b) {
  for (int n : {50, 100, 200, 400, 800, 10000, 100000}) b->Arg(n);
  b->Unit(benchmark::kMicrosecond);
}

BENCHMARK(BM_EkfStep)->Apply(denseSizes);
BENCHMARK(BM_EifStep)->Apply(denseSizes);
BENCHMARK(BM_SeifStep)->Apply(seifSizes);
BENCHMARK(BM_SeifStepAndAllMarginals)->Apply(seifSizes);
BENCHMARK(BM_SeifStepAndOneMarginal)->Apply(seifSizes);
