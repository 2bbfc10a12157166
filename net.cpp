// The wire protocol: framing and message codecs. doc/protocol.txt is the
// byte-by-byte description; keep the two in step.
//
// Encoders write what they are given and CHECK the invariants the decoder
// would reject (a master or worker that sends such a frame has a bug).
// Decoders trust nothing: every count is checked against the bytes left
// before anything is allocated, every value against its range, and the
// payload must be used up exactly.
#include "net.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "check.h"

// The same macro, and the same default, as radiosity.cpp (--version).
#ifndef RADIOSITY_VERSION
#define RADIOSITY_VERSION "0.1"
#endif

namespace proto {
namespace {

// Largest payload of each type, checked by FrameReader as soon as the
// header is in (before buffering the payload). 0 for unknown types.
constexpr uint32_t kMaxBuild = 256;
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

// ---- writing ----------------------------------------------------------

void PutU8(std::string* out, uint8_t v) { out->push_back(char(v)); }

void PutLE(std::string* out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out->push_back(char((v >> (8 * i)) & 0xff));
}

void PutVarint(std::string* out, uint64_t v) {
  while (v >= 0x80) {
    out->push_back(char((v & 0x7f) | 0x80));
    v >>= 7;
  }
  out->push_back(char(v));
}

void PutF64(std::string* out, double d) {
  uint64_t bits;
  std::memcpy(&bits, &d, 8);
  PutLE(out, bits, 8);
}

void PutVec(std::string* out, const glm::dvec3& v) {
  PutF64(out, v.x);
  PutF64(out, v.y);
  PutF64(out, v.z);
}

// Writes a header with length 0 and returns where it starts.
size_t BeginFrame(Msg type, std::string* out) {
  size_t start = out->size();
  PutLE(out, 0, 4);
  PutU8(out, uint8_t(type));
  PutLE(out, 0, 3);
  return start;
}

// Fills in the payload length of the frame that starts at `start`.
void EndFrame(size_t start, std::string* out) {
  uint64_t len = out->size() - start - kHeaderSize;
  CHECK(len <= 0xffffffffu);
  for (int i = 0; i < 4; ++i) (*out)[start + i] = char((len >> (8 * i)) & 0xff);
}

// ---- reading ----------------------------------------------------------

// Unsigned LEB128 at *p, in its shortest form and within 64 bits. The
// one-byte case is inline (most varints in a column are one byte); on
// failure *p is left where it was.
enum class VarintStatus { kOk, kTruncated, kTooBig, kOverlong };

VarintStatus GetVarintSlow(const uint8_t** p, const uint8_t* end, uint64_t* v) {
  const uint8_t* q = *p;
  uint64_t r = 0;
  for (int shift = 0;; shift += 7) {
    if (q >= end) return VarintStatus::kTruncated;
    const uint8_t b = *q++;
    if (shift == 63 && b > 1) return VarintStatus::kTooBig;
    r |= uint64_t(b & 0x7f) << shift;
    if (!(b & 0x80)) {
      if (b == 0 && shift > 0) return VarintStatus::kOverlong;
      break;
    }
  }
  *p = q;
  *v = r;
  return VarintStatus::kOk;
}

inline VarintStatus GetVarint(const uint8_t** p, const uint8_t* end, uint64_t* v) {
  if (*p < end && **p < 0x80) {
    *v = *(*p)++;
    return VarintStatus::kOk;
  }
  return GetVarintSlow(p, end, v);
}

class Reader {
 public:
  Reader(const char* data, size_t size, std::string* err)
      : p_(reinterpret_cast<const uint8_t*>(data)), size_(size), err_(err) {}
  Reader(const std::string& p, std::string* err) : Reader(p.data(), p.size(), err) {}

  size_t left() const { return size_ - pos_; }
  size_t pos() const { return pos_; }

  bool Fail(const std::string& what) {
    *err_ = what;
    return false;
  }

  bool Need(size_t n, const char* what) {
    if (left() >= n) return true;
    return Fail(std::string("truncated: ") + what + " needs " + std::to_string(n) +
                " bytes at offset " + std::to_string(pos_) + ", " + std::to_string(left()) +
                " left");
  }

