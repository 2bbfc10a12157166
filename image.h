// Pictures and geometry exports of a solved mesh.
#ifndef RADIOSITY_IMAGE_H
#define RADIOSITY_IMAGE_H

#include <array>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "scene.h"

// What to draw: polygons (triangles, or convex planar quads) with a linear
// radiosity (RGB) at every vertex, interpolated across (Gouraud).
struct ShadedMesh {
  // The points, double: Shade lends the mesh's own vertices (`lent`, not a
  // copy: 24 bytes a vertex, 50 an element); a mesh made by hand keeps
  // them in `own`.
  const std::vector<glm::dvec3>& positions() const { return lent ? *lent : own; }
  std::vector<glm::dvec3> own;
  const std::vector<glm::dvec3>* lent = nullptr;
  // float: only drawn, after exposure, into 8 bits; positions stay double.
  std::vector<glm::vec3> colors;          // linear radiosity, >= 0
  std::vector<std::array<int, 4>> polys;  // vertex ids, CCW; [3] < 0: triangle
};

// Picture size limits (--size): a side at most kMaxImageSide and the whole
// at most kMaxImagePixels, 8192 x 8192. Rendering and writing take about
// 18 bytes per pixel (a float RGB and a float depth per pixel, the 8-bit
// copy, the PNG encoder's buffers), so about 1.2 GB at the limit.
constexpr int kMaxImageSide = 16384;
constexpr long kMaxImagePixels = 1L << 26;

struct Image {
  int width = 0, height = 0;
  std::vector<glm::vec3> pixels;  // linear radiosity, row 0 at the top (float: 8-bit output)
};

// A camera that frames the box [lo, hi], looking at it from the front
// (+z side), slightly above.
Camera FrameBox(const glm::dvec3& lo, const glm::dvec3& hi);

// Z-buffered perspective rendering. Back-facing polygons are culled (faces
// are one-sided). Pixels that see nothing are black.
void Render(const ShadedMesh& mesh, const Camera& cam, int width, int height,
            Image* out);

// Exposure from the scene: the scale that maps linear radiosity to display
// values (see image.cpp for the rule).
float AutoExposure(const ShadedMesh& mesh);

// Writes an 8-bit sRGB picture, exposure applied and clamped.
// FORMAT is "png" or "ppm". False with *err on an I/O error.
bool WriteImage(const Image& img, float exposure, const std::string& path,
                const std::string& format, std::string* err);

// PLY (ascii) with per-vertex colours, exposure and sRGB applied, which
// MeshLab and Blender open.
bool WritePly(const ShadedMesh& mesh, float exposure, const std::string& path,
              std::string* err);

// glTF 2.0: GLTF_PATH (JSON) and BIN_PATH (its buffer, named in the JSON
// by its file name: keep them in one directory). Float positions,
// triangle indices (quads split) and COLOR_0 vertex colours: exposed,
// clamped linear radiosity (glTF colours are linear; viewers apply sRGB),
// under an unlit material (KHR_materials_unlit) so that viewers show the
// radiosity as computed instead of lighting it again.
bool WriteGltf(const ShadedMesh& mesh, float exposure, const std::string& gltf_path,
               const std::string& bin_path, std::string* err);

#endif
