#include "groups.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "check.h"
#include "float_round.h"
#include "memory.h"
#include "radix_sort.h"

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

// A patch as the rule sees it besides what the mesh keeps (its centre,
// its face's plane, its top elements' corners): its extent, and what is
// known so far of the distance to its nearest receiver (Fits). 64 bytes
// a patch, not 136 with copies of the centre and plane and a list of
// corners: at 10^6 elements, beside the whole mesh and the scene, the
// group search was the master's peak.
struct PatchInfo {
  glm::dvec3 lo{0.0}, hi{0.0};  // its elements' corners' bounding box
  double near = 0, far = 0;     // the distance is at least near, at most far
  bool candidate = false;
};

// A patch asking for its nearest receiver (Grouper::Nearest): what every
// test of the search reads, gathered once.
struct Query {
  int p;
  const glm::dvec3& c;   // its centre
  const glm::dvec3& n;   // its face's plane
  double offset;
  const PatchInfo& in;
};

// An element's bounding box in float, rounded outward: it holds the box
// in double, so the distance from a point to it is never larger (each
// step of BoxDistance is monotonic), and an element no nearer by it is no
// nearer by the exact box (Grouper::Nearer). 24 bytes an element, not 48.
struct FloatBox {
  glm::vec3 lo, hi;
};

// A box of the tree of elements (Grouper::BuildTree): their bounding box,
// and of their planes the normals' bounding box and the least offset.
struct Box {
  glm::dvec3 lo{0.0}, hi{0.0};
  glm::dvec3 nlo{0.0}, nhi{0.0};
  double off = 0;
  // A slab over the elements' corners: dot(nr, v) <= top for each (nr the
  // plane of its first element's patch; up to rounding, Grouper::slack_).
  // Thin where the elements lie in about one plane, as a tilted wall's
  // whose box its plane crosses: the box alone cannot tell that none of
  // them is in front of a patch of that wall (Worth).
  glm::dvec3 nr{0.0};
  double top = 0;
};
// A box of the tree to look into (Grouper::Nearest): levels_[level][i].
struct Visit {
  double d;  // the box's distance from the patch's centre
  int level, i;
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
    // Candidates by cell of G_, by id, with their boxes: a first member's
    // look ahead reads them in a row.
    struct Entry {
      int id;
      glm::dvec3 lo, hi;
    };
    std::unordered_map<Cell, std::vector<Entry>, CellHash> cells;
    for (size_t p = 0; p < info_.size(); ++p)
      if (info_[p].candidate)
        cells[CellOf(m_.patch_center[p], G_)].push_back({int(p), info_[p].lo, info_[p].hi});
    if (cells.empty()) return;
    std::vector<char> taken(info_.size(), 0);
    std::vector<int> group;
    for (size_t p = 0; p < info_.size(); ++p) {
      if (!info_[p].candidate || taken[p]) continue;
      const std::vector<Entry>& cell = cells[CellOf(m_.patch_center[p], G_)];
      group.assign(1, int(p));
      taken[p] = 1;
      glm::dvec3 lo = info_[p].lo, hi = info_[p].hi;
      int looked = 0;
      for (auto it = std::upper_bound(cell.begin(), cell.end(), int(p),
                                      [](int id, const Entry& e) { return id < e.id; });
           it != cell.end(); ++it) {
        const int q = it->id;
        if (taken[q]) continue;
        if (int(group.size()) == kMaxGroup || ++looked > kLookAhead) break;
        const glm::dvec3 l = glm::min(lo, it->lo), h = glm::max(hi, it->hi);
        const double width = glm::length(h - l);
        // The rule's tests (the answer is their conjunction, and none
        // depends on what the others found: Fits' bounds only save it
        // searches), cheapest first: no wider than what is known of each
        // member's nearest receiver allows, the normals, then the
        // searches that finish that (most pairs of a room of boxes face
        // different ways: no search for them), then the planes, then the
        // segments.
        auto all = [&](auto test) {
          return std::all_of(group.begin(), group.end(), test);
        };
        if (!all([&](int g) { return MayFit(g, width); }) || !MayFit(q, width) ||
            !all([&](int g) { return Parallel(g, q); }) ||
            !all([&](int g) { return Fits(g, width); }) || !Fits(q, width) ||
            !all([&](int g) { return Alike(g, q); }) ||
            !all([&](int g) { return Clear(g, q); }))
          continue;
        group.push_back(q);
        taken[q] = 1;
        lo = l;
        hi = h;
      }
      if (group.size() < 2) continue;
      PatchGroup pg;
      pg.members = group;
      for (int q : group) {
        const double a = m_.patch_area[size_t(q)];
        pg.area += a;
        pg.center += a * m_.patch_center[size_t(q)];
        pg.normal += a * Plane(q).normal;
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
      PatchInfo& in = info_[p];
      in.lo = in.hi = m_.patch_center[p];
      AnyCorner(int(p), [&](const glm::dvec3& v) {
        in.lo = glm::min(in.lo, v);
        in.hi = glm::max(in.hi, v);
        return false;
      });
    }
  }

