// The simulator (docs/simulator.md). Order of the random draws, fixed: all landmarks
// (x then y, by subject), then per step k: the control noise (e_v, e_w), then for each
// landmark in range in subject order its detection draw (a uniform, only when
// detection_probability < 1) and, when detected, the measurement noise (e_range,
// e_bearing), then, only when clutter > 0, the number of false detections (one uniform per
// Poisson chunk) and for each its range and bearing (two uniforms).
#include <seif/core/errors.hpp>
#include <seif/sim/world.hpp>

#include <seif/core/angles.hpp>
#include <seif/models/range_bearing.hpp>
#include "models/velocity_motion.hpp"

#include "landmark_grid.hpp"
#include "path.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace seif {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kFirstSubject = 6;           // MRCLAM: subjects 1-5 are robots
constexpr double kMinDetectionRange = 1e-6;  // closer landmarks have no defined bearing

// Paper world: the unit square. Either path passes close enough to every point of the
// square that, with the 0.2 sensor, every landmark is seen, as in the paper, whose EKF has
// all 1275 links (docs/simulator.md). The lawnmower: lanes 0.1 from the border, at most
// 0.2 apart, corners of radius 0.04. The Lissajous curve: amplitude 0.4.
constexpr double kPaperMargin = 0.1;
constexpr double kPaperLaneSpacing = 0.2;
constexpr double kPaperTurnRadius = 0.04;
constexpr double kPaperAmplitude = 0.4;
constexpr int kPaperLandmarks = 50;
constexpr int kPaperSteps = 500;
constexpr double kPaperSpeed = 0.02;  // 10 m in 500 s: 1.6 laps of the 6.12 m curve
// Uniform world: lawnmower loop.
constexpr int kUniformLandmarks = 500;
constexpr double kUniformSpeed = kPaperSpeed;
constexpr double kLaneSpacingPerRange = 1.5;  // lanes 1.5 sensor ranges apart: swaths overlap
constexpr double kMarginPerRange = 0.75;      // path 0.75 sensor ranges inside the border
// Park world (WorldPreset::Park).
constexpr int kParkLandmarks = 150;
constexpr double kParkDensity = 1.0 / 400.0;  // trees per m^2
constexpr double kParkSpeed = 3.0;           // m/s
constexpr double kParkPeriod = 0.25;         // s
// Corridor world.
constexpr int kCorridorLandmarks = 1000;
constexpr double kCorridorSpeed = 0.05;  // density 50 x width 0.4 x 0.05 m = 1 new landmark/step

// Tracking controller (Kanayama et al. 1990), gains per control period dt.
constexpr double kNaturalFrequencyPerStep = 0.2;  // omega_n dt of the lateral/heading loop
constexpr double kDamping = 0.7;                  // zeta
constexpr double kAlongTrackGainPerStep = 0.3;    // k_x dt
constexpr double kMaxTurnPerStep = 1.0;           // |w| dt <= 1 rad
constexpr double kMaxSpeedFactor = 2.0;           // 0 <= v <= 2 speed

/// mt19937_64 with portable draws (std::*_distribution differ between standard libraries).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  /// Uniform on [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  /// A Poisson count of mean `mean` by inversion, one uniform per chunk of mean at most
  /// kPoissonChunk (a sum of independent Poisson counts is Poisson; exp(-chunk) stays normal).
  std::size_t poisson(double mean) {
    constexpr double kPoissonChunk = 256.0;
    std::size_t n = 0;
    while (mean > 0.0) {
      const double m = std::min(mean, kPoissonChunk);
      mean -= m;
      const double u = uniform();
      double p = std::exp(-m);
      double cdf = p;
      std::size_t k = 0;
      while (u >= cdf && p > 0.0) {  // p underflows past the tail if cdf rounds below u
        ++k;
        p *= m / static_cast<double>(k);
        cdf += p;
      }
      n += k;
    }
    return n;
  }
  /// Two independent standard normals (Box-Muller; consumes exactly two engine outputs).
  std::pair<double, double> normalPair() {
    const double u1 = static_cast<double>((engine_() >> 11) + 1) * 0x1.0p-53;  // (0, 1]
    const double u2 = uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1));
    return {radius * std::cos(2.0 * kPi * u2), radius * std::sin(2.0 * kPi * u2)};
  }

 private:
  std::mt19937_64 engine_;
};

