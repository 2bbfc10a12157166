#include "groups.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace {

struct Cell {
  int64_t x, y, z;
  bool operator==(const Cell& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellHash {
  size_t operator()(const Cell& c) const {
    return size_t(c.x) * 0x9E3779B97F4A7C15ull ^ size_t(c.y) * 0xC2B2AE3D27D4EB4Full ^
           size_t(c.z);
  }
};
using Grid = std::unordered_map<Cell, std::vector<int>, CellHash>;

Cell CellOf(const glm::dvec3& x, double size) {
  return {int64_t(std::floor(x.x / size)), int64_t(std::floor(x.y / size)),
          int64_t(std::floor(x.z / size))};
}

// A patch as the rule sees it: its plane, centre, corners and extent, and
// how wide a group holding it may be.
struct PatchInfo {
  glm::dvec3 c{0.0}, n{0.0};
  double offset = 0;
  std::vector<int> corners;     // vertex ids of its elements' corners
  glm::dvec3 lo{0.0}, hi{0.0};  // their bounding box
  double limit = 0;             // the widest group it may be in
  bool candidate = false;
};

class Grouper {
 public:
  Grouper(const MeshOptions& opts, Mesh* mesh) : m_(*mesh) {
    const double P = m_.patch_size;
    // At least patch size / 16, as the option says.
    G_ = std::max(opts.group_size > 0 ? opts.group_size : kGroupPatches * P, P / 16);
    C_ = P / 8;
    tau_ = P / 16;
    lift_ = P / 32;
    eps_ = 1e-9 * std::max(m_.scene_diagonal, P);
  }

  void Run(Mesh* mesh) {
    Describe();
    IndexElements();
    Grid cells;  // candidates by cell of G_, by id
    for (size_t p = 0; p < info_.size(); ++p)
      if (info_[p].candidate) cells[CellOf(info_[p].c, G_)].push_back(int(p));
    if (cells.empty()) return;
    std::vector<char> taken(info_.size(), 0);
    std::vector<int> group;
    for (size_t p = 0; p < info_.size(); ++p) {
      if (!info_[p].candidate || taken[p]) continue;
      const std::vector<int>& cell = cells[CellOf(info_[p].c, G_)];
      group.assign(1, int(p));
      taken[p] = 1;
      glm::dvec3 lo = info_[p].lo, hi = info_[p].hi;
      double limit = info_[p].limit;
      int looked = 0;
      for (int q : cell) {
        if (q <= int(p) || taken[q]) continue;
        if (int(group.size()) == kMaxGroup || ++looked > kLookAhead) break;
        // No wider than the nearest receiver of any member allows.
        const glm::dvec3 l = glm::min(lo, info_[q].lo), h = glm::max(hi, info_[q].hi);
        const double lim = std::min(limit, info_[q].limit);
        if (glm::length(h - l) > lim) continue;
        bool ok = true;
        for (int g : group)
          if (!Compatible(g, q)) {
            ok = false;
            break;
          }
        if (!ok) continue;
        group.push_back(q);
        taken[q] = 1;
        lo = l;
        hi = h;
        limit = lim;
      }
      if (group.size() < 2) continue;
      PatchGroup pg;
      pg.members = group;
      for (int q : group) {
        const Patch& pa = m_.patches[q];
        pg.area += pa.area;
        pg.center += pa.area * pa.center;
        pg.normal += pa.area * info_[q].n;
      }
      pg.center /= pg.area;
      pg.normal = glm::normalize(pg.normal);
      for (int q : group) mesh->group_of[q] = int32_t(mesh->groups.size());
      mesh->groups.push_back(std::move(pg));
    }
  }

 private:
  void Describe() {
    info_.resize(m_.patches.size());
    for (size_t p = 0; p < m_.patches.size(); ++p) {
      const Patch& pa = m_.patches[p];
      const IdSpan tops = m_.Tops(int(p));
      const MeshFace& f = m_.faces[pa.face];
      PatchInfo& in = info_[p];
      in.c = pa.center;
      in.n = f.normal;
      in.offset = f.offset;
      in.lo = in.hi = pa.center;
      for (int e : tops) {
        const Element& el = m_.elems[e];
        for (int k = 0; k < (el.IsTriangle() ? 3 : 4); ++k) {
          if (std::find(in.corners.begin(), in.corners.end(), el.v[k]) == in.corners.end())
            in.corners.push_back(el.v[k]);
          in.lo = glm::min(in.lo, m_.verts[el.v[k]]);
          in.hi = glm::max(in.hi, m_.verts[el.v[k]]);
        }
      }
    }
  }

  // Every element by the cells of C_ and of the patch size its bounding box
  // overlaps; then each
  // patch's limit from the nearest element it can light.
  void IndexElements() {
    elo_.resize(m_.elems.size());
    ehi_.resize(m_.elems.size());
    stamp_.assign(m_.elems.size(), 0);
    for (size_t e = 0; e < m_.elems.size(); ++e) {
      const Element& el = m_.elems[e];
      glm::dvec3 lo = m_.verts[el.v[0]], hi = lo;
      for (int k = 1; k < (el.IsTriangle() ? 3 : 4); ++k) {
        lo = glm::min(lo, m_.verts[el.v[k]]);
        hi = glm::max(hi, m_.verts[el.v[k]]);
      }
      elo_[e] = lo;
      ehi_[e] = hi;
      for (auto [grid, cell] : {std::make_pair(&grid_, C_), std::make_pair(&coarse_, m_.patch_size)}) {
        const Cell a = CellOf(lo, cell), b = CellOf(hi, cell);
        for (int64_t x = a.x; x <= b.x; ++x)
          for (int64_t y = a.y; y <= b.y; ++y)
            for (int64_t z = a.z; z <= b.z; ++z) (*grid)[{x, y, z}].push_back(int(e));
      }
    }
    for (size_t p = 0; p < info_.size(); ++p) {
      PatchInfo& in = info_[p];
      // Emitters shoot alone: their direct light is most of the answer.
      const glm::dvec3& ke = m_.faces[m_.patches[p].face].emission;
      if (ke.r != 0 || ke.g != 0 || ke.b != 0) continue;
      // Small patches only: a patch of about the patch size already is the
      // mesh's unit of where light leaves from, and a group of those would
      // cast the shadows of one point over several patches' width.
      const double size = glm::length(in.hi - in.lo);
      if (size > kSmallPatch * m_.patch_size) continue;
      in.limit = std::min(G_, kGroupReach * Nearest(int(p)));
      in.candidate = size <= in.limit;
    }
  }

  // The distance from p's centre to the nearest element (bounding box) that
  // p can light: in front of p's plane, facing p, of another patch; G_ /
  // kGroupReach when none is nearer. Found ring by ring of cells about the
  // centre: after ring r every element nearer than r·cell has been seen.
  // Near receivers in the fine grid, up to kFineRings rings; farther ones,
  // when none is near, in the coarse grid (cell: the patch size), so that
  // a search out to G_ / kGroupReach looks at 9^3 cells, not 65^3.
  double Nearest(int p) {
    double best = G_ / kGroupReach;
    ++stamp_now_;
    Rings(p, grid_, C_, kFineRings, &best);
    if (best > kFineRings * C_) Rings(p, coarse_, m_.patch_size, -1, &best);
    return best;
  }

  // Rings 0, 1, ... (to `last`; -1: as far as needed) of grid cells about
  // p's centre, lowering *best to the nearest element p lights.
  void Rings(int p, const Grid& grid, double cell, int64_t last, double* best) {
    const PatchInfo& in = info_[size_t(p)];
    const Cell c0 = CellOf(in.c, cell);
    // An element at distance δ lies in ring floor(δ / cell) + 1 or nearer.
    for (int64_t r = 0; double(r - 1) * cell < *best && (last < 0 || r <= last); ++r)
      for (int64_t dx = -r; dx <= r; ++dx)
        for (int64_t dy = -r; dy <= r; ++dy) {
          const bool side = std::abs(dx) == r || std::abs(dy) == r;
          for (int64_t dz = -r; dz <= r; dz += side || r == 0 ? 1 : 2 * r) {
            auto it = grid.find({c0.x + dx, c0.y + dy, c0.z + dz});
            if (it == grid.end()) continue;
            for (int e : it->second) {
              if (stamp_[size_t(e)] == stamp_now_) continue;
              stamp_[size_t(e)] = stamp_now_;
              const glm::dvec3 d = glm::max(glm::max(elo_[e] - in.c, in.c - ehi_[e]), 0.0);
              const double dist = glm::length(d);
              if (dist < *best && Lights(p, e)) *best = dist;
            }
          }
        }
  }

  // May light from patch p reach element e: e of another patch, some
  // corner of e in front of p, some corner of p in front of e.
  bool Lights(int p, int e) const {
    const Element& el = m_.elems[size_t(e)];
    if (el.patch == p) return false;
    const PatchInfo& in = info_[size_t(p)];
    bool front = false;
    for (int k = 0; k < (el.IsTriangle() ? 3 : 4) && !front; ++k)
      front = glm::dot(in.n, m_.verts[el.v[k]]) - in.offset > eps_;
    if (!front) return false;
    const MeshFace& f = m_.faces[m_.patches[el.patch].face];
    for (int v : in.corners)
      if (glm::dot(f.normal, m_.verts[v]) - f.offset > eps_) return true;
    return false;
  }

  // May a and b shoot as one? The rule of groups.h.
  bool Compatible(int a, int b) {
    const PatchInfo& A = info_[a];
    const PatchInfo& B = info_[b];
    if (glm::dot(A.n, B.n) < std::cos(kGroupAngle * M_PI / 180)) return false;
    for (int v : B.corners)
      if (glm::dot(A.n, m_.verts[v]) - A.offset < -tau_) return false;
    for (int v : A.corners)
      if (glm::dot(B.n, m_.verts[v]) - B.offset < -tau_) return false;
    return Clear(a, b);
  }

  // The segment between the lifted centres of a and b crosses no element
  // of another patch: the cells it passes through, walked in order
  // (Amanatides & Woo), hold every element it could cross.
  bool Clear(int a, int b) {
    const glm::dvec3 P = info_[a].c + lift_ * info_[a].n;
    const glm::dvec3 Q = info_[b].c + lift_ * info_[b].n;
    const glm::dvec3 d = Q - P;
    Cell c = CellOf(P, C_);
    const Cell end = CellOf(Q, C_);
    int64_t* at[3] = {&c.x, &c.y, &c.z};
    const int64_t last[3] = {end.x, end.y, end.z};
    int step[3];
    double next[3], delta[3];
    for (int i = 0; i < 3; ++i) {
      step[i] = d[i] > 0 ? 1 : d[i] < 0 ? -1 : 0;
      next[i] = step[i] == 0 ? HUGE_VAL : ((double(*at[i]) + (step[i] > 0)) * C_ - P[i]) / d[i];
      delta[i] = step[i] == 0 ? HUGE_VAL : C_ / std::abs(d[i]);
    }
    ++stamp_now_;
    // Rounding may end the walk a cell short or long: at most this many.
    int64_t left = 3;
    for (int i = 0; i < 3; ++i) left += std::abs(last[i] - *at[i]);
    for (; left > 0; --left) {
      auto it = grid_.find(c);
      if (it != grid_.end())
        for (int e : it->second) {
          if (stamp_[size_t(e)] == stamp_now_) continue;
          stamp_[size_t(e)] = stamp_now_;
          if (Crosses(e, P, Q, a, b)) return false;
        }
      if (c == end) break;
      const int i = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
      if (next[i] > 1) break;
      *at[i] += step[i];
      next[i] += delta[i];
    }
    return true;
  }

  bool Crosses(int e, const glm::dvec3& P, const glm::dvec3& Q, int a, int b) const {
    const Element& el = m_.elems[e];
    if (el.patch == a || el.patch == b) return false;
    const MeshFace& f = m_.faces[m_.patches[el.patch].face];
    const double sp = glm::dot(f.normal, P) - f.offset, sq = glm::dot(f.normal, Q) - f.offset;
    if ((sp > 0) == (sq > 0) || sp == sq) return false;
    const glm::dvec3 X = P + (Q - P) * (sp / (sp - sq));
    const int n = el.IsTriangle() ? 3 : 4;
    // Convex, counter-clockwise from the front; on an edge counts as a hit.
    const double P2 = m_.patch_size * m_.patch_size;
    for (int k = 0; k < n; ++k) {
      const glm::dvec3& u = m_.verts[el.v[k]];
      const glm::dvec3& w = m_.verts[el.v[(k + 1) % n]];
      if (glm::dot(glm::cross(w - u, X - u), f.normal) < -1e-12 * P2) return false;
    }
    return true;
  }

  const Mesh& m_;
  double G_, C_, tau_, lift_, eps_;
  std::vector<PatchInfo> info_;
  Grid grid_;                        // elements by the cells of C_ they overlap
  Grid coarse_;                      // ... and by those of the patch size
  std::vector<glm::dvec3> elo_, ehi_;  // their bounding boxes
  std::vector<uint32_t> stamp_;      // per element: last search that looked at it
  uint32_t stamp_now_ = 0;
};

}  // namespace

void FormGroups(const MeshOptions& opts, Mesh* mesh) {
  mesh->groups.clear();
  mesh->group_of.assign(mesh->patches.size(), -1);
  if (!opts.groups || mesh->patches.empty()) return;
  Grouper(opts, mesh).Run(mesh);
}
