#pragma once
// A small self-contained SLAM scenario for filter tests: landmarks scattered around a
// circular path, range-bearing observations with noise, all from one seed.
#include <seif/core/angles.hpp>
#include <seif/core/dataset.hpp>
#include <seif/filters/slam_filter.hpp>
#include <seif/io/mrclam.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/sim/world.hpp>
#include "models/velocity_motion.hpp"

#include <filesystem>
#include <random>
#include <vector>

namespace seif::test {

struct Scenario {
  Pose2 start = Pose2::Zero();
  std::vector<Vec2> landmarks;
  std::vector<Step> steps;
  NoiseModel noise;
};

/// `noise_scale` multiplies every noise sigma (smaller: a more nearly linear problem).
/// A filter config with the scenario's noise (the paper's default models).
inline FilterConfig configFor(const Scenario& s) {
  FilterConfig c = paperFilterConfig(s.noise);
  return c;
}

inline Scenario makeScenario(std::uint64_t seed, int landmarks, int steps,
                             double sensor_range = 3.0, double noise_scale = 1.0) {
  Scenario s;
  s.noise = {0.05 * noise_scale, 0.02 * noise_scale, 0.05 * noise_scale, 0.02 * noise_scale};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> radius(2.0, 8.0), angle(-3.14159, 3.14159);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (int i = 0; i < landmarks; ++i) {
    const double r = radius(rng), a = angle(rng);
    s.landmarks.emplace_back(5.0 + r * std::cos(a), r * std::sin(a));
  }
  s.start = Pose2(5.0, -5.0, 0.0);  // on a circle of radius 5 about (5, 0), heading +x
  Pose2 truth = s.start;
  for (int k = 0; k < steps; ++k) {
    const VelocityControl u{1.0, 0.2, 0.5};
    const VelocityControl noisy{u.v + s.noise.sigma_v * n01(rng),
                                u.w + s.noise.sigma_w * n01(rng), u.dt};
    truth = VelocityMotionModel::apply(truth, noisy);
    Step step;
    step.time = (k + 1) * u.dt;
    step.u = u;
    for (int i = 0; i < landmarks; ++i) {
      const double d = (s.landmarks[static_cast<std::size_t>(i)] - truth.head<2>()).norm();
      if (d > sensor_range || d < 1e-3) continue;
      const Vec2 z = RangeBearingModel(1.0, 1.0).predict(truth, s.landmarks[static_cast<std::size_t>(i)]);
      step.observations.push_back({100 + i,
                                   Vec2(z.x() + s.noise.sigma_range * n01(rng),
                                        wrapAngle(z.y() + s.noise.sigma_bearing * n01(rng))),
                                   std::nullopt});
    }
    s.steps.push_back(std::move(step));
  }
  return s;
}

/// The paper's world over `steps` steps (50 landmarks, seed 3), written as an MRCLAM folder
/// `dir`/data, which it returns.
inline std::filesystem::path writePaperWorld(const std::filesystem::path& dir, int steps) {
  const std::filesystem::path data = dir / "data";
  writeMrclam(data, simulate(presetConfig(WorldPreset::Paper, 50, steps, 3)));
  return data;
}

}  // namespace seif::test
