// The wire protocol (protocol.h): every message's round trip and the
// documented bytes, values out of range refused, truncated, oversized and
// garbled payloads and frames, the frame reader over any chunking.
#include "protocol.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ffcodec.h"
#include "groups.h"
#include "hemicube.h"
#include "test_util.h"
#include "wire_util.h"

namespace {

using proto::FrameReader;
using proto::Msg;

// The scene payload as the document lays it out, without any validation,
// so that tests can write invalid values.
std::string RawScene(const proto::SceneSetup& m) {
  std::string s;
  s += char(m.rotate);
  WVar(&s, uint32_t(m.resolution));
  WLE(&s, m.seed, 4);
  WVar(&s, uint32_t(m.mesh.elements_per_patch));
  WF64(&s, m.mesh.patch_size);
  s += char(m.mesh.join);
  WF64(&s, m.heartbeat_s);
  WVec(&s, m.scene.lo);
  WVec(&s, m.scene.hi);
  WVar(&s, m.scene.materials.size());
  for (const auto& mt : m.scene.materials) {
    WVec(&s, mt.kd);
    WVec(&s, mt.ke);
  }
  // The vertex table: every point once (by its bits), in order of first
  // use; then each face's corners as 0 (the next vertex of the table) or
  // how many places before the next one the vertex is.
  std::vector<glm::dvec3> table;
  std::vector<size_t> ids;
  for (const auto& f : m.scene.faces)
    for (const auto& v : f.verts) {
      size_t i = 0;
      while (i < table.size() && std::memcmp(&table[i], &v, sizeof v) != 0) ++i;
      if (i == table.size()) table.push_back(v);
      ids.push_back(i);
    }
  WVar(&s, table.size());
  for (const auto& v : table) WVec(&s, v);
  WVar(&s, m.scene.faces.size());
  long previous = -1;
  size_t fresh = 0, k = 0;
  for (const auto& f : m.scene.faces) {
    WVar(&s, uint32_t(f.material));
    const long d = f.index - previous - 1;  // zigzag: 0, -1, 1, -2 as 0, 1, 2, 3
    WVar(&s, d >= 0 ? uint64_t(2 * d) : uint64_t(-2 * d - 1));
    previous = f.index;
    WVar(&s, f.verts.size());
    for (size_t c = 0; c < f.verts.size(); ++c, ++k) {
      WVar(&s, ids[k] == fresh ? 0 : fresh - ids[k]);
      if (ids[k] == fresh) ++fresh;
    }
  }
  return s;
}


// A scene with everything BuildMesh reads: the inside of a box with its own
// material per face (one emitting), a pentagon and a triangle with
// coordinates that are not short decimals, face indices with gaps.
proto::SceneSetup TestSetup() {
  std::vector<glm::dvec3> kd = {glm::dvec3(0.1, 0.2, 0.3), glm::dvec3(1.0),     glm::dvec3(0.0),
                                glm::dvec3(0.7, 0.5, 0.3), glm::dvec3(1.0 / 3), glm::dvec3(0.5)};
  std::vector<glm::dvec3> ke = {glm::dvec3(0), glm::dvec3(12.5, 11, 1e-3), glm::dvec3(0),
                                glm::dvec3(0), glm::dvec3(0),              glm::dvec3(0)};
  proto::SceneSetup m;
  m.scene = Box(2.0, kd, ke);
  const double t = 1.0 / 3, u = std::sqrt(2.0) / 10;
  AddFace(&m.scene, {{0.5, 0.1, 0.5}, {1.5 + u, 0.1, 0.5}, {1.7, 0.1, 1.2 + t}, {1.0, 0.1, 1.6},
                     {0.3, 0.1, 1.1 - u}},
          glm::dvec3(0.25), glm::dvec3(0));  // a pentagon over the floor, facing down
  std::reverse(m.scene.faces.back().verts.begin(), m.scene.faces.back().verts.end());
  FacePlane(&m.scene.faces.back());
  AddFace(&m.scene, {{t, 1.9, t}, {t, 1.9, 1.0 + u}, {1.0 + t, 1.9, t}}, glm::dvec3(0.9),
          glm::dvec3(0));
  m.scene.faces.back().material = 2;  // materials shared by faces
  for (size_t i = 0; i < m.scene.faces.size(); ++i) m.scene.faces[i].index = int(3 * i + 1);
  m.mesh.patch_size = 0.45;
  m.mesh.elements_per_patch = 3;
  m.resolution = 128;
  m.rotate = 0;
  m.seed = 0xdeadbeef;
  m.heartbeat_s = 0.375;
  return m;
}

// Decodes a payload of type t with the matching decoder (Heartbeat and Bye:
// empty or not). For the fuzz and truncation tests.
bool DecodeAny(Msg t, const std::string& p, std::string* err) {
  switch (t) {
    case Msg::kHello: { proto::Hello m; return proto::DecodeHello(p, &m, err); }
    case Msg::kScene: { proto::SceneSetup m; return proto::DecodeScene(p, &m, err); }
    case Msg::kReady: { proto::Ready m; return proto::DecodeReady(p, &m, err); }
    case Msg::kWork: { std::vector<proto::Assignment> m; return proto::DecodeWork(p, &m, err); }
    case Msg::kColumn: { proto::Column m; return proto::DecodeColumn(p, &m, err); }
    case Msg::kDivide: { std::vector<int32_t> m; return proto::DecodeDivide(p, &m, err); }
    case Msg::kError: { std::string m; return proto::DecodeError(p, &m, err); }
    case Msg::kHeartbeat:
    case Msg::kBye:
      if (p.empty()) return true;
      *err = "not empty";
      return false;
  }
  return false;
}

proto::Column SmallColumn() {
  proto::Column c;
  c.patch = 17;
  c.k = 4;
  c.compute_s = 0.0123;
  c.wait_s = 1.5e-4;
  c.ff = {{0, 0.25f}, {1, 1e-7f}, {130, 0.015625f}, {100000, 1.0f}, {2000000000, 3e-20f}};
  return c;
}

// One valid frame of every type.
std::vector<std::string> SampleFrames() {
  std::vector<std::string> f(9);
  proto::Hello h;
  h.build = proto::BuildId();
  proto::EncodeHello(h, &f[0]);
  proto::EncodeScene(TestSetup(), &f[1]);
  proto::EncodeReady({123456, 0x0123456789abcdefull}, &f[2]);
  proto::EncodeWork({{0, 0}, {5, 1}, {1000000, 300}}, &f[3]);
  proto::EncodeColumn(SmallColumn(), &f[4]);
  proto::EncodeDivide({9, 3, 2000000, 0}, &f[5]);
  proto::EncodeHeartbeat(&f[6]);
  proto::EncodeError("worker: mesh differs (élément 3)", &f[7]);
  proto::EncodeBye(&f[8]);
  return f;
}

Msg TypeOf(const std::string& frame) { return Msg(uint8_t(frame[4])); }

// ---- names and identity -----------------------------------------------

TEST(Protocol, MsgNames) {
  const char* names[] = {"hello",  "scene",     "ready", "work", "column",
                         "divide", "heartbeat", "error", "bye"};
  for (int t = 1; t <= 9; ++t) EXPECT_STREQ(proto::MsgName(Msg(t)), names[t - 1]);
  EXPECT_STREQ(proto::MsgName(Msg(0)), "unknown");
  EXPECT_STREQ(proto::MsgName(Msg(10)), "unknown");
  EXPECT_STREQ(proto::MsgName(Msg(255)), "unknown");
}


TEST(Protocol, HelloRoundTrips) {
  for (const std::string& b : {std::string(), proto::BuildId(), std::string(256, 'x')}) {
    proto::Hello h;
    h.build = b;
    std::string frame;
    proto::EncodeHello(h, &frame);
    const std::string p = PayloadOf(frame, Msg::kHello);
    EXPECT_EQ(p.substr(0, 6), std::string("RADW\x07\x00", 6));  // magic, version
    proto::Hello d;
    d.magic = 0;
    d.version = 0;
    std::string err;
    ASSERT_TRUE(proto::DecodeHello(p, &d, &err)) << err;
    EXPECT_EQ(d.magic, proto::kMagic);
    EXPECT_EQ(d.version, proto::kVersion);
    EXPECT_EQ(d.build, b);
  }
  // A build string longer than 256 bytes or not printable is refused.
  std::string p = "RADW" + std::string("\x07\x00", 2);
  std::string long_build = p;
  WVar(&long_build, 257);
  long_build += std::string(257, 'x');
  std::string err;
  proto::Hello d;
  EXPECT_FALSE(proto::DecodeHello(long_build, &d, &err));
  EXPECT_FALSE(err.empty());
  std::string nl = p + "\x03" "a\nb";
  err.clear();
  EXPECT_FALSE(proto::DecodeHello(nl, &d, &err));
  EXPECT_FALSE(err.empty());
}

TEST(Protocol, HelloOfAnotherVersionStillShowsItsVersion) {
  // Magic and version never move, so a mismatch is reported as such even
  // when the rest is laid out differently.
  proto::Hello h;
  h.version = 8;
  h.build = "radiosity 9.9 proto 8";
  std::string frame;
  proto::EncodeHello(h, &frame);
  std::string p = PayloadOf(frame, Msg::kHello) + "future fields";
  proto::Hello d;
  std::string err;
  ASSERT_TRUE(proto::DecodeHello(p, &d, &err)) << err;
  EXPECT_EQ(d.magic, proto::kMagic);
  EXPECT_EQ(d.version, 8);
  EXPECT_EQ(d.build, h.build);
  // Not ours at all: magic and version come back, the build is empty.
  ASSERT_TRUE(proto::DecodeHello("HTTP/1.1 200 OK\r\n", &d, &err)) << err;
  EXPECT_NE(d.magic, proto::kMagic);
  EXPECT_EQ(d.build, "");
  // Too short for magic and version.
  EXPECT_FALSE(proto::DecodeHello("RADW\x01", &d, &err));
}

TEST(Protocol, SceneRoundTripsBitForBitAndRebuildsTheSameMesh) {
  const proto::SceneSetup m = TestSetup();
  std::string frame;
  proto::EncodeScene(m, &frame);
  const std::string p = PayloadOf(frame, Msg::kScene);
  EXPECT_EQ(Hex(p), Hex(RawScene(m))) << "the layout is not the documented one";
  proto::SceneSetup d;
  std::string err;
  ASSERT_TRUE(proto::DecodeScene(p, &d, &err)) << err;
  EXPECT_EQ(d.resolution, m.resolution);
  EXPECT_EQ(d.rotate, m.rotate);
  EXPECT_EQ(d.seed, m.seed);
  EXPECT_EQ(Bits(d.heartbeat_s), Bits(m.heartbeat_s));
  EXPECT_EQ(Bits(d.mesh.patch_size), Bits(m.mesh.patch_size));
  // The groups come with the work (Assignment): a worker forms none.
  EXPECT_TRUE(m.mesh.groups);
  EXPECT_FALSE(d.mesh.groups);
  EXPECT_EQ(d.mesh.elements_per_patch, m.mesh.elements_per_patch);
  EXPECT_EQ(d.mesh.join, m.mesh.join);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(Bits(d.scene.lo[k]), Bits(m.scene.lo[k]));
    EXPECT_EQ(Bits(d.scene.hi[k]), Bits(m.scene.hi[k]));
  }
  ASSERT_EQ(d.scene.materials.size(), m.scene.materials.size());
  for (size_t i = 0; i < m.scene.materials.size(); ++i) {
    EXPECT_EQ(d.scene.materials[i].name, "");
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(Bits(d.scene.materials[i].kd[k]), Bits(m.scene.materials[i].kd[k]));
      EXPECT_EQ(Bits(d.scene.materials[i].ke[k]), Bits(m.scene.materials[i].ke[k]));
    }
  }
  ASSERT_EQ(d.scene.faces.size(), m.scene.faces.size());
  for (size_t i = 0; i < m.scene.faces.size(); ++i) {
    const Face &a = d.scene.faces[i], &b = m.scene.faces[i];
    EXPECT_EQ(a.material, b.material);
    EXPECT_EQ(a.index, b.index);
    EXPECT_EQ(a.object, 0);
    EXPECT_EQ(a.line, 0);
    EXPECT_EQ(Bits(a.area), Bits(b.area));
    ASSERT_EQ(a.verts.size(), b.verts.size());
    for (int k = 0; k < 3; ++k) EXPECT_EQ(Bits(a.normal[k]), Bits(b.normal[k]));
    for (size_t v = 0; v < a.verts.size(); ++v)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(Bits(a.verts[v][k]), Bits(b.verts[v][k]));
  }
  EXPECT_EQ(d.scene.objects, std::vector<std::string>{"default"});
  EXPECT_EQ(d.scene.path, "");
  EXPECT_FALSE(d.scene.has_camera);

  // What the worker does with it.
  Mesh original = MakeMesh(m.scene, m.mesh), rebuilt = MakeMesh(d.scene, d.mesh);
  EXPECT_EQ(rebuilt.elems.size(), original.elems.size());
  EXPECT_GT(original.elems.size(), 500u);
  EXPECT_EQ(MeshHash(rebuilt), MeshHash(original));

  // And with the default mesh options on the plain box of test_util.h.
  proto::SceneSetup box;
  box.scene = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  frame.clear();
  proto::EncodeScene(box, &frame);
  ASSERT_TRUE(proto::DecodeScene(PayloadOf(frame, Msg::kScene), &d, &err)) << err;
  EXPECT_EQ(MeshHash(MakeMesh(d.scene, d.mesh)), MeshHash(MakeMesh(box.scene)));
}

