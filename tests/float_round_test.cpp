#include "float_round.h"

#include <cfloat>
#include <cmath>

#include <gtest/gtest.h>

// A double rounded to a float on each side holds it: each bound rounded
// outward, beyond float's range and in it, at and between floats.
TEST(FloatRound, BoundsRoundOutward) {
  const double third = 1.0 / 3, big = 1024.0 + 1.0 / 3;
  for (double x : {third, -third, big, -big, 0.1, -0.1, 1e-30, -1e-30, 1e-50, -1e-50, 1e300,
                   -1e300, 0.0, 0.5, -0.5, 1024.0, double(FLT_MAX), -double(FLT_MAX)}) {
    EXPECT_LE(double(FloatDown(x)), x) << x;
    EXPECT_GE(double(FloatUp(x)), x) << x;
    // The nearest such: x itself where it is a float, else the two floats
    // about it.
    if (std::abs(x) > double(FLT_MAX)) continue;
    if (double(float(x)) == x) {
      EXPECT_EQ(FloatDown(x), float(x)) << x;
      EXPECT_EQ(FloatUp(x), float(x)) << x;
    } else {
      EXPECT_EQ(std::nextafter(FloatDown(x), HUGE_VALF), FloatUp(x)) << x;
    }
  }
  EXPECT_EQ(FloatDown(1e300), FLT_MAX);
  EXPECT_EQ(FloatUp(1e300), HUGE_VALF);
  EXPECT_EQ(FloatDown(-1e300), -HUGE_VALF);
  EXPECT_EQ(FloatUp(-1e300), -FLT_MAX);
}
