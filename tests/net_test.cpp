#include "net.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "hemicube.h"
#include "test_util.h"

namespace {

using proto::FrameReader;
using proto::Msg;

// ---- raw writers, written from doc/protocol.txt (not from net.cpp) ------

void WLE(std::string* s, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) s->push_back(char((v >> (8 * i)) & 0xff));
}
void WVar(std::string* s, uint64_t v) {
  do {
    uint8_t b = v & 0x7f;
    v >>= 7;
    s->push_back(char(v ? b | 0x80 : b));
  } while (v);
}
void WF64(std::string* s, double d) {
  uint64_t b;
  std::memcpy(&b, &d, 8);
  WLE(s, b, 8);
}
void WVec(std::string* s, const glm::dvec3& v) {
  WF64(s, v.x);
  WF64(s, v.y);
  WF64(s, v.z);
}
std::string Header(uint32_t len, uint8_t type, uint8_t r0 = 0, uint8_t r1 = 0, uint8_t r2 = 0) {
  std::string h;
  WLE(&h, len, 4);
  h += char(type);
  h += char(r0);
  h += char(r1);
  h += char(r2);
  return h;
}

// The scene payload as the document lays it out, without any validation,
// so that tests can write invalid values.
std::string RawScene(const proto::SceneSetup& m) {
  std::string s;
  s += char(m.rotate);
  WVar(&s, uint32_t(m.resolution));
  WLE(&s, m.seed, 4);
  WVar(&s, uint32_t(m.mesh.elements_per_patch));
  WF64(&s, m.mesh.patch_size);
  WVec(&s, m.scene.lo);
  WVec(&s, m.scene.hi);
  WVar(&s, m.scene.materials.size());
  for (const auto& mt : m.scene.materials) {
    WVec(&s, mt.kd);
    WVec(&s, mt.ke);
  }
  WVar(&s, m.scene.faces.size());
  for (const auto& f : m.scene.faces) {
    WVar(&s, uint32_t(f.material));
    WVar(&s, uint32_t(f.index));
    WVar(&s, f.verts.size());
    WVec(&s, f.normal);
    WF64(&s, f.area);
    for (const auto& v : f.verts) WVec(&s, v);
  }
  return s;
}

uint64_t Bits(double d) {
  uint64_t b;
  std::memcpy(&b, &d, 8);
  return b;
}
uint32_t Bits(float f) {
  uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}
std::string Hex(const std::string& s) {
  std::string h;
  char buf[4];
  for (char c : s) {
    std::snprintf(buf, sizeof buf, "%02x", unsigned(uint8_t(c)));
    h += buf;
  }
  return h;
}

