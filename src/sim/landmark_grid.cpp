#include "landmark_grid.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace seif::sim {

LandmarkGrid::LandmarkGrid(const std::vector<Vec2>& points, const Vec2& lo, const Vec2& hi,
                           double min_cell)
    : lo_(lo), cell_(min_cell), nx_(1), ny_(1) {
  assert(min_cell > 0.0 && points.size() < (std::size_t{1} << 32));
  const Vec2 extent = (hi - lo).cwiseMax(0.0);
  const double max_cells = 4.0 * static_cast<double>(points.size()) + 64.0;
  auto cellsAlong = [&](double len) { return std::floor(len / cell_) + 1.0; };
  while (cellsAlong(extent.x()) * cellsAlong(extent.y()) > max_cells) cell_ *= 2.0;
  nx_ = static_cast<long>(cellsAlong(extent.x()));
  ny_ = static_cast<long>(cellsAlong(extent.y()));

  auto cellOf = [&](const Vec2& p) {
    const long ix = std::clamp(static_cast<long>(std::floor((p.x() - lo_.x()) / cell_)), 0L, nx_ - 1);
    const long iy = std::clamp(static_cast<long>(std::floor((p.y() - lo_.y()) / cell_)), 0L, ny_ - 1);
    return static_cast<std::size_t>(iy * nx_ + ix);
  };
  // Counting sort by cell (stable, so each cell lists its points in increasing index).
  start_.assign(static_cast<std::size_t>(nx_ * ny_) + 1, 0);
  std::vector<std::uint32_t> cell(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    cell[i] = static_cast<std::uint32_t>(cellOf(points[i]));
    ++start_[cell[i] + 1];
  }
  for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
  pos_.resize(points.size());
  index_.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::uint32_t k = next[cell[i]]++;
    pos_[k] = points[i];
    index_[k] = static_cast<std::uint32_t>(i);
  }
}

std::size_t LandmarkGrid::query(const Vec2& centre, double radius, double min_distance,
                                std::vector<std::uint32_t>& found) const {
  const double fx0 = std::floor((centre.x() - radius - lo_.x()) / cell_);
  const double fx1 = std::floor((centre.x() + radius - lo_.x()) / cell_);
  const double fy0 = std::floor((centre.y() - radius - lo_.y()) / cell_);
  const double fy1 = std::floor((centre.y() + radius - lo_.y()) / cell_);
  if (!(fx1 >= 0.0 && fy1 >= 0.0 && fx0 < static_cast<double>(nx_) &&
        fy0 < static_cast<double>(ny_))) {
    return 0;  // the disc misses the grid (or the centre is not finite)
  }
  // Clamp in floating point first: casting an out-of-range double to long is undefined.
  const long ix0 = static_cast<long>(std::max(fx0, 0.0));
  const long ix1 = static_cast<long>(std::min(fx1, static_cast<double>(nx_ - 1)));
  const long iy0 = static_cast<long>(std::max(fy0, 0.0));
  const long iy1 = static_cast<long>(std::min(fy1, static_cast<double>(ny_ - 1)));
  const double r2 = radius * radius;
  const double min2 = min_distance * min_distance;
  const std::size_t first = found.size();
  std::size_t checked = 0;
  for (long iy = iy0; iy <= iy1; ++iy) {
    // Cells of one row are contiguous: one run of entries.
    const std::uint32_t b = start_[static_cast<std::size_t>(iy * nx_ + ix0)];
    const std::uint32_t e = start_[static_cast<std::size_t>(iy * nx_ + ix1) + 1];
    checked += e - b;
    for (std::uint32_t k = b; k < e; ++k) {
      const double q = (pos_[k] - centre).squaredNorm();
      if (q <= r2 && q >= min2) found.push_back(index_[k]);
    }
  }
  std::sort(found.begin() + static_cast<std::ptrdiff_t>(first), found.end());
  return checked;
}

}  // namespace seif::sim
