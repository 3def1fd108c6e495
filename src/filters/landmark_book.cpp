#include <seif/core/errors.hpp>
#include "filters/landmark_book.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>

namespace seif {

LandmarkBook::LandmarkBook(std::string filter, const Pose2& start, const FilterConfig& config)
    : filter_(std::move(filter)), linearization_(config.linearization), gate_(config.outlier_gate) {
  // The OC-EKF keeps the same records as first-estimates Jacobians: the pose predictions
  // (its motion Jacobian) and each landmark's first estimate (its null space).
  if (keepsFirstEstimates(linearization_)) fej_.emplace(start);
  // A step's plan allocates only when it holds more observations than any before (the
  // SEIF's steady state allocates nothing, tests/test_seif_allocation.cpp).
  plan_.reserve(64);
  planned_new_.reserve(64);
}

int LandmarkBook::require(int id) const {
  const int s = find(id);
  if (s < 0) throw UnknownLandmark(filter_, id);
  return s;
}

namespace {
[[noreturn]] void badObservation(const std::string& filter, std::size_t k, const Observation& z,
                                 const std::string& what) {
  std::ostringstream msg;
  msg << filter << ": observation " << k << " (landmark " << z.landmark << "): " << what;
  throw ModelError(msg.str());
}
}  // namespace

void LandmarkBook::check(std::span<const Observation> z, const MeasurementModel& sensor) const {
  for (std::size_t k = 0; k < z.size(); ++k) {
    if (z[k].landmark < 0) badObservation(filter_, k, z[k], "no landmark id; this filter needs known data association");
    if (!z[k].z.allFinite()) badObservation(filter_, k, z[k], "the measurement is not finite");
    const Mat2 R = sensor.noise(z[k]);
    if (!R.allFinite()) badObservation(filter_, k, z[k], "the measurement noise is not finite");
    if (std::abs(R(0, 1) - R(1, 0)) > 1e-9 * (std::abs(R(0, 0)) + std::abs(R(1, 1)))) {  // beyond rounding
      badObservation(filter_, k, z[k], "the measurement noise is not symmetric");
    }
    if (!(R(0, 0) > 0.0 && R(0, 0) * R(1, 1) - R(0, 1) * R(1, 0) > 0.0)) {
      badObservation(filter_, k, z[k], "the measurement noise is not positive definite");
    }
  }
}

std::span<const PlannedObservation> LandmarkBook::plan(std::span<const Observation> z,
                                                       const MeasurementModel& sensor, const Pose2& x,
                                                       const std::function<Vec2(int)>& mean) {
  plan_.clear();
  planned_new_.clear();
  planned_rejections_ = 0;
  check(z, sensor);  // an update is applied whole or not at all
  for (const Observation& o : z) {
    PlannedObservation p;
    p.z = &o;
    p.slot = find(o.landmark);
    Vec2 y;
    if (p.slot < 0) {
      const auto it = std::find_if(planned_new_.begin(), planned_new_.end(),
                                   [&](const auto& n) { return n.first == o.landmark; });
      if (it == planned_new_.end()) {  // the first sighting: the inverse model places it
        p.first = true;
        p.initial = sensor.inverse(x, o.z);
        if (!p.initial.allFinite()) {
          badObservation(filter_, static_cast<std::size_t>(&o - z.data()), o, "the inverse model gives no finite position");
        }
        p.slot = size() + static_cast<int>(planned_new_.size());
        planned_new_.emplace_back(o.landmark, p.initial);
        setJacobianPolicy(p, p.initial);
        plan_.push_back(p);
        continue;
      }
      p.slot = size() + static_cast<int>(it - planned_new_.begin());
      y = it->second;
      setJacobianPolicy(p, it->second);
    } else {
      y = mean(p.slot);
      if (fej_) setJacobianPolicy(p, fej_->landmark(p.slot));
    }
    if (gate_.wouldReject(sensor, x, y, o, sensor.noise(o).inverse())) {
      ++planned_rejections_;
      continue;
    }
    plan_.push_back(p);
  }
  return plan_;
}

void LandmarkBook::setJacobianPolicy(PlannedObservation& p, const Vec2& first) const {
  if (linearization_ == Linearization::FirstEstimates) p.jacobian_landmark = first;
  if (linearization_ == Linearization::ObservabilityConstrained) {
    p.constraint = ObservabilityConstraint{fej_->predictedPosition(), first};
  }
}

void LandmarkBook::commit() {
  for (const auto& [id, initial] : planned_new_) {
    slot_.emplace(id, size());
    ids_.push_back(id);
    if (fej_) fej_->addLandmark(initial);
  }
  gate_.count(planned_rejections_);
  planned_new_.clear();
  planned_rejections_ = 0;
  plan_.clear();
}

bool LandmarkBook::rejects(const MeasurementModel& sensor, const Pose2& x, const Vec2& y, const Observation& z) {
  return gate_.rejects(sensor, x, y, z, sensor.noise(z).inverse());
}

MotionIncrement LandmarkBook::motionIncrement(const MotionIncrement& m, const Vec2& position) {
  checkIncrement(m, filter_);  // before anything changes: a predict is all or nothing
  return fej_ ? fej_->fejIncrement(m, position) : m;
}

LandmarkBook::Mark LandmarkBook::mark() const {
  return {size(), fej_ ? fej_->predictedPosition() : Vec2::Zero(), gate_.rejected()};
}

void LandmarkBook::undo(const Mark& mark) {
  while (size() > mark.landmarks) {
    slot_.erase(ids_.back());
    ids_.pop_back();
  }
  if (fej_) fej_->restore(mark.predicted, mark.landmarks);
  gate_.restore(mark.rejected);
  planned_new_.clear();
  planned_rejections_ = 0;
  plan_.clear();
}

void LandmarkBook::removeSlot(int slot) {
  const int last = size() - 1;
  if (slot < 0 || slot > last) throw InvalidArgument(filter_ + ": no landmark slot " + std::to_string(slot));
  slot_.erase(ids_[static_cast<std::size_t>(slot)]);
  if (slot != last) {
    ids_[static_cast<std::size_t>(slot)] = ids_.back();
    slot_[ids_.back()] = slot;
  }
  ids_.pop_back();
  if (fej_) fej_->removeSlot(slot);
}

}  // namespace seif
