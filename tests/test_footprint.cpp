// The track score's sensor footprint (src/association/footprint.hpp): per axis, the
// single-linkage clusters of the values seen, whatever their order, and their hull; a bearing
// wraps with the model's period; an outlier adds no volume; the state round-trips and damage
// is refused.
#include "association/footprint.hpp"
#include "core/binary_archive.hpp"

#include <seif/core/errors.hpp>
#include <seif/models/cartesian.hpp>
#include <seif/models/range_bearing.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace seif {
namespace {

constexpr double kPi = std::numbers::pi;

/// Single linkage by sorting: consecutive values at most `gap` apart share an interval.
std::vector<SensorFootprint::Interval> linked(std::vector<double> v, double gap) {
  std::sort(v.begin(), v.end());
  std::vector<SensorFootprint::Interval> out;
  for (double x : v) {
    if (!out.empty() && x - out.back().hi <= gap) {
      out.back().hi = x;
    } else {
      out.push_back({x, x});
    }
  }
  return out;
}

TEST(SensorFootprint, ClustersAreTheSingleLinkageOfTheValuesInAnyOrderAndTheHullSpansThem) {
  // A Cartesian sensor (no wrap), sigma 0.1 and 0.3: gaps of 1 and 3. Values in clusters
  // with gaps around the threshold, inserted in random orders.
  const CartesianModel sensor(Vec2(0.01, 0.09).asDiagonal());
  const double gap[2] = {kFootprintGapSigmas * 0.1, kFootprintGapSigmas * 0.3};
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<Vec2> z;
    std::uniform_real_distribution<double> cluster(0.0, 40.0), within(-1.0, 1.0);
    for (int c = 0; c < 6; ++c) {
      const Vec2 centre(cluster(rng), 3.0 * cluster(rng));
      for (int i = 0; i < 8; ++i) z.push_back(centre + Vec2(within(rng), 3.0 * within(rng)));
    }
    std::shuffle(z.begin(), z.end(), rng);
    SensorFootprint f;
    for (const Vec2& v : z) f.add(sensor, v);
    double volume = 1.0;
    for (int k = 0; k < 2; ++k) {
      std::vector<double> offsets;
      for (const Vec2& v : z) offsets.push_back(v[k] - z.front()[k]);  // offsets from the first
      const auto expected = linked(offsets, gap[k]);
      const auto& got = f.clusters(k);
      ASSERT_EQ(got.size(), expected.size()) << trial << " axis " << k;
      std::size_t values = 0;
      for (std::size_t i = 0; i < got.size(); ++i) {
        EXPECT_DOUBLE_EQ(got[i].span.lo, expected[i].lo) << trial;
        EXPECT_DOUBLE_EQ(got[i].span.hi, expected[i].hi) << trial;
        EXPECT_EQ(got[i].values, static_cast<std::size_t>(std::count_if(offsets.begin(), offsets.end(), [&](double x) {
                                   return x >= expected[i].lo && x <= expected[i].hi;
                                 })));
        values += got[i].values;
      }
      EXPECT_EQ(values, z.size());
      // Every cluster holds more than 1 % of 48 values: the hull spans them all.
      ASSERT_EQ(f.hull(k).size(), 1u);
      EXPECT_EQ(f.hull(k)[0].lo, expected.front().lo);
      EXPECT_EQ(f.hull(k)[0].hi, expected.back().hi);
      volume *= expected.back().hi - expected.front().lo;
    }
    EXPECT_NEAR(f.volume(), volume, 1e-9 * volume);
    // Every value seen is inside, and so is a point in a gap between clusters (landmarks
    // are sparse, the sensor is not); a point beyond the hull is not.
    for (const Vec2& v : z) EXPECT_TRUE(f.contains(sensor, v));
    const auto& xs = f.clusters(0);
    for (std::size_t i = 0; i + 1 < xs.size(); ++i) {
      const Vec2 between(z.front()[0] + 0.5 * (xs[i].span.hi + xs[i + 1].span.lo), z.front()[1]);
      EXPECT_TRUE(f.contains(sensor, between)) << trial;
    }
    EXPECT_FALSE(f.contains(sensor, Vec2(z.front()[0] + xs.back().span.hi + 0.01, z.front()[1])));
  }
}

