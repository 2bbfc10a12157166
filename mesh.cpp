#include "mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <unordered_map>

#include "check.h"
#include "groups.h"
#include "hash.h"
#include "surface.h"

namespace {

bool LexLess(const glm::dvec3& a, const glm::dvec3& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

// The point k/n of the way from p to q, computed from the lexicographically
// smaller endpoint so that a face walking the edge the other way gets the
// bit-identical point (no hemicube cracks between faces cut alike).
glm::dvec3 EdgePoint(const glm::dvec3& p, const glm::dvec3& q, int k, int n) {
  if (k == 0) return p;
  if (k == n) return q;
  if (LexLess(p, q)) return p + (q - p) * (double(k) / n);
  return q + (p - q) * (double(n - k) / n);
}

// Vertex ids of one input face: points are welded by exact value so that
// the pieces of a split polygon share their common edges. An
// open-addressing table of ids, kept from face to face (a hash map per
// face cost a third of BuildMesh at 10^6 faces).
class FaceVerts {
 public:
  explicit FaceVerts(std::vector<glm::dvec3>* verts) : verts_(verts) {}
  void NextFace() {
    for (size_t i : used_) table_[i] = -1;
    used_.clear();
  }
  int Id(const glm::dvec3& p) {
    if (2 * (used_.size() + 1) > table_.size()) Grow();
    const size_t mask = table_.size() - 1;
    size_t i = PointHash()(p) & mask;
    for (; table_[i] >= 0; i = (i + 1) & mask)
      if ((*verts_)[table_[i]] == p) return table_[i];
    table_[i] = int(verts_->size());
    used_.push_back(i);
    verts_->push_back(p);
    return table_[i];
  }

 private:
  void Grow() {
    std::vector<int> ids;
    for (size_t i : used_) ids.push_back(table_[i]);
    table_.assign(std::max<size_t>(64, 2 * table_.size()), -1);
    used_.clear();
    const size_t mask = table_.size() - 1;
    for (int id : ids) {
      size_t i = PointHash()((*verts_)[id]) & mask;
      while (table_[i] >= 0) i = (i + 1) & mask;
      table_[i] = id;
      used_.push_back(i);
    }
  }

  std::vector<glm::dvec3>* verts_;
  std::vector<int> table_;
  std::vector<size_t> used_;
};

double PolyArea(const Mesh& m, const Element& e) {
  thread_local std::vector<glm::dvec3> p;  // no allocation per element
  p.clear();
  for (int k = 0; k < (e.IsTriangle() ? 3 : 4); ++k) p.push_back(m.verts[e.v[k]]);
  return glm::length(AreaVector(p));
}

bool Convex(const std::vector<glm::dvec3>& q, const glm::dvec3& n) {
  for (size_t i = 0; i < q.size(); ++i) {
    const glm::dvec3& a = q[i];
    const glm::dvec3& b = q[(i + 1) % q.size()];
    const glm::dvec3& c = q[(i + 2) % q.size()];
    if (glm::dot(glm::cross(b - a, c - b), n) <= 0) return false;
  }
  return true;
}

// Ear clipping in the face's plane; polygons are simple (not
// self-intersecting) by the scene contract.
std::vector<std::array<int, 3>> Triangulate(const std::vector<glm::dvec3>& poly,
                                            const glm::dvec3& n) {
  std::vector<std::array<int, 3>> tris;
  std::vector<int> idx(poly.size());
  for (size_t i = 0; i < idx.size(); ++i) idx[i] = int(i);
  auto cross_n = [&](int a, int b, int c) {
    return glm::dot(glm::cross(poly[b] - poly[a], poly[c] - poly[b]), n);
  };
  auto inside = [&](int p, int a, int b, int c) {
    return cross_n(a, b, p) >= 0 && cross_n(b, c, p) >= 0 && cross_n(c, a, p) >= 0;
  };
  size_t guard = 0;
  while (idx.size() > 3 && guard++ < 4 * poly.size() * poly.size()) {
    bool cut = false;
    for (size_t i = 0; i < idx.size() && !cut; ++i) {
      int a = idx[(i + idx.size() - 1) % idx.size()], b = idx[i], c = idx[(i + 1) % idx.size()];
      if (cross_n(a, b, c) <= 0) continue;  // reflex or collinear
      bool ear = true;
      for (int p : idx)
        if (p != a && p != b && p != c && inside(p, a, b, c)) { ear = false; break; }
      if (!ear) continue;
      tris.push_back({a, b, c});
      idx.erase(idx.begin() + i);
      cut = true;
    }
    if (!cut) break;
  }
  if (idx.size() == 3 && cross_n(idx[0], idx[1], idx[2]) > 0)
    tris.push_back({idx[0], idx[1], idx[2]});
  return tris;
}

struct Builder {
  Mesh* m;
  int face;
  int epp;  // elements per patch edge
  FaceVerts* fv;
  std::unordered_map<long long, int> patch_of;  // coarse cell -> patch id

  int PatchFor(long long key) {
    auto it = patch_of.find(key);
    if (it != patch_of.end()) return it->second;
    int id = int(m->patches.size());
    m->patches.emplace_back();
    m->patches.back().face = face;
    m->faces[face].patches.push_back(id);
    patch_of.emplace(key, id);
    return id;
  }

  void AddElement(const std::array<int, 4>& v, long long patch_key) {
    Element e;
    e.v = v;
    e.area = PolyArea(*m, e);
    if (!(e.area > 0)) return;  // a sliver of rounding; it receives nothing
    int patch = PatchFor(patch_key);
    e.patch = patch;
    m->patches[patch].elements.push_back(int(m->elems.size()));
    m->elems.push_back(e);
  }

  // Quad a,b,c,d (convex, planar) cut into nu x nv patches of epp x epp
  // elements by bilinear interpolation; cells stay planar and convex.
  void Quad(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
            const glm::dvec3& d, int nu, int nv, long long piece) {
    int NU = nu * epp, NV = nv * epp;
    std::vector<int> id((NU + 1) * (NV + 1));
    for (int j = 0; j <= NV; ++j)
      for (int i = 0; i <= NU; ++i) {
        glm::dvec3 p;
        if (j == 0) p = EdgePoint(a, b, i, NU);
        else if (j == NV) p = EdgePoint(d, c, i, NU);
        else if (i == 0) p = EdgePoint(a, d, j, NV);
        else if (i == NU) p = EdgePoint(b, c, j, NV);
        else {
          double s = double(i) / NU, t = double(j) / NV;
          p = (1 - s) * (1 - t) * a + s * (1 - t) * b + s * t * c + (1 - s) * t * d;
        }
        id[j * (NU + 1) + i] = fv->Id(p);
      }
    for (int j = 0; j < NV; ++j)
      for (int i = 0; i < NU; ++i) {
        long long key = (piece << 40) | (long long)(j / epp) << 20 | (i / epp);
        AddElement({id[j * (NU + 1) + i], id[j * (NU + 1) + i + 1],
                    id[(j + 1) * (NU + 1) + i + 1], id[(j + 1) * (NU + 1) + i]},
                   key);
      }
  }

  // Triangle a,b,c cut into n*n patches (the usual 4-way grid), each of
  // epp*epp elements.
  void Tri(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, int n,
           long long piece) {
    int N = n * epp;
    auto at = [&](int i, int j) -> int {  // point a + (b-a) i/N + (c-a) j/N
      glm::dvec3 p;
      if (j == 0) p = EdgePoint(a, b, i, N);
      else if (i == 0) p = EdgePoint(a, c, j, N);
      else if (i + j == N) p = EdgePoint(b, c, j, N);
      else p = a + (b - a) * (double(i) / N) + (c - a) * (double(j) / N);
      return fv->Id(p);
    };
    std::vector<int> id((N + 1) * (N + 1), -1);
    for (int j = 0; j <= N; ++j)
      for (int i = 0; i + j <= N; ++i) id[j * (N + 1) + i] = at(i, j);
    auto V = [&](int i, int j) { return id[j * (N + 1) + i]; };
    for (int j = 0; j < N; ++j)
      for (int i = 0; i + j < N; ++i) {
        int I = i / epp, J = j / epp, s = i % epp + j % epp;
        long long up = (piece << 40) | (long long)J << 20 | I << 1;
        AddElement({V(i, j), V(i + 1, j), V(i, j + 1), -1}, s < epp ? up : up | 1);
        if (i + j + 1 < N)
          AddElement({V(i + 1, j), V(i + 1, j + 1), V(i, j + 1), -1},
                     s < epp - 1 ? up : up | 1);
      }
  }
};

int Cuts(double length, double size) {
  return std::max(1, int(std::ceil(length / size - 1e-9)));
}

}  // namespace

namespace {

MeshEstimate Estimate(const std::vector<Surface>& surfaces, double ps, int epp) {
  MeshEstimate m;
  for (const Surface& f : surfaces) {
    double ext = 0;
    for (const auto& p : f.poly) ext = std::max(ext, glm::length(p - f.poly[0]));
    double n = std::ceil(ext / ps) * epp;
    const double pieces = f.poly.size() > 4 ? double(f.poly.size() - 2) : 1.0;
    m.elements += n * n * pieces;
    m.vertices += (n + 1) * (n + 1) * pieces;
  }
  return m;
}

}  // namespace

// From the surfaces, as BuildMesh will cut them: a floor of 10^6
// triangles is one quad's elements, not 10^6 faces' worth.
MeshEstimate EstimateMesh(const Scene& scene, const MeshOptions& opts) {
  const double ps =
      opts.patch_size > 0 ? opts.patch_size : glm::length(scene.hi - scene.lo) / 16;
  if (!(ps > 0)) return MeshEstimate();
  return Estimate(BuildSurfaces(scene, opts.join), ps, opts.elements_per_patch);
}

bool BuildMesh(const Scene& scene, const MeshOptions& opts, Mesh* mesh,
               std::string* err) {
  *mesh = Mesh();
  mesh->scene_diagonal = glm::length(scene.hi - scene.lo);
  mesh->patch_size = opts.patch_size > 0 ? opts.patch_size : mesh->scene_diagonal / 16;
  if (!(mesh->patch_size > 0) || opts.elements_per_patch < 1) {
    *err = "the scene has no extent to mesh";
    return false;
  }
  const double ps = mesh->patch_size;
  const int epp = opts.elements_per_patch;

  const std::vector<Surface> surfaces = BuildSurfaces(scene, opts.join);

  // Count first so an absurd patch size is refused before allocating.
  const MeshEstimate size = Estimate(surfaces, ps, epp);
  const double estimate = size.elements, vertices = size.vertices;
  if (estimate > kMaxElements) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "%zu faces (%zu surfaces) at patch size %g and %d elements per patch edge "
                  "would make about %.3g elements (limit %d)",
                  scene.faces.size(), surfaces.size(), ps, epp, estimate, kMaxElements);
    *err = buf;
    return false;
  }

  // Reserved from the estimates (at most a few times too much; pages never
  // written cost no memory): growing by doubling wrote every array two or
  // three times over, most of BuildMesh's time at 10^6 faces.
  mesh->faces.reserve(surfaces.size());
  mesh->elems.reserve(size_t(estimate));
  mesh->verts.reserve(size_t(vertices));
  mesh->patches.reserve(size_t(estimate) / size_t(epp * epp) + surfaces.size());
  mesh->corner_begin.assign(scene.faces.size() + 1, 0);
  for (const Surface& f : surfaces) {
    if (f.faces.size() > 1)
      for (int i : f.faces) mesh->corner_begin[i + 1] = int(scene.faces[i].verts.size());
  }
  for (size_t i = 0; i < scene.faces.size(); ++i) {
    if (mesh->corner_begin[i + 1] > 0)
      mesh->face_corners.insert(mesh->face_corners.end(), scene.faces[i].verts.begin(),
                                scene.faces[i].verts.end());
    mesh->corner_begin[i + 1] += mesh->corner_begin[i];
  }

  FaceVerts fv(&mesh->verts);
  for (const Surface& f : surfaces) {
    const Material& mat = scene.materials[f.material];
    MeshFace mf;
    mf.scene_faces = f.faces;
    mf.normal = f.normal;
    mf.rho = mat.kd;
    mf.emission = mat.ke;
    mf.material = f.material;
    mf.area = f.area;
    mf.offset = f.offset;
    int face = int(mesh->faces.size());
    mesh->faces.push_back(std::move(mf));

    mesh->faces[face].vbegin = int(mesh->verts.size());
    fv.NextFace();
    Builder b{mesh, face, epp, &fv, {}};
    const auto& v = f.poly;
    if (v.size() == 3) {
      double e = std::max({glm::length(v[1] - v[0]), glm::length(v[2] - v[1]),
                           glm::length(v[0] - v[2])});
      b.Tri(v[0], v[1], v[2], Cuts(e, ps), 0);
    } else if (v.size() == 4 && Convex(v, f.normal)) {
      int nu = Cuts(std::max(glm::length(v[1] - v[0]), glm::length(v[2] - v[3])), ps);
      int nv = Cuts(std::max(glm::length(v[3] - v[0]), glm::length(v[2] - v[1])), ps);
      b.Quad(v[0], v[1], v[2], v[3], nu, nv, 0);
    } else {
      // One cut count for all pieces keeps their shared edges conforming.
      auto tris = Triangulate(v, f.normal);
      int n = 1;
      for (const auto& t : tris)
        for (int k = 0; k < 3; ++k)
          n = std::max(n, Cuts(glm::length(v[t[(k + 1) % 3]] - v[t[k]]), ps));
      for (size_t t = 0; t < tris.size(); ++t)
        b.Tri(v[tris[t][0]], v[tris[t][1]], v[tris[t][2]], n, (long long)t);
    }
    mesh->faces[face].vend = int(mesh->verts.size());
  }

  for (Patch& p : mesh->patches) {
    glm::dvec3 c(0.0);
    for (int e : p.elements) {
      p.area += mesh->elems[e].area;
      c += mesh->elems[e].area * mesh->Centroid(e);
    }
    CHECK(p.area > 0);
    p.center = c / p.area;
  }
  FormGroups(opts, mesh);
  return true;
}

