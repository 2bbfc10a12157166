// Run-time subdivision's side of the mesh (declared in mesh.h): the flat
// edge adjacency of the leaves (ConnectEdges), dividing a leaf with shared
// midpoints and T-vertices (Divide), and the queries on that adjacency
// (MidpointOf, Outline, LeafNeighbours). Building the hierarchy and its
// hash are mesh.cpp's.
#include <algorithm>
#include <cstring>

#include "check.h"
#include "hash.h"
#include "mesh.h"

namespace {

int Corners(const Element& e) { return e.IsTriangle() ? 3 : 4; }

// Element e's corner after k: a compare, not a division by 3 or 4 (these
// run per edge of every edge-list walk).
int NextCorner(const Element& e, int k) { return k + 1 < Corners(e) ? k + 1 : 0; }
int Next(int k, int n) { return k + 1 < n ? k + 1 : 0; }

uint64_t Undirected(int a, int b) { return a < b ? EdgeKey(a, b) : EdgeKey(b, a); }

int32_t Slot(int elem, int k) { return int32_t(elem) * 4 + k; }

// The element (leaf or divided) whose edge k runs a -> b, or -1. Elements
// of a face never overlap, so there is at most one; divided ones stay in
// the lists, which is how MidpointOf() finds the midpoints they made.
int EdgeElement(const Mesh& m, int a, int b, int* k) {
  for (int32_t s = m.out_head[a]; s >= 0; s = m.out_next[s]) {
    const Element& e = m.elems[s >> 2];
    if (e.v[NextCorner(e, s & 3)] == b) {
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
  return SegmentHash(m.verts[e.v[k]], m.verts[e.v[NextCorner(e, k)]]);
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
    const glm::dvec3& b = m.verts[e.v[NextCorner(e, s & 3)]];
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
  if (add) BorderReserve(m, Corners(e));  // once, not per edge added
  for (int k = 0, n = Corners(e); k < n; ++k) {
    if (!add) {
      if (bits >> k & 1) BorderRemove(m, Slot(elem, k));
    } else if (Owner(*m, e.v[Next(k, n)], e.v[k]) < 0) {
      bits |= uint8_t(1 << k);
      BorderPut(&m->border, *m, Slot(elem, k));
      ++m->border_count;
    }
  }
  if (!add) bits = 0;
}

// Element elem's edge k becomes home to T-vertex v.
void PutMid(Mesh* m, int elem, int k, int v) {
  m->tverts.try_emplace(elem, std::array<int, 4>{{-1, -1, -1, -1}}).first->second[k] = v;
  m->elems[elem].tverts = true;
}

// Element n's edge (p, q) (its own vertex ids) becomes home to T-vertex v.
void SetMid(Mesh* m, int n, int p, int q, int v) {
  const Element& e = m->elems[n];
  for (int k = 0, c = Corners(e); k < c; ++k)
    if (e.v[k] == p && e.v[Next(k, c)] == q) PutMid(m, n, k, v);
}

// A vertex Divide() makes: on an edge (a, b), or a quad's centre (a < 0).
int AddVertex(Mesh* m, int face, int a, int b, const glm::dvec3& p) {
  const int v = int(m->verts.size());
  m->verts.push_back(p);
  MeshFace& f = m->faces[size_t(face)];
  if (f.divided_at < 0) {
    f.divided_at = int32_t(m->divide_verts.size());
    m->divide_verts.emplace_back();
  }
  m->divide_verts[size_t(f.divided_at)].push_back(v);
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
    SetMid(m, n, b, a, v);
    return v;
  }
  // Copies: AddVertex() below grows (and may move) m->verts.
  const glm::dvec3 pa = m->verts[a], pb = m->verts[b];
  std::vector<int> along;
  BorderFind(*m, pa, pb, &along);
  for (int n : along) {
    const Element& ne = m->elems[n];
    const int nf = m->patches[ne.patch].face;
    if (nf == face || !ne.IsLeaf()) continue;
    const std::array<int, 4> mids = m->Mids(n);
    for (int k = 0, c = Corners(ne); k < c; ++k) {
      const int x = ne.v[k], y = ne.v[Next(k, c)];
      const glm::dvec3 px = m->verts[x], py = m->verts[y];
      if (mids[k] >= 0 || !((px == pa && py == pb) || (px == pb && py == pa))) continue;
      PutMid(m, n, k, AddVertex(m, nf, x, y, p));
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
      if (const int v = m.Mids(e)[k]; v >= 0) return v;
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
      if (Owner(*mesh, el.v[Next(k, n)], el.v[k]) < 0) {
        mesh->border_bits[e] |= uint8_t(1 << k);
        border.push_back(Slot(int(e), k));
      }
  }
  BorderReserve(mesh, border.size());
  for (int32_t s : border) BorderPut(&mesh->border, *mesh, s);
  mesh->border_count = border.size();
}

void ReleaseEdges(Mesh* mesh) {
  for (auto* v : {&mesh->out_head, &mesh->out_next, &mesh->border}) std::vector<int32_t>().swap(*v);
  std::vector<uint64_t>().swap(mesh->split);
  std::vector<uint8_t>().swap(mesh->border_bits);
  mesh->border_count = 0;
  mesh->connected = false;
}

void Divide(Mesh* mesh, int32_t elem) {
  ConnectEdges(mesh);
  CHECK(elem >= 0 && size_t(elem) < mesh->elems.size() && mesh->elems[elem].IsLeaf());
  const Element parent = mesh->elems[elem];
  const int face = mesh->patches[parent.patch].face;
  const int n = Corners(parent);
  int mid[4];
  for (int k = 0; k < n; ++k) mid[k] = Midpoint(mesh, face, parent.v[k], parent.v[Next(k, n)]);
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
  for (int c = 0; c < kChildren; ++c) {
    const std::array<int, 4>& kv = kids[c];
    CHECK(c >= n || kv[c] == v[c]);
    Element child;
    child.v = kv;
    child.patch = parent.patch;
    child.level = parent.level + 1;
    // A neighbour already finer than the parent by two levels leaves a
    // T-vertex on the child's edge (the subdivision policy avoids it).
    // Only on the parent's outline: child c < n has parent corner c at its
    // corner c (as kids lays them out), so its edges c - 1 and c; the
    // others lie inside the parent (on its new centre, or between two of
    // its sides' midpoints), where nothing but the children has an edge.
    int mids[4] = {-1, -1, -1, -1};
    for (int k = 0; k < n; ++k)
      if (c < n && (k == c || Next(k, n) == c)) mids[k] = MidpointOf(*mesh, kv[k], kv[Next(k, n)]);
    const int id = int(mesh->elems.size());
    mesh->elems.push_back(child);
    if (!mesh->columns_only) {
      mesh->elem_area.push_back(ElementArea(*mesh, child));
      mesh->parent.push_back(elem);
    }
    for (int k = 0; k < n; ++k)
      if (mids[k] >= 0) PutMid(mesh, id, k, mids[k]);
    Link(mesh, id);
  }
  for (int k = 0; k < kChildren; ++k) Border(mesh, first + k, true);
}

int Outline(const Mesh& mesh, int elem, int out[8]) {
  const Element& e = mesh.elems[elem];
  const std::array<int, 4> mids = mesh.Mids(elem);
  int ids[8], n = 0, from = -1;
  for (int k = 0; k < Corners(e); ++k) {
    ids[n++] = e.v[k];
    if (mids[k] < 0) continue;
    if (from < 0) from = n;
    ids[n++] = mids[k];
  }
  if (from < 0) from = 0;
  for (int i = 0; i < n; ++i) out[i] = ids[(from + i) % n];
  return n;
}

void LeafNeighbours(const Mesh& mesh, int elem, std::vector<int>* out) {
  out->clear();
  const Element& e = mesh.elems[elem];
  const std::array<int, 4> mids = mesh.Mids(elem);
  auto add = [&](int a, int b) {
    const int n = Owner(mesh, a, b);
    if (n >= 0 && std::find(out->begin(), out->end(), n) == out->end()) out->push_back(n);
    return n >= 0;
  };
  for (int k = 0, c = Corners(e); k < c; ++k) {
    const int p = e.v[k], q = e.v[Next(k, c)];
    if (add(q, p)) continue;               // alike
    if (mids[k] >= 0) {                    // finer, across a T-vertex
      add(q, mids[k]);
      add(mids[k], p);
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

