#include "shooters.h"

#include <algorithm>

#include "check.h"

void ShooterQueue::Build(const std::vector<double>& bounds, const std::vector<double>& weights) {
  CHECK(weights.size() == bounds.size());
  if (bounds.size() < size_t(n_)) taken_.clear();
  taken_.resize(bounds.size(), 0);  // a split adds patches: what was taken stays
  n_ = int(bounds.size());
  bound_.resize(bounds.size());
  tree_.assign(2 * bounds.size(), -HUGE_VAL);
  weight_.assign(2 * bounds.size(), 0);
  for (size_t i = 0; i < bounds.size(); ++i) {
    bound_[i] = Clean(bounds[i]);
    if (!taken_[i]) tree_[bounds.size() + i] = bound_[i];
    CHECK(weights[i] >= 0);
    weight_[bounds.size() + i] = weights[i];
  }
  for (size_t k = bounds.size(); k-- > 1;) {
    tree_[k] = std::max(tree_[2 * k], tree_[2 * k + 1]);
    weight_[k] = std::max(weight_[2 * k], weight_[2 * k + 1]);
  }
  dirty_.clear();
  visited_ = 0;
}

void ShooterQueue::Leaf(int i, double value) {
  tree_[size_t(n_) + size_t(i)] = value;
  dirty_.push_back(i);
  if (dirty_.size() > size_t(n_)) Flush();  // no Best() for long: bounded all the same
}

// Up from each changed leaf, recomputing each node from its children,
// until one stays as it was: a node is recomputed after any change of a
// child, so the tree is right however the paths overlap.
void ShooterQueue::Flush() {
  if (4 * dirty_.size() > size_t(n_)) {
    for (size_t k = size_t(n_); k-- > 1;) tree_[k] = std::max(tree_[2 * k], tree_[2 * k + 1]);
  } else {
    for (int32_t i : dirty_)
      for (size_t node = (size_t(n_) + size_t(i)) >> 1; node >= 1; node >>= 1) {
        const double m = std::max(tree_[2 * node], tree_[2 * node + 1]);
        if (tree_[node] == m) break;
        tree_[node] = m;
      }
  }
  dirty_.clear();
}

void ShooterQueue::Set(int i, double bound) {
  CHECK(i >= 0 && i < n_);
  bound_[i] = Clean(bound);
  if (!taken_[i]) Leaf(i, bound_[i]);
}

void ShooterQueue::Take(int i) {
  CHECK(i >= 0 && i < n_ && !taken_[i]);
  taken_[i] = 1;
  Leaf(i, -HUGE_VAL);
}

void ShooterQueue::Release(int i) {
  CHECK(i >= 0 && i < n_);
  if (!taken_[i]) return;
  taken_[i] = 0;
  Leaf(i, bound_[i]);
}
