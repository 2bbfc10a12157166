#include "ffcodec.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define FFCODEC_SSSE3 1
#endif

#include "check.h"

namespace proto {
namespace {

// Form factor <-> 24 bits: the float's bits (sign 0) >> 7, rounded to
// nearest (ties away from zero); never 0 and never inf/NaN. Only for the
// escape of a column's 11-bit codes (below).
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

// Form factor <-> 11 bits: code = e << 6 | m stands for
// (1 + m / 64) 2^(e - 31), e in 0..31, m in 0..63. The code is the
// float's (or double's) exponent and top 6 fraction bits with the
// exponent rebased, so codes are in the order of their values and code + 1
// is the next value. Code 0 (2^-31) is the escape instead: a 24-bit code
// follows. A value has an 11-bit code exactly when its 24-bit code is
// within those of code 1 and kCodeMax, so that each value has one coding.
// Why 6 fraction bits: the hemicube's own error per element (it covers a
// whole number of pixels) is far above a code step, 2^-6; with the
// rounding carried on (below) the answer moves far less than with the
// hemicube's seed (README, "Bytes per form factor"), and the differences
// of codes this coarse mostly fit in one byte. With 7 bits (protocol 6)
// 26% to 32% of the differences took two bytes at R 64, and the maze and
// the room took 1.63 and 1.54 bytes a form factor there; with 6, 5% to
// 11% do.
constexpr int kFractionBits = 6;
constexpr uint32_t kEscape = 0;
constexpr uint32_t kCodeMax = (32u << kFractionBits) - 1;                 // 2047: 2 - 2^-6
constexpr uint32_t kFloatBias = 96u << 23;                                // 127 - 31, in a float's exponent field
constexpr uint64_t kDoubleBias = uint64_t(1023 - 31) << kFractionBits;   // in the code's exponent field
constexpr int kDoubleShift = 52 - kFractionBits;                          // a double's fraction bits not in the code

// The float of a code (not the escape): its exponent and fraction bits,
// rebased.
constexpr uint32_t CodeFloatBits(uint32_t code) { return (code << (23 - kFractionBits)) + kFloatBias; }

// The 24-bit codes of the values of codes 1 (2^-31 (1 + 2^-6)) and
// kCodeMax (2 - 2^-6): the range sent as 11-bit codes.
constexpr uint32_t kLo24 = CodeFloatBits(1) >> 7;
constexpr uint32_t kHi24 = CodeFloatBits(kCodeMax) >> 7;

bool CodeRange(uint32_t code24) { return code24 >= kLo24 && code24 <= kHi24; }

// The value of a code (not the escape), exactly.
double CodeValue(uint32_t code) {
  return BitsDouble((uint64_t(code) + kDoubleBias) << kDoubleShift);
}

// The code nearest to x > 0 (ties up), clamped to 1 .. kCodeMax.
uint32_t CodeRound(double x) {
  const int64_t q = int64_t((DoubleBits(x) + (uint64_t(1) << (kDoubleShift - 1))) >> kDoubleShift) - int64_t(kDoubleBias);
  return uint32_t(std::min<int64_t>(std::max<int64_t>(q, 1), kCodeMax));
}

// Codes on the wire: each code's difference d from the code before it in
// the column (the previous one not escaped; 0 before the first). A short
// one, -kShortBias <= d < kShortBias, is one byte d + kShortBias (below
// kShortCodes); a long one two: kShortCodes + (v >> 8) and v & 0xff, with
// v = kLongBias + d - kShortBias for d >= kShortBias and v = kLongBias + d
// + kShortBias for d < -kShortBias (0 .. 4095 holds every difference of
// two codes), so that two bytes never stand for a short difference and
// each column has one coding. The first bytes of all codes come first,
// then the second bytes and the escapes: the decoder reads code i's first
// byte at i, and no branch on its length. Neighbouring elements of a
// patch have near form factors, so most differences are short: 89% of
// them on the maze at R 64, 95% on the room (radiosity-ffbytes).
constexpr uint32_t kShortCodes = 240;
constexpr int32_t kShortBias = kShortCodes / 2;
constexpr int32_t kLongBias = 32 << kFractionBits;  // 2048
static_assert((256 - kShortCodes) << 8 == 2 * kLongBias, "two bytes hold every difference of codes");

// A run of ids on the wire: one varint of gap << kRunLenBits | min(length -
// 1, kRunLenMore), and the length - 1 - kRunLenMore in a second one where
// it is kRunLenMore or more. Protocol 6 sent the gap and the length - 1 as
// two varints, two bytes a run at least: on a room of 3,800 boxes, whose
// columns are runs of 2.5 ids, that was 0.82 bytes a form factor, 0.54
// now (3 bits of length: 2 took 0.56, 4 0.63).
constexpr int kRunLenBits = 3;
constexpr uint64_t kRunLenMore = (1u << kRunLenBits) - 1;

#ifdef FFCODEC_SSSE3
// Eight codes at a time, with SSSE3 (checked at run time: the build is
// for plain x86-64): the second bytes spread to the long ones' lanes by a
// shuffle, the differences summed up in 16-bit lanes, and the form
// factors stored beside the ids the runs wrote. From form factor i, while
// a whole group's bytes are there; stops at a group with a code that is
// not 1 .. kCodeMax (an escape, or bytes that are no column), which the
// scalar loop then decodes. Returns where it stopped; *x and *last move on.
// Within 8 bytes of the end it goes on too (below): the last long
// differences of a column are spread over many groups (11% of them are
// long on the maze at R 64), and stopping where fewer than 8 second bytes
// were left gave the scalar loop a tenth of the maze's groups.
// Decoding a column took 3.4 to 4.6 ns a form factor with the scalar loop
// alone, 1.5 to 2.0 with this (radiosity-ffbytes, shipped scenes, R 256).

// kSpread[m][j]: where in the second bytes lane j's is, for lanes whose
// bit is set in m (the long ones), or 0x80 (a zero).
constexpr std::array<std::array<uint8_t, 8>, 256> MakeSpread() {
  std::array<std::array<uint8_t, 8>, 256> t{};
  for (unsigned m = 0; m < 256; ++m)
    for (unsigned j = 0, k = 0; j < 8; ++j) t[m][j] = m >> j & 1 ? uint8_t(k++) : uint8_t(0x80);
  return t;
}
alignas(8) constexpr std::array<std::array<uint8_t, 8>, 256> kSpread = MakeSpread();

__attribute__((target("ssse3,popcnt"))) size_t DecodeEights(const uint8_t* p, size_t size, size_t n,
                                                            size_t i, size_t* x_io, uint32_t* last_io,
                                                            FormFactor* ff) {
  size_t x = *x_io;
  const __m128i zero = _mm_setzero_si128();
  __m128i last = _mm_set1_epi16(int16_t(*last_io));
  for (; i + 8 <= n; i += 8) {
    const __m128i b0 = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(p + i));
    const __m128i long8 = _mm_cmpgt_epi8(_mm_xor_si128(b0, _mm_set1_epi8(char(0x80))),
                                         _mm_set1_epi8(char((kShortCodes - 1) ^ 0x80)));
    const unsigned m = unsigned(_mm_movemask_epi8(long8)) & 0xff;
    const unsigned longs = unsigned(_mm_popcnt_u32(m));
    __m128i spread = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(kSpread[m].data()));
    const uint8_t* second = p + x;
    if (x + 8 > size) {
      if (x + longs > size) break;  // truncated: the scalar loop says so
      // Near the end the 8 bytes are loaded from size - 8 (size >= n >= 8)
      // and the spread's indices moved on by as many (the zeros' high bit
      // stays set): no load past the end.
      second = p + size - 8;
      spread = _mm_add_epi8(spread, _mm_set1_epi8(char(x + 8 - size)));
    }
    const __m128i b1 = _mm_shuffle_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(second)), spread);
    const __m128i w0 = _mm_unpacklo_epi8(b0, zero), w1 = _mm_unpacklo_epi8(b1, zero);
    const __m128i is_long = _mm_unpacklo_epi8(long8, long8);
    const __m128i d_short = _mm_sub_epi16(w0, _mm_set1_epi16(kShortBias));
    const __m128i v = _mm_or_si128(_mm_slli_epi16(_mm_sub_epi16(w0, _mm_set1_epi16(kShortCodes)), 8), w1);
    const __m128i up = _mm_and_si128(_mm_cmpgt_epi16(v, _mm_set1_epi16(kLongBias - 1)),
                                     _mm_set1_epi16(2 * kShortBias));
    const __m128i d_long = _mm_add_epi16(_mm_sub_epi16(v, _mm_set1_epi16(kLongBias + kShortBias)), up);
    __m128i c = _mm_or_si128(_mm_andnot_si128(is_long, d_short), _mm_and_si128(is_long, d_long));
    c = _mm_add_epi16(c, _mm_slli_si128(c, 2));  // the sums of the differences so far
    c = _mm_add_epi16(c, _mm_slli_si128(c, 4));
    c = _mm_add_epi16(c, _mm_slli_si128(c, 8));
    c = _mm_add_epi16(c, last);
    // Every lane in 1 .. kCodeMax, else the scalar loop. (A lane's true
    // sum is within 65536 - kCodeMax of 0, so 16 bits wrap none into range.)
    const __m128i ok = _mm_and_si128(_mm_cmpgt_epi16(c, zero),
                                     _mm_cmplt_epi16(c, _mm_set1_epi16(int16_t(kCodeMax + 1))));
    if (_mm_movemask_epi8(ok) != 0xffff) break;
    last = _mm_shufflehi_epi16(c, 0xff);
    last = _mm_unpackhi_epi64(last, last);
    x += longs;
    // CodeFloatBits: the code shifted by 23 - kFractionBits - 16 in its
    // 16-bit lane (it fits), then as a 32-bit lane's top half.
    static_assert((kCodeMax << (23 - kFractionBits - 16)) <= 0xffff, "codes fit in their floats' top halves");
    const __m128i top = _mm_slli_epi16(c, 23 - kFractionBits - 16);
    const __m128i bias = _mm_set1_epi32(int32_t(kFloatBias));
    const __m128i flo = _mm_add_epi32(_mm_unpacklo_epi16(zero, top), bias);
    const __m128i fhi = _mm_add_epi32(_mm_unpackhi_epi16(zero, top), bias);
    const __m128i ids = _mm_set1_epi64x(0xffffffff);
    __m128i* const o = reinterpret_cast<__m128i*>(ff + i);
    // Each store from its register: as an array and a loop, GCC built the
    // four on the stack and copied them from there (decoding 1.3 ns a
    // form factor on the blender room then took 1.6 to 1.9).
    auto put = [&](int k, __m128i f) {
      _mm_storeu_si128(o + k, _mm_or_si128(_mm_and_si128(_mm_loadu_si128(o + k), ids), f));
    };
    put(0, _mm_unpacklo_epi32(zero, flo));
    put(1, _mm_unpackhi_epi32(zero, flo));
    put(2, _mm_unpacklo_epi32(zero, fhi));
    put(3, _mm_unpackhi_epi32(zero, fhi));
  }
  *x_io = x;
  *last_io = uint32_t(uint16_t(_mm_cvtsi128_si32(last)));
  return i;
}
#endif
// Eight entries {id + j, 0} at out, as four 16-byte stores (GCC's vector
// extensions: SSE2 on x86-64), each from its register: half the stores of
// eight ids alone, and most runs are a few ids.
typedef uint32_t U32x4 __attribute__((vector_size(16)));
static_assert(sizeof(FormFactor) == 8 && offsetof(FormFactor, f) == 4, "{elem, f}");
inline void PutIds(FormFactor* out, uint32_t id) {
  const U32x4 e0 = id + U32x4{0, 0, 1, 0}, e1 = e0 + U32x4{2, 0, 2, 0};
  const U32x4 e2 = e0 + U32x4{4, 0, 4, 0}, e3 = e0 + U32x4{6, 0, 6, 0};
  std::memcpy(out, &e0, 16);
  std::memcpy(out + 2, &e1, 16);
  std::memcpy(out + 4, &e2, 16);
  std::memcpy(out + 6, &e3, 16);
}

}  // namespace

