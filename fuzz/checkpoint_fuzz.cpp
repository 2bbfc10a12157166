// libFuzzer target: checkpoint values after a valid hash (checkpoint.h).
// The input is a checkpoint's payload; the target adds the header and the
// SHA-256 that make it pass the checksum, as an edited and re-hashed file
// would. What DecodeCheckpoint then accepts must hold only values a run
// could write (finite radiosity, counts within the mesh and the shots),
// and must encode again to the same bytes.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "checkpoint.h"
#include "coding.h"
#include "crypto.h"

namespace {

bool Finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string file("RADCKPT\n", 8);
  PutFixed32(&file, kCheckpointVersion);
  PutFixed32(&file, 0);
  PutFixed64(&file, size);
  file.append(reinterpret_cast<const char*>(data), size);
  file += Sha256Of(file);
  Checkpoint c;
  std::string err;
  if (!DecodeCheckpoint(file, &c, &err)) {
    if (err.empty()) std::abort();
    return 0;
  }
  const SolverState& s = c.solver;
  if (s.b.size() != c.elements || s.unshot.size() != c.patches || s.shots < 0) std::abort();
  for (const glm::dvec3& v : s.b)
    if (!Finite(v)) std::abort();
  for (const glm::dvec3& v : s.unshot)
    if (!Finite(v)) std::abort();
  for (int32_t p : c.run.pending)
    if (p < 0 || uint64_t(p) >= c.patches) std::abort();
  if (!std::isfinite(c.run.seconds) || c.run.seconds < 0 || c.run.wave < 1) std::abort();
  if (EncodeCheckpoint(c) != file) std::abort();
  return 0;
}
