// The hemicube's per-mesh cache (declared in hemicube.h): each face's
// plane, box and element outlines laid out flat in the order a column reads
// them, and the bounding-volume hierarchy over the faces, rebuilt when the
// mesh changes (Key). Drawing a column from it is hemicube.cpp's.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>

#include "check.h"
#include "float_round.h"
#include "groups.h"
#include "hemicube.h"
#include "memory.h"

bool Hemicube::Key::operator==(const Key& o) const {
  return mesh == o.mesh && verts == o.verts && elems == o.elems && nverts == o.nverts &&
         nelems == o.nelems && nfaces == o.nfaces && divided == o.divided && splits == o.splits &&
         first == o.first &&
         last == o.last;
}

// What changes when the mesh does: Divide() appends elements and vertices
// and counts itself; SplitPatch() reorders a face's leaves and counts
// itself; a mesh built anew moves its arrays or their sizes or
// end points. Cheap enough to compare on every column.
Hemicube::Key Hemicube::KeyOf(const Mesh& mesh) {
  Key k;
  k.mesh = &mesh;
  k.verts = mesh.verts.data();
  k.elems = mesh.elems.data();
  k.nverts = mesh.verts.size();
  k.nelems = mesh.elems.size();
  k.nfaces = mesh.faces.size();
  k.divided = mesh.divided;
  k.splits = mesh.splits.size();
  if (!mesh.verts.empty()) {
    k.first = mesh.verts.front();
    k.last = mesh.verts.back();
  }
  return k;
}

void Hemicube::ReleaseCache() {
  key_ = Key();  // the next Column builds the cache again, or updates it
  FreeStorage(&acc_), FreeStorage(&block_), FreeStorage(&touched_);
}

Hemicube::FaceBox Hemicube::BoxOf(const Mesh& mesh, const MeshFace& mf) {
  glm::dvec3 lo = mesh.verts[mf.vbegin], hi = lo;
  auto grow = [&](int i) {
    lo = glm::min(lo, mesh.verts[i]);
    hi = glm::max(hi, mesh.verts[i]);
  };
  for (int i = mf.vbegin; i < mf.vend; ++i) grow(i);
  for (int i : mesh.DivideVerts(mf)) grow(i);
  FaceBox box;
  for (int a = 0; a < 3; ++a) {
    box.lo[a] = FloatDown(lo[a]);
    box.hi[a] = FloatUp(hi[a]);
  }
  return box;
}