  bool LE(int bytes, uint64_t* v, const char* what) {
    if (!Need(size_t(bytes), what)) return false;
    uint64_t r = 0;
    for (int i = 0; i < bytes; ++i) r |= uint64_t(p_[pos_ + i]) << (8 * i);
    pos_ += size_t(bytes);
    *v = r;
    return true;
  }

  bool U8(uint8_t* v, const char* what) {
    uint64_t r;
    if (!LE(1, &r, what)) return false;
    *v = uint8_t(r);
    return true;
  }

  // Unsigned LEB128 of at most `max`, in its shortest form.
  bool Varint(uint64_t max, uint64_t* v, const char* what) {
    const size_t start = pos_;
    const uint8_t* q = p_ + pos_;
    uint64_t r = 0;
    switch (GetVarint(&q, p_ + size_, &r)) {
      case VarintStatus::kOk: break;
      case VarintStatus::kTruncated:
        return Fail(std::string("truncated: varint ") + what + " at offset " +
                    std::to_string(start) + " runs past the end");
      case VarintStatus::kTooBig:
        return Fail(std::string("varint ") + what + " at offset " + std::to_string(start) +
                    " does not fit in 64 bits");
      case VarintStatus::kOverlong:
        return Fail(std::string("varint ") + what + " at offset " + std::to_string(start) +
                    " is not in its shortest form");
    }
    pos_ = size_t(q - p_);
    if (r > max)
      return Fail(std::string(what) + " " + std::to_string(r) + " is out of range (max " +
                  std::to_string(max) + ")");
    *v = r;
    return true;
  }

  bool Int32(int32_t* v, const char* what) {
    uint64_t r;
    if (!Varint(INT32_MAX, &r, what)) return false;
    *v = int32_t(r);
    return true;
  }

  // A count of items each at least `min_bytes` long: no more than the rest
  // of the payload could hold, so nothing absurd is ever allocated.
  bool Count(size_t min_bytes, uint64_t* n, const char* what) {
    if (!Varint(UINT64_MAX, n, what)) return false;
    if (*n > left() / min_bytes)
      return Fail(std::string(what) + " " + std::to_string(*n) + " needs at least " +
                  std::to_string(min_bytes) + " bytes each, " + std::to_string(left()) +
                  " bytes left");
    return true;
  }

  bool F64(double* d, const char* what) {
    uint64_t bits;
    if (!LE(8, &bits, what)) return false;
    std::memcpy(d, &bits, 8);
    if (!std::isfinite(*d))
      return Fail(std::string(what) + " at offset " + std::to_string(pos_ - 8) + " is not finite");
    return true;
  }

  bool Vec(glm::dvec3* v, const char* what) {
    return F64(&v->x, what) && F64(&v->y, what) && F64(&v->z, what);
  }

  bool Bytes(size_t n, std::string* s, const char* what) {
    if (!Need(n, what)) return false;
    s->assign(reinterpret_cast<const char*>(p_ + pos_), n);
    pos_ += n;
    return true;
  }

  bool End(const char* msg) {
    if (left() == 0) return true;
    return Fail(std::string(msg) + ": " + std::to_string(left()) +
                " bytes left over after offset " + std::to_string(pos_));
  }

  const uint8_t* p_;
  size_t size_;
  size_t pos_ = 0;
  std::string* err_;
};

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
    const double len = glm::length(f.normal);
    if (!std::isfinite(len) || !(std::fabs(len - 1) <= 1e-6))
      return fail(at + "normal is not of unit length");
    if (!(f.area > 0) || !std::isfinite(f.area)) return fail(at + "area is not finite and > 0");
  }
  return true;
}

// Form factor <-> 24 bits: the float's bits (sign 0) >> 7, rounded to
// nearest (ties away from zero); never 0 and never inf/NaN. Only for the
// escape of a column's 16-bit codes (below).
constexpr uint32_t kFfMin = 1;           // 2^-142: the smallest code, a subnormal
constexpr uint32_t kFfLimit = 0xff0000;  // exponent all ones: inf and NaN

uint32_t FfCode(float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  uint32_t q = (bits + 0x40) >> 7;
  if (q >= kFfLimit) q = kFfLimit - 1;  // bits >= 0x7f7fffc0, next to FLT_MAX: truncate
  if (q < kFfMin) q = kFfMin;           // below 2^-143: not a form factor
  return q;
}