double sinc(double a) { return std::abs(a) < 1e-4 ? 1.0 - a * a / 6.0 : std::sin(a) / a; }

/// The geometry of one world: where the landmarks are drawn and the path the robot tracks.
struct World {
  Vec2 lo;
  Vec2 hi;
  sim::ReferencePath path;
};

double uniformSide(const WorldConfig& c) { return std::sqrt(c.landmarks / c.density); }

sim::ReferencePath uniformPath(double side, double sensor_range) {
  const double margin = std::min(kMarginPerRange * sensor_range, 0.25 * side);
  return sim::lawnmowerLoop(side, margin, kLaneSpacingPerRange * sensor_range);
}

double corridorLength(const WorldConfig& c) {
  return c.landmarks / (c.density * c.corridor_width);
}

World makeWorld(const WorldConfig& c) {
  switch (c.preset) {
    case WorldPreset::Paper:
      return {Vec2(0.0, 0.0), Vec2(1.0, 1.0),
              c.paper_path == PaperPath::Lissajous
                  ? sim::lissajous(Vec2(0.5, 0.5), kPaperAmplitude, 3, 2)
                  : sim::lawnmowerLoop(1.0, kPaperMargin, kPaperLaneSpacing, kPaperTurnRadius)};
    case WorldPreset::Uniform:
    case WorldPreset::Park: {
      const double side = uniformSide(c);
      return {Vec2(0.0, 0.0), Vec2(side, side), uniformPath(side, c.sensor_range)};
    }
    case WorldPreset::Corridor: {
      const double length = corridorLength(c);
      const double half = 0.5 * c.corridor_width;
      return {Vec2(0.0, -half), Vec2(length, half),
              sim::PathBuilder(Pose2(0.0, 0.0, 0.0)).line(length).build(false)};
    }
  }
  throw InvalidArgument("invalid simulator config: unknown world preset");
}

void require(bool ok, const std::string& what) {
  if (!ok) throw InvalidArgument("invalid simulator config: " + what);
}

template <typename T>
std::string got(const char* name, T value) {
  std::ostringstream s;
  s << name << " (got " << value << ")";
  return s.str();
}

void validate(const WorldConfig& c) {
  require(c.paper_path == PaperPath::Lawnmower || c.paper_path == PaperPath::Lissajous,
          "unknown paper path");
  require(c.preset == WorldPreset::Paper || c.preset == WorldPreset::Uniform ||
              c.preset == WorldPreset::Corridor || c.preset == WorldPreset::Park,
          "unknown world preset");
  // The bounds keep a mistyped count from filling the memory: 10^7 landmarks hold ~0.5 GB,
  // 10^8 false detections ~4 GB of log.
  require(c.landmarks >= 1 && c.landmarks <= 10'000'000, got("landmarks must be in [1, 10^7]", c.landmarks));
  require(c.steps >= 1, got("steps must be >= 1", c.steps));
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  auto sigma = [](double v) { return std::isfinite(v) && v >= 0.0; };
  require(positive(c.sensor_range), got("sensor_range must be positive and finite", c.sensor_range));
  require(c.min_range >= 0.0 && c.min_range < c.sensor_range,
          got("min_range must be >= 0 and below sensor_range", c.min_range));
  // The log's controls stay within what the readers take (|v| <= 10^3 m/s, |w| <= 10^3
  // rad/s): v <= 2 speed and |w| dt <= 1 (kMaxSpeedFactor, kMaxTurnPerStep).
  require(positive(c.dt) && c.dt >= 1e-3, got("dt must be finite and >= 1e-3 s", c.dt));
  require(positive(c.speed) && c.speed <= 500.0, got("speed must be positive and at most 500 m/s", c.speed));
  require(positive(c.density), got("density must be positive and finite", c.density));
  require(positive(c.corridor_width),
          got("corridor_width must be positive and finite", c.corridor_width));
  require(sigma(c.noise.sigma_v), got("noise.sigma_v must be finite and >= 0", c.noise.sigma_v));
  require(sigma(c.noise.sigma_w), got("noise.sigma_w must be finite and >= 0", c.noise.sigma_w));
  require(sigma(c.noise.sigma_range),
          got("noise.sigma_range must be finite and >= 0", c.noise.sigma_range));
  require(sigma(c.noise.sigma_bearing),
          got("noise.sigma_bearing must be finite and >= 0", c.noise.sigma_bearing));
  // Each false detection may start a provisional landmark: at 10^3 a scan, association
  // spends its time starting and removing them (a SEIF's removals grow with their links).
  require(std::isfinite(c.clutter) && c.clutter >= 0.0 && c.clutter <= 1000.0,
          got("clutter must be in [0, 1000] false detections per scan", c.clutter));
  require(c.clutter * static_cast<double>(c.steps) <= 1e8,
          got("clutter x steps must be at most 10^8 false detections in all", c.clutter * static_cast<double>(c.steps)));
  require(c.detection_probability >= 0.0 && c.detection_probability <= 1.0,
          got("detection_probability must be in [0, 1]", c.detection_probability));
  if (c.preset == WorldPreset::Corridor) {
    require(std::isfinite(corridorLength(c)), "corridor length landmarks / (density * width) overflows");
  }
}

