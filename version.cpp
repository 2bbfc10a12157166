#include "version.h"

#include <cstring>

namespace proto {

std::string BuildId() {
  std::string id =
      std::string("radiosity ") + kRadiosityVersion + " proto " + std::to_string(kVersion) + " ";
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

}  // namespace proto