float FfValue(uint32_t q) {
  uint32_t bits = q << 7;
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

// Form factor <-> 16 bits: code = e << 11 | m stands for
// (1 + m / 2048) 2^(e - 31), e in 0..31, m in 0..2047. The code is the
// float's (or double's) exponent and top 11 fraction bits with the
// exponent rebased, so codes are in the order of their values and code + 1
// is the next value. Code 0 (2^-31) is the escape instead: a 24-bit code
// follows. A value is sent with 16 bits exactly when its 24-bit code is
// within those of code 1 and code 0xffff, so that each value has one coding.
constexpr uint32_t kF16Escape = 0;
constexpr uint32_t kF16Max = 0xffff;
constexpr uint32_t kF16FloatBias = 96u << 23;    // 127 - 31, in a float's exponent field
constexpr uint64_t kF16DoubleBias = 992u << 11;  // 1023 - 31, in the code's exponent field
// The 24-bit codes of the values of codes 1 (2^-31 (1 + 2^-11)) and 0xffff
// (2 - 2^-11): the range sent in 16 bits.
constexpr uint32_t kF16Lo24 = 0x30001000u >> 7;
constexpr uint32_t kF16Hi24 = 0x3ffff000u >> 7;

bool F16Range(uint32_t code24) { return code24 >= kF16Lo24 && code24 <= kF16Hi24; }

// The value of a 16-bit code (not the escape), exactly.
double F16Value(uint32_t code) {
  const uint64_t bits = (uint64_t(code) + kF16DoubleBias) << 41;
  double d;
  std::memcpy(&d, &bits, 8);
  return d;
}

// The code nearest to x > 0 (ties up), clamped to 1 .. 0xffff.
uint32_t F16Round(double x) {
  uint64_t bits;
  std::memcpy(&bits, &x, 8);
  const int64_t q = int64_t((bits + (uint64_t(1) << 40)) >> 41) - int64_t(kF16DoubleBias);
  return uint32_t(std::min<int64_t>(std::max<int64_t>(q, 1), kF16Max));
}

// The form factors of one column, 2 bytes each (5 for an escape), with
// error diffusion: each value is coded as its form factor plus the
// rounding residual carried so far, clamped to within kFormFactorError of
// the form factor, and the residual of that (target minus coded value) is
// carried on, so the coded sum differs from the true sum by the last
// residual only. The form factors are visited from the largest exponent
// down (in id order within one exponent), so that what is left at the end
// is a rounding step of the smallest ones: |sum F' - sum F| is at most
// 2^-11 of the largest form factor, and in practice far less
// (doc/protocol.txt). Escaped values are coded alone; their (tiny) error
// is carried too. The residual is exact enough in double.
void PutFormFactors(const std::vector<FormFactor>& ff, std::string* out) {
  const size_t n = ff.size();
  // The visiting order: a counting sort on the float's exponent field.
  size_t first[256] = {};
  for (const FormFactor& f : ff) {
    CHECK(f.f > 0 && std::isfinite(f.f));
    uint32_t bits;
    std::memcpy(&bits, &f.f, 4);
    ++first[255 - (bits >> 23)];
  }
  for (size_t e = 0, sum = 0; e < 256; ++e) {
    const size_t c = first[e];
    first[e] = sum;
    sum += c;
  }
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) {
    uint32_t bits;
    std::memcpy(&bits, &ff[i].f, 4);
    order[first[255 - (bits >> 23)]++] = uint32_t(i);
  }

  // The codes, by id: 16 bits, or kEscaped | the 24-bit code.
  constexpr uint32_t kEscaped = 1u << 31;
  std::vector<uint32_t> codes(n);
  size_t escapes = 0;
  double carry = 0;
  for (uint32_t i : order) {
    const double x = ff[i].f;
    const uint32_t c24 = FfCode(ff[i].f);
    if (!F16Range(c24)) {
      codes[i] = kEscaped | c24;
      ++escapes;
      carry += x - double(FfValue(c24));
      continue;
    }
    // x has 24 significant bits, so lo and hi are exact.
    const double lo = x - x * kFormFactorError, hi = x + x * kFormFactorError;
    const double target = x + carry;
    uint32_t q = F16Round(std::min(std::max(target, lo), hi));
    double v = F16Value(q);
    // Rounding may step just outside [lo, hi]: take the neighbour inside.
    if (v > hi) v = F16Value(--q);
    else if (v < lo) v = F16Value(++q);
    CHECK(q >= 1 && q <= kF16Max && v >= lo && v <= hi);
    codes[i] = q;
    carry = target - v;
  }

  const size_t start = out->size();
  out->resize(start + 2 * n + 3 * escapes);
  uint8_t* p = reinterpret_cast<uint8_t*>(&(*out)[start]);
  for (uint32_t q : codes) {
    if (q & kEscaped) {
      p[0] = p[1] = 0;  // the escape
      p[2] = uint8_t(q);
      p[3] = uint8_t(q >> 8);
      p[4] = uint8_t(q >> 16);
      p += 5;
    } else {
      p[0] = uint8_t(q);
      p[1] = uint8_t(q >> 8);
      p += 2;
    }
  }
}

}  // namespace

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
  PutLE(out, m.magic, 4);
  PutLE(out, m.version, 2);
  PutVarint(out, m.build.size());
  out->append(m.build);
  EndFrame(start, out);
}

