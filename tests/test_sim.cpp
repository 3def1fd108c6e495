// Tests of the simulator (include/seif/sim/world.hpp, docs/simulator.md), through its
// public API only. Statistical checks use 99.9 % bounds derived from the sample size, on
// fixed seeds: they pass or fail deterministically, and fail if the noise is wrong.
#include <seif/core/errors.hpp>
#include <seif/core/angles.hpp>
#include <seif/core/dataset.hpp>
#include <seif/models/range_bearing.hpp>
#include <seif/sim/world.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using seif::PaperPath;
using seif::paperPathName;
using seif::parsePaperPath;
using seif::presetConfig;
using seif::RobotLog;
using seif::SimStats;
using seif::simulate;
using seif::Vec2;
using seif::WorldConfig;
using seif::WorldPreset;

constexpr double kZ999 = 3.2905;  // two-sided 99.9 % quantile of the standard normal

/// Sample mean and variance (unbiased) of xs.
struct Moments {
  double mean;
  double variance;
};

Moments moments(const std::vector<double>& xs) {
  double sum = 0.0;
  for (double x : xs) sum += x;
  const double mean = sum / static_cast<double>(xs.size());
  double ss = 0.0;
  for (double x : xs) ss += (x - mean) * (x - mean);
  return {mean, ss / static_cast<double>(xs.size() - 1)};
}

/// Checks that xs looks like n draws of N(0, 1): the mean within kZ999 / sqrt(n), and the
/// sample variance within the normal approximation of its chi-square distribution,
/// (n - 1) s^2 ~ chi2(n - 1) ~ N(n - 1, 2 (n - 1)).
void expectStandardNormal(const std::vector<double>& xs, const std::string& what) {
  ASSERT_GT(xs.size(), 100u) << what;
  const double n = static_cast<double>(xs.size());
  const Moments m = moments(xs);
  EXPECT_LT(std::abs(m.mean), kZ999 / std::sqrt(n)) << what << ": mean " << m.mean << ", n " << n;
  EXPECT_LT(std::abs(m.variance - 1.0), kZ999 * std::sqrt(2.0 / (n - 1.0)))
      << what << ": variance " << m.variance << ", n " << n;
}

/// The ground-truth index of a time stamp (stamps are k * dt).
std::size_t stepOf(double t, double dt) { return static_cast<std::size_t>(std::lround(t / dt)); }

bool sameLog(const RobotLog& a, const RobotLog& b) {
  if (a.odometry.size() != b.odometry.size() || a.measurements.size() != b.measurements.size() ||
      a.groundtruth.size() != b.groundtruth.size() || a.landmarks.size() != b.landmarks.size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.odometry.size(); ++i) {
    const auto &p = a.odometry[i], &q = b.odometry[i];
    if (p.time != q.time || p.v != q.v || p.w != q.w) return false;
  }
  for (std::size_t i = 0; i < a.measurements.size(); ++i) {
    const auto &p = a.measurements[i], &q = b.measurements[i];
    if (p.time != q.time || p.subject != q.subject || p.range != q.range || p.bearing != q.bearing) {
      return false;
    }
  }
  for (std::size_t i = 0; i < a.groundtruth.size(); ++i) {
    if (a.groundtruth[i].time != b.groundtruth[i].time ||
        a.groundtruth[i].pose != b.groundtruth[i].pose) {
      return false;
    }
  }
  return a.landmarks == b.landmarks;
}

// --- names and configs -------------------------------------------------------------

TEST(SimWorldPreset, ParsesTheFourNamesAndRejectsOthersListingThem) {
  EXPECT_EQ(seif::parseWorldPreset("paper"), WorldPreset::Paper);
  EXPECT_EQ(seif::parseWorldPreset("uniform"), WorldPreset::Uniform);
  EXPECT_EQ(seif::parseWorldPreset("corridor"), WorldPreset::Corridor);
  EXPECT_EQ(seif::parseWorldPreset("park"), WorldPreset::Park);
  for (WorldPreset p : {WorldPreset::Paper, WorldPreset::Uniform, WorldPreset::Corridor, WorldPreset::Park}) {
    EXPECT_EQ(seif::parseWorldPreset(seif::worldPresetName(p)), p);
  }
  for (const char* bad : {"", "Paper", "papers", "grid"}) {
    try {
      seif::parseWorldPreset(bad);
      ADD_FAILURE() << "accepted \"" << bad << "\"";
    } catch (const seif::InvalidArgument& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("paper"), std::string::npos) << msg;
      EXPECT_NE(msg.find("uniform"), std::string::npos) << msg;
      EXPECT_NE(msg.find("corridor"), std::string::npos) << msg;
      EXPECT_NE(msg.find("park"), std::string::npos) << msg;
    }
  }
}

