#include "path.hpp"

#include <seif/core/angles.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <utility>

namespace seif::sim {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMaxArcStep = 2.0 * kPi / 180.0;  // arcs are sampled every 2 degrees

}  // namespace

ReferencePath::ReferencePath(std::vector<Pose2> vertices, bool closed)
    : v_(std::move(vertices)), closed_(closed), length_(0.0) {
  assert(v_.size() >= 2);
  if (closed_) {
    if ((v_.back().head<2>() - v_.front().head<2>()).norm() < 1e-6) v_.pop_back();
    v_.push_back(v_.front());
  }
  s_.resize(v_.size());
  s_[0] = 0.0;
  for (std::size_t i = 1; i < v_.size(); ++i) {
    s_[i] = s_[i - 1] + (v_[i].head<2>() - v_[i - 1].head<2>()).norm();
  }
  length_ = s_.back();
  assert(length_ > 0.0);
}

Pose2 ReferencePath::pose(double s) const {
  if (closed_) {
    s = std::fmod(s, length_);
    if (s < 0.0) s += length_;
  } else if (s <= 0.0 || s >= length_) {  // continue straight beyond the ends
    const Pose2& end = s <= 0.0 ? v_.front() : v_.back();
    const double ds = s <= 0.0 ? s : s - length_;
    return {end.x() + ds * std::cos(end.z()), end.y() + ds * std::sin(end.z()), end.z()};
  }
  // Segment i .. i+1 with s_[i] <= s < s_[i+1] (zero-length segments are never chosen).
  const auto it = std::upper_bound(s_.begin(), s_.end(), s);
  const std::size_t i = std::min<std::size_t>(
      static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - s_.begin(), 1)) - 1,
      v_.size() - 2);
  const double len = s_[i + 1] - s_[i];
  const double t = len > 0.0 ? std::clamp((s - s_[i]) / len, 0.0, 1.0) : 0.0;
  const Pose2& a = v_[i];
  const Pose2& b = v_[i + 1];
  return {a.x() + t * (b.x() - a.x()), a.y() + t * (b.y() - a.y()),
          wrapAngle(a.z() + t * wrapAngle(b.z() - a.z()))};
}

PathBuilder::PathBuilder(const Pose2& start) : v_{start} {}

PathBuilder& PathBuilder::line(double length) {
  if (length <= 1e-12) return *this;
  const Pose2 p = v_.back();
  v_.emplace_back(p.x() + length * std::cos(p.z()), p.y() + length * std::sin(p.z()), p.z());
  return *this;
}

PathBuilder& PathBuilder::arc(double radius, double angle) {
  if (radius <= 1e-12 || std::abs(angle) <= 1e-12) return *this;
  const Pose2 p = v_.back();
  const double side = angle > 0.0 ? 1.0 : -1.0;  // centre on the left (+1) or right (-1)
  const Vec2 normal(-std::sin(p.z()), std::cos(p.z()));
  const Vec2 centre = p.head<2>() + side * radius * normal;
  const int pieces = std::max(1, static_cast<int>(std::ceil(std::abs(angle) / kMaxArcStep)));
  for (int j = 1; j <= pieces; ++j) {
    const double th = p.z() + angle * j / pieces;
    const Vec2 q = centre - side * radius * Vec2(-std::sin(th), std::cos(th));
    v_.emplace_back(q.x(), q.y(), wrapAngle(th));
  }
  return *this;
}

ReferencePath PathBuilder::build(bool closed) const { return ReferencePath(v_, closed); }

ReferencePath lissajous(const Vec2& centre, double amplitude, int p, int q, int samples) {
  std::vector<Pose2> v;
  v.reserve(static_cast<std::size_t>(samples));
  for (int i = 0; i < samples; ++i) {
    const double u = 2.0 * kPi * i / samples;
    v.emplace_back(centre.x() + amplitude * std::sin(p * u),
                   centre.y() + amplitude * std::sin(q * u),
                   std::atan2(q * std::cos(q * u), p * std::cos(p * u)));
  }
  return ReferencePath(std::move(v), true);
}

ReferencePath lawnmowerLoop(double side, double margin, double max_spacing, double turn_radius) {
  // n lanes (n even, n >= 2) at x_i = margin + i d, d = (side - 2 margin) / (n - 1) <= max_spacing.
  const double span = side - 2.0 * margin;
  int lanes = 2;
  while (span / (lanes - 1) > max_spacing) lanes += 2;
  const double d = span / (lanes - 1);
  // Radius of every turn: half circles (rho = d / 2) unless a tighter radius is asked for.
  const double rho = turn_radius > 0.0 && turn_radius < 0.5 * d ? turn_radius : 0.5 * d;
  const double y_top = side - margin - rho;  // lanes end here; top turns reach side - margin
  const double y_low = margin + d;         // inner lanes start here, above the return leg
  const double y_outer = margin + rho;     // the first and the last lane reach down to here
  PathBuilder b(Pose2(margin, y_outer, kPi / 2));
  auto turn = [&](double side_sign) {  // to the next lane: +1 left, -1 right
    b.arc(rho, side_sign * kPi / 2).line(d - 2.0 * rho).arc(rho, side_sign * kPi / 2);
  };
  b.line(y_top - y_outer);  // lane 0, up
  for (int i = 1; i < lanes; ++i) {
    const bool down = i % 2 == 1;
    turn(down ? -1.0 : 1.0);  // right turns at the top, left turns at the bottom
    const double bottom = i == lanes - 1 ? y_outer : y_low;
    b.line(y_top - bottom);
  }
  b.arc(rho, -kPi / 2).line(span - 2.0 * rho).arc(rho, -kPi / 2);  // return leg along y = margin
  return b.build(true);
}

}  // namespace seif::sim
