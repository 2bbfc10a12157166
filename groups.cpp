#include "groups.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

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

// A patch as the rule sees it: its plane, centre, corners and extent.
struct PatchInfo {
  glm::dvec3 c{0.0}, n{0.0};
  double offset = 0;
  std::vector<int> corners;  // vertex ids of its elements' corners
  glm::dvec3 lo{0.0}, hi{0.0};  // their bounding box
  bool candidate = false;
};

class Grouper {
 public:
  Grouper(const MeshOptions& opts, Mesh* mesh) : m_(*mesh) {
    // At least patch size / 16: an element then overlaps at most 17 x 17
    // cells of the wall grid below.
    L_ = std::max(opts.group_size > 0 ? opts.group_size : m_.patch_size, m_.patch_size / 16);
    tau_ = L_ / 16;
    lift_ = L_ / 32;
  }

  void Run(Mesh* mesh) {
    Describe();
    std::unordered_map<Cell, std::vector<int>, CellHash> cells;  // candidates, by id
    for (size_t p = 0; p < info_.size(); ++p)
      if (info_[p].candidate) cells[CellOf(info_[p].c)].push_back(int(p));
    if (cells.empty()) return;
    IndexElements(cells);
    std::vector<char> taken(info_.size(), 0);
    std::vector<int> group;
    for (size_t p = 0; p < info_.size(); ++p) {
      if (!info_[p].candidate || taken[p]) continue;
      const std::vector<int>& cell = cells[CellOf(info_[p].c)];
      group.assign(1, int(p));
      taken[p] = 1;
      glm::dvec3 lo = info_[p].lo, hi = info_[p].hi;
      for (int q : cell) {
        if (q <= int(p) || taken[q]) continue;
        if (int(group.size()) == kMaxGroup) break;
        // No wider than a patch: the mesh's own bound on where light
        // leaves from.
        const glm::dvec3 l = glm::min(lo, info_[q].lo), h = glm::max(hi, info_[q].hi);
        if (glm::length(h - l) > L_) continue;
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
  Cell CellOf(const glm::dvec3& x) const {
    return {int64_t(std::floor(x.x / L_)), int64_t(std::floor(x.y / L_)),
            int64_t(std::floor(x.z / L_))};
  }

  void Describe() {
    info_.resize(m_.patches.size());
    for (size_t p = 0; p < m_.patches.size(); ++p) {
      const Patch& pa = m_.patches[p];
      const MeshFace& f = m_.faces[pa.face];
      PatchInfo& in = info_[p];
      in.c = pa.center;
      in.n = f.normal;
      in.offset = f.offset;
      in.lo = in.hi = pa.center;
      for (int e : pa.elements) {
        const Element& el = m_.elems[e];
        for (int k = 0; k < (el.IsTriangle() ? 3 : 4); ++k) {
          if (std::find(in.corners.begin(), in.corners.end(), el.v[k]) == in.corners.end())
            in.corners.push_back(el.v[k]);
          in.lo = glm::min(in.lo, m_.verts[el.v[k]]);
          in.hi = glm::max(in.hi, m_.verts[el.v[k]]);
        }
      }
      // Emitters shoot alone: their direct light is most of the answer.
      const glm::dvec3& ke = f.emission;
      in.candidate = ke.r == 0 && ke.g == 0 && ke.b == 0 && glm::length(in.hi - in.lo) <= L_;
    }
  }

  // Top-level elements by the cells their bounding boxes overlap, only for
  // cells a segment between two candidates can reach (theirs and the
  // neighbours).
  void IndexElements(const std::unordered_map<Cell, std::vector<int>, CellHash>& cand) {
    std::unordered_set<Cell, CellHash> wanted;
    for (const auto& kv : cand)
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz)
            wanted.insert({kv.first.x + dx, kv.first.y + dy, kv.first.z + dz});
    for (size_t p = 0; p < m_.patches.size(); ++p)
      for (int e : m_.patches[p].elements) {
        const Element& el = m_.elems[e];
        glm::dvec3 lo = m_.verts[el.v[0]], hi = lo;
        for (int k = 1; k < (el.IsTriangle() ? 3 : 4); ++k) {
          lo = glm::min(lo, m_.verts[el.v[k]]);
          hi = glm::max(hi, m_.verts[el.v[k]]);
        }
        const Cell a = CellOf(lo), b = CellOf(hi);
        for (int64_t x = a.x; x <= b.x; ++x)
          for (int64_t y = a.y; y <= b.y; ++y)
            for (int64_t z = a.z; z <= b.z; ++z)
              if (wanted.count({x, y, z})) elems_[{x, y, z}].push_back(e);
      }
  }

  // May a and b shoot as one? The rule of groups.h.
  bool Compatible(int a, int b) const {
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
  // of another patch.
  bool Clear(int a, int b) const {
    const glm::dvec3 P = info_[a].c + lift_ * info_[a].n;
    const glm::dvec3 Q = info_[b].c + lift_ * info_[b].n;
    const Cell lo = CellOf(glm::min(P, Q)), hi = CellOf(glm::max(P, Q));
    for (int64_t x = lo.x; x <= hi.x; ++x)
      for (int64_t y = lo.y; y <= hi.y; ++y)
        for (int64_t z = lo.z; z <= hi.z; ++z) {
          auto it = elems_.find({x, y, z});
          if (it == elems_.end()) continue;
          for (int e : it->second)
            if (Crosses(e, P, Q, a, b)) return false;
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
    for (int k = 0; k < n; ++k) {
      const glm::dvec3& u = m_.verts[el.v[k]];
      const glm::dvec3& w = m_.verts[el.v[(k + 1) % n]];
      if (glm::dot(glm::cross(w - u, X - u), f.normal) < -1e-12 * L_ * L_) return false;
    }
    return true;
  }

  const Mesh& m_;
  double L_, tau_, lift_;
  std::vector<PatchInfo> info_;
  std::unordered_map<Cell, std::vector<int>, CellHash> elems_;
};

}  // namespace

void FormGroups(const MeshOptions& opts, Mesh* mesh) {
  mesh->groups.clear();
  mesh->group_of.assign(mesh->patches.size(), -1);
  if (!opts.groups || mesh->patches.empty()) return;
  Grouper(opts, mesh).Run(mesh);
}
