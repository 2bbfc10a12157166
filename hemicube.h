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
// than the hemicube's own accuracy of about 1/R²).
#ifndef RADIOSITY_HEMICUBE_H
#define RADIOSITY_HEMICUBE_H

#include <cstdint>
#include <vector>

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
  long elements = 0;       // leaf elements on front-facing faces
  long covered = 0;        // elements with F > 0
  long pixels = 0;         // hemicube pixels (3 R²)
};

class Hemicube {
 public:
  // R: pixels across the top face; even, 8..kMaxResolution.
  explicit Hemicube(int resolution);
  int resolution() const { return res_; }

  // Form factors F(shooter -> e) > 0 for leaf elements e, in increasing e.
  // The hemicube is turned by `angle` radians about the patch normal. A
  // group's shooter (groups.h) looks from the group's centroid along its
  // normal and leaves the members' elements out.
  void Column(const Mesh& mesh, int shooter, double angle,
              std::vector<FormFactor>* out, ColumnStats* stats = nullptr);

  static constexpr int kMaxResolution = 4096;

 private:
  void Scan(int face, const float (*pt)[2], int n, float za, float zb, float zc,
            int32_t id);

  int res_;
  // Delta form factors as prefix sums along each row (R + 1 per row):
  // the top face's R rows, then 4 side faces of R/2 rows.
  std::vector<double> prefix_;
  std::vector<float> depth_;  // 1/distance, larger is nearer; 0 = empty
  std::vector<int32_t> item_; // element id or -1
  std::vector<float> local_;  // 3 floats per vertex, in the shooter frame
  std::vector<float> screen_; // 10 floats per vertex: pixel x, y on each face
  std::vector<uint32_t> code_;// outcodes per vertex, 5 bits per face
  std::vector<double> acc_;   // per element
  std::vector<int> front_, leaves_;  // scratch, kept to avoid reallocation
};

// The hemicube angle for the k-th shot of patch p: a hash, so that any
// process computing that column turns the hemicube alike.
double ShotAngle(unsigned seed, int patch, int k);

// The column of the k-th shot of `patch`, turned by ShotAngle when
// `rotate`: what every process that computes columns (the master alone,
// a worker, the simulation, the benchmarks) calls, so that they agree.
void ShotColumn(Hemicube* hemicube, const Mesh& mesh, int patch, int k, bool rotate,
                unsigned seed, std::vector<FormFactor>* out, ColumnStats* stats = nullptr);

#endif
