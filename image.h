// Pictures and geometry exports of a solved mesh.
#ifndef RADIOSITY_IMAGE_H
#define RADIOSITY_IMAGE_H

#include <array>
#include <cstdint>
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
  // Copies lent points into `own`: for a copy that outlives the mesh's next
  // division (the view server's threads read a snapshot later).
  void Keep() {
    if (lent) own = *lent;
    lent = nullptr;
  }
  // float: drawn into 8 bits after exposure, or written linear as RGBE
  // (8-bit mantissas) or EXR float, which a float holds exactly; positions
  // stay double.
  std::vector<glm::vec3> colors;          // linear radiosity, >= 0
  std::vector<std::array<int, 4>> polys;  // vertex ids, CCW; [3] < 0: triangle
};

// Picture size limits (--size): a side at most kMaxImageSide and the whole
// at most kMaxImagePixels, 8192 x 8192. Rendering and writing take about
// 18 bytes per pixel (a float RGB and a float depth per pixel, the 8-bit
// copy, the PNG encoder's buffers), so about 1.2 GB at the limit; the RGBE
// copy of final.hdr adds about 4. --format exr takes about 40 (float
// planes, and tinyexr's two copies of the file), 2.7 GB at the limit.
constexpr int kMaxImageSide = 16384;
constexpr long kMaxImagePixels = 1L << 26;

struct Image {
  int width = 0, height = 0;
  std::vector<glm::vec3> pixels;  // linear radiosity, row 0 at the top (float, as ShadedMesh's colours)
};

// The body of a JSON string: quotes, backslashes and control characters
// escaped, and '<' too, so that it may stand inside an HTML <script>
// element (view.html) without ending it.
std::string JsonString(const std::string& s);

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

// A linear value as 8-bit sRGB, as the PNG pictures and result.ply hold
// it: times the exposure, clamped to [0, 1] (NaN: 0), the exact sRGB
// transfer curve, rounded.
uint8_t EncodeSrgb8(float linear, float exposure);

// Writes the picture to every path in PATHS, encoded once (the last
// wave's frame and final.png are one picture; a PNG of 512 x 512 takes
// some 50 ms to encode): FORMAT "png" or "ppm" in 8-bit sRGB, exposure
// applied and clamped; "exr" linear, as it is (exr.h). False with *err on
// an I/O error.
bool WriteImage(const Image& img, float exposure, const std::vector<std::string>& paths,
                const std::string& format, std::string* err);

// The picture as it is, linear (no exposure, no clamp, no sRGB curve), as
// Radiance RGBE (stb_image_write, run-length encoded): 8-bit mantissas
// under the largest channel's exponent, so each channel is within
// max(R, G, B) / 128 below the float, over 2^-128 to 2^127; for tone
// mappers and for reading lighting values off the picture.
bool WriteRadianceHdr(const Image& img, const std::string& path, std::string* err);

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
