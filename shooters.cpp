#include "shooters.h"

#include <algorithm>

#include "check.h"

void ShooterQueue::Build(const std::vector<double>& bounds) {
  if (bounds.size() != size_t(n_)) taken_.assign(bounds.size(), 0);
  n_ = int(bounds.size());
  bound_.resize(bounds.size());
  tree_.assign(2 * bounds.size(), -HUGE_VAL);
  for (size_t i = 0; i < bounds.size(); ++i) {
    bound_[i] = Clean(bounds[i]);
    if (!taken_[i]) tree_[bounds.size() + i] = bound_[i];
  }
  for (size_t k = bounds.size(); k-- > 1;) tree_[k] = std::max(tree_[2 * k], tree_[2 * k + 1]);
  visited_ = 0;
}

// Up from a leaf, until a node's greatest bound stays as it was (its
// ancestors then stay too).
void ShooterQueue::Update(size_t node, double value) {
  tree_[node] = value;
  for (node >>= 1; node >= 1; node >>= 1) {
    const double m = std::max(tree_[2 * node], tree_[2 * node + 1]);
    if (tree_[node] == m) return;
    tree_[node] = m;
  }
}

void ShooterQueue::Set(int i, double bound) {
  CHECK(i >= 0 && i < n_);
  bound_[i] = Clean(bound);
  if (!taken_[i]) Update(size_t(n_) + size_t(i), bound_[i]);
}

void ShooterQueue::Take(int i) {
  CHECK(i >= 0 && i < n_ && !taken_[i]);
  taken_[i] = 1;
  Update(size_t(n_) + size_t(i), -HUGE_VAL);
}

void ShooterQueue::Release(int i) {
  CHECK(i >= 0 && i < n_);
  if (!taken_[i]) return;
  taken_[i] = 0;
  Update(size_t(n_) + size_t(i), bound_[i]);
}