void Hemicube::BuildCache(const Mesh& mesh) {
  if (UpdateCache(mesh)) return;
  // A column reads the mesh's vertices face by face in the hierarchy's
  // order, scattered over the array as the cache's own arrays are.
  PreferHugePages(mesh.verts.data(), mesh.verts.size() * sizeof(mesh.verts[0]));
  // The old cache's largest arrays go first, not kept beside the new ones.
  FreeStorage(&faces_), FreeStorage(&boxes_), FreeStorage(&outline_), FreeStorage(&outline_wide_);
  FreeStorage(&elem_), FreeStorage(&outline_n_);
  // First in face order: planes, boxes and ranks (the order a plain
  // z-buffer draws the leaves in, which breaks depth ties).
  Huge<CacheFace> byface;
  Huge<FaceBox> bybox;
  std::vector<int> leaves;
  // Reserved to their sizes (an upper bound for byface): grown by doubling,
  // the copies of faces were the largest thing a -j 0 master held.
  byface.reserve(mesh.faces.size());
  bybox.reserve(mesh.faces.size());
  elem_.reserve(size_t(mesh.LeafCount()));
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const MeshFace& mf = mesh.faces[f];
    CacheFace cf;
    cf.face = int(f);
    cf.normal = mf.normal;
    cf.offset = mf.offset;
    cf.lb = int(elem_.size());
    mesh.FaceLeaves(mf, &leaves);
    elem_.insert(elem_.end(), leaves.begin(), leaves.end());
    cf.le = int(elem_.size());
    if (cf.le == cf.lb) continue;  // nothing to draw
    byface.push_back(cf);
    bybox.push_back(BoxOf(mesh, mf));
  }
  // Culling needs of the hierarchy only that each node's box holds its
  // faces' boxes (its children's hold theirs): any such hierarchy gives
  // the same columns (hemicube.h, set_culling). So it is kept where as
  // many faces have leaves and each lies within its node's box as it
  // stands (another mesh of the same faces); BuildNodes would take about a
  // tenth of a second at 10^6 elements.
  std::vector<int> order(byface.size());
  bool keep = !nodes_.empty() && by_face_.size() == byface.size();
  if (keep) {
    for (size_t j = 0; j < order.size(); ++j) order[size_t(by_face_[j])] = int(j);
    for (const Node& nd : nodes_) {
      if (nd.right >= 0) continue;
      for (int i = nd.first; keep && i < nd.first + nd.count; ++i) {
        const FaceBox& b = bybox[size_t(order[size_t(i)])];
        for (int a = 0; a < 3; ++a) keep &= b.lo[a] >= nd.box.lo[a] && b.hi[a] <= nd.box.hi[a];
      }
      if (!keep) break;
    }
  }
  if (!keep) {
    for (size_t i = 0; i < order.size(); ++i) order[i] = int(i);
    nodes_.clear();
    if (!order.empty()) BuildNodes(bybox, &order, 0, int(order.size()));
    ++hierarchy_builds_;
  }

  // Then laid out in the hierarchy's order, the order a column reads them:
  // each face's vertices and its leaves' outlines together. The faces and
  // boxes are permuted in place, cycle by cycle: a second copy of them was
  // the largest thing a worker held while it built the cache.
  faces_ = std::move(byface);
  boxes_ = std::move(bybox);
  by_face_.assign(order.size(), 0);
  auto permute = [&order](auto* a) {
    std::vector<bool> done(order.size());
    for (size_t i = 0; i < order.size(); ++i) {
      if (done[i]) continue;
      const auto first = (*a)[i];
      size_t j = i;
      for (size_t k = size_t(order[j]); k != i; j = k, k = size_t(order[k])) {
        (*a)[j] = (*a)[k];
        done[j] = true;
      }
      (*a)[j] = first;
      done[j] = true;
    }
  };
  permute(&faces_);
  permute(&boxes_);
  // Each leaf's outline, counted first so that it is allocated once at
  // its size (grown by doubling, its old copies stayed resident).
  outline_n_.resize(elem_.size());
  size_t total = 0;
  for (size_t r = 0; r < elem_.size(); ++r) {
    int vid[8];
    outline_n_[r] = uint8_t(Outline(mesh, elem_[r], vid));
    total += outline_n_[r];
  }
  size_t most = 0;
  for (const CacheFace& cf : faces_) {
    const MeshFace& mf = mesh.faces[cf.face];
    most = std::max(most, size_t(mf.vend - mf.vbegin) + mesh.DivideVerts(mf).size());
  }
  // 16 bits an index where they fit: 8 bytes an element less.
  wide_ = most > 65536;
  if (wide_) outline_wide_.reserve(total);
  else outline_.reserve(total);
  for (size_t f = 0; f < faces_.size(); ++f) {
    by_face_[order[f]] = int(f);
    PutOutlines(mesh, &faces_[f]);
  }
  FinishCache(mesh, most);
}