  // The plane of patch p: its face's.
  const MeshFace& Plane(int p) const { return m_.faces[size_t(m_.patches[size_t(p)].face)]; }

  // Whether f(v) holds for some corner v of patch p's top elements, asked
  // of each in turn until one does (a corner two elements share is asked
  // twice: the rule's tests ask whether any or all of them pass, which a
  // repeat does not change).
  template <class F>
  bool AnyCorner(int p, F f) const {
    for (int e : m_.Tops(p)) {
      const Element& el = m_.elems[size_t(e)];
      for (int k = 0; k < (el.IsTriangle() ? 3 : 4); ++k)
        if (f(m_.verts[size_t(el.v[k])])) return true;
    }
    return false;
  }

  // Element el's bounding box, in double.
  void Bound(const Element& el, glm::dvec3* lo, glm::dvec3* hi) const {
    *lo = *hi = m_.verts[size_t(el.v[0])];
    for (int k = 1; k < (el.IsTriangle() ? 3 : 4); ++k) {
      *lo = glm::min(*lo, m_.verts[size_t(el.v[k])]);
      *hi = glm::max(*hi, m_.verts[size_t(el.v[k])]);
    }
  }

  // Every element's bounding box, and a tree of them; then which patches
  // are candidates.
  void IndexElements() {
    BuildTree(false);
    for (size_t p = 0; p < info_.size(); ++p) {
      PatchInfo& in = info_[p];
      // Emitters shoot alone: their direct light is most of the answer.
      const glm::dvec3& ke = m_.Emission(Plane(int(p)));
      if (ke.r != 0 || ke.g != 0 || ke.b != 0) continue;
      // Small patches only: a patch of about the patch size already is the
      // mesh's unit of where light leaves from, and a group of those would
      // cast the shadows of one point over several patches' width.
      const double size = glm::length(in.hi - in.lo);
      if (size > kSmallPatch * m_.patch_size) continue;
      in.far = G_ / kGroupReach;
      in.candidate = Fits(int(p), size);
    }
  }

  // May patch p be in a group `width` across: width <= min(G, kGroupReach
  // · d(p)), d(p) its distance to the nearest element it can light (G /
  // kGroupReach when none is nearer). The first question, whether p is a
  // candidate, looks only as far as p's size (most small patches of a
  // dense scene are not); a later one, from a partner that faces alike,
  // finds d(p) (a group grows, and asks again); what was found is kept.
  bool Fits(int p, double width) {
    PatchInfo& in = info_[size_t(p)];
    if (!MayFit(p, width)) return false;
    if (width <= kGroupReach * in.near) return true;
    const double within = in.near > 0 ? G_ / kGroupReach : width / kGroupReach;
    const double d = Nearest(p, within, width);
    if (d < within) in.far = d;                      // an element it lights, that far
    if (kGroupReach * d >= width) in.near = d;       // none nearer (the search ran out)
    return kGroupReach * d >= width;
  }

