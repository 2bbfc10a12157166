#include "mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <unordered_map>

#include "check.h"
#include "groups.h"
#include "hash.h"
#include "memory.h"
#include "point_ids.h"
#include "surface.h"

bool LexLess(const glm::dvec3& a, const glm::dvec3& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

glm::dvec3 EdgePoint(const glm::dvec3& p, const glm::dvec3& q, int k, int n) {
  if (k == 0) return p;
  if (k == n) return q;
  if (LexLess(p, q)) return p + (q - p) * (double(k) / n);
  return q + (p - q) * (double(n - k) / n);
}

double ElementArea(const Mesh& m, const Element& e) {
  const int n = e.IsTriangle() ? 3 : 4;
  glm::dvec3 p[4];
  for (int k = 0; k < n; ++k) p[k] = m.verts[size_t(e.v[k])];
  return glm::length(AreaVector(p, size_t(n)));
}

namespace {

// A patch's top elements' area centroid and (*area) their areas summed,
// in their order: BuildMesh's patch centres, and Center's once the areas
// are freed (ElementArea gives them again, to the bit).
glm::dvec3 TopsCentroid(const Mesh& m, int patch, double* area) {
  *area = 0;
  glm::dvec3 c(0.0);
  for (int e : m.Tops(patch)) {
    const double a = m.columns_only ? ElementArea(m, m.elems[size_t(e)]) : m.elem_area[size_t(e)];
    *area += a;
    c += a * m.Centroid(e);
  }
  return c / *area;
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

// Cuts the surfaces one after another into patches and elements; its
// buffers are kept from face to face (10^6 faces, each a few patches).
struct Builder {
  Builder(Mesh* mesh, int elements_per_patch, PointIds* ids)
      : m(mesh), epp(elements_per_patch), fv(ids) {}
  Mesh* m;
  int epp;  // elements per patch edge
  PointIds* fv;  // the face's vertices, welded by value so that pieces share edges
  int face = -1;
  // Per patch cell of the piece being cut (Quad, Tri: its index of the
  // cell), the patch made for it, or -1.
  std::vector<int> patch_of;
  // The face's elements by patch as they come (a face's elements
  // interleave its patches), until Finish() lays them out in patch order.
  std::vector<std::pair<int32_t, int32_t>> tops;
  std::vector<int32_t> count;  // per patch of the face: its top elements (Finish)
  std::vector<int> id;         // the piece's grid points (Quad, Tri)
  int first_patch = -1;

  void Start(int f) {
    face = f;
    first_patch = -1;
    tops.clear();
  }

  void Cells(size_t n) { patch_of.assign(n, -1); }

  int PatchFor(size_t cell) {
    int& id = patch_of[cell];
    if (id >= 0) return id;
    id = int(m->patches.size());
    if (first_patch < 0) first_patch = m->faces[face].patch_at = id;
    ++m->faces[face].built;
    m->patches.emplace_back();
    m->patches.back().face = face;
    return id;
  }

  void AddElement(const std::array<int, 4>& v, size_t cell) {
    Element e;
    e.v = v;
    const double area = ElementArea(*m, e);
    if (!(area > 0)) return;  // a sliver of rounding; it receives nothing
    int patch = PatchFor(cell);
    e.patch = patch;
    tops.push_back({patch - first_patch, int32_t(m->elems.size())});
    m->elems.push_back(e);
    m->elem_area.push_back(area);
    m->parent.push_back(-1);
  }

  // The face's top elements into Mesh::patch_tops patch by patch, each
  // patch's in the order they came (a counting sort).
  void Finish() {
    if (first_patch < 0) return;
    const size_t patches = m->patches.size() - size_t(first_patch);
    count.assign(patches + 1, 0);
    for (const auto& t : tops) ++count[size_t(t.first) + 1];
    const int32_t at = int32_t(m->patch_tops.size());
    for (size_t i = 0; i < patches; ++i) {
      Patch& p = m->patches[size_t(first_patch) + i];
      p.tops = count[i + 1];
      count[i + 1] += count[i];
      p.tops_at = at + count[i];
    }
    m->patch_tops.resize(m->patch_tops.size() + tops.size());
    for (const auto& t : tops) m->patch_tops[size_t(at + count[size_t(t.first)]++)] = t.second;
  }

  // Quad a,b,c,d (convex, planar) cut into nu x nv patches of epp x epp
  // elements by bilinear interpolation; cells stay planar and convex.
  void Quad(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
            const glm::dvec3& d, int nu, int nv) {
    int NU = nu * epp, NV = nv * epp;
    id.resize(size_t(NU + 1) * size_t(NV + 1));
    Cells(size_t(nu) * size_t(nv));
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
        AddElement({id[j * (NU + 1) + i], id[j * (NU + 1) + i + 1],
                    id[(j + 1) * (NU + 1) + i + 1], id[(j + 1) * (NU + 1) + i]},
                   size_t(j / epp) * size_t(nu) + size_t(i / epp));
      }
  }

  // Triangle a,b,c cut into n*n patches (the usual 4-way grid), each of
  // epp*epp elements.
  void Tri(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, int n) {
    int N = n * epp;
    auto at = [&](int i, int j) -> int {  // point a + (b-a) i/N + (c-a) j/N
      glm::dvec3 p;
      if (j == 0) p = EdgePoint(a, b, i, N);
      else if (i == 0) p = EdgePoint(a, c, j, N);
      else if (i + j == N) p = EdgePoint(b, c, j, N);
      else p = a + (b - a) * (double(i) / N) + (c - a) * (double(j) / N);
      return fv->Id(p);
    };
    id.assign(size_t(N + 1) * size_t(N + 1), -1);
    Cells(2 * size_t(n) * size_t(n));
    for (int j = 0; j <= N; ++j)
      for (int i = 0; i + j <= N; ++i) id[j * (N + 1) + i] = at(i, j);
    auto V = [&](int i, int j) { return id[j * (N + 1) + i]; };
    for (int j = 0; j < N; ++j)
      for (int i = 0; i + j < N; ++i) {
        int I = i / epp, J = j / epp, s = i % epp + j % epp;
        const size_t up = 2 * (size_t(J) * size_t(n) + size_t(I));
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
  return EstimateMesh(scene, BuildSurfaces(scene, opts.join), opts);
}

MeshEstimate EstimateMesh(const Scene& scene, const std::vector<Surface>& surfaces,
                          const MeshOptions& opts) {
  const double ps =
      opts.patch_size > 0 ? opts.patch_size : glm::length(scene.hi - scene.lo) / 16;
  if (!(ps > 0)) return MeshEstimate();
  return Estimate(surfaces, ps, opts.elements_per_patch);
}

bool BuildMesh(const Scene& scene, const MeshOptions& opts, Mesh* mesh,
               std::string* err, const std::function<void()>& read) {
  return BuildMesh(scene, BuildSurfaces(scene, opts.join), opts, mesh, err, read);
}

namespace {

// BuildMesh from `surfaces`; `consume`, when not null, is the same array,
// whose surfaces are freed as they are cut.
bool Build(const Scene& scene, const std::vector<Surface>& surfaces,
           std::vector<Surface>* consume, const MeshOptions& opts, Mesh* mesh, std::string* err,
           const std::function<void()>& read) {
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
  mesh->face_scene_at.reserve(surfaces.size() + 1);
  mesh->face_scene_at.push_back(0);
  mesh->elems.reserve(size_t(estimate));
  mesh->elem_area.reserve(size_t(estimate));
  mesh->parent.reserve(size_t(estimate));
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

  if (read) read();
  for (const Material& mat : scene.materials) mesh->materials.push_back({mat.kd, mat.ke});
  PointIds fv(&mesh->verts);
  Builder b(mesh, epp, &fv);
  // Freed bytes not yet given back: a trim walks the whole heap, so it
  // is done every few megabytes, not per surface.
  constexpr size_t kReturnEvery = size_t(8) << 20;
  size_t freed = 0;
  for (size_t s = 0; s < surfaces.size(); ++s) {
    const Surface& f = surfaces[s];
    MeshFace mf;
    mesh->face_scene.insert(mesh->face_scene.end(), f.faces.begin(), f.faces.end());
    mesh->face_scene_at.push_back(int32_t(mesh->face_scene.size()));
    mf.normal = f.normal;
    mf.material = f.material;
    mf.offset = f.offset;
    int face = int(mesh->faces.size());
    mesh->faces.push_back(std::move(mf));

    mesh->faces[face].vbegin = int(mesh->verts.size());
    fv.Clear();
    b.Start(face);
    const auto& v = f.poly;
    if (v.size() == 3) {
      double e = std::max({glm::length(v[1] - v[0]), glm::length(v[2] - v[1]),
                           glm::length(v[0] - v[2])});
      b.Tri(v[0], v[1], v[2], Cuts(e, ps));
    } else if (v.size() == 4 && Convex(v, f.normal)) {
      int nu = Cuts(std::max(glm::length(v[1] - v[0]), glm::length(v[2] - v[3])), ps);
      int nv = Cuts(std::max(glm::length(v[3] - v[0]), glm::length(v[2] - v[1])), ps);
      b.Quad(v[0], v[1], v[2], v[3], nu, nv);
    } else {
      // One cut count for all pieces keeps their shared edges conforming.
      auto tris = Triangulate(v, f.normal);
      int n = 1;
      for (const auto& t : tris)
        for (int k = 0; k < 3; ++k)
          n = std::max(n, Cuts(glm::length(v[t[(k + 1) % 3]] - v[t[k]]), ps));
      // Each piece's patches are its own: cells are per Tri call.
      for (size_t t = 0; t < tris.size(); ++t) b.Tri(v[tris[t][0]], v[tris[t][1]], v[tris[t][2]], n);
    }
    b.Finish();
    mesh->faces[face].vend = int(mesh->verts.size());
    if (consume) {
      Surface& done = (*consume)[s];
      freed += done.poly.capacity() * sizeof(done.poly[0]) + done.faces.capacity() * sizeof(int);
      FreeStorage(&done.poly), FreeStorage(&done.faces);
      if (freed >= kReturnEvery) {
        ReturnFreeMemory();
        freed = 0;
      }
    }
  }
  // Then the emptied surfaces' array (some 18 bytes an element) and what
  // was freed since the last trim, before the patches' areas and centres
  // are made: standing beside the whole mesh they were a worker's peak.
  if (consume) {
    FreeStorage(consume);
    ReturnFreeMemory();
  }

  mesh->patch_area.resize(mesh->patches.size());
  mesh->patch_center.resize(mesh->patches.size());
  for (size_t i = 0; i < mesh->patches.size(); ++i) {
    mesh->patch_center[i] = TopsCentroid(*mesh, int(i), &mesh->patch_area[i]);
    CHECK(mesh->patch_area[i] > 0);
  }
  FormGroups(opts, mesh);
  return true;
}

}  // namespace

bool BuildMesh(const Scene& scene, const std::vector<Surface>& surfaces, const MeshOptions& opts,
               Mesh* mesh, std::string* err, const std::function<void()>& read) {
  return Build(scene, surfaces, nullptr, opts, mesh, err, read);
}

bool BuildMesh(const Scene& scene, std::vector<Surface>&& surfaces, const MeshOptions& opts,
               Mesh* mesh, std::string* err, const std::function<void()>& read) {
  return Build(scene, surfaces, &surfaces, opts, mesh, err, read);
}

namespace {

// Depth first from the ids on `stack` (the last one first), children in
// order, appended to *out.
void CollectLeaves(const std::vector<Element>& elems, std::vector<int> stack,
                   std::vector<int>* out) {
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
  out->clear();
  const IdSpan tops = Tops(patch);
  CollectLeaves(elems, {std::make_reverse_iterator(tops.end()), std::make_reverse_iterator(tops.begin())}, out);
}

void Mesh::FaceLeaves(const MeshFace& f, std::vector<int>* out) const {
  out->clear();
  for (int p : FacePatches(f)) {
    const IdSpan tops = Tops(p);
    CollectLeaves(elems, {std::make_reverse_iterator(tops.end()), std::make_reverse_iterator(tops.begin())}, out);
  }
}

void Mesh::LeavesUnder(int elem, std::vector<int>* out) const {
  out->clear();
  CollectLeaves(elems, {elem}, out);
}

glm::dvec3 Mesh::Center(int patch) const {
  if (!columns_only) return patch_center[size_t(patch)];
  // A piece: one SplitPatch appended, or a split patch (its first piece).
  // Once a column: a scan of the split patches (up to about 2 x 10^5 at
  // 10^6 elements, some 0.1 ms against a column's 10).
  const IdSpan tops = Tops(patch);
  if (patch >= BuiltPatches() || std::find(splits.begin(), splits.end(), patch) != splits.end())
    return Centroid(tops[0]);
  double area;
  return TopsCentroid(*this, patch, &area);
}

void Mesh::KeepColumnsOnly() {
  columns_only = true;
  FreeStorage(&elem_area), FreeStorage(&parent), FreeStorage(&patch_area), FreeStorage(&patch_center);
  FreeStorage(&face_scene), FreeStorage(&face_scene_at), FreeStorage(&corner_begin), FreeStorage(&face_corners);
  if (groups.empty()) FreeStorage(&group_of);
}

glm::dvec3 Mesh::Centroid(int elem) const {
  const Element& e = elems[elem];
  int n = e.IsTriangle() ? 3 : 4;
  glm::dvec3 c(0.0);
  for (int k = 0; k < n; ++k) c += verts[e.v[k]];
  return c / double(n);
}

namespace {

// One step of the hash: the state xor a 64-bit word, through splitmix64.
uint64_t Mix(uint64_t h, uint64_t w) { return SplitMix64(h ^ w); }

uint64_t Int(int v) { return uint64_t(uint32_t(v)); }

}  // namespace

uint64_t MeshHash(const Mesh& mesh) {
  uint64_t h = 0x6d657368;  // "mesh"
  h = Mix(h, mesh.verts.size());
  h = Mix(h, mesh.elems.size());
  h = Mix(h, mesh.patches.size());
  h = Mix(h, mesh.faces.size());
  for (const auto& v : mesh.verts) {
    h = Mix(h, DoubleBits(v.x));
    h = Mix(h, DoubleBits(v.y));
    h = Mix(h, DoubleBits(v.z));
  }
  // A mesh that keeps columns only has its parents again from the children.
  std::vector<int32_t> parents;
  if (mesh.columns_only) {
    parents.assign(mesh.elems.size(), -1);
    for (size_t i = 0; i < mesh.elems.size(); ++i)
      for (int k = 0; k < kChildren && !mesh.elems[i].IsLeaf(); ++k)
        parents[size_t(mesh.elems[i].first_child + k)] = int32_t(i);
  }
  const std::vector<int32_t>& parent = mesh.columns_only ? parents : mesh.parent;
  for (size_t i = 0; i < mesh.elems.size(); ++i) {
    const Element& e = mesh.elems[i];
    h = Mix(h, Int(e.v[0]) | Int(e.v[1]) << 32);
    h = Mix(h, Int(e.v[2]) | Int(e.v[3]) << 32);
    h = Mix(h, Int(e.patch) | Int(parent[i]) << 32);
    h = Mix(h, Int(e.first_child) | Int(e.level) << 32);
    h = Mix(h, DoubleBits(mesh.columns_only ? ElementArea(mesh, e) : mesh.elem_area[i]));
  }
  for (size_t i = 0; i < mesh.patches.size(); ++i) {
    const Patch& p = mesh.patches[i];
    const glm::dvec3 c = mesh.Center(int(i));
    h = Mix(h, Int(p.face) | uint64_t(uint32_t(p.tops)) << 32);
    h = Mix(h, DoubleBits(c.x));
    h = Mix(h, DoubleBits(c.y));
    h = Mix(h, DoubleBits(c.z));
  }
  return h;
}
