// Shooter division: cutting a patch into patches along its elements (the
// mesh's side, declared in mesh.h), and the policy that chooses them
// (Subdivider::SplitPass, declared and described in subdivide.h). The
// sharing of the unshot power is the solver's (Solver::Split).
#include <algorithm>
#include <cmath>
#include <vector>

#include "check.h"
#include "mesh.h"
#include "radix_sort.h"
#include "subdivide.h"

namespace {

// The top elements the pieces of `patch` would have.
void PieceTops(const Mesh& m, int patch, std::vector<int>* tops) {
  tops->clear();
  const IdSpan el = m.Tops(patch);
  if (el.size() > 1) {
    tops->assign(el.begin(), el.end());
  } else if (el.size() == 1 && !m.elems[size_t(el[0])].IsLeaf()) {
    for (int k = 0; k < kChildren; ++k) tops->push_back(m.elems[size_t(el[0])].first_child + k);
  }
}

// Element `top` and everything below it to patch `patch`.
void MoveTo(Mesh* m, int top, int patch) {
  std::vector<int> stack{top};
  while (!stack.empty()) {
    Element& e = m->elems[size_t(stack.back())];
    stack.pop_back();
    e.patch = patch;
    if (!e.IsLeaf())
      for (int k = 0; k < kChildren; ++k) stack.push_back(e.first_child + k);
  }
}

}  // namespace

int SplitPieces(const Mesh& mesh, int patch, std::vector<int>* tops) {
  if (tops) tops->clear();
  if (patch < 0 || size_t(patch) >= mesh.patches.size()) return 0;
  if (!mesh.group_of.empty() && mesh.group_of[size_t(patch)] >= 0) return 0;
  std::vector<int> own;
  if (!tops) tops = &own;
  PieceTops(mesh, patch, tops);
  return int(tops->size());
}

void ReserveSplits(Mesh* mesh, const std::vector<int32_t>& patches) {
  size_t added = 0;
  for (int32_t p : patches) added += size_t(std::max(SplitPieces(*mesh, p) - 1, 0));
  mesh->patches.reserve(mesh->patches.size() + added);
  mesh->patch_tops.reserve(mesh->patch_tops.size() + added);
  if (!mesh->columns_only) {
    mesh->patch_area.reserve(mesh->patch_area.size() + added);
    mesh->patch_center.reserve(mesh->patch_center.size() + added);
  }
  if (!mesh->group_of.empty()) mesh->group_of.reserve(mesh->group_of.size() + added);
}

void SplitPatch(Mesh* mesh, int patch) {
  std::vector<int> tops;
  CHECK(SplitPieces(*mesh, patch, &tops) > 1);
  const int face = mesh->patches[size_t(patch)].face;
  for (size_t i = 0; i < tops.size(); ++i) {
    const int id = i == 0 ? patch : int(mesh->patches.size());
    if (i > 0) {
      mesh->patches.emplace_back();
      MeshFace& f = mesh->faces[size_t(face)];
      if (f.last_piece < 0) f.first_piece = id;
      else mesh->patches[size_t(f.last_piece)].next_piece = id;
      f.last_piece = id;
      if (!mesh->group_of.empty()) mesh->group_of.push_back(-1);
    }
    // As BuildMesh makes a patch: its top elements' areas and centroids.
    Patch& p = mesh->patches[size_t(id)];
    p.face = face;
    // One top element: the first piece in the patch's first slot, the
    // others in slots appended.
    if (i > 0) {
      p.tops_at = int32_t(mesh->patch_tops.size());
      mesh->patch_tops.push_back(tops[i]);
    }
    mesh->patch_tops[size_t(p.tops_at)] = tops[i];
    p.tops = 1;
    if (!mesh->columns_only) {
      mesh->patch_area.resize(mesh->patches.size());
      mesh->patch_center.resize(mesh->patches.size());
      mesh->patch_area[size_t(id)] = mesh->elem_area[size_t(tops[i])];
      mesh->patch_center[size_t(id)] = mesh->Centroid(tops[i]);
    }
    MoveTo(mesh, tops[i], id);
  }
  // A divided top that gave its children away stays with the patch: its
  // children are what shoot and receive.
  mesh->splits.push_back(patch);
  mesh->split_added += long(tops.size()) - 1;
}

