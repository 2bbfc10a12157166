#include "shooters.h"

#include <algorithm>

void ShooterQueue::Build(const std::vector<double>& bounds, const std::vector<double>& weights) {
  CHECK(weights.size() == bounds.size());
  if (bounds.size() < size_t(n_)) taken_.clear();
  taken_.resize(bounds.size(), 0);  // a split adds patches: what was taken stays
  n_ = int(bounds.size());
  // Level l + 1 has a node per kFanout of level l's, up to the root.
  first_.assign(1, 0);
  size_t count = bounds.size();
  do {
    const size_t parents = (count + kFanout - 1) / kFanout;
    first_.push_back(first_.back() + parents * kFanout);
    count = parents;
  } while (count > 1);
  bound_.resize(bounds.size());
  tree_.assign(first_.back() + 1, -HUGE_VAL);
  weight_.assign(first_.back() + 1, 0);
  for (size_t i = 0; i < bounds.size(); ++i) {
    bound_[i] = Clean(bounds[i]);
    if (!taken_[i]) tree_[i] = bound_[i];
    CHECK(weights[i] >= 0);
    weight_[i] = weights[i];
  }
  Recompute(&weight_);
  Recompute(&tree_);
  dirty_.clear();
  rebuild_ = false;
  visited_ = 0;
}

// Every inner node of *v from its children, level by level up.
void ShooterQueue::Recompute(std::vector<double, HugePageAllocator<double>>* v) const {
  for (int l = 1; l < int(first_.size()); ++l)
    for (size_t k = 0, nodes = (first_[size_t(l)] - first_[size_t(l) - 1]) / kFanout; k < nodes; ++k)
      (*v)[first_[size_t(l)] + k] = Max(*v, l, k);
}

// The greatest of node k's children (of level l - 1) in v.
double ShooterQueue::Max(const std::vector<double, HugePageAllocator<double>>& v, int l, size_t k) const {
  const double* c = &v[first_[size_t(l) - 1] + k * kFanout];
  double m[4] = {c[0], c[1], c[2], c[3]};  // four chains: a max waits on the last
  for (size_t j = 4; j < kFanout; j += 4)
    for (size_t u = 0; u < 4; ++u) m[u] = std::max(m[u], c[j + u]);
  return std::max(std::max(m[0], m[1]), std::max(m[2], m[3]));
}

void ShooterQueue::Expect(size_t changes) {
  if (4 * changes > size_t(n_)) rebuild_ = true;
}

void ShooterQueue::Shrunk(int i) {
  dirty_.push_back(i);
  if (dirty_.size() > size_t(n_)) Flush();  // no Best() for long: bounded all the same
}

// Level by level from the changed leaves up, recomputing each listed node
// from its children and listing its parent only when it changed: a node
// is recomputed after its children's last change, and the nodes near the
// root that many paths share are recomputed once a level, not once a
// path. Leaves changed in id order (a shot's patches mostly are) list
// each parent once; out of order they list some twice, which costs a
// recomputation and changes nothing. Every node at once (about as dear
// as a node per kFanout leaves changed) when so many shrank.
void ShooterQueue::Flush() {
  if (rebuild_ || kFanout * dirty_.size() > size_t(n_)) {
    Recompute(&tree_);
    dirty_.clear();
    rebuild_ = false;
    return;
  }
  std::vector<int32_t>& level = scratch_;
  level.clear();
  for (int32_t i : dirty_) {
    const int32_t node = int32_t(size_t(i) / kFanout);
    if (level.empty() || level.back() != node) level.push_back(node);
  }
  dirty_.clear();
  for (int l = 1; !level.empty(); ++l) {
    std::vector<int32_t>& up = dirty_;
    for (int32_t node : level) {
      const size_t k = size_t(node);
      const double m = Max(tree_, l, k);
      if (Node(l, k) == m) continue;
      Node(l, k) = m;
      const int32_t parent = int32_t(k / kFanout);
      if (l + 1 < int(first_.size()) && (up.empty() || up.back() != parent)) up.push_back(parent);
    }
    level.swap(up);
    up.clear();
  }
}

void ShooterQueue::Take(int i) {
  CHECK(i >= 0 && i < n_ && !taken_[i]);
  taken_[i] = 1;
  bound_[i] = tree_[size_t(i)];
  Leaf(i, -HUGE_VAL);
}

void ShooterQueue::Release(int i) {
  CHECK(i >= 0 && i < n_);
  if (!taken_[i]) return;
  taken_[i] = 0;
  Leaf(i, bound_[i]);
}