TEST(Protocol, SceneValuesOutOfRangeAreRefused) {
  const proto::SceneSetup good = TestSetup();
  ASSERT_EQ(good.scene.materials.size(), 9u);  // default, 6 walls, pentagon, triangle
  std::string err;
  proto::SceneSetup d;
  ASSERT_TRUE(proto::DecodeScene(RawScene(good), &d, &err)) << err;
  using S = proto::SceneSetup;
  struct Case {
    const char* what;
    void (*edit)(S*);
    bool ok;
  };
  const Case cases[] = {
      {"resolution 8", [](S* m) { m->resolution = 8; }, true},
      {"resolution max", [](S* m) { m->resolution = Hemicube::kMaxResolution; }, true},
      {"resolution 6", [](S* m) { m->resolution = 6; }, false},
      {"resolution 0", [](S* m) { m->resolution = 0; }, false},
      {"resolution odd", [](S* m) { m->resolution = 129; }, false},
      {"resolution max+2", [](S* m) { m->resolution = Hemicube::kMaxResolution + 2; }, false},
      {"rotate 2", [](S* m) { m->rotate = 2; }, false},
      {"rotate 1", [](S* m) { m->rotate = 1; }, true},
      {"epp 1", [](S* m) { m->mesh.elements_per_patch = 1; }, true},
      {"epp 64", [](S* m) { m->mesh.elements_per_patch = 64; }, true},
      {"epp 0", [](S* m) { m->mesh.elements_per_patch = 0; }, false},
      {"epp 65", [](S* m) { m->mesh.elements_per_patch = 65; }, false},
      {"patch size 0", [](S* m) { m->mesh.patch_size = 0; }, true},
      {"patch size < 0", [](S* m) { m->mesh.patch_size = -0.5; }, false},
      {"patch size inf", [](S* m) { m->mesh.patch_size = HUGE_VAL; }, false},
      {"patch size nan", [](S* m) { m->mesh.patch_size = std::nan(""); }, false},
      {"heartbeat 1 ms", [](S* m) { m->heartbeat_s = 1e-3; }, true},
      {"heartbeat max", [](S* m) { m->heartbeat_s = proto::kMaxHeartbeat; }, true},
      {"heartbeat 0", [](S* m) { m->heartbeat_s = 0; }, false},
      {"heartbeat < 0", [](S* m) { m->heartbeat_s = -1; }, false},
      {"heartbeat past max", [](S* m) { m->heartbeat_s = std::nextafter(proto::kMaxHeartbeat, 1e9); }, false},
      {"heartbeat inf", [](S* m) { m->heartbeat_s = HUGE_VAL; }, false},
      {"heartbeat nan", [](S* m) { m->heartbeat_s = std::nan(""); }, false},
      {"lo > hi", [](S* m) { m->scene.lo.y = m->scene.hi.y + 1; }, false},
      {"hi nan", [](S* m) { m->scene.hi.z = std::nan(""); }, false},
      {"no materials", [](S* m) { m->scene.materials.clear(); m->scene.faces.clear(); }, false},
      {"no faces", [](S* m) { m->scene.faces.clear(); }, true},
      {"material out of range", [](S* m) { m->scene.faces[3].material = 9; }, false},
      {"material last", [](S* m) { m->scene.faces[3].material = 8; }, true},
      {"two vertices", [](S* m) { m->scene.faces[2].verts.resize(2); }, false},
      {"no vertices", [](S* m) { m->scene.faces[2].verts.clear(); }, false},
      {"vertex nan", [](S* m) { m->scene.faces[6].verts[4].y = std::nan(""); }, false},
      {"vertex inf", [](S* m) { m->scene.faces[0].verts[0].x = -HUGE_VAL; }, false},
      // Normal and area are not sent: the decoder computes them, and a
      // face whose vertices make no area is refused.
      {"collinear", [](S* m) { m->scene.faces[1].verts = {glm::dvec3(0), glm::dvec3(1), glm::dvec3(2)}; }, false},
      {"a point", [](S* m) { m->scene.faces[1].verts.assign(4, glm::dvec3(0.5)); }, false},
      {"1000 vertices", [](S* m) {
         auto& v = m->scene.faces[1].verts;
         v.resize(1000);
         for (int i = 0; i < 1000; ++i) v[i] = glm::dvec3(std::cos(i * 2 * M_PI / 1000), std::sin(i * 2 * M_PI / 1000), 3);
       }, true},
      {"1001 vertices", [](S* m) { m->scene.faces[1].verts.resize(1001, glm::dvec3(0.5)); }, false},
      {"index 0 everywhere", [](S* m) { for (Face& f : m->scene.faces) f.index = 0; }, true},
      {"index decreasing", [](S* m) { m->scene.faces[2].index = 0; }, true},
      {"index max", [](S* m) { m->scene.faces.back().index = INT32_MAX; }, true},
      {"kd > 1", [](S* m) { m->scene.materials[1].kd.g = std::nextafter(1.0, 2.0); }, false},
      {"kd < 0", [](S* m) { m->scene.materials[1].kd.b = -1e-300; }, false},
      {"kd nan", [](S* m) { m->scene.materials[0].kd.r = std::nan(""); }, false},
      {"ke < 0", [](S* m) { m->scene.materials[2].ke.r = -1; }, false},
      {"ke inf", [](S* m) { m->scene.materials[2].ke.r = HUGE_VAL; }, false},
      {"ke big", [](S* m) { m->scene.materials[2].ke.r = 1e300; }, true},
  };
  for (const Case& c : cases) {
    proto::SceneSetup m = good;
    c.edit(&m);
    err.clear();
    EXPECT_EQ(proto::DecodeScene(RawScene(m), &d, &err), c.ok) << c.what << ": " << err;
    if (!c.ok) {
      EXPECT_FALSE(err.empty()) << c.what;
    }
  }
}