  // Fits(p, width) unless what is known of d(p) already says no.
  bool MayFit(int p, double width) const {
    return width <= G_ && kGroupReach * info_[size_t(p)].far >= width;
  }

  // A bounding-volume tree of the elements' boxes: the elements in the
  // Morton order of their boxes' centres, kLeaf to a leaf, each level
  // above the union of two boxes of the one below, up to one root; by
  // facing, first by the way their patches face (the axis nearest the
  // normal, and its sign), then in that order. The order is only the
  // search's speed: every search is exact whatever the tree (Nearest), so
  // the codes are coarse enough to hold the element's id below them, and
  // sorted by radix (stable: ties stay in id order).
  //
  // Candidacy searches the tree in Morton order: a small patch's nearest
  // receiver is mostly a patch beside it that faces another way (the
  // floor by a box's side), in its own leaf or one near it. The searches
  // for d(p) in full (Run) search the tree by facing: at a seam (a wall
  // and the ceiling, finely tessellated) a Morton leaf holds elements of
  // both, its box lies across the plane of either and in reach of it, so
  // every search from either surface scanned every seam leaf in reach,
  // while a leaf of one facing is passed whole (Worth).
  void BuildTree(bool by_facing) {
    const size_t n = m_.elems.size();
    CHECK(n <= size_t{1} << kIdBits);
    // A tree built again (by facing) is built without the old one beside.
    FreeStorage(&box_);
    FreeStorage(&levels_);
    // The codes' box: the vertices' (the elements' corners and perhaps a
    // few more: any box orders them).
    glm::dvec3 lo(0.0), hi(0.0), a, b;
    for (size_t v = 0; v < m_.verts.size(); ++v) {
      lo = v ? glm::min(lo, m_.verts[v]) : m_.verts[v];
      hi = v ? glm::max(hi, m_.verts[v]) : m_.verts[v];
    }
    // Every dot product and sum of the slabs' bounds and of the tests they
    // stand for is of terms at most about 2 |x| + |y| + |z| of some
    // vertex: their rounding, even summed up the tree's levels, stays far
    // below this.
    const glm::dvec3 far = glm::max(glm::abs(lo), glm::abs(hi));
    slack_ = 1e-12 * (far.x + far.y + far.z);
    // By facing, an axis gives a bit to the facing's three.
    const int bits = by_facing ? kAxisBits - 1 : kAxisBits;
    const glm::dvec3 scale = double(1 << bits) / glm::max(hi - lo, glm::dvec3(1e-300));
    std::vector<uint64_t> keyed(n);
    for (size_t e = 0; e < n; ++e) {
      Bound(m_.elems[e], &a, &b);
      const glm::dvec3 q =
          glm::clamp((0.5 * (a + b) - lo) * scale, 0.0, double((1 << bits) - 1));
      uint64_t facing = 0;
      if (by_facing) {
        const glm::dvec3& nn = Plane(m_.elems[e].patch).normal;
        const glm::dvec3 an = glm::abs(nn);
        const int axis = an.x >= an.y && an.x >= an.z ? 0 : an.y >= an.z ? 1 : 2;
        facing = uint64_t(2 * axis + (nn[axis] < 0));
      }
      keyed[e] = (facing << 3 * bits | Spread(uint64_t(q.x)) | Spread(uint64_t(q.y)) << 1 |
                  Spread(uint64_t(q.z)) << 2)
                     << kIdBits |
                 e;
    }
    RadixSort(&keyed, [](uint64_t k) { return k; }, kIdBits);
    order_.resize(n);
    std::vector<int32_t> slot(n);
    for (size_t i = 0; i < n; ++i) {
      order_[i] = int(keyed[i] & ((uint64_t{1} << kIdBits) - 1));
      slot[size_t(order_[i])] = int32_t(i);
    }
    FreeStorage(&keyed);
    // The boxes in the tree's order (a leaf's are read in a row), in float
    // (FloatBox), written to their places as the mesh is read in its own
    // order (read in the tree's, it waited on a cache miss an element),
    // and the leaves made as their elements come, from the boxes in
    // double and the corners' most in front along the face's normal (the
    // slab; its plane the first element's to come). Not from the float
    // boxes: a wall's elements, flat in its plane, must stay on it to the
    // eps_ that Side and the slab allow, which float's rounding is not
    // (the searches from the tessellated box's tiles took 2 to 17 times
    // as long). And each patch's home: the leaf of its first top element.
    box_.resize(n);
    home_.assign(m_.patches.size(), -1);
    levels_.assign(1, std::vector<Box>((n + kLeaf - 1) / kLeaf));
    std::vector<bool> made(levels_[0].size(), false);
    for (size_t e = 0; e < n; ++e) {
      const size_t i = size_t(slot[e]);
      const Element& el = m_.elems[e];
      Bound(el, &a, &b);
      box_[i] = {{FloatDown(a.x), FloatDown(a.y), FloatDown(a.z)},
                {FloatUp(b.x), FloatUp(b.y), FloatUp(b.z)}};
      const Patch& pa = m_.patches[size_t(el.patch)];
      const MeshFace& f = m_.faces[size_t(pa.face)];
      double top = glm::dot(f.normal, m_.verts[size_t(el.v[0])]);
      for (int k = 1; k < (el.IsTriangle() ? 3 : 4); ++k)
        top = std::max(top, glm::dot(f.normal, m_.verts[size_t(el.v[k])]));
      if (m_.patch_tops[size_t(pa.tops_at)] == int32_t(e)) home_[size_t(el.patch)] = int(i / kLeaf);
      Extend(&levels_[0][i / kLeaf], {a, b, f.normal, f.normal, f.offset, f.normal, top},
             !made[i / kLeaf]);
      made[i / kLeaf] = true;
    }
    FreeStorage(&slot);
    while (levels_.back().size() > 1) {
      const std::vector<Box>& below = levels_.back();
      std::vector<Box> up((below.size() + 1) / 2);
      for (size_t i = 0; i < below.size(); ++i) Extend(&up[i / 2], below[i], i % 2 == 0);
      levels_.push_back(std::move(up));
    }
    by_facing_ = by_facing;
    recent_.fill(-1);  // places in the order before
  }

