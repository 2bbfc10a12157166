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

// A shot's many Set calls in a row (Expect'ed or not, most bounds
// growing, some shrinking) between two Best() calls, over sizes that make
// one to three levels of 64-child nodes with partly filled last nodes,
// and a Build that grows the shooters keeping the taken: Best() still
// gives what a scan gives.
TEST(ShooterQueue, ManySetsAShotPickWhatAFullScanPicks) {
  std::mt19937 rng(11);
  for (int n : {63, 64, 65, 130, 4095, 4097, 9000}) {
    std::uniform_int_distribution<int> id(0, n - 1), coin(0, 7);
    std::uniform_real_distribution<double> unit(0, 1);
    std::vector<double> c(n), w(n);
    std::vector<char> taken(n, 0);
    double a0 = 0, a = 0;
    auto power = [&](int i) { return c[i] + w[i] * a; };
    auto bounds = [&] {
      std::vector<double> b(c.size());
      for (size_t i = 0; i < c.size(); ++i) b[i] = c[i] + w[i] * a0;
      return b;
    };
    auto weights = [&] {  // above |w| by more than the powers' rounding
      std::vector<double> v(w.size());
      for (size_t i = 0; i < w.size(); ++i) v[i] = w[i] * (1 + 1e-9);
      return v;
    };
    for (int i = 0; i < n; ++i) {
      c[i] = std::floor(8 * unit(rng)) - 2;  // coarse: ties are common
      w[i] = std::floor(4 * unit(rng)) / 4;
    }
    ShooterQueue q;
    q.Build(bounds(), weights());
    for (int step = 0; step < 200; ++step) {
      const int sets = coin(rng) == 0 ? n / 2 : int(std::sqrt(double(n)));
      if (coin(rng) < 4) q.Expect(size_t(sets));
      for (int s = 0; s < sets; ++s) {
        const int i = id(rng);
        c[i] += coin(rng) == 0 ? -std::floor(4 * unit(rng)) : std::floor(3 * unit(rng));
        q.Set(i, c[i] + w[i] * a0);
      }
      for (int t = coin(rng); t > 0; --t) {
        const int i = id(rng);
        if (taken[i]) q.Release(i); else q.Take(i);
        taken[i] = !taken[i];
      }
      a += (unit(rng) - 0.5) / 4;
      if (coin(rng) == 0) {  // a re-base, sometimes with more shooters (a split)
        a0 = a;
        if (coin(rng) < 2) {
          const size_t more = size_t(1 + coin(rng));
          for (size_t k = 0; k < more; ++k) {
            c.push_back(std::floor(8 * unit(rng)) - 2);
            w.push_back(0.25);
            taken.push_back(0);
          }
        }
        q.Build(bounds(), weights());
      }
      int want = -1;
      double best = 0;
      for (size_t i = 0; i < c.size(); ++i)
        if (!taken[i] && power(int(i)) > best) best = power(want = int(i));
      ASSERT_EQ(q.Best(std::abs(a - a0), power), want) << "n " << n << " step " << step;
    }
  }
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
