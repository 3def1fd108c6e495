#pragma once
// The sensor's footprint for the track score (ConfirmRule::Score; docs/association.md): where
// in measurement space the sensor reports. It decides which provisional landmarks a scan
// missed (log(1 - P_D) each) and the volume the clutter density is spread over.
//
// Per axis of the measurement, each value is taken as its offset residual(z, origin) from the
// first observation, so an axis wraps where the model's residual wraps it (a bearing). The
// values so far are kept as clusters: those nearer each other than kFootprintGapSigmas of the
// sensor's default noise along the axis join one (single linkage), which counts its values.
// The footprint along the axis is the hull of the clusters holding at least
// kFootprintOutlierFraction of the values:
//   - on an axis without a period, from the lowest cluster to the highest: holes between
//     landmarks are in view, and one outlying range adds nothing;
//   - on a periodic axis (model.period()), the circle without its largest empty arc: a field
//     of view across the bearing +-pi is one sector, and the sector behind it stays out.
#include <seif/core/types.hpp>
#include <seif/models/measurement_model.hpp>

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

namespace seif {

class ArchiveWriter;
class ArchiveReader;

/// Values nearer than this many standard deviations of the sensor's noise along an axis join
/// one cluster.
inline constexpr double kFootprintGapSigmas = 10.0;
/// A cluster holding fewer than this share of the values is an outlier, out of the hull.
inline constexpr double kFootprintOutlierFraction = 0.01;

class SensorFootprint {
 public:
  struct Interval {
    double lo = 0.0, hi = 0.0;  // offsets from the origin, lo <= hi
  };
  struct Cluster {
    Interval span;
    std::size_t values = 0;
  };

  bool empty() const { return !origin_; }
  /// Grows the footprint by the measurement z.
  void add(const MeasurementModel& sensor, const Vec2& z);
  /// Whether z lies in the footprint (on every axis, inside its hull).
  bool contains(const MeasurementModel& sensor, const Vec2& z) const;
  /// The product over the axes of the length of their hulls (0 while one is a point).
  double volume() const;
  /// Axis k's clusters, ordered, and its hull: one interval, or two on a periodic axis
  /// whose hull crosses the wrap (up to +period/2 and from -period/2).
  const std::vector<Cluster>& clusters(int k) const { return axes_[static_cast<std::size_t>(k)].clusters; }
  const std::vector<Interval>& hull(int k) const { return axes_[static_cast<std::size_t>(k)].hull; }

  void save(ArchiveWriter& w) const;
  /// Throws DataError (through r) for clusters that are not finite, ordered and disjoint.
  static SensorFootprint restore(ArchiveReader& r);
  /// The footprint of the associator's state version 2, a box [lo, hi] (lo > hi: empty),
  /// held as one cluster per axis about the box's centre, without a period.
  static SensorFootprint fromBox(const Vec2& lo, const Vec2& hi);

 private:
  struct Axis {
    double period = 0.0;
    std::vector<Cluster> clusters;  // sorted, disjoint
    std::vector<Interval> hull;
    std::size_t values = 0;
    void add(double v, double gap);
    void updateHull();
  };

  std::optional<Vec2> origin_;
  std::array<Axis, 2> axes_;
};

}  // namespace seif
