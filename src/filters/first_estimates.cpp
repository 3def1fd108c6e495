#include "filters/first_estimates.hpp"

namespace seif {

MotionIncrement FirstEstimates::fejIncrement(const MotionIncrement& m, const Vec2& position) {
  const Vec2 next = position + m.delta.head<2>();  // p_{k+1|k}
  const Vec2 d = next - predicted_;                // p_{k+1|k} - p_{k|k-1}
  MotionIncrement fej = m;
  fej.J_delta_x.block<2, 1>(0, 2) = Vec2(-d.y(), d.x());  // S d (the FEJ-EKF state Jacobian)
  predicted_ = next;
  return fej;
}

}  // namespace seif
