// The sensor's footprint (footprint.hpp): per axis, clusters of values by single linkage,
// and their hull without the outliers.
#include "association/footprint.hpp"

#include "core/binary_archive.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace seif {

void SensorFootprint::Axis::add(double v, double gap) {
  ++values;
  // The first cluster that ends within a gap below v, or after it.
  auto it = std::lower_bound(clusters.begin(), clusters.end(), v - gap,
                             [](const Cluster& c, double x) { return c.span.hi < x; });
  if (it == clusters.end() || it->span.lo > v + gap) {
    clusters.insert(it, Cluster{{v, v}, 1});
    return;
  }
  it->span.lo = std::min(it->span.lo, v);
  it->span.hi = std::max(it->span.hi, v);
  ++it->values;
  // The clusters after it that now lie within a gap of it join it.
  auto last = std::next(it);
  for (; last != clusters.end() && last->span.lo <= it->span.hi + gap; ++last) {
    it->span.hi = std::max(it->span.hi, last->span.hi);
    it->values += last->values;
  }
  clusters.erase(std::next(it), last);
}

void SensorFootprint::Axis::updateHull() {
  hull.clear();
  if (clusters.empty()) return;
  // The clusters of the hull: those holding kFootprintOutlierFraction of the values, or all
  // of them where none does.
  const double least = kFootprintOutlierFraction * static_cast<double>(values);
  const bool any = std::any_of(clusters.begin(), clusters.end(), [&](const Cluster& c) { return static_cast<double>(c.values) >= least; });
  const auto kept = [&](const Cluster& c) { return !any || static_cast<double>(c.values) >= least; };
  const Cluster* first = nullptr;
  const Cluster* last = nullptr;
  // On a periodic axis, the largest empty arc between two kept clusters (none: widest < 0).
  double widest = -1.0;
  Interval around{};
  for (const Cluster& c : clusters) {
    if (!kept(c)) continue;
    if (last != nullptr && c.span.lo - last->span.hi > widest) {
      widest = c.span.lo - last->span.hi;
      around = {last->span.hi, c.span.lo};
    }
    if (first == nullptr) first = &c;
    last = &c;
  }
  const Interval whole{first->span.lo, last->span.hi};
  // The arc across the wrap, from the highest kept cluster round to the lowest.
  if (period <= 0.0 || widest < 0.0 || first->span.lo + period - last->span.hi >= widest) {
    hull.push_back(whole);
  } else {
    hull.push_back({-0.5 * period, around.lo});
    hull.push_back({around.hi, 0.5 * period});
  }
}

void SensorFootprint::add(const MeasurementModel& sensor, const Vec2& z) {
  if (!origin_) {
    origin_ = z;
    for (int k = 0; k < 2; ++k) axes_[static_cast<std::size_t>(k)].period = sensor.period()[k];
  }
  const Vec2 t = sensor.residual(z, *origin_);
  for (int k = 0; k < 2; ++k) {
    Axis& axis = axes_[static_cast<std::size_t>(k)];
    axis.add(t[k], kFootprintGapSigmas * std::sqrt(sensor.noise()(k, k)));
    axis.updateHull();
  }
}

bool SensorFootprint::contains(const MeasurementModel& sensor, const Vec2& z) const {
  if (!origin_) return false;
  const Vec2 t = sensor.residual(z, *origin_);
  for (int k = 0; k < 2; ++k) {
    const std::vector<Interval>& h = axes_[static_cast<std::size_t>(k)].hull;
    if (std::none_of(h.begin(), h.end(), [&](const Interval& i) { return i.lo <= t[k] && t[k] <= i.hi; })) return false;
  }
  return true;
}

double SensorFootprint::volume() const {
  double v = 1.0;
  for (const Axis& axis : axes_) {
    double length = 0.0;
    for (const Interval& i : axis.hull) length += i.hi - i.lo;
    v *= length;
  }
  return v;
}

void SensorFootprint::save(ArchiveWriter& w) const {
  w.u64(origin_ ? 1 : 0);
  if (!origin_) return;
  w.fixed(*origin_);
  for (const Axis& axis : axes_) {
    w.f64(axis.period);
    w.count(axis.clusters.size());
    for (const Cluster& c : axis.clusters) {
      w.f64(c.span.lo);
      w.f64(c.span.hi);
      w.u64(c.values);
    }
  }
}

SensorFootprint SensorFootprint::restore(ArchiveReader& r) {
  SensorFootprint f;
  if (r.u64Max("footprint", 1) == 0) return f;
  Vec2 origin;
  r.fixed("footprint origin", origin, true);
  f.origin_ = origin;
  for (std::size_t k = 0; k < 2; ++k) {
    Axis& axis = f.axes_[k];
    axis.period = r.f64("footprint period");
    if (!(axis.period >= 0.0) || !std::isfinite(axis.period)) r.fail("the sensor footprint's period is not a length");
    const std::size_t n = r.count("footprint clusters", 3 * 9);
    if (n == 0) r.fail("the sensor's footprint has an axis without clusters");
    axis.clusters.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      Cluster c;
      c.span.lo = r.f64("footprint cluster");
      c.span.hi = r.f64("footprint cluster");
      c.values = static_cast<std::size_t>(r.u64("footprint cluster's values"));
      if (!std::isfinite(c.span.lo) || !std::isfinite(c.span.hi) || c.span.lo > c.span.hi || c.values == 0 ||
          (!axis.clusters.empty() && c.span.lo <= axis.clusters.back().span.hi)) {
        r.fail("the sensor's footprint along axis " + std::to_string(k) + " is not finite, ordered, disjoint clusters");
      }
      axis.values += c.values;
      axis.clusters.push_back(c);
    }
    axis.updateHull();
  }
  return f;
}

SensorFootprint SensorFootprint::fromBox(const Vec2& lo, const Vec2& hi) {
  SensorFootprint f;
  if ((lo.array() > hi.array()).any()) return f;
  const Vec2 centre = 0.5 * (lo + hi);
  f.origin_ = centre;
  for (int k = 0; k < 2; ++k) {
    const double half = 0.5 * (hi[k] - lo[k]);
    Axis& axis = f.axes_[static_cast<std::size_t>(k)];
    axis.clusters.push_back(Cluster{{-half, half}, 1});
    axis.values = 1;
    axis.updateHull();
  }
  return f;
}

}  // namespace seif
