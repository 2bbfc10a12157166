// One column of form factors: from a shooter patch's centre to every leaf
// element, by the hemicube (Cohen & Greenberg 1985): a top face and four
// half side faces, delta form factors per pixel, an item buffer of element
// ids with a depth test. A leaf is drawn by its outline (Outline: corners
// and T-vertices), so that it meets finer neighbours' edges exactly.
//
// Numbers: the shooter's frame and the delta form factors are set up in
// double; vertices are projected and rasterised in float after being moved
// into the shooter's frame (relative coordinates, so precision does not
// depend on where the scene sits or on its units); each element's form
// factor is summed in double and handed out as float (7 digits are more
// than the hemicube's own accuracy of about 1/R²). The culling tests are
// done in double on boxes grown by a margin far above float rounding, so
// that a face is skipped only where none of its float pixels could win.
//
// Cost: faces are reached through a bounding-volume hierarchy, front to
// back; a node or face is skipped whole when it lies behind the shooter,
// outside every hemicube face, or behind the depths already drawn (a
// kTile-pixel tile's least depth, then pixels); so is a leaf that covers
// 64 pixels or more, before it is scanned, and one whose pixel box holds
// no pixel centre (a finely cut scene's many; all of a face's leaves at
// once where the face's own pixel box holds none). So a column costs about
// its visible faces and its pixels, not the scene: the maze or a room of
// boxes leaves most of its elements unread. The item buffer holds leaf
// ranks (their order in the flat copy), which break depth ties as the
// plain face-order z-buffer did.
#ifndef RADIOSITY_HEMICUBE_H
#define RADIOSITY_HEMICUBE_H

#include <array>
#include <cstdint>
#include <vector>

#include "memory.h"
#include "mesh.h"

struct FormFactor {
  int32_t elem;
  float f;
};

// Where a column's time goes; summed over columns by callers.
struct ColumnStats {
  double transform_s = 0;  // face culling, vertex transform and outcodes
  double raster_s = 0;     // clear, clip, project, scan-convert
  double readback_s = 0;   // item buffer -> form factors
  long elements = 0;       // leaf elements visited (on faces not culled)
  long covered = 0;        // elements with F > 0
  long pixels = 0;         // hemicube pixels (3 R²)
};

class Hemicube {
 public:
  // R: pixels across the top face; even, 8..kMaxResolution.
  explicit Hemicube(int resolution);
  int resolution() const { return res_; }

  // Form factors F(shooter -> e) > 0 for leaf elements e, in increasing e.
  // The hemicube is turned by `angle` radians about the patch normal.
  // `group`: the shooter group `shooter` is the first member of (groups.h),
  // or null when it shoots alone; the column then looks from the group's
  // centroid along its normal and leaves the members' elements out. It is
  // given, not read from the mesh: a worker's mesh has no groups, the
  // master sends each with the work (protocol.h, Assignment).
  void Column(const Mesh& mesh, int shooter, const PatchGroup* group, double angle,
              std::vector<FormFactor>* out, ColumnStats* stats = nullptr);

  // Makes the copy of the mesh the columns read (Column makes it when the
  // mesh has changed since), so that a worker has it before the first
  // work comes.
  void Prepare(const Mesh& mesh);

  // For a mesh about to change by divisions and splits: frees the parts
  // of the copy of the mesh the columns read that the next Column makes
  // anew (the sums' blocks), and keeps those it updates (BuildCache): the
  // faces, their hierarchy, leaves and outlines, about 30 bytes an element.
  void ReleaseCache();

  // Culling on (the default): faces are visited front to back through a
  // bounding-volume hierarchy and skipped, with their elements unread,
  // where they lie wholly behind the shooter, outside a hemicube face or
  // behind what that face's item buffer already holds (and so are large
  // leaves and those between pixel centres, one by one). Off: every front-facing face on every hemicube
  // face, in face order, as a plain z-buffer would. The columns are the same either way (the tests compare
  // them): culled faces could not have won a pixel, and depth ties go to
  // the element drawn first in face order whatever order they are drawn in.
  void set_culling(bool on) { culling_ = on; }

  static constexpr int kMaxResolution = 4096;

  // How many times the hierarchy over faces was built (not kept from the
  // mesh before a division: BuildCache).
  long HierarchyBuilds() const { return hierarchy_builds_; }
  // How many times the cache was updated after divisions and splits
  // rather than built whole (BuildCache).
  long CacheUpdates() const { return cache_updates_; }
  // Whether this cache is laid out as `o`'s is, array by array (faces,
  // boxes, leaves, outlines): an updated cache against one built whole.
  bool SameCache(const Hemicube& o) const;

