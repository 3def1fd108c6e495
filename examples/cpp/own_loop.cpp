// A filter in your own loop: a robot driver that owns its sensors and calls the filter.
//
// This is how seif is embedded on a robot: you decide when a motion happened and what the
// sensor saw; the filter keeps the map and the pose. Here the "robot" is a few lines of
// simulation so that the example runs anywhere, in milliseconds.
//
// Symbols used (all from <seif/seif.hpp>, namespace seif):
//   FilterConfig      the models a filter uses: motion (VelocityModel) and sensor (RangeBearingModel)
//   makeFilter        builds a filter from a spec: "ekf", "eif", "seif", "seif:active=4", ...
//   VelocityControl   a motion input (v [m/s], w [rad/s], dt [s])
//   Observation       one sighting: landmark id, measurement z = (range [m], bearing [rad])
//   SlamFilter        predict / update / pose / poseCovariance / marginal / predictMeasurement
//   Marginal, MarginalMode  a joint marginal (mean, covariance), exact or Markov-blanket local
#include <seif/seif.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

int main() {
  using namespace seif;

  // 1. The models: a velocity-controlled robot with per-step noise on (v, w), and a
  //    range-bearing sensor at the robot's origin. Every filter is configured this way.
  FilterConfig config;
  config.motion = std::make_shared<VelocityModel>(0.05, 0.02, NoiseForm::PerStep);
  config.sensor = std::make_shared<RangeBearingModel>(0.05, 0.02);

  // 2. The filter: the SEIF keeps at most 4 landmarks linked to the robot, so every
  //    update costs the same whatever the size of the map.
  const Pose2 start(0.0, 0.0, 0.0);
  std::unique_ptr<SlamFilter> filter = makeFilter("seif:active=4", start, config);

  // 3. The world the driver sees: ten landmarks inside and outside the circle the robot
  //    drives (radius v / w = 5 m about (0, 5)), and the true robot pose.
  std::vector<Vec2> landmarks;
  for (int i = 0; i < 10; ++i) {
    const double r = i % 2 == 0 ? 4.0 : 6.0, a = 0.628 * i;
    landmarks.emplace_back(r * std::sin(a), 5.0 - r * std::cos(a));
  }
  Pose2 truth = start;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 1.0);

  // 4. The driver's loop: move, sense, tell the filter.
  for (int k = 0; k < 700; ++k) {  // 70 s: a little more than one lap
    const VelocityControl u{0.5, 0.1, 0.1};
    truth = config.motion->apply(truth, VelocityControl{u.v + 0.05 * noise(rng), u.w + 0.02 * noise(rng), u.dt});
    filter->predict(u);  // the filter linearises its motion model at its own pose

    std::vector<Observation> seen;
    for (int i = 0; i < static_cast<int>(landmarks.size()); ++i) {
      const Vec2 z = config.sensor->predict(truth, landmarks[static_cast<std::size_t>(i)]);
      if (z.x() > 4.0) continue;  // out of range
      seen.push_back({i, Vec2(z.x() + 0.05 * noise(rng), z.y() + 0.02 * noise(rng)), std::nullopt});
    }
    filter->update(seen);  // all sightings of one instant: applied whole or not at all
  }

  // 5. Reading the estimate: the pose and its covariance, a joint marginal, and what the
  //    sensor should see of landmark 0 with its innovation covariance (for gating).
  const Pose2 x = filter->pose();
  const Mat3 P = filter->poseCovariance();
  std::printf("pose (%.3f, %.3f, %.3f), truth (%.3f, %.3f, %.3f)\n", x.x(), x.y(), x.z(), truth.x(), truth.y(),
              truth.z());
  std::printf("pose sigma x %.4f m, y %.4f m, theta %.4f rad\n", std::sqrt(P(0, 0)), std::sqrt(P(1, 1)),
              std::sqrt(P(2, 2)));
  const int ids[] = {0, 1};
  const Marginal exact = filter->marginal(ids, true, MarginalMode::Exact);
  const Marginal local = filter->marginal(ids, true, MarginalMode::Local);
  std::printf("joint marginal of pose + 2 landmarks: %ldx%ld, trace exact %.5f >= local %.5f\n",
              static_cast<long>(exact.covariance.rows()), static_cast<long>(exact.covariance.cols()),
              exact.covariance.trace(), local.covariance.trace());
  const PredictedMeasurement z0 = filter->predictMeasurement(0, *config.sensor, config.sensor->noise());
  std::printf("landmark 0: expected range %.3f m, bearing %.3f rad, innovation sigma %.4f m\n", z0.z.x(), z0.z.y(),
              std::sqrt(z0.S(0, 0)));
  std::printf("mapped %zu landmarks; %zu linked to the robot\n", filter->landmarkIds().size(), filter->robotLinks());
  const bool ok = (x.head<2>() - truth.head<2>()).norm() < 1.0 && filter->landmarkIds().size() == landmarks.size();
  std::printf("%s\n", ok ? "own loop: OK" : "own loop: the estimate is off");
  return ok ? 0 : 1;
}
