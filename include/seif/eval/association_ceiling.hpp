#pragma once
// How well any associator could do on a dataset with ground truth: each labelled observation
// associated with the true map seen from the true pose (docs/association.md, "The ceiling").
//
// With the map and the pose known exactly, the observations of one instant are independent
// given their landmarks, so the most likely landmark of an observation is the one whose
// predicted measurement h(x_true, y_j) is nearest in the Mahalanobis distance of the sensor
// noise R (the normaliser is the same for every candidate). It is a reference, not a proof
// of a bound: it uses the likelihood alone (an associator that also knows the sensor's
// footprint, which landmarks could have been seen at all, can do a few points better), and
// it counts every labelled observation, where an associator's correct_fraction counts only
// those it kept (dropping ambiguous ones raises that; compare with correct / observations).
//   individual  each observation to its most likely true landmark (what a nearest-neighbour
//               gate would do with a perfect map);
//   joint       the scan's most likely one-to-one assignment of observations to true
//               landmarks (what joint compatibility would do with a perfect map).
// The clutter is left out (observations without a truth id are not offered), which only
// helps: the ceiling is optimistic.
#include <seif/io/event_source.hpp>
#include <seif/models/measurement_model.hpp>

#include <cstddef>
#include <optional>

namespace seif {

struct AssociationCeilingOptions {
  /// Candidates: true landmarks whose d² to the observation is at most this (χ²₂ at
  /// 1 − 1e-6); an observation of a landmark farther than that counts as not recovered.
  double gate = 27.631021115928547;
  /// The joint assignment's branch and bound visits at most this many nodes per scan; a scan
  /// that reaches it keeps the best assignment found (counted in `joint_truncated`).
  std::size_t max_nodes = 200000;
};

struct AssociationCeiling {
  std::size_t observations = 0;     ///< with a truth id among the true landmarks, inside the ground truth's span
  std::size_t individual = 0;       ///< of them, whose individually most likely true landmark is their own
  std::size_t joint = 0;            ///< of them, paired with their own under the scan's most likely assignment
  std::size_t scans = 0;            ///< instants with at least one such observation
  std::size_t joint_truncated = 0;  ///< scans whose search reached max_nodes
};

/// Reads `source` to its end and scores the two ceilings above with `sensor` (its noise R,
/// or an observation's own). nullopt when the source has no ground-truth track or no true
/// landmarks. Observations outside the track's time span are skipped (the pose there is
/// unknown). Throws what the source throws (DataError naming the file and line).
std::optional<AssociationCeiling> associationCeiling(EventSource& source, const MeasurementModel& sensor,
                                                     const AssociationCeilingOptions& options = {});

}  // namespace seif