// The count, the id runs, then the codes (one or two bytes each, and 3
// more for an escape), with error diffusion: each value is coded as its
// form factor plus the rounding residual carried so far, clamped to within
// kFormFactorError of the form factor, and the residual of that (target
// minus coded value) is carried on, so the coded sum differs from the true
// sum by the last residual only. The form factors are visited from the
// largest exponent down (in id order within one exponent), so that what
// is left at the end is a rounding step of the smallest ones: |sum F' -
// sum F| is at most 2^-6 of the largest form factor, and in practice far
// less (doc/protocol.txt). Escaped values are coded alone; their (tiny)
// error is carried too. The residual is exact enough in double. The
// visiting order and the codes are kept in the thread's scratch, reused
// from column to column.
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
    // The gap (>= 1 after the first run) and the length - 1 up to 7 in one
    // varint, the rest of a longer length in another.
    const uint64_t gap = uint64_t(ff[i].elem - end), len1 = j - i - 1;
    PutVarint(out, gap << kRunLenBits | std::min<uint64_t>(len1, kRunLenMore));
    if (len1 >= kRunLenMore) PutVarint(out, len1 - kRunLenMore);
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
  static thread_local std::vector<uint32_t> order, codes;
  order.resize(n);
  codes.resize(n);
  for (size_t i = 0; i < n; ++i) {
    uint32_t bits;
    std::memcpy(&bits, &ff[i].f, 4);
    order[first[255 - (bits >> 23)]++] = uint32_t(i);
  }

  // The codes, by id: 11 bits, or kEscaped | the 24-bit code.
  constexpr uint32_t kEscaped = 1u << 31;
  double carry = 0;
  for (uint32_t i : order) {
    const double x = ff[i].f;
    const uint32_t c24 = FfCode(ff[i].f);
    if (!CodeRange(c24)) {
      codes[i] = kEscaped | c24;
      carry += x - double(FfValue(c24));
      continue;
    }
    // x has 24 significant bits, so lo and hi are exact.
    const double lo = x - x * kFormFactorError, hi = x + x * kFormFactorError;
    const double target = x + carry;
    uint32_t q = CodeRound(std::min(std::max(target, lo), hi));
    double v = CodeValue(q);
    // Rounding may step just outside [lo, hi]: take the neighbour inside.
    if (v > hi) v = CodeValue(--q);
    else if (v < lo) v = CodeValue(++q);
    CHECK(q >= 1 && q <= kCodeMax && v >= lo && v <= hi);
    codes[i] = q;
    carry = target - v;
  }

  // The differences, in id order: n first bytes, then the second bytes of
  // the long ones and the escapes' 24-bit codes.
  auto difference = [](uint32_t q, uint32_t* last) {
    const uint32_t code = q & kEscaped ? kEscape : q;
    const int32_t d = int32_t(code) - int32_t(*last);
    if (!(q & kEscaped)) *last = code;
    return d;
  };
  auto is_short = [](int32_t d) { return d >= -kShortBias && d < kShortBias; };
  size_t extra = 0;
  uint32_t last = 0;
  for (uint32_t q : codes) {
    extra += is_short(difference(q, &last)) ? 0 : 1;
    if (q & kEscaped) extra += 3;
  }
  const size_t start = out->size();
  out->resize(start + n + extra);
  uint8_t* p = reinterpret_cast<uint8_t*>(&(*out)[start]);
  uint8_t* x = p + n;
  last = 0;
  for (uint32_t q : codes) {
    const int32_t d = difference(q, &last);
    if (is_short(d)) {
      *p++ = uint8_t(d + kShortBias);
    } else {
      const uint32_t v = uint32_t(kLongBias + (d >= 0 ? d - kShortBias : d + kShortBias));
      *p++ = uint8_t(kShortCodes + (v >> 8));
      *x++ = uint8_t(v);
    }
    if (q & kEscaped) {
      x[0] = uint8_t(q);
      x[1] = uint8_t(q >> 8);
      x[2] = uint8_t(q >> 16);
      x += 3;
    }
  }
}

