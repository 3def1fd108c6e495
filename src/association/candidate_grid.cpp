#include "association/candidate_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace seif {

int SpreadBound::bucket(double value) {
  if (std::isnan(value) || value >= std::ldexp(1.0, kMaxExponent)) return kBuckets - 1;
  if (!(value >= std::ldexp(1.0, kMinExponent))) return 0;
  int e = 0;
  const double f = std::frexp(value, &e);  // value = f 2^e, f in [0.5, 1)
  const int sub = std::min(kPerOctave - 1, static_cast<int>((f - 0.5) * 2.0 * kPerOctave));
  return 1 + (e - 1 - kMinExponent) * kPerOctave + sub;
}

double SpreadBound::upperEdge(int bucket) {
  if (bucket <= 0) return std::ldexp(1.0, kMinExponent);
  if (bucket >= kBuckets - 1) return std::numeric_limits<double>::infinity();
  const int e = (bucket - 1) / kPerOctave + kMinExponent + 1, sub = (bucket - 1) % kPerOctave;
  return std::ldexp(0.5 + 0.5 * static_cast<double>(sub + 1) / kPerOctave, e);
}

void SpreadBound::add(double value) {
  const int b = bucket(value);
  ++count_[static_cast<std::size_t>(b)];
  top_ = std::max(top_, b);
}

void SpreadBound::remove(double value) {
  --count_[static_cast<std::size_t>(bucket(value))];
  while (top_ > 0 && count_[static_cast<std::size_t>(top_)] == 0) --top_;
}

double SpreadBound::max() const {
  return count_[static_cast<std::size_t>(top_)] == 0 ? 0.0 : upperEdge(top_);
}

std::pair<std::int64_t, std::int64_t> CandidateGrid::cellOf(const Vec2& y) const {
  // Clamped (monotone, so a box still contains every cell it did): a mean or a reach beyond
  // 2^52 cells, or not a number, never reaches an integer conversion out of range.
  constexpr double kFar = 0x1p52;
  const auto index = [this](double x) {
    double v = std::floor(x / cell_);
    if (!(v > -kFar)) v = -kFar;
    if (!(v < kFar)) v = kFar;
    return static_cast<std::int64_t>(v);
  };
  return {index(y.x()), index(y.y())};
}

std::int64_t CandidateGrid::keyOf(const Vec2& y) const {
  const auto [i, j] = cellOf(y);
  return pack(i, j);
}

void CandidateGrid::erase(std::int64_t key, int id) {
  auto& v = cells_[key];
  v.erase(std::find(v.begin(), v.end(), id));
  if (v.empty()) cells_.erase(key);
}

void CandidateGrid::put(int id, const Vec2& y) {
  const auto it = where_.find(id);
  const std::int64_t key = keyOf(y);
  if (it != where_.end()) {
    if (it->second.key != key) {
      erase(it->second.key, id);
      cells_[key].push_back(id);
      it->second.key = key;
    }
    it->second.y = y;
    return;
  }
  cells_[key].push_back(id);
  where_[id] = {key, y};
}

void CandidateGrid::setSpread(int id, double sigma) {
  const auto [it, added] = spread_.try_emplace(id, sigma);
  if (!added) {
    largest_.remove(it->second);
    it->second = sigma;
  }
  largest_.add(sigma);
}

double CandidateGrid::spread(int id) const {
  const auto it = spread_.find(id);
  return it != spread_.end() ? it->second : 0.0;
}

void CandidateGrid::remove(int id) {
  if (const auto sp = spread_.find(id); sp != spread_.end()) {
    largest_.remove(sp->second);
    spread_.erase(sp);
  }
  const auto it = where_.find(id);
  if (it == where_.end()) return;
  erase(it->second.key, id);
  where_.erase(it);
}

void CandidateGrid::query(const Vec2& c, double radius, double scale, std::vector<int>& out) const {
  out.clear();
  const double reach = radius + scale * largest_.max();
  const auto take = [&](const std::vector<int>& cell) {
    for (int id : cell) {
      const double r = radius + scale * spread(id);
      if ((where_.at(id).y - c).squaredNorm() <= r * r) out.push_back(id);
    }
  };
  // The box's cells per axis, in doubles (a reach wider than the map's coordinates never
  // reaches an integer conversion).
  const auto cells = [&](double x) { return std::floor((x + reach) / cell_) - std::floor((x - reach) / cell_) + 1.0; };
  const double box = cells(c.x()) * cells(c.y());
  if (!(box <= static_cast<double>(cells_.size()))) {  // a reach wider than the map: its occupied cells
    for (const auto& [key, cell] : cells_) take(cell);
  } else {
    const auto lo = cellOf(c - Vec2::Constant(reach)), hi = cellOf(c + Vec2::Constant(reach));
    for (std::int64_t i = lo.first; i <= hi.first; ++i) {
      for (std::int64_t j = lo.second; j <= hi.second; ++j) {
        if (const auto it = cells_.find(pack(i, j)); it != cells_.end()) take(it->second);
      }
    }
  }
  std::sort(out.begin(), out.end());
}

std::vector<std::pair<int, Vec2>> CandidateGrid::positions() const {
  std::vector<std::pair<int, Vec2>> out;
  out.reserve(where_.size());
  for (const auto& [id, e] : where_) out.emplace_back(id, e.y);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

std::vector<std::pair<int, double>> CandidateGrid::spreads() const {
  std::vector<std::pair<int, double>> out(spread_.begin(), spread_.end());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace seif