// The one frame in `frame`: its type must be `type`; returns the payload.
std::string PayloadOf(const std::string& frame, Msg type) {
  FrameReader r;
  r.Append(frame.data(), frame.size());
  Msg t = Msg(0);
  std::string p, err;
  EXPECT_EQ(r.Next(&t, &p, &err), FrameReader::kFrame) << err;
  EXPECT_EQ(t, type);
  EXPECT_EQ(r.buffered(), 0u);
  EXPECT_EQ(frame.size(), proto::kHeaderSize + p.size());
  return p;
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
  m.scene.faces.back().normal = -m.scene.faces.back().normal;
  AddFace(&m.scene, {{t, 1.9, t}, {t, 1.9, 1.0 + u}, {1.0 + t, 1.9, t}}, glm::dvec3(0.9),
          glm::dvec3(0));
  m.scene.faces.back().material = 2;  // materials shared by faces
  for (size_t i = 0; i < m.scene.faces.size(); ++i) m.scene.faces[i].index = int(3 * i + 1);
  m.mesh.patch_size = 0.45;
  m.mesh.elements_per_patch = 3;
  m.resolution = 128;
  m.rotate = 0;
  m.seed = 0xdeadbeef;
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

TEST(Net, MsgNames) {
  const char* names[] = {"hello",  "scene",     "ready", "work", "column",
                         "divide", "heartbeat", "error", "bye"};
  for (int t = 1; t <= 9; ++t) EXPECT_STREQ(proto::MsgName(Msg(t)), names[t - 1]);
  EXPECT_STREQ(proto::MsgName(Msg(0)), "unknown");
  EXPECT_STREQ(proto::MsgName(Msg(10)), "unknown");
  EXPECT_STREQ(proto::MsgName(Msg(255)), "unknown");
}

TEST(Net, BuildIdNamesVersionProtocolAndCompiler) {
  const std::string id = proto::BuildId();
  EXPECT_EQ(id.rfind("radiosity ", 0), 0u) << id;
  EXPECT_NE(id.find(" proto 1 "), std::string::npos) << id;
  EXPECT_NE(id.find(__VERSION__), std::string::npos) << id;
  EXPECT_NE(id.find("64-bit le"), std::string::npos) << id;  // what this test runs on
  EXPECT_LE(id.size(), 256u);
  for (char c : id) EXPECT_TRUE(c >= 0x20 && c <= 0x7e) << id;
  EXPECT_EQ(id, proto::BuildId());
  RecordProperty("build_id", id);
}

// ---- round trips --------------------------------------------------------

TEST(Net, HelloRoundTrips) {
  for (const std::string& b : {std::string(), proto::BuildId(), std::string(256, 'x')}) {
    proto::Hello h;
    h.build = b;
    std::string frame;
    proto::EncodeHello(h, &frame);
    const std::string p = PayloadOf(frame, Msg::kHello);
    EXPECT_EQ(p.substr(0, 6), std::string("RADW\x01\x00", 6));  // magic, version
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
  std::string p = "RADW" + std::string("\x01\x00", 2);
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

TEST(Net, HelloOfAnotherVersionStillShowsItsVersion) {
  // Magic and version never move, so a mismatch is reported as such even
  // when the rest is laid out differently.
  proto::Hello h;
  h.version = 7;
  h.build = "radiosity 9.9 proto 7";
  std::string frame;
  proto::EncodeHello(h, &frame);
  std::string p = PayloadOf(frame, Msg::kHello) + "future fields";
  proto::Hello d;
  std::string err;
  ASSERT_TRUE(proto::DecodeHello(p, &d, &err)) << err;
  EXPECT_EQ(d.magic, proto::kMagic);
  EXPECT_EQ(d.version, 7);
  EXPECT_EQ(d.build, h.build);
  // Not ours at all: magic and version come back, the build is empty.
  ASSERT_TRUE(proto::DecodeHello("HTTP/1.1 200 OK\r\n", &d, &err)) << err;
  EXPECT_NE(d.magic, proto::kMagic);
  EXPECT_EQ(d.build, "");
  // Too short for magic and version.
  EXPECT_FALSE(proto::DecodeHello("RADW\x01", &d, &err));
}

TEST(Net, SceneRoundTripsBitForBitAndRebuildsTheSameMesh) {
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
  EXPECT_EQ(Bits(d.mesh.patch_size), Bits(m.mesh.patch_size));
  EXPECT_EQ(d.mesh.elements_per_patch, m.mesh.elements_per_patch);
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
  EXPECT_EQ(proto::MeshHash(rebuilt), proto::MeshHash(original));

  // And with the default mesh options on the plain box of test_util.h.
  proto::SceneSetup box;
  box.scene = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  frame.clear();
  proto::EncodeScene(box, &frame);
  ASSERT_TRUE(proto::DecodeScene(PayloadOf(frame, Msg::kScene), &d, &err)) << err;
  EXPECT_EQ(proto::MeshHash(MakeMesh(d.scene, d.mesh)), proto::MeshHash(MakeMesh(box.scene)));
}

TEST(Net, SceneValuesOutOfRangeAreRefused) {
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
      {"normal inf", [](S* m) { m->scene.faces[1].normal.x = HUGE_VAL; }, false},
      {"normal not unit", [](S* m) { m->scene.faces[1].normal *= 2.0; }, false},
      {"area 0", [](S* m) { m->scene.faces[1].area = 0; }, false},
      {"area nan", [](S* m) { m->scene.faces[1].area = std::nan(""); }, false},
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

TEST(Net, ReadyRoundTrips) {
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

TEST(Net, WorkRoundTrips) {
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
  std::vector<proto::Assignment> d;
  EXPECT_FALSE(proto::DecodeWork(p, &d, &err));
  EXPECT_FALSE(err.empty());
}

TEST(Net, DivideRoundTripsInOrder) {
  for (const auto& v : {std::vector<int32_t>{}, std::vector<int32_t>{0},
                        std::vector<int32_t>{900, 3, 17, 2000000, 4, INT32_MAX}}) {
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
  WVar(&p, 1ull << 31);
  std::vector<int32_t> d;
  EXPECT_FALSE(proto::DecodeDivide(p, &d, &err));
  EXPECT_FALSE(err.empty());
}

TEST(Net, ErrorRoundTripsAsOneLineOfUtf8) {
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

TEST(Net, HeartbeatAndByeAreBareHeaders) {
  std::string hb, bye;
  proto::EncodeHeartbeat(&hb);
  proto::EncodeBye(&bye);
  EXPECT_EQ(Hex(hb), "0000000007000000");
  EXPECT_EQ(Hex(bye), "0000000009000000");
}

// ---- columns ------------------------------------------------------------

// A form factor's 16-bit code (doc/protocol.txt): code = e << 11 | m stands
// for (1 + m/2048) 2^(e-31); code 0 is the escape.
double Code16Value(uint32_t code) {
  return std::ldexp(1.0 + double(code & 0x7ff) / 2048, int(code >> 11) - 31);
}
// The 24-bit code of the escape: float bits >> 7, rounded; and its value.
uint32_t Code24(float f) { return (Bits(f) + 0x40) >> 7; }
float FfValue24(uint32_t q) {
  const uint32_t b = q << 7;
  float f;
  std::memcpy(&f, &b, 4);
  return f;
}
// The 16-bit code nearest to f (no error diffusion), for comparison.
double Nearest16(double f) {
  int ex;
  const double mant = 2 * std::frexp(f, &ex);  // f = mant 2^(ex-1), mant in [1, 2)
  return std::ldexp(std::round(mant * 2048) / 2048, ex - 1);
}

// One form factor's bytes in a raw column: a 16-bit code, or Esc(code24).
uint64_t Esc(uint32_t code24) { return uint64_t(1) << 32 | code24; }

// A column payload as the document lays it out, without any validation:
// patch, k, compute_s, wait_s, n, runs (gap, length - 1), form factors.
std::string RawColumn(uint64_t n, const std::vector<std::pair<uint64_t, uint64_t>>& runs,
                      const std::vector<uint64_t>& codes, uint64_t patch = 1, double secs = 0,
                      double wait = 0) {
  std::string p;
  WVar(&p, patch);
  WVar(&p, 0);
  WF64(&p, secs);
  WF64(&p, wait);
  WVar(&p, n);
  WVar(&p, runs.size());
  for (const auto& r : runs) {
    WVar(&p, r.first);
    WVar(&p, r.second);
  }
  for (uint64_t q : codes) {
    if (q >> 32) {
      WLE(&p, 0, 2);
      WLE(&p, q & 0xffffff, 3);
    } else {
      WLE(&p, q, 2);
    }
  }
  return p;
}

// Encodes and decodes; the ids come back exactly.
proto::Column RoundTrip(const proto::Column& c, std::string* payload = nullptr) {
  std::string frame, err;
  proto::EncodeColumn(c, &frame);
  proto::Column d;
  const std::string p = PayloadOf(frame, Msg::kColumn);
  EXPECT_TRUE(proto::DecodeColumn(p, &d, &err)) << err;
  EXPECT_EQ(d.patch, c.patch);
  EXPECT_EQ(d.k, c.k);
  EXPECT_EQ(Bits(d.compute_s), Bits(c.compute_s));
  EXPECT_EQ(Bits(d.wait_s), Bits(c.wait_s));
  EXPECT_EQ(d.ff.size(), c.ff.size());
  for (size_t i = 0; i < std::min(c.ff.size(), d.ff.size()); ++i)
    if (d.ff[i].elem != c.ff[i].elem) {
      ADD_FAILURE() << "id " << i << ": " << d.ff[i].elem << " for " << c.ff[i].elem;
      break;
    }
  // Decoding and encoding again changes nothing: the coding is canonical.
  std::string again;
  proto::EncodeColumn(d, &again);
  EXPECT_TRUE(again == frame) << "re-encoded differently";
  if (payload) *payload = p;
  return d;
}

// The sum of a column's form factors, in long double.
long double Sum(const std::vector<FormFactor>& ff) {
  long double s = 0;
  for (const FormFactor& f : ff) s += f.f;
  return s;
}

TEST(Net, ColumnRoundTripsWithinTheFormFactorError) {
  std::mt19937 rng(2024);
  proto::Column c;
  c.patch = 123456;
  c.k = 9;
  c.compute_s = 0.03125;
  c.wait_s = 2.75;
  // Ids from 0 to millions in runs and gaps of every size; f from 1e-14 to
  // 1 on a log scale with random mantissas (a third below 2^-31: escaped).
  std::uniform_real_distribution<double> lg(std::log(1e-14), 0.0);
  std::geometric_distribution<int> gap(0.3), len(0.1);
  int32_t id = 0;
  while (c.ff.size() < 200000) {
    for (int n = 1 + len(rng); n > 0; --n) c.ff.push_back({id++, float(std::exp(lg(rng)))});
    id += 1 + gap(rng) + (c.ff.size() % 1000 < 20 ? int(rng() % 100000) : 0);
  }
  ASSERT_GT(c.ff.back().elem, 5000000);
  const proto::Column d = RoundTrip(c);
  ASSERT_EQ(d.ff.size(), c.ff.size());
  double worst = 0, worst_escaped = 0;
  size_t escaped = 0;
  for (size_t i = 0; i < c.ff.size(); ++i) {
    const float f = c.ff[i].f, g = d.ff[i].f;
    ASSERT_TRUE(g > 0 && std::isfinite(g));
    const double rel = std::fabs(double(g) - f) / f;
    EXPECT_LE(rel, proto::kFormFactorError) << f << " -> " << g;
    if (Code24(f) < 0x600020) {  // below code 1 (2^-31 (1 + 2^-11)): escaped, 24 bits kept
      ++escaped;
      EXPECT_EQ(Bits(g), Code24(f) << 7) << f;
      worst_escaped = std::max(worst_escaped, rel);
    } else {  // a 16-bit code: 12 significant bits
      EXPECT_EQ(Bits(g) & 0xfff, 0u) << f;
      worst = std::max(worst, rel);
    }
  }
  EXPECT_GT(escaped, c.ff.size() / 5);
  EXPECT_LE(worst_escaped, 1.0 / (1 << 17));
  EXPECT_GT(worst, proto::kFormFactorRounding);  // diffusion moves values past one rounding
  // The column sum: within one code step of the largest form factor.
  float largest = 0;
  for (const FormFactor& f : c.ff) largest = std::max(largest, f.f);
  const double sum_err = double(std::fabs(Sum(d.ff) - Sum(c.ff)));
  EXPECT_LE(sum_err, proto::kColumnSumError * (1 + proto::kFormFactorError) * largest);
  std::printf("[          ] column round trip: %zu form factors (%zu escaped), max relative "
              "error %.4g (bound 2^-10 = %.4g), escaped %.4g; sum error %.3g of %.6f\n",
              c.ff.size(), escaped, worst, proto::kFormFactorError, worst_escaped, sum_err,
              double(Sum(c.ff)));
  RecordProperty("max_relative_error", std::to_string(worst));

  // The ends of the ranges, each first in its column (nothing carried).
  struct Case {
    float f, want;
  };
  const uint32_t tie_bits = 0x28000040;  // 2^-47 (1 + 2^-17): a 24-bit tie
  float tie;
  std::memcpy(&tie, &tie_bits, 4);
  const Case ends[] = {
      {tie, FfValue24(0x500001)},  // escaped, away from zero
      {1.0f, 1.0f},
      {0.75f, 0.75f},
      {std::nextafter(2.0f, 0.0f), 2.0f},  // its 24-bit code is 2.0's: escaped
      {2.0f - 1.0f / 2048, 2.0f - 1.0f / 2048},  // code 0xffff
      {1.0f + 1.0f / 4096, 1.0f + 1.0f / 2048},  // a tie: up
      {1.0f + 1.0f / 8192, 1.0f},
      {FLT_MIN, FLT_MIN},
      {1e-30f, FfValue24(Code24(1e-30f))},
      {FLT_MAX, FfValue24(0xfeffff)},  // the largest 24-bit code, truncated
  };
  for (const Case& e : ends) {
    proto::Column one;
    one.ff = {{INT32_MAX, e.f}};
    EXPECT_EQ(RoundTrip(one).ff[0].f, e.want) << e.f;
  }

  // An empty column.
  proto::Column e;
  EXPECT_TRUE(RoundTrip(e).ff.empty());
}

TEST(Net, ColumnSixteenBitCodesAreTheDocumentedValues) {
  // One column with every code 1 .. 0xffff, in one run from id 0.
  std::vector<uint64_t> codes;
  for (uint32_t q = 1; q <= 0xffff; ++q) codes.push_back(q);
  const std::string p = RawColumn(codes.size(), {{0, codes.size() - 1}}, codes);
  proto::Column d;
  std::string err;
  ASSERT_TRUE(proto::DecodeColumn(p, &d, &err)) << err;
  ASSERT_EQ(d.ff.size(), codes.size());
  for (uint32_t q = 1; q <= 0xffff; ++q) {
    ASSERT_EQ(d.ff[q - 1].elem, int32_t(q - 1));
    ASSERT_EQ(double(d.ff[q - 1].f), Code16Value(q)) << std::hex << q;
  }
  EXPECT_EQ(double(d.ff.front().f), std::ldexp(1 + 1.0 / 2048, -31));
  EXPECT_EQ(double(d.ff.back().f), 2 - 1.0 / 2048);
  // And the encoder makes exactly these codes from these values.
  proto::Column again = d;
  std::string frame;
  proto::EncodeColumn(again, &frame);
  EXPECT_TRUE(PayloadOf(frame, Msg::kColumn) == p);
}

TEST(Net, ColumnEscapesValuesOutsideTheSixteenBitCodes) {
  proto::Column c;
  c.ff = {{0, 1e-12f}, {1, 1e-30f}, {2, 1.5f}, {3, 3.0f}, {4, FLT_TRUE_MIN}};
  std::string p;
  const proto::Column d = RoundTrip(c, &p);
  const std::string want = RawColumn(5, {{0, 4}},
                                     {Esc(Code24(1e-12f)), Esc(Code24(1e-30f)), 0xfc00,
                                      Esc(Code24(3.0f)), Esc(1)},
                                     0);
  EXPECT_EQ(Hex(p), Hex(want));
  EXPECT_NEAR(d.ff[0].f, 1e-12f, 1e-12 / (1 << 17));
  EXPECT_NEAR(d.ff[1].f, 1e-30f, 1e-30 / (1 << 17));
  EXPECT_EQ(d.ff[2].f, 1.5f);  // in range: a 16-bit code (31 << 11 | 1024), exact
  EXPECT_EQ(d.ff[3].f, 3.0f);
  EXPECT_EQ(d.ff[4].f, FLT_TRUE_MIN * 128);  // the smallest 24-bit code

  // Where the 16-bit codes end: values whose 24-bit code is code 1's or
  // code 0xffff's are sent in 16 bits, the next ones out escaped.
  const float lo = float(Code16Value(1)), hi = float(Code16Value(0xffff));
  EXPECT_EQ(Code24(lo), 0x600020u);
  EXPECT_EQ(Code24(hi), 0x7fffe0u);
  struct Case {
    float f;
    uint64_t code;
  };
  const Case cases[] = {
      {lo, 1},
      {std::nextafter(lo, 0.0f), 1},  // same 24-bit code as lo
      {FfValue24(0x60001f), Esc(0x60001f)},
      {std::ldexp(1.0f, -31), Esc(0x600000)},
      {hi, 0xffff},
      {std::nextafter(hi, 2.0f), 0xffff},
      {FfValue24(0x7fffe1), Esc(0x7fffe1)},
  };
  for (const Case& e : cases) {
    proto::Column one;
    one.ff = {{0, e.f}};
    std::string q;
    RoundTrip(one, &q);
    EXPECT_EQ(Hex(q), Hex(RawColumn(1, {{0, 0}}, {e.code}, 0))) << e.f;
  }
  // An escape may hold only what 16 bits cannot: one coding per value.
  proto::Column got;
  std::string err;
  for (uint32_t q24 : {0x60001fu, 0x7fffe1u, 1u, 0xfeffffu}) {
    EXPECT_TRUE(proto::DecodeColumn(RawColumn(1, {{0, 0}}, {Esc(q24)}), &got, &err)) << err;
    EXPECT_EQ(Bits(got.ff[0].f), q24 << 7);
  }
  for (uint32_t q24 : {0x600020u, 0x7fffe0u, 0x7e0000u, 0u, 0xff0000u, 0xffffffu}) {
    err.clear();
    EXPECT_FALSE(proto::DecodeColumn(RawColumn(1, {{0, 0}}, {Esc(q24)}), &got, &err)) << q24;
    EXPECT_FALSE(err.empty());
  }
}

TEST(Net, ColumnIdsAreMaximalRuns) {
  struct Case {
    std::vector<int32_t> ids;
    std::vector<std::pair<uint64_t, uint64_t>> runs;  // gap, length - 1
  };
  std::vector<int32_t> long_run, every_other, mixed;
  for (int32_t i = 1; i <= 100000; ++i) long_run.push_back(i);
  for (int32_t i = 0; i < 2000; i += 2) every_other.push_back(i);
  std::vector<std::pair<uint64_t, uint64_t>> every_other_runs(1000, {1, 0});
  every_other_runs[0] = {0, 0};
  std::mt19937 rng(5);
  std::vector<std::pair<uint64_t, uint64_t>> mixed_runs;
  for (int64_t next = 0, k = 0; k < 300; ++k) {
    const uint64_t gap = (k == 0 ? 0 : 1) + rng() % (k % 7 == 0 ? 100000 : 20);
    const uint64_t len = 1 + rng() % (k % 5 == 0 ? 3000 : 30);
    for (uint64_t i = 0; i < len; ++i) mixed.push_back(int32_t(next + int64_t(gap + i)));
    mixed_runs.push_back({gap, len - 1});
    next += int64_t(gap + len);
  }
  const Case cases[] = {
      {{}, {}},
      {{0}, {{0, 0}}},
      {{7}, {{7, 0}}},
      {{INT32_MAX}, {{INT32_MAX, 0}}},
      {{0, INT32_MAX}, {{0, 0}, {INT32_MAX - 1, 0}}},
      {{0, 1, 2, 10, INT32_MAX}, {{0, 2}, {7, 0}, {INT32_MAX - 11, 0}}},
      {{5, 6, 7, 300}, {{5, 2}, {292, 0}}},
      {{INT32_MAX - 2, INT32_MAX - 1, INT32_MAX}, {{INT32_MAX - 2, 2}}},
      {long_run, {{1, 99999}}},
      {every_other, every_other_runs},
      {mixed, mixed_runs},
  };
  for (const Case& e : cases) {
    proto::Column c;
    for (int32_t id : e.ids) c.ff.push_back({id, 0.25f});  // code 0xe800
    std::string p;
    RoundTrip(c, &p);
    EXPECT_EQ(Hex(p), Hex(RawColumn(e.ids.size(), e.runs,
                                    std::vector<uint64_t>(e.ids.size(), 0xe800), 0)))
        << e.ids.size() << " ids";
  }
  std::string run_bytes;
  WVar(&run_bytes, mixed_runs.size());
  for (const auto& r : mixed_runs) {
    WVar(&run_bytes, r.first);
    WVar(&run_bytes, r.second);
  }
  std::printf("[          ] %zu ids in %zu runs: %zu bytes (%.3f per id)\n", mixed.size(),
              mixed_runs.size(), run_bytes.size(), double(run_bytes.size()) / double(mixed.size()));
}

TEST(Net, ColumnPayloadsOutOfRangeAreRefused) {
  proto::Column d;
  std::string err;
  ASSERT_TRUE(proto::DecodeColumn(RawColumn(2, {{0, 1}}, {1, 0xffff}), &d, &err)) << err;
  ASSERT_TRUE(proto::DecodeColumn(RawColumn(1, {{INT32_MAX, 0}}, {1}), &d, &err)) << err;
  ASSERT_TRUE(proto::DecodeColumn(RawColumn(3, {{0, 0}, {1, 1}}, {1, 2, 3}), &d, &err)) << err;
  ASSERT_TRUE(proto::DecodeColumn(RawColumn(0, {}, {}), &d, &err)) << err;
  using R = std::vector<std::pair<uint64_t, uint64_t>>;
  const std::string good = RawColumn(2, {{3, 1}}, {1, 2});
  const std::string bad[] = {
      RawColumn(0, {}, {}, 1ull << 31),                // patch > INT32_MAX
      RawColumn(0, {}, {}, 1, -1),                     // compute_s < 0
      RawColumn(0, {}, {}, 1, std::nan("")),           // compute_s NaN
      RawColumn(0, {}, {}, 1, HUGE_VAL),               // compute_s inf
      RawColumn(0, {}, {}, 1, 0, -1e-9),               // wait_s < 0
      RawColumn(0, {}, {}, 1, 0, std::nan("")),        // wait_s NaN
      RawColumn(0, {}, {}, 1, 0, HUGE_VAL),            // wait_s inf
      RawColumn(1, {{1ull << 31, 0}}, {1}),            // first id > INT32_MAX
      RawColumn(2, {{INT32_MAX, 1}}, {1, 1}),          // second id > INT32_MAX
      RawColumn(2, {{0, 0}, {INT32_MAX, 0}}, {1, 1}),  // id 2^31
      RawColumn(1, {{0, 1ull << 31}}, {1}),            // run length - 1 > INT32_MAX
      RawColumn(1, {{0, UINT64_MAX}}, {1}),            // run length 2^64
      RawColumn(2, {{0, 0}, {0, 0}}, {1, 1}),          // gap 0 after a run: not maximal
      RawColumn(3, {{4, 1}, {0, 0}}, {1, 1, 1}),       // the same, longer
      RawColumn(2, {{0, 0}}, {1, 1}),                  // lengths 1 for 2 form factors
      RawColumn(2, {{0, 2}}, {1, 1}),                  // lengths 3 for 2 form factors
      RawColumn(3, {{0, 0}, {1, 0}}, {1, 1, 1}),       // lengths 2 for 3
      RawColumn(2, {}, {1, 1}),                        // no runs for 2 form factors
      RawColumn(1, {{0, 0}, {1, 0}}, {1, 1}),          // more runs than form factors
      RawColumn(0, R{{0, 0}}, {1}),                    // a run in an empty column
      RawColumn(1, {{0, 0}}, {0}),                     // an escape without its 3 bytes
      RawColumn(2, {{0, 1}}, {1}),                     // too few form factors
      RawColumn(1, {{0, 0}}, {1, 1}),                  // too many
      RawColumn(2, {{0, 1}}, {1}) + std::string("\x01", 1),      // 1 of 2 bytes
      RawColumn(1, {{0, 0}}, {}) + std::string("\0\0\x01\x00", 4),  // 4 of 5 bytes
      RawColumn(1, {{0, 0}}, {Esc(0)}),                // f = 0
      RawColumn(1, {{0, 0}}, {Esc(0xff0000)}),         // f = inf
      RawColumn(1, {{0, 0}}, {Esc(0xffffff)}),         // f = NaN
      RawColumn(1, {{0, 0}}, {Esc(0xff0001)}),         // f = NaN
      RawColumn(1, {{0, 0}}, {Esc(0x7e0000)}),         // 0.5 escaped: has a 16-bit code
      std::string("\x80\x00", 2) + good.substr(1),      // overlong patch varint
      good.substr(0, 18) + std::string("\x82\x00", 2) + good.substr(19),  // overlong n
      good.substr(0, 19) + std::string("\x81\x00", 2) + good.substr(20),  // overlong run count
      good.substr(0, 20) + std::string("\x83\x00", 2) + good.substr(21),  // overlong gap
      good.substr(0, 21) + std::string("\x81\x00", 2) + good.substr(22),  // overlong length
  };
  ASSERT_TRUE(proto::DecodeColumn(good, &d, &err)) << err;
  for (const std::string& p : bad) {
    err.clear();
    EXPECT_FALSE(proto::DecodeColumn(p, &d, &err)) << Hex(p);
    EXPECT_FALSE(err.empty()) << Hex(p);
    EXPECT_EQ(err.find('\n'), std::string::npos) << err;
  }
  // The messages name what is wrong.
  auto why = [&](const std::string& p) {
    err.clear();
    EXPECT_FALSE(proto::DecodeColumn(p, &d, &err));
    return err;
  };
  EXPECT_NE(why(RawColumn(2, {{0, 0}, {0, 0}}, {1, 1})).find("maximal"), std::string::npos);
  EXPECT_NE(why(RawColumn(2, {{0, 0}}, {1, 1})).find("runs make 1 ids for 2"), std::string::npos);
  EXPECT_NE(why(RawColumn(2, {{0, 2}}, {1, 1})).find("more than the 2"), std::string::npos);
  EXPECT_NE(why(RawColumn(2, {{INT32_MAX, 1}}, {1, 1})).find("out of range"), std::string::npos);
  EXPECT_NE(why(RawColumn(1, {{0, 0}}, {Esc(0x7e0000)})).find("16-bit"), std::string::npos);
  EXPECT_NE(why(good.substr(0, 20) + std::string("\x83\x00", 2) + good.substr(21))
                .find("shortest"),
            std::string::npos);
  EXPECT_NE(why(good + "x").find("left over"), std::string::npos);
}


TEST(Net, ColumnMutationsGiveCleanErrorsOrCanonicalColumns) {
  // Columns with and without escapes (the decoder's two paths), bytes
  // changed, inserted, removed: a clean error, or a column that is valid
  // and encodes to the same bytes.
  std::mt19937 rng(31337);
  std::vector<std::string> payloads;
  for (bool escapes : {false, true}) {
    proto::Column c;
    int32_t id = 3;
    for (int k = 0; k < 40; ++k) {
      const float f = escapes && k % 7 == 0 ? 1e-11f : float(1e-4 * (1 + k % 5));
      c.ff.push_back({id, f});
      id += 1 + (k % 4 == 0 ? int32_t(rng() % 300) : 0);
    }
    std::string frame;
    proto::EncodeColumn(c, &frame);
    payloads.push_back(PayloadOf(frame, Msg::kColumn));
  }
  int accepted = 0, refused = 0;
  for (int iter = 0; iter < 40000; ++iter) {
    std::string g = payloads[size_t(iter) % 2];
    for (int n = 1 + int(rng() % 3); n > 0 && !g.empty(); --n) {
      const size_t at = 18 + rng() % (g.size() - 18);  // after the times
      switch (rng() % 5) {
        case 0: g[at] = char(rng()); break;
        case 1: g[at] = char(rng() % 2 ? 0 : 0x80 | (rng() & 0x7f)); break;
        case 2: g.insert(g.begin() + long(at), char(rng() % 4)); break;
        case 3: g.erase(at, 1 + rng() % 3); break;
        case 4: g.resize(at); break;
      }
      if (g.size() <= 18) break;
    }
    proto::Column d;
    std::string err;
    if (!proto::DecodeColumn(g.data(), g.size(), &d, &err)) {
      ++refused;
      ASSERT_FALSE(err.empty()) << Hex(g);
      ASSERT_EQ(err.find('\n'), std::string::npos) << err;
      continue;
    }
    ++accepted;
    for (size_t i = 0; i < d.ff.size(); ++i) {
      ASSERT_TRUE(d.ff[i].f > 0 && std::isfinite(d.ff[i].f)) << Hex(g);
      ASSERT_TRUE(i == 0 || d.ff[i].elem > d.ff[i - 1].elem) << Hex(g);
    }
    std::string again;
    proto::EncodeColumn(d, &again);
    ASSERT_EQ(Hex(again.substr(proto::kHeaderSize)), Hex(g));
  }
  std::printf("[          ] mutated columns: %d accepted, %d refused\n", accepted, refused);
  EXPECT_GT(accepted, 1000);
  EXPECT_GT(refused, 10000);
}

TEST(NetDeathTest, EncodeColumnChecksItsInput) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  auto enc = [](std::vector<FormFactor> ff, double secs = 0, double wait = 0) {
    proto::Column c;
    c.ff = std::move(ff);
    c.compute_s = secs;
    c.wait_s = wait;
    std::string out;
    proto::EncodeColumn(c, &out);
  };
  EXPECT_DEATH(enc({{1, 0.0f}}), "CHECK");
  EXPECT_DEATH(enc({{1, -0.5f}}), "CHECK");
  EXPECT_DEATH(enc({{1, std::nanf("")}}), "CHECK");
  EXPECT_DEATH(enc({{1, HUGE_VALF}}), "CHECK");
  EXPECT_DEATH(enc({{3, 0.1f}, {3, 0.1f}}), "CHECK");
  EXPECT_DEATH(enc({{3, 0.1f}, {2, 0.1f}}), "CHECK");
  EXPECT_DEATH(enc({{-1, 0.1f}}), "CHECK");
  EXPECT_DEATH(enc({{1, 0.1f}}, -1.0), "CHECK");
  EXPECT_DEATH(enc({{1, 0.1f}}, std::nan("")), "CHECK");
  EXPECT_DEATH(enc({{1, 0.1f}}, 0, -1.0), "CHECK");
  EXPECT_DEATH(enc({{1, 0.1f}}, 0, HUGE_VAL), "CHECK");
}

// The worked example of doc/protocol.txt, byte for byte.
TEST(Net, ColumnFrameIsTheDocumentedExample) {
  proto::Column c;
  c.patch = 3;
  c.k = 1;
  c.compute_s = 0.25;
  c.wait_s = 0.5;
  c.ff = {{5, 0.25f}, {6, 0.3f}, {7, 0.3f}, {300, 1e-12f}};
  std::string frame;
  proto::EncodeColumn(c, &frame);
  EXPECT_EQ(Hex(frame),
            "2400000005000000"  // header: 36 payload bytes, type 5 (column)
            "0301"              // patch 3, k 1
            "000000000000d03f"  // compute_s 0.25
            "000000000000e03f"  // wait_s 0.5
            "04"                // 4 form factors
            "02"                // in 2 runs:
            "0502"              //   ids 5, 6, 7: gap 5 from 0, length 3
            "a40200"            //   id 300: gap 292 (a4 02) from 8, length 1
            "00e8"              // 0.25 = 2^-2: e 29, m 0, code 0xe800
            "9ae9"              // 0.3f ~ 1.2 2^-2: m 409.6 -> 410, code 0xe99a
            "99e9"              // 0.3f - 4.88e-5 carried: m 409.2 -> 409, code 0xe999
            "00007a1957");      // 1e-12 < 2^-31: escape, 24-bit code 0x57197a
  proto::Column d;
  std::string err;
  ASSERT_TRUE(proto::DecodeColumn(PayloadOf(frame, Msg::kColumn), &d, &err)) << err;
  ASSERT_EQ(d.ff.size(), 4u);
  EXPECT_EQ(d.ff[1].f, 0.300048828125f);
  EXPECT_EQ(d.ff[2].f, 0.2999267578125f);
  EXPECT_EQ(d.ff[1].f + d.ff[2].f, 0.5999755859375f);  // 2 x 0.3f - 2.44e-5
  EXPECT_EQ(double(d.ff[3].f), double(FfValue24(0x57197a)));
  EXPECT_NEAR(d.ff[3].f, 1.0000056e-12, 1e-19);
}

// Random columns shaped to stress the diffusion: smooth stretches, jumps
// of many binades both ways, lone large values among small ones.
TEST(Net, ColumnSumIsKeptByErrorDiffusion) {
  // 0.3f is coded 4.88e-5 high (code 0xe99a); the form factors of smaller
  // exponents come after it, whatever their ids, and the first takes what
  // it can of the residual: 2^-10 of itself, the clamp.
  for (const auto& ff : {std::vector<FormFactor>{{0, 0.3f}, {1, 1e-6f}, {2, 1e-6f}},
                         std::vector<FormFactor>{{0, 1e-6f}, {1, 1e-6f}, {2, 0.3f}}}) {
    proto::Column c;
    c.ff = ff;
    const proto::Column d = RoundTrip(c);
    const size_t big = ff[0].f == 0.3f ? 0 : 2, small = 1;
    EXPECT_EQ(d.ff[big].f, 0.300048828125f);
    const double rel = (double(d.ff[small].f) - 1e-6f) / 1e-6f;
    EXPECT_LE(rel, 0);
    EXPECT_GE(rel, -proto::kFormFactorError);
    EXPECT_LT(rel, -0.5 * proto::kFormFactorError);  // within a code step of the clamp
    // What is left: 0.3f's residual, 4.8816e-5, less about 2 x 2^-10 x 1e-6.
    EXPECT_NEAR(double(Sum(d.ff) - Sum(c.ff)), 4.8816e-5 - 1.4e-9, 0.4e-9);
  }

  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(0, 1);
  double worst_ratio = 0, worst_rel = 0;
  for (int col = 0; col < 300; ++col) {
    proto::Column c;
    double level = std::exp(-20 * u(rng));
    const int n = 1 + int(rng() % 3000);
    for (int i = 0; i < n; ++i) {
      if (rng() % 50 == 0) level = std::exp(-20 * u(rng));  // a jump
      const double f = level * (1 + 0.3 * u(rng)) * (rng() % 200 == 0 ? 1000 : 1);
      c.ff.push_back({3 * i, float(std::min(f, 1.0))});
    }
    const proto::Column d = RoundTrip(c);
    float largest = 0;
    for (size_t i = 0; i < c.ff.size(); ++i) {
      largest = std::max(largest, c.ff[i].f);
      ASSERT_LE(std::fabs(double(d.ff[i].f) - c.ff[i].f), proto::kFormFactorError * c.ff[i].f);
    }
    const long double sum = Sum(c.ff);
    const double err = double(std::fabs(Sum(d.ff) - sum));
    const double bound = proto::kColumnSumError * (1 + proto::kFormFactorError) * largest;
    ASSERT_LE(err, bound) << col;
    worst_ratio = std::max(worst_ratio, err / bound);
    worst_rel = std::max(worst_rel, err / double(sum));
  }
  std::printf("[          ] random columns: sum error at most %.3g of the bound "
              "(2^-11 of the largest form factor), %.3g of the sum\n",
              worst_ratio, worst_rel);
}

// Real columns: the hemicube of the shipped room from patches all over it.
TEST(Net, RealColumnsCostLessThanFiveBytesPerFormFactor) {
  std::string path = __FILE__;
  path = path.substr(0, path.find_last_of('/') + 1) + "../scenes/room.obj";
  struct stat st;
  if (stat(path.c_str(), &st) != 0) path = "scenes/room.obj";
  Scene scene;
  std::string err;
  std::vector<std::string> warnings;
  ASSERT_TRUE(LoadScene(path, &scene, &err, &warnings)) << err;
  Mesh mesh;
  ASSERT_TRUE(BuildMesh(scene, MeshOptions(), &mesh, &err)) << err;
  Hemicube h(256);
  const int n = int(mesh.patches.size());
  std::vector<int> shooters;
  for (int i = 0; i < 40; ++i) shooters.push_back(i * n / 40);
  shooters.push_back(n - 1);
  size_t frames = 0, payload_bytes = 0, count = 0, escaped = 0;
  double worst = 0, mean = 0, worst_sum = 0, worst_sum_nearest = 0;
  std::vector<std::string> payloads;
  for (int p : shooters) {
    proto::Column c;
    c.patch = p;
    c.compute_s = 0.004;
    c.wait_s = 0.0001;
    h.Column(mesh, p, 0.0, &c.ff);
    ASSERT_FALSE(c.ff.empty());
    std::string frame;
    proto::EncodeColumn(c, &frame);
    payloads.push_back(PayloadOf(frame, Msg::kColumn));
    proto::Column d;
    ASSERT_TRUE(proto::DecodeColumn(payloads.back(), &d, &err)) << err;
    ASSERT_EQ(d.ff.size(), c.ff.size());
    long double nearest = 0;
    for (size_t i = 0; i < c.ff.size(); ++i) {
      ASSERT_EQ(d.ff[i].elem, c.ff[i].elem);
      const double rel = std::fabs(double(d.ff[i].f) - c.ff[i].f) / c.ff[i].f;
      worst = std::max(worst, rel);
      mean += rel;
      escaped += Code24(c.ff[i].f) < 0x600020;
      nearest += Nearest16(c.ff[i].f);
    }
    const long double sum = Sum(c.ff);
    worst_sum = std::max(worst_sum, double(std::fabs(Sum(d.ff) - sum) / sum));
    worst_sum_nearest = std::max(worst_sum_nearest, double(std::fabs(nearest - sum) / sum));
    frames += frame.size();
    payload_bytes += frame.size() - proto::kHeaderSize;
    count += c.ff.size();
  }
  mean /= double(count);
  const double per_ff = double(frames) / double(count);
  std::printf("[          ] room, R = 256: %zu columns, %zu form factors (%.0f per column, %zu "
              "escaped), %.3f bytes per form factor (whole frames), %.3f (payloads); raw i32 + "
              "f32 would be 8\n",
              shooters.size(), count, double(count) / double(shooters.size()), escaped, per_ff,
              double(payload_bytes) / double(count));
  std::printf("[          ] room: relative error per form factor max %.4g (2^%.2f), mean %.4g "
              "(2^%.2f); column sum relative error max %.3g (nearest code without diffusion: "
              "%.3g)\n",
              worst, std::log2(worst), mean, std::log2(mean), worst_sum, worst_sum_nearest);

  // Decode time, as the master pays it: 20000 decodes of these payloads in
  // 5 rounds; the best round is the least disturbed by the machine.
  size_t decoded = 0;
  double best_round = HUGE_VAL, total_ns = 0;
  for (int round = 0; round < 5; ++round) {
    size_t round_ff = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < 4000; ++i) {
      proto::Column d;
      if (!proto::DecodeColumn(payloads[size_t(i) % payloads.size()], &d, &err)) FAIL() << err;
      round_ff += d.ff.size();
    }
    const double ns =
        std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
    best_round = std::min(best_round, ns / double(round_ff));
    total_ns += ns;
    decoded += round_ff;
  }
  std::printf("[          ] room: decoding takes %.3f ns per form factor (%.3f in the best of 5 "
              "rounds; %.2f us per column of %.0f)\n",
              total_ns / double(decoded), best_round,
              total_ns / double(decoded) * double(count) / double(shooters.size()) / 1000,
              double(count) / double(shooters.size()));
  RecordProperty("bytes_per_form_factor", std::to_string(per_ff));
  RecordProperty("decode_ns_per_form_factor", std::to_string(total_ns / double(decoded)));
  EXPECT_LT(per_ff, 2.5);
  EXPECT_LE(worst, proto::kFormFactorError);
  EXPECT_LT(mean, 1.5 * proto::kFormFactorRounding);
  EXPECT_LE(worst_sum, 1e-6);
}

// ---- malformed input ----------------------------------------------------

TEST(Net, EveryTruncatedPayloadFailsWithAMessage) {
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

TEST(Net, ExtraBytesFail) {
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

TEST(Net, HugeCountsFailFastWithoutAllocating) {
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
    std::string mats = sc.substr(0, 64);  // fixed fields, then the material count
    WVar(&mats, n);
    EXPECT_FALSE(proto::DecodeScene(mats, &d, &err));
    EXPECT_NE(err.find("material count"), std::string::npos) << err;
    // A face claiming n vertices.
    s = TestSetup();
    s.scene.faces.resize(1);
    std::string fv = RawScene(s).substr(0, RawScene(s).size() - 32 - 4 * 24);
    fv.resize(fv.size() - 1);  // its vertex count (4, one byte)
    WVar(&fv, n);
    fv += std::string(200, '\0');
    EXPECT_FALSE(proto::DecodeScene(fv, &d, &err));
    EXPECT_NE(err.find("vertex count"), std::string::npos) << err;
  }
}

TEST(Net, BadHeadersFail) {
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

TEST(Net, FrameReaderGivesTheSameFramesHoweverTheBytesArrive) {
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

TEST(Net, FrameReaderKeepsUpWithALongStream) {
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

TEST(Net, RandomGarbageGivesCleanErrorsOrValidFrames) {
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

// ---- mesh hash -------------------------------------------------------------

TEST(Net, MeshHashSeesGeometryAndHierarchy) {
  const Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  const Mesh a = MakeMesh(s);
  const uint64_t h = proto::MeshHash(a);
  EXPECT_EQ(proto::MeshHash(MakeMesh(s)), h);
  MeshOptions o;
  o.elements_per_patch = 3;
  EXPECT_NE(proto::MeshHash(MakeMesh(s, o)), h);
  Mesh b = a;
  b.verts[17].y = std::nextafter(b.verts[17].y, 2.0);  // one bit of one coordinate
  EXPECT_NE(proto::MeshHash(b), h);
  b = a;
  std::swap(b.elems[3].v[0], b.elems[3].v[1]);
  EXPECT_NE(proto::MeshHash(b), h);
  b = a;
  b.elems[5].first_child = int(b.elems.size());  // as if divided
  EXPECT_NE(proto::MeshHash(b), h);
  b = a;
  b.elems.push_back(b.elems.back());
  EXPECT_NE(proto::MeshHash(b), h);
  Scene moved = s;
  for (auto& f : moved.faces)
    for (auto& v : f.verts) v.x += 1;
  moved.lo.x += 1;
  moved.hi.x += 1;
  EXPECT_NE(proto::MeshHash(MakeMesh(moved)), h);
}

}  // namespace