  // b made to hold o too (to be o, when b holds nothing yet).
  static void Extend(Box* b, const Box& o, bool first) {
    if (first) {
      *b = o;
      return;
    }
    b->lo = glm::min(b->lo, o.lo);
    b->hi = glm::max(b->hi, o.hi);
    b->nlo = glm::min(b->nlo, o.nlo);
    b->nhi = glm::max(b->nhi, o.nhi);
    b->off = std::min(b->off, o.off);
    // dot(b.nr, v) = dot(o.nr, v) + dot(b.nr - o.nr, v), v in o's box.
    b->top = std::max(b->top, o.top + Support(b->nr - o.nr, o.lo, o.hi));
  }

  // The most dot(d, x) reaches over box lo, hi (up to rounding).
  static double Support(const glm::dvec3& d, const glm::dvec3& lo, const glm::dvec3& hi) {
    return std::max(d.x * lo.x, d.x * hi.x) + std::max(d.y * lo.y, d.y * hi.y) +
           std::max(d.z * lo.z, d.z * hi.z);
  }

  // May an element in b face patch p: some point of p's box in front of
  // its plane (Lights, LightsBox)? Each term of the dot product bounded by
  // the largest over the corners of the normals' box and p's box, summed
  // in glm::dot's order, less the least offset: rounding is monotonic, so
  // no element b holds is farther in front than this.
  bool MayFace(const Box& b, const PatchInfo& in) const {
    glm::dvec3 m;
    for (int i = 0; i < 3; ++i)
      m[i] = std::max(std::max(b.nlo[i] * in.lo[i], b.nlo[i] * in.hi[i]),
                      std::max(b.nhi[i] * in.lo[i], b.nhi[i] * in.hi[i]));
    return m.x + m.y + m.z - b.off > eps_;
  }