// The vertex table and the corners that refer to it, written by hand: the
// table must be in order of first use, each point once, every point used.
TEST(Protocol, SceneVertexTableIsChecked) {
  proto::SceneSetup none = TestSetup();
  none.scene.faces.clear();
  const std::string head = RawScene(none).substr(0, RawScene(none).size() - 2);  // to the table
  const glm::dvec3 p[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  auto scene = [&](std::vector<glm::dvec3> table, uint64_t index, std::vector<uint64_t> corners) {
    std::string s = head;
    WVar(&s, table.size());
    for (const auto& v : table) WVec(&s, v);
    WVar(&s, 1);  // one face
    WVar(&s, 0);  // material 0
    WVar(&s, index);
    WVar(&s, corners.size());
    for (uint64_t c : corners) WVar(&s, c);
    return s;
  };
  struct Case {
    const char* what;
    std::string payload;
    const char* error;  // "" when it decodes
  };
  const Case cases[] = {
      {"a triangle", scene({p[0], p[1], p[2]}, 0, {0, 0, 0}), ""},
      {"a quad", scene({p[0], p[1], p[3], p[2]}, 6, {0, 0, 0, 0}), ""},
      {"an earlier vertex again", scene({p[0], p[1], p[2]}, 0, {0, 0, 0, 3}), ""},
      {"past the table", scene({p[0], p[1], p[2]}, 0, {0, 0, 0, 0}), "more vertices than the table"},
      {"back past the first", scene({p[0], p[1], p[2]}, 0, {0, 0, 3}), "face vertex"},
      {"a vertex unused", scene({p[0], p[1], p[2], p[3]}, 0, {0, 0, 0}), "used by no face"},
      {"a vertex twice", scene({p[0], p[1], p[2], p[0]}, 0, {0, 0, 0, 0}), "repeats vertex 0"},
      {"-0.0 is not 0.0", scene({p[0], p[1], p[2], glm::dvec3(-0.0, 0, 0)}, 0, {0, 0, 0, 0}), ""},
      {"index -1", scene({p[0], p[1], p[2]}, 1, {0, 0, 0}), "index -1"},
      {"index 2^31-1", scene({p[0], p[1], p[2]}, uint64_t(INT32_MAX) * 2, {0, 0, 0}), ""},
      {"index 2^31", scene({p[0], p[1], p[2]}, uint64_t(INT32_MAX) * 2 + 2, {0, 0, 0}), "face index"},
      {"no area", scene({p[0], glm::dvec3(1, 1, 1), glm::dvec3(2, 2, 2)}, 0, {0, 0, 0}), "area"},
  };
  for (const Case& c : cases) {
    proto::SceneSetup d;
    std::string err;
    const bool ok = proto::DecodeScene(c.payload, &d, &err);
    EXPECT_EQ(ok, !*c.error) << c.what << ": " << err;
    if (*c.error) {
      EXPECT_NE(err.find(c.error), std::string::npos) << c.what << ": " << err;
      EXPECT_EQ(err.find('\n'), std::string::npos) << c.what;
    }
    if (!ok) continue;
    // What decodes encodes to the same bytes.
    std::string again;
    proto::EncodeScene(d, &again);
    EXPECT_EQ(Hex(again.substr(proto::kHeaderSize)), Hex(c.payload)) << c.what;
  }
}

TEST(Protocol, ReadyRoundTrips) {
  for (proto::Ready r : {proto::Ready{0, 0}, proto::Ready{20000000, 0x0123456789abcdefull},
                         proto::Ready{UINT64_MAX, UINT64_MAX}}) {
    std::string frame;
    proto::EncodeReady(r, &frame);
    const std::string p = PayloadOf(frame, Msg::kReady);
    EXPECT_EQ(p.size(), 16u);
    proto::Ready d;
    std::string err;
    ASSERT_TRUE(proto::DecodeReady(p, &d, &err)) << err;
    EXPECT_EQ(d.elements, r.elements);
    EXPECT_EQ(d.mesh_hash, r.mesh_hash);
  }
}

// A column sent from its form factors coded once (bench/feed.cpp) is the
// frame EncodeColumn makes of them, and decodes to the same column.
TEST(Protocol, ColumnFromCodedFormFactorsIsTheSameFrame) {
  const proto::Column c = SmallColumn();
  std::string frame, coded, from_coded = "kept";
  proto::EncodeColumn(c, &frame);
  proto::PutFormFactors(c.ff, &coded);
  proto::Column header = c;
  header.ff.clear();  // not read: the coded bytes stand for it
  proto::EncodeColumn(header, coded, &from_coded);
  EXPECT_EQ(from_coded, "kept" + frame);
  proto::Column d;
  std::string err;
  ASSERT_TRUE(proto::DecodeColumn(PayloadOf(frame, Msg::kColumn), &d, &err)) << err;
  EXPECT_EQ(d.patch, c.patch);
  EXPECT_EQ(d.k, c.k);
  EXPECT_EQ(d.ff.size(), c.ff.size());
}

TEST(Protocol, WorkRoundTrips) {
  std::mt19937 rng(7);
  std::vector<proto::Assignment> big;
  for (int i = 0; i < 1000; ++i) big.push_back({int32_t(rng() >> 1), int32_t(rng() % 1000)});
  using W = std::vector<proto::Assignment>;
  for (const W& w : {W{}, W{{0, 0}}, W{{INT32_MAX, INT32_MAX}, {3, 2}, {3, 1}}, big}) {
    std::string frame;
    proto::EncodeWork(w, &frame);
    std::vector<proto::Assignment> d = {{1, 1}};
    std::string err;
    ASSERT_TRUE(proto::DecodeWork(PayloadOf(frame, Msg::kWork), &d, &err)) << err;
    ASSERT_EQ(d.size(), w.size());
    for (size_t i = 0; i < w.size(); ++i) {
      EXPECT_EQ(d[i].patch, w[i].patch);
      EXPECT_EQ(d[i].k, w[i].k);
    }
  }
  std::string p, err;
  WVar(&p, 1);
  WVar(&p, 1ull << 31);  // patch > INT32_MAX
  WVar(&p, 0);
  WVar(&p, 0);
  std::vector<proto::Assignment> d;
  EXPECT_FALSE(proto::DecodeWork(p, &d, &err));
  EXPECT_FALSE(err.empty());
}

// A group's first member's assignment carries the group: members,
// centre and normal bit for bit (the worker's column is the master's).
proto::Assignment Grouped(int32_t patch, int32_t k, std::vector<int> members) {
  proto::Assignment a{patch, k};
  a.group.members = std::move(members);
  a.group.center = glm::dvec3(0.1, 1.0 / 3, -2e-7);
  a.group.normal = glm::normalize(glm::dvec3(0.2, 1, -0.1));
  return a;
}

TEST(Protocol, WorkCarriesShooterGroups) {
  std::vector<int> widest;
  for (int i = 0; i < kMaxGroup; ++i) widest.push_back(1000 + 300 * i);
  std::vector<int> last = {INT32_MAX - 2, INT32_MAX};
  const std::vector<proto::Assignment> w = {
      {7, 0}, Grouped(3, 2, {3, 4, 9, 200000}), {8, 1}, Grouped(1000, 0, widest),
      Grouped(INT32_MAX - 2, 5, last)};
  std::string frame;
  proto::EncodeWork(w, &frame);
  const std::string p = PayloadOf(frame, Msg::kWork);
  // The layout: count, then per assignment patch, k, member count and,
  // for a group, the members after the first as increments, centre, normal.
  std::string raw;
  WVar(&raw, w.size());
  for (const proto::Assignment& a : w) {
    WVar(&raw, uint32_t(a.patch));
    WVar(&raw, uint32_t(a.k));
    WVar(&raw, a.group.members.size());
    for (size_t i = 1; i < a.group.members.size(); ++i)
      WVar(&raw, uint32_t(a.group.members[i] - a.group.members[i - 1]));
    if (a.group.members.empty()) continue;
    WVec(&raw, a.group.center);
    WVec(&raw, a.group.normal);
  }
  EXPECT_EQ(Hex(p), Hex(raw)) << "the layout is not the documented one";
  // A lone shooter's assignment costs one byte more than before groups
  // travelled; a group of 4 spread over 2 * 10^5 patches, 54 bytes more.
  std::string one;
  proto::EncodeWork({w[1]}, &one);
  EXPECT_EQ(one.size(), proto::kHeaderSize + 1 + 1 + 1 + 1 + 1 + 1 + 3 + 48);
  std::vector<proto::Assignment> d;
  std::string err;
  ASSERT_TRUE(proto::DecodeWork(p, &d, &err)) << err;
  ASSERT_EQ(d.size(), w.size());
  for (size_t i = 0; i < w.size(); ++i) {
    EXPECT_EQ(d[i].patch, w[i].patch);
    EXPECT_EQ(d[i].k, w[i].k);
    EXPECT_EQ(d[i].Group() != nullptr, w[i].Group() != nullptr) << i;
    EXPECT_EQ(d[i].group.members, w[i].group.members) << i;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(Bits(d[i].group.center[k]), Bits(w[i].group.center[k])) << i;
      EXPECT_EQ(Bits(d[i].group.normal[k]), Bits(w[i].group.normal[k])) << i;
    }
  }
}

