// The patch -> element hierarchy built from the scene's faces.
//
// The input faces are joined into surfaces (surface.h): adjacent coplanar
// faces of one material become one convex polygon. Each surface (a
// MeshFace) is cut into patches (the shooters) of at most
// MeshOptions::patch_size across, and each patch into elements (the
// receivers), which may cover parts of several input faces. Elements are
// convex planar triangles or quads; vertices are shared inside one
// surface (for Gouraud shading and gap-free hemicube rasterisation) but
// never across surfaces, so that shading does not bleed
// round corners. Grid points on a face's edge are computed from the edge's
// endpoints in a canonical order, so two faces cut the same way along a
// common edge produce bit-identical points and the hemicube sees no cracks.
//
// The hierarchy is plain data (ids into flat arrays) so that run-time
// subdivision can append children and ship the same edits to workers:
// Divide() is deterministic, so the same sequence of divisions applied to
// two equal meshes leaves them equal, element and vertex ids included.
#ifndef RADIOSITY_MESH_H
#define RADIOSITY_MESH_H

#include <array>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "coding.h"
#include "hash.h"
#include "scene.h"
#include "surface.h"

// A divided element has kChildren consecutive children: a quad 2 x 2 by
// its edge midpoints and centre, a triangle into four by its edge midpoints.
constexpr int kChildren = 4;

struct Element {
  std::array<int, 4> v{{-1, -1, -1, -1}};  // vertex ids, CCW; v[3] < 0: triangle
  int patch = -1;                          // owning patch
  int first_child = -1;                    // -1: a leaf (a receiver)
  uint8_t level = 0;                       // 0..12 (--max-level)
  // Mesh::tverts holds T-vertices on its edges: few elements have any, so
  // they are kept beside the elements, not in each (40 bytes, not 56).
  // Its area and parent are apart too (Mesh::elem_area, Mesh::parent),
  // which a worker does not keep.
  bool tverts = false;
  bool IsTriangle() const { return v[3] < 0; }
  bool IsLeaf() const { return first_child < 0; }
};
static_assert(sizeof(Element) == 28, "README, Memory: bytes per element");

// Ids in one of the mesh's flat arrays, [first, last): a patch's top
// elements, a surface's scene faces (Mesh::Tops, Mesh::SceneFaces).
struct IdSpan {
  const int32_t* first = nullptr;
  const int32_t* last = nullptr;
  const int32_t* begin() const { return first; }
  const int32_t* end() const { return last; }
  size_t size() const { return size_t(last - first); }
  int32_t operator[](size_t i) const { return first[i]; }
};

struct Patch {
  int face = -1;                 // index into Mesh::faces
  // Its top-level elements: Mesh::patch_tops[tops_at, tops_at + tops)
  // (a range of one flat array rather than a vector a patch and its heap
  // block: 48 bytes a patch less).
  int32_t tops_at = 0, tops = 0;
  int32_t next_piece = -1;       // the face's next patch SplitPatch appended, or -1
  // Its area and centre are apart (Mesh::patch_area, Mesh::Center): a
  // worker keeps neither.
};
static_assert(sizeof(Patch) == 16, "README, Memory: bytes per patch");

// A surface (surface.h): one input face, or adjacent coplanar faces of
// one material joined into a convex polygon.
struct MeshFace {
  int vbegin = 0, vend = 0;      // its vertices: Mesh::verts[vbegin, vend)
  // Its patches (Mesh::FacePatches): BuildMesh's, Mesh::patches[patch_at,
  // patch_at + built), then those SplitPatch appended, first_piece to
  // last_piece by Patch::next_piece (not a vector a face and its heap
  // block: 40 bytes a face less).
  int32_t patch_at = 0, built = 0, first_piece = -1, last_piece = -1;
  int material = 0;              // Scene::materials and Mesh::materials index
  // The vertices Divide() added to it (Mesh::DivideVerts): its list in
  // Mesh::divide_verts, or -1 while it has none (most faces; a vector in
  // every face was 24 bytes). Its scene faces are apart (Mesh::SceneFaces),
  // which a worker does not keep: one cache line a face, not 104 bytes.
  int32_t divided_at = -1;
  glm::dvec3 normal{0.0};
  double offset = 0.0;           // plane: dot(normal, x) == offset
};
static_assert(sizeof(MeshFace) == 64, "README, Memory: bytes per face");

