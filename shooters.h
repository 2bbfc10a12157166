// The choice of the next shooter without looking at every one (issue 14):
// a tournament tree (a max segment tree) over shooter ids 0..n-1, kept up
// to date one shooter at a time as shots land.
//
// The owner's power of shooter i may depend on a term shared by all of
// them (the solver's ambient overshooting estimate, which every shot
// moves, and with it every patch's power at once). So the tree does not
// hold the powers but an upper bound of each as of a reference point of
// the shared term, and the owner says how far any power may have moved
// since (`drift`, one number for all, times a weight per shooter). Best() then visits only the
// shooters whose bound plus drift reaches the best exact power found so
// far, computes their exact power with the owner's function, and returns
// what a full scan in id order with `power > best` would: the greatest
// power above 0, the lowest id among equal ones. The owner re-bases (new
// reference point, every bound set again: Build) when the drift has made
// the visits dear (Visited()).
//
// Numbers: bounds and powers are double, as the solver's are.
// Taken shooters (handed to a worker, not yet shot) are kept out of the
// tree, so that a scheduler asking for the next one many times per shot
// pays O(log n) per take, not a scan of what it holds. A bound that grew
// reaches the tree's inner nodes at once (as far up as it is the greatest);
// one that shrank, at the next Best(): level by level from the shrunk
// leaves, or all at once when more than a quarter of the shooters shrank
// or are about to change (Expect).
#ifndef RADIOSITY_SHOOTERS_H
#define RADIOSITY_SHOOTERS_H

#include <cmath>
#include <cstdint>
#include <vector>

#include "memory.h"

class ShooterQueue {
 public:
  // Every bound set at once (-inf or NaN: never chosen), with each
  // shooter's weight (>= 0: how much of the drift applies to it), O(n).
  // The taken stay taken (when n grows, the new ones are not); none is
  // when n shrinks.
  void Build(const std::vector<double>& bounds, const std::vector<double>& weights);
  int size() const { return n_; }

  // Shooter i's bound changed.
  void Set(int i, double bound);
  // About `changes` Set calls follow: when they are more than a quarter of
  // the shooters (a small scene, where one column reaches most patches)
  // the tree is rebuilt at the next Best instead of kept up to date per
  // change.
  void Expect(size_t changes);
  // Taken shooters are not chosen until released.
  void Take(int i);
  void Release(int i);
  bool Taken(int i) const { return taken_[i] != 0; }
  // What Set(i) will touch, fetched early (the owner setting many
  // shooters scattered over arrays larger than the caches).
  void Prefetch(int i) const {
    __builtin_prefetch(&taken_[size_t(i)]);
    __builtin_prefetch(&tree_[leaves_ + size_t(i)], 1);
    __builtin_prefetch(&tree_[(leaves_ + size_t(i)) / 2], 1);  // where a grown bound's walk goes
  }

  // The untaken shooter with the greatest power(i) > 0, ties to the lowest
  // id; -1 when none has power above 0. Requires power(i) <= bound(i) +
  // weight(i) · drift for every i (the owner's promise; drift >= 0, finite).
  template <class Power>
  int Best(double drift, const Power& power);

  // Shooters whose exact power Best() computed since the last Build.
  long Visited() const { return visited_; }

 private:
  static double Clean(double b) { return b == b ? b : -HUGE_VAL; }  // NaN: out
  void Leaf(int i, double value);
  void Flush();

  int n_ = 0;
  size_t leaves_ = 1;  // n rounded up to a power of two
  // Node 1 is the root, node k's children are 2k and 2k+1, shooter i is
  // leaf leaves_ + i (the leaves past n hold -inf). A node holds the
  // greatest bound of the untaken shooters under it.
  // In 2 MB pages (memory.h): a shot sets leaves scattered over them.
  std::vector<double, HugePageAllocator<double>> tree_;
  std::vector<double, HugePageAllocator<double>> weight_;  // the same tree of the weights (taken or not)
  // Per shooter, its bound while it is taken (an untaken one's is its
  // leaf): Set writes one array, not two, for the shooters a shot reaches.
  std::vector<double> bound_;
  std::vector<uint8_t> taken_;
  std::vector<int32_t> dirty_;  // leaves shrunk since the last Flush
  bool rebuild_ = false;        // Expect: every node at the next Flush
  std::vector<int32_t> stack_;  // Best's scratch, and Flush's
  long visited_ = 0;
};

template <class Power>
int ShooterQueue::Best(double drift, const Power& power) {
  int best = -1;
  double best_power = 0;
  if (n_ == 0) return best;
  Flush();
  // Depth first, the larger child first, so that the best is met early
  // and prunes the rest: a node whose bound plus drift is below the best
  // power so far (or not above 0 before any) holds nothing better.
  stack_.clear();
  stack_.push_back(1);
  while (!stack_.empty()) {
    const size_t k = size_t(stack_.back());
    stack_.pop_back();
    const double reach = tree_[k] + weight_[k] * drift;
    if (!(reach >= best_power) || (best < 0 && !(reach > 0))) continue;
    if (k >= leaves_) {
      const int i = int(k - leaves_);
      ++visited_;
      const double p = power(i);
      if (p > best_power || (p == best_power && best >= 0 && i < best)) {
        best_power = p;
        best = i;
      }
      continue;
    }
    const bool left_first = tree_[2 * k] >= tree_[2 * k + 1];
    stack_.push_back(int32_t(left_first ? 2 * k + 1 : 2 * k));
    stack_.push_back(int32_t(left_first ? 2 * k : 2 * k + 1));
  }
  return best;
}

#endif