// Each malformed group is refused with a one-line message.
TEST(Protocol, BadShooterGroupsAreRefused) {
  struct Case {
    const char* name;
    std::function<void(std::string*)> members;  // after patch 5, k 0
    const char* error;
  };
  const glm::dvec3 c(0.5), up(0, 1, 0);
  auto vecs = [](std::string* s, glm::dvec3 c, glm::dvec3 n) { WVec(s, c), WVec(s, n); };
  const Case cases[] = {
      {"one member", [&](std::string* s) { WVar(s, 1); vecs(s, c, up); }, "1 member"},
      {"not increasing", [&](std::string* s) { WVar(s, 3); WVar(s, 2); WVar(s, 0); vecs(s, c, up); },
       "members not increasing"},
      {"too many", [&](std::string* s) {
         WVar(s, kMaxGroup + 1);
         for (int i = 0; i < kMaxGroup; ++i) WVar(s, 1);
         vecs(s, c, up);
       }, "group member count"},
      {"past 2^31-1", [&](std::string* s) { WVar(s, 2); WVar(s, INT32_MAX); vecs(s, c, up); },
       "is not in 0..2^31-1"},
      {"centre nan", [&](std::string* s) { WVar(s, 2); WVar(s, 1); vecs(s, glm::dvec3(std::nan("")), up); },
       "group centre"},
      {"normal inf", [&](std::string* s) { WVar(s, 2); WVar(s, 1); vecs(s, c, glm::dvec3(0, HUGE_VAL, 0)); },
       "group normal"},
      {"normal not unit", [&](std::string* s) { WVar(s, 2); WVar(s, 1); vecs(s, c, glm::dvec3(0, 1.001, 0)); },
       "normal is not of unit length"},
      {"normal zero", [&](std::string* s) { WVar(s, 2); WVar(s, 1); vecs(s, c, glm::dvec3(0)); },
       "normal is not of unit length"},
      {"cut short", [&](std::string* s) { WVar(s, 2); WVar(s, 1); WVec(s, c); }, "group normal"},
  };
  for (const Case& k : cases) {
    std::string p;
    WVar(&p, 1);
    WVar(&p, 5);
    WVar(&p, 0);
    k.members(&p);
    std::vector<proto::Assignment> d;
    std::string err;
    EXPECT_FALSE(proto::DecodeWork(p, &d, &err)) << k.name;
    EXPECT_NE(err.find(k.error), std::string::npos) << k.name << ": " << err;
    EXPECT_EQ(err.find('\n'), std::string::npos) << k.name << ": " << err;
  }
}