// ---- the policy (Subdivider::SplitPass; subdivide.h) ------------------

namespace {

// A patch SplitPass may split: not an emitter, with pieces (SplitPieces;
// not in a shooter group) into *tops.
bool Splittable(const Mesh& m, int p, std::vector<int>* tops) {
  const glm::dvec3& ke = m.Emission(m.faces[size_t(m.patches[size_t(p)].face)]);
  return !(ke.r + ke.g + ke.b > 0) && SplitPieces(m, p, tops) > 1;
}

// A grid cell's key: three 21-bit cell coordinates, clamped (clamping
// keeps a point's cell inside any clamped range that held it).
uint64_t CellKey(const glm::ivec3& c) {
  constexpr int kMax = (1 << 21) - 1;
  const glm::ivec3 k = glm::clamp(c, glm::ivec3(0), glm::ivec3(kMax));
  return uint64_t(k.x) << 42 | uint64_t(k.y) << 21 | uint64_t(k.z);
}

}  // namespace

// near_ for the patches from `from` on (the built ones, then the pieces
// splits made): whether another face's top element lies within a radius
// of split_near × its width, in front of it and facing back. Both ways
// below test the same pairs' closeness the same way: the same answer.
void Subdivider::FindNear(const Mesh& mesh, size_t from) {
  const size_t n = mesh.patches.size();
  near_.resize(n, 0);
  if (!(opts_.split_near > 0) || from >= n) return;
  std::vector<Searcher> searchers;
  for (size_t p = from; p < n; ++p)
    if (Splittable(mesh, int(p), &tops_)) {
      const MeshFace& face = mesh.faces[size_t(mesh.patches[p].face)];
      searchers.push_back({mesh.patch_center[p], face.normal, opts_.split_near * std::sqrt(mesh.patch_area[p]),
                           mesh.patches[p].face, int32_t(p)});
    }
  if (searchers.empty()) return;
  size_t count = 0;
  for (size_t p = 0; p < mesh.patches.size(); ++p) count += mesh.Tops(int(p)).size();
  if (searchers.size() * kStreamBelow < count) StreamNear(mesh, searchers);
  else GridNear(mesh, searchers, count);
}

namespace {

// The closeness FindNear asks for: a top element of a face with `normal`
// against a searcher, `d` from the searcher's centre to its centroid.
bool Close(const glm::dvec3& d, const glm::dvec3& normal, const Subdivider::Searcher& s) {
  return glm::dot(d, s.normal) > 0 && glm::dot(normal, d) < 0 && glm::dot(d, d) < s.r * s.r;
}

// The half-width of the box a searcher's cells must cover: a little more
// than its radius, so that whatever Close accepts lies within, rounding
// or not.
double Reach(const Subdivider::Searcher& s) { return s.r * (1 + 1e-6); }

// Searchers by the cells their boxes meet: (cell, searcher) pairs sorted
// by cell, behind a bit per hash of a cell met, so that a cell none meets
// (most of those looked up) is passed by with one test of 8 KB that stays
// in the first-level cache.
class CellIndex {
 public:
  using Pairs = std::vector<std::pair<uint64_t, int32_t>>;
  void Add(uint64_t cell, int32_t searcher) {
    bits_[Bit(cell) / 64] |= uint64_t(1) << (Bit(cell) % 64);
    pairs_.emplace_back(cell, searcher);
  }
  void Sort() { std::sort(pairs_.begin(), pairs_.end()); }
  // The searchers in `cell`, in id order.
  std::pair<Pairs::const_iterator, Pairs::const_iterator> In(uint64_t cell) const {
    if (!(bits_[Bit(cell) / 64] >> (Bit(cell) % 64) & 1)) return {pairs_.end(), pairs_.end()};
    return std::equal_range(pairs_.begin(), pairs_.end(), std::make_pair(cell, int32_t(-1)),
                            [](const auto& a, const auto& b) { return a.first < b.first; });
  }

