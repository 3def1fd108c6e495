#pragma once
// The per-landmark policy every filter shares (docs/architecture.md, "landmark book"):
// which slot of the state an id holds, how a new landmark enters the map (the sensor's
// inverse model), which observations the gross-outlier gate rejects, and where Jacobians
// are evaluated (the linearisation policy: standard or first estimates). A filter asks the
// book to plan an update, applies the plan in its own form (covariance, dense or sparse
// information), and commits it; nothing in the book changes before the commit, so an
// update that fails leaves the book as it was.
#include <seif/core/types.hpp>
#include "filters/first_estimates.hpp"
#include "filters/outlier_gate.hpp"
#include <seif/filters/slam_filter.hpp>

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace seif {

/// Offsets in the state vector [x, y, th, l0x, l0y, l1x, ...] (docs/conventions.md).
struct StateLayout {
  static constexpr int kPoseDim = 3;
  static constexpr int kLandmarkDim = 2;
  /// First index of landmark slot `slot`.
  static constexpr Eigen::Index landmark(int slot) {
    return kPoseDim + kLandmarkDim * static_cast<Eigen::Index>(slot);
  }
  /// Size of the state with `landmarks` landmarks.
  static constexpr Eigen::Index size(int landmarks) { return landmark(landmarks); }
};

/// One observation of an update, as the book planned it.
struct PlannedObservation {
  const Observation* z = nullptr;
  int slot = -1;        ///< the landmark's slot (a new landmark's once committed)
  bool first = false;   ///< the first sighting of a new landmark: it enters the map at `initial`
  Vec2 initial = Vec2::Zero();  ///< first: the inverse-model mean g(x, z)
  /// Where this observation's Jacobians take the landmark: nullopt at its current mean
  /// (standard), else its first estimate (first-estimates Jacobians).
  std::optional<Vec2> jacobian_landmark;
  /// Linearization::ObservabilityConstrained: the directions its Jacobians must annihilate.
  std::optional<ObservabilityConstraint> constraint;
  /// The policy's last word on this observation's Jacobians (every filter calls it after
  /// evaluating them): the observability constraint when there is one, else nothing.
  void constrain(Mat23& J_x, Mat2& J_y) const {
    if (constraint) constraint->apply(J_x, J_y);
  }
};

class LandmarkBook {
 public:
  /// `filter` names the filter in messages; the gate and the linearisation come from `config`.
  LandmarkBook(std::string filter, const Pose2& start, const FilterConfig& config);

  // ---- ids and slots
  /// Slot of `id`, or -1 when the landmark is not in the map.
  int find(int id) const {
    const auto it = slot_.find(id);
    return it == slot_.end() ? -1 : it->second;
  }
  /// Slot of `id`; throws UnknownLandmark when it is not in the map.
  int require(int id) const;
  /// Ids by slot: the order landmarks entered the map (their order in the state).
  const std::vector<int>& ids() const { return ids_; }
  int size() const { return static_cast<int>(ids_.size()); }

  // ---- one update
  /// Throws ModelError naming the first observation that no update can take: no landmark
  /// id, a measurement or noise that is not finite. plan() checks this first.
  void check(std::span<const Observation> z, const MeasurementModel& sensor) const;
  /// Plans the update with `z`, made by `sensor` at robot mean `x`; `mean(slot)` gives a
  /// mapped landmark's mean. First every observation is checked (a landmark id, finite
  /// values, a first sighting the inverse model can place), and ModelError names the first
  /// bad one: nothing is planned. Then, in order: the first sighting of an unknown id is new
  /// (slot size() + k, mean from the inverse model at x, never gated: there is nothing to
  /// compare it with); every other observation is gated (OutlierGate) at the landmark's
  /// mean - a new one's initial mean - and planned, or left out and counted at commit().
  /// The plan is valid until the next plan().
  std::span<const PlannedObservation> plan(std::span<const Observation> z, const MeasurementModel& sensor,
                                           const Pose2& x, const std::function<Vec2(int)>& mean);
  /// Observations the last plan() left out as gross outliers.
  std::size_t plannedRejections() const { return planned_rejections_; }
  /// Commits the last plan(): its new landmarks join the map (ids, first estimates) and its
  /// rejections are counted. The filter calls it once its own form holds the update.
  void commit();

  /// The gate alone on one observation of a mapped landmark at (x, y), counted now if it
  /// rejects (the ESEIF's choice of z_beta gates before it plans).
  bool rejects(const MeasurementModel& sensor, const Pose2& x, const Vec2& y, const Observation& z);
  /// Observations rejected by the gate over the filter's life.
  std::size_t rejected() const { return gate_.rejected(); }

  // ---- linearisation policy
  Linearization linearization() const { return linearization_; }
  /// Whether the policy keeps first estimates (fej and oc): checkpoints store them then.
  static bool keepsFirstEstimates(Linearization l) {
    return l == Linearization::FirstEstimates || l == Linearization::ObservabilityConstrained;
  }
  /// The increment the filter applies: with first estimates, its heading column from the
  /// pose predictions (FirstEstimates::fejIncrement); else `m` itself. `position` is the
  /// robot position the increment was linearised at.
  MotionIncrement motionIncrement(const MotionIncrement& m, const Vec2& position);

  // ---- removal and merge (each filter applies the same change to its own form)
  /// Removes slot `slot`; the last slot takes its place (the filter moves its rows likewise).
  void removeSlot(int slot);

  /// The book's state before a step, to undo it: O(1) to take; undo(mark) removes the
  /// landmarks committed since and restores the first-estimates prediction and the gate's
  /// count (a step that failed, undone whole by its filter).
  struct Mark {
    int landmarks = 0;
    Vec2 predicted = Vec2::Zero();
    std::size_t rejected = 0;
  };
  Mark mark() const;
  void undo(const Mark& mark);

 private:
  friend struct CheckpointAccess;  // checkpoints: src/filters/bookkeeping_state.cpp
  /// Where p's Jacobians go under the policy, `first` the landmark's first estimate.
  void setJacobianPolicy(PlannedObservation& p, const Vec2& first) const;
  std::string filter_;
  Linearization linearization_;
  OutlierGate gate_;
  std::optional<FirstEstimates> fej_;
  std::vector<int> ids_;
  std::unordered_map<int, int> slot_;
  std::vector<PlannedObservation> plan_;
  std::vector<std::pair<int, Vec2>> planned_new_;  // id, initial mean
  std::size_t planned_rejections_ = 0;
};

}  // namespace seif
