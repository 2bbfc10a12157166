#include "shooters.h"

#include <algorithm>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace {

// Shooters whose power is c_i + w_i·a for a shared a (weight |w_i|, drift
// |a − a0|), on a coarse grid of values so that ties
// are common; the queue's bounds are the powers at a0. Best() must give
// what a scan in id order gives, with shooters taken and released and
// powers changed between the calls.
TEST(ShooterQueue, PicksWhatAFullScanPicks) {
  std::mt19937 rng(7);
  for (int n : {1, 2, 3, 7, 64, 1000}) {
    std::uniform_int_distribution<int> id(0, n - 1), grid(-4, 12), coin(0, 3);
    std::vector<double> c(n), w(n);
    std::vector<char> taken(n, 0);
    double a0 = 0, a = 0;
    auto power = [&](int i) { return c[i] + w[i] * a; };
    auto bounds = [&] {
      std::vector<double> b(n);
      for (int i = 0; i < n; ++i) b[i] = c[i] + w[i] * a0;
      return b;
    };
    auto weights = [&] {
      std::vector<double> v(n);
      for (int i = 0; i < n; ++i) v[i] = std::abs(w[i]) * (1 + 1e-12);
      return v;
    };
    for (int i = 0; i < n; ++i) {
      c[i] = grid(rng);
      w[i] = grid(rng) / 12.0;
    }
    ShooterQueue q;
    q.Build(bounds(), weights());
    for (int step = 0; step < 3000; ++step) {
      switch (coin(rng)) {
        case 0: {  // a shot: one shooter's power changes
          const int i = id(rng);
          c[i] = grid(rng);
          q.Set(i, c[i] + w[i] * a0);
          break;
        }
        case 1: {  // a take or a release
          const int i = id(rng);
          if (taken[i]) q.Release(i); else q.Take(i);
          taken[i] = !taken[i];
          break;
        }
        case 2:  // the shared term moves; sometimes a re-base
          a += grid(rng) / 16.0;
          if (coin(rng) == 0) {
            a0 = a;
            q.Build(bounds(), weights());
          }
          break;
        default:
          break;
      }
      int want = -1;
      double best = 0;
      for (int i = 0; i < n; ++i)
        if (!taken[i] && power(i) > best) best = power(want = i);
      ASSERT_EQ(q.Best(std::abs(a - a0), power), want) << "n " << n << " step " << step;
      for (int i = 0; i < n; ++i) ASSERT_EQ(q.Taken(i), taken[i] != 0);
    }
  }
}

TEST(ShooterQueue, NothingAboveZeroIsNoShooter) {
  ShooterQueue q;
  q.Build({0.0, -1.0, NAN, -HUGE_VAL}, {1.0, 1.0, 1.0, 1.0});
  EXPECT_EQ(q.Best(0.0, [](int i) { return i == 2 ? NAN : 0.0; }), -1);
  q.Build({}, {});
  EXPECT_EQ(q.Best(0.0, [](int) { return 1.0; }), -1);
}

// Pruning works: with no drift and distinct powers, one path is visited.
TEST(ShooterQueue, VisitsOnlyTheCandidates) {
  const int n = 1 << 12;
  std::vector<double> b(n);
  for (int i = 0; i < n; ++i) b[i] = double((i * 2654435761u) % 100003);
  ShooterQueue q;
  q.Build(b, std::vector<double>(n, 1.0));
  const int best = q.Best(0.0, [&](int i) { return b[i]; });
  EXPECT_EQ(b[best], *std::max_element(b.begin(), b.end()));
  EXPECT_EQ(q.Visited(), 1);
}

}  // namespace
