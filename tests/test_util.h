// Scenes built in code for unit tests: no files, exact geometry.
#ifndef RADIOSITY_TESTS_TEST_UTIL_H
#define RADIOSITY_TESTS_TEST_UTIL_H

#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "mesh.h"
#include "scene.h"

// Adds a planar polygon (counter-clockwise seen from its front) with its
// own material.
inline void AddFace(Scene* s, std::vector<glm::dvec3> verts, glm::dvec3 kd, glm::dvec3 ke) {
  Material m;
  m.name = "m" + std::to_string(s->materials.size());
  m.kd = kd;
  m.ke = ke;
  s->materials.push_back(m);
  Face f;
  f.verts = std::move(verts);
  FacePlane(&f);
  f.material = int(s->materials.size()) - 1;
  f.index = int(s->faces.size());
  f.line = f.index + 1;
  if (s->faces.empty()) s->lo = s->hi = f.verts[0];
  for (const auto& p : f.verts) {
    s->lo = glm::min(s->lo, p);
    s->hi = glm::max(s->hi, p);
  }
  s->faces.push_back(f);
}

inline Scene EmptyScene() {
  Scene s;
  s.materials.push_back(Material{"default", glm::dvec3(0.5), glm::dvec3(0.0)});
  s.objects.push_back("default");
  return s;
}

// The inside of the box [0,size]^3, every face facing in. kd/ke per face
// (six entries) or one for all.
// A small light (0.04 across, at height 2) over a square occluder (x, y
// in 0.3..0.7 at height 1, both sides) and a floor (face 0): a sharp shadow whose edge on the floor
// is at x or y = 0.5 ± 0.4, so that a run divides and goes through waves.
inline Scene ShadowScene() {
  Scene s = EmptyScene();
  AddFace(&s, {{-1, -1, 0}, {2, -1, 0}, {2, 2, 0}, {-1, 2, 0}}, glm::dvec3(0.6), glm::dvec3(0));
  AddFace(&s, {{0.3, 0.3, 1}, {0.3, 0.7, 1}, {0.7, 0.7, 1}, {0.7, 0.3, 1}}, glm::dvec3(0.5),
          glm::dvec3(0));  // faces down
  AddFace(&s, {{0.3, 0.3, 1.001}, {0.7, 0.3, 1.001}, {0.7, 0.7, 1.001}, {0.3, 0.7, 1.001}},
          glm::dvec3(0.5), glm::dvec3(0));  // faces up, to the light
  AddFace(&s, {{0.48, 0.48, 2}, {0.48, 0.52, 2}, {0.52, 0.52, 2}, {0.52, 0.48, 2}}, glm::dvec3(0),
          glm::dvec3(100));  // the light, facing down
  return s;
}

inline Scene Box(double size, std::vector<glm::dvec3> kd, std::vector<glm::dvec3> ke) {
  Scene s = EmptyScene();
  const double L = size;
  const std::vector<std::vector<glm::dvec3>> faces = {
      {{0, 0, 0}, {0, 0, L}, {L, 0, L}, {L, 0, 0}},  // floor, +y
      {{0, L, 0}, {L, L, 0}, {L, L, L}, {0, L, L}},  // ceiling, -y
      {{0, 0, 0}, {0, L, 0}, {0, L, L}, {0, 0, L}},  // x = 0, +x
      {{L, 0, 0}, {L, 0, L}, {L, L, L}, {L, L, 0}},  // x = L, -x
      {{0, 0, 0}, {L, 0, 0}, {L, L, 0}, {0, L, 0}},  // z = 0, +z
      {{0, 0, L}, {0, L, L}, {L, L, L}, {L, 0, L}},  // z = L, -z
  };
  if ((kd.size() != 1 && kd.size() != 6) || (ke.size() != 1 && ke.size() != 6)) std::abort();
  for (size_t i = 0; i < faces.size(); ++i)
    AddFace(&s, faces[i], kd[kd.size() == 1 ? 0 : i], ke[ke.size() == 1 ? 0 : i]);
  return s;
}

// What a scene absorbs, Σ A (1−ρ)/ρ (B − Ke), and emits, Σ A Ke, per
// channel, from its per-face radiosity b: equal when it is closed.
inline void PowerBalance(const Scene& s, const std::vector<glm::dvec3>& b, glm::dvec3* absorbed,
                         glm::dvec3* emitted) {
  *absorbed = *emitted = glm::dvec3(0.0);
  for (size_t f = 0; f < s.faces.size(); ++f) {
    const Material& mat = s.materials[s.faces[f].material];
    *absorbed += s.faces[f].area * (1.0 - mat.kd) / mat.kd * (b[f] - mat.ke);
    *emitted += s.faces[f].area * mat.ke;
  }
}

inline Mesh MakeMesh(const Scene& s, MeshOptions o = MeshOptions()) {
  Mesh m;
  std::string err;
  if (!BuildMesh(s, o, &m, &err)) std::abort();
  return m;
}

// A shipped scene's OBJ: beside the tests' sources, or from the top
// directory when they were moved.
inline std::string ShippedScenePath(const std::string& name) {
  std::string path = __FILE__;
  path = path.substr(0, path.find_last_of('/') + 1) + "../scenes/" + name + ".obj";
  struct stat st;
  if (stat(path.c_str(), &st) != 0) path = "scenes/" + name + ".obj";
  return path;
}

// A shipped scene, loaded (aborts with the error should it not load: the
// tests that use it test other things).
inline Scene ShippedScene(const std::string& name) {
  Scene scene;
  std::string err;
  std::vector<std::string> warnings;
  if (!LoadScene(ShippedScenePath(name), &scene, &err, &warnings)) {
    std::fprintf(stderr, "%s: %s\n", name.c_str(), err.c_str());
    std::abort();
  }
  return scene;
}

// A shipped scene meshed with the default options (aborts likewise).
inline Mesh ShippedMesh(const std::string& name) {
  const Scene scene = ShippedScene(name);
  Mesh mesh;
  std::string err;
  if (!BuildMesh(scene, MeshOptions(), &mesh, &err)) {
    std::fprintf(stderr, "%s: %s\n", name.c_str(), err.c_str());
    std::abort();
  }
  return mesh;
}

#endif
