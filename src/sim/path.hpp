#pragma once
// Internal to the simulator: the reference paths the robot tracks (docs/simulator.md).
// A path is a dense polyline of poses whose headings are the exact tangents of the curve
// it samples; pose(s) interpolates position linearly and heading along the shorter arc.
#include <seif/core/types.hpp>

#include <vector>

namespace seif::sim {

class ReferencePath {
 public:
  /// `vertices` (at least two) with their tangent headings. A closed path returns from the
  /// last vertex to the first; an open path continues straight beyond both ends.
  ReferencePath(std::vector<Pose2> vertices, bool closed);

  double length() const { return length_; }
  bool closed() const { return closed_; }

  /// The pose at arc length s (taken modulo length() on a closed path).
  Pose2 pose(double s) const;

 private:
  std::vector<Pose2> v_;   // closed: the first vertex repeated at the end
  std::vector<double> s_;  // cumulative arc length at each vertex
  bool closed_;
  double length_;
};

/// Builds a path from straight lines and circular arcs, sampling arcs every 2 degrees.
class PathBuilder {
 public:
  explicit PathBuilder(const Pose2& start);
  PathBuilder& line(double length);
  /// Arc of the given radius turning by `angle` (> 0 left / counter-clockwise, < 0 right).
  PathBuilder& arc(double radius, double angle);
  ReferencePath build(bool closed) const;

 private:
  std::vector<Pose2> v_;
};

/// Lissajous curve x = cx + a sin(p u), y = cy + a sin(q u) (p = 1, q = 2 is a figure
/// eight), starting at the centre (u = 0) and sampled at `samples` parameter values.
ReferencePath lissajous(const Vec2& centre, double amplitude, int p, int q, int samples = 4096);

/// Closed boustrophedon ("lawnmower") loop through the square [0, side]^2 (see
/// docs/simulator.md): an even number of lanes parallel to y, at most `max_spacing` apart,
/// `margin` from the border, and a return leg along the bottom. Neighbouring lanes are
/// joined by half circles, or, with 0 < turn_radius < half the lane spacing, by two quarter
/// circles of that radius and a straight piece, so that every lane runs up to within
/// margin + turn_radius of the border.
ReferencePath lawnmowerLoop(double side, double margin, double max_spacing,
                            double turn_radius = 0.0);

}  // namespace seif::sim