TEST(SensorFootprint, AFieldOfViewAcrossTheBearingPiIsOneSectorBehindTheSensor) {
  // A rear-facing range-bearing sensor (sigma_bearing 0.01: gap 0.1 rad) seeing bearings
  // within 0.4 rad of pi, at 2-10 m. Its footprint is that sector: not the front, and its
  // volume is about 8 m x 0.8 rad, where a box of the values would span the whole turn.
  const RangeBearingModel sensor(0.05, 0.01);
  SensorFootprint f;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> range(2.0, 10.0), off(-0.4, 0.4);
  Vec2 lo = Vec2::Constant(1e9), hi = Vec2::Constant(-1e9);
  for (int i = 0; i < 400; ++i) {
    const double b = std::remainder(kPi + off(rng), 2.0 * kPi);
    const Vec2 z(range(rng), b);
    f.add(sensor, z);
    lo = lo.cwiseMin(z);
    hi = hi.cwiseMax(z);
  }
  EXPECT_GT(hi[1] - lo[1], 6.0);  // the box's bearing extent: nearly the whole turn
  EXPECT_EQ(f.clusters(1).size(), 1u) << "one cluster, across the wrap";
  EXPECT_NEAR(f.volume(), 8.0 * 0.8, 0.3);
  EXPECT_TRUE(f.contains(sensor, Vec2(5.0, kPi)));
  EXPECT_TRUE(f.contains(sensor, Vec2(5.0, -kPi + 0.2)));
  EXPECT_FALSE(f.contains(sensor, Vec2(5.0, 0.0)));  // in front: never seen
  EXPECT_FALSE(f.contains(sensor, Vec2(5.0, 1.5)));
  EXPECT_FALSE(f.contains(sensor, Vec2(15.0, kPi)));  // beyond the ranges seen
}

TEST(SensorFootprint, ABlindSectorStaysOutOfTheHull) {
  // A sensor that sees all round but the sector (0.5, 1.5) rad, its first value at bearing 0:
  // the largest empty arc lies inside the offsets, so the hull is two intervals (a box of the
  // values would be the whole turn).
  const RangeBearingModel sensor(0.1, 0.01);
  SensorFootprint f;
  f.add(sensor, Vec2(5.0, 0.0));
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> range(1.0, 9.0), bearing(1.5, 0.5 + 2.0 * kPi);
  for (int i = 0; i < 2000; ++i) f.add(sensor, Vec2(range(rng), std::remainder(bearing(rng), 2.0 * kPi)));
  ASSERT_EQ(f.hull(1).size(), 2u);
  EXPECT_NEAR(f.volume(), 8.0 * (2.0 * kPi - 1.0), 0.2);
  EXPECT_FALSE(f.contains(sensor, Vec2(5.0, 1.0)));
  EXPECT_TRUE(f.contains(sensor, Vec2(5.0, 0.4)));
  EXPECT_TRUE(f.contains(sensor, Vec2(5.0, 1.6)));
  EXPECT_TRUE(f.contains(sensor, Vec2(5.0, kPi)));
  EXPECT_TRUE(f.contains(sensor, Vec2(5.0, -3.0)));
}

TEST(SensorFootprint, AnOutlyingRangeAddsNoVolumeAndNoReach) {
  // A forward sensor (sigma_range 0.5: gap 5 m) seeing 1-30 m; one detection at 80 m.
  const RangeBearingModel sensor(0.5, 0.02);
  SensorFootprint f;
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> range(1.0, 30.0), bearing(-1.5, 1.5);
  for (int i = 0; i < 300; ++i) f.add(sensor, Vec2(range(rng), bearing(rng)));
  const double before = f.volume();
  EXPECT_GT(before, 0.9 * 29.0 * 3.0);
  f.add(sensor, Vec2(80.0, 0.3));
  EXPECT_EQ(f.volume(), before);
  EXPECT_EQ(f.clusters(0).size(), 2u);
  EXPECT_TRUE(f.contains(sensor, Vec2(20.0, 0.3)));
  EXPECT_FALSE(f.contains(sensor, Vec2(50.0, 0.3)));  // a box would reach here
  EXPECT_FALSE(f.contains(sensor, Vec2(20.0, 2.5)));  // behind the field of view

  // Among the first few values an outlier holds more than 1 % of them, and is in the hull
  // until the others outnumber it a hundred to one.
  SensorFootprint early;
  early.add(sensor, Vec2(80.0, 0.3));
  int n = 0;
  for (; n < 99; ++n) early.add(sensor, Vec2(range(rng), bearing(rng)));
  EXPECT_TRUE(early.contains(sensor, Vec2(50.0, 0.3)));
  early.add(sensor, Vec2(range(rng), bearing(rng)));
  EXPECT_FALSE(early.contains(sensor, Vec2(50.0, 0.3)));
}

