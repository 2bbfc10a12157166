// The benchmarks' one way to get the scene and mesh they measure (the
// program's default mesh options unless given), or a line "PROG: FILE:LINE: what" on
// stderr and exit 1 (a benchmark has nothing to measure without them).
#ifndef RADIOSITY_BENCH_LOAD_H
#define RADIOSITY_BENCH_LOAD_H

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "mesh.h"
#include "scene.h"

inline void LoadSceneOrDie(const char* prog, const std::string& path, Scene* scene) {
  std::string err;
  std::vector<std::string> warnings;
  if (!LoadScene(path, scene, &err, &warnings)) {
    std::fprintf(stderr, "%s: %s\n", prog, err.c_str());
    std::exit(1);
  }
}

inline void BuildMeshOrDie(const char* prog, const Scene& scene, const MeshOptions& opts, Mesh* mesh) {
  std::string err;
  if (!BuildMesh(scene, opts, mesh, &err)) {
    std::fprintf(stderr, "%s: %s\n", prog, err.c_str());
    std::exit(1);
  }
}

inline void LoadMeshOrDie(const char* prog, const std::string& path, Scene* scene, Mesh* mesh,
                          const MeshOptions& opts = MeshOptions()) {
  LoadSceneOrDie(prog, path, scene);
  BuildMeshOrDie(prog, *scene, opts, mesh);
}

#endif
