#include "shooters.h"

#include <algorithm>

#include "check.h"

void ShooterQueue::Build(const std::vector<double>& bounds, const std::vector<double>& weights) {
  CHECK(weights.size() == bounds.size());
  if (bounds.size() < size_t(n_)) taken_.clear();
  taken_.resize(bounds.size(), 0);  // a split adds patches: what was taken stays
  n_ = int(bounds.size());
  leaves_ = 1;
  while (leaves_ < bounds.size()) leaves_ *= 2;
  bound_.resize(bounds.size());
  tree_.assign(2 * leaves_, -HUGE_VAL);
  weight_.assign(2 * leaves_, 0);
  for (size_t i = 0; i < bounds.size(); ++i) {
    bound_[i] = Clean(bounds[i]);
    if (!taken_[i]) tree_[leaves_ + i] = bound_[i];
    CHECK(weights[i] >= 0);
    weight_[leaves_ + i] = weights[i];
  }
  for (size_t k = leaves_; k-- > 1;) {
    tree_[k] = std::max(tree_[2 * k], tree_[2 * k + 1]);
    weight_[k] = std::max(weight_[2 * k], weight_[2 * k + 1]);
  }
  dirty_.clear();
  rebuild_ = false;
  visited_ = 0;
}

void ShooterQueue::Expect(size_t changes) {
  if (4 * changes > size_t(n_)) rebuild_ = true;
}

// A bound that grew (light arrived) raises the nodes above it to it, up to
// the first that holds as much: the max of children, one of which grew, is
// the old max or the new value. Nodes above shrunk leaves not yet flushed
// may hold too much and stop the walk early; Flush recomputes them from
// their children later, this leaf's side included.
void ShooterQueue::Leaf(int i, double value) {
  size_t k = leaves_ + size_t(i);
  const double old = tree_[k];
  tree_[k] = value;
  if (rebuild_) return;  // all at once at the next Best (Expect)
  if (value >= old) {
    for (k >>= 1; k >= 1 && tree_[k] < value; k >>= 1) tree_[k] = value;
    return;
  }
  dirty_.push_back(i);
  if (dirty_.size() > size_t(n_)) Flush();  // no Best() for long: bounded all the same
}

// Level by level from the changed leaves up (all leaves are at one depth),
// recomputing each listed node from its children and listing its parent
// only when it changed: a node is recomputed after its children's last
// change, and the nodes near the root that many paths share are
// recomputed once a level, not once a path. Leaves changed in id order (a
// shot's patches mostly are) list each parent once; out of order they
// list some twice, which costs a recomputation and changes nothing.
void ShooterQueue::Flush() {
  if (rebuild_ || 4 * dirty_.size() > size_t(n_)) {
    for (size_t k = leaves_; k-- > 1;) tree_[k] = std::max(tree_[2 * k], tree_[2 * k + 1]);
    dirty_.clear();
    rebuild_ = false;
    return;
  }
  std::vector<int32_t>& level = stack_;
  level.clear();
  for (int32_t i : dirty_) {
    const int32_t node = int32_t((leaves_ + size_t(i)) >> 1);
    if (level.empty() || level.back() != node) level.push_back(node);
  }
  dirty_.clear();
  while (!level.empty()) {
    std::vector<int32_t>& up = dirty_;
    for (int32_t node : level) {
      const size_t k = size_t(node);
      const double m = std::max(tree_[2 * k], tree_[2 * k + 1]);
      if (tree_[k] == m) continue;
      tree_[k] = m;
      if (k > 1 && (up.empty() || up.back() != int32_t(k >> 1))) up.push_back(int32_t(k >> 1));
    }
    level.swap(up);
    up.clear();
  }
}

void ShooterQueue::Set(int i, double bound) {
  CHECK(i >= 0 && i < n_);
  if (taken_[i]) bound_[i] = Clean(bound);
  else Leaf(i, Clean(bound));
}

void ShooterQueue::Take(int i) {
  CHECK(i >= 0 && i < n_ && !taken_[i]);
  taken_[i] = 1;
  bound_[i] = tree_[leaves_ + size_t(i)];
  Leaf(i, -HUGE_VAL);
}

void ShooterQueue::Release(int i) {
  CHECK(i >= 0 && i < n_);
  if (!taken_[i]) return;
  taken_[i] = 0;
  Leaf(i, bound_[i]);
}
