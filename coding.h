// Byte coding for the binary formats (the wire protocol, checkpoints), in
// the manner of LevelDB's util/coding.h: Put* append little-endian fixed
// integers, IEEE 754 doubles and unsigned LEB128 varints to a string; a
// Reader takes them back with every length checked against the bytes left.
#ifndef RADIOSITY_CODING_H
#define RADIOSITY_CODING_H

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include <glm/vec3.hpp>

// ---- writing ----------------------------------------------------------

inline void PutU8(std::string* out, uint8_t v) { out->push_back(char(v)); }

// The low `bytes` bytes of v, least significant first.
inline void PutFixed(std::string* out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out->push_back(char((v >> (8 * i)) & 0xff));
}
inline void PutFixed32(std::string* out, uint32_t v) { PutFixed(out, v, 4); }
inline void PutFixed64(std::string* out, uint64_t v) { PutFixed(out, v, 8); }

// Overwrites 4 (8) bytes at dst: a length filled in once it is known.
inline void EncodeFixed32(char* dst, uint32_t v) {
  for (int i = 0; i < 4; ++i) dst[i] = char((v >> (8 * i)) & 0xff);
}
inline void EncodeFixed64(char* dst, uint64_t v) {
  for (int i = 0; i < 8; ++i) dst[i] = char((v >> (8 * i)) & 0xff);
}

inline void PutVarint(std::string* out, uint64_t v) {
  while (v >= 0x80) {
    out->push_back(char((v & 0x7f) | 0x80));
    v >>= 7;
  }
  out->push_back(char(v));
}

// A double's IEEE 754 bits, and the double of such bits. For doubles
// >= 0 the bits are in the order of the values: they sort and bisect as
// the values do (image.cpp's exposure and sRGB codes).
inline uint64_t DoubleBits(double d) {
  uint64_t bits;
  std::memcpy(&bits, &d, 8);
  return bits;
}
inline double BitsDouble(uint64_t bits) {
  double d;
  std::memcpy(&d, &bits, 8);
  return d;
}

inline void PutF64(std::string* out, double d) { PutFixed64(out, DoubleBits(d)); }

// IEEE 754 single (the browser view's mesh: WebGL draws in float).
inline void PutF32(std::string* out, float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  PutFixed32(out, bits);
}

inline void PutVec(std::string* out, const glm::dvec3& v) {
  PutF64(out, v.x);
  PutF64(out, v.y);
  PutF64(out, v.z);
}

// ---- reading ----------------------------------------------------------

// Unsigned LEB128 at *p, in its shortest form and within 64 bits. The
// one-byte case is inline (most varints in a column are one byte); on
// failure *p is left where it was.
enum class VarintStatus { kOk, kTruncated, kTooBig, kOverlong };

VarintStatus GetVarintSlow(const uint8_t** p, const uint8_t* end, uint64_t* v);

inline VarintStatus GetVarint(const uint8_t** p, const uint8_t* end, uint64_t* v) {
  if (*p < end && **p < 0x80) {
    *v = *(*p)++;
    return VarintStatus::kOk;
  }
  return GetVarintSlow(p, end, v);
}

// A varint that GetVarint has accepted already: no checks left to make.
inline uint64_t GetCheckedVarint(const uint8_t** p) {
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

// Reads what Put* wrote, from bytes it does not own. Each getter returns
// false with *err (one line, naming `what` and the offset) when the bytes
// do not hold it; the reader then stays failed (every later get fails and
// leaves its output alone), so a decoder may read a whole record and test
// ok() once.
class Reader {
 public:
  Reader(const char* data, size_t size, std::string* err)
      : p_(reinterpret_cast<const uint8_t*>(data)), size_(size), err_(err) {}
  Reader(std::string_view s, std::string* err) : Reader(s.data(), s.size(), err) {}

  bool ok() const { return ok_; }
  size_t left() const { return size_ - pos_; }
  size_t pos() const { return pos_; }
  const uint8_t* data() const { return p_; }
  // Moves to `pos` (<= size): a caller that read ahead on data() itself.
  void Seek(size_t pos) { pos_ = pos; }

  // Fails with `what` as the message.
  bool Fail(const std::string& what);

  // Fixed-width little-endian unsigned of 1..8 bytes.
  bool Fixed(int bytes, uint64_t* v, const char* what);
  bool U8(uint8_t* v, const char* what);
  // A double's bits as they are (F64), or only a finite one (Finite).
  bool F64(double* d, const char* what);
  bool Finite(double* d, const char* what);
  bool Vec(glm::dvec3* v, const char* what);
  bool FiniteVec(glm::dvec3* v, const char* what);
  // A varint of at most `max`, in its shortest form.
  bool Varint(uint64_t max, uint64_t* v, const char* what);
  // A varint of at most INT32_MAX.
  bool Int32(int32_t* v, const char* what);
  // A count of items each at least `min_bytes` long, as a varint (Count)
  // or a u64 (Count64): no more than the rest could hold, so that a bad
  // count never allocates much.
  bool Count(size_t min_bytes, uint64_t* n, const char* what);
  bool Count64(size_t min_bytes, uint64_t* n, const char* what);
  bool Bytes(size_t n, std::string* s, const char* what);
  // That nothing is left after `record`.
  bool End(const char* record);

 private:
  bool Need(size_t n, const char* what);
  bool Fits(size_t min_bytes, uint64_t n, const char* what);

  const uint8_t* p_;
  size_t size_;
  size_t pos_ = 0;
  std::string* err_;
  bool ok_ = true;
};

#endif
