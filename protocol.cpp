// The wire protocol: framing and message codecs. doc/protocol.txt is the
// byte-by-byte description; keep the two in step.
//
// Encoders write what they are given and CHECK the invariants the decoder
// would reject (a master or worker that sends such a frame has a bug).
// Decoders trust nothing: every count is checked against the bytes left
// before anything is allocated, every value against its range, and the
// payload must be used up exactly.
#include "protocol.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "check.h"
#include "coding.h"
#include "ffcodec.h"
#include "groups.h"
#include "hash.h"

namespace proto {
namespace {

// Largest payload of each type, checked by FrameReader as soon as the
// header is in (before buffering the payload). 0 for unknown types.
constexpr uint32_t kMaxErrorText = 4096;
// Hello is read leniently when magic or version differ (see DecodeHello),
// so leave room for a longer hello of a later version.
constexpr uint32_t kMaxHelloFrame = 4096;

bool KnownType(uint8_t t) { return t >= uint8_t(Msg::kHello) && t <= uint8_t(Msg::kBye); }

uint32_t MaxPayload(Msg m) {
  switch (m) {
    case Msg::kHello: return kMaxHelloFrame;
    case Msg::kReady: return 16;
    case Msg::kHeartbeat:
    case Msg::kBye: return 0;
    case Msg::kError: return 2 + kMaxErrorText;  // varint(4096) is 2 bytes
    case Msg::kScene:
    case Msg::kWork:
    case Msg::kColumn:
    case Msg::kDivide: return kMaxFrame;
  }
  return 0;
}

bool Printable(const std::string& s) {
  for (char c : s)
    if (uint8_t(c) < 0x20 || uint8_t(c) > 0x7e) return false;
  return true;
}

// Length of the well-formed UTF-8 sequence at s[i] (no overlongs, no
// surrogates, <= U+10FFFF), or 0.
size_t Utf8Len(const std::string& s, size_t i) {
  const uint8_t b0 = uint8_t(s[i]);
  if (b0 < 0x80) return 1;
  size_t n;
  uint32_t cp, min;
  if ((b0 & 0xe0) == 0xc0) n = 2, cp = b0 & 0x1f, min = 0x80;
  else if ((b0 & 0xf0) == 0xe0) n = 3, cp = b0 & 0x0f, min = 0x800;
  else if ((b0 & 0xf8) == 0xf0) n = 4, cp = b0 & 0x07, min = 0x10000;
  else return 0;
  if (i + n > s.size()) return 0;
  for (size_t k = 1; k < n; ++k) {
    const uint8_t b = uint8_t(s[i + k]);
    if ((b & 0xc0) != 0x80) return 0;
    cp = cp << 6 | (b & 0x3f);
  }
  if (cp < min || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return 0;
  return n;
}

bool Control(char c) { return uint8_t(c) < 0x20 || uint8_t(c) == 0x7f; }

// A point's hash, of its bits.
uint64_t PointHash(const glm::dvec3& p) {
  uint64_t b[3];
  std::memcpy(b, &p, sizeof b);
  return SplitMix64(b[0] ^ SplitMix64(b[1] ^ SplitMix64(b[2])));
}

// The scene frame's vertex table as the encoder makes it: each point once,
// by its bits (so -0.0 and 0.0 stay apart and every vertex comes back bit
// for bit), numbered in the order of first use. Open addressing, at most
// half full; a slot holds the top half of the point's hash beside its
// number, so that a probe compares points only when the hashes agree (at
// 10^6 faces the table is far larger than the caches: one miss per
// look-up, not two).
class VertexTable {
 public:
  explicit VertexTable(size_t expect) {
    points_.reserve(expect);
    Resize(expect);
  }
  // p's number; a new point is added at the end (*added true).
  uint32_t Insert(const glm::dvec3& p, bool* added) {
    if (2 * (points_.size() + 1) > slots_.size()) Resize(slots_.size());
    const uint64_t h = PointHash(p), tag = h & ~uint64_t(0xffffffff);
    for (size_t i = h & (slots_.size() - 1);; i = (i + 1) & (slots_.size() - 1)) {
      const uint64_t slot = slots_[i];
      if (slot == kEmpty) {
        slots_[i] = tag | points_.size();
        points_.push_back(p);
        *added = true;
        return uint32_t(points_.size() - 1);
      }
      if ((slot & ~uint64_t(0xffffffff)) == tag &&
          std::memcmp(&points_[uint32_t(slot)], &p, sizeof p) == 0) {
        *added = false;
        return uint32_t(slot);
      }
    }
  }
  const std::vector<glm::dvec3>& points() const { return points_; }

 private:
  static constexpr uint64_t kEmpty = UINT64_MAX;  // no point has number 2^32-1
  void Resize(size_t want) {
    size_t n = 16;
    while (n < 2 * want) n *= 2;
    slots_.assign(n, kEmpty);
    for (size_t k = 0; k < points_.size(); ++k) {
      const uint64_t h = PointHash(points_[k]);
      size_t i = h & (n - 1);
      while (slots_[i] != kEmpty) i = (i + 1) & (n - 1);
      slots_[i] = (h & ~uint64_t(0xffffffff)) | k;
    }
  }
  std::vector<glm::dvec3> points_;
  std::vector<uint64_t> slots_;
};

// A face's index as the difference from the one before, less 1 (0 for
// consecutive faces), zigzag-coded: 0, -1, 1, -2 ... as 0, 1, 2, 3 ...
uint64_t ZigZag(int64_t v) { return v < 0 ? (uint64_t(-(v + 1)) << 1) | 1 : uint64_t(v) << 1; }
int64_t UnZigZag(uint64_t z) { return z & 1 ? -int64_t(z >> 1) - 1 : int64_t(z >> 1); }

// A face's or a group's normal: the hemicube's frame is built on it as
// unit (within 1e-6, far above rounding, far below a wrong normal).
bool UnitNormal(const glm::dvec3& n) {
  const double len = glm::length(n);
  return std::isfinite(len) && std::fabs(len - 1) <= 1e-6;
}

// The checks DecodeScene makes on values; EncodeScene CHECKs them too.
bool ValidSetup(const SceneSetup& m, std::string* err) {
  auto fail = [&](const std::string& what) {
    *err = what;
    return false;
  };
  if (m.resolution < 8 || m.resolution > Hemicube::kMaxResolution || m.resolution % 2 != 0)
    return fail("resolution " + std::to_string(m.resolution) + " is not an even number in 8.." +
                std::to_string(Hemicube::kMaxResolution));
  if (m.rotate > 1) return fail("rotate " + std::to_string(m.rotate) + " is not 0 or 1");
  if (m.mesh.elements_per_patch < 1 || m.mesh.elements_per_patch > 64)
    return fail("elements per patch " + std::to_string(m.mesh.elements_per_patch) +
                " is not in 1..64");
  if (!std::isfinite(m.mesh.patch_size) || m.mesh.patch_size < 0)
    return fail("patch size is not finite and >= 0");
  if (!(m.heartbeat_s > 0 && m.heartbeat_s <= kMaxHeartbeat))
    return fail("heartbeat period is not in (0, " + std::to_string(int(kMaxHeartbeat)) + "] s");
  const Scene& s = m.scene;
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(s.lo[k]) || !std::isfinite(s.hi[k]) || !(s.lo[k] <= s.hi[k]))
      return fail("bounding box is not finite with lo <= hi");
  if (s.materials.empty()) return fail("no materials (the default material is missing)");
  if (s.materials.size() > size_t(INT32_MAX) || s.faces.size() > size_t(INT32_MAX))
    return fail("too many materials or faces");
  for (size_t i = 0; i < s.materials.size(); ++i) {
    const Material& mt = s.materials[i];
    for (int k = 0; k < 3; ++k) {
      if (!(mt.kd[k] >= 0 && mt.kd[k] <= 1))
        return fail("material " + std::to_string(i) + ": Kd is not in [0,1]");
      if (!(mt.ke[k] >= 0 && std::isfinite(mt.ke[k])))
        return fail("material " + std::to_string(i) + ": Ke is not finite and >= 0");
    }
  }
  for (size_t i = 0; i < s.faces.size(); ++i) {
    const Face& f = s.faces[i];
    const std::string at = "face " + std::to_string(i) + ": ";
    if (f.material < 0 || size_t(f.material) >= s.materials.size())
      return fail(at + "material " + std::to_string(f.material) + " does not exist (" +
                  std::to_string(s.materials.size()) + " materials)");
    if (f.index < 0) return fail(at + "negative index");
    if (f.verts.size() < 3)
      return fail(at + std::to_string(f.verts.size()) + " vertices (at least 3)");
    if (f.verts.size() > size_t(INT32_MAX)) return fail(at + "too many vertices");
    for (const auto& v : f.verts)
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        return fail(at + "a vertex is not finite");
    if (!(f.area > 0) || !std::isfinite(f.area)) return fail(at + "area is not finite and > 0");
    if (!UnitNormal(f.normal)) return fail(at + "normal is not of unit length");
  }
  return true;
}

}  // namespace

// Writes a header with length 0 and returns where it starts.
size_t BeginFrame(Msg type, std::string* out) {
  size_t start = out->size();
  PutFixed32(out, 0);
  PutU8(out, uint8_t(type));
  PutFixed(out, 0, 3);
  return start;
}

// Fills in the payload length of the frame that starts at `start`.
void EndFrame(size_t start, std::string* out) {
  uint64_t len = out->size() - start - kHeaderSize;
  CHECK(len <= 0xffffffffu);
  EncodeFixed32(&(*out)[start], uint32_t(len));
}

const char* MsgName(Msg m) {
  switch (m) {
    case Msg::kHello: return "hello";
    case Msg::kScene: return "scene";
    case Msg::kReady: return "ready";
    case Msg::kWork: return "work";
    case Msg::kColumn: return "column";
    case Msg::kDivide: return "divide";
    case Msg::kHeartbeat: return "heartbeat";
    case Msg::kError: return "error";
    case Msg::kBye: return "bye";
  }
  return "unknown";
}

// ---- encoders ---------------------------------------------------------

void EncodeHello(const Hello& m, std::string* out) {
  CHECK(m.build.size() <= kMaxBuild && Printable(m.build));
  size_t start = BeginFrame(Msg::kHello, out);
  PutFixed32(out, m.magic);
  PutFixed(out, m.version, 2);
  PutVarint(out, m.build.size());
  out->append(m.build);
  EndFrame(start, out);
}

void PutBoxAndMaterials(const Scene& scene, std::string* out) {
  PutVec(out, scene.lo);
  PutVec(out, scene.hi);
  PutVarint(out, scene.materials.size());
  for (const Material& mt : scene.materials) {
    PutVec(out, mt.kd);
    PutVec(out, mt.ke);
  }
}

// The scene part of the scene frame: bounding box, materials, the vertex
// table in order of first use, faces as material, index and corners.
void PutGeometry(const Scene& scene, std::string* out) {
  PutBoxAndMaterials(scene, out);
  size_t corners = 0;
  for (const Face& f : scene.faces) corners += f.verts.size();
  VertexTable table(corners / 2);
  std::vector<uint32_t> ids;
  ids.reserve(corners);
  bool added;
  for (const Face& f : scene.faces)
    for (const glm::dvec3& v : f.verts) ids.push_back(table.Insert(v, &added));
  out->reserve(out->size() + 24 * table.points().size() + 3 * scene.faces.size() + 2 * corners);
  PutVarint(out, table.points().size());
  for (const glm::dvec3& v : table.points()) PutVec(out, v);
  PutVarint(out, scene.faces.size());
  int64_t previous = -1;
  uint32_t fresh = 0;  // vertices used so far: the next new one's number
  const uint32_t* id = ids.data();
  for (const Face& f : scene.faces) {
    PutVarint(out, uint32_t(f.material));
    PutVarint(out, ZigZag(int64_t(f.index) - previous - 1));
    previous = f.index;
    PutVarint(out, f.verts.size());
    for (size_t k = 0; k < f.verts.size(); ++k, ++id) {
      // 0: the next vertex of the table; b: the one b places before it.
      PutVarint(out, *id == fresh ? 0 : fresh - *id);
      if (*id == fresh) ++fresh;
    }
  }
}

void EncodeScene(const SceneSetup& m, std::string* out) {
  std::string err;
  if (!ValidSetup(m, &err)) {
    std::fprintf(stderr, "radiosity: internal error: EncodeScene: %s\n", err.c_str());
    CHECK(!"a valid scene setup");
  }
  // Normals and areas are not sent: the worker's FacePlane must find what
  // the master's faces hold, or it builds another mesh.
  Face g;
  for (const Face& f : m.scene.faces) {
    g.verts.assign(f.verts.begin(), f.verts.end());
    FacePlane(&g);
    CHECK(std::memcmp(&g.normal, &f.normal, sizeof g.normal) == 0 &&
          std::memcmp(&g.area, &f.area, sizeof g.area) == 0);
  }
  // A scene past kMaxFrame is still encoded (with its true length, below
  // 4 GiB): the receiver refuses it as too long. Callers that want a
  // clear message check the frame's size against kMaxFrame first.
  size_t start = BeginFrame(Msg::kScene, out);
  PutU8(out, m.rotate);
  PutVarint(out, uint32_t(m.resolution));
  PutFixed32(out, m.seed);
  PutVarint(out, uint32_t(m.mesh.elements_per_patch));
  PutF64(out, m.mesh.patch_size);
  PutU8(out, m.mesh.join);
  PutF64(out, m.heartbeat_s);
  PutGeometry(m.scene, out);
  EndFrame(start, out);
}

void EncodeReady(const Ready& m, std::string* out) {
  size_t start = BeginFrame(Msg::kReady, out);
  PutFixed64(out, m.elements);
  PutFixed64(out, m.mesh_hash);
  EndFrame(start, out);
}

void EncodeWork(const std::vector<Assignment>& m, std::string* out) {
  size_t start = BeginFrame(Msg::kWork, out);
  PutVarint(out, m.size());
  for (const Assignment& a : m) {
    CHECK(a.patch >= 0 && a.k >= 0);
    PutVarint(out, uint32_t(a.patch));
    PutVarint(out, uint32_t(a.k));
    const std::vector<int>& members = a.group.members;
    PutVarint(out, members.size());
    if (members.empty()) continue;
    CHECK(members.size() >= 2 && members.size() <= size_t(kMaxGroup) && members[0] == a.patch);
    for (size_t i = 1; i < members.size(); ++i) {
      CHECK(members[i] > members[i - 1]);
      PutVarint(out, uint32_t(members[i] - members[i - 1]));
    }
    CHECK(UnitNormal(a.group.normal));
    PutVec(out, a.group.center);
    PutVec(out, a.group.normal);
  }
  EndFrame(start, out);
}

namespace {
// A column frame's fields before its form factors; returns BeginFrame's.
size_t BeginColumn(const Column& m, std::string* out) {
  CHECK(m.patch >= 0 && m.k >= 0);
  CHECK(std::isfinite(m.compute_s) && m.compute_s >= 0);
  CHECK(std::isfinite(m.wait_s) && m.wait_s >= 0);
  size_t start = BeginFrame(Msg::kColumn, out);
  PutVarint(out, uint32_t(m.patch));
  PutVarint(out, uint32_t(m.k));
  PutF64(out, m.compute_s);
  PutF64(out, m.wait_s);
  return start;
}
}  // namespace

void EncodeColumn(const Column& m, std::string* out) {
  const size_t start = BeginColumn(m, out);
  PutFormFactors(m.ff, out);
  EndFrame(start, out);
}

void EncodeColumn(const Column& m, std::string_view coded_ff, std::string* out) {
  const size_t start = BeginColumn(m, out);
  out->append(coded_ff);
  EndFrame(start, out);
}

void EncodeDivide(const std::vector<int32_t>& elems, std::string* out) {
  size_t start = BeginFrame(Msg::kDivide, out);
  PutVarint(out, elems.size());
  // An edit e >= 0 divides element e, ~p splits patch p: 2e and 2p + 1.
  for (int32_t e : elems) PutVarint(out, e >= 0 ? 2 * uint64_t(e) : 2 * uint64_t(~e) + 1);
  EndFrame(start, out);
}

void EncodeHeartbeat(std::string* out) { EndFrame(BeginFrame(Msg::kHeartbeat, out), out); }

void EncodeBye(std::string* out) { EndFrame(BeginFrame(Msg::kBye, out), out); }

void EncodeError(const std::string& text, std::string* out) {
  // Made one line of valid UTF-8 of at most kMaxErrorText bytes: control
  // characters become spaces, bytes that are not UTF-8 become '?', and the
  // text is cut at a character boundary.
  std::string t;
  for (size_t i = 0; i < text.size();) {
    size_t n = Utf8Len(text, i);
    if (n == 0) {
      if (t.size() + 1 > kMaxErrorText) break;
      t.push_back('?');
      ++i;
      continue;
    }
    if (t.size() + n > kMaxErrorText) break;
    if (n == 1 && Control(text[i])) t.push_back(' ');
    else t.append(text, i, n);
    i += n;
  }
  size_t start = BeginFrame(Msg::kError, out);
  PutVarint(out, t.size());
  out->append(t);
  EndFrame(start, out);
}

// ---- decoders ---------------------------------------------------------

bool DecodeHello(std::string_view payload, Hello* m, std::string* err) {
  Reader r(payload, err);
  uint64_t magic, version;
  if (!r.Fixed(4, &magic, "magic") || !r.Fixed(2, &version, "version")) return false;
  m->magic = uint32_t(magic);
  m->version = uint16_t(version);
  m->build.clear();
  if (m->magic != kMagic || m->version != kVersion) {
    // Another protocol (or not ours at all): what follows may be laid out
    // differently, so take the build string only if it reads as one and
    // let the caller report the mismatch.
    std::string ignored;
    Reader rest(payload, &ignored);
    rest.Seek(r.pos());
    uint64_t n;
    std::string b;
    if (rest.Varint(kMaxBuild, &n, "") && rest.Bytes(size_t(n), &b, "") && Printable(b))
      m->build = b;
    return true;
  }
  uint64_t n;
  if (!r.Varint(kMaxBuild, &n, "build string length")) return false;
  if (!r.Bytes(size_t(n), &m->build, "build string")) return false;
  if (!Printable(m->build)) return r.Fail("build string is not printable ASCII");
  return r.End("hello");
}

bool DecodeScene(std::string_view payload, SceneSetup* m, std::string* err) {
  Reader r(payload, err);
  SceneSetup s;
  s.scene.objects = {"default"};
  uint64_t v;
  if (!r.U8(&s.rotate, "rotate")) return false;
  if (!r.Varint(uint64_t(Hemicube::kMaxResolution), &v, "resolution")) return false;
  s.resolution = int32_t(v);
  if (!r.Fixed(4, &v, "seed")) return false;
  s.seed = uint32_t(v);
  if (!r.Varint(64, &v, "elements per patch")) return false;
  s.mesh.elements_per_patch = int(v);
  if (!r.Finite(&s.mesh.patch_size, "patch size")) return false;
  uint8_t join;
  if (!r.U8(&join, "join")) return false;
  if (join > 1) return r.Fail("join " + std::to_string(join) + " is not 0 or 1");
  s.mesh.join = join;
  s.mesh.groups = false;  // the master's come with the work
  if (!r.Finite(&s.heartbeat_s, "heartbeat period")) return false;
  if (!r.FiniteVec(&s.scene.lo, "bounding box lo") || !r.FiniteVec(&s.scene.hi, "bounding box hi"))
    return false;

  uint64_t nm;
  if (!r.Count(48, &nm, "material count")) return false;
  if (nm == 0) return r.Fail("no materials (the default material is missing)");
  s.scene.materials.resize(size_t(nm));
  for (Material& mt : s.scene.materials)
    if (!r.FiniteVec(&mt.kd, "material Kd") || !r.FiniteVec(&mt.ke, "material Ke")) return false;

  // Each count is held to the bytes left and to the loader's own limits
  // (scene.h) before anything is allocated.
  uint64_t nv;
  if (!r.Count(24, &nv, "vertex count")) return false;
  if (nv > uint64_t(kMaxVertices))
    return r.Fail(std::to_string(nv) + " vertices (the limit is " + std::to_string(kMaxVertices) + ")");
  std::vector<glm::dvec3> points(static_cast<size_t>(nv));
  for (glm::dvec3& p : points)
    if (!r.FiniteVec(&p, "vertex")) return false;
  {
    // No point twice: sorted by hash, only neighbours of one hash are
    // compared (a hash table would miss the caches at every point).
    std::vector<std::pair<uint64_t, uint32_t>> keys(points.size());
    for (size_t i = 0; i < points.size(); ++i) keys[i] = {PointHash(points[i]), uint32_t(i)};
    std::sort(keys.begin(), keys.end());
    for (size_t i = 1; i < keys.size(); ++i)
      for (size_t j = i; j-- > 0 && keys[j].first == keys[i].first;)
        if (std::memcmp(&points[keys[j].second], &points[keys[i].second], sizeof(glm::dvec3)) == 0)
          return r.Fail("vertex " + std::to_string(keys[i].second) + " repeats vertex " +
                        std::to_string(keys[j].second));
  }
  // A face is at least 3 one-byte varints and 3 one-byte corners.
  constexpr size_t kMinFace = 6;
  uint64_t nf;
  if (!r.Count(kMinFace, &nf, "face count")) return false;
  if (nf > uint64_t(kMaxFaces))
    return r.Fail(std::to_string(nf) + " faces (the limit is " + std::to_string(kMaxFaces) + ")");
  s.scene.faces.resize(size_t(nf));
  int64_t previous = -1;
  uint64_t fresh = 0, corners = 0;
  for (size_t i = 0; i < s.scene.faces.size(); ++i) {
    Face& f = s.scene.faces[i];
    auto at = [i] { return "face " + std::to_string(i) + ": "; };
    if (!r.Varint(nm - 1, &v, "face material")) return false;
    f.material = int(v);
    if (!r.Varint(UINT32_MAX, &v, "face index")) return false;
    const int64_t index = previous + 1 + UnZigZag(v);
    if (index < 0 || index > INT32_MAX)
      return r.Fail(at() + "index " + std::to_string(index) + " is not in 0..2^31-1");
    f.index = int(index);
    previous = index;
    uint64_t n;
    if (!r.Count(1, &n, "face vertex count")) return false;
    if (n < 3 || n > kMaxPolygon)
      return r.Fail(at() + std::to_string(n) + " vertices (3.." + std::to_string(kMaxPolygon) + ")");
    corners += n;
    if (corners > uint64_t(kMaxCorners))
      return r.Fail(at() + "more than " + std::to_string(kMaxCorners) + " face vertices in all");
    f.verts.resize(size_t(n));
    for (glm::dvec3& p : f.verts) {
      uint64_t back;
      if (!r.Varint(fresh, &back, "face vertex")) return false;
      if (back == 0 && fresh == nv)
        return r.Fail(at() + "uses more vertices than the table's " + std::to_string(nv));
      p = points[size_t(back == 0 ? fresh++ : fresh - back)];
    }
    FacePlane(&f);
  }
  if (fresh != nv)
    return r.Fail(std::to_string(nv - fresh) + " vertices of the table are used by no face");
  if (!r.End("scene")) return false;
  if (!ValidSetup(s, err)) return false;
  *m = std::move(s);
  return true;
}

bool DecodeReady(std::string_view payload, Ready* m, std::string* err) {
  Reader r(payload, err);
  if (!r.Fixed(8, &m->elements, "element count") || !r.Fixed(8, &m->mesh_hash, "mesh hash"))
    return false;
  return r.End("ready");
}

bool DecodeWork(std::string_view payload, std::vector<Assignment>* m, std::string* err) {
  Reader r(payload, err);
  uint64_t n;
  if (!r.Count(3, &n, "assignment count")) return false;
  std::vector<Assignment> w(static_cast<size_t>(n));
  for (Assignment& a : w) {
    uint64_t members;
    if (!r.Int32(&a.patch, "patch") || !r.Int32(&a.k, "k") ||
        !r.Varint(kMaxGroup, &members, "group member count"))
      return false;
    if (members == 0) continue;
    auto at = [&a] { return "patch " + std::to_string(a.patch) + "'s group: "; };
    if (members == 1) return r.Fail(at() + "1 member (a group has 2.." + std::to_string(kMaxGroup) + ")");
    a.group.members.resize(size_t(members));
    a.group.members[0] = a.patch;
    for (size_t i = 1; i < a.group.members.size(); ++i) {
      uint64_t d;
      if (!r.Varint(UINT32_MAX, &d, "group member")) return false;
      const int64_t q = int64_t(a.group.members[i - 1]) + int64_t(d);
      if (d == 0) return r.Fail(at() + "members not increasing");
      if (q > INT32_MAX) return r.Fail(at() + "member " + std::to_string(q) + " is not in 0..2^31-1");
      a.group.members[i] = int(q);
    }
    if (!r.FiniteVec(&a.group.center, "group centre") || !r.FiniteVec(&a.group.normal, "group normal"))
      return false;
    if (!UnitNormal(a.group.normal)) return r.Fail(at() + "normal is not of unit length");
  }
  if (!r.End("work")) return false;
  *m = std::move(w);
  return true;
}

// The master's hot path; its loops are GetFormFactors'.
bool DecodeColumn(std::string_view payload, Column* m, std::string* err) {
  // Into *m itself: a master that decodes into the same Column each time
  // keeps its form factors' storage (no allocation, no zeroing per shot).
  Reader r(payload, err);
  if (!r.Int32(&m->patch, "patch") || !r.Int32(&m->k, "k")) return false;
  if (!r.Finite(&m->compute_s, "compute time")) return false;
  if (!(m->compute_s >= 0)) return r.Fail("compute time is negative");
  if (!r.Finite(&m->wait_s, "wait time")) return false;
  if (!(m->wait_s >= 0)) return r.Fail("wait time is negative");
  return GetFormFactors(&r, &m->ff);
}

bool DecodeDivide(std::string_view payload, std::vector<int32_t>* m, std::string* err) {
  Reader r(payload, err);
  uint64_t n;
  if (!r.Count(1, &n, "element count")) return false;
  std::vector<int32_t> d(static_cast<size_t>(n));
  for (int32_t& e : d) {
    uint64_t x;
    if (!r.Varint(2 * uint64_t(INT32_MAX) + 1, &x, "edit")) return false;
    e = x & 1 ? ~int32_t(x >> 1) : int32_t(x >> 1);
  }
  if (!r.End("divide")) return false;
  *m = std::move(d);
  return true;
}

bool DecodeError(std::string_view payload, std::string* text, std::string* err) {
  Reader r(payload, err);
  uint64_t n;
  std::string t;
  if (!r.Varint(kMaxErrorText, &n, "error text length")) return false;
  if (!r.Bytes(size_t(n), &t, "error text")) return false;
  for (size_t i = 0; i < t.size();) {
    size_t k = Utf8Len(t, i);
    if (k == 0) return r.Fail("error text is not UTF-8 at byte " + std::to_string(i));
    if (k == 1 && Control(t[i]))
      return r.Fail("error text has a control character at byte " + std::to_string(i));
    i += k;
  }
  if (!r.End("error")) return false;
  *text = std::move(t);
  return true;
}

// ---- framing ----------------------------------------------------------

// Drops what has been read once it is half the buffer: each byte is moved
// at most once on average, and a long stream does not grow memory. Done
// before the buffer next changes rather than after a frame is handed out,
// so that a payload's view stays valid until then.
void FrameReader::Compact() {
  if (pos_ == buf_.size()) {
    buf_.clear();
    pos_ = 0;
    if (buf_.capacity() > (size_t{1} << 20)) buf_.shrink_to_fit();
  } else if (pos_ > buf_.size() / 2) {
    buf_.erase(0, pos_);
    pos_ = 0;
  }
}

void FrameReader::Append(const char* data, size_t n) {
  if (bad_) return;  // nothing more will be read: do not keep it
  Compact();
  buf_.append(data, n);
}

FrameReader::Result FrameReader::Next(Msg* type, std::string* payload, std::string* err) {
  std::string_view view;
  const Result r = Next(type, &view, err);
  if (r == kFrame) {
    payload->assign(view.data(), view.size());
    // The copy is the caller's now: give the buffer back at once, not at
    // the next call (a worker's scene frame, 9 MB at 10^6 elements, would
    // stand beside the mesh it builds from that copy).
    Compact();
  }
  return r;
}

FrameReader::Result FrameReader::Next(Msg* type, std::string_view* payload, std::string* err) {
  if (bad_) {
    *err = "the stream is unusable after an earlier bad frame";
    return kBad;
  }
  Compact();
  if (buffered() < kHeaderSize) return kNeedMore;
  const unsigned char* h = reinterpret_cast<const unsigned char*>(buf_.data() + pos_);
  const uint32_t len = uint32_t(h[0]) | uint32_t(h[1]) << 8 | uint32_t(h[2]) << 16 |
                       uint32_t(h[3]) << 24;
  auto bad = [&](const std::string& why) {
    bad_ = true;
    buf_.clear();
    buf_.shrink_to_fit();
    pos_ = 0;
    *err = why;
    return kBad;
  };
  if (!KnownType(h[4])) return bad("unknown frame type " + std::to_string(h[4]));
  const Msg t = Msg(h[4]);
  if (h[5] || h[6] || h[7])
    return bad(std::string(MsgName(t)) + " frame header has non-zero reserved bytes");
  if (len > MaxPayload(t))
    return bad(std::string(MsgName(t)) + " frame of " + std::to_string(len) +
               " payload bytes is longer than the limit of " + std::to_string(MaxPayload(t)));
  if (buffered() - kHeaderSize < len) return kNeedMore;
  *type = t;
  *payload = std::string_view(buf_.data() + pos_ + kHeaderSize, len);
  pos_ += kHeaderSize + len;
  return kFrame;
}

}  // namespace proto