int32_t SentCode(float f) {
  // A decoded code's value is exact: the nearest code is itself.
  return f > 0 && CodeRange(FfCode(f)) ? int32_t(CodeRound(double(f))) : -1;
}

// The hot path: tight loops over the bytes, one allocation at most (none
// once *out_ff has held a column as long), no strings unless it fails.
// One pass over the runs checks them and writes their ids, one over the
// codes their form factors.
bool GetFormFactors(Reader* r, std::vector<FormFactor>* out_ff) {
  uint64_t n, runs;
  if (!r->Count(1, &n, "form factor count")) return false;
  if (!r->Count(1, &runs, "run count")) return false;
  if (runs > n)
    return r->Fail("run count " + std::to_string(runs) + " is more than the " +
                   std::to_string(n) + " form factors");

  const uint8_t* const base = r->data();
  const uint8_t* const end = base + r->pos() + r->left();
  auto at = [&](const uint8_t* q) { return std::to_string(q - base); };

  // A run's ids are written kShort at a time whatever its length (most
  // runs are a patch's few elements): a loop of the run's length would
  // mispredict its exit at nearly every run. What is written past the
  // run is overwritten by the next run's ids, or lies in the kShort - 1
  // entries of scratch past the n form factors.
  constexpr size_t kShort = 8;
  out_ff->resize(size_t(n) + kShort - 1);
  FormFactor* const ff = out_ff->data();

  // Runs: gap << 3 | min(length - 1, 7), and length - 8 when that is 7;
  // checked, and their ids written.
  const uint8_t* p = base + r->pos();
  // A varint at p, p past it; else false, with the Reader's own message
  // for it at its offset.
  auto varint = [&](uint64_t* v, const char* what) {
    const uint8_t* const at = p;
    if (GetVarint(&p, end, v) == VarintStatus::kOk) return true;
    r->Seek(size_t(at - base));
    r->Varint(UINT64_MAX, v, what);  // fails, and says why
    return false;
  };
  uint64_t next = 0;  // one past the previous run's last id
  uint64_t filled = 0;
  for (uint64_t k = 0; k < runs; ++k) {
    const uint8_t* const gap_at = p;
    uint64_t gap, len1;
    // Most runs are a head of one or two bytes (a gap below 2048) and a
    // length below 8, or its rest in one byte: read without a branch on
    // which (a branch per run on the head's length alone, taken at random
    // on a room of boxes, made decoding half as slow again as protocol
    // 6's). The rest, and what is no shortest varint, below.
    bool quick = false;
    if (end - p >= 3) {
      const uint32_t b0 = p[0], b1 = p[1];
      const uint32_t two = b0 >> 7;  // the head's second byte is there
      const uint64_t head = (b0 & 0x7f) | ((b1 << 7) & (0u - two));
      const uint32_t at = 1 + two;
      const uint32_t more = (head & kRunLenMore) == kRunLenMore;
      const uint32_t b2 = p[at];
      // A second byte must end the varint and not be 0 (shortest form);
      // so must the rest's one byte.
      if (((two & ((b1 >> 7) | (b1 == 0))) | (more & (b2 >> 7))) == 0) {
        gap = head >> kRunLenBits;
        len1 = (head & kRunLenMore) + (b2 & (0u - more));
        p += at + more;
        quick = true;
      }
    }
    if (!quick) {
      uint64_t head;
      if (!varint(&head, "run gap and length")) return false;
      gap = head >> kRunLenBits;
      len1 = head & kRunLenMore;
      if (gap > INT32_MAX)
        return r->Fail("run gap " + std::to_string(gap) + " is out of range (max " +
                       std::to_string(INT32_MAX) + ")");
      if (len1 == kRunLenMore) {
        uint64_t more;
        if (!varint(&more, "run length - 8")) return false;
        if (more > INT32_MAX - kRunLenMore)
          return r->Fail("run length - 1 " + std::to_string(more + kRunLenMore) +
                         " is out of range (max " + std::to_string(INT32_MAX) + ")");
        len1 += more;
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
    PutIds(out, id);
    for (uint32_t j = kShort; j < len; ++j) out[j].elem = int32_t(id + j);
    filled += len;
  }
  if (filled != n)
    return r->Fail("runs make " + std::to_string(filled) + " ids for " + std::to_string(n) +
                   " form factors");
  if (uint64_t(end - p) < n)
    return r->Fail("truncated: " + std::to_string(n) + " form factors need at least " +
                   std::to_string(n) + " bytes at offset " + at(p) + ", " +
                   std::to_string(end - p) + " left");
  out_ff->resize(size_t(n));

  // The codes: first bytes at p[i], the rest from p[x] on. Without a
  // branch on the difference's length (10% to 28% are long on the shipped
  // scenes, at random: such a branch made decoding 4.2 to 6.3 ns a form
  // factor against 3.4 to 4.6 without); x may run past the bytes (size),
  // read at the last byte then, and is checked once at the end.
  const size_t size = size_t(end - p);
  size_t x = size_t(n);
  uint32_t last = 0;
#ifdef FFCODEC_SSSE3
  static const bool simd = __builtin_cpu_supports("ssse3") && __builtin_cpu_supports("popcnt");
#endif
  for (size_t i = 0; i < n;) {
#ifdef FFCODEC_SSSE3
    if (simd && (i = DecodeEights(p, size, n, i, &x, &last, ff)) == n) break;
#endif
    // Eight (or what is left) one at a time: the group DecodeEights
    // stopped at, or the last few.
    for (const size_t stop = std::min<size_t>(n, i + 8); i < stop; ++i) {
    const uint32_t b0 = p[i], b1 = p[std::min(x, size - 1)];
    const uint32_t is_long = b0 >= kShortCodes;
    const int32_t d_short = int32_t(b0) - kShortBias;
    const int32_t v = int32_t((b0 - kShortCodes) << 8 | b1);
    const int32_t d_long = v - kLongBias - kShortBias + 2 * kShortBias * (v >= kLongBias);
    const int32_t d = d_short ^ ((d_short ^ d_long) & -int32_t(is_long));
    x += is_long;
    const uint32_t code = last + uint32_t(d);
    if (code - 1 < kCodeMax) {  // 1 .. kCodeMax: a value
      last = code;
      const uint32_t bits = CodeFloatBits(code);
      std::memcpy(&ff[i].f, &bits, 4);
      continue;
    }
    if (code != kEscape)  // differences of two bytes below -2047 or above 2047 too
      return r->Fail("form factor " + std::to_string(i) + " at offset " + at(p + i) + ": code " +
                     std::to_string(int32_t(code)) + " is out of range (1 .. " +
                     std::to_string(kCodeMax) + ")");
    // The escape: a 24-bit code outside the 11-bit codes' range.
    if (x > size || size - x < 3)
      return r->Fail("truncated: escaped form factor " + std::to_string(i) +
                     " needs 3 bytes at offset " + at(p + std::min(x, size)) + ", " +
                     std::to_string(x > size ? 0 : size - x) + " left");
    const uint32_t q = uint32_t(p[x]) | uint32_t(p[x + 1]) << 8 | uint32_t(p[x + 2]) << 16;
    if (q < kFfMin) return r->Fail("form factor " + std::to_string(i) + " is 0");
    if (q >= kFfLimit) return r->Fail("form factor " + std::to_string(i) + " is inf or NaN");
    if (CodeRange(q))
      return r->Fail("form factor " + std::to_string(i) + " at offset " + at(p + x) +
                     " is escaped but has an 11-bit code");
    ff[i].f = FfValue(q);
    x += 3;
    }
  }
  if (x > size)
    return r->Fail("truncated: the form factors' second bytes need " + std::to_string(x - size) +
                   " more bytes after offset " + at(end));
  p += x;
  if (p != end)
    return r->Fail("column: " + std::to_string(end - p) + " bytes left over after offset " +
                   at(p));
  r->Seek(size_t(end - base));
  return true;
}

}  // namespace proto