  // The bits of x (kAxisBits, at most 21) spread to every third bit: one
  // axis of a Morton code.
  static uint64_t Spread(uint64_t x) {
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
  }

  // The distance from c to box lo, hi (0 inside). Rounding keeps it
  // monotonic: a box holding another is never farther than it.
  static double BoxDistance(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dvec3& c) {
    return glm::length(glm::max(glm::max(lo - c, c - hi), 0.0));
  }

  // The distance from p's centre to the nearest element (bounding box) that
  // p can light: in front of p's plane, facing p, of another patch; `within`
  // when none is nearer. Down the tree, past every box no nearer than the
  // best so far, wholly on or behind p's plane (its corner farthest in
  // front is not in front) or facing away from p (MayFace): the exact least
  // distance, whatever the order of the search; or, as soon as one is found
  // nearer than `width` / kGroupReach (p cannot be in a group that wide
  // then: the least is nearer still), that one.
  double Nearest(int p, double within, double width) {
    const MeshFace& f = Plane(p);
    const Query s{p, m_.patch_center[size_t(p)], f.normal, f.offset, info_[size_t(p)]};
    double best = within;
    if (order_.empty()) return best;
    // Only candidacy asks no farther than the width (Fits). The full
    // searches start in Morton order, and change to the order by facing
    // once they have scanned four times as many leaves as the tree has,
    // about what building it again costs: a room of boxes, where they
    // scan a few leaves each (about one a leaf of the tree in all), never
    // pays for it; the tessellated box, where they scan the seams, pays
    // once, early.
    const bool full = !(kGroupReach * within <= width);
    if (full && !by_facing_ && full_leaves_ > 4 * levels_[0].size()) BuildTree(true);
    // The elements that were nearest for the last few searches first
    // (patches come in mesh order, neighbours after one another): one of
    // them often ends the search at once, or bounds it.
    int found = -1;
    for (int k : recent_)
      if (k >= 0 && Nearer(s, size_t(k), &best)) found = k;
    auto remember = [&] {
      if (found < 0 || std::find(recent_.begin(), recent_.end(), found) != recent_.end()) return;
      std::rotate(recent_.rbegin(), recent_.rbegin() + 1, recent_.rend());
      recent_[0] = found;
    };
    // Then the leaf of p's first element: its neighbours in the tree's
    // order are near it.
    const int home = home_[size_t(p)];
    if (home >= 0 && !(kGroupReach * best < width)) {
      ScanLeaf(s, home, &best, &found);
      full_leaves_ += full;
    }
    if (kGroupReach * best < width) {
      remember();
      return best;
    }
    // Any element nearer than `within` ends the search: depth first, the
    // nearer child first, the first one found. With the home leaf scanned,
    // the rest of the tree is the siblings of the boxes that hold it: they
    // are looked into from the home leaf up, the nearest in the tree's
    // order first (its receiver is mostly beside it), and the path from
    // the root down to p, which every search passed, is not walked.
    if (!full) {
      stack_.clear();
      if (home < 0) {
        Visit root{0, int(levels_.size()) - 1, 0};
        if (Worth(s, best, &root)) stack_.push_back(root);
        Descend(s, &best, &found);
      }
      for (int level = 0; home >= 0 && level + 1 < int(levels_.size()) && found < 0; ++level) {
        Visit sibling{0, level, (home >> level) ^ 1};
        if (size_t(sibling.i) < levels_[size_t(level)].size() && Worth(s, best, &sibling)) {
          stack_.push_back(sibling);
          Descend(s, &best, &found);
        }
      }
      remember();
      return best;
    }
    // Best first: the box nearest p's centre next, so that the search
    // ends at the first box no nearer than the best element so far; from
    // the siblings of the boxes that hold the home leaf, as above.
    heap_.clear();
    auto push = [&](int level, int i) {
      Visit v{0, level, i};
      if (!Worth(s, best, &v)) return;
      heap_.push_back(v);
      std::push_heap(heap_.begin(), heap_.end(), Farther);
    };
    if (home < 0) push(int(levels_.size()) - 1, 0);
    for (int level = 0; home >= 0 && level + 1 < int(levels_.size()); ++level)
      if (size_t((home >> level) ^ 1) < levels_[size_t(level)].size())
        push(level, (home >> level) ^ 1);
    while (!heap_.empty() && heap_.front().d < best) {
      std::pop_heap(heap_.begin(), heap_.end(), Farther);
      const Visit v = heap_.back();
      heap_.pop_back();
      if (v.level == 0) {
        ScanLeaf(s, v.i, &best, &found);
        ++full_leaves_;
        if (kGroupReach * best < width) break;
        continue;
      }
      const size_t below = levels_[size_t(v.level) - 1].size();
      for (int c = 2 * v.i; c <= 2 * v.i + 1 && size_t(c) < below; ++c) push(v.level - 1, c);
    }
    remember();
    return best;
  }