TEST(SimWorldPreset, TheParkIsAnOutdoorWorldAtVictoriaParksScale) {
  const seif::WorldConfig c = seif::presetConfig(WorldPreset::Park, 0, 0, 3);
  EXPECT_EQ(c.landmarks, 150);
  EXPECT_DOUBLE_EQ(c.sensor_range, 30.0);
  EXPECT_DOUBLE_EQ(c.noise.sigma_range, 0.5);
  SimStats stats;
  const RobotLog log = simulate(c, &stats);
  // About 2 km of lawnmower loop at 3 m/s, 4 Hz; ~6-7 trees in view (the paper world's count).
  EXPECT_GT(c.steps, 1500);
  EXPECT_GT(stats.mean_detections_per_step, 4.0);
  EXPECT_LT(stats.mean_detections_per_step, 10.0);
  EXPECT_GE(stats.distinct_landmarks_seen, 140u);
  const seif::Dataset d = seif::buildDataset(log);
  for (const seif::Step& s : d.steps) {
    for (const seif::Observation& z : s.observations) {
      EXPECT_GE(z.z.x(), 0.0);  // noisy ranges of trees between 1 m and 30 m
      EXPECT_LT(z.z.x(), 32.0);
    }
  }
}

TEST(SimWorldPreset, DefaultsFollowThePaperAndTheSizeOfTheWorld) {
  const WorldConfig p = presetConfig(WorldPreset::Paper, 0, 0, 7);
  EXPECT_EQ(p.landmarks, 50);
  EXPECT_EQ(p.steps, 500);
  EXPECT_EQ(p.seed, 7u);
  EXPECT_NEAR(p.noise.sigma_v * p.noise.sigma_v, 1e-4, 1e-18);
  EXPECT_NEAR(p.noise.sigma_w * p.noise.sigma_w, 1e-3, 1e-17);
  EXPECT_NEAR(p.noise.sigma_range * p.noise.sigma_range, 0.002, 1e-17);
  EXPECT_NEAR(p.noise.sigma_bearing * p.noise.sigma_bearing, 0.003, 1e-17);
  EXPECT_EQ(p.sensor_range, 0.2);
  EXPECT_EQ(p.dt, 1.0);
  EXPECT_EQ(presetConfig(WorldPreset::Paper, 80, 120).landmarks, 80);
  EXPECT_EQ(presetConfig(WorldPreset::Paper, 80, 120).steps, 120);

  // Uniform: at least the paper's 500 steps, and one lap of a larger world takes more.
  EXPECT_EQ(presetConfig(WorldPreset::Uniform, 50).steps, 500);
  const WorldConfig u = presetConfig(WorldPreset::Uniform, 5000);
  EXPECT_GT(u.steps, 10000);
  EXPECT_EQ(u.noise.sigma_range, p.noise.sigma_range);

  // Corridor: length N / (density * width); steps = length / (speed * dt).
  const WorldConfig c = presetConfig(WorldPreset::Corridor, 2000);
  const double length = 2000 / (c.density * c.corridor_width);
  EXPECT_EQ(c.steps, static_cast<int>(std::ceil(length / (c.speed * c.dt))));
}

