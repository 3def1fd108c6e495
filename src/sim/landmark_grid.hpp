#pragma once
// Internal to the simulator: a uniform grid over the landmarks (compressed rows, built by a
// counting sort) so that a range query touches only the cells under the sensor's disc and
// costs the same at 10^2 and 10^6 landmarks of equal density.
#include <seif/core/types.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace seif::sim {

class LandmarkGrid {
 public:
  /// Indexes `points` (all inside [lo, hi]) with square cells of side at least
  /// `min_cell`, enlarged when needed to keep the number of cells below 4 N + 64.
  LandmarkGrid(const std::vector<Vec2>& points, const Vec2& lo, const Vec2& hi,
               double min_cell);

  /// Appends to `found` the indices of the points within `radius` of `centre` (and farther
  /// than `min_distance`), in increasing index order. Returns the number of candidates
  /// whose distance was computed.
  std::size_t query(const Vec2& centre, double radius, double min_distance,
                    std::vector<std::uint32_t>& found) const;

  double cellSize() const { return cell_; }

 private:
  Vec2 lo_;
  double cell_;
  long nx_, ny_;
  std::vector<std::uint32_t> start_;  // cell c holds entries start_[c] .. start_[c+1]-1
  std::vector<Vec2> pos_;             // positions in cell order
  std::vector<std::uint32_t> index_;  // original index of each entry
};

}  // namespace seif::sim
