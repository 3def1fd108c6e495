#include <seif/core/angles.hpp>

#include <gtest/gtest.h>

#include <numbers>

using seif::wrapAngle;
constexpr double kPi = std::numbers::pi;

TEST(WrapAngle, MapsIntoHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(wrapAngle(kPi), kPi);
  EXPECT_DOUBLE_EQ(wrapAngle(-kPi), kPi);
  EXPECT_NEAR(wrapAngle(3 * kPi + 0.1), -kPi + 0.1, 1e-12);
  EXPECT_NEAR(wrapAngle(-0.5), -0.5, 0);
  for (double a = -50.0; a < 50.0; a += 0.37) {
    const double w = wrapAngle(a);
    EXPECT_GT(w, -kPi);
    EXPECT_LE(w, kPi);
    EXPECT_NEAR(std::remainder(w - a, 2 * kPi), 0.0, 1e-12);
  }
}