/// The control that tracks `ref` (feed-forward: the exact velocity-model control from `ref`
/// to `next`) from the true pose `x`: Kanayama et al. 1990,
///   v = v_r cos e_th + k_x e_x,   w = w_r + v_r (k_y e_y + k_th sin e_th),
/// with k_y = (omega_n / speed)^2, k_th = 2 zeta omega_n / speed (docs/simulator.md).
VelocityControl track(const Pose2& x, const Pose2& ref, const Pose2& next, double speed,
                      double dt) {
  const double w_r = wrapAngle(next.z() - ref.z()) / dt;
  const double v_r = (next.head<2>() - ref.head<2>()).norm() / (dt * sinc(0.5 * w_r * dt));
  const double c = std::cos(x.z());
  const double s = std::sin(x.z());
  const Vec2 d = ref.head<2>() - x.head<2>();
  const double e_x = c * d.x() + s * d.y();   // along the robot's heading
  const double e_y = -s * d.x() + c * d.y();  // to its left
  const double e_th = wrapAngle(ref.z() - x.z());
  const double omega_n = kNaturalFrequencyPerStep / dt;
  const double k_x = kAlongTrackGainPerStep / dt;
  double v = v_r * std::cos(e_th) + k_x * e_x;
  double w = w_r + v_r * (omega_n * omega_n / (speed * speed) * e_y +
                          2.0 * kDamping * omega_n / speed * std::sin(e_th));
  v = std::clamp(v, 0.0, kMaxSpeedFactor * speed);
  w = std::clamp(w, -kMaxTurnPerStep / dt, kMaxTurnPerStep / dt);
  return {v, w, dt};
}

}  // namespace

WorldPreset parseWorldPreset(std::string_view name) {
  if (name == "paper") return WorldPreset::Paper;
  if (name == "uniform") return WorldPreset::Uniform;
  if (name == "corridor") return WorldPreset::Corridor;
  if (name == "park") return WorldPreset::Park;
  throw InvalidArgument("unknown world \"" + std::string(name) +
                              "\": valid worlds are paper, uniform, corridor, park");
}

std::string_view worldPresetName(WorldPreset preset) {
  switch (preset) {
    case WorldPreset::Paper: return "paper";
    case WorldPreset::Uniform: return "uniform";
    case WorldPreset::Corridor: return "corridor";
    case WorldPreset::Park: return "park";
  }
  return "unknown";
}

PaperPath parsePaperPath(std::string_view name) {
  if (name == "lawnmower") return PaperPath::Lawnmower;
  if (name == "lissajous") return PaperPath::Lissajous;
  throw InvalidArgument("unknown paper path \"" + std::string(name) +
                              "\": valid paths are lawnmower, lissajous");
}

std::string_view paperPathName(PaperPath path) {
  switch (path) {
    case PaperPath::Lawnmower: return "lawnmower";
    case PaperPath::Lissajous: return "lissajous";
  }
  return "unknown";
}