TEST(SimConfig, InvalidConfigsThrowNamingTheField) {
  const WorldConfig good = presetConfig(WorldPreset::Paper, 10, 10);
  EXPECT_NO_THROW(simulate(good));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* field;
    void (*edit)(WorldConfig&, double);
    std::vector<double> values;
  };
  const std::vector<Case> cases = {
      {"landmarks", [](WorldConfig& c, double v) { c.landmarks = static_cast<int>(v); }, {0, -3}},
      {"steps", [](WorldConfig& c, double v) { c.steps = static_cast<int>(v); }, {0, -1}},
      {"sensor_range", [](WorldConfig& c, double v) { c.sensor_range = v; }, {0, -0.2, nan, inf}},
      {"dt", [](WorldConfig& c, double v) { c.dt = v; }, {0, -1, nan, inf, 1e-4}},
      {"speed", [](WorldConfig& c, double v) { c.speed = v; }, {0, -0.02, nan, 501}},
      {"density", [](WorldConfig& c, double v) { c.density = v; }, {0, nan}},
      {"corridor_width", [](WorldConfig& c, double v) { c.corridor_width = v; }, {0, -1}},
      {"sigma_v", [](WorldConfig& c, double v) { c.noise.sigma_v = v; }, {-0.01, nan, inf}},
      {"sigma_w", [](WorldConfig& c, double v) { c.noise.sigma_w = v; }, {-1e-9, nan}},
      {"sigma_range", [](WorldConfig& c, double v) { c.noise.sigma_range = v; }, {-1, inf}},
      {"sigma_bearing", [](WorldConfig& c, double v) { c.noise.sigma_bearing = v; }, {-1, nan}},
  };
  for (const Case& k : cases) {
    for (double v : k.values) {
      WorldConfig c = good;
      k.edit(c, v);
      try {
        simulate(c);
        ADD_FAILURE() << k.field << " = " << v << " was accepted";
      } catch (const seif::InvalidArgument& e) {
        EXPECT_NE(std::string(e.what()).find(k.field), std::string::npos) << e.what();
      }
    }
  }
  WorldConfig silent = good;  // zero noise is valid
  silent.noise = {0.0, 0.0, 0.0, 0.0};
  EXPECT_NO_THROW(simulate(silent));
}

// --- reproducibility -----------------------------------------------------------------

TEST(SimReproducibility, SameSeedGivesIdenticalLogsAndOtherSeedsDiffer) {
  for (WorldPreset p : {WorldPreset::Paper, WorldPreset::Uniform, WorldPreset::Corridor}) {
    const WorldConfig c = presetConfig(p, 200, 300, 42);
    const RobotLog a = simulate(c);
    const RobotLog b = simulate(c);
    EXPECT_TRUE(sameLog(a, b)) << seif::worldPresetName(p);
    WorldConfig other = c;
    other.seed = 43;
    const RobotLog d = simulate(other);
    EXPECT_FALSE(sameLog(a, d)) << seif::worldPresetName(p);
    EXPECT_NE(a.landmarks.begin()->second, d.landmarks.begin()->second);
    EXPECT_NE(a.groundtruth.back().pose, d.groundtruth.back().pose);
  }
}

// --- the paper's world ----------------------------------------------------------------

TEST(SimPaperWorld, HasThePaperSetupAndTheLogLayout) {
  const WorldConfig c = presetConfig(WorldPreset::Paper, 0, 0, 1);
  const RobotLog log = simulate(c);
  EXPECT_EQ(log.robot, 1);
  ASSERT_EQ(log.landmarks.size(), 50u);
  int subject = 6;
  for (const auto& [id, y] : log.landmarks) {
    EXPECT_EQ(id, subject++);
    EXPECT_TRUE(y.x() >= 0.0 && y.x() <= 1.0 && y.y() >= 0.0 && y.y() <= 1.0) << y.transpose();
  }
  ASSERT_EQ(log.odometry.size(), 501u);  // 500 controls and the final stop row
  ASSERT_EQ(log.groundtruth.size(), 501u);
  EXPECT_EQ(log.odometry.back().v, 0.0);
  EXPECT_EQ(log.odometry.back().w, 0.0);
  for (std::size_t k = 0; k < log.odometry.size(); ++k) {
    EXPECT_EQ(log.odometry[k].time, static_cast<double>(k) * c.dt);
  }
  for (std::size_t k = 0; k < log.groundtruth.size(); ++k) {
    EXPECT_EQ(log.groundtruth[k].time, static_cast<double>(k) * c.dt);
  }
  ASSERT_TRUE(log.noise.has_value());
  EXPECT_EQ(log.noise->sigma_v, c.noise.sigma_v);
  EXPECT_EQ(log.noise->sigma_bearing, c.noise.sigma_bearing);
  ASSERT_FALSE(log.measurements.empty());
  for (std::size_t i = 0; i < log.measurements.size(); ++i) {
    const auto& m = log.measurements[i];
    const std::size_t k = stepOf(m.time, c.dt);
    EXPECT_EQ(m.time, static_cast<double>(k) * c.dt);  // stamped (k + 1) dt, after the motion
    EXPECT_GE(k, 1u);
    EXPECT_LE(k, 500u);
    EXPECT_TRUE(log.landmarks.count(m.subject)) << m.subject;
    EXPECT_GT(m.bearing, -std::numbers::pi);
    EXPECT_LE(m.bearing, std::numbers::pi);
    if (i > 0) {  // sorted by time, then subject
      const auto& p = log.measurements[i - 1];
      EXPECT_TRUE(p.time < m.time || (p.time == m.time && p.subject < m.subject));
    }
  }
}