// A face's patches in order, BuildMesh's then SplitPatch's pieces:
// for (int p : mesh.FacePatches(face)).
struct FacePatchIds {
  const std::vector<Patch>* patches;
  int32_t first, built_end, first_piece;
  struct Iterator {
    const FacePatchIds* ids;
    int32_t p;
    int operator*() const { return p; }
    Iterator& operator++() {
      p = p + 1 < ids->built_end ? p + 1
          : p < ids->built_end   ? ids->first_piece
                                 : (*ids->patches)[size_t(p)].next_piece;
      return *this;
    }
    bool operator!=(const Iterator& o) const { return p != o.p; }
  };
  Iterator begin() const { return {this, first < built_end ? first : first_piece}; }
  Iterator end() const { return {this, -1}; }
  // Walks the pieces: a face has few.
  size_t size() const {
    size_t n = 0;
    for (Iterator i = begin(); i != end(); ++i) ++n;
    return n;
  }
  int operator[](size_t k) const {
    Iterator i = begin();
    while (k-- > 0) ++i;
    return *i;
  }
};

// Hash of a point by value (glm's == compares by value), for joining
// equal points: a face's shared grid points, coplanar faces' shading.
// -0 and 0 hash alike, as they compare equal.
struct PointHash {
  static uint64_t Bits(double d) { return DoubleBits(d == 0 ? 0.0 : d); }
  size_t operator()(const glm::dvec3& p) const {
    return SplitMix64(SplitMix64(SplitMix64(Bits(p.x)) ^ Bits(p.y)) ^ Bits(p.z));
  }
};

struct MeshOptions {
  // Largest patch edge; 0 picks the default rule: the scene's bounding-box
  // diagonal / 16 (see man page, MESH).
  double patch_size = 0.0;
  // Elements per patch edge (a patch becomes n x n elements).
  int elements_per_patch = 2;
  // Join adjacent coplanar faces of one material into surfaces before
  // cutting (surface.h; --no-join turns it off).
  bool join = true;
  // Shooter groups (groups.h): small patches that shoot together, formed
  // in cells of group_size; 0 picks the default, the patch size.
  bool groups = true;
  double group_size = 0.0;
};

// Patches that shoot together from one hemicube (groups.h).
struct PatchGroup {
  std::vector<int> members;      // increasing; members[0] is the shooter
  double area = 0.0;             // Σ member areas
  glm::dvec3 center{0.0};        // area centroid: where the hemicube sits
  glm::dvec3 normal{0.0};        // area-weighted mean normal, unit
};

