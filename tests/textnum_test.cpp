#include "textnum.h"

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

// result.csv's text is what printf gave before, byte for byte: %.9g and %d.
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

// result.ply's coordinates: each reads back as the float written, in no
// more characters than %.9g takes.
TEST(TextNum, FloatReadsBackAsItself) {
  std::vector<float> values = {0.0f, -0.0f, 1.0f, -1.0f, 0.1f, 2.5f, 1e-4f, 0.454545468f, 1e10f,
                               FLT_MIN, FLT_MAX, FLT_TRUE_MIN, -FLT_MAX};
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> exponent(-40, 38), mantissa(-1, 1);
  for (int i = 0; i < 100000; ++i) values.push_back(mantissa(rng) * std::pow(10.0f, exponent(rng)));
  for (float v : values) {
    std::string got;
    AppendFloat(&got, v);
    char* end = nullptr;
    const float back = std::strtof(got.c_str(), &end);
    ASSERT_EQ(*end, '\0') << got;
    ASSERT_EQ(std::signbit(back), std::signbit(v)) << got;
    ASSERT_EQ(back, v) << got;
    char g9[64];
    std::snprintf(g9, sizeof g9, "%.9g", double(v));
    ASSERT_LE(got.size(), std::strlen(g9)) << got << " against " << g9;
  }
  std::string s;
  AppendFloat(&s, 0.1f);
  AppendFloat(&s, 2.5f);
  EXPECT_EQ(s, "0.12.5");
}