// After divisions and splits (a pass's, applied by a worker or a -j 0
// master) only the faces they touched are read from the mesh again: a
// face with a new element or a split patch, or with a vertex Divide added
// (the midpoint a division in a neighbouring face put on its edge, which
// its leaves' outlines then go through). Every other face's leaves,
// outline lengths and outlines are copied as they stand. Faces, boxes and
// hierarchy stay: divisions add no face, and their vertices lie on the
// face's edges or within it, inside its box (checked: else the whole
// build). At 10^6 elements the whole build took 0.08 s a pass on each
// worker, 0.56 s of its 200-shot run. False, having changed nothing,
// where the cache is not this mesh's before such edits.
bool Hemicube::UpdateCache(const Mesh& mesh) {
  const Key& was = cached_;
  if (faces_.empty() || was.mesh != &mesh || was.nfaces != mesh.faces.size() ||
      mesh.verts.empty() || was.first != mesh.verts.front() || was.nverts > mesh.verts.size() ||
      was.nelems > mesh.elems.size() || was.splits > mesh.splits.size() ||
      was.divided > mesh.divided)
    return false;
  std::vector<uint8_t> redo(mesh.faces.size(), 0);
  for (size_t e = was.nelems; e < mesh.elems.size(); ++e)
    redo[size_t(mesh.patches[size_t(mesh.elems[e].patch)].face)] = 1;
  for (size_t i = was.splits; i < mesh.splits.size(); ++i)
    redo[size_t(mesh.patches[size_t(mesh.splits[i])].face)] = 1;
  size_t most = 0;
  for (size_t j = 0; j < faces_.size(); ++j) {
    const CacheFace& cf = faces_[j];
    const MeshFace& mf = mesh.faces[size_t(cf.face)];
    const size_t nd = mesh.DivideVerts(mf).size();
    most = std::max(most, size_t(mf.vend - mf.vbegin) + nd);
    if (nd != size_t(cf.nd)) redo[size_t(cf.face)] = 1;
    if (!redo[size_t(cf.face)]) continue;
    const FaceBox b = BoxOf(mesh, mf);
    if (std::memcmp(&b, &boxes_[j], sizeof b) != 0) return false;
  }
  if ((most > 65536) != wide_) return false;

  // Leaves and outline lengths in face order, as the whole build lays them.
  Huge<int32_t> elem;
  Huge<uint8_t> count;
  elem.reserve(size_t(mesh.LeafCount()));
  count.reserve(size_t(mesh.LeafCount()));
  std::vector<int> lb(faces_.size()), le(faces_.size()), leaves;
  for (int j : by_face_) {
    const CacheFace& cf = faces_[size_t(j)];
    lb[size_t(j)] = int(elem.size());
    if (!redo[size_t(cf.face)]) {
      elem.insert(elem.end(), elem_.begin() + cf.lb, elem_.begin() + cf.le);
      count.insert(count.end(), outline_n_.begin() + cf.lb, outline_n_.begin() + cf.le);
    } else {
      mesh.FaceLeaves(mesh.faces[size_t(cf.face)], &leaves);
      for (int l : leaves) {
        int vid[8];
        elem.push_back(l);
        count.push_back(uint8_t(Outline(mesh, l, vid)));
      }
    }
    le[size_t(j)] = int(elem.size());
  }
  size_t total = 0;
  for (uint8_t n : count) total += n;
  elem_ = std::move(elem);
  outline_n_ = std::move(count);
  // The outlines in the hierarchy's order: a face's old ones end where the
  // next face's begin (read before that face is laid out anew).
  Huge<uint16_t> old16 = std::move(outline_);
  Huge<int32_t> old32 = std::move(outline_wide_);
  const size_t old_total = wide_ ? old32.size() : old16.size();
  outline_.clear(), outline_wide_.clear();
  if (wide_) outline_wide_.reserve(total);
  else outline_.reserve(total);
  for (size_t j = 0; j < faces_.size(); ++j) {
    CacheFace& cf = faces_[j];
    const long from = cf.pb, to = long(j + 1 < faces_.size() ? size_t(faces_[j + 1].pb) : old_total);
    cf.lb = lb[j];
    cf.le = le[j];
    if (redo[size_t(cf.face)]) {
      PutOutlines(mesh, &cf);
      continue;
    }
    cf.pb = int(wide_ ? outline_wide_.size() : outline_.size());
    if (wide_) outline_wide_.insert(outline_wide_.end(), old32.begin() + from, old32.begin() + to);
    else outline_.insert(outline_.end(), old16.begin() + from, old16.begin() + to);
  }
  ++cache_updates_;
  FinishCache(mesh, most);
  return true;
}

bool Hemicube::SameCache(const Hemicube& o) const {
  if (faces_.size() != o.faces_.size()) return false;
  for (size_t j = 0; j < faces_.size(); ++j) {
    const CacheFace &a = faces_[j], &b = o.faces_[j];
    if (a.face != b.face || a.vb != b.vb || a.ve != b.ve || a.nd != b.nd || a.lb != b.lb ||
        a.le != b.le || a.pb != b.pb || a.normal != b.normal || a.offset != b.offset)
      return false;
  }
  return std::memcmp(boxes_.data(), o.boxes_.data(), boxes_.size() * sizeof(FaceBox)) == 0 &&
         by_face_ == o.by_face_ && elem_ == o.elem_ && outline_n_ == o.outline_n_ &&
         wide_ == o.wide_ && outline_ == o.outline_ && outline_wide_ == o.outline_wide_;
}

