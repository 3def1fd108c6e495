#pragma once
// The SEIF's private steps, one at a time, for tests (SeifSlam befriends SeifStepsForTests).
#include "filters/seif_slam.hpp"

#include <span>

namespace seif {
/// The SEIF's private steps, one at a time (SeifSlam befriends this test-only accessor).
struct SeifStepsForTests {
  static void motionUpdate(SeifSlam& f, const MotionIncrement& m) { f.motionUpdate(m); }
  static void recoverMean(SeifSlam& f) { f.recoverMean(); }
  static void measurementUpdate(SeifSlam& f, std::span<const Observation> z) { f.measurementUpdate(z, f.sensorModel()); }
  static void recoverExactMean(SeifSlam& f) { f.recoverExactMean(); }
  static void sparsify(SeifSlam& f) { f.sparsify(); }
};
}  // namespace seif