  // Nearest's depth-first search of the boxes on stack_ and below them,
  // until an element nearer than *best is found (*found).
  void Descend(const Query& s, double* best, int* found) {
    while (!stack_.empty() && *found < 0) {
      const Visit v = stack_.back();
      stack_.pop_back();
      if (v.level == 0) {
        ScanLeaf(s, v.i, best, found);
        continue;
      }
      const size_t below = levels_[size_t(v.level) - 1].size();
      Visit a{0, v.level - 1, 2 * v.i}, b{0, v.level - 1, 2 * v.i + 1};
      const bool has_a = Worth(s, *best, &a), has_b = size_t(b.i) < below && Worth(s, *best, &b);
      if (has_a && has_b && a.d < b.d) std::swap(a, b);
      if (has_a) stack_.push_back(a);
      if (has_b) stack_.push_back(b);
    }
  }

  // Is box v of the tree worth looking into for p's receivers nearer than
  // best: not as far, not wholly on or behind p's plane (its box, or its
  // slab: bounded with slack_ to spare, no corner farther in front than
  // eps_, as Lights computes it), not facing away.
  // Sets v's distance.
  bool Worth(const Query& s, double best, Visit* v) const {
    const Box& b = levels_[size_t(v->level)][size_t(v->i)];
    v->d = BoxDistance(b.lo, b.hi, s.c);
    return v->d < best && Side(b.lo, b.hi, s.n, s.offset) >= 0 && MayFace(b, s.in) &&
           b.top + Support(s.n - b.nr, b.lo, b.hi) - s.offset > eps_ - slack_;
  }

  // The elements of leaf i that s lights nearer than *best: *best the
  // nearest one's distance, *found its place.
  void ScanLeaf(const Query& s, int i, double* best, int* found) const {
    for (size_t k = size_t(i) * kLeaf, end = std::min(order_.size(), k + kLeaf); k < end; ++k)
      if (Nearer(s, k, best)) *found = int(k);
  }

  // Whether s lights the element at place k of the tree's order nearer
  // than *best, by its bounding box in double: then *best is that
  // distance. Its float box (box_) rules out most at once, nearer by
  // rounding as it may be; only the rest are read from the mesh.
  bool Nearer(const Query& s, size_t k, double* best) const {
    const FloatBox& fb = box_[k];
    if (!(BoxDistance(glm::dvec3(fb.lo), glm::dvec3(fb.hi), s.c) < *best)) return false;
    const Element& el = m_.elems[size_t(order_[k])];
    if (el.patch == s.p) return false;
    glm::dvec3 lo, hi;
    Bound(el, &lo, &hi);
    const double dist = BoxDistance(lo, hi, s.c);
    if (!(dist < *best) || !LightsBox(s, el, lo, hi)) return false;
    *best = dist;
    return true;
  }