 private:
  static constexpr uint64_t kBits = 1 << 16;
  static uint64_t Bit(uint64_t cell) { return (cell * 0x9E3779B97F4A7C15ull) >> 48; }
  std::vector<uint64_t> bits_ = std::vector<uint64_t>(kBits / 64, 0);
  Pairs pairs_;
};

}  // namespace

// Per patch, how far its top elements' centroids lie from its centre at
// most (float, rounded up), for the patches made since the last call. A
// patch split since keeps its value: it has one top element now, whose
// centroid is its centre (SplitPatch), so any value bounds it.
void Subdivider::Radii(const Mesh& mesh) {
  for (size_t p = radius_.size(); p < mesh.patches.size(); ++p) {
    double r = 0;
    for (int e : mesh.Tops(int(p))) r = std::max(r, glm::distance(mesh.Centroid(e), mesh.patch_center[p]));
    radius_.push_back(std::nextafter(float(r), HUGE_VALF));
  }
}

// Few searchers: the top elements streamed past them, each patch's first
// tested as a whole, its sphere (centre, radius) against the spheres of
// the searchers whose boxes meet the same coarse cells (2 × the greatest
// reach or patch radius wide: any box meets at most 2 × 2 × 2 of them);
// then each top element of a patch that meets one, its centroid's fine
// cell (2 × the greatest reach) among those the searchers' boxes meet.
// A pass after the first searches the pieces of the last splits, tens or
// hundreds at 10^6 elements: most patches are far from all of them, and
// their top elements' centroids (scattered reads) are not computed.
void Subdivider::StreamNear(const Mesh& mesh, const std::vector<Searcher>& searchers) {
  Radii(mesh);
  double reach = 0, radius = 0;
  glm::dvec3 lo(HUGE_VAL);
  for (const Searcher& s : searchers) {
    reach = std::max(reach, Reach(s));
    lo = glm::min(lo, s.c0 - Reach(s));
  }
  // The boxes a little larger than the radii, rounding or not.
  const double slack = 1e-9 * mesh.scene_diagonal;
  for (float r : radius_) radius = std::max(radius, double(r));
  radius = radius * (1 + 1e-6) + slack;
  lo -= glm::dvec3(radius);
  const double fine = 2 * reach, coarse = 2 * std::max(reach, radius);
  if (!(fine > 0)) return;
  // A point's cell, from `lo` (below every box); by the cell's inverse,
  // the same for every box: a monotone map, so whatever lies in two boxes
  // lies in a cell of each.
  const double per_fine = 1 / fine, per_coarse = 1 / coarse;
  auto cell_of = [&](const glm::dvec3& x, double per) { return glm::ivec3(glm::floor((x - lo) * per)); };
  // The key of each cell the box of half-width h around c meets.
  auto cells = [&](const glm::dvec3& c, double h, double per, auto&& f) {
    const glm::ivec3 i = cell_of(c - glm::dvec3(h), per), j = cell_of(c + glm::dvec3(h), per);
    for (int x = i.x; x <= j.x; ++x)
      for (int y = i.y; y <= j.y; ++y)
        for (int z = i.z; z <= j.z; ++z) f(CellKey({x, y, z}));
  };
  CellIndex near_coarse, near_fine;
  for (size_t i = 0; i < searchers.size(); ++i) {
    const Searcher& s = searchers[i];
    cells(s.c0, Reach(s), per_coarse, [&](uint64_t k) { near_coarse.Add(k, int32_t(i)); });
    cells(s.c0, Reach(s), per_fine, [&](uint64_t k) { near_fine.Add(k, int32_t(i)); });
  }
  near_coarse.Sort();
  near_fine.Sort();
  std::vector<uint8_t> found(searchers.size(), 0);
  size_t left = searchers.size();
  for (size_t p = 0; p < mesh.patches.size() && left > 0; ++p) {
    const glm::dvec3& pc = mesh.patch_center[p];
    const double r = double(radius_[p]) * (1 + 1e-6) + slack;
    // Its sphere against the spheres of the searchers in its cells; a
    // cell crowded with them (searchers far smaller than the largest
    // patch) is taken as met, so that no patch tests more than a few.
    constexpr int kSpheres = 8;
    bool meets = false;
    cells(pc, r, per_coarse, [&](uint64_t k) {
      if (meets) return;
      const auto in = near_coarse.In(k);
      int tested = 0;
      for (auto it = in.first; it != in.second && !meets; ++it, ++tested) {
        const Searcher& s = searchers[size_t(it->second)];
        const double d = r + Reach(s);
        meets = tested == kSpheres || (!found[size_t(it->second)] && glm::dot(pc - s.c0, pc - s.c0) <= d * d);
      }
    });
    if (!meets) continue;
    const int face = mesh.patches[p].face;
    const glm::dvec3& normal = mesh.faces[size_t(face)].normal;
    for (int e : mesh.Tops(int(p))) {
      const glm::dvec3 c = mesh.Centroid(e);
      const auto in = near_fine.In(CellKey(cell_of(c, per_fine)));
      for (auto it = in.first; it != in.second; ++it) {
        const Searcher& s = searchers[size_t(it->second)];
        if (found[size_t(it->second)] || s.face == face || !Close(c - s.c0, normal, s)) continue;
        found[size_t(it->second)] = 1;
        --left;
      }
    }
  }
  for (size_t i = 0; i < searchers.size(); ++i) near_[size_t(searchers[i].patch)] = found[i];
}

