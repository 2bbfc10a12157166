// Unit tests of the OpenEXR writer (exr.h), read back with tinyexr's
// reader, and of a whole run's linear pictures: final.exr and final.hdr
// (image.cpp's RGBE, read with stbi_loadf) against result.csv on a face of
// known, uniform radiosity.
#include "exr.h"

#include <stb_image.h>
#include <tinyexr.h>

#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "app.h"
#include "options.h"
#include "temp_dir.h"

namespace {

// A picture as read back: RGB per pixel, row 0 at the top.
struct Read {
  int width = 0, height = 0;
  std::vector<glm::vec3> pixels;
  glm::vec3 at(int x, int y) const { return pixels[size_t(y) * width + x]; }
};

Read ReadHdr(const std::string& path) {
  Read r;
  int channels = 0;
  float* data = stbi_loadf(path.c_str(), &r.width, &r.height, &channels, 3);
  EXPECT_NE(data, nullptr) << path << ": " << stbi_failure_reason();
  if (!data) return r;
  for (size_t i = 0; i < size_t(r.width) * r.height; ++i)
    r.pixels.emplace_back(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
  stbi_image_free(data);
  return r;
}

Read ReadExr(const std::string& path) {
  Read r;
  float* rgba = nullptr;
  const char* err = nullptr;
  const int status = LoadEXR(&rgba, &r.width, &r.height, path.c_str(), &err);
  EXPECT_EQ(status, TINYEXR_SUCCESS) << path << ": " << (err ? err : "");
  if (err) FreeEXRErrorMessage(err);
  if (status != TINYEXR_SUCCESS) return r;
  for (size_t i = 0; i < size_t(r.width) * r.height; ++i)
    r.pixels.emplace_back(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]);
  std::free(rgba);
  return r;
}

// RGBE keeps 8 bits of mantissa under the largest channel's exponent and
// stb rounds down: each channel within max(R, G, B) / 128 below the float.
void ExpectRgbe(const glm::vec3& got, const glm::vec3& want, const std::string& where) {
  const float step = std::max({want.r, want.g, want.b}) / 128;
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(got[k], want[k]) << where << " channel " << k;
    EXPECT_GE(got[k], want[k] - step) << where << " channel " << k;
  }
}

// Values over the range radiosity takes (Ke is in the scene's units, up
// to 1e30), a black pixel, unequal channels, and a different value in
// every pixel so that a flipped or transposed picture shows.
Image TestImage() {
  Image img;
  img.width = 5;
  img.height = 3;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float v = float(1 + x + 10 * y);
      img.pixels.emplace_back(v * 1e-3f, v, v * 1e3f);
    }
  img.pixels[0] = glm::vec3(0.0f);
  img.pixels[1] = glm::vec3(17, 12, 4);     // the Cornell light's Ke
  img.pixels[2] = glm::vec3(1e-20f, 0, 3e30f);
  return img;
}

TEST(Exr, RoundTripIsExact) {
  TempDir dir;
  const Image img = TestImage();
  std::string err;
  const std::string path = dir.path() + "/t.exr";
  ASSERT_TRUE(WriteOpenExr(img, path, &err)) << err;
  const Read r = ReadExr(path);
  ASSERT_EQ(r.width, img.width);
  ASSERT_EQ(r.height, img.height);
  EXPECT_EQ(r.pixels, img.pixels);  // 32-bit float: the same floats

  // One pixel, and a picture of many ZIP blocks (16 rows each).
  for (const auto& [w, h] : {std::pair<int, int>{1, 1}, {300, 70}}) {
    Image big;
    big.width = w;
    big.height = h;
    for (int i = 0; i < w * h; ++i) big.pixels.emplace_back(float(i % 977) / 7, 0.25f, float(i));
    ASSERT_TRUE(WriteOpenExr(big, path, &err)) << err;
    EXPECT_EQ(ReadExr(path).pixels, big.pixels) << w << "x" << h;
  }
}

TEST(Exr, WriteErrorsNameTheFile) {
  const Image img = TestImage();
  std::string err;
  EXPECT_FALSE(WriteOpenExr(img, "/nonexistent/dir/final.exr", &err));
  EXPECT_EQ(err.rfind("/nonexistent/dir/final.exr: ", 0), 0u) << err;
}

