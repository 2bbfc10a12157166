// Writes the seed corpus of protocol_fuzz into DIR: one stream of every
// message a master and a worker exchange (the scene is SCENE.obj), and one
// payload per message type, in protocol_fuzz's input format.
//   protocol_seeds SCENE.obj DIR
#include <cstdio>
#include <string>
#include <vector>

#include "protocol.h"
#include "scene.h"

namespace {

void Save(const std::string& path, const std::string& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) {
    std::perror(path.c_str());
    std::exit(1);
  }
  std::fclose(f);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace proto;
  if (argc != 3) {
    std::fprintf(stderr, "usage: protocol_seeds SCENE.obj DIR\n");
    return 2;
  }
  SceneSetup setup;
  std::string err;
  std::vector<std::string> warnings;
  if (!LoadScene(argv[1], &setup.scene, &err, &warnings)) {
    std::fprintf(stderr, "protocol_seeds: %s\n", err.c_str());
    return 1;
  }
  Column col;
  col.patch = 3;
  col.k = 2;
  col.compute_s = 0.001;
  col.wait_s = 0.0005;
  const float fs[] = {1e-3f, 2.5e-4f, 0.3f, 1e-9f, 1e-12f, 0.5f, 0.01f, 3e-6f, 1.5f, 0.125f};
  for (int i = 0; i < 10; ++i) col.ff.push_back({i < 5 ? i : 10 + 3 * i, fs[i]});
  std::vector<std::pair<Msg, std::string>> frames;
  auto add = [&](Msg m, void (*enc)(std::string*)) {
    std::string s;
    enc(&s);
    frames.push_back({m, s});
  };
  std::string s;
  EncodeHello(Hello(), &s); frames.push_back({Msg::kHello, s}); s.clear();
  EncodeScene(setup, &s); frames.push_back({Msg::kScene, s}); s.clear();
  EncodeReady({1234, 0x0123456789abcdefull}, &s); frames.push_back({Msg::kReady, s}); s.clear();
  // One assignment carries its shooter group (protocol.h, Assignment).
  Assignment grouped{12, 1};
  grouped.group.members = {12, 13, 17, 400};
  grouped.group.center = glm::dvec3(0.25, 0.5, 0.125);
  grouped.group.normal = glm::dvec3(0, 1, 0);
  EncodeWork({{0, 0}, {5, 1}, grouped, {300, 7}}, &s); frames.push_back({Msg::kWork, s}); s.clear();
  EncodeColumn(col, &s); frames.push_back({Msg::kColumn, s}); s.clear();
  EncodeDivide({4, 9, 16, 1000000}, &s); frames.push_back({Msg::kDivide, s}); s.clear();
  add(Msg::kHeartbeat, EncodeHeartbeat);
  EncodeError("built a different mesh (12 elements, this has 14)", &s);
  frames.push_back({Msg::kError, s}); s.clear();
  add(Msg::kBye, EncodeBye);
  const std::string dir = argv[2];
  std::string stream = std::string("\0\7", 2);
  for (const auto& f : frames) {
    stream += f.second;
    const char mode = char(((int(f.first) - 1) << 1) | 1);
    Save(dir + "/payload-" + MsgName(f.first), mode + f.second.substr(kHeaderSize));
  }
  Save(dir + "/stream", stream);
  return 0;
}