// Many searchers (the first pass): the top elements of every face in a
// grid of cells the searchers' median radius across, sorted by cell;
// each searcher looks in the cells it reaches (or at every element, when
// those cells would be more).
void Subdivider::GridNear(const Mesh& mesh, const std::vector<Searcher>& searchers, size_t count) {
  std::vector<double> radii;
  for (const Searcher& s : searchers) radii.push_back(s.r);
  std::nth_element(radii.begin(), radii.begin() + long(radii.size() / 2), radii.end());
  const double cell = radii[radii.size() / 2];
  if (!(cell > 0)) return;
  // 16 bytes a top element, reserved to their count: the centroids (24
  // bytes more) are computed again where a cell is searched (the face is
  // where padding would be: the test that skips a searcher's own face
  // reads no element and no patch), and grown by doubling the array
  // stood at three times its size while it moved, the master's peak in a
  // dividing run (the whole mesh's tops).
  struct Top {
    uint64_t key;
    int32_t e;
    int32_t face;
  };
  // The grid's origin below every centroid: the vertices' least corner (a
  // centroid is their mean), one pass over an array where the centroids
  // were a pass of scattered reads each (7-10 ms at 260,000 tops).
  glm::dvec3 lo(HUGE_VAL);
  for (const glm::dvec3& v : mesh.verts) lo = glm::min(lo, v);
  auto cell_of = [&](const glm::dvec3& x) { return glm::ivec3(glm::floor((x - lo) / cell)); };
  std::vector<Top> tops;
  tops.reserve(count);
  for (size_t p = 0; p < mesh.patches.size(); ++p)
    for (int e : mesh.Tops(int(p))) tops.push_back({CellKey(cell_of(mesh.Centroid(e))), e, mesh.patches[p].face});
  // By cell only: the search asks whether a cell holds a close element,
  // not which, so the order within a cell does not matter. Linear (16
  // bytes a top more while it sorts) where std::sort took 26-35 ms at
  // 260,000 tops.
  RadixSort(&tops, [](const Top& t) { return t.key; });
  auto before = [](const Top& t, uint64_t k) { return t.key < k; };
  for (const Searcher& s : searchers) {
    auto close = [&](const Top& t) {
      return t.face != s.face && Close(mesh.Centroid(t.e) - s.c0, mesh.faces[size_t(t.face)].normal, s);
    };
    const glm::ivec3 a = cell_of(s.c0 - glm::dvec3(Reach(s))), b = cell_of(s.c0 + glm::dvec3(Reach(s)));
    const glm::dvec3 span = glm::dvec3(b - a) + 1.0;
    bool found = false;
    if (span.x * span.y * span.z > double(tops.size())) {
      for (const Top& t : tops)
        if ((found = close(t))) break;
    } else {
      // A row of cells along z is one run of keys (z is the key's low
      // bits, clamped alike): one search a row, not a cell.
      for (int x = a.x; x <= b.x && !found; ++x)
        for (int y = a.y; y <= b.y && !found; ++y) {
          const uint64_t first = CellKey({x, y, a.z}), last = CellKey({x, y, b.z});
          auto it = std::lower_bound(tops.begin(), tops.end(), first, before);
          for (; it != tops.end() && it->key <= last && !found; ++it) found = close(*it);
        }
    }
    near_[size_t(s.patch)] = found;
  }
}

