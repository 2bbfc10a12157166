#include "ffcodec.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "check.h"

namespace proto {
namespace {

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

// The float of a 16-bit code (not the escape): its exponent and fraction
// bits, rebased.
inline uint32_t F16FloatBits(uint32_t code) { return (code << 12) + kF16FloatBias; }

}  // namespace

// The count, the id runs, then the form factors, 2 bytes each (5 for an
// escape), with error diffusion: each value is coded as its form factor plus the
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
  PutVarint(out, n);
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
  for (size_t i = 0; i < n;) {
    size_t j = i + 1;
    while (j < n && ff[j].elem == ff[j - 1].elem + 1) ++j;
    PutVarint(out, uint64_t(ff[i].elem - end));  // >= 1 after the first run
    PutVarint(out, j - i - 1);
    end = int64_t(ff[j - 1].elem) + 1;
    i = j;
  }

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

// Eight entries {id + j, the form factor of 16-bit code j} at out, the
// codes little-endian at c, as four 16-byte stores (GCC's vector
// extensions: SSE2 on x86-64), each from its register (made as an array,
// GCC built the four on the stack and copied them from there: 7% of
// decoding); bit 31 of a lane of *zero set by a code 0 (0 - 1).
namespace {
typedef uint32_t U32x4 __attribute__((vector_size(16)));
typedef uint16_t U16x8 __attribute__((vector_size(16)));
static_assert(sizeof(FormFactor) == 8 && offsetof(FormFactor, f) == 4, "{elem, f}");
inline void PutEight(FormFactor* out, uint32_t id, const uint8_t* c, U32x4* zero) {
  U16x8 codes;
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  std::memcpy(&codes, c, sizeof codes);
#else
  for (int j = 0; j < 8; ++j) codes[j] = uint16_t(c[2 * j] | c[2 * j + 1] << 8);
#endif
  const U32x4 lo = __builtin_convertvector(__builtin_shufflevector(codes, codes, 0, 1, 2, 3), U32x4);
  const U32x4 hi = __builtin_convertvector(__builtin_shufflevector(codes, codes, 4, 5, 6, 7), U32x4);
  *zero |= (lo - 1) | (hi - 1);
  const U32x4 flo = (lo << 12) + kF16FloatBias, fhi = (hi << 12) + kF16FloatBias;  // F16FloatBits
  const U32x4 ilo = id + U32x4{0, 1, 2, 3}, ihi = ilo + 4;
  const U32x4 e0 = __builtin_shufflevector(ilo, flo, 0, 4, 1, 5);
  const U32x4 e1 = __builtin_shufflevector(ilo, flo, 2, 6, 3, 7);
  const U32x4 e2 = __builtin_shufflevector(ihi, fhi, 0, 4, 1, 5);
  const U32x4 e3 = __builtin_shufflevector(ihi, fhi, 2, 6, 3, 7);
  std::memcpy(out, &e0, 16);
  std::memcpy(out + 2, &e1, 16);
  std::memcpy(out + 4, &e2, 16);
  std::memcpy(out + 6, &e3, 16);
}
}  // namespace

int32_t SentCode(float f) {
  // A decoded 16-bit code's value is exact: the nearest code is itself.
  return f > 0 && F16Range(FfCode(f)) ? int32_t(F16Round(double(f))) : -1;
}

// The hot path: tight loops over the bytes, one allocation, no strings
// unless it fails. One pass over the runs checks them and writes their
// ids, and, in the usual case of a column without escapes, where the
// codes are the last 2 bytes per form factor, each id's form factor with
// it (PutEight: the ids' stores written whole, and no second pass over
// the list). Whether that case holds is known only after the runs (they
// end where the codes begin); when it does not (escapes, or bytes that
// are no column), the general path writes every form factor again.
bool GetFormFactors(Reader* r, std::vector<FormFactor>* out_ff) {
  uint64_t n, runs;
  if (!r->Count(2, &n, "form factor count")) return false;
  if (!r->Count(2, &runs, "run count")) return false;
  if (runs > n)
    return r->Fail("run count " + std::to_string(runs) + " is more than the " +
                   std::to_string(n) + " form factors");

  const uint8_t* const base = r->data();
  const uint8_t* const end = base + r->pos() + r->left();
  const uint8_t* const runs_at = base + r->pos();
  auto at = [&](const uint8_t* q) { return std::to_string(q - base); };

  // A run's ids are written kShort at a time whatever its length (most
  // runs are a patch's few elements): a loop of the run's length would
  // mispredict its exit at nearly every run. What is written past the
  // run is overwritten by the next run's ids, or lies in the kShort - 1
  // entries of scratch past the n form factors.
  constexpr size_t kShort = 8;
  out_ff->resize(size_t(n) + kShort - 1);
  FormFactor* const ff = out_ff->data();

  // Where the codes are if the column has no escapes; ff[0, fused) have
  // their form factors from there.
  const uint8_t* const guess = uint64_t(end - runs_at) >= 2 * n ? end - 2 * n : nullptr;
  uint64_t fused = 0;
  U32x4 zero = {0, 0, 0, 0};

  // Runs: (gap, length - 1) each; checked, and their ids written.
  const uint8_t* p = runs_at;
  uint64_t next = 0;  // one past the previous run's last id
  uint64_t filled = 0;
  for (uint64_t k = 0; k < runs; ++k) {
    const uint8_t* const gap_at = p;
    uint64_t gap, len1;
    // Most runs are a gap below 128 and a length below 129, a byte each
    // (91% and all but 0.1% on a room of 10,000 boxes): one test for both.
    if (end - p >= 2 && ((p[0] | p[1]) & 0x80) == 0) {
      gap = p[0];
      len1 = p[1];
      p += 2;
    } else {
      if (GetVarint(&p, end, &gap) != VarintStatus::kOk || gap > INT32_MAX) {
        r->Seek(size_t(gap_at - base));
        r->Varint(INT32_MAX, &gap, "run gap");  // fails, and says why
        return false;
      }
      const uint8_t* const len_at = p;
      if (GetVarint(&p, end, &len1) != VarintStatus::kOk || len1 > INT32_MAX) {
        r->Seek(size_t(len_at - base));
        r->Varint(INT32_MAX, &len1, "run length - 1");
        return false;
      }
    }
    if (gap == 0 && k > 0)
      return r->Fail("run " + std::to_string(k) + " at offset " + at(gap_at) +
                     " has gap 0: it continues the previous run (runs must be maximal)");
    const uint64_t len = len1 + 1;
    if (len > n - filled)
      return r->Fail("run " + std::to_string(k) + " at offset " + at(gap_at) + " makes " +
                     std::to_string(filled + len) + " ids, more than the " + std::to_string(n) +
                     " form factors");
    const uint32_t id = uint32_t(next + gap);
    next += gap + len;
    if (next - 1 > uint64_t(INT32_MAX))
      return r->Fail("run " + std::to_string(k) + " at offset " + at(gap_at) + ": element id " +
                     std::to_string(next - 1) + " is out of range (max " +
                     std::to_string(INT32_MAX) + ")");
    FormFactor* const out = ff + filled;
    if (guess && filled + kShort <= n) {  // then so were all runs before
      PutEight(out, id, guess + 2 * filled, &zero);
      for (uint32_t j = kShort; j < len; ++j) {
        const uint32_t code = uint32_t(guess[2 * (filled + j)]) | uint32_t(guess[2 * (filled + j) + 1]) << 8;
        zero[0] |= code - 1;
        const uint32_t bits = F16FloatBits(code);
        out[j].elem = int32_t(id + j);
        std::memcpy(&out[j].f, &bits, 4);
      }
      fused = filled + len;
    } else {
      for (uint32_t j = 0; j < kShort; ++j) out[j].elem = int32_t(id + j);
      for (uint32_t j = kShort; j < len; ++j) out[j].elem = int32_t(id + j);
    }
    filled += len;
  }
  if (filled != n)
    return r->Fail("runs make " + std::to_string(filled) + " ids for " + std::to_string(n) +
                   " form factors");
  const uint8_t* const codes_at = p;
  if (uint64_t(end - codes_at) < 2 * n)
    return r->Fail("truncated: " + std::to_string(n) + " form factors need at least " +
                   std::to_string(2 * n) + " bytes at offset " + at(codes_at) + ", " +
                   std::to_string(end - codes_at) + " left");
  out_ff->resize(size_t(n));

  if (codes_at == guess) {
    // No room for an escape: the rest in one pass. A code 0 (an escape
    // without its 3 bytes) is noted and reported by the general path.
    uint32_t any_zero = zero[0] | zero[1] | zero[2] | zero[3];  // bit 31 set by code 0 (0 - 1)
    for (size_t i = size_t(fused); i < n; ++i) {
      const uint32_t code = uint32_t(codes_at[2 * i]) | uint32_t(codes_at[2 * i + 1]) << 8;
      any_zero |= code - 1;
      const uint32_t bits = F16FloatBits(code);
      std::memcpy(&ff[i].f, &bits, 4);
    }
    if (!(any_zero >> 31)) {
      r->Seek(size_t(end - base));
      return true;
    }
  }

  // The general path: form factors with escapes, every byte checked.
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
      return r->Fail("truncated: form factor " + std::to_string(i) + " needs 2 bytes at offset " +
                     at(p) + ", " + std::to_string(end - p) + " left");
    // The escape: a 24-bit code outside the 16-bit codes' range.
    if (end - p < 5)
      return r->Fail("truncated: escaped form factor " + std::to_string(i) +
                     " needs 5 bytes at offset " + at(p) + ", " + std::to_string(end - p) +
                     " left");
    const uint32_t q = uint32_t(p[2]) | uint32_t(p[3]) << 8 | uint32_t(p[4]) << 16;
    if (q < kFfMin) return r->Fail("form factor " + std::to_string(i) + " is 0");
    if (q >= kFfLimit) return r->Fail("form factor " + std::to_string(i) + " is inf or NaN");
    if (F16Range(q))
      return r->Fail("form factor " + std::to_string(i) + " at offset " + at(p) +
                     " is escaped but has a 16-bit code");
    ff[i].f = FfValue(q);
    p += 5;
    ++i;
  }
  if (p != end)
    return r->Fail("column: " + std::to_string(end - p) + " bytes left over after offset " +
                   at(p));
  r->Seek(size_t(end - base));
  return true;
}


}  // namespace proto