  // Where box lo, hi lies against plane dot(n, x) == offset: +1 wholly in
  // front (every point farther than eps_), -1 wholly not, 0 across. A
  // corner inside the box is no farther in front than the box's farthest
  // corner, nor nearer than its nearest (rounding is monotonic), so a
  // box's answer is its corners' answer.
  int Side(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dvec3& n, double offset) const {
    const glm::dvec3 far(n.x >= 0 ? hi.x : lo.x, n.y >= 0 ? hi.y : lo.y, n.z >= 0 ? hi.z : lo.z);
    if (!(glm::dot(n, far) - offset > eps_)) return -1;
    const glm::dvec3 near(n.x >= 0 ? lo.x : hi.x, n.y >= 0 ? lo.y : hi.y, n.z >= 0 ? lo.z : hi.z);
    return glm::dot(n, near) - offset > eps_ ? 1 : 0;
  }

  // Lights(s, el) for element el of another patch, its bounding box lo,
  // hi: decided from the two bounding boxes where they lie wholly on one
  // side of the other's plane, from the corners only where they do not.
  bool LightsBox(const Query& s, const Element& el, const glm::dvec3& lo,
                 const glm::dvec3& hi) const {
    const int front = Side(lo, hi, s.n, s.offset);
    if (front < 0) return false;
    const MeshFace& other = Plane(el.patch);
    const int back = Side(s.in.lo, s.in.hi, other.normal, other.offset);
    if (back < 0) return false;
    if (front > 0 && back > 0) return true;
    return Lights(s, el);
  }

  // May light from patch s.p reach element el of another patch: some
  // corner of el in front of s.p, some corner of s.p in front of el.
  bool Lights(const Query& s, const Element& el) const {
    bool front = false;
    for (int k = 0; k < (el.IsTriangle() ? 3 : 4) && !front; ++k)
      front = glm::dot(s.n, m_.verts[size_t(el.v[k])]) - s.offset > eps_;
    if (!front) return false;
    const MeshFace& f = Plane(el.patch);
    return AnyCorner(s.p,
                     [&](const glm::dvec3& v) { return glm::dot(f.normal, v) - f.offset > eps_; });
  }

  // Are a's and b's normals within kGroupAngle?
  bool Parallel(int a, int b) const {
    return !(glm::dot(Plane(a).normal, Plane(b).normal) < std::cos(kGroupAngle * M_PI / 180));
  }

  // May a and b, Parallel, shoot as one, as far as their planes tell? The
  // rule of groups.h but the normals and the segment between them (Clear).
  bool Alike(int a, int b) const {
    const MeshFace& A = Plane(a);
    const MeshFace& B = Plane(b);
    // Some corner of patch p behind f's plane by more than tau_.
    auto behind = [&](const MeshFace& f, int p) {
      return AnyCorner(
          p, [&](const glm::dvec3& v) { return glm::dot(f.normal, v) - f.offset < -tau_; });
    };
    return !behind(A, b) && !behind(B, a);
  }

