#include "mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <unordered_map>

#include "check.h"
#include "groups.h"
#include "hash.h"

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
// the pieces of a split polygon share their common edges.
class FaceVerts {
 public:
  explicit FaceVerts(std::vector<glm::dvec3>* verts) : verts_(verts) {}
  int Id(const glm::dvec3& p) {
    auto [it, added] = ids_.try_emplace(p, int(verts_->size()));
    if (added) verts_->push_back(p);
    return it->second;
  }

 private:
  std::vector<glm::dvec3>* verts_;
  std::unordered_map<glm::dvec3, int, PointHash> ids_;
};

double PolyArea(const Mesh& m, const Element& e) {
  std::vector<glm::dvec3> p;
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

  // Count first so an absurd patch size is refused before allocating.
  double estimate = 0;
  for (const Face& f : scene.faces) {
    double ext = 0;
    for (const auto& p : f.verts) ext = std::max(ext, glm::length(p - f.verts[0]));
    double n = std::ceil(ext / ps) * epp;
    estimate += n * n * (f.verts.size() > 4 ? double(f.verts.size() - 2) : 1.0);
  }
  if (estimate > kMaxElements) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "%zu faces at patch size %g and %d elements per patch edge would make "
                  "about %.3g elements (limit %d)",
                  scene.faces.size(), ps, epp, estimate, kMaxElements);
    *err = buf;
    return false;
  }

  for (size_t fi = 0; fi < scene.faces.size(); ++fi) {
    const Face& f = scene.faces[fi];
    const Material& mat = scene.materials[f.material];
    MeshFace mf;
    mf.scene_face = int(fi);
    mf.normal = f.normal;
    mf.rho = mat.kd;
    mf.emission = mat.ke;
    mf.material = f.material;
    mf.area = f.area;
    mf.offset = glm::dot(f.normal, f.verts[0]);
    int face = int(mesh->faces.size());
    mesh->faces.push_back(mf);

    mesh->faces[face].vbegin = int(mesh->verts.size());
    FaceVerts fv(&mesh->verts);
    Builder b{mesh, face, epp, &fv, {}};
    const auto& v = f.verts;
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

int Find(const std::unordered_map<uint64_t, int>& m, uint64_t key) {
  auto it = m.find(key);
  return it == m.end() ? -1 : it->second;
}

void Own(Mesh* m, int elem, bool add) {
  const Element& e = m->elems[elem];
  for (int k = 0, n = Corners(e); k < n; ++k) {
    const uint64_t key = EdgeKey(e.v[k], e.v[(k + 1) % n]);
    if (add) m->owner[key] = elem;
    else m->owner.erase(key);
  }
}

Segment Seg(const Mesh& m, int a, int b) {
  const glm::dvec3 &p = m.verts[a], &q = m.verts[b];
  return LexLess(p, q) ? Segment(p, q) : Segment(q, p);
}

// Adds `elem`'s edges that have no neighbour in its face to Mesh::border,
// or takes all its edges out.
void Border(Mesh* m, int elem, bool add) {
  const Element& e = m->elems[elem];
  for (int k = 0, n = Corners(e); k < n; ++k) {
    const int p = e.v[k], q = e.v[(k + 1) % n];
    if (!add) {
      auto it = m->border.find(Seg(*m, p, q));
      if (it == m->border.end()) continue;
      auto& v = it->second;
      v.erase(std::remove(v.begin(), v.end(), elem), v.end());
      if (v.empty()) m->border.erase(it);
    } else if (Find(m->owner, EdgeKey(q, p)) < 0) {
      m->border[Seg(*m, p, q)].push_back(elem);
    }
  }
}

// Element n's edge (p, q) (its own vertex ids) becomes home to T-vertex v.
void SetMid(Element* n, int p, int q, int v) {
  for (int k = 0, c = Corners(*n); k < c; ++k)
    if (n->v[k] == p && n->v[(k + 1) % c] == q) n->mid[k] = v;
}

int NewMidpoint(Mesh* m, int face, int a, int b, const glm::dvec3& p) {
  const int v = int(m->verts.size());
  m->verts.push_back(p);
  m->faces[face].divide_verts.push_back(v);
  m->midpoint.emplace(Undirected(a, b), v);
  m->split.emplace(v, Undirected(a, b));
  return v;
}

// The midpoint of edge a -> b of an element of face `face`: the one a
// neighbour made, or a new vertex, which the neighbour across the edge (if
// it is a leaf with that very edge) then holds as a T-vertex; so do leaves
// of other faces along the same edge, with a copy of their own.
int Midpoint(Mesh* m, int face, int a, int b) {
  if (int v = Find(m->midpoint, Undirected(a, b)); v >= 0) return v;
  const glm::dvec3 p = EdgePoint(m->verts[a], m->verts[b], 1, 2);
  const int v = NewMidpoint(m, face, a, b, p);
  if (int n = Find(m->owner, EdgeKey(b, a)); n >= 0) {
    SetMid(&m->elems[n], b, a, v);
    return v;
  }
  auto it = m->border.find(Seg(*m, a, b));
  if (it == m->border.end()) return v;
  // Copies: NewMidpoint() below grows (and may move) m->verts.
  const glm::dvec3 pa = m->verts[a], pb = m->verts[b];
  for (int n : it->second) {
    Element& ne = m->elems[n];
    const int nf = m->patches[ne.patch].face;
    if (nf == face || !ne.IsLeaf()) continue;
    for (int k = 0, c = Corners(ne); k < c; ++k) {
      const int x = ne.v[k], y = ne.v[(k + 1) % c];
      const glm::dvec3 px = m->verts[x], py = m->verts[y];
      if (ne.mid[k] >= 0 || !((px == pa && py == pb) || (px == pb && py == pa))) continue;
      ne.mid[k] = NewMidpoint(m, nf, x, y, p);
    }
  }
  return v;
}

}  // namespace

void ConnectEdges(Mesh* mesh) {
  if (mesh->connected) return;
  mesh->connected = true;
  for (size_t e = 0; e < mesh->elems.size(); ++e)
    if (mesh->elems[e].IsLeaf()) Own(mesh, int(e), true);
  for (size_t e = 0; e < mesh->elems.size(); ++e)
    if (mesh->elems[e].IsLeaf()) Border(mesh, int(e), true);
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
    const int c = int(mesh->verts.size());
    const auto& p = mesh->verts;
    mesh->verts.push_back(0.25 * (p[v[0]] + p[v[1]] + p[v[2]] + p[v[3]]));
    mesh->faces[face].divide_verts.push_back(c);
    kids = {{{v[0], mid[0], c, mid[3]}, {mid[0], v[1], mid[1], c},
             {c, mid[1], v[2], mid[2]}, {mid[3], c, mid[2], v[3]}}};
  }
  Own(mesh, elem, false);
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
    for (int k = 0; k < n; ++k)
      child.mid[k] = Find(mesh->midpoint, Undirected(kv[k], kv[(k + 1) % n]));
    mesh->elems.push_back(child);
    Own(mesh, int(mesh->elems.size()) - 1, true);
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
    int n = Find(mesh.owner, EdgeKey(a, b));
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
      auto it = mesh.split.find(s);
      if (it == mesh.split.end()) continue;
      const int r0 = int(it->second >> 32), r1 = int(uint32_t(it->second));
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
