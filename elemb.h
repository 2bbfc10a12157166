// Per-element radiosity B, read-only, wherever it is kept: a plain array
// (references, tests) or the solver's records, where each element's B
// sits beside its area (Solver::radiosity(): one cache line a shot waits
// on per element instead of two). A view: it holds no copy, and the
// array it was made from must outlive it.
#ifndef RADIOSITY_ELEMB_H
#define RADIOSITY_ELEMB_H

#include <cstddef>
#include <iterator>
#include <vector>

#include <glm/glm.hpp>

class ElemB {
 public:
  ElemB(const std::vector<glm::dvec3>& b) : ElemB(b.data(), b.size(), sizeof(glm::dvec3)) {}
  // n values, the first at `first`, each `stride` bytes after the last.
  ElemB(const glm::dvec3* first, size_t n, size_t stride)
      : first_(reinterpret_cast<const char*>(first)), n_(n), stride_(stride) {}

  size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  const glm::dvec3& operator[](size_t e) const {
    return *reinterpret_cast<const glm::dvec3*>(first_ + e * stride_);
  }

  class const_iterator {
   public:
    typedef std::forward_iterator_tag iterator_category;
    typedef glm::dvec3 value_type;
    typedef std::ptrdiff_t difference_type;
    typedef const glm::dvec3* pointer;
    typedef const glm::dvec3& reference;
    const_iterator(const ElemB* v, size_t e) : v_(v), e_(e) {}
    reference operator*() const { return (*v_)[e_]; }
    const_iterator& operator++() { ++e_; return *this; }
    bool operator==(const const_iterator& o) const { return e_ == o.e_; }
    bool operator!=(const const_iterator& o) const { return e_ != o.e_; }
   private:
    const ElemB* v_;
    size_t e_;
  };
  typedef const_iterator iterator;
  const_iterator begin() const { return {this, 0}; }
  const_iterator end() const { return {this, n_}; }

  // A copy as a plain array.
  operator std::vector<glm::dvec3>() const { return std::vector<glm::dvec3>(begin(), end()); }

 private:
  const char* first_;
  size_t n_;
  size_t stride_;
};

// The same values (compared as doubles: the same bits but for -0 and NaN).
inline bool operator==(const ElemB& a, const ElemB& b) {
  if (a.size() != b.size()) return false;
  for (size_t e = 0; e < a.size(); ++e)
    if (a[e] != b[e]) return false;
  return true;
}

#endif