namespace {

// Depth first from the ids on `stack` (the last one first), children in order.
void CollectLeaves(const std::vector<Element>& elems, std::vector<int> stack,
                   std::vector<int>* out) {
  out->clear();
  while (!stack.empty()) {
    int e = stack.back();
    stack.pop_back();
    if (elems[e].IsLeaf()) {
      out->push_back(e);
    } else {
      for (int k = kChildren - 1; k >= 0; --k) stack.push_back(elems[e].first_child + k);
    }
  }
}

}  // namespace

void Mesh::Leaves(int patch, std::vector<int>* out) const {
  CollectLeaves(elems, {patches[patch].elements.rbegin(), patches[patch].elements.rend()}, out);
}

void Mesh::LeavesUnder(int elem, std::vector<int>* out) const {
  CollectLeaves(elems, {elem}, out);
}

glm::dvec3 Mesh::Centroid(int elem) const {
  const Element& e = elems[elem];
  int n = e.IsTriangle() ? 3 : 4;
  glm::dvec3 c(0.0);
  for (int k = 0; k < n; ++k) c += verts[e.v[k]];
  return c / double(n);
}

namespace {

int Corners(const Element& e) { return e.IsTriangle() ? 3 : 4; }

uint64_t Undirected(int a, int b) { return a < b ? EdgeKey(a, b) : EdgeKey(b, a); }

int32_t Slot(int elem, int k) { return int32_t(elem) * 4 + k; }

// The element (leaf or divided) whose edge k runs a -> b, or -1. Elements
// of a face never overlap, so there is at most one; divided ones stay in
// the lists, which is how MidpointOf() finds the midpoints they made.
int EdgeElement(const Mesh& m, int a, int b, int* k) {
  for (int32_t s = m.out_head[a]; s >= 0; s = m.out_next[s]) {
    const Element& e = m.elems[s >> 2];
    if (e.v[((s & 3) + 1) % Corners(e)] == b) {
      *k = s & 3;
      return s >> 2;
    }
  }
  return -1;
}

// The leaf with edge a -> b, or -1.
int Owner(const Mesh& m, int a, int b) {
  int k;
  const int e = EdgeElement(m, a, b, &k);
  return e >= 0 && m.elems[e].IsLeaf() ? e : -1;
}

// Puts the edges of element `elem` (new, or all at ConnectEdges) in the
// vertices' lists.
void Link(Mesh* m, int elem) {
  const Element& e = m->elems[elem];
  m->out_next.resize(4 * m->elems.size(), -1);
  m->border_bits.resize(m->elems.size(), 0);
  for (int k = 0, n = Corners(e); k < n; ++k) {
    m->out_next[Slot(elem, k)] = m->out_head[e.v[k]];
    m->out_head[e.v[k]] = Slot(elem, k);
  }
}

// A segment's hash by its end points in lexicographic order.
size_t SegmentHash(const glm::dvec3& p, const glm::dvec3& q) {
  const bool lo = LexLess(p, q);
  return SplitMix64(PointHash()(lo ? p : q) * 31 ^ PointHash()(lo ? q : p));
}

size_t SlotHash(const Mesh& m, int32_t s) {
  const Element& e = m.elems[s >> 2];
  const int k = s & 3;
  return SegmentHash(m.verts[e.v[k]], m.verts[e.v[(k + 1) % Corners(e)]]);
}

void BorderPut(std::vector<int32_t>* table, const Mesh& m, int32_t s) {
  const size_t mask = table->size() - 1;
  size_t i = SlotHash(m, s) & mask;
  while ((*table)[i] >= 0) i = (i + 1) & mask;
  (*table)[i] = s;
}

// Makes room for `more` entries: linear probing at most 3/4 full, 4 bytes
// a slot, so 5 to 11 bytes per border edge.
void BorderReserve(Mesh* m, size_t more) {
  size_t size = std::max<size_t>(64, m->border.size());
  while (4 * (m->border_count + more) > 3 * size) size *= 2;
  if (size == m->border.size()) return;
  std::vector<int32_t> grown(size, -1);
  for (int32_t x : m->border)
    if (x >= 0) BorderPut(&grown, *m, x);
  m->border.swap(grown);
}

void BorderAdd(Mesh* m, int32_t s) {
  BorderReserve(m, 1);
  BorderPut(&m->border, *m, s);
  ++m->border_count;
}

// Takes slot s out, moving later entries of its probe run back (no
// tombstones).
void BorderRemove(Mesh* m, int32_t s) {
  std::vector<int32_t>& t = m->border;
  const size_t mask = t.size() - 1;
  size_t i = SlotHash(*m, s) & mask;
  while (t[i] != s) {
    CHECK(t[i] >= 0);
    i = (i + 1) & mask;
  }
  for (size_t j = (i + 1) & mask; t[j] >= 0; j = (j + 1) & mask) {
    const size_t home = SlotHash(*m, t[j]) & mask;
    // t[j] may move to i unless its home lies cyclically in (i, j].
    if ((j > i && (home <= i || home > j)) || (j < i && home <= i && home > j)) {
      t[i] = t[j];
      i = j;
    }
  }
  t[i] = -1;
  --m->border_count;
}

// Elements with a border edge from p to q (either way), in increasing id.
void BorderFind(const Mesh& m, const glm::dvec3& p, const glm::dvec3& q, std::vector<int>* out) {
  out->clear();
  if (m.border.empty()) return;
  const size_t mask = m.border.size() - 1;
  for (size_t i = SegmentHash(p, q) & mask; m.border[i] >= 0; i = (i + 1) & mask) {
    const int32_t s = m.border[i];
    const Element& e = m.elems[s >> 2];
    const glm::dvec3& a = m.verts[e.v[s & 3]];
    const glm::dvec3& b = m.verts[e.v[((s & 3) + 1) % Corners(e)]];
    if ((a == p && b == q) || (a == q && b == p)) out->push_back(s >> 2);
  }
  std::sort(out->begin(), out->end());
  out->erase(std::unique(out->begin(), out->end()), out->end());
}

// Adds `elem`'s edges that have no neighbour in its face to the border
// table, or takes all its edges out.
void Border(Mesh* m, int elem, bool add) {
  const Element& e = m->elems[elem];
  uint8_t& bits = m->border_bits[elem];
  for (int k = 0, n = Corners(e); k < n; ++k) {
    if (!add) {
      if (bits >> k & 1) BorderRemove(m, Slot(elem, k));
    } else if (Owner(*m, e.v[(k + 1) % n], e.v[k]) < 0) {
      bits |= uint8_t(1 << k);
      BorderAdd(m, Slot(elem, k));
    }
  }
  if (!add) bits = 0;
}

// Element n's edge (p, q) (its own vertex ids) becomes home to T-vertex v.
void SetMid(Element* n, int p, int q, int v) {
  for (int k = 0, c = Corners(*n); k < c; ++k)
    if (n->v[k] == p && n->v[(k + 1) % c] == q) n->mid[k] = v;
}

// A vertex Divide() makes: on an edge (a, b), or a quad's centre (a < 0).
int AddVertex(Mesh* m, int face, int a, int b, const glm::dvec3& p) {
  const int v = int(m->verts.size());
  m->verts.push_back(p);
  m->faces[face].divide_verts.push_back(v);
  m->out_head.push_back(-1);
  m->split.push_back(a < 0 ? kNoEdge : Undirected(a, b));
  return v;
}

// The midpoint of edge a -> b of an element of face `face`: the one a
// neighbour made, or a new vertex, which the neighbour across the edge (if
// it is a leaf with that very edge) then holds as a T-vertex; so do leaves
// of other faces along the same edge, with a copy of their own.
int Midpoint(Mesh* m, int face, int a, int b) {
  if (int v = MidpointOf(*m, a, b); v >= 0) return v;
  const glm::dvec3 p = EdgePoint(m->verts[a], m->verts[b], 1, 2);
  const int v = AddVertex(m, face, a, b, p);
  if (int n = Owner(*m, b, a); n >= 0) {
    SetMid(&m->elems[n], b, a, v);
    return v;
  }
  // Copies: AddVertex() below grows (and may move) m->verts.
  const glm::dvec3 pa = m->verts[a], pb = m->verts[b];
  std::vector<int> along;
  BorderFind(*m, pa, pb, &along);
  for (int n : along) {
    Element& ne = m->elems[n];
    const int nf = m->patches[ne.patch].face;
    if (nf == face || !ne.IsLeaf()) continue;
    for (int k = 0, c = Corners(ne); k < c; ++k) {
      const int x = ne.v[k], y = ne.v[(k + 1) % c];
      const glm::dvec3 px = m->verts[x], py = m->verts[y];
      if (ne.mid[k] >= 0 || !((px == pa && py == pb) || (px == pb && py == pa))) continue;
      ne.mid[k] = AddVertex(m, nf, x, y, p);
    }
  }
  return v;
}

}  // namespace

