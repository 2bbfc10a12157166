// OpenEXR pictures (--format exr): the radiosity the camera sees, as it
// is (no exposure, no clamp, no sRGB curve), for tone mapping and for
// reading lighting values off the picture.
#ifndef RADIOSITY_EXR_H
#define RADIOSITY_EXR_H

#include <string>

#include "image.h"

// Channels B, G, R as 32-bit float, ZIP compressed (tinyexr): the
// picture's floats exactly. Float, not half: half ends at 65504 and Ke is
// in the scene's own units (up to 1e30). Encoded in memory and written
// with WriteFileAtomic (files.h) like every output. False with
// *err = "PATH: what".
bool WriteOpenExr(const Image& img, const std::string& path, std::string* err);

#endif
