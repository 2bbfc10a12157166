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
// pays O(log n) per take, not a scan of what it holds.
//
// The tree has 64 children a node (kFanout): a shot sets the bounds of
// thousands of shooters scattered over the leaves, and in a binary tree
// each level a grown bound climbs was a cache line of its own to wait for
// (at 66,543 shooters the Set calls took as long as the rest of a shot).
// Here the nodes above the leaves are 1/63 of them (9 KB at 66,543
// shooters) and stay in the caches, so a Set costs its leaf's line. A
// bound that grew reaches the inner nodes at once (as far up as it is the
// greatest); one that shrank, at the next Best(): node by node from the
// shrunk leaves, or all at once when they are many or most of the
// shooters are about to change (Expect). Best() looks at a node's 64
// children's reaches in one contiguous pass and visits them greatest
// first.
#ifndef RADIOSITY_SHOOTERS_H
#define RADIOSITY_SHOOTERS_H

#include <cmath>
#include <cstdint>
#include <vector>

#include "check.h"
#include "memory.h"

class ShooterQueue {
 public:
  // Every bound set at once (-inf or NaN: never chosen), with each
  // shooter's weight (>= 0: how much of the drift applies to it), O(n).
  // The taken stay taken (when n grows, the new ones are not); none is
  // when n shrinks.
  void Build(const std::vector<double>& bounds, const std::vector<double>& weights);
  int size() const { return n_; }

  // Shooter i's bound changed. Inline, as what it calls: a shot sets
  // thousands, and a call spills the caller's floating-point registers.
  void Set(int i, double bound) {
    CHECK(i >= 0 && i < n_);
    if (taken_[size_t(i)]) bound_[size_t(i)] = Clean(bound);
    else Leaf(i, Clean(bound));
  }
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
    __builtin_prefetch(&tree_[size_t(i)], 1);
  }

  // The untaken shooter with the greatest power(i) > 0, ties to the lowest
  // id; -1 when none has power above 0. Requires power(i) <= bound(i) +
  // weight(i) · drift for every i (the owner's promise; drift >= 0, finite).
  template <class Power>
  int Best(double drift, const Power& power);

  // Shooters whose exact power Best() computed since the last Build.
  long Visited() const { return visited_; }

  // The addresses Set(i) writes and those it only reads, beyond the inner
  // nodes (which stay in the caches), appended: what a shot waits on per
  // shooter it reaches (Solver::ShotLines).
  void Touches(int i, std::vector<const void*>* written, std::vector<const void*>* read) const {
    written->push_back(&tree_[size_t(i)]);
    read->push_back(&taken_[size_t(i)]);
  }

 private:
  static constexpr size_t kFanout = 64;
  static double Clean(double b) { return b == b ? b : -HUGE_VAL; }  // NaN: out
  void Leaf(int i, double value);
  void Shrunk(int i);
  void Flush();
  // Node k of level l (0: the leaves, shooter i is leaf i).
  double& Node(int l, size_t k) { return tree_[first_[size_t(l)] + k]; }
  double Max(const std::vector<double, HugePageAllocator<double>>& v, int l, size_t k) const;
  void Recompute(std::vector<double, HugePageAllocator<double>>* v) const;
  template <class Power>
  void Visit(int level, size_t node, double drift, const Power& power, int* best, double* best_power);

  int n_ = 0;
  // The levels one after the other, the leaves first, each padded to whole
  // groups of kFanout children (-inf bounds, weight 0), up to the root (one
  // node). first_[l]: where level l starts; first_.size() - 1 is the root's
  // level. A node holds the greatest bound of the untaken shooters under it.
  // In 2 MB pages (memory.h): a shot sets leaves scattered over them.
  std::vector<double, HugePageAllocator<double>> tree_;
  std::vector<double, HugePageAllocator<double>> weight_;  // the same tree of the weights (taken or not)
  std::vector<size_t> first_;
  // Per shooter, its bound while it is taken (an untaken one's is its
  // leaf): Set writes one array, not two, for the shooters a shot reaches.
  std::vector<double> bound_;
  std::vector<uint8_t> taken_;
  std::vector<int32_t> dirty_;  // leaves shrunk since the last Flush
  bool rebuild_ = false;        // Expect: every node at the next Flush
  std::vector<int32_t> scratch_;  // Flush's
  long visited_ = 0;
};

// A bound that grew (light arrived) raises the nodes above it to it, up to
// the first that holds as much: the max of children, one of which grew, is
// the old max or the new value. Nodes above shrunk leaves not yet flushed
// may hold too much and stop the walk early; Flush recomputes them from
// their children later, this leaf's side included.
inline void ShooterQueue::Leaf(int i, double value) {
  const double old = tree_[size_t(i)];
  tree_[size_t(i)] = value;
  if (rebuild_) return;  // all at once at the next Best (Expect)
  if (!(value >= old)) return Shrunk(i);
  // Every level, without a branch: a node holds at least what each child
  // does, so above the first node that holds value every node does too,
  // and the max changes none of them. Where a walk stopped was data (at
  // once for about a quarter of a shot's leaves, after one level for
  // another quarter): a branch the predictor could not learn.
  size_t k = size_t(i);
  for (int l = 1; l < int(first_.size()); ++l) {
    k /= kFanout;
    double& node = Node(l, k);
    node = node >= value ? node : value;
  }
}

template <class Power>
int ShooterQueue::Best(double drift, const Power& power) {
  int best = -1;
  double best_power = 0;
  if (n_ == 0) return best;
  Flush();
  Visit(int(first_.size()) - 1, 0, drift, power, &best, &best_power);
  return best;
}

// Depth first, the child of greatest reach first, so that the best is
// met early and prunes the rest (its siblings then in id order): a node
// whose bound plus drift is below the best power so far (or not above 0
// before any) holds nothing better.
template <class Power>
void ShooterQueue::Visit(int level, size_t node, double drift, const Power& power, int* best,
                         double* best_power) {
  const size_t first = first_[size_t(level) - 1] + node * kFanout;
  double reach[kFanout];
  for (size_t j = 0; j < kFanout; ++j) {
    const double r = tree_[first + j] + weight_[first + j] * drift;
    reach[j] = r == r ? r : -HUGE_VAL;  // -inf + inf (a drift too large to weigh): nothing there
  }
  size_t top = 0;
  for (size_t j = 1; j < kFanout; ++j) top = reach[j] > reach[top] ? j : top;
  auto visit = [&](size_t c) {
    const double r = reach[c];
    if (!(r >= *best_power) || (*best < 0 && !(r > 0))) return;
    const size_t k = node * kFanout + c;
    if (level > 1) {
      Visit(level - 1, k, drift, power, best, best_power);
      return;
    }
    const int i = int(k);
    ++visited_;
    const double p = power(i);
    if (p > *best_power || (p == *best_power && *best >= 0 && i < *best)) {
      *best_power = p;
      *best = i;
    }
  };
  visit(top);
  for (size_t j = 0; j < kFanout; ++j)
    if (j != top) visit(j);
}

#endif