void EncodeScene(const SceneSetup& m, std::string* out) {
  std::string err;
  if (!ValidSetup(m, &err)) {
    std::fprintf(stderr, "radiosity: internal error: EncodeScene: %s\n", err.c_str());
    CHECK(!"a valid scene setup");
  }
  // A scene past kMaxFrame is still encoded (with its true length, below
  // 4 GiB): the receiver refuses it as too long. Callers that want a
  // clear message check the frame's size against kMaxFrame first.
  size_t start = BeginFrame(Msg::kScene, out);
  PutU8(out, m.rotate);
  PutVarint(out, uint32_t(m.resolution));
  PutLE(out, m.seed, 4);
  PutVarint(out, uint32_t(m.mesh.elements_per_patch));
  PutF64(out, m.mesh.patch_size);
  PutVec(out, m.scene.lo);
  PutVec(out, m.scene.hi);
  PutVarint(out, m.scene.materials.size());
  for (const Material& mt : m.scene.materials) {
    PutVec(out, mt.kd);
    PutVec(out, mt.ke);
  }
  PutVarint(out, m.scene.faces.size());
  for (const Face& f : m.scene.faces) {
    PutVarint(out, uint32_t(f.material));
    PutVarint(out, uint32_t(f.index));
    PutVarint(out, f.verts.size());
    PutVec(out, f.normal);
    PutF64(out, f.area);
    for (const auto& v : f.verts) PutVec(out, v);
  }
  EndFrame(start, out);
}

void EncodeReady(const Ready& m, std::string* out) {
  size_t start = BeginFrame(Msg::kReady, out);
  PutLE(out, m.elements, 8);
  PutLE(out, m.mesh_hash, 8);
  EndFrame(start, out);
}

void EncodeWork(const std::vector<Assignment>& m, std::string* out) {
  size_t start = BeginFrame(Msg::kWork, out);
  PutVarint(out, m.size());
  for (const Assignment& a : m) {
    CHECK(a.patch >= 0 && a.k >= 0);
    PutVarint(out, uint32_t(a.patch));
    PutVarint(out, uint32_t(a.k));
  }
  EndFrame(start, out);
}