struct Mesh {
  std::vector<glm::dvec3> verts;
  std::vector<Element> elems;
  std::vector<Patch> patches;
  std::vector<MeshFace> faces;
  // What only the master reads (the solver, subdivision, groups, the
  // results), apart from Element and Patch so that a worker need not keep
  // it (KeepColumnsOnly): 12 bytes an element and 32 a patch. double, as
  // are vertices, normals and offsets: a 1e4 sliver or a scene at 1e-4 or
  // 1e4 must keep its areas and planes; the solver divides by areas (ρ/A)
  // and sums B·A over 1e6 : 1e-6 light ranges.
  std::vector<double> elem_area;         // per element: ElementArea
  std::vector<int32_t> parent;           // per element: -1 if made by BuildMesh
  std::vector<double> patch_area;        // per patch: Σ its top elements' areas
  std::vector<glm::dvec3> patch_center;  // per patch: see Center
  bool columns_only = false;             // KeepColumnsOnly ran
  // The patches' top elements, patch by patch (Patch::tops_at), and the
  // surfaces' scene faces (face_scene_at). A split patch keeps its
  // first slot for its first piece; its other pieces are appended.
  std::vector<int32_t> patch_tops;
  std::vector<int32_t> face_scene;
  // Per face and one more: face f's scene faces are face_scene[
  // face_scene_at[f], face_scene_at[f + 1]) (SceneFaces; master only).
  std::vector<int32_t> face_scene_at;
  // The vertices Divide() added to a face, per face that has any
  // (MeshFace::divided_at; DivideVerts), in the order it added them.
  std::vector<std::vector<int>> divide_verts;
  // Per Scene::materials index: Kd and Ke, looked up through
  // MeshFace::material (Rho, Emission) rather than 48 bytes in every face.
  struct Material {
    glm::dvec3 rho{0.0}, emission{0.0};
  };
  std::vector<Material> materials;
  // The T-vertices of the elements with Element::tverts: mids[k] >= 0 is a
  // vertex a finer neighbour put at the midpoint of edge v[k] -> v[k+1],
  // drawn as a corner of this element too, so that the hemicube sees no
  // crack and shading no seam along the edge.
  std::unordered_map<int32_t, std::array<int, 4>> tverts;
  double patch_size = 0.0;     // as used
  double scene_diagonal = 0.0; // bounding-box diagonal, the scene's scale
  // The corners of the input faces that joined into larger surfaces, for
  // their results (FaceRadiosity weighs each leaf by its overlap with the
  // face): scene face f's are face_corners[corner_begin[f], corner_begin[f + 1]),
  // empty for a face that is a surface alone. corner_begin has a row per
  // scene face and one more.
  std::vector<glm::dvec3> face_corners;
  std::vector<int> corner_begin;
  std::vector<PatchGroup> groups;  // FormGroups (groups.h)
  std::vector<int32_t> group_of;   // per patch: index into groups, or -1

  // Adjacency for Divide() and LeafNeighbours(), made by ConnectEdges()
  // and kept by Divide(): flat arrays indexed by vertex or by edge slot
  // 4 × element + k (edge k of an element runs v[k] -> v[k+1]), about 45
  // bytes per element in all (README, Layout). Vertex ids are per face, so
  // none of it joins two faces but `border`.
  std::vector<int32_t> out_head;  // per vertex: a slot whose edge leaves it, or -1
  std::vector<int32_t> out_next;  // per slot: the next slot leaving the same vertex
  // Per vertex Divide() added (from split_base): the undirected edge
  // (EdgeKey(min, max)) it is the midpoint of; kNoEdge for a quad's centre.
  std::vector<uint64_t> split;
  int32_t split_base = 0;
  // Leaves' edges with no leaf of their face on the exact reverse edge when
  // they were made (bit k per element), and an open-addressing table of
  // those slots (-1: empty) hashed by the edge's two points: the
  // neighbours in other faces, which get a copy of a midpoint made there.
  std::vector<uint8_t> border_bits;
  std::vector<int32_t> border;
  size_t border_count = 0;
  bool connected = false;                      // once ConnectEdges() ran
  int divided = 0;                             // Divide() calls so far
  // The patches SplitPatch() split, in the order it ran (a patch may be
  // split more than once): its pieces are the patches it appended.
  std::vector<int32_t> splits;
  long split_added = 0;  // patches SplitPatch() appended

  long LeafCount() const { return long(elems.size()) - divided; }
  // The patches as BuildMesh made them, however many splits since.
  long BuiltPatches() const { return long(patches.size()) - split_added; }