WorldConfig paperConfig(PaperPath path, std::uint64_t seed) {
  WorldConfig c = presetConfig(WorldPreset::Paper, 0, 0, seed);
  c.paper_path = path;
  return c;
}

/// Times the true robot enters the disc of radius 0.05 around `p` (after leaving it).
int visits(const RobotLog& log, const Vec2& p) {
  int count = 0;
  bool inside = false;
  for (const auto& g : log.groundtruth) {
    const bool now = (g.pose.head<2>() - p).norm() < 0.05;
    count += now && !inside;
    inside = now;
  }
  return count;
}

TEST(SimPaperWorld, TruePathStaysInsideTheSquareAndNearItsReference) {
  for (PaperPath path : {PaperPath::Lawnmower, PaperPath::Lissajous}) {
    for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u}) {
      SimStats st;
      const RobotLog log = simulate(paperConfig(path, seed), &st);
      for (const auto& g : log.groundtruth) {
        EXPECT_TRUE(g.pose.x() > 0.05 && g.pose.x() < 0.95 && g.pose.y() > 0.05 && g.pose.y() < 0.95)
            << paperPathName(path) << " seed " << seed << " t " << g.time << ": " << g.pose.transpose();
      }
      EXPECT_LT(st.max_tracking_error, 0.1) << paperPathName(path) << " seed " << seed;
      // Both revisit places: the 1.75 laps of the lawnmower loop come back to their start
      // (0.1, 0.14) once; the 1.6 laps of the 3:2 Lissajous curve pass the centre four times.
      if (path == PaperPath::Lawnmower) {
        EXPECT_EQ(visits(log, log.groundtruth.front().pose.head<2>()), 2) << "seed " << seed;
      } else {
        EXPECT_GE(visits(log, Vec2(0.5, 0.5)), 4) << "seed " << seed;
      }
    }
  }
}

TEST(SimPaperWorld, EveryLandmarkIsSeen) {
  // The paper's EKF has all 1275 links: the robot must see all 50 landmarks, on either path.
  for (PaperPath path : {PaperPath::Lawnmower, PaperPath::Lissajous}) {
    for (std::uint64_t seed = 1; seed <= 50; ++seed) {
      SimStats st;
      simulate(paperConfig(path, seed), &st);
      EXPECT_EQ(st.distinct_landmarks_seen, 50u) << paperPathName(path) << " seed " << seed;
    }
  }
}

TEST(SimPaperWorld, SeesAboutFiveLandmarksPerStep) {
  // 50 landmarks in the unit square and the annulus 0.05 < r < 0.2 give 5.9 in range away
  // from the border; the border and the blind zone's dropped noisy ranges take off about 1.
  for (PaperPath path : {PaperPath::Lawnmower, PaperPath::Lissajous}) {
    double total = 0.0;
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
      SimStats st;
      const RobotLog log = simulate(paperConfig(path, seed), &st);
      EXPECT_EQ(st.measurements, log.measurements.size());
      EXPECT_DOUBLE_EQ(st.mean_detections_per_step, log.measurements.size() / 500.0);
      EXPECT_GT(st.mean_detections_per_step, 3.5) << paperPathName(path) << " seed " << seed;
      EXPECT_LT(st.mean_detections_per_step, 7.0) << paperPathName(path) << " seed " << seed;
      total += st.mean_detections_per_step;
    }
    EXPECT_NEAR(total / 10.0, 5.0, 0.5) << paperPathName(path);
  }
}