TEST(Protocol, DivideRoundTripsInOrder) {
  for (const auto& v : {std::vector<int32_t>{}, std::vector<int32_t>{0},
                        std::vector<int32_t>{900, 3, 17, 2000000, 4, INT32_MAX},
                        std::vector<int32_t>{~0, 5, ~INT32_MAX, ~7}}) {  // ~p: splits
    std::string frame;
    proto::EncodeDivide(v, &frame);
    std::vector<int32_t> d = {42};
    std::string err;
    ASSERT_TRUE(proto::DecodeDivide(PayloadOf(frame, Msg::kDivide), &d, &err)) << err;
    EXPECT_EQ(d, v);
  }
  std::string p, err;
  WVar(&p, 2);
  WVar(&p, 5);
  WVar(&p, 1ull << 32);  // edits are 2e or 2p + 1 below 2^32
  std::vector<int32_t> d;
  EXPECT_FALSE(proto::DecodeDivide(p, &d, &err));
  EXPECT_FALSE(err.empty());
}

TEST(Protocol, ErrorRoundTripsAsOneLineOfUtf8) {
  auto round = [](const std::string& text) {
    std::string frame, d, err;
    proto::EncodeError(text, &frame);
    EXPECT_TRUE(proto::DecodeError(PayloadOf(frame, Msg::kError), &d, &err)) << err;
    return d;
  };
  EXPECT_EQ(round(""), "");
  const std::string utf8 = "worker 3: mesh differs: élément ∑ 😀";
  EXPECT_EQ(round(utf8), utf8);
  EXPECT_EQ(round("two\nlines\tand\x7f"), "two lines and ");
  EXPECT_EQ(round("bad \xff\xc0\x80 bytes"), "bad ??? bytes");
  EXPECT_EQ(round(std::string(5000, 'a')), std::string(4096, 'a'));
  EXPECT_EQ(round(std::string(4095, 'a') + "€"), std::string(4095, 'a'));  // not cut inside
  // The decoder takes only what the encoder makes.
  for (const std::string& bad : {std::string("\xc0\x80"), std::string("\xed\xa0\x80"),
                                 std::string("\xf4\x90\x80\x80"), std::string("\x80"),
                                 std::string("a\nb"), std::string("\xe2\x82")}) {
    std::string p, d, err;
    WVar(&p, bad.size());
    p += bad;
    EXPECT_FALSE(proto::DecodeError(p, &d, &err)) << Hex(bad);
    EXPECT_FALSE(err.empty());
  }
  std::string p, d, err;
  WVar(&p, 4097);
  p += std::string(4097, 'a');
  EXPECT_FALSE(proto::DecodeError(p, &d, &err));
}