WorldConfig presetConfig(WorldPreset preset, int landmarks, int steps, std::uint64_t seed) {
  WorldConfig c;
  c.preset = preset;
  c.seed = seed;
  // The paper's noise variances: 1e-4 (forward velocity), 1e-3 (rotational velocity),
  // 0.002 (range), 0.003 (bearing); sensor range 0.2; 50 landmarks per square unit.
  c.noise.sigma_v = std::sqrt(1e-4);
  c.noise.sigma_w = std::sqrt(1e-3);
  c.noise.sigma_range = std::sqrt(0.002);
  c.noise.sigma_bearing = std::sqrt(0.003);
  c.sensor_range = 0.2;
  c.min_range = 0.05;
  c.dt = 1.0;
  c.density = 50.0;
  c.corridor_width = 0.4;
  auto lapSteps = [&](double length) {
    return std::ceil(length / (c.speed * c.dt));
  };
  auto toSteps = [](double s) {
    require(s < 2e9, "the default number of steps does not fit an int; pass steps");
    return static_cast<int>(s);
  };
  switch (preset) {
    case WorldPreset::Paper:
      c.landmarks = landmarks > 0 ? landmarks : kPaperLandmarks;
      c.speed = kPaperSpeed;
      c.steps = steps > 0 ? steps : kPaperSteps;
      break;
    case WorldPreset::Uniform:
      c.landmarks = landmarks > 0 ? landmarks : kUniformLandmarks;
      c.speed = kUniformSpeed;
      c.steps = steps > 0 ? steps
                          : toSteps(std::max<double>(
                                kPaperSteps, lapSteps(uniformPath(uniformSide(c), c.sensor_range)
                                                          .length())));
      break;
    case WorldPreset::Park:
      c.landmarks = landmarks > 0 ? landmarks : kParkLandmarks;
      c.density = kParkDensity;
      c.sensor_range = 30.0;
      c.min_range = 1.0;
      c.speed = kParkSpeed;
      c.dt = kParkPeriod;
      c.noise.sigma_v = 0.16;
      c.noise.sigma_w = 0.012;
      c.noise.sigma_range = 0.5;
      c.noise.sigma_bearing = 2.0 * std::numbers::pi / 180.0;
      c.steps = steps > 0 ? steps : toSteps(lapSteps(uniformPath(uniformSide(c), c.sensor_range).length()));
      break;
    case WorldPreset::Corridor:
      c.landmarks = landmarks > 0 ? landmarks : kCorridorLandmarks;
      c.speed = kCorridorSpeed;
      c.steps = steps > 0 ? steps : toSteps(std::max(1.0, lapSteps(corridorLength(c))));
      break;
  }
  return c;
}