int MidpointOf(const Mesh& m, int a, int b) {
  int k;
  for (int pass = 0; pass < 2; ++pass, std::swap(a, b)) {
    const int e = EdgeElement(m, a, b, &k);
    if (e < 0) continue;
    const Element& el = m.elems[e];
    if (el.IsLeaf()) {
      if (el.mid[k] >= 0) return el.mid[k];
      continue;
    }
    // The children as Divide() lays them out: child 0 starts v[0], mid[0]
    // and ends mid[last]; child 1 holds mid[1] after v[1]; a quad's child
    // 2 ends with mid[2].
    const Element* c = &m.elems[el.first_child];
    const int n = Corners(el);
    if (k == 0) return c[0].v[1];
    if (k == n - 1) return c[0].v[n - 1];
    return k == 1 ? c[1].v[2] : c[2].v[3];
  }
  return -1;
}

void ConnectEdges(Mesh* mesh) {
  if (mesh->connected) return;
  mesh->connected = true;
  mesh->out_head.assign(mesh->verts.size(), -1);
  mesh->split_base = int32_t(mesh->verts.size());
  for (size_t e = 0; e < mesh->elems.size(); ++e)
    if (mesh->elems[e].IsLeaf()) Link(mesh, int(e));
  // The border edges first, then a table of the right size: growing it
  // edge by edge would rehash (from the geometry, out of cache) ever again.
  std::vector<int32_t> border;
  mesh->border_bits.assign(mesh->elems.size(), 0);
  for (size_t e = 0; e < mesh->elems.size(); ++e) {
    const Element& el = mesh->elems[e];
    for (int k = 0, n = Corners(el); k < n && el.IsLeaf(); ++k)
      if (Owner(*mesh, el.v[(k + 1) % n], el.v[k]) < 0) {
        mesh->border_bits[e] |= uint8_t(1 << k);
        border.push_back(Slot(int(e), k));
      }
  }
  BorderReserve(mesh, border.size());
  for (int32_t s : border) BorderPut(&mesh->border, *mesh, s);
  mesh->border_count = border.size();
}