TEST(Protocol, HeartbeatAndByeAreBareHeaders) {
  std::string hb, bye;
  proto::EncodeHeartbeat(&hb);
  proto::EncodeBye(&bye);
  EXPECT_EQ(Hex(hb), "0000000007000000");
  EXPECT_EQ(Hex(bye), "0000000009000000");
}


// ---- malformed input ----------------------------------------------------

TEST(Protocol, EveryTruncatedPayloadFailsWithAMessage) {
  for (const std::string& frame : SampleFrames()) {
    const Msg t = TypeOf(frame);
    const std::string p = PayloadOf(frame, t);
    std::string err;
    ASSERT_TRUE(DecodeAny(t, p, &err)) << proto::MsgName(t) << ": " << err;
    for (size_t len = 0; len < p.size(); ++len) {
      err.clear();
      EXPECT_FALSE(DecodeAny(t, p.substr(0, len), &err)) << proto::MsgName(t) << " cut to " << len;
      EXPECT_FALSE(err.empty()) << proto::MsgName(t) << " cut to " << len;
    }
  }
}

TEST(Protocol, ExtraBytesFail) {
  for (const std::string& frame : SampleFrames()) {
    const Msg t = TypeOf(frame);
    const std::string p = PayloadOf(frame, t);
    for (const std::string& extra : {std::string(1, '\0'), std::string("abc")}) {
      std::string err;
      EXPECT_FALSE(DecodeAny(t, p + extra, &err)) << proto::MsgName(t);
      EXPECT_FALSE(err.empty()) << proto::MsgName(t);
    }
  }
}

TEST(Protocol, HugeCountsFailFastWithoutAllocating) {
  // Counts that would need gigabytes fail on the bytes left, before any
  // allocation (which would throw bad_alloc and fail this test).
  std::string err;
  for (uint64_t n : {uint64_t(1) << 31, uint64_t(1) << 40, UINT64_MAX}) {
    std::string p;
    WVar(&p, n);
    p += std::string(8, '\x01');
    std::vector<proto::Assignment> w;
    std::vector<int32_t> v;
    EXPECT_FALSE(proto::DecodeWork(p, &w, &err));
    EXPECT_FALSE(proto::DecodeDivide(p, &v, &err));
    std::string col = std::string("\x01\x01", 2) + std::string(16, '\0');
    WVar(&col, n);
    proto::Column c;
    EXPECT_FALSE(proto::DecodeColumn(col, &c, &err));
    EXPECT_NE(err.find("bytes left"), std::string::npos) << err;
    // A run count as large, after a plausible form factor count.
    std::string runs = std::string("\x01\x01", 2) + std::string(16, '\0') + "\x08";
    WVar(&runs, n);
    runs += std::string(16, '\x01');
    EXPECT_FALSE(proto::DecodeColumn(runs, &c, &err));
    EXPECT_NE(err.find("run count"), std::string::npos) << err;

    proto::SceneSetup s = TestSetup();
    s.scene.faces.clear();
    std::string sc = RawScene(s);
    sc.pop_back();  // the face count
    proto::SceneSetup d;
    WVar(&sc, n);
    sc += std::string(10, '\0');
    EXPECT_FALSE(proto::DecodeScene(sc, &d, &err));
    EXPECT_NE(err.find("face count"), std::string::npos) << err;
    std::string mats = sc.substr(0, 82);  // fixed fields, then the material count
    WVar(&mats, n);
    EXPECT_FALSE(proto::DecodeScene(mats, &d, &err));
    EXPECT_NE(err.find("material count"), std::string::npos) << err;
    // A vertex table as large.
    std::string vt = RawScene(s).substr(0, RawScene(s).size() - 2);  // to the table's count
    WVar(&vt, n);
    vt += std::string(30, '\0');
    EXPECT_FALSE(proto::DecodeScene(vt, &d, &err));
    EXPECT_NE(err.find("vertex count"), std::string::npos) << err;
    // A face claiming n vertices.
    s = TestSetup();
    s.scene.faces.resize(1);
    std::string fv = RawScene(s).substr(0, RawScene(s).size() - 4);  // its 4 corners
    fv.resize(fv.size() - 1);  // its vertex count (4, one byte)
    WVar(&fv, n);
    fv += std::string(200, '\0');
    EXPECT_FALSE(proto::DecodeScene(fv, &d, &err));
    EXPECT_NE(err.find("vertex count"), std::string::npos) << err;
  }
}

TEST(Protocol, BadHeadersFail) {
  struct Case {
    std::string header;
    bool bad;
  };
  const Case cases[] = {
      {Header(proto::kMaxFrame, 2), false},  // a scene of the largest size: wait for it
      {Header(proto::kMaxFrame + 1, 2), true},
      {Header(0xffffffffu, 5), true},
      {Header(proto::kMaxFrame, 5), false},
      {Header(0, 0), true},
      {Header(0, 10), true},
      {Header(0, 255), true},
      {Header(0, 7, 1, 0, 0), true},
      {Header(0, 7, 0, 1, 0), true},
      {Header(0, 7, 0, 0, 0x80), true},
      {Header(1, 7), true},   // heartbeat with a payload
      {Header(1, 9), true},   // bye with a payload
      {Header(17, 3), true},  // ready is 16 bytes
      {Header(16, 3), false},
      {Header(4099, 8), true},  // error text is at most 4096 bytes
      {Header(4097, 1), true},  // hello
  };
  for (const Case& c : cases) {
    FrameReader r;
    r.Append(c.header.data(), c.header.size());
    Msg t;
    std::string p, err;
    FrameReader::Result res = r.Next(&t, &p, &err);
    EXPECT_EQ(res, c.bad ? FrameReader::kBad : FrameReader::kNeedMore) << Hex(c.header);
    if (!c.bad) continue;
    EXPECT_FALSE(err.empty());
    // No resynchronisation: it stays bad and keeps nothing.
    std::string good;
    proto::EncodeHeartbeat(&good);
    r.Append(good.data(), good.size());
    err.clear();
    EXPECT_EQ(r.Next(&t, &p, &err), FrameReader::kBad);
    EXPECT_FALSE(err.empty());
    EXPECT_EQ(r.buffered(), 0u);
  }
  // Seven bytes of a header are not a frame yet.
  FrameReader r;
  std::string hb;
  proto::EncodeHeartbeat(&hb);
  r.Append(hb.data(), 7);
  Msg t;
  std::string p, err;
  EXPECT_EQ(r.Next(&t, &p, &err), FrameReader::kNeedMore);
  r.Append(hb.data() + 7, 1);
  EXPECT_EQ(r.Next(&t, &p, &err), FrameReader::kFrame);
  EXPECT_EQ(t, Msg::kHeartbeat);
}

