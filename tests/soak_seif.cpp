// Soak (ctest label `slow`): a million SEIF steps on a fixed map. H stays symmetric positive
// definite, nothing becomes NaN, the estimate keeps tracking the robot, and the filter's
// memory stays flat once the map is built.
#include <seif/core/angles.hpp>
#include "filters/seif_slam.hpp"
#include <seif/models/range_bearing.hpp>
#include "models/velocity_motion.hpp"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>
#include <malloc.h>
#if defined(__SANITIZE_ADDRESS__)
// ASan's runtime exports it; GCC 12 ships no header declaring it.
extern "C" std::size_t __sanitizer_get_current_allocated_bytes();
#endif

#include <numbers>
#include <random>
#include <vector>

namespace {

using namespace seif;

/// Bytes in use on the heap (ASan's allocator replaces glibc's, whose mallinfo2 it leaves at 0).
std::size_t heapInUse() {
#if defined(__SANITIZE_ADDRESS__)
  return __sanitizer_get_current_allocated_bytes();
#else
  return mallinfo2().uordblks;
#endif
}

TEST(Soak, AMillionSeifStepsOnAFixedMap) {
  constexpr long kSteps = 1'000'000;
  constexpr long kCheckEvery = 20'000;
  constexpr double kSensorRange = 2.0;
  // 60 landmarks in an annulus about a circular path of radius 5 (one lap = 314 steps).
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> radius(3.0, 7.0), angle(-std::numbers::pi, std::numbers::pi);
  std::normal_distribution<double> n01;
  std::vector<Vec2> landmarks;
  for (int i = 0; i < 60; ++i) {
    const double r = radius(rng), a = angle(rng);
    landmarks.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  const NoiseModel noise{0.02, 0.01, 0.02, 0.01};
  const FilterConfig config = paperFilterConfig(noise);
  const VelocityControl u{1.0, 0.2, 0.1};
  Pose2 truth(5.0, 0.0, std::numbers::pi / 2);
  SeifSlam seif(truth, config);
  std::vector<Observation> z;
  std::size_t heap_after_warmup = 0;
  double worst_position_error = 0.0;
  for (long k = 1; k <= kSteps; ++k) {
    truth = VelocityMotionModel::apply(truth, u);  // the robot drives the circle exactly
    const VelocityControl odometry{u.v + noise.sigma_v * n01(rng), u.w + noise.sigma_w * n01(rng), u.dt};
    z.clear();
    for (std::size_t i = 0; i < landmarks.size(); ++i) {
      if ((landmarks[i] - truth.head<2>()).norm() > kSensorRange) continue;
      const Vec2 h = RangeBearingModel(1.0, 1.0).predict(truth, landmarks[i]);
      z.push_back({static_cast<int>(i),
                   Vec2(h.x() + noise.sigma_range * n01(rng),
                        wrapAngle(h.y() + noise.sigma_bearing * n01(rng))),
                   std::nullopt});
    }
    seif.step(odometry, z);
    const Pose2 x = seif.pose();
    ASSERT_TRUE(x.allFinite()) << "step " << k;
    worst_position_error = std::max(worst_position_error, (x - truth).head<2>().norm());
    if (k % kCheckEvery != 0) continue;
    const Eigen::SparseMatrix<double> H = seif.sparseInformation();
    const double asymmetry = (H - Eigen::SparseMatrix<double>(H.transpose())).norm() / H.norm();
    ASSERT_LT(asymmetry, 1e-12) << "step " << k;  // rounding in the dense block updates only
    Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(H);
    ASSERT_EQ(llt.info(), Eigen::Success) << "H is not positive definite at step " << k;
    ASSERT_TRUE(seif.mean().allFinite()) << "step " << k;
    const std::size_t heap = heapInUse();
    if (k == 5 * kCheckEvery) heap_after_warmup = heap;
    if (k > 5 * kCheckEvery) {
      // Flat: the checks above allocate and free; the filter holds what it held.
      ASSERT_LE(heap, heap_after_warmup + 64 * 1024) << "the heap grew by " << heap - heap_after_warmup
                                                     << " bytes between step " << 5 * kCheckEvery << " and " << k;
    }
  }
  EXPECT_EQ(seif.landmarkIds().size(), landmarks.size());
  EXPECT_LT(worst_position_error, 0.5) << "the estimate lost the robot";
  RecordProperty("worst_position_error", std::to_string(worst_position_error));
}

}  // namespace