void Divide(Mesh* mesh, int32_t elem) {
  ConnectEdges(mesh);
  CHECK(elem >= 0 && size_t(elem) < mesh->elems.size() && mesh->elems[elem].IsLeaf());
  const Element parent = mesh->elems[elem];
  const int face = mesh->patches[parent.patch].face;
  const int n = Corners(parent);
  int mid[4];
  for (int k = 0; k < n; ++k) mid[k] = Midpoint(mesh, face, parent.v[k], parent.v[(k + 1) % n]);
  const std::array<int, 4>& v = parent.v;
  std::array<std::array<int, 4>, kChildren> kids;
  if (n == 3) {
    kids = {{{v[0], mid[0], mid[2], -1}, {mid[0], v[1], mid[1], -1},
             {mid[2], mid[1], v[2], -1}, {mid[0], mid[1], mid[2], -1}}};
  } else {
    const auto& p = mesh->verts;
    const int c = AddVertex(mesh, face, -1, -1, 0.25 * (p[v[0]] + p[v[1]] + p[v[2]] + p[v[3]]));
    kids = {{{v[0], mid[0], c, mid[3]}, {mid[0], v[1], mid[1], c},
             {c, mid[1], v[2], mid[2]}, {mid[3], c, mid[2], v[3]}}};
  }
  Border(mesh, elem, false);
  ++mesh->divided;
  const int first = int(mesh->elems.size());
  mesh->elems[elem].first_child = first;
  for (const auto& kv : kids) {
    Element child;
    child.v = kv;
    child.patch = parent.patch;
    child.parent = elem;
    child.level = parent.level + 1;
    child.area = PolyArea(*mesh, child);
    // A neighbour already finer than the parent by two levels leaves a
    // T-vertex on the child's edge (the subdivision policy avoids it).
    for (int k = 0; k < n; ++k) child.mid[k] = MidpointOf(*mesh, kv[k], kv[(k + 1) % n]);
    mesh->elems.push_back(child);
    Link(mesh, int(mesh->elems.size()) - 1);
  }
  for (int k = 0; k < kChildren; ++k) Border(mesh, first + k, true);
}

