#include "textnum.h"

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

// The outputs' text is what printf gave before (result.csv and result.ply
// byte for byte): %.9g and %d.
TEST(TextNum, G9IsPrintfsPercentPoint9g) {
  std::vector<double> values = {0.0, -0.0, 1.0, -1.0, 0.1, 1e-5, 1e-4, 123456789.0, 1234567890.0,
                                1e16, 1e-300, DBL_MIN, DBL_MAX, DBL_TRUE_MIN, FLT_MAX, 0.5,
                                0.454545468, 2.5e-7, 999999999.5, 9.9999999995e-5, HUGE_VAL,
                                -HUGE_VAL, NAN};
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> exponent(-40, 40), mantissa(-1, 1);
  for (int i = 0; i < 100000; ++i) values.push_back(mantissa(rng) * std::pow(10.0, exponent(rng)));
  for (int i = 0; i < 10000; ++i) values.push_back(double(float(mantissa(rng) * 100)));
  for (double v : values) {
    char want[64];
    std::snprintf(want, sizeof want, "%.9g", v);
    std::string got;
    AppendG9(&got, v);
    ASSERT_EQ(got, want) << v;
  }
}

TEST(TextNum, IntIsPrintfsPercentD) {
  for (long v : {0L, 1L, -1L, 9L, 10L, 255L, 2147483647L, -2147483648L}) {
    char want[32];
    std::snprintf(want, sizeof want, "%ld", v);
    std::string got = "x";
    AppendInt(&got, v);
    EXPECT_EQ(got, std::string("x") + want);
  }
}