TEST(SensorFootprint, AValueBetweenClustersJoinsThem) {
  const CartesianModel sensor(Vec2(0.01, 0.01).asDiagonal());  // gap 1 on both axes
  SensorFootprint f;
  for (double x : {0.0, 1.8, 3.6, 5.4}) f.add(sensor, Vec2(x, 0.0));
  ASSERT_EQ(f.clusters(0).size(), 4u);
  f.add(sensor, Vec2(0.9, 0.0));  // within 1 of 0 and of 1.8: those two join
  EXPECT_EQ(f.clusters(0).size(), 3u);
  EXPECT_EQ(f.clusters(0)[0].values, 3u);
  f.add(sensor, Vec2(2.7, 0.0));
  f.add(sensor, Vec2(4.5, 0.0));  // now one cluster from 0 to 5.4
  ASSERT_EQ(f.clusters(0).size(), 1u);
  EXPECT_DOUBLE_EQ(f.clusters(0)[0].span.lo, 0.0);
  EXPECT_DOUBLE_EQ(f.clusters(0)[0].span.hi, 5.4);
  EXPECT_EQ(f.clusters(0)[0].values, 7u);
  EXPECT_EQ(f.volume(), 0.0);  // the second axis has seen one value only
}

TEST(SensorFootprint, AVersionTwoBoxHoldsWhatTheBoxHeld) {
  // The associator's state version 2 kept a box; restored, the footprint contains the same
  // points, the whole turn of bearing included.
  const RangeBearingModel sensor(0.5, 0.03);
  const SensorFootprint f = SensorFootprint::fromBox(Vec2(1.0, -kPi), Vec2(31.0, kPi));
  EXPECT_NEAR(f.volume(), 30.0 * 2.0 * kPi, 1e-9);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> range(0.0, 40.0), bearing(-kPi, kPi);
  for (int i = 0; i < 1000; ++i) {
    const Vec2 z(range(rng), bearing(rng));
    EXPECT_EQ(f.contains(sensor, z), z[0] >= 1.0 && z[0] <= 31.0) << z.transpose();
  }
  const SensorFootprint g = SensorFootprint::fromBox(Vec2(1.0, -0.5), Vec2(9.0, 0.7));
  for (int i = 0; i < 1000; ++i) {
    const Vec2 z(range(rng), bearing(rng));
    EXPECT_EQ(g.contains(sensor, z), z[0] >= 1.0 && z[0] <= 9.0 && z[1] >= -0.5 && z[1] <= 0.7) << z.transpose();
  }
  EXPECT_TRUE(SensorFootprint::fromBox(Vec2::Constant(INFINITY), Vec2::Constant(-INFINITY)).empty());
}

TEST(SensorFootprint, RoundTripsAndRefusesIntervalsOutOfOrder) {
  const RangeBearingModel sensor(0.5, 0.03);
  SensorFootprint f;
  for (double r : {1.0, 3.0, 20.0, 60.0}) f.add(sensor, Vec2(r, 0.1 * r));
  ArchiveWriter w;
  f.save(w);
  const std::string bytes = w.bytes();
  ArchiveReader r(bytes, "footprint");
  const SensorFootprint g = SensorFootprint::restore(r);
  r.finish();
  ArchiveWriter w2;
  g.save(w2);
  EXPECT_TRUE(w2.bytes() == bytes);
  EXPECT_EQ(g.volume(), f.volume());

  // Intervals that overlap, are reversed or not finite: refused, naming the footprint.
  for (const auto& bad : std::vector<std::vector<double>>{{0.0, 2.0, 1.0, 3.0}, {2.0, 1.0}, {0.0, NAN}}) {
    ArchiveWriter b;
    b.u64(1);
    b.fixed(Vec2(1.0, 0.0));
    b.f64(0.0);  // period
    b.count(bad.size() / 2);
    for (std::size_t i = 0; i < bad.size(); i += 2) {
      b.f64(bad[i]);
      b.f64(bad[i + 1]);
      b.u64(3);
    }
    b.f64(2.0 * kPi);
    b.count(1);
    b.f64(0.0);
    b.f64(1.0);
    b.u64(3);
    const std::string damaged = b.bytes();
    ArchiveReader rb(damaged, "damaged");
    try {
      (void)SensorFootprint::restore(rb);
      ADD_FAILURE() << "accepted";
    } catch (const DataError& e) {
      EXPECT_NE(std::string(e.what()).find("footprint"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace seif
