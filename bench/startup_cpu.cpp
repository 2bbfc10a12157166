// radiosity-startup: the master's start-up on one scene in CPU seconds of
// its one thread, part by part, as one table row on stdout
// (bench/startup.sh adds the headers):
//   radiosity-startup SCENE.obj [--no-join] [--patch-size L]
// load (LoadScene), join (BuildSurfaces: coplanar faces joined),
// estimate (EstimateMesh from those surfaces, as the master and the
// worker check it before building), mesh (BuildMesh from them, without
// groups), groups (FormGroups); then the master's "meshed in" of -v in
// CPU seconds (join + estimate + mesh + groups), the faces, surfaces,
// elements, groups formed and a hash of the mesh and its groups: equal
// hashes, equal start-up results.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "clock.h"
#include "groups.h"
#include "mesh.h"
#include "scene.h"
#include "surface.h"

namespace {

uint64_t GroupsHash(const Mesh& mesh) {
  uint64_t h = MeshHash(mesh);
  for (const PatchGroup& g : mesh.groups)
    for (int p : g.members) h = SplitMix64(h ^ uint64_t(uint32_t(p)));
  return SplitMix64(h ^ mesh.groups.size());
}

}  // namespace

int main(int argc, char** argv) {
  MeshOptions opts;
  for (int i = 2; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--no-join")) {
      opts.join = false;
    } else if (!std::strcmp(argv[i], "--patch-size") && i + 1 < argc) {
      opts.patch_size = std::atof(argv[++i]);
    } else {
      argc = 0;
      break;
    }
  }
  if (argc < 2) {
    std::fprintf(stderr, "usage: radiosity-startup SCENE.obj [--no-join] [--patch-size L]\n");
    return 2;
  }
  std::string err;
  std::vector<std::string> warnings;
  Scene scene;
  double t = ThreadCpuSeconds();
  auto lap = [&t] {
    const double now = ThreadCpuSeconds(), d = now - t;
    t = now;
    return d;
  };
  if (!LoadScene(argv[1], &scene, &err, &warnings)) {
    std::fprintf(stderr, "radiosity-startup: %s\n", err.c_str());
    return 1;
  }
  const double load = lap();
  const std::vector<Surface> surfaces = BuildSurfaces(scene, opts.join);
  const double join = lap();
  EstimateMesh(scene, surfaces, opts);
  const double estimate = lap();
  opts.groups = false;
  Mesh mesh;
  if (!BuildMesh(scene, surfaces, opts, &mesh, &err)) {
    std::fprintf(stderr, "radiosity-startup: %s\n", err.c_str());
    return 1;
  }
  const double built = lap();
  opts.groups = true;
  FormGroups(opts, &mesh);
  const double groups = lap();
  std::printf("| %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %zu | %zu | %zu | %zu | %016llx |\n",
              argv[1], load, join, estimate, built, groups, join + estimate + built + groups,
              scene.faces.size(), surfaces.size(), mesh.elems.size(), mesh.groups.size(),
              (unsigned long long)GroupsHash(mesh));
  return 0;
}