// ---- framing --------------------------------------------------------------

struct Frame {
  Msg type;
  std::string payload;
  bool operator==(const Frame& o) const { return type == o.type && payload == o.payload; }
};

// Feeds `stream` in pieces of the sizes `chunk` returns; reads every frame
// as soon as it is complete.
template <class Chunk>
std::vector<Frame> ReadAll(const std::string& stream, Chunk chunk, size_t* peak) {
  FrameReader r;
  std::vector<Frame> out;
  *peak = 0;
  for (size_t pos = 0; pos < stream.size();) {
    size_t n = std::min(chunk(), stream.size() - pos);
    r.Append(stream.data() + pos, n);
    pos += n;
    *peak = std::max(*peak, r.buffered());
    Frame f;
    std::string err;
    FrameReader::Result res;
    while ((res = r.Next(&f.type, &f.payload, &err)) == FrameReader::kFrame) out.push_back(f);
    EXPECT_EQ(res, FrameReader::kNeedMore) << err;
  }
  EXPECT_EQ(r.buffered(), 0u);
  return out;
}

TEST(Protocol, FrameReaderGivesTheSameFramesHoweverTheBytesArrive) {
  std::mt19937 rng(99);
  const std::vector<std::string> samples = SampleFrames();
  std::string stream;
  std::vector<Frame> want;
  size_t largest = 0;
  for (int i = 0; i < 400; ++i) {
    std::string f;
    if (i % 3 == 0) {
      f = samples[rng() % samples.size()];
    } else {  // columns of random sizes, as a master receives them
      proto::Column c;
      c.patch = int32_t(rng() % 1000);
      c.k = i;
      int32_t id = int32_t(rng() % 50);
      for (int n = int(rng() % 500); n > 0; --n) {
        c.ff.push_back({id, float(rng() % 1000 + 1) * 1e-6f});
        id += 1 + int32_t(rng() % 30);
      }
      proto::EncodeColumn(c, &f);
    }
    want.push_back({TypeOf(f), f.substr(proto::kHeaderSize)});
    largest = std::max(largest, f.size());
    stream += f;
  }
  size_t peak;
  EXPECT_EQ(ReadAll(stream, [&] { return stream.size(); }, &peak), want);
  EXPECT_EQ(ReadAll(stream, [] { return size_t{1}; }, &peak), want);
  EXPECT_LE(peak, largest);
  for (size_t most : {7, 100, 5000}) {
    std::uniform_int_distribution<size_t> sz(1, most);
    EXPECT_EQ(ReadAll(stream, [&] { return sz(rng); }, &peak), want) << most;
    EXPECT_LT(peak, largest + most);
  }
}

TEST(Protocol, FrameReaderKeepsUpWithALongStream) {
  // 200 MB through in 64 KB reads: linear time (the buffer is compacted,
  // not re-copied per frame) and every frame intact.
  proto::Column c;
  for (int32_t e = 0; e < 2500; ++e) c.ff.push_back({3 * e, 0.001f});
  std::string col;
  proto::EncodeColumn(c, &col);
  std::string hb;
  proto::EncodeHeartbeat(&hb);
  std::string block;
  while (block.size() < (size_t{1} << 20)) block += col + hb;
  FrameReader r;
  size_t frames = 0, bytes = 0;
  Msg t;
  std::string p, err;
  for (int round = 0; round < 200; ++round)
    for (size_t pos = 0; pos < block.size(); pos += 65536) {
      r.Append(block.data() + pos, std::min<size_t>(65536, block.size() - pos));
      FrameReader::Result res;
      while ((res = r.Next(&t, &p, &err)) == FrameReader::kFrame) {
        ++frames;
        bytes += p.size() + proto::kHeaderSize;
        ASSERT_TRUE(t == Msg::kHeartbeat || p.size() == col.size() - proto::kHeaderSize);
      }
      ASSERT_EQ(res, FrameReader::kNeedMore) << err;
      ASSERT_LT(r.buffered(), col.size() + 65536);
    }
  EXPECT_EQ(bytes, 200 * block.size());
  EXPECT_EQ(r.buffered(), 0u);
  EXPECT_GT(frames, 0u);
}

TEST(Protocol, FrameReaderGivesALargeFrameBackOnceCopiedOut) {
  // A worker copies its scene frame out (9 MB at 10^6 elements) and builds
  // its mesh from the copy: the reader must not keep the frame beside it
  // until its next call.
  proto::Column c;
  c.patch = 3;
  for (int32_t e = 0; e < 1200000; ++e) c.ff.push_back({e, 0.5f / 1200000});
  std::string f;
  proto::EncodeColumn(c, &f);
  ASSERT_GT(f.size(), size_t{1} << 20);
  FrameReader r;
  r.Append(f.data(), f.size());
  Msg t;
  std::string payload, err;
  ASSERT_EQ(r.Next(&t, &payload, &err), FrameReader::kFrame) << err;
  EXPECT_EQ(payload.size(), f.size() - proto::kHeaderSize);
  EXPECT_LT(r.held(), size_t{1} << 20);
}

TEST(Protocol, FrameReaderViewStaysValidUntilTheNextCall) {
  // A whole column and part of the next in the buffer: the first column's
  // payload handed out as a view is still its bytes when read after Next
  // returned (had the reader moved the rest of the buffer over it then,
  // as it may before its next call, the view would see the next frame).
  proto::Column a, b;
  a.patch = 1;
  b.patch = 2;
  for (int32_t e = 0; e < 300; ++e) a.ff.push_back({2 * e, 0.001f * float(e + 1)});
  for (int32_t e = 0; e < 900; ++e) b.ff.push_back({e, 0.002f});
  std::string fa, fb;
  proto::EncodeColumn(a, &fa);
  proto::EncodeColumn(b, &fb);
  const std::string stream = fa + fb;
  FrameReader r;
  r.Append(stream.data(), fa.size() + 10);
  Msg t;
  std::string_view view;
  std::string err;
  ASSERT_EQ(r.Next(&t, &view, &err), FrameReader::kFrame) << err;
  EXPECT_EQ(t, Msg::kColumn);
  EXPECT_EQ(view, std::string_view(fa).substr(proto::kHeaderSize));
  EXPECT_EQ(r.Next(&t, &view, &err), FrameReader::kNeedMore);
  // Then the rest: the next frame whole, as the copying Next gives it.
  r.Append(stream.data() + fa.size() + 10, fb.size() - 10);
  ASSERT_EQ(r.Next(&t, &view, &err), FrameReader::kFrame) << err;
  EXPECT_EQ(view, std::string_view(fb).substr(proto::kHeaderSize));
  proto::Column got;
  ASSERT_TRUE(proto::DecodeColumn(view, &got, &err)) << err;
  EXPECT_EQ(got.patch, 2);
  EXPECT_EQ(got.ff.size(), b.ff.size());
  EXPECT_EQ(r.buffered(), 0u);
}