TEST(SimPaperWorld, PathsParseAndNameEachOther) {
  for (PaperPath path : {PaperPath::Lawnmower, PaperPath::Lissajous}) {
    EXPECT_EQ(parsePaperPath(paperPathName(path)), path);
  }
  try {
    parsePaperPath("spiral");
    FAIL() << "no exception";
  } catch (const seif::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("lawnmower, lissajous"), std::string::npos) << e.what();
  }
}

TEST(SimSensor, ReportsNoRangeInsideItsBlindZone) {
  // The blind zone applies to what the sensor reports: no logged range is below min_range,
  // and the noisy ranges that fell below it were dropped and counted.
  std::size_t dropped = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SimStats st;
    const RobotLog log = simulate(presetConfig(WorldPreset::Paper, 0, 0, seed), &st);
    for (const auto& m : log.measurements) EXPECT_GE(m.range, 0.05) << "seed " << seed;
    dropped += st.ranges_below_minimum;
  }
  EXPECT_GT(dropped, 0u);
}

/// Every measurement is of a landmark within range of the true pose, and every landmark
/// within range is measured exactly once per step: the spatial index misses nothing.
/// (Without range noise, so that no detection is dropped for a non-positive noisy range.)
void expectDetectionsMatchBruteForce(WorldConfig c) {
  c.noise.sigma_range = 0.0;
  const RobotLog log = simulate(c);
  std::map<std::pair<std::size_t, int>, int> measured;
  for (const auto& m : log.measurements) {
    const std::size_t k = stepOf(m.time, c.dt);
    const Vec2 d = log.landmarks.at(m.subject) - log.groundtruth[k].pose.head<2>();
    EXPECT_LE(d.norm(), c.sensor_range);
    EXPECT_GE(d.norm(), std::max(1e-6, c.min_range));
    ++measured[{k, m.subject}];
  }
  std::size_t expected = 0;
  for (std::size_t k = 1; k < log.groundtruth.size(); ++k) {
    for (const auto& [id, y] : log.landmarks) {
      const double r = (y - log.groundtruth[k].pose.head<2>()).norm();
      if (r <= c.sensor_range && r >= std::max(1e-6, c.min_range)) {
        ++expected;
        const auto it = measured.find({k, id});
        EXPECT_TRUE(it != measured.end() && it->second == 1) << "step " << k << " subject " << id;
      }
    }
  }
  EXPECT_EQ(expected, log.measurements.size());
}

TEST(SimPaperWorld, EveryMeasurementIsWithinRangeAndNoneIsMissed) {
  expectDetectionsMatchBruteForce(presetConfig(WorldPreset::Paper, 0, 0, 3));
  expectDetectionsMatchBruteForce(presetConfig(WorldPreset::Uniform, 3000, 1500, 4));
  expectDetectionsMatchBruteForce(presetConfig(WorldPreset::Corridor, 400, 0, 5));
  WorldConfig far = presetConfig(WorldPreset::Uniform, 300, 400, 6);
  far.sensor_range = 1.5;  // a disc larger than several cells, reaching past the border
  expectDetectionsMatchBruteForce(far);
}

// --- noise ----------------------------------------------------------------------------

TEST(SimNoise, MeasurementResidualsAreStandardNormal) {
  const WorldConfig c = presetConfig(WorldPreset::Paper, 0, 2000, 11);
  const RobotLog log = simulate(c);
  std::vector<double> range, bearing, product;
  for (const auto& m : log.measurements) {
    const seif::Pose2& x = log.groundtruth[stepOf(m.time, c.dt)].pose;
    const Vec2 h = seif::RangeBearingModel(1.0, 1.0).predict(x, log.landmarks.at(m.subject));
    // Detections with a noisy range <= 0 are dropped; beyond 4 sigma that selection has
    // no measurable effect on the residuals.
    if (h.x() < 4.0 * c.noise.sigma_range) continue;
    const Vec2 e = seif::RangeBearingModel(1.0, 1.0).residual(Vec2(m.range, m.bearing), h);
    range.push_back(e.x() / c.noise.sigma_range);
    bearing.push_back(e.y() / c.noise.sigma_bearing);
    product.push_back(range.back() * bearing.back());
  }
  expectStandardNormal(range, "range residual");
  expectStandardNormal(bearing, "bearing residual");
  // Independent components: E[e_r e_b] = 0, Var = 1.
  EXPECT_LT(std::abs(moments(product).mean), kZ999 / std::sqrt(static_cast<double>(product.size())));
}

