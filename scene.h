// Scene input: a strict parser of the OBJ + MTL subset in doc/design (see
// man/radiosity.1, SCENE FORMAT). Errors come back as one line
// "FILE:LINE: what is wrong"; main() prefixes "radiosity: " and exits 2.
#ifndef RADIOSITY_SCENE_H
#define RADIOSITY_SCENE_H

#include <string>
#include <vector>

#include <glm/glm.hpp>

// Far beyond any scene this program can solve, but small enough that the
// limit is reported instead of ending in bad_alloc.
// Every face becomes at least one element, so more faces than the mesh's
// element cap (kMaxElements, mesh.h) could never run: refused while
// reading, before the faces alone fill the memory (about 150 bytes each).
// The scene frame (protocol.h) is held to the same limits.
constexpr long kMaxVertices = 32000000;
constexpr long kMaxFaces = 8000000;
constexpr long kMaxCorners = 64000000;
// A polygon's vertices: the mesh cuts a face along its outline, so one
// polygon of 10,000 vertices would become over a million elements.
constexpr size_t kMaxPolygon = 1000;

// The mean of a colour's channels: the luminance that the solver's noise
// and first light and the subdivider's dividing factor compare.
inline double Lum(const glm::dvec3& c) { return (c.r + c.g + c.b) / 3; }

struct Material {
  std::string name;
  glm::dvec3 kd{0.5};  // diffuse reflectance, each channel in [0,1]
  glm::dvec3 ke{0.0};  // emitted exitance (radiosity units), >= 0
};

struct Camera {
  glm::dvec3 eye{0.0}, target{0.0, 0.0, -1.0};
  double fov_deg = 45.0;  // vertical field of view
};

// One accepted `f` statement. Coordinates are double: scenes are scaled by
// 1e±4 in tests and faces must stay planar and non-degenerate at any scale.
struct Face {
  std::vector<glm::dvec3> verts;  // >= 3, planar, counter-clockwise from the front
  glm::dvec3 normal{0.0};         // unit, front side
  double area = 0.0;
  int material = 0;  // index into Scene::materials
  int object = 0;    // index into Scene::objects
  int index = 0;     // 0-based index among all `f` lines (result.csv "face")
  int line = 0;      // 1-based line of the `f` statement
};

struct Scene {
  std::string path;
  std::vector<std::string> files;        // the OBJ and each MTL read
  std::vector<Face> faces;               // accepted faces in file order
  std::vector<Material> materials;       // [0] is the default (Kd 0.5, Ke 0)
  std::vector<std::string> objects;      // [0] is "default"
  bool has_camera = false;
  Camera camera;
  glm::dvec3 lo{0.0}, hi{0.0};           // bounding box of the accepted faces
};

// Reads PATH (and the MTL files it names, relative to PATH's directory).
// On failure returns false with *err = "FILE:LINE: what is wrong".
// Non-fatal problems (e.g. a zero-area face skipped) are appended to
// *warnings in the same format.
bool LoadScene(const std::string& path, Scene* scene, std::string* err,
               std::vector<std::string>* warnings);

// Frees every face's vertex list and keeps the rest (index, object,
// material, area, normal): all the master needs of the scene once the mesh
// is built, the scene hashed and sent (README, Layout: memory).
void DropVertices(Scene* scene);

// A polygon's normal scaled to its area (Newell's method).
glm::dvec3 AreaVector(const std::vector<glm::dvec3>& poly);
// The same of poly[0, size): an element's corners, without a vector.
glm::dvec3 AreaVector(const glm::dvec3* poly, size_t size);
// Sets face->area and face->normal from face->verts (AreaVector, its
// length, the vector over its length), as LoadScene does for every face.
// The scene frame leaves both out: the worker computes them with this
// same function, bit for bit (the hello checks that it is the same build).
void FacePlane(Face* face);

// Parses "ex ey ez tx ty tz fov" (the --camera option and the OBJ comment).
bool ParseCamera(const std::string& text, Camera* cam, std::string* err);

#endif