void Hemicube::PutOutlines(const Mesh& mesh, CacheFace* cf) {
  const MeshFace& mf = mesh.faces[size_t(cf->face)];
  cf->vb = mf.vbegin;
  cf->ve = mf.vend;
  // Face-relative indices, in the order DrawFace transforms them: its
  // vertices, then its divide_verts, which keep the order of vertex ids
  // (Divide appends), as the near-plane clip needs to cut shared edges
  // alike; so a divide_vert's index is found by binary search.
  const std::vector<int>& dv = mesh.DivideVerts(mf);
  cf->nd = int(dv.size());
  CHECK(dv.empty() || dv.front() >= mf.vend);
  CHECK(std::adjacent_find(dv.begin(), dv.end(), std::greater_equal<int>()) == dv.end());
  cf->pb = int(wide_ ? outline_wide_.size() : outline_.size());
  for (int r = cf->lb; r < cf->le; ++r) {
    int vid[8];
    const int nv = Outline(mesh, elem_[size_t(r)], vid);
    for (int i = 0; i < nv; ++i) {
      int rel = vid[i] - cf->vb;
      if (vid[i] >= cf->ve) {
        const auto it = std::lower_bound(dv.begin(), dv.end(), vid[i]);
        CHECK(it != dv.end() && *it == vid[i]);  // a vertex of this face
        rel = cf->ve - cf->vb + int(it - dv.begin());
      }
      CHECK(rel >= 0);
      if (wide_) outline_wide_.push_back(rel);
      else outline_.push_back(uint16_t(rel));
    }
  }
}

void Hemicube::FinishCache(const Mesh& mesh, size_t most) {
  for (auto* a : {&lx_, &ly_, &lz_}) a->resize(most);
  code_.resize(most);
  for (int h = 0; h < 5; ++h) {
    sxy_[h].resize(most);
  }
  acc_.clear();
  block_.assign((mesh.elems.size() + kSumBlock - 1) / kSumBlock, -1);
  touched_.assign((mesh.elems.size() + 63) / 64, 0);
  // HugePageAllocator's arrays are advised before their first touch, but
  // the heap hands out memory the mesh's build already touched in small
  // pages, which the advice leaves so: collapsed now, once filled.
  auto huge = [](const auto& a) { PreferHugePages(a.data(), a.size() * sizeof(a[0])); };
  huge(faces_), huge(boxes_), huge(elem_), huge(outline_), huge(outline_wide_);
  huge(outline_n_), huge(nodes_), huge(block_);
  key_ = cached_ = KeyOf(mesh);
}

// Median split along the box's longest axis, down to a few faces a node:
// a face's own test is as cheap as a node's, and a leaf of 8 small faces
// costs fewer node tests than it draws in vain (a tessellated scene: about
// 8% less time than 4 a leaf, 16 no better).
int Hemicube::BuildNodes(const Huge<FaceBox>& boxes, std::vector<int>* order,
                         int first, int count) {
  constexpr int kLeafFaces = 8;
  const int at = int(nodes_.size());
  nodes_.emplace_back();
  Node nd;
  nd.box = boxes[(*order)[first]];
  for (int i = first; i < first + count; ++i)
    for (int a = 0; a < 3; ++a) {
      nd.box.lo[a] = std::min(nd.box.lo[a], boxes[(*order)[i]].lo[a]);
      nd.box.hi[a] = std::max(nd.box.hi[a], boxes[(*order)[i]].hi[a]);
    }
  if (count <= kLeafFaces) {
    nd.first = first;
    nd.count = count;
  } else {
    const glm::dvec3 ext = nd.box.Hi() - nd.box.Lo();
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
    const int mid = first + count / 2;
    std::nth_element(order->begin() + first, order->begin() + mid,
                     order->begin() + first + count, [&](int a, int b) {
                       return double(boxes[a].lo[axis]) + boxes[a].hi[axis] <
                              double(boxes[b].lo[axis]) + boxes[b].hi[axis];
                     });
    BuildNodes(boxes, order, first, mid - first);
    nd.right = BuildNodes(boxes, order, mid, first + count - mid);
  }
  nodes_[at] = nd;
  return at;
}

// Whether a pixel of hemicube face h in [xa, xb) x [ra, rb) holds a depth
// <= zt (something at zt could show there): tile by tile, by the tile's
// least depth where that settles it (kept up to date lazily: Scan marks
// the tiles it writes), else pixel by pixel in the tile's part of the
// rectangle, stopping at the first.
