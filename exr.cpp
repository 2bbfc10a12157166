// The OpenEXR writer (exr.h), through tinyexr: Debian's libtinyexr-dev is
// one header and a small library on zlib, and it encodes to memory, which
// the staged, atomic writes of files.h need.
#include "exr.h"

#include <tinyexr.h>

#include <cstdlib>
#include <cstring>
#include <vector>

#include "check.h"
#include "files.h"

bool WriteOpenExr(const Image& img, const std::string& path, std::string* err) {
  CHECK(img.width > 0 && img.height > 0 &&
        img.pixels.size() == size_t(img.width) * img.height);
  const size_t n = img.pixels.size();
  // Planes in the channel order of the file: B, G, R (alphabetical, as
  // OpenEXR readers expect).
  std::vector<float> planes[3];
  for (int c = 0; c < 3; ++c) {
    planes[c].resize(n);
    for (size_t i = 0; i < n; ++i) planes[c][i] = img.pixels[i][2 - c];
  }
  float* ptrs[3] = {planes[0].data(), planes[1].data(), planes[2].data()};
  EXRImage image;
  InitEXRImage(&image);
  image.images = reinterpret_cast<unsigned char**>(ptrs);
  image.width = img.width;
  image.height = img.height;
  image.num_channels = 3;

  EXRChannelInfo channels[3];
  std::memset(channels, 0, sizeof channels);
  for (int c = 0; c < 3; ++c) channels[c].name[0] = "BGR"[c];
  int types[3] = {TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT, TINYEXR_PIXELTYPE_FLOAT};
  EXRHeader header;
  InitEXRHeader(&header);
  header.num_channels = 3;
  header.channels = channels;
  header.pixel_types = types;            // as given
  header.requested_pixel_types = types;  // as stored
  header.compression_type = TINYEXR_COMPRESSIONTYPE_ZIP;

  unsigned char* mem = nullptr;
  const char* why = nullptr;
  const size_t size = SaveEXRImageToMemory(&image, &header, &mem, &why);
  if (size == 0) {
    *err = path + ": cannot encode OpenEXR" + (why ? std::string(": ") + why : "");
    if (why) FreeEXRErrorMessage(why);
    std::free(mem);
    return false;
  }
  const std::string bytes(reinterpret_cast<const char*>(mem), size);
  std::free(mem);
  return WriteFileAtomic(path, bytes, err);
}