// spread_ for the splittable patches from `from` on: their pieces' range
// of mean direct luminance over the scale (subdivide.h); the lit scene's
// mean first, when from is 0.
void Subdivider::Spread(const Mesh& mesh, const std::vector<float>& direct, size_t from) {
  const size_t n = mesh.patches.size();
  spread_.resize(n, 0);
  if (from == 0) {
    double sum = 0, area = 0;  // over every leaf not emitting
    for (size_t e = 0; e < mesh.elems.size(); ++e) {
      const Element& el = mesh.elems[e];
      const glm::dvec3& ke = mesh.Emission(mesh.FaceOf(int(e)));
      if (!el.IsLeaf() || ke.r + ke.g + ke.b > 0) continue;
      sum += double(direct[e]) * mesh.elem_area[size_t(e)];
      area += mesh.elem_area[size_t(e)];
    }
    direct_mean_ = area > 0 ? sum / area : 0;
  }
  for (size_t p = from; p < n; ++p) {
    spread_[p] = 0;
    if (!Splittable(mesh, int(p), &tops_)) continue;
    double hi = -HUGE_VAL, lo = HUGE_VAL;
    for (int t : tops_) {
      mesh.LeavesUnder(t, &leaves_);
      double s = 0, a = 0;
      for (int l : leaves_) {
        s += double(direct[size_t(l)]) * mesh.elem_area[size_t(l)];
        a += mesh.elem_area[size_t(l)];
      }
      const double m = a > 0 ? s / a : 0;
      hi = std::max(hi, m);
      lo = std::min(lo, m);
    }
    const double scale = hi + 0.2 * direct_mean_;
    if (scale > 0) spread_[p] = (hi - lo) / scale;
  }
}

std::vector<int32_t> Subdivider::SplitPass(const Mesh& mesh, const std::vector<float>& direct,
                                           bool direct_done, const std::vector<int>& times_shot) {
  std::vector<int32_t> out;
  if (!opts_.split) return out;
  CHECK(direct.size() == mesh.elems.size());
  CHECK(times_shot.size() == mesh.patches.size());
  FindNear(mesh, near_.size());
  // Every patch when the wave's direct light is complete, then the pieces
  // made since (their pieces' light is as it was then: divisions in the
  // wave hand it down unchanged).
  if (direct_done) Spread(mesh, direct, measured_ ? spread_.size() : 0);
  measured_ |= direct_done;
  const size_t n = mesh.patches.size();
  for (size_t p = 0; p < n; ++p) {
    const bool uneven = measured_ && p < spread_.size() && spread_[p] > split_threshold_;
    const bool close = p < near_.size() && near_[p];
    if (!(close || uneven)) continue;
    out.push_back(int32_t(p));
    if (p < spread_.size()) spread_[p] = 0;
    if (close) near_[p] = 0;
  }
  splits_ += long(out.size());
  for (int32_t p : out)
    if (times_shot[size_t(p)] > 0) ++divided_in_wave_;
  if (measured_) split_threshold_ = std::max(opts_.split_floor, split_threshold_ * opts_.decay);
  return out;
}