/// The control (v, w) that moves `a` to `b` in dt under the velocity model, and the
/// component of the chord across the arc's mean heading (zero if the model moved it).
struct Recovered {
  double v;
  double w;
  double across;
};

Recovered recoverControl(const seif::Pose2& a, const seif::Pose2& b, double dt) {
  const double w = seif::wrapAngle(b.z() - a.z()) / dt;
  const double mid = a.z() + 0.5 * w * dt;
  const Vec2 d = b.head<2>() - a.head<2>();
  const double along = d.x() * std::cos(mid) + d.y() * std::sin(mid);
  const double across = -d.x() * std::sin(mid) + d.y() * std::cos(mid);
  const double half = 0.5 * w * dt;
  const double sinc = std::abs(half) < 1e-8 ? 1.0 : std::sin(half) / half;
  return {along / (dt * sinc), w, across};
}

TEST(SimNoise, TrueMotionDiffersFromTheCommandByTheControlNoise) {
  const WorldConfig c = presetConfig(WorldPreset::Paper, 0, 5000, 12);
  const RobotLog log = simulate(c);
  std::vector<double> ev, ew;
  for (std::size_t k = 0; k + 1 < log.odometry.size(); ++k) {
    const Recovered r = recoverControl(log.groundtruth[k].pose, log.groundtruth[k + 1].pose, c.dt);
    EXPECT_NEAR(r.across, 0.0, 1e-12) << "step " << k;  // moved along a circular arc
    ev.push_back((r.v - log.odometry[k].v) / c.noise.sigma_v);
    ew.push_back((r.w - log.odometry[k].w) / c.noise.sigma_w);
  }
  expectStandardNormal(ev, "forward velocity noise");
  expectStandardNormal(ew, "rotational velocity noise");
}

TEST(SimNoise, WithoutNoiseTheLogIsExact) {
  WorldConfig c = presetConfig(WorldPreset::Paper, 0, 300, 13);
  c.noise = {0.0, 0.0, 0.0, 0.0};
  const RobotLog log = simulate(c);
  for (std::size_t k = 0; k + 1 < log.odometry.size(); ++k) {
    const Recovered r = recoverControl(log.groundtruth[k].pose, log.groundtruth[k + 1].pose, c.dt);
    EXPECT_NEAR(r.v, log.odometry[k].v, 1e-12);
    EXPECT_NEAR(r.w, log.odometry[k].w, 1e-12);
  }
  for (const auto& m : log.measurements) {
    const Vec2 h = seif::RangeBearingModel(1.0, 1.0).predict(log.groundtruth[stepOf(m.time, c.dt)].pose,
                                                    log.landmarks.at(m.subject));
    EXPECT_EQ(m.range, h.x());
    EXPECT_EQ(m.bearing, h.y());
  }
}

// --- the uniform world -----------------------------------------------------------------

TEST(SimUniformWorld, FiftyLandmarksLookLikeThePaperWorld) {
  const WorldConfig c = presetConfig(WorldPreset::Uniform, 50, 0, 21);
  SimStats st;
  const RobotLog log = simulate(c, &st);
  const RobotLog paper = simulate(presetConfig(WorldPreset::Paper, 0, 0, 21));
  EXPECT_EQ(log.landmarks, paper.landmarks);  // same square, same draws
  EXPECT_EQ(log.odometry.size(), 501u);
  EXPECT_EQ(c.sensor_range, 0.2);
  EXPECT_GT(st.mean_detections_per_step, 4.0);
  EXPECT_LT(st.mean_detections_per_step, 8.0);
  for (const auto& g : log.groundtruth) {
    EXPECT_TRUE(g.pose.x() > 0.0 && g.pose.x() < 1.0 && g.pose.y() > 0.0 && g.pose.y() < 1.0);
  }
}

