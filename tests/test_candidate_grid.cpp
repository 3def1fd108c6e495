// The associator's index of landmark means (src/association/candidate_grid.hpp): what a
// query offers equals the brute-force disc test over every landmark, whatever the spreads
// and their changes; the bound on the largest spread stays above it and close to it.
#include "association/candidate_grid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <vector>

namespace seif {
namespace {

TEST(SpreadBound, StaysAboveTheLargestAndWithinAnEighthOfIt) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> exponent(-30.0, 30.0);
  SpreadBound bound;
  EXPECT_EQ(bound.max(), 0.0);
  std::multiset<double> values;
  for (int k = 0; k < 5000; ++k) {
    if (values.empty() || rng() % 3 != 0) {
      const double v = std::exp2(exponent(rng));
      bound.add(v);
      values.insert(v);
    } else {  // remove one, the largest one time in four
      auto it = rng() % 4 == 0 ? std::prev(values.end()) : std::next(values.begin(), rng() % values.size());
      bound.remove(*it);
      values.erase(it);
    }
    const double largest = values.empty() ? 0.0 : *values.rbegin();
    ASSERT_GE(bound.max(), largest) << k;
    ASSERT_LE(bound.max(), largest * (1.0 + 1.0 / SpreadBound::kPerOctave)) << k;
  }
  while (!values.empty()) {
    bound.remove(*values.begin());
    values.erase(values.begin());
  }
  EXPECT_EQ(bound.max(), 0.0);
}

TEST(SpreadBound, ItsBucketsCoverEveryValue) {
  // Each value lies in its bucket: below the bucket's upper edge, at or above the one before.
  for (double v : {0x1p-40, 0x1p-39, 0.3, 0.5, 0.9999, 1.0, 1.0625, 1.125, 3.0, 1e6, 0x1p39, 0x1.fffffp39}) {
    const int b = SpreadBound::bucket(v);
    EXPECT_LT(v, SpreadBound::upperEdge(b)) << v;
    EXPECT_GE(v, SpreadBound::upperEdge(b - 1)) << v;
  }
  // Out of range: zero and the tiny are read as 2^-40, the huge, infinity and NaN as infinity.
  EXPECT_EQ(SpreadBound::upperEdge(SpreadBound::bucket(0.0)), 0x1p-40);
  EXPECT_EQ(SpreadBound::upperEdge(SpreadBound::bucket(1e-300)), 0x1p-40);
  for (double v : {0x1p40, 1e300, std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    EXPECT_EQ(SpreadBound::upperEdge(SpreadBound::bucket(v)), std::numeric_limits<double>::infinity()) << v;
  }
}

TEST(CandidateGrid, AQueryOffersExactlyWhatTheDiscTestOverEveryLandmarkOffers) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coordinate(-50.0, 50.0), unit(0.0, 1.0);
  CandidateGrid grid;
  grid.setCell(4.0);
  std::map<int, Vec2> where;
  std::map<int, double> spread;
  std::vector<int> out;
  for (int k = 0; k < 3000; ++k) {
    const int id = static_cast<int>(rng() % 300);
    const double u = unit(rng);
    if (u < 0.45) {  // index or move, near or far
      const Vec2 y = where.count(id) && u < 0.2 ? Vec2(where[id] + Vec2(0.3, -0.2)) : Vec2(coordinate(rng), coordinate(rng));
      grid.put(id, y);
      where[id] = y;
    } else if (u < 0.8) {  // a spread: mostly small, sometimes one far larger than the map
      const double s = u < 0.78 ? 2.0 * unit(rng) : 500.0 * unit(rng);
      grid.setSpread(id, s);
      spread[id] = s;
    } else if (u < 0.9) {
      grid.remove(id);
      where.erase(id);
      spread.erase(id);
    } else {
      const Vec2 c(coordinate(rng), coordinate(rng));
      const double radius = 5.0 * unit(rng), scale = 3.0 * unit(rng);
      grid.query(c, radius, scale, out);
      std::vector<int> expected;
      for (const auto& [i, y] : where) {
        const double r = radius + scale * (spread.count(i) ? spread[i] : 0.0);
        if ((y - c).squaredNorm() <= r * r) expected.push_back(i);
      }
      ASSERT_EQ(out, expected) << "operation " << k;
    }
  }
}

TEST(CandidateGrid, MeansAndReachesFarBeyondTheGridStayExact) {
  // Cell indices beyond 2^52 are clamped and keys 2^32 cells apart may share a list: the
  // exact distance test still decides (UBSan checks the conversions in the sanitizer build).
  CandidateGrid grid;
  grid.setCell(0.5);
  grid.put(1, Vec2(1e300, -1e300));
  grid.put(2, Vec2(0.0, 0.0));
  grid.put(3, Vec2(0.5 * 0x1p32, 0.0));  // its cell's key is cell 0's
  grid.setSpread(1, 1e10);
  std::vector<int> out;
  grid.query(Vec2(1e300, -1e300), 1.0, 0.0, out);
  EXPECT_EQ(out, std::vector<int>{1});
  grid.query(Vec2(0.1, 0.0), 1.0, 0.0, out);
  EXPECT_EQ(out, std::vector<int>{2});
  grid.query(Vec2(0.5 * 0x1p32, 0.1), 1.0, 0.0, out);
  EXPECT_EQ(out, std::vector<int>{3});
  grid.setSpread(2, std::numeric_limits<double>::infinity());  // a reach of infinity: every cell
  grid.query(Vec2(5.0, 5.0), 1.0, 1.0, out);
  EXPECT_EQ(out, std::vector<int>{2});
}

TEST(CandidateGrid, ASpreadThatIsNotANumberOffersNothingAndHidesNothing) {
  CandidateGrid grid;
  grid.setCell(1.0);
  grid.put(1, Vec2(0.0, 0.0));
  grid.put(2, Vec2(0.5, 0.0));
  grid.setSpread(1, std::numeric_limits<double>::quiet_NaN());
  std::vector<int> out;
  grid.query(Vec2(0.6, 0.0), 0.2, 1.0, out);
  EXPECT_EQ(out, std::vector<int>{2});
}

}  // namespace
}  // namespace seif
