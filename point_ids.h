// Ids of points welded by exact value (PointHash: -0 and 0 alike), the
// first point seen getting the next id: an open-addressing table over the
// points' own array, so no node is allocated per point (a hash map cost a
// third of BuildMesh at 10^6 faces, and most of joining's welding).
// BuildMesh clears it per face (vertices are never shared across faces);
// joining (surface.cpp) welds the whole scene.
#ifndef RADIOSITY_POINT_IDS_H
#define RADIOSITY_POINT_IDS_H

#include <algorithm>
#include <vector>

#include <glm/glm.hpp>

#include "mesh.h"

class PointIds {
 public:
  // Ids index *points; new points are appended to it.
  explicit PointIds(std::vector<glm::dvec3>* points) : points_(points) {}
  // Room for `points` points without growing on the way.
  void Reserve(size_t points) {
    if (2 * points > table_.size()) {
      size_t size = 64;
      while (size < 2 * points) size *= 2;
      Rehash(size);
    }
  }
  // Forgets the points welded so far (they stay in *points).
  void Clear() {
    for (size_t i : used_) table_[i] = -1;
    used_.clear();
  }
  // Starts loading p's slot of the table, for an Id(p) a little later: a
  // table of millions of points misses the cache at every look-up.
  void Prefetch(const glm::dvec3& p) const {
    if (!table_.empty()) __builtin_prefetch(&table_[PointHash()(p) & (table_.size() - 1)]);
  }
  int Id(const glm::dvec3& p) {
    if (2 * (used_.size() + 1) > table_.size()) Grow();
    const size_t mask = table_.size() - 1;
    size_t i = PointHash()(p) & mask;
    for (; table_[i] >= 0; i = (i + 1) & mask)
      if ((*points_)[size_t(table_[i])] == p) return table_[i];
    table_[i] = int(points_->size());
    used_.push_back(i);
    points_->push_back(p);
    return table_[i];
  }

 private:
  void Grow() { Rehash(std::max<size_t>(64, 2 * table_.size())); }

  void Rehash(size_t size) {
    std::vector<int> ids;
    ids.reserve(used_.size());
    for (size_t i : used_) ids.push_back(table_[i]);
    table_.assign(size, -1);
    used_.clear();
    const size_t mask = table_.size() - 1;
    for (int id : ids) {
      size_t i = PointHash()((*points_)[size_t(id)]) & mask;
      while (table_[i] >= 0) i = (i + 1) & mask;
      table_[i] = id;
      used_.push_back(i);
    }
  }

  std::vector<glm::dvec3>* points_;
  std::vector<int> table_;
  std::vector<size_t> used_;  // slots in use, for Clear and Grow
};

#endif