  IdSpan Tops(int patch) const {
    const Patch& p = patches[size_t(patch)];
    return {patch_tops.data() + p.tops_at, patch_tops.data() + p.tops_at + p.tops};
  }
  FacePatchIds FacePatches(const MeshFace& f) const {
    return {&patches, f.patch_at, f.patch_at + f.built, f.first_piece};
  }
  IdSpan SceneFaces(size_t face) const {
    return {face_scene.data() + face_scene_at[face], face_scene.data() + face_scene_at[face + 1]};
  }
  const std::vector<int>& DivideVerts(const MeshFace& f) const {
    static const std::vector<int> kNone;
    return f.divided_at < 0 ? kNone : divide_verts[size_t(f.divided_at)];
  }
  // Leaf elements of a patch, in a stable order.
  void Leaves(int patch, std::vector<int>* out) const;
  // Leaf elements of a face: its patches' (FacePatches) in turn.
  void FaceLeaves(const MeshFace& f, std::vector<int>* out) const;
  // Leaf elements under element `elem` (itself when it is a leaf).
  void LeavesUnder(int elem, std::vector<int>* out) const;
  const MeshFace& FaceOf(int elem) const { return faces[patches[elems[elem].patch].face]; }
  const glm::dvec3& Rho(const MeshFace& f) const { return materials[size_t(f.material)].rho; }
  const glm::dvec3& Emission(const MeshFace& f) const { return materials[size_t(f.material)].emission; }
  // Element elem's T-vertices (Mesh::tverts), -1 where it has none.
  std::array<int, 4> Mids(int elem) const {
    if (!elems[size_t(elem)].tverts) return {{-1, -1, -1, -1}};
    return tverts.at(elem);
  }
  glm::dvec3 Centroid(int elem) const;
  // A patch's centre, where the hemicube sits: a piece SplitPatch made
  // has its top element's centroid, other patches their top elements'
  // area centroid. Kept in patch_center; computed again, to the bit, once
  // KeepColumnsOnly freed it (a worker needs only those it shoots).
  glm::dvec3 Center(int patch) const;
  // Frees what only the master reads: the areas, parents, patch centres, the
  // links back to the scene's faces (face_scene, corner_begin,
  // face_corners), and the group index per patch where no groups formed
  // (an empty one reads alike: GroupOf, SplitPieces). Divide and
  // SplitPatch do not fill them from then on. The columns are the same.
  void KeepColumnsOnly();
};

// Builds the mesh. Fails (false, *err) only when limits are exceeded, e.g.
// the element count a patch size implies is larger than kMaxElements.
// `read`, when given, is called once BuildMesh has read the faces'
// vertices (the surfaces are made, their corners copied) and before any
// element is made: from then on it reads only the scene's materials, so a
// caller done with the vertices may free them there (the worker does:
// its peak is the mesh built beside the scene).
bool BuildMesh(const Scene& scene, const MeshOptions& opts, Mesh* mesh,
               std::string* err, const std::function<void()>& read = nullptr);
// The same from the scene's surfaces, BuildSurfaces(scene, opts.join):
// for a caller that checks EstimateMesh first, so the faces are joined
// once (joining is most of the estimate).
bool BuildMesh(const Scene& scene, const std::vector<Surface>& surfaces, const MeshOptions& opts,
               Mesh* mesh, std::string* err, const std::function<void()>& read = nullptr);
// The same, consuming the surfaces: each one's polygon and faces are
// freed once it is cut and given back to the system every few megabytes
// (ReturnFreeMemory), and the array once all are cut, so that they do not
// stand beside the finished mesh (a worker's peak: about 27 bytes an
// element at 10^6 elements, and the array 18).
bool BuildMesh(const Scene& scene, std::vector<Surface>&& surfaces, const MeshOptions& opts,
               Mesh* mesh, std::string* err, const std::function<void()>& read = nullptr);

// The elements and vertices BuildMesh would make at most (before making
// any): a face's extent over the patch size, cut as BuildMesh cuts it.
struct MeshEstimate {
  double elements = 0, vertices = 0;
};
MeshEstimate EstimateMesh(const Scene& scene, const MeshOptions& opts);
MeshEstimate EstimateMesh(const Scene& scene, const std::vector<Surface>& surfaces,
                          const MeshOptions& opts);

// The most elements a mesh may have, built or divided. The master needs
// about 0.52 KB per element (memory.h), so this is about 4 GB.
constexpr int kMaxElements = 8'000'000;