void EncodeColumn(const Column& m, std::string* out) {
  CHECK(m.patch >= 0 && m.k >= 0);
  CHECK(std::isfinite(m.compute_s) && m.compute_s >= 0);
  CHECK(std::isfinite(m.wait_s) && m.wait_s >= 0);
  size_t start = BeginFrame(Msg::kColumn, out);
  PutVarint(out, uint32_t(m.patch));
  PutVarint(out, uint32_t(m.k));
  PutF64(out, m.compute_s);
  PutF64(out, m.wait_s);
  const std::vector<FormFactor>& ff = m.ff;
  PutVarint(out, ff.size());
  // Ids as maximal runs of consecutive ids.
  size_t runs = 0;
  int64_t prev = -1;
  for (const FormFactor& f : ff) {
    CHECK(f.elem > prev);  // ids increase (and are >= 0)
    if (runs == 0 || f.elem != prev + 1) ++runs;
    prev = f.elem;
  }
  PutVarint(out, runs);
  int64_t end = 0;  // one past the previous run's last id
  for (size_t i = 0; i < ff.size();) {
    size_t j = i + 1;
    while (j < ff.size() && ff[j].elem == ff[j - 1].elem + 1) ++j;
    PutVarint(out, uint64_t(ff[i].elem - end));  // >= 1 after the first run
    PutVarint(out, j - i - 1);
    end = int64_t(ff[j - 1].elem) + 1;
    i = j;
  }
  PutFormFactors(ff, out);
  EndFrame(start, out);
}

