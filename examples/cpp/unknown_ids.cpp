// A filter in your own loop when the sensor does not say what it saw.
//
// own_loop.cpp's robot, with a sensor like most real ones: it reports a range and a bearing
// but no landmark id, misses a landmark now and then, and sometimes reports something that
// is not there. Between predict and update an Associator names each observation: a mapped
// landmark inside the gate, a new (provisional) landmark far from all of them, or nothing
// (dropped as ambiguous). A new landmark must be seen again to stay; the false detections,
// seen once, are removed from the filter exactly.
//
// Symbols used (all from <seif/seif.hpp>, namespace seif), besides own_loop.cpp's:
//   AssociationOptions  method (Known, NearestNeighbour, Jcbb), gates, provisional landmarks
//   Associator          associate(filter, step, observations): sets each Observation::landmark
//                       (or drops the observation); finish(filter): removes what was never
//                       confirmed and scores the map against Observation::truth
//   Observation::truth  what was really seen, for scoring only: no filter or associator
//                       decision reads it (kUnknownLandmark: a false detection)
//   AssociationCounts   observations, correct, wrong, new and spurious landmarks, ...
#include <seif/seif.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

int main() {
  using namespace seif;

  // 1. The models and the filter: as own_loop.cpp, with the recommended constant-time
  //    configuration, whose covariances are honest enough to gate with.
  FilterConfig config;
  config.motion = std::make_shared<VelocityModel>(0.05, 0.02, NoiseForm::PerStep);
  config.sensor = std::make_shared<RangeBearingModel>(0.05, 0.02);
  const Pose2 start(0.0, 0.0, 0.0);
  std::unique_ptr<SlamFilter> filter = makeFilter("seif:profile=consistent", start, config);

  // 2. The associator: nearest neighbour inside the chi-square gate (0.99), a new landmark
  //    beyond 0.9999, confirmed when seen 4 times within 20 scans. Its gates use the filter's
  //    own marginals (in the SEIF, a bounded Markov blanket: constant time).
  AssociationOptions options;
  options.method = AssociationMethod::NearestNeighbour;
  Associator associator(options);

  // 3. The world: own_loop.cpp's ten landmarks about the circle the robot drives.
  std::vector<Vec2> landmarks;
  for (int i = 0; i < 10; ++i) {
    const double r = i % 2 == 0 ? 4.0 : 6.0, a = 0.628 * i;
    landmarks.emplace_back(r * std::sin(a), 5.0 - r * std::cos(a));
  }
  Pose2 truth = start;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);

  // 4. The driver's loop: move, sense, associate, update.
  for (std::size_t k = 0; k < 700; ++k) {
    const VelocityControl u{0.5, 0.1, 0.1};
    truth = config.motion->apply(truth, VelocityControl{u.v + 0.05 * noise(rng), u.w + 0.02 * noise(rng), u.dt});
    filter->predict(u);

    std::vector<Observation> seen;
    for (int i = 0; i < static_cast<int>(landmarks.size()); ++i) {
      const Vec2 z = config.sensor->predict(truth, landmarks[static_cast<std::size_t>(i)]);
      if (z.x() > 4.0 || uniform(rng) < 0.1) continue;  // out of range, or missed (one in ten)
      Observation o;                                     // o.landmark stays kUnknownLandmark
      o.z = Vec2(z.x() + 0.05 * noise(rng), z.y() + 0.02 * noise(rng));
      o.truth = i;  // for scoring only
      seen.push_back(o);
    }
    if (uniform(rng) < 0.2) {  // a false detection in one scan in five
      Observation clutter;
      clutter.z = Vec2(0.5 + 3.5 * uniform(rng), wrapAngle(6.283185307179586 * uniform(rng)));
      seen.push_back(clutter);
    }
    associator.associate(*filter, k, seen);  // names each observation, drops the ambiguous ones
    filter->update(seen);
  }
  associator.finish(*filter);  // removes the landmarks still provisional, scores the map

  // 5. What came of it: the map, and the association scored against the truth.
  const AssociationCounts& c = associator.counts();
  const Pose2 x = filter->pose();
  std::printf("pose (%.3f, %.3f, %.3f), truth (%.3f, %.3f, %.3f)\n", x.x(), x.y(), x.z(), truth.x(), truth.y(),
              truth.z());
  std::printf("%zu observations: %zu of the %zu with a true landmark kept are right, %zu wrong\n", c.observations,
              c.correct, c.scored, c.wrong);
  std::printf("%zu landmarks started, %zu provisional ones removed, %zu ambiguous observations dropped\n",
              c.new_landmarks, c.provisional_removed, c.ambiguous_dropped);
  std::printf("mapped %zu landmarks (%zu spurious, %zu duplicates) of the %zu in the world\n", c.landmarks_final,
              c.spurious_landmarks, c.duplicate_landmarks, landmarks.size());
  const bool ok = (x.head<2>() - truth.head<2>()).norm() < 1.0 && c.landmarks_final == landmarks.size() &&
                  c.spurious_landmarks == 0 && c.correct >= c.scored * 99 / 100;
  std::printf("%s\n", ok ? "unknown ids: OK" : "unknown ids: the map or the association is off");
  return ok ? 0 : 1;
}