 private:
  // The mesh as the column reads it, rebuilt when the mesh changes (built,
  // divided, replaced; Key): flat, in the order it is read, each face's
  // leaves contiguous with their outlines precomputed. About 14 bytes an
  // element (a quad's) and 88 a face; the sums only where a column reaches.
  // A face is what drawing it reads, one cache line (the array is aligned
  // to 64); its box, read only to cull a face of many leaves and to build
  // the hierarchy, is apart in boxes_.
  struct alignas(64) CacheFace {
    glm::dvec3 normal{0.0};
    double offset = 0;
    int face = -1;                // in the mesh
    int vb = 0, ve = 0;           // its vertices: Mesh::verts[vb, ve)
    int nd = 0;                   // and its divide_verts' count
    int lb = 0, le = 0;           // its leaves' ranks: [lb, le)
    int pb = 0;                   // its first leaf's outline in outline_
  };
  // The bounding box of a face's vertices in float, rounded outward: a
  // box a little larger culls a little less, never a face it should draw
  // (the columns are the same).
  struct FaceBox {
    float lo[3], hi[3];
    glm::dvec3 Lo() const { return glm::dvec3(lo[0], lo[1], lo[2]); }
    glm::dvec3 Hi() const { return glm::dvec3(hi[0], hi[1], hi[2]); }
  };
  struct Node {                   // of the hierarchy over faces, depth first
    // Its faces' boxes' union: float as theirs are, so exactly (36 bytes
    // a node, not 64 with a double box).
    FaceBox box;
    int first = 0, count = 0;     // a leaf: faces_[first, first + count)
    int right = -1;               // an inner node: its second child (first is next)
  };
  static_assert(sizeof(Node) == 36, "README, Memory: the hemicube cache");
  // The cache's arrays are read at scattered places and at 10^6 elements
  // are far larger than the TLB reaches in 4 KB pages (memory.h).
  template <class T>
  using Huge = std::vector<T, HugePageAllocator<T>>;
  struct Key {
    const Mesh* mesh = nullptr;
    const void* verts = nullptr;
    const void* elems = nullptr;
    size_t nverts = 0, nelems = 0, nfaces = 0;
    int divided = -1;
    size_t splits = 0;
    glm::dvec3 first{0.0}, last{0.0};
    bool operator==(const Key& o) const;
  };
  static Key KeyOf(const Mesh& mesh);
  void BuildCache(const Mesh& mesh);
  bool UpdateCache(const Mesh& mesh);
  // Face cf's leaves' outlines (ranks [cf.lb, cf.le) of elem_) appended to
  // outline_ or outline_wide_; its vertex ranges and pb set.
  void PutOutlines(const Mesh& mesh, CacheFace* cf);
  // The scratch sized to `most` vertices a face, the sums' blocks to the
  // mesh's elements, the cache's key; both BuildCache and UpdateCache end so.
  void FinishCache(const Mesh& mesh, size_t most);
  // The face's box from its vertices and divide_verts, in float rounded out.
  static FaceBox BoxOf(const Mesh& mesh, const MeshFace& mf);
  // Nodes over faces boxes[order[first, first + count)], reordering `order`.
  int BuildNodes(const Huge<FaceBox>& boxes, std::vector<int>* order, int first,
                 int count);
  // The hemicube faces (5 bits) box [lo, hi] may cover visibly: not
  // wholly behind the shooter, outside the face or behind its buffer.
  uint32_t Visible(const glm::dvec3& lo, const glm::dvec3& hi);
  bool Open(int h, int xa, int xb, int ra, int rb, float zt);
  // Leaves whose pixel box is this large or larger are tested against the
  // tiles before they are drawn (Hidden).
  static constexpr double kHiddenArea = 64;
  bool Hidden(int h, float x0, float x1, float y0, float y1, float za, float zb, float zc);
  // Its vertices into the shooter's frame, its leaves into the buffers of
  // the hemicube faces in `mask`; adds to clock's stages when non-null.
  void DrawFace(const Mesh& mesh, int f, uint32_t mask, double* clock);
  // A polygon's first topmost and bottommost corners, its x range and the
  // rows it covers (Rows): for the tests before Scan, and for Scan.
  struct Extent {
    int top = 0, bottom = 0, ya = 0, yb = 0;
    float x0 = 0, x1 = 0;
  };
  static Extent Bounds(const float (*pt)[2], int n, int H);
  void Scan(int face, const float (*pt)[2], int n, const Extent& e, float za, float zb,
            float zc, int32_t rank);