int Outline(const Element& e, int out[8]) {
  int ids[8], n = 0, from = -1;
  for (int k = 0; k < Corners(e); ++k) {
    ids[n++] = e.v[k];
    if (e.mid[k] < 0) continue;
    if (from < 0) from = n;
    ids[n++] = e.mid[k];
  }
  if (from < 0) from = 0;
  for (int i = 0; i < n; ++i) out[i] = ids[(from + i) % n];
  return n;
}

void LeafNeighbours(const Mesh& mesh, int elem, std::vector<int>* out) {
  out->clear();
  const Element& e = mesh.elems[elem];
  auto add = [&](int a, int b) {
    const int n = Owner(mesh, a, b);
    if (n >= 0 && std::find(out->begin(), out->end(), n) == out->end()) out->push_back(n);
    return n >= 0;
  };
  for (int k = 0, c = Corners(e); k < c; ++k) {
    const int p = e.v[k], q = e.v[(k + 1) % c];
    if (add(q, p)) continue;               // alike
    if (e.mid[k] >= 0) {                   // finer, across a T-vertex
      add(q, e.mid[k]);
      add(e.mid[k], p);
      continue;
    }
    // Coarser: p -> q is half of the neighbour's edge, split at p or q.
    for (int s : {p, q}) {
      if (s < mesh.split_base || mesh.split[s - mesh.split_base] == kNoEdge) continue;
      const uint64_t edge = mesh.split[s - mesh.split_base];
      const int r0 = int(edge >> 32), r1 = int(uint32_t(edge));
      const int other = s == p ? q : p;
      if (other != r0 && other != r1) continue;
      // Our way along the coarse edge runs from `from` to `to`.
      const int far = other == r0 ? r1 : r0;
      const int from = s == p ? far : other, to = s == p ? other : far;
      add(to, from);
    }
  }
}

