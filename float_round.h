// A double rounded to a float on a known side: boxes kept in float that
// must hold the boxes in double (the group search's element boxes, the
// hemicube cache's face boxes) and bounds that must not shrink (the
// subdivider's). Written here rather than by std::nextafter: its call
// into libm was a tenth of the group search's tree building.
#ifndef RADIOSITY_FLOAT_ROUND_H
#define RADIOSITY_FLOAT_ROUND_H

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

// x rounded to a float at or below it, beyond float's range too (the
// largest float, or -inf: a plain cast is undefined there).
inline float FloatDown(double x) {
  const float f = x > double(FLT_MAX) ? FLT_MAX : x < -double(FLT_MAX) ? -HUGE_VALF : float(x);
  if (!(double(f) > x)) return f;
  // The float below f (finite, as f > x): one step of f's bits away from
  // zero below it, toward it above.
  if (f == 0) return -std::numeric_limits<float>::denorm_min();
  uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  u = f > 0 ? u - 1 : u + 1;
  float below;
  std::memcpy(&below, &u, sizeof below);
  return below;
}

// x rounded to a float at or above it.
inline float FloatUp(double x) { return -FloatDown(-x); }

#endif
