#include <seif/eval/association_ceiling.hpp>

#include <seif/core/dataset.hpp>
#include <seif/core/errors.hpp>

#include <Eigen/LU>

#include <algorithm>
#include <limits>
#include <utility>
#include <vector>

namespace seif {
namespace {

struct Candidate {
  int landmark;
  double d2;  // Mahalanobis distance² of the observation from h(x_true, y_landmark)
};

struct ScoredObservation {
  int truth;
  std::vector<Candidate> candidates;  // sorted by d2
};

// Every true landmark within the gate of z seen from x, nearest first.
std::vector<Candidate> candidatesOf(const Observation& z, const Pose2& x, const MeasurementModel& sensor,
                                    const std::map<int, Vec2>& landmarks, double gate) {
  const Mat2 R_inv = sensor.noise(z).inverse();
  std::vector<Candidate> out;
  for (const auto& [id, y] : landmarks) {
    Vec2 zhat;
    try {
      zhat = sensor.predict(x, y);
    } catch (const ModelError&) {
      continue;  // degenerate (the landmark at the sensor): it cannot have been seen
    }
    const Vec2 r = sensor.residual(z.z, zhat);
    const double d2 = r.dot(R_inv * r);
    if (d2 <= gate) out.push_back({id, d2});
  }
  std::sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) { return a.d2 < b.d2; });
  return out;
}

// The scan's most likely one-to-one assignment: minimise Σ d² over observations, an
// observation left unpaired costing the gate. Depth-first branch and bound, observations
// with the fewest candidates first; the bound adds each remaining observation's own best.
class JointAssignment {
 public:
  JointAssignment(const std::vector<ScoredObservation>& scan, double gate, std::size_t max_nodes)
      : scan_(scan), gate_(gate), max_nodes_(max_nodes) {
    order_.resize(scan.size());
    for (std::size_t i = 0; i < scan.size(); ++i) order_[i] = i;
    std::sort(order_.begin(), order_.end(),
              [&](std::size_t a, std::size_t b) { return scan[a].candidates.size() < scan[b].candidates.size(); });
    rest_.assign(scan.size() + 1, 0.0);
    for (std::size_t k = scan.size(); k-- > 0;) {
      const auto& c = scan[order_[k]].candidates;
      rest_[k] = rest_[k + 1] + (c.empty() ? gate : std::min(gate, c.front().d2));
    }
    current_.assign(scan.size(), -1);
    best_.assign(scan.size(), -1);
  }

  // The landmark each observation is paired with (-1: none), in the scan's order.
  std::vector<int> solve(bool* truncated) {
    search(0, 0.0);
    *truncated = nodes_ >= max_nodes_;
    return best_;
  }

 private:
  void search(std::size_t k, double cost) {
    if (nodes_ >= max_nodes_ || cost + rest_[k] >= best_cost_) return;
    ++nodes_;
    if (k == order_.size()) {
      best_cost_ = cost;
      best_ = current_;
      return;
    }
    const std::size_t i = order_[k];
    for (const Candidate& c : scan_[i].candidates) {
      if (std::find(used_.begin(), used_.end(), c.landmark) != used_.end()) continue;
      used_.push_back(c.landmark);
      current_[i] = c.landmark;
      search(k + 1, cost + c.d2);
      used_.pop_back();
    }
    current_[i] = -1;
    search(k + 1, cost + gate_);
  }

  const std::vector<ScoredObservation>& scan_;
  double gate_;
  std::size_t max_nodes_;
  std::size_t nodes_ = 0;
  std::vector<std::size_t> order_;
  std::vector<double> rest_;  // rest_[k]: Σ over order_[k..] of each one's best cost
  std::vector<int> current_, best_, used_;
  double best_cost_ = std::numeric_limits<double>::infinity();
};

}  // namespace

std::optional<AssociationCeiling> associationCeiling(EventSource& source, const MeasurementModel& sensor,
                                                     const AssociationCeilingOptions& options) {
  if (!(options.gate > 0.0)) throw InvalidArgument("associationCeiling: the gate must be > 0");
  std::vector<TimedPose> track;
  std::vector<ObservationEvent> scans;
  for (Event e; source.next(e);) {
    if (auto* p = std::get_if<TimedPose>(&e)) {
      track.push_back(*p);
    } else if (auto* o = std::get_if<ObservationEvent>(&e)) {
      scans.push_back(std::move(*o));
    }
  }
  const std::map<int, Vec2>& landmarks = source.info().landmarks;
  if (track.empty() || landmarks.empty()) return std::nullopt;
  std::stable_sort(track.begin(), track.end(), [](const TimedPose& a, const TimedPose& b) { return a.time < b.time; });

  AssociationCeiling c;
  std::vector<ScoredObservation> scan;
  for (const ObservationEvent& event : scans) {
    if (event.time < track.front().time || event.time > track.back().time) continue;
    const Pose2 x = interpolatePose(track, event.time);
    scan.clear();
    for (const Observation& z : event.observations) {
      if (z.truth == kUnknownLandmark || !landmarks.contains(z.truth)) continue;
      scan.push_back({z.truth, candidatesOf(z, x, sensor, landmarks, options.gate)});
    }
    if (scan.empty()) continue;
    ++c.scans;
    c.observations += scan.size();
    for (const ScoredObservation& s : scan) {
      if (!s.candidates.empty() && s.candidates.front().landmark == s.truth) ++c.individual;
    }
    bool truncated = false;
    const std::vector<int> paired = JointAssignment(scan, options.gate, options.max_nodes).solve(&truncated);
    if (truncated) ++c.joint_truncated;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (paired[i] == scan[i].truth) ++c.joint;
    }
  }
  return c;
}

}  // namespace seif
