// The benchmarks' one way to get the scene and mesh they measure: with the
// program's default mesh options, or a line "PROG: FILE:LINE: what" on
// stderr and exit 1 (a benchmark has nothing to measure without them).
#ifndef RADIOSITY_BENCH_LOAD_H
#define RADIOSITY_BENCH_LOAD_H

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "mesh.h"
#include "scene.h"

inline void LoadMeshOrDie(const char* prog, const std::string& path, Scene* scene, Mesh* mesh) {
  std::string err;
  std::vector<std::string> warnings;
  if (!LoadScene(path, scene, &err, &warnings) || !BuildMesh(*scene, MeshOptions(), mesh, &err)) {
    std::fprintf(stderr, "%s: %s\n", prog, err.c_str());
    std::exit(1);
  }
}

#endif