TEST(SimUniformWorld, OneLapCoversTheSquareAndReturnsToTheStart) {
  const WorldConfig c = presetConfig(WorldPreset::Uniform, 2000, 0, 22);
  const double side = std::sqrt(2000 / c.density);
  SimStats st;
  const RobotLog log = simulate(c, &st);
  for (const auto& [id, y] : log.landmarks) {
    EXPECT_TRUE(y.x() >= 0.0 && y.x() <= side && y.y() >= 0.0 && y.y() <= side);
  }
  for (const auto& g : log.groundtruth) {
    EXPECT_TRUE(g.pose.x() > 0.0 && g.pose.x() < side && g.pose.y() > 0.0 && g.pose.y() < side);
  }
  EXPECT_GE(st.distinct_landmarks_seen, 1960u);  // >= 98 %
  EXPECT_NEAR(st.mean_detections_per_step, 6.0, 1.0);
  EXPECT_LT((log.groundtruth.back().pose.head<2>() - log.groundtruth.front().pose.head<2>()).norm(),
            c.sensor_range);
}

// --- the corridor ---------------------------------------------------------------------

TEST(SimCorridorWorld, DistinctLandmarksSeenGrowLinearly) {
  const WorldConfig c = presetConfig(WorldPreset::Corridor, 3000, 0, 31);
  SimStats st;
  const RobotLog log = simulate(c, &st);
  std::vector<int> first_seen(static_cast<std::size_t>(c.steps) + 1, 0);
  std::map<int, bool> seen;
  for (const auto& m : log.measurements) {
    if (!seen[m.subject]) {
      seen[m.subject] = true;
      ++first_seen[stepOf(m.time, c.dt)];
    }
  }
  EXPECT_GE(seen.size(), 2850u);  // passes (almost) all of them
  // Cumulative count against the straight line through the origin and the end point.
  const double rate = static_cast<double>(seen.size()) / c.steps;
  EXPECT_NEAR(rate, c.density * c.corridor_width * c.speed * c.dt, 0.1);
  double count = 0.0;
  double worst = 0.0;
  for (std::size_t k = 0; k < first_seen.size(); ++k) {
    count += first_seen[k];
    worst = std::max(worst, std::abs(count - rate * static_cast<double>(k)));
  }
  EXPECT_LT(worst, 0.03 * static_cast<double>(seen.size())) << "rate " << rate;
  EXPECT_NEAR(st.mean_detections_per_step, 6.0, 1.0);
}

TEST(SimCorridorWorld, CostPerStepIsIndependentOfTheNumberOfLandmarks) {
  SimStats small, big;
  simulate(presetConfig(WorldPreset::Corridor, 100, 0, 32), &small);
  simulate(presetConfig(WorldPreset::Corridor, 1000000, 300, 32), &big);
  ASSERT_GT(small.candidates_checked_max_per_step, 0u);
  const double ratio = static_cast<double>(big.candidates_checked_max_per_step) /
                       static_cast<double>(small.candidates_checked_max_per_step);
  EXPECT_LT(ratio, 1.5) << small.candidates_checked_max_per_step << " vs "
                        << big.candidates_checked_max_per_step;
  EXPECT_GT(ratio, 1.0 / 1.5);
  EXPECT_NEAR(big.mean_detections_per_step, small.mean_detections_per_step, 1.5);
}

TEST(SimCorridorWorld, DrivesPastAHundredThousandLandmarks) {
  const WorldConfig c = presetConfig(WorldPreset::Corridor, 100000, 0, 33);
  SimStats st;
  const RobotLog log = simulate(c, &st);
  EXPECT_EQ(log.landmarks.size(), 100000u);
  EXPECT_EQ(log.odometry.size(), static_cast<std::size_t>(c.steps) + 1);
  EXPECT_GE(st.distinct_landmarks_seen, 95000u);
  EXPECT_LT(st.candidates_checked_max_per_step, 60u);
  EXPECT_LT(st.max_tracking_error, 0.15);
  for (const auto& g : log.groundtruth) {
    ASSERT_LT(std::abs(g.pose.y()), 0.5 * c.corridor_width) << "t " << g.time;
  }
}

}  // namespace
