// Cost of the model evaluations that every filter step makes.
#include <seif/models/range_bearing.hpp>
#include "models/velocity_motion.hpp"

#include <benchmark/benchmark.h>

static void BM_VelocityMotionWithJacobians(benchmark::State& state) {
  seif::Pose2 x(0.3, -0.2, 0.7);
  const seif::VelocityControl u{0.5, 0.2, 0.1};
  seif::Mat3 J_x;
  seif::Mat32 J_u;
  for (auto _ : state) {
    benchmark::DoNotOptimize(seif::VelocityMotionModel::delta(x, u, &J_x, &J_u));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_VelocityMotionWithJacobians);

static void BM_RangeBearingWithJacobians(benchmark::State& state) {
  const seif::Pose2 x(0.3, -0.2, 0.7);
  const seif::Vec2 y(1.0, 2.0);
  seif::Mat23 J_x;
  seif::Mat2 J_y;
  for (auto _ : state) {
    benchmark::DoNotOptimize(seif::RangeBearingModel(1.0, 1.0).predict(x, y, &J_x, &J_y));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_RangeBearingWithJacobians);
