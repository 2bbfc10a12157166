// libFuzzer target: the OBJ + MTL loader (scene.h), and the mesh built from
// what it accepts. The input is an OBJ file, optionally followed by the
// line "%%MTL%%" and an MTL file; both are written to a private temporary
// directory as f.obj and f.mtl (the loader reads files: an `mtllib f.mtl`
// in the OBJ reaches the second part). The seeds (fuzz/seeds.sh) are the
// shipped scenes and the tests' scenes in that form.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "mesh.h"
#include "scene.h"

namespace {

std::string g_dir;

void Write(const std::string& path, const char* data, size_t n) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (n && std::fwrite(data, 1, n, f) != n) std::abort();
  std::fclose(f);
}

void RemoveDir() {
  std::remove((g_dir + "/f.obj").c_str());
  std::remove((g_dir + "/f.mtl").c_str());
  rmdir(g_dir.c_str());
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  char tmpl[] = "/tmp/scene_fuzz.XXXXXX";
  if (!mkdtemp(tmpl)) std::abort();
  g_dir = tmpl;
  std::atexit(RemoveDir);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string in(reinterpret_cast<const char*>(data), size);
  static const std::string kSep = "\n%%MTL%%\n";
  const size_t cut = in.find(kSep);
  const std::string obj = in.substr(0, cut);
  const std::string mtl = cut == std::string::npos ? "" : in.substr(cut + kSep.size());
  Write(g_dir + "/f.obj", obj.data(), obj.size());
  Write(g_dir + "/f.mtl", mtl.data(), mtl.size());
  Scene scene;
  std::string err;
  std::vector<std::string> warnings;
  if (!LoadScene(g_dir + "/f.obj", &scene, &err, &warnings)) {
    if (err.empty()) std::abort();  // a refusal always says why
    return 0;
  }
  // What the loader accepts, the mesh must take (small scenes only: a
  // face spanning the bounding box makes 16 x 16 patches).
  if (scene.faces.size() <= 16) {
    Mesh mesh;
    if (!BuildMesh(scene, MeshOptions(), &mesh, &err)) std::abort();
  }
  return 0;
}