  // Every element by the cells of C_ its bounding box overlaps (in the
  // tree's order: Clear's answer does not depend on it): made when the
  // first pair is tested (a scene where no two candidates meet needs none).
  // A cell's elements in runs of one plane (their patches' normal and
  // offset, equal as doubles: Crosses' sides of it come out the same),
  // each run after its length, negated: a segment
  // that the plane does not cross crosses none of them (Clear), as the
  // floor's dozens of elements in a cell at a fine tessellation, under
  // every segment between two floor patches.
  void IndexGrid() {
    stamp_.assign(m_.elems.size(), 0);
    glm::dvec3 lo, hi;
    for (size_t k = 0; k < order_.size(); ++k) {
      Bound(m_.elems[size_t(order_[k])], &lo, &hi);
      const Cell a = CellOf(lo, C_), b = CellOf(hi, C_);
      for (int64_t x = a.x; x <= b.x; ++x)
        for (int64_t y = a.y; y <= b.y; ++y)
          for (int64_t z = a.z; z <= b.z; ++z) grid_[{x, y, z}].push_back(order_[k]);
    }
    auto plane = [&](int e) {
      const MeshFace& f = Plane(m_.elems[size_t(e)].patch);
      return std::array<double, 4>{f.normal.x, f.normal.y, f.normal.z, f.offset};
    };
    std::vector<int> runs;
    for (auto& cell : grid_) {
      std::vector<int>& list = cell.second;
      std::stable_sort(list.begin(), list.end(), [&](int a, int b) { return plane(a) < plane(b); });
      runs.clear();
      for (size_t i = 0, j; i < list.size(); i = j) {
        for (j = i + 1; j < list.size() && plane(list[j]) == plane(list[i]);) ++j;
        runs.push_back(-int(j - i));
        runs.insert(runs.end(), list.begin() + long(i), list.begin() + long(j));
      }
      list.swap(runs);
    }
    FreeStorage(&runs);
  }

  // The segment between the lifted centres of a and b crosses no element
  // of another patch: the cells it passes through, walked in order
  // (Amanatides & Woo), hold every element it could cross.
  bool Clear(int a, int b) {
    if (grid_.empty()) IndexGrid();
    const glm::dvec3 P = m_.patch_center[size_t(a)] + lift_ * Plane(a).normal;
    const glm::dvec3 Q = m_.patch_center[size_t(b)] + lift_ * Plane(b).normal;
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
      if (it != grid_.end()) {
        const std::vector<int>& list = it->second;
        for (size_t r = 0, len; r < list.size(); r += 1 + len) {
          len = size_t(-list[r]);
          // Crosses' first test, for the run's plane.
          const MeshFace& f = Plane(m_.elems[size_t(list[r + 1])].patch);
          const double sp = glm::dot(f.normal, P) - f.offset, sq = glm::dot(f.normal, Q) - f.offset;
          if ((sp > 0) == (sq > 0) || sp == sq) continue;
          for (size_t k = r + 1; k <= r + len; ++k) {
            const int e = list[k];
            if (stamp_[size_t(e)] == stamp_now_) continue;
            stamp_[size_t(e)] = stamp_now_;
            if (Crosses(e, P, Q, a, b)) return false;
          }
        }
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
    const MeshFace& f = Plane(el.patch);
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
  double slack_ = 0;  // what rounding may take from a slab's bound (BuildTree)
  std::vector<PatchInfo> info_;
  Grid grid_;                        // elements by the cells of C_ they overlap (Clear)
  static constexpr size_t kLeaf = 32;        // elements to a leaf of the tree
  // A Morton code's bits an axis, above an element's id (kMaxElements).
  static constexpr int kAxisBits = 13, kIdBits = 24;
  static_assert(kMaxElements <= (1 << kIdBits) && 3 * kAxisBits + kIdBits <= 64, "keys");
  bool by_facing_ = false;                   // the tree's order (BuildTree)
  size_t full_leaves_ = 0;                   // leaves the full searches scanned (Nearest)
  std::vector<int> order_;                   // elements in the tree's order
  std::vector<FloatBox> box_;                // ... and their bounding boxes
  std::vector<int> home_;                    // per patch: the leaf of its first top element
  std::vector<std::vector<Box>> levels_;     // the tree's boxes: leaves first, root last
  // Deeper first among equally near (many boxes hold p's centre): down to
  // a leaf rather than across the tree.
  static bool Farther(const Visit& a, const Visit& b) {
    return a.d > b.d || (a.d == b.d && a.level > b.level);
  }
  std::vector<Visit> heap_, stack_;          // Nearest's boxes to look into
  std::array<int, 4> recent_{-1, -1, -1, -1};  // Nearest's last answers, in order_, newest first
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