// ---- garbage --------------------------------------------------------------

// Checks what a decoder accepted: the values are in range and encoding them
// again gives the same bytes (the coding is canonical).
void CheckAccepted(Msg t, const std::string& p) {
  std::string err, again;
  switch (t) {
    case Msg::kHello: {
      proto::Hello m;
      ASSERT_TRUE(proto::DecodeHello(p, &m, &err));
      if (m.magic == proto::kMagic && m.version == proto::kVersion) {
        proto::EncodeHello(m, &again);
        EXPECT_EQ(Hex(again.substr(8)), Hex(p));
      }
      return;
    }
    case Msg::kScene: {
      proto::SceneSetup m;
      ASSERT_TRUE(proto::DecodeScene(p, &m, &err));
      proto::EncodeScene(m, &again);  // CHECKs every value
      break;
    }
    case Msg::kReady: {
      proto::Ready m;
      ASSERT_TRUE(proto::DecodeReady(p, &m, &err));
      proto::EncodeReady(m, &again);
      break;
    }
    case Msg::kWork: {
      std::vector<proto::Assignment> m;
      ASSERT_TRUE(proto::DecodeWork(p, &m, &err));
      proto::EncodeWork(m, &again);
      break;
    }
    case Msg::kColumn: {
      proto::Column m;
      ASSERT_TRUE(proto::DecodeColumn(p, &m, &err));
      proto::EncodeColumn(m, &again);  // CHECKs ids and form factors
      break;
    }
    case Msg::kDivide: {
      std::vector<int32_t> m;
      ASSERT_TRUE(proto::DecodeDivide(p, &m, &err));
      proto::EncodeDivide(m, &again);
      break;
    }
    case Msg::kError: {
      std::string m;
      ASSERT_TRUE(proto::DecodeError(p, &m, &err));
      proto::EncodeError(m, &again);
      break;
    }
    default:
      return;
  }
  EXPECT_EQ(Hex(again.substr(proto::kHeaderSize)), Hex(p)) << proto::MsgName(t);
}

TEST(Protocol, RandomGarbageGivesCleanErrorsOrValidFrames) {
  std::mt19937 rng(20240611);
  const std::vector<std::string> samples = SampleFrames();
  const Msg decoders[] = {Msg::kHello, Msg::kScene,  Msg::kReady, Msg::kWork,
                          Msg::kColumn, Msg::kDivide, Msg::kError};
  auto byte = [&] {
    // Bytes that matter to varints and to the ranges: 0, 1, 0x7f, 0x80, 0xff.
    static const uint8_t special[] = {0, 1, 2, 3, 0x7f, 0x80, 0xff, 0x40, 0x3f};
    return char(rng() % 2 ? uint8_t(rng()) : special[rng() % sizeof special]);
  };
  std::vector<int> accepted(10, 0), refused(10, 0);
  int frames = 0, bad_streams = 0;
  for (int iter = 0; iter < 20000; ++iter) {
    std::string g;
    const int kind = int(rng() % 4);
    if (kind == 0) {  // pure noise
      for (int n = int(rng() % 80); n > 0; --n) g += byte();
    } else {  // a valid payload (sometimes another type's) mutated
      const std::string& f = samples[rng() % samples.size()];
      g = f.substr(proto::kHeaderSize);
      for (int n = int(rng() % 4) + (kind == 3 ? 0 : 1); n > 0 && !g.empty(); --n) {
        size_t at = rng() % g.size();
        switch (rng() % 4) {
          case 0: g[at] = byte(); break;
          case 1: g.insert(g.begin() + long(at), byte()); break;
          case 2: g.erase(at, 1 + rng() % 3); break;
          case 3: g.resize(at); break;
        }
      }
    }
    for (Msg t : decoders) {
      std::string err;
      if (DecodeAny(t, g, &err)) {
        ++accepted[int(t)];
        CheckAccepted(t, g);
      } else {
        ++refused[int(t)];
        ASSERT_FALSE(err.empty()) << proto::MsgName(t) << " " << Hex(g);
        ASSERT_EQ(err.find('\n'), std::string::npos) << err;
      }
    }
    // The same bytes as a stream, after a header that is sometimes valid
    // and sometimes noise, in random pieces.
    std::string stream;
    if (rng() % 2) {
      Msg t = decoders[rng() % 7];
      stream = Header(uint32_t(g.size()), uint8_t(t)) + g;
      if (rng() % 2) stream += samples[rng() % samples.size()];
    } else {
      for (int n = int(rng() % 16); n > 0; --n) stream += byte();
      stream += g;
    }
    FrameReader r;
    size_t steps = 0;
    for (size_t pos = 0; pos < stream.size();) {
      size_t n = std::min<size_t>(1 + rng() % 40, stream.size() - pos);
      r.Append(stream.data() + pos, n);
      pos += n;
      Msg t;
      std::string p, err;
      FrameReader::Result res;
      while ((res = r.Next(&t, &p, &err)) == FrameReader::kFrame) {
        ++frames;
        ASSERT_LE(++steps, stream.size() / proto::kHeaderSize);  // each frame eats >= 8 bytes
        std::string derr;
        if (DecodeAny(t, p, &derr)) CheckAccepted(t, p);
        else ASSERT_FALSE(derr.empty());
      }
      if (res == FrameReader::kBad) {
        ASSERT_FALSE(err.empty());
        ++bad_streams;
        break;
      }
    }
  }
  for (Msg t : decoders) {
    std::printf("[          ] garbage into %-6s: %5d accepted, %5d refused\n", proto::MsgName(t),
                accepted[int(t)], refused[int(t)]);
    EXPECT_GT(refused[int(t)], 1000);
  }
  std::printf("[          ] garbage streams: %d frames read, %d streams refused\n", frames,
              bad_streams);
  EXPECT_GT(accepted[int(Msg::kColumn)], 10);
  EXPECT_GT(accepted[int(Msg::kScene)], 10);
  EXPECT_GT(bad_streams, 1000);
}

}  // namespace
