#include "coding.h"

#include <cmath>

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

bool Reader::Fail(const std::string& what) {
  if (ok_) *err_ = what;  // the first failure is the one to report
  ok_ = false;
  return false;
}

bool Reader::Need(size_t n, const char* what) {
  if (!ok_) return false;
  if (left() >= n) return true;
  return Fail(std::string("truncated: ") + what + " needs " + std::to_string(n) +
              " bytes at offset " + std::to_string(pos_) + ", " + std::to_string(left()) +
              " left");
}

bool Reader::Fixed(int bytes, uint64_t* v, const char* what) {
  if (!Need(size_t(bytes), what)) return false;
  uint64_t r = 0;
  for (int i = 0; i < bytes; ++i) r |= uint64_t(p_[pos_ + i]) << (8 * i);
  pos_ += size_t(bytes);
  *v = r;
  return true;
}

bool Reader::U8(uint8_t* v, const char* what) {
  uint64_t r;
  if (!Fixed(1, &r, what)) return false;
  *v = uint8_t(r);
  return true;
}

bool Reader::F64(double* d, const char* what) {
  uint64_t bits;
  if (!Fixed(8, &bits, what)) return false;
  *d = BitsDouble(bits);
  return true;
}

bool Reader::Finite(double* d, const char* what) {
  if (!F64(d, what)) return false;
  if (!std::isfinite(*d))
    return Fail(std::string(what) + " at offset " + std::to_string(pos_ - 8) + " is not finite");
  return true;
}

bool Reader::Vec(glm::dvec3* v, const char* what) {
  return F64(&v->x, what) && F64(&v->y, what) && F64(&v->z, what);
}

bool Reader::FiniteVec(glm::dvec3* v, const char* what) {
  return Finite(&v->x, what) && Finite(&v->y, what) && Finite(&v->z, what);
}

bool Reader::Varint(uint64_t max, uint64_t* v, const char* what) {
  if (!ok_) return false;
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

bool Reader::Int32(int32_t* v, const char* what) {
  uint64_t r;
  if (!Varint(INT32_MAX, &r, what)) return false;
  *v = int32_t(r);
  return true;
}

bool Reader::Fits(size_t min_bytes, uint64_t n, const char* what) {
  if (n <= left() / min_bytes) return true;
  return Fail(std::string(what) + " " + std::to_string(n) + " needs at least " +
              std::to_string(min_bytes) + " bytes each, " + std::to_string(left()) +
              " bytes left");
}

bool Reader::Count(size_t min_bytes, uint64_t* n, const char* what) {
  uint64_t r;
  if (!Varint(UINT64_MAX, &r, what) || !Fits(min_bytes, r, what)) return false;
  *n = r;
  return true;
}

bool Reader::Count64(size_t min_bytes, uint64_t* n, const char* what) {
  uint64_t r;
  if (!Fixed(8, &r, what) || !Fits(min_bytes, r, what)) return false;
  *n = r;
  return true;
}

bool Reader::Bytes(size_t n, std::string* s, const char* what) {
  if (!Need(n, what)) return false;
  s->assign(reinterpret_cast<const char*>(p_ + pos_), n);
  pos_ += n;
  return true;
}

bool Reader::End(const char* record) {
  if (!ok_) return false;
  if (left() == 0) return true;
  return Fail(std::string(record) + ": " + std::to_string(left()) +
              " bytes left over after offset " + std::to_string(pos_));
}
