// The form factors of a column on the wire (doc/protocol.txt, "column"):
// element ids as runs of consecutive ids, form factors as 11-bit codes
// with 7 significant bits (rounding error 2^-7, kFormFactorRounding), each
// sent as its difference from the one before in one byte or two, and
// error diffusion (the rounding residual carried on, largest exponents
// first), so that each decoded form factor is within kFormFactorError
// (2^-5) of its own, and the decoded column sum within kColumnSumError
// (one code step, 2^-6) of the largest form factor of the true sum, in
// practice far closer. Values outside the 11-bit codes (below 2^-31, or 2
// and more) are escaped to a 24-bit code (relative error 2^-17).
#ifndef RADIOSITY_FFCODEC_H
#define RADIOSITY_FFCODEC_H

#include <cstdint>
#include <string>
#include <vector>

#include "coding.h"
#include "hemicube.h"

namespace proto {

// Column coding bounds. Per form factor F and its decoded F':
// |F' - F| <= kFormFactorError F. Per column:
// |sum F' - sum F| <= kColumnSumError (1 + kFormFactorError) max F, plus
// 2^-17 F for each F below 2^-31 (escaped) and the rounding of the sums
// themselves. kFormFactorRounding is the rounding of one 11-bit code (half
// its step): the scale of a form factor's typical error.
constexpr double kFormFactorError = 1.0 / (1 << 5);
constexpr double kFormFactorRounding = 1.0 / (1 << 7);
constexpr double kColumnSumError = 1.0 / (1 << 6);

// Appends the count, the id runs and the codes of `ff` (increasing elem,
// f > 0 and finite: CHECKed).
void PutFormFactors(const std::vector<FormFactor>& ff, std::string* out);

// Reads what PutFormFactors wrote from r to the end of its bytes (the
// column's last field), into *ff; false with r's error when the bytes are
// not exactly such a list. The master's hot path.
bool GetFormFactors(Reader* r, std::vector<FormFactor>* ff);

// The 11-bit code a decoded form factor was sent as, or -1 for one sent
// escaped (outside the 11-bit codes' range): what a column's codes are,
// read back from its values (bench/ffbytes.cpp weighs codings of them).
int32_t SentCode(float f);

}  // namespace proto

#endif
