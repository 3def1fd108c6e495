#pragma once
// The gross-outlier gate of every filter's measurement update: a reading no sensor could
// have made (a 1e6 m range, a corrupted row) is rejected before it reaches the estimate.
//
// An observation of a mapped landmark y, predicted at the filter's current estimate x, is
// rejected when its innovation nu = z - h(x, y) (bearing wrapped) lies more than `sigmas`
// measurement standard deviations away:  nu^T Z^-1 nu > sigmas^2.
// The state's own uncertainty is left out on purpose: the test is O(1) in every filter and
// needs no covariance, so it is meant to be very loose (default 1000 sigma: 200 m of range
// with MRCLAM's 0.2 m, 45 m in the paper's world), far beyond any error of the estimate, and
// it is no substitute for a chi-square gate on the innovation covariance. A landmark's first
// sighting has no prediction and is never rejected.
#include <seif/core/types.hpp>
#include <seif/models/measurement_model.hpp>

#include <cstddef>
#include <limits>

namespace seif {

class OutlierGate {
 public:
  /// `sigmas` > 0; infinity disables the gate.
  explicit OutlierGate(double sigmas);

  /// Whether z, made by `sensor`, is rejected at robot pose x and landmark mean y (and
  /// counts it if so). Z_inv is the inverse of the observation's noise.
  bool rejects(const MeasurementModel& sensor, const Pose2& x, const Vec2& y, const Observation& z,
               const Mat2& Z_inv);
  /// rejects() without counting: the caller counts with count() once its update holds.
  bool wouldReject(const MeasurementModel& sensor, const Pose2& x, const Vec2& y, const Observation& z,
                   const Mat2& Z_inv) const;
  void count(std::size_t rejections) { rejected_ += rejections; }
  /// Back to an earlier count (a step undone).
  void restore(std::size_t rejected) { rejected_ = rejected; }

  std::size_t rejected() const { return rejected_; }
  double sigmas() const { return sigmas_; }

 private:
  friend struct CheckpointAccess;  // checkpoints: src/filters/*_state.cpp
  double sigmas_;
  double threshold_;  // sigmas^2
  std::size_t rejected_ = 0;
};

}  // namespace seif