// The face's B in result.csv (face,object,area,B_r,B_g,B_b).
glm::vec3 CsvRadiosity(const std::string& csv, int face) {
  std::ifstream in(csv);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
    if (f.size() == 6 && f[0] == std::to_string(face))
      return glm::vec3(std::stof(f[3]), std::stof(f[4]), std::stof(f[5]));
  }
  ADD_FAILURE() << csv << ": no row for face " << face;
  return glm::vec3(-1.0f);
}

// A whole run, -j 0, --format exr: the camera looks straight at a light of
// Kd 0, whose B is exactly its Ke everywhere (a flat-lit face: every
// element, every vertex and every pixel of it the same), filling the
// middle of the picture; a floor below the view takes its light, so the
// solver has work. The light's pixels must be its result.csv row: the
// EXR's floats within float rounding (the interpolation of three equal
// vertex colours, relative 1e-6), final.hdr within RGBE's step; what the
// camera does not see is 0 in both.
TEST(Exr, FinalPicturesMatchResultCsvOnAFlatLitFace) {
  TempDir dir;
  dir.Write("s.mtl", "newmtl light\nKd 0\nKe 0.5 2 7\nnewmtl white\nKd 0.8\n");
  const std::string scene = dir.Write(
      "s.obj",
      "mtllib s.mtl\n"
      "# camera 0.5 0.5 -2  0.5 0.5 0  30\n"
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "v 0 -0.2 0\nv 1 -0.2 0\nv 1 -0.2 -1\nv 0 -0.2 -1\n"
      "usemtl light\nf 1 4 3 2\n"      // facing -z, the camera
      "usemtl white\nf 5 8 7 6\n");    // facing +y, lit, out of view
  const std::string out = dir.path() + "/out";
  std::vector<std::string> args = {"radiosity", "-j", "0", "-q", "-r", "16", "--size", "64x48",
                                    "--format", "exr", "-o", out, scene};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  Options opts;
  std::string err;
  ASSERT_EQ(ParseOptions(int(args.size()), argv.data(), &opts, &err), Parsed::kRun) << err;
  // The run takes SIGINT, SIGTERM and SIGHUP and ignores SIGPIPE, as main's
  // does; the test process gets its own handlers back after it.
  const int kSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE};
  struct sigaction saved[4];
  for (int i = 0; i < 4; ++i) sigaction(kSignals[i], nullptr, &saved[i]);
  {
    MasterRun run(opts);
    run.Build();
    run.Run();
    run.WriteOutputs();
  }
  for (int i = 0; i < 4; ++i) sigaction(kSignals[i], &saved[i], nullptr);
  const glm::vec3 b = CsvRadiosity(out + "/result.csv", 0);
  EXPECT_EQ(b, glm::vec3(0.5f, 2.0f, 7.0f));
  EXPECT_FALSE(std::filesystem::exists(out + "/final.png"));
  EXPECT_TRUE(std::filesystem::exists(out + "/frame-01.exr"));

  const Read exr = ReadExr(out + "/final.exr"), hdr = ReadHdr(out + "/final.hdr");
  ASSERT_EQ(exr.width, 64);
  ASSERT_EQ(exr.height, 48);
  ASSERT_EQ(hdr.width, 64);
  ASSERT_EQ(hdr.height, 48);
  // The light spans 0.5 / (2 tan 15 deg) = 93% of the height, centred:
  // the middle half of the picture is all light, the corners of the width
  // (wider than high) see nothing.
  int checked = 0;
  for (int y = 12; y < 36; ++y)
    for (int x = 16; x < 48; ++x, ++checked) {
      const std::string where = "pixel " + std::to_string(x) + "," + std::to_string(y);
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(exr.at(x, y)[k], b[k], 1e-6 * b[k]) << where;
      ExpectRgbe(hdr.at(x, y), b, where);
    }
  EXPECT_EQ(checked, 24 * 32);
  for (const auto& [x, y] : {std::pair<int, int>{0, 0}, {63, 0}, {0, 47}, {63, 47}}) {
    EXPECT_EQ(exr.at(x, y), glm::vec3(0.0f));
    EXPECT_EQ(hdr.at(x, y), glm::vec3(0.0f));
  }
}

}  // namespace