void EncodeDivide(const std::vector<int32_t>& elems, std::string* out) {
  size_t start = BeginFrame(Msg::kDivide, out);
  PutVarint(out, elems.size());
  for (int32_t e : elems) {
    CHECK(e >= 0);
    PutVarint(out, uint32_t(e));
  }
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

bool DecodeHello(const std::string& payload, Hello* m, std::string* err) {
  Reader r(payload, err);
  uint64_t magic, version;
  if (!r.LE(4, &magic, "magic") || !r.LE(2, &version, "version")) return false;
  m->magic = uint32_t(magic);
  m->version = uint16_t(version);
  m->build.clear();
  if (m->magic != kMagic || m->version != kVersion) {
    // Another protocol (or not ours at all): what follows may be laid out
    // differently, so take the build string only if it reads as one and
    // let the caller report the mismatch.
    std::string ignored;
    Reader rest(payload, &ignored);
    rest.pos_ = r.pos_;
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

bool DecodeScene(const std::string& payload, SceneSetup* m, std::string* err) {
  Reader r(payload, err);
  SceneSetup s;
  s.scene.objects = {"default"};
  uint64_t v;
  if (!r.U8(&s.rotate, "rotate")) return false;
  if (!r.Varint(uint64_t(Hemicube::kMaxResolution), &v, "resolution")) return false;
  s.resolution = int32_t(v);
  if (!r.LE(4, &v, "seed")) return false;
  s.seed = uint32_t(v);
  if (!r.Varint(64, &v, "elements per patch")) return false;
  s.mesh.elements_per_patch = int(v);
  if (!r.F64(&s.mesh.patch_size, "patch size")) return false;
  if (!r.Vec(&s.scene.lo, "bounding box lo") || !r.Vec(&s.scene.hi, "bounding box hi"))
    return false;

  uint64_t nm;
  if (!r.Count(48, &nm, "material count")) return false;
  if (nm == 0) return r.Fail("no materials (the default material is missing)");
  s.scene.materials.resize(size_t(nm));
  for (Material& mt : s.scene.materials)
    if (!r.Vec(&mt.kd, "material Kd") || !r.Vec(&mt.ke, "material Ke")) return false;

  // A face is at least 3 one-byte varints, normal, area and 3 vertices.
  constexpr size_t kMinFace = 3 + 4 * 8 + 3 * 24;
  uint64_t nf;
  if (!r.Count(kMinFace, &nf, "face count")) return false;
  s.scene.faces.resize(size_t(nf));
  for (size_t i = 0; i < s.scene.faces.size(); ++i) {
    Face& f = s.scene.faces[i];
    if (!r.Varint(nm - 1, &v, "face material")) return false;
    f.material = int(v);
    if (!r.Varint(INT32_MAX, &v, "face index")) return false;
    f.index = int(v);
    uint64_t nv;
    if (!r.Count(24, &nv, "face vertex count")) return false;
    if (nv < 3) return r.Fail("face " + std::to_string(i) + " has " + std::to_string(nv) +
                              " vertices (at least 3)");
    if (!r.Vec(&f.normal, "face normal") || !r.F64(&f.area, "face area")) return false;
    f.verts.resize(size_t(nv));
    for (auto& p : f.verts)
      if (!r.Vec(&p, "vertex")) return false;
  }
  if (!r.End("scene")) return false;
  if (!ValidSetup(s, err)) return false;
  *m = std::move(s);
  return true;
}

bool DecodeReady(const std::string& payload, Ready* m, std::string* err) {
  Reader r(payload, err);
  if (!r.LE(8, &m->elements, "element count") || !r.LE(8, &m->mesh_hash, "mesh hash"))
    return false;
  return r.End("ready");
}

bool DecodeWork(const std::string& payload, std::vector<Assignment>* m, std::string* err) {
  Reader r(payload, err);
  uint64_t n;
  if (!r.Count(2, &n, "assignment count")) return false;
  std::vector<Assignment> w(static_cast<size_t>(n));
  for (Assignment& a : w)
    if (!r.Int32(&a.patch, "patch") || !r.Int32(&a.k, "k")) return false;
  if (!r.End("work")) return false;
  *m = std::move(w);
  return true;
}

// A varint DecodeColumn has checked already (shortest form, <= INT32_MAX).
inline uint64_t CheckedVarint(const uint8_t** p) {
  const uint8_t* q = *p;
  uint64_t v = 0;
  int shift = 0;
  uint8_t b;
  do {
    b = *q++;
    v |= uint64_t(b & 0x7f) << shift;
    shift += 7;
  } while (b & 0x80);
  *p = q;
  return v;
}

// The float of a 16-bit code (not the escape): its exponent and fraction
// bits, rebased.
inline uint32_t F16FloatBits(uint32_t code) { return (code << 12) + kF16FloatBias; }

// The master's hot path: tight loops over the bytes, one allocation, no
// strings unless it fails. The runs are checked first without writing
// anything; then, in the usual case of a column without escapes (exactly 2
// bytes per form factor left), ids and form factors are written in one
// pass. Columns with escapes, and every error, take the general path.
bool DecodeColumn(const char* data, size_t size, Column* m, std::string* err) {
  Reader r(data, size, err);
  Column c;
  if (!r.Int32(&c.patch, "patch") || !r.Int32(&c.k, "k")) return false;
  if (!r.F64(&c.compute_s, "compute time")) return false;
  if (!(c.compute_s >= 0)) return r.Fail("compute time is negative");
  if (!r.F64(&c.wait_s, "wait time")) return false;
  if (!(c.wait_s >= 0)) return r.Fail("wait time is negative");
  uint64_t n, runs;
  if (!r.Count(2, &n, "form factor count")) return false;
  if (!r.Count(2, &runs, "run count")) return false;
  if (runs > n)
    return r.Fail("run count " + std::to_string(runs) + " is more than the " +
                  std::to_string(n) + " form factors");

  const uint8_t* const base = r.p_;
  const uint8_t* const end = base + size;
  const uint8_t* const runs_at = base + r.pos();
  auto at = [&](const uint8_t* q) { return std::to_string(q - base); };

  // Runs: (gap, length - 1) each; checked, nothing written.
  const uint8_t* p = runs_at;
  uint64_t next = 0;  // one past the previous run's last id
  uint64_t filled = 0;
  for (uint64_t k = 0; k < runs; ++k) {
    const uint8_t* const gap_at = p;
    uint64_t gap, len1;
    if (GetVarint(&p, end, &gap) != VarintStatus::kOk || gap > INT32_MAX) {
      r.pos_ = size_t(gap_at - base);
      r.Varint(INT32_MAX, &gap, "run gap");  // fails, and says why
      return false;
    }
    const uint8_t* const len_at = p;
    if (GetVarint(&p, end, &len1) != VarintStatus::kOk || len1 > INT32_MAX) {
      r.pos_ = size_t(len_at - base);
      r.Varint(INT32_MAX, &len1, "run length - 1");
      return false;
    }
    if (gap == 0 && k > 0)
      return r.Fail("run " + std::to_string(k) + " at offset " + at(gap_at) +
                    " has gap 0: it continues the previous run (runs must be maximal)");
    const uint64_t len = len1 + 1;
    if (len > n - filled)
      return r.Fail("run " + std::to_string(k) + " at offset " + at(gap_at) + " makes " +
                    std::to_string(filled + len) + " ids, more than the " + std::to_string(n) +
                    " form factors");
    next += gap + len;
    if (next - 1 > uint64_t(INT32_MAX))
      return r.Fail("run " + std::to_string(k) + " at offset " + at(gap_at) + ": element id " +
                    std::to_string(next - 1) + " is out of range (max " +
                    std::to_string(INT32_MAX) + ")");
    filled += len;
  }
  if (filled != n)
    return r.Fail("runs make " + std::to_string(filled) + " ids for " + std::to_string(n) +
                  " form factors");
  const uint8_t* const codes_at = p;
  if (uint64_t(end - codes_at) < 2 * n)
    return r.Fail("truncated: " + std::to_string(n) + " form factors need at least " +
                  std::to_string(2 * n) + " bytes at offset " + at(codes_at) + ", " +
                  std::to_string(end - codes_at) + " left");

  c.ff.resize(size_t(n));
  FormFactor* const ff = c.ff.data();
  if (uint64_t(end - codes_at) == 2 * n) {
    // No room for an escape: one pass. A code 0 (an escape without its 3
    // bytes) is noted and reported by the general path.
    const uint8_t* q = runs_at;
    const uint8_t* pc = codes_at;
    FormFactor* out = ff;
    uint32_t any_zero = 0;  // bit 31 set by code 0 (0 - 1)
    uint32_t id = 0;
    for (uint64_t k = 0; k < runs; ++k) {
      id += uint32_t(CheckedVarint(&q));
      const uint32_t stop = id + uint32_t(CheckedVarint(&q)) + 1;  // <= 2^31
      for (; id != stop; ++id, ++out, pc += 2) {
        const uint32_t code = uint32_t(pc[0]) | uint32_t(pc[1]) << 8;
        any_zero |= code - 1;
        const uint32_t bits = F16FloatBits(code);
        out->elem = int32_t(id);
        std::memcpy(&out->f, &bits, 4);
      }
    }
    if (!(any_zero >> 31)) {
      *m = std::move(c);
      return true;
    }
  }

  // The general path: ids, then form factors with escapes, every byte
  // checked.
  p = runs_at;
  {
    uint32_t id = 0;
    FormFactor* out = ff;
    for (uint64_t k = 0; k < runs; ++k) {
      id += uint32_t(CheckedVarint(&p));
      const uint32_t len = uint32_t(CheckedVarint(&p)) + 1;
      for (uint32_t j = 0; j < len; ++j) out[j].elem = int32_t(id + j);
      out += len;
      id += len;
    }
  }
  p = codes_at;
  for (size_t i = 0; i < n;) {
    // Up to the next escape no bounds check is needed: the bytes left hold
    // 2 for each form factor left.
    const size_t stop = std::min<size_t>(n, i + size_t(end - p) / 2);
    for (; i < stop; ++i, p += 2) {
      const uint32_t q = uint32_t(p[0]) | uint32_t(p[1]) << 8;
      if (q == kF16Escape) break;
      const uint32_t bits = F16FloatBits(q);
      std::memcpy(&ff[i].f, &bits, 4);
    }
    if (i == n) break;
    if (i == stop)  // a code cut short: fewer than 2 bytes left
      return r.Fail("truncated: form factor " + std::to_string(i) + " needs 2 bytes at offset " +
                    at(p) + ", " + std::to_string(end - p) + " left");
    // The escape: a 24-bit code outside the 16-bit codes' range.
    if (end - p < 5)
      return r.Fail("truncated: escaped form factor " + std::to_string(i) +
                    " needs 5 bytes at offset " + at(p) + ", " + std::to_string(end - p) +
                    " left");
    const uint32_t q = uint32_t(p[2]) | uint32_t(p[3]) << 8 | uint32_t(p[4]) << 16;
    if (q < kFfMin) return r.Fail("form factor " + std::to_string(i) + " is 0");
    if (q >= kFfLimit) return r.Fail("form factor " + std::to_string(i) + " is inf or NaN");
    if (F16Range(q))
      return r.Fail("form factor " + std::to_string(i) + " at offset " + at(p) +
                    " is escaped but has a 16-bit code");
    ff[i].f = FfValue(q);
    p += 5;
    ++i;
  }
  if (p != end)
    return r.Fail("column: " + std::to_string(end - p) + " bytes left over after offset " +
                  at(p));
  *m = std::move(c);
  return true;
}

bool DecodeColumn(const std::string& payload, Column* m, std::string* err) {
  return DecodeColumn(payload.data(), payload.size(), m, err);
}

bool DecodeDivide(const std::string& payload, std::vector<int32_t>* m, std::string* err) {
  Reader r(payload, err);
  uint64_t n;
  if (!r.Count(1, &n, "element count")) return false;
  std::vector<int32_t> d(static_cast<size_t>(n));
  for (int32_t& e : d)
    if (!r.Int32(&e, "element id")) return false;
  if (!r.End("divide")) return false;
  *m = std::move(d);
  return true;
}

bool DecodeError(const std::string& payload, std::string* text, std::string* err) {
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

void FrameReader::Append(const char* data, size_t n) {
  if (bad_) return;  // nothing more will be read: do not keep it
  buf_.append(data, n);
}

FrameReader::Result FrameReader::Next(Msg* type, std::string* payload, std::string* err) {
  if (bad_) {
    *err = "the stream is unusable after an earlier bad frame";
    return kBad;
  }
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
  payload->assign(buf_, pos_ + kHeaderSize, len);
  pos_ += kHeaderSize + len;
  // Drop what has been read once it is half the buffer: each byte is moved
  // at most once on average, and a long stream does not grow memory.
  if (pos_ == buf_.size()) {
    buf_.clear();
    pos_ = 0;
    if (buf_.capacity() > (size_t{1} << 20)) buf_.shrink_to_fit();
  } else if (pos_ > buf_.size() / 2) {
    buf_.erase(0, pos_);
    pos_ = 0;
  }
  return kFrame;
}

// ---- identity ---------------------------------------------------------

std::string BuildId() {
  std::string id = "radiosity " RADIOSITY_VERSION " proto " + std::to_string(kVersion) + " ";
#ifdef __VERSION__
  id += __VERSION__;
#else
  id += "unknown-compiler";
#endif
  const uint16_t one = 1;
  uint8_t first;
  std::memcpy(&first, &one, 1);
  id += " " + std::to_string(8 * sizeof(void*)) + "-bit " + (first ? "le" : "be");
  // Floating-point modes that change the mesh's bits.
#ifdef __FAST_MATH__
  id += " fast-math";
#endif
#ifdef __FMA__
  id += " fma";
#endif
  for (char& c : id)
    if (uint8_t(c) < 0x20 || uint8_t(c) > 0x7e) c = '?';
  if (id.size() > kMaxBuild) id.resize(kMaxBuild);
  return id;
}

namespace {

// One step of the hash: the state xor a 64-bit word, through splitmix64's
// finaliser (a bijection with full avalanche).
uint64_t Mix(uint64_t h, uint64_t w) {
  uint64_t z = h ^ w;
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

uint64_t Bits(double d) {
  uint64_t b;
  std::memcpy(&b, &d, 8);
  return b;
}

uint64_t Int(int v) { return uint64_t(uint32_t(v)); }

}  // namespace

uint64_t MeshHash(const Mesh& mesh) {
  uint64_t h = 0x6d657368;  // "mesh"
  h = Mix(h, mesh.verts.size());
  h = Mix(h, mesh.elems.size());
  h = Mix(h, mesh.patches.size());
  h = Mix(h, mesh.faces.size());
  for (const auto& v : mesh.verts) {
    h = Mix(h, Bits(v.x));
    h = Mix(h, Bits(v.y));
    h = Mix(h, Bits(v.z));
  }
  for (const Element& e : mesh.elems) {
    h = Mix(h, Int(e.v[0]) | Int(e.v[1]) << 32);
    h = Mix(h, Int(e.v[2]) | Int(e.v[3]) << 32);
    h = Mix(h, Int(e.patch) | Int(e.parent) << 32);
    h = Mix(h, Int(e.first_child) | Int(e.level) << 32);
    h = Mix(h, Bits(e.area));
  }
  for (const Patch& p : mesh.patches) {
    h = Mix(h, Int(p.face) | uint64_t(p.elements.size()) << 32);
    h = Mix(h, Bits(p.center.x));
    h = Mix(h, Bits(p.center.y));
    h = Mix(h, Bits(p.center.z));
  }
  return h;
}

}  // namespace proto