  int res_;
  bool culling_ = true;
  // Delta form factors as prefix sums along each row (R + 1 per row):
  // the top face's R rows, then 4 side faces of R/2 rows.
  std::vector<double> prefix_;
  std::vector<float> depth_;  // 1/distance, larger is nearer; 0 = empty
  std::vector<int32_t> item_; // leaf rank or -1
  // Per kTile x kTile pixels of each face (the top's, then the sides'):
  // the least depth, valid where dirty_ is 0 (Scan sets it on writing).
  static constexpr int kTile = 8;
  std::vector<float> tile_min_;
  std::vector<uint8_t> dirty_;
  // Where hemicube face h begins in depth_ and item_, and in tile_min_
  // and dirty_: once, not per polygon Scan draws and per box Open tests.
  size_t pixel_at_[5] = {}, tile_at_[5] = {};
  // Per hemicube face, the rows [first, last) Scan wrote since the last
  // readback, which reads and clears only those.
  int rows_[5][2] = {{INT32_MAX, 0}, {INT32_MAX, 0}, {INT32_MAX, 0}, {INT32_MAX, 0}, {INT32_MAX, 0}};

  Key key_;      // of the mesh the cache holds; empty after ReleaseCache
  Key cached_;   // of the mesh the cache was last built or updated for
  long hierarchy_builds_ = 0, cache_updates_ = 0;
  // Faces with leaves in the hierarchy's order, and their outlines in that
  // order: a column reads them front to back, nearly in memory order. The
  // vertices are the mesh's own (a face's are contiguous there but for
  // those Divide added), not copied: that would cost 24 bytes a vertex.
  Huge<CacheFace> faces_;
  Huge<FaceBox> boxes_;            // per faces_ entry
  std::vector<int32_t> by_face_;   // faces_ indices in mesh face order
  Huge<int32_t> elem_;             // rank -> element id; ranks in face order
  // Face-relative vertex indices: 16 bits, or 32 in outline_wide_ (and
  // wide_) when a face has more than 65,536 vertices.
  Huge<uint16_t> outline_;
  Huge<int32_t> outline_wide_;
  bool wide_ = false;
  Huge<uint8_t> outline_n_;       // per rank: its outline's length
  Huge<Node> nodes_;

  // Per column: the shooter's frame and per-face scratch.
  glm::dvec3 c_{0.0}, u_{0.0}, v_{0.0}, n_{0.0};
  alignas(16) double frame_[12][2];  // c_, u_, v_, n_ by component, twice (DrawFace's pairs)
  float near_ = 0;
  double coplanar_ = 0, margin_ = 0;
  const PatchGroup* self_ = nullptr;  // in a column: the shooter's group (its members are skipped), or null
  std::vector<int> self_faces_;      // the mesh faces of its members, sorted
  std::vector<float> lx_, ly_, lz_;  // face vertices in the shooter frame
  std::vector<uint32_t> code_;       // outcodes per vertex, 5 bits per face
  // Pixel x, y on each hemicube face, side by side: a leaf's corner is
  // gathered by one load.
  std::vector<std::array<float, 2>> sxy_[5];
  std::vector<int> stack_;
  // Form factors summed per element, sparse: a block of kSumBlock sums for
  // each kSumBlock elements a column reaches, not 8 bytes for every
  // element (a light in a room of boxes reaches 64-element blocks all).
  static constexpr int kSumBlock = 8;
  std::vector<double> acc_;
  Huge<int32_t> block_;              // per kSumBlock elements: its first sum in acc_, or -1
  std::vector<uint64_t> touched_;    // per element: its sum is in acc_
  long visited_ = 0;                 // leaves drawn this column
};

// The hemicube angle for the k-th shot of patch p: a hash, so that any
// process computing that column turns the hemicube alike.
double ShotAngle(unsigned seed, int patch, int k);

// The column of the k-th shot of `patch` (for `group`, as Column), turned
// by ShotAngle when `rotate`: what every process that computes columns
// (the master alone, a worker, the simulation, the benchmarks) calls, so
// that they agree.
void ShotColumn(Hemicube* hemicube, const Mesh& mesh, int patch, const PatchGroup* group, int k,
                bool rotate, unsigned seed, std::vector<FormFactor>* out,
                ColumnStats* stats = nullptr);

#endif