// Geometry shared by building (mesh.cpp) and division (divide.cpp).
// Lexicographic order of points: which end of an edge is "first".
bool LexLess(const glm::dvec3& a, const glm::dvec3& b);
// The point k/n of the way from p to q, computed from the lexicographically
// smaller endpoint so that a face walking the edge the other way gets the
// bit-identical point (no hemicube cracks between faces cut alike).
glm::dvec3 EdgePoint(const glm::dvec3& p, const glm::dvec3& q, int k, int n);
// The area of element e from its corners.
double ElementArea(const Mesh& m, const Element& e);

// Divides leaf element `elem` into kChildren children appended to
// mesh->elems. Midpoints are computed from their edge's endpoints in the
// canonical order (bit-identical from either side, and to a neighbouring
// face cut alike) and reused when a neighbour made them first; a leaf of
// another face along the same edge gets its own copy of the point (faces
// share no vertices) as a T-vertex.
void Divide(Mesh* mesh, int32_t elem);

// Fills the adjacency arrays for the leaves (once; Divide() keeps them
// since). Not done by BuildMesh: a run without subdivision needs none.
void ConnectEdges(Mesh* mesh);
// Frees them (about 40 bytes an element) where no division follows: the
// master's pictures and outputs at the end of a run.
void ReleaseEdges(Mesh* mesh);

// The key of the edge a -> b: directed (a, b) or undirected (min, max).
inline uint64_t EdgeKey(int a, int b) { return uint64_t(uint32_t(a)) << 32 | uint32_t(b); }
constexpr uint64_t kNoEdge = ~uint64_t{0};

// The midpoint Divide() made (or a neighbour holds as a T-vertex) on the
// edge between vertices a and b, either way round, or -1. Needs
// ConnectEdges().
int MidpointOf(const Mesh& mesh, int a, int b);

// The outline of element `elem`: its corners and the T-vertices on its
// edges, counter-clockwise, from its first T-vertex if it has one (so a
// fan from out[0] has no degenerate triangle). Returns the count, <= 8.
int Outline(const Mesh& mesh, int elem, int out[8]);

// Leaf elements of the same face sharing a piece of an edge with leaf
// `elem`: alike, finer (across a T-vertex) or coarser. Needs
// ConnectEdges().
void LeafNeighbours(const Mesh& mesh, int elem, std::vector<int>* out);

// Shooter division (split.cpp): a patch cut into smaller patches along
// its elements. A patch of several top elements becomes one patch per top
// element; a patch of one top element that is divided becomes one patch
// per child. The patch keeps the first piece, the others are appended to
// Mesh::patches (and to its face's list) in order, each element below a
// piece moves to it, and Mesh::splits records the split. Deterministic,
// and independent of divisions made before or after (a piece's elements
// are those below its top element, divided or not), so divisions and
// splits replayed in any interleaving that keeps each kind's order give
// the same mesh. A patch in a shooter group is never split (groups.h).
//
// The pieces SplitPatch(p) would make (their top elements into *tops
// when not null): 0 when p cannot be split (one top element and a leaf,
// or a member of a group).
int SplitPieces(const Mesh& mesh, int patch, std::vector<int>* tops = nullptr);
void SplitPatch(Mesh* mesh, int patch);
// Room in the mesh's per-patch arrays for every piece SplitPatch will
// make of these patches, before a pass splits them: grown split by split
// those arrays doubled past what the pass needs and stood beside their
// old copies while they moved (a pass at 10^6 elements makes 10^5 pieces
// and more; the solver's per-patch arrays follow, Solver::Split).
void ReserveSplits(Mesh* mesh, const std::vector<int32_t>& patches);

// A hash of the mesh geometry and hierarchy (vertex bits, element
// vertices, parents), to check that a worker built what the master has
// and that a checkpoint's divisions replay to the mesh it saved.
uint64_t MeshHash(const Mesh& mesh);

#endif