RobotLog simulate(const WorldConfig& config, SimStats* stats) {
  validate(config);
  const WorldConfig& c = config;
  const World world = makeWorld(c);
  const auto n = static_cast<std::size_t>(c.landmarks);
  const auto T = static_cast<std::size_t>(c.steps);
  Rng rng(c.seed);

  std::vector<Vec2> landmarks(n);
  const Vec2 extent = world.hi - world.lo;
  for (Vec2& y : landmarks) {
    const double ux = rng.uniform();
    const double uy = rng.uniform();
    y = world.lo + Vec2(ux * extent.x(), uy * extent.y());
  }
  const sim::LandmarkGrid grid(landmarks, world.lo, world.hi, c.sensor_range);

  RobotLog log;
  {
    std::ostringstream source;
    source << "simulated " << worldPresetName(c.preset) << " world (";
    if (c.preset == WorldPreset::Paper) source << paperPathName(c.paper_path) << " path, ";
    source << c.landmarks
           << " landmarks, " << c.steps << " steps, seed " << c.seed;
    if (c.detection_probability < 1.0) source << ", detection probability " << c.detection_probability;
    if (c.clutter > 0.0) source << ", clutter " << c.clutter << " per scan";
    source << ")";
    log.source = source.str();
  }
  log.robot = 1;
  log.noise = c.noise;
  for (std::size_t i = 0; i < n; ++i) {
    log.landmarks.emplace_hint(log.landmarks.end(), kFirstSubject + static_cast<int>(i),
                               landmarks[i]);
  }
  log.odometry.reserve(T);
  log.groundtruth.reserve(T + 1);
  {  // Expected detections per step, plus 10 %: avoids the copies (and the memory peak) of
     // growing a vector of millions of measurements. Only a hint: the vector still grows.
    const double per_step = std::min(static_cast<double>(n), n / (extent.x() * extent.y()) *
                                                                 kPi * c.sensor_range * c.sensor_range);
    const double expected = 1.1 * (per_step + c.clutter) * static_cast<double>(T) + 64.0;
    log.measurements.reserve(static_cast<std::size_t>(std::min(expected, 0x1.0p27)));
  }

  SimStats st;
  std::vector<char> seen(n, 0);
  std::vector<std::uint32_t> found;
  auto reference = [&](std::size_t k) {
    return world.path.pose(c.speed * (static_cast<double>(k) * c.dt));
  };
  Pose2 x = reference(0);
  Pose2 ref = x;
  log.groundtruth.push_back({0.0, x});
  // One blind zone for the true and the reported range: neither is logged below it.
  const double blind_zone = std::max(kMinDetectionRange, c.min_range);
  const RangeBearingModel sensor(1.0, 1.0);  // geometry only: the noise is drawn below
  for (std::size_t k = 0; k < T; ++k) {
    const Pose2 next = reference(k + 1);
    const VelocityControl u = track(x, ref, next, c.speed, c.dt);
    log.odometry.push_back({static_cast<double>(k) * c.dt, u.v, u.w});

    const auto [e_v, e_w] = rng.normalPair();
    x = VelocityMotionModel::apply(
        x, {u.v + c.noise.sigma_v * e_v, u.w + c.noise.sigma_w * e_w, c.dt});
    const double t = static_cast<double>(k + 1) * c.dt;
    log.groundtruth.push_back({t, x});
    ref = next;
    st.max_tracking_error = std::max(st.max_tracking_error, (x.head<2>() - ref.head<2>()).norm());

    found.clear();
    const std::size_t checked = grid.query(x.head<2>(), c.sensor_range, blind_zone, found);
    st.candidates_checked_total += checked;
    st.candidates_checked_max_per_step = std::max(st.candidates_checked_max_per_step, checked);
    st.max_detections_per_step = std::max(st.max_detections_per_step, found.size());
    if (found.empty()) ++st.steps_without_detection;
    for (const std::uint32_t i : found) {
      if (c.detection_probability < 1.0 && !(rng.uniform() < c.detection_probability)) {
        ++st.missed_detections;
        continue;
      }
      const Vec2 z = sensor.predict(x, landmarks[i]);
      const auto [e_r, e_b] = rng.normalPair();
      const double range = z.x() + c.noise.sigma_range * e_r;
      if (range < blind_zone) {  // the sensor reports no range inside its blind zone
        ++st.ranges_below_minimum;
        continue;
      }
      log.measurements.push_back({t, kFirstSubject + static_cast<int>(i), range,
                                  wrapAngle(z.y() + c.noise.sigma_bearing * e_b)});
      seen[i] = 1;
    }
    if (c.clutter > 0.0) {  // false detections, area-uniform in the footprint, after the real ones
      const std::size_t count = rng.poisson(c.clutter);
      const double r0 = blind_zone * blind_zone;
      const double r1 = c.sensor_range * c.sensor_range;
      for (std::size_t j = 0; j < count; ++j) {
        const double range = std::clamp(std::sqrt(r0 + rng.uniform() * (r1 - r0)), blind_zone, c.sensor_range);
        const double bearing = wrapAngle(-kPi + 2.0 * kPi * rng.uniform());
        log.measurements.push_back({t, kClutterSubject, range, bearing});
      }
      st.clutter += count;
    }
  }
  // A final stop command stamped T dt closes the last control interval, so that a reader
  // knows when the last step ends even if nothing was seen in it.
  log.odometry.push_back({static_cast<double>(T) * c.dt, 0.0, 0.0});
  st.measurements = log.measurements.size();
  st.mean_detections_per_step = static_cast<double>(st.measurements) / static_cast<double>(T);
  st.distinct_landmarks_seen = static_cast<std::size_t>(std::count(seen.begin(), seen.end(), 1));
  if (stats) *stats = st;
  return log;
}

}  // namespace seif