namespace {

// One step of the hash: the state xor a 64-bit word, through splitmix64.
uint64_t Mix(uint64_t h, uint64_t w) { return SplitMix64(h ^ w); }

uint64_t Bits(double d) {
  uint64_t b;
  std::memcpy(&b, &d, 8);
  return b;
}

uint64_t Int(int v) { return uint64_t(uint32_t(v)); }

}  // namespace

uint64_t MeshHash(const Mesh& mesh) {
  uint64_t h = 0x6d657368;  // "mesh"
  h = Mix(h, mesh.verts.size());
  h = Mix(h, mesh.elems.size());
  h = Mix(h, mesh.patches.size());
  h = Mix(h, mesh.faces.size());
  for (const auto& v : mesh.verts) {
    h = Mix(h, Bits(v.x));
    h = Mix(h, Bits(v.y));
    h = Mix(h, Bits(v.z));
  }
  for (const Element& e : mesh.elems) {
    h = Mix(h, Int(e.v[0]) | Int(e.v[1]) << 32);
    h = Mix(h, Int(e.v[2]) | Int(e.v[3]) << 32);
    h = Mix(h, Int(e.patch) | Int(e.parent) << 32);
    h = Mix(h, Int(e.first_child) | Int(e.level) << 32);
    h = Mix(h, Bits(e.area));
  }
  for (const Patch& p : mesh.patches) {
    h = Mix(h, Int(p.face) | uint64_t(p.elements.size()) << 32);
    h = Mix(h, Bits(p.center.x));
    h = Mix(h, Bits(p.center.y));
    h = Mix(h, Bits(p.center.z));
  }
  return h;
}
