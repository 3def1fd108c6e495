#pragma once
// The associator's spatial index of landmark means (associator.cpp): a uniform grid with
// insert, move, remove and a disc query, each O(landmarks in the cells touched), so that the
// candidates of an observation never come from a scan of the map.
//
// Each landmark carries a spread: the standard deviation of its mean along its worst axis
// when last known (sqrt(lambda_max(Sigma_yy))). A query offers a landmark when its indexed
// mean is within `radius + scale * spread` of the point, so the box of cells a query visits
// must reach as far as the largest spread: SpreadBound keeps an upper bound of it that can
// drop when the largest goes, without allocating.
#include <seif/core/types.hpp>

#include <array>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace seif {

/// An upper bound on the largest of a changing multiset of non-negative values, at most 1/8
/// above it: a count per bucket, eight buckets per octave from 2^-40 to 2^40 (below: one
/// bucket read as 2^-40; above, or NaN: one read as infinity). O(1) to add; removing the
/// largest scans down to the next non-empty bucket. No allocation.
class SpreadBound {
 public:
  void add(double value);
  /// `value` must have been added (and not removed since).
  void remove(double value);
  /// 0 when empty.
  double max() const;

  static constexpr int kPerOctave = 8;
  static constexpr int kMinExponent = -40;
  static constexpr int kMaxExponent = 40;
  static constexpr int kBuckets = (kMaxExponent - kMinExponent) * kPerOctave + 2;
  static int bucket(double value);
  /// The bucket's upper edge: every value of the bucket is below it (or equal, at 2^-40).
  static double upperEdge(int bucket);

 private:
  std::array<std::uint32_t, kBuckets> count_{};
  int top_ = 0;  // the highest bucket that may be non-empty
};

class CandidateGrid {
 public:
  /// The cell's side; the grid is unusable (ready() false) until it is set.
  void setCell(double cell) { cell_ = cell; }
  bool ready() const { return cell_ > 0.0; }

  /// Indexes landmark `id` at `y`, or moves it there.
  void put(int id, const Vec2& y);
  /// The landmark's spread (kept until remove(), whether it is indexed or not).
  void setSpread(int id, double sigma);
  double spread(int id) const;
  void remove(int id);

  /// The ids indexed within `radius + scale * spread(id)` of `c`, ascending.
  void query(const Vec2& c, double radius, double scale, std::vector<int>& out) const;

  // For checkpoints: the cell side, every indexed position and every spread, by id.
  double cell() const { return cell_; }
  std::vector<std::pair<int, Vec2>> positions() const;
  std::vector<std::pair<int, double>> spreads() const;

 private:
  struct Entry {
    std::int64_t key;
    Vec2 y;
  };
  std::pair<std::int64_t, std::int64_t> cellOf(const Vec2& y) const;
  /// Distinct cells may share a key (cells 2^32 apart): a key's list then holds both, which
  /// only adds candidates that the exact distance test drops.
  static std::int64_t pack(std::int64_t i, std::int64_t j) {
    return static_cast<std::int64_t>((static_cast<std::uint64_t>(i) << 32) ^ (static_cast<std::uint64_t>(j) & 0xffffffffu));
  }
  std::int64_t keyOf(const Vec2& y) const;
  void erase(std::int64_t key, int id);

  double cell_ = 0.0;
  SpreadBound largest_;  // of every spread: the query's box
  std::unordered_map<std::int64_t, std::vector<int>> cells_;
  std::unordered_map<int, Entry> where_;
  std::unordered_map<int, double> spread_;
};

}  // namespace seif
