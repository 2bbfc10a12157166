#include "image.h"

#include <stb_image.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

namespace {

// Appends a polygon (3 or 4 vertices, in the given order) with one colour
// per vertex.
void AddPoly(ShadedMesh* m, std::vector<glm::dvec3> ps, std::vector<glm::vec3> cs) {
  std::array<int, 4> q{-1, -1, -1, -1};
  for (size_t i = 0; i < ps.size(); ++i) {
    q[i] = int(m->own.size());
    m->own.push_back(ps[i]);
    m->colors.push_back(cs.size() == 1 ? cs[0] : cs[i]);
  }
  m->polys.push_back(q);
}

// A square of side 2·HALF in the plane z = Z, centred on (CX, CY), facing +z.
void AddSquare(ShadedMesh* m, double cx, double cy, double z, double half, glm::vec3 c) {
  AddPoly(m, {{cx - half, cy - half, z}, {cx + half, cy - half, z},
              {cx + half, cy + half, z}, {cx - half, cy + half, z}}, {c});
}

Camera Cam(glm::dvec3 eye, glm::dvec3 target, double fov = 45) {
  Camera c;
  c.eye = eye;
  c.target = target;
  c.fov_deg = fov;
  return c;
}

bool Lit(const glm::vec3& p) { return p.r > 0 || p.g > 0 || p.b > 0; }

int CountLit(const Image& img) {
  int n = 0;
  for (const auto& p : img.pixels) n += Lit(p);
  return n;
}

const glm::vec3& At(const Image& img, int x, int y) {
  return img.pixels[size_t(y) * img.width + x];
}

// In a convex shape, the lit pixels of every row and column are contiguous.
void ExpectNoHoles(const Image& img) {
  for (int pass = 0; pass < 2; ++pass) {
    const int lines = pass ? img.width : img.height;
    const int len = pass ? img.height : img.width;
    for (int l = 0; l < lines; ++l) {
      int first = -1, last = -1, lit = 0;
      for (int i = 0; i < len; ++i) {
        if (Lit(pass ? At(img, l, i) : At(img, i, l))) {
          if (first < 0) first = i;
          last = i;
          ++lit;
        }
      }
      if (first >= 0) {
        EXPECT_EQ(lit, last - first + 1) << (pass ? "column " : "row ") << l;
      }
    }
  }
}

std::string ReadAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

class ImageFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/image_test.XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string dir_;
};

TEST(Image, FrontQuadFillsProjectedArea) {
  ShadedMesh m;
  AddSquare(&m, 0, 0, 0, 1, glm::vec3(1));
  Image img;
  Render(m, Cam({0, 0, 5}, {0, 0, 0}), 200, 200, &img);
  ASSERT_EQ(img.width, 200);
  ASSERT_EQ(img.height, 200);
  ASSERT_EQ(img.pixels.size(), 200u * 200u);
  // Half side 1 at distance 5 is 1 / (5 tan 22.5°) of the half-height (100 px).
  const double side = 2 * 100 / (5 * std::tan(glm::radians(22.5)));
  EXPECT_NEAR(CountLit(img), side * side, 0.03 * side * side);
  EXPECT_TRUE(Lit(At(img, 100, 100)));
  EXPECT_FALSE(Lit(At(img, 0, 0)));
  EXPECT_FALSE(Lit(At(img, 199, 199)));
  EXPECT_FLOAT_EQ(At(img, 100, 100).g, 1.0f);
  ExpectNoHoles(img);
}

TEST(Image, BackFacingQuadDrawsNothing) {
  ShadedMesh m;
  AddPoly(&m, {{-1, -1, 0}, {-1, 1, 0}, {1, 1, 0}, {1, -1, 0}}, {glm::vec3(1)});
  AddPoly(&m, {{-1, -1, 1}, {1, 1, 1}, {1, -1, 1}}, {glm::vec3(1)});
  Image img;
  Render(m, Cam({0, 0, 5}, {0, 0, 0}), 64, 64, &img);
  EXPECT_EQ(CountLit(img), 0);
  // The same quads seen from behind are front faces.
  Render(m, Cam({0, 0, -5}, {0, 0, 0}), 64, 64, &img);
  EXPECT_GT(CountLit(img), 0);
}

TEST(Image, Orientation) {
  ShadedMesh m;
  AddSquare(&m, 1, 0, 0, 0.4, {1, 0, 0});   // right
  AddSquare(&m, -1, 0, 0, 0.4, {0, 1, 0});  // left
  AddSquare(&m, 0, 1, 0, 0.4, {0, 0, 1});   // top
  Image img;
  Render(m, Cam({0, 0, 5}, {0, 0, 0}), 101, 101, &img);
  EXPECT_EQ(At(img, 75, 50), glm::vec3(1, 0, 0));
  EXPECT_EQ(At(img, 25, 50), glm::vec3(0, 1, 0));
  EXPECT_EQ(At(img, 50, 25), glm::vec3(0, 0, 1));
  EXPECT_FALSE(Lit(At(img, 50, 75)));

  // Straight down: the far side (-z) at the top, +x still on the right.
  ShadedMesh floor;
  AddPoly(&floor, {{-1, 0, -2}, {-1, 0, -1}, {1, 0, -1}, {1, 0, -2}}, {glm::vec3(1, 0, 0)});
  AddPoly(&floor, {{0.5, 0, -0.5}, {0.5, 0, 0.5}, {1.5, 0, 0.5}, {1.5, 0, -0.5}}, {glm::vec3(0, 1, 0)});
  Render(floor, Cam({0, 10, 0}, {0, 0, 0}), 101, 101, &img);
  EXPECT_EQ(At(img, 50, 32), glm::vec3(1, 0, 0));
  EXPECT_EQ(At(img, 60, 50), glm::vec3(0, 1, 0));
  EXPECT_FALSE(Lit(At(img, 50, 80)));
  EXPECT_FALSE(Lit(At(img, 40, 50)));
}

TEST(Image, SharedEdgesLeaveNoCracks) {
  ShadedMesh m;
  // Two quads whose union is convex, sharing a slanted edge.
  AddPoly(&m, {{-1, -1, 0}, {0.3, -1.1, 0}, {0.2, 1.05, 0}, {-1, 1, 0}}, {glm::vec3(1)});
  AddPoly(&m, {{0.3, -1.1, 0}, {1, -1, 0}, {1.1, 1, 0}, {0.2, 1.05, 0}}, {glm::vec3(1)});
  Image img;
  Render(m, Cam({0.1, 0.2, 3}, {0, 0, 0}), 256, 256, &img);
  EXPECT_GT(CountLit(img), 1000);
  ExpectNoHoles(img);

  // A square made of a grid of quads with jittered inner vertices, seen at
  // an angle: every pixel inside must be covered.
  ShadedMesh grid;
  const int n = 24;
  std::vector<glm::dvec3> v((n + 1) * (n + 1));
  std::srand(7);
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      glm::dvec2 p(-1 + 2.0 * i / n, -1 + 2.0 * j / n);
      if (i > 0 && i < n && j > 0 && j < n)
        p += (glm::dvec2(std::rand(), std::rand()) / double(RAND_MAX) - 0.5) * (0.6 / n);
      v[j * (n + 1) + i] = {p.x, p.y, 0};
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int k = j * (n + 1) + i;
      AddPoly(&grid, {v[k], v[k + 1], v[k + n + 2], v[k + n + 1]}, {glm::vec3(0.5f)});
    }
  }
  Render(grid, Cam({0.7, 0.9, 2.5}, {0, 0, 0}), 300, 200, &img);
  EXPECT_GT(CountLit(img), 10000);
  ExpectNoHoles(img);
}

TEST(Image, NearerHidesFartherInAnyOrder) {
  ShadedMesh a, b;
  AddSquare(&a, 0, 0, 0, 1, {1, 0, 0});
  AddSquare(&a, 0, 0, 1, 0.5, {0, 1, 0});
  AddSquare(&b, 0, 0, 1, 0.5, {0, 1, 0});
  AddSquare(&b, 0, 0, 0, 1, {1, 0, 0});
  Image ia, ib;
  Render(a, Cam({0, 0, 5}, {0, 0, 0}), 101, 101, &ia);
  Render(b, Cam({0, 0, 5}, {0, 0, 0}), 101, 101, &ib);
  EXPECT_EQ(At(ia, 50, 50), glm::vec3(0, 1, 0));
  EXPECT_EQ(At(ia, 50, 30), glm::vec3(1, 0, 0));
  EXPECT_EQ(ia.pixels, ib.pixels);
}

TEST(Image, GouraudRampIsMonotonic) {
  ShadedMesh m;
  AddPoly(&m, {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}},
          {glm::vec3(0), glm::vec3(1), glm::vec3(1), glm::vec3(0)});
  Image img;
  Render(m, Cam({0, 0, 4}, {0, 0, 0}), 128, 128, &img);
  float prev = -1;
  int lit = 0;
  for (int x = 0; x < img.width; ++x) {
    const glm::vec3& p = At(img, x, 64);
    if (!(p.r > 0)) continue;
    if (lit == 0) {
      EXPECT_LT(p.r, 0.05f);
    }
    EXPECT_GE(p.r, prev) << "x " << x;
    EXPECT_LE(p.r, 1.0f + 1e-5f);
    prev = p.r;
    ++lit;
  }
  EXPECT_GT(lit, 50);
  EXPECT_GT(prev, 0.95f);
}

TEST(Image, InterpolationIsPerspectiveCorrect) {
  // A floor receding from z = -1 (colour 0) to z = -5 (colour 1); its
  // middle, z = -3, is at the centre of the picture and has colour 0.5.
  ShadedMesh m;
  AddPoly(&m, {{-1, 0, -1}, {1, 0, -1}, {1, 0, -5}, {-1, 0, -5}},
          {glm::vec3(0), glm::vec3(0), glm::vec3(1), glm::vec3(1)});
  Image img;
  Render(m, Cam({0, 1, 0}, {0, 0, -3}), 101, 101, &img);
  EXPECT_NEAR(At(img, 50, 50).r, 0.5f, 0.01f);
}

TEST(Image, PolygonCrossingNearPlaneIsClipped) {
  // A large floor extending behind the eye: it must appear below the
  // horizon only, never wrapped into the sky.
  ShadedMesh m;
  AddPoly(&m, {{-20, 0, 20}, {20, 0, 20}, {20, 0, -20}, {-20, 0, -20}}, {glm::vec3(1)});
  Image img;
  Render(m, Cam({0, 1, 0}, {0, 1, -1}), 120, 100, &img);
  for (int y = 0; y < 50; ++y)
    for (int x = 0; x < 120; ++x) ASSERT_FALSE(Lit(At(img, x, y))) << x << "," << y;
  for (int y = 60; y < 100; ++y)
    for (int x = 0; x < 120; ++x) ASSERT_TRUE(Lit(At(img, x, y))) << x << "," << y;
}

TEST(Image, ScaleInvariant) {
  auto scene = [](double s, ShadedMesh* m, Camera* cam) {
    *m = ShadedMesh();
    AddPoly(m, {{-1.3 * s, -0.7 * s, 0.1 * s}, {1.1 * s, -0.9 * s, -0.2 * s},
                {0.9 * s, 1.2 * s, 0.3 * s}, {-1.1 * s, 0.8 * s, 0.2 * s}},
            {glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, 1), glm::vec3(1)});
    AddPoly(m, {{-0.37 * s, -0.41 * s, 0.9 * s}, {0.53 * s, -0.29 * s, 0.8 * s},
                {0.11 * s, 0.63 * s, 1.1 * s}}, {glm::vec3(0.3f)});
    // A floor reaching behind the eye.
    AddPoly(m, {{-9 * s, -1.5 * s, 9 * s}, {9 * s, -1.5 * s, 9 * s},
                {9 * s, -1.5 * s, -9 * s}, {-9 * s, -1.5 * s, -9 * s}}, {glm::vec3(0.7f)});
    *cam = Cam(glm::dvec3(0.31, 0.77, 3.3) * s, glm::dvec3(0.05, -0.1, 0) * s, 50);
  };
  ShadedMesh m;
  Camera cam;
  scene(1, &m, &cam);
  Image ref;
  Render(m, cam, 160, 120, &ref);
  EXPECT_GT(CountLit(ref), 5000);
  for (double s : {1e-4, 1e4}) {
    scene(s, &m, &cam);
    Image img;
    Render(m, cam, 160, 120, &img);
    int differ = 0;
    for (size_t i = 0; i < img.pixels.size(); ++i) {
      differ += Lit(img.pixels[i]) != Lit(ref.pixels[i]);
      EXPECT_NEAR(img.pixels[i].r, ref.pixels[i].r, 1e-4) << i;
    }
    EXPECT_EQ(differ, 0) << "scale " << s;
  }
}

TEST(Image, FrameBoxFitsTheBox) {
  for (double s : {1e-4, 1.0, 1e4}) {
    const glm::dvec3 lo = glm::dvec3(-1, 0, -3) * s, hi = glm::dvec3(2, 1.5, 1) * s;
    const Camera cam = FrameBox(lo, hi);
    EXPECT_EQ(cam.fov_deg, 45);
    EXPECT_EQ(cam.target, 0.5 * (lo + hi));
    EXPECT_GT(cam.eye.z, hi.z);
    EXPECT_GT(cam.eye.y, cam.target.y);
    // The box's outward faces: lit, but not up to the border.
    ShadedMesh m;
    const double x0 = lo.x, y0 = lo.y, z0 = lo.z, x1 = hi.x, y1 = hi.y, z1 = hi.z;
    AddPoly(&m, {{x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}}, {glm::vec3(1)});
    AddPoly(&m, {{x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}}, {glm::vec3(1)});
    AddPoly(&m, {{x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}}, {glm::vec3(1)});
    AddPoly(&m, {{x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}}, {glm::vec3(1)});
    Image img;
    Render(m, cam, 100, 100, &img);
    EXPECT_GT(CountLit(img), 2500);
    for (int i = 0; i < 100; ++i) {
      EXPECT_FALSE(Lit(At(img, i, 0)) || Lit(At(img, i, 99)) || Lit(At(img, 0, i)) ||
                   Lit(At(img, 99, i)));
    }
  }
  const Camera point = FrameBox(glm::dvec3(1), glm::dvec3(1));
  EXPECT_GT(glm::length(point.eye - point.target), 0);
}

TEST(Image, AutoExposure) {
  ShadedMesh empty;
  EXPECT_EQ(AutoExposure(empty), 1.0f);
  ShadedMesh black;
  AddSquare(&black, 0, 0, 0, 1, glm::vec3(0));
  EXPECT_EQ(AutoExposure(black), 1.0f);

  // A large wall of luminance 1 and a small, very bright light: the wall
  // decides, in any units.
  for (float unit : {1e-6f, 1.0f, 1e6f, 1e30f}) {
    ShadedMesh m;
    AddSquare(&m, 0, 0, 0, 5, glm::vec3(unit));
    AddSquare(&m, 0, 0, 1, 0.5, glm::vec3(1000 * unit));
    const float e = AutoExposure(m);
    EXPECT_TRUE(std::isfinite(e) && e > 0);
    EXPECT_NEAR(e * unit, 0.8f, 1e-3f) << unit;
  }

  // Only the light is lit yet: it is shown at 0.8.
  ShadedMesh dark;
  AddSquare(&dark, 0, 0, 0, 5, glm::vec3(0));
  AddSquare(&dark, 0, 0, 1, 0.5, glm::vec3(0, 1e6f, 0));
  EXPECT_NEAR(AutoExposure(dark) * 0.7152f * 1e6f, 0.8f, 1e-3f);

  ShadedMesh huge;
  AddSquare(&huge, 0, 0, 0, 1, glm::vec3(std::numeric_limits<float>::max()));
  const float e = AutoExposure(huge);
  EXPECT_TRUE(std::isfinite(e) && e > 0);
  ShadedMesh tiny;
  AddSquare(&tiny, 0, 0, 0, 1, glm::vec3(std::numeric_limits<float>::denorm_min()));
  const float t = AutoExposure(tiny);
  EXPECT_TRUE(std::isfinite(t) && t > 0);
}

// The exposure as one sort of every weighted vertex's (luminance, weight)
// finds it: what AutoExposure does a run of luminances at a time.
float ExposureBySort(const ShadedMesh& mesh) {
  std::vector<std::pair<double, double>> lw(mesh.positions().size());
  for (size_t i = 0; i < lw.size(); ++i) {
    const glm::dvec3 c(mesh.colors[i]);
    double lum = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
    if (!std::isfinite(lum) || lum < 0) lum = 0;
    lw[i] = {lum, 0.0};
  }
  for (const auto& q : mesh.polys) {
    const int n = q[3] < 0 ? 3 : 4;
    // image.cpp's PolyArea.
    const auto& p = mesh.positions();
    const glm::dvec3 d = n == 3 ? glm::cross(p[size_t(q[1])] - p[size_t(q[0])], p[size_t(q[2])] - p[size_t(q[0])])
                                : glm::cross(p[size_t(q[2])] - p[size_t(q[0])], p[size_t(q[3])] - p[size_t(q[1])]);
    const double a = 0.5 * glm::length(d);
    if (!std::isfinite(a)) continue;
    for (int k = 0; k < n; ++k) lw[size_t(q[k])].second += a / n;
  }
  lw.erase(std::remove_if(lw.begin(), lw.end(), [](const auto& x) { return !(x.second > 0); }),
           lw.end());
  double total = 0, brightest = 0;
  for (const auto& [lum, w] : lw) {
    total += w;
    brightest = std::max(brightest, lum);
  }
  std::sort(lw.begin(), lw.end());
  double level = 0, sum = 0;
  for (const auto& [lum, w] : lw) {
    sum += w;
    level = lum;
    if (sum >= 0.95 * total) break;
  }
  if (!(level > 0)) level = brightest;
  if (!(level > 0)) return 1.0f;
  return float(std::clamp(0.8 / level, double(std::numeric_limits<float>::min()),
                          double(std::numeric_limits<float>::max())));
}

// Grids of quads sharing their corners (weights summed from up to four),
// uneven cells, luminances with ties, zeros, NaN, a few bright ones, most
// of them close together (one bin of many values) or not, and vertices no
// polygon uses (bright, and left out): the same exposure, to the bit, as
// the sort of all of them.
TEST(Image, AutoExposureIsTheWeightedPercentileOfASort) {
  std::mt19937 rng(7);
  for (int n : {2, 9, 70})
    for (float spread : {1.0f / 7, 1e-6f})
      for (int palette : {1, 5, 1000}) {
        ShadedMesh m;
        std::uniform_real_distribution<double> jitter(0.0, 0.4);
        std::uniform_int_distribution<int> pick(0, palette - 1);
        for (int y = 0; y <= n; ++y)
          for (int x = 0; x <= n; ++x) {
            m.own.push_back({x + jitter(rng), y + jitter(rng), 0});
            const int c = pick(rng);
            const float v = c == 0 ? 0.0f : c == 1 ? NAN : c < 4 ? 1000.0f : 0.5f + float(c) * spread;
            m.colors.push_back(glm::vec3(v, v / 2, c % 3 ? v : 0.0f));
          }
        for (int y = 0; y < n; ++y)
          for (int x = 0; x < n; ++x) {
            const int a = y * (n + 1) + x;
            m.polys.push_back({a, a + 1, a + n + 2, (x + y) % 5 ? a + n + 1 : -1});
          }
        for (int k = 0; k < 10; ++k) {
          m.own.push_back({0, 0, 1});
          m.colors.push_back(glm::vec3(1e6f));
        }
        EXPECT_EQ(AutoExposure(m), ExposureBySort(m)) << n << " " << spread << " " << palette;
      }
}

// The codes change where the sRGB curve (IEC 61966-2-1) crosses k - 0.5
// of 255: those points from the curve's inverse, and each code checked a
// hair either side of its boundary, at several exposures, then at a
// million random values against the count of boundaries below them.
TEST(Image, EncodeSrgb8IsTheCurveRounded) {
  std::vector<double> edge(256, 0.0);  // edge[k]: where k - 1 becomes k
  for (int k = 1; k < 256; ++k) {
    const double s = (k - 0.5) / 255;
    edge[size_t(k)] = s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
  }
  for (float exposure : {1.0f, 0.37f, 2.0f, 1000.0f}) {
    for (int k = 1; k < 256; ++k) {
      const float below = float(edge[size_t(k)] * (1 - 1e-6) / exposure);
      const float above = float(edge[size_t(k)] * (1 + 1e-6) / exposure);
      EXPECT_EQ(EncodeSrgb8(below, exposure), k - 1) << k << " at exposure " << exposure;
      EXPECT_EQ(EncodeSrgb8(above, exposure), k) << k << " at exposure " << exposure;
    }
  }
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> log_v(-12, 0.1);
  for (int i = 0; i < 1000000; ++i) {
    const float v = float(std::pow(10.0, log_v(rng)));
    const auto at = std::upper_bound(edge.begin() + 1, edge.end(), double(v));
    const double near = std::min(at == edge.end() ? 1.0 : *at, 1.0);
    if (std::abs(double(v) - near) < 1e-6 * near || std::abs(double(v) - at[-1]) < 1e-6 * at[-1])
      continue;  // a hair from a boundary: checked above
    const int want = v >= 1 ? 255 : int(at - edge.begin()) - 1;
    ASSERT_EQ(EncodeSrgb8(v, 1.0f), want) << v;
  }
  EXPECT_EQ(EncodeSrgb8(0.0f, 1.0f), 0);
  EXPECT_EQ(EncodeSrgb8(-1.0f, 1.0f), 0);
  EXPECT_EQ(EncodeSrgb8(std::nanf(""), 1.0f), 0);
  EXPECT_EQ(EncodeSrgb8(1.0f, 1.0f), 255);
  EXPECT_EQ(EncodeSrgb8(0.5f, 4.0f), 255);
}

TEST_F(ImageFiles, WriteImagePpmAndPng) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Image img;
  img.width = 3;
  img.height = 2;
  img.pixels = {glm::vec3(0.5f), glm::vec3(nan, 0, 1), glm::vec3(2, -1, 0.001f),
                glm::vec3(0.25f), glm::vec3(0), glm::vec3(1)};

  const std::string ppm = dir_ + "/a.ppm";
  std::string err;
  ASSERT_TRUE(WriteImage(img, 1.0f, {ppm}, "ppm", &err)) << err;
  const std::string bytes = ReadAll(ppm);
  const std::string header = "P6\n3 2\n255\n";
  ASSERT_EQ(bytes.size(), header.size() + 3 * 2 * 3);
  EXPECT_EQ(bytes.substr(0, header.size()), header);
  const std::vector<int> expect = {188, 188, 188, 0, 0, 255, 255, 0, 3,
                                   137, 137, 137, 0, 0, 0, 255, 255, 255};
  for (size_t i = 0; i < expect.size(); ++i)
    EXPECT_EQ(uint8_t(bytes[header.size() + i]), expect[i]) << i;

  // Exposure 2 brings 0.25 to 0.5.
  ASSERT_TRUE(WriteImage(img, 2.0f, {ppm}, "ppm", &err)) << err;
  EXPECT_EQ(uint8_t(ReadAll(ppm)[header.size() + 9]), 188);

  const std::string png = dir_ + "/a.png";
  // Two paths: one picture, encoded once.
  const std::string png2 = dir_ + "/b.png";
  ASSERT_TRUE(WriteImage(img, 1.0f, {png, png2}, "png", &err)) << err;
  EXPECT_GT(std::filesystem::file_size(png), 0u);
  EXPECT_EQ(ReadAll(png2), ReadAll(png));
  int w = 0, h = 0, comp = 0;
  unsigned char* data = stbi_load(png.c_str(), &w, &h, &comp, 3);
  ASSERT_NE(data, nullptr);
  EXPECT_EQ(w, 3);
  EXPECT_EQ(h, 2);
  for (size_t i = 0; i < expect.size(); ++i) EXPECT_EQ(data[i], expect[i]) << i;
  stbi_image_free(data);

  const std::string bad = dir_ + "/missing/a.png";
  EXPECT_FALSE(WriteImage(img, 1.0f, {bad}, "png", &err));
  EXPECT_EQ(err.rfind(bad + ": ", 0), 0u) << err;
  EXPECT_FALSE(WriteImage(img, 1.0f, {bad}, "ppm", &err));
  EXPECT_EQ(err.rfind(bad + ": ", 0), 0u) << err;
  EXPECT_FALSE(WriteImage(img, 1.0f, {dir_ + "/a.jpg"}, "jpg", &err));
  EXPECT_NE(err.find("jpg"), std::string::npos) << err;
}

// final.hdr: the picture linear, as RGBE, read back with stb's reader.
// Each channel within max(R, G, B) / 128 below the float (8-bit mantissas
// under the largest channel's exponent, rounded down), over the range
// radiosity takes (Ke is in the scene's units); row 0 at the top.
TEST_F(ImageFiles, WriteRadianceHdr) {
  Image img;
  img.width = 3;
  img.height = 2;
  img.pixels = {glm::vec3(0),     glm::vec3(17, 12, 4),     glm::vec3(1e-20f, 0, 3e30f),
                glm::vec3(0.25f), glm::vec3(1e-3f, 1, 1e3f), glm::vec3(0.5f, 2, 7)};
  const std::string path = dir_ + "/a.hdr";
  std::string err;
  ASSERT_TRUE(WriteRadianceHdr(img, path, &err)) << err;
  EXPECT_EQ(ReadAll(path).rfind("#?RADIANCE\n", 0), 0u);
  int w = 0, h = 0, comp = 0;
  float* data = stbi_loadf(path.c_str(), &w, &h, &comp, 3);
  ASSERT_NE(data, nullptr) << stbi_failure_reason();
  EXPECT_EQ(w, 3);
  EXPECT_EQ(h, 2);
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    const glm::vec3& want = img.pixels[i];
    const float step = std::max({want.r, want.g, want.b}) / 128;
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE(data[3 * i + k], want[k]) << "pixel " << i << " channel " << k;
      EXPECT_GE(data[3 * i + k], want[k] - step) << "pixel " << i << " channel " << k;
    }
  }
  stbi_image_free(data);

  const std::string bad = dir_ + "/missing/a.hdr";
  EXPECT_FALSE(WriteRadianceHdr(img, bad, &err));
  EXPECT_EQ(err.rfind(bad + ": ", 0), 0u) << err;
}

TEST_F(ImageFiles, WritePly) {
  ShadedMesh m;
  AddPoly(&m, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}},
          {glm::vec3(0.5f, 0, 1), glm::vec3(1), glm::vec3(1), glm::vec3(1)});
  AddPoly(&m, {{0, 0, 1e-4}, {2.5, 0, 1e-4}, {0, 3, 1e-4}}, {glm::vec3(0.25f)});
  const std::string path = dir_ + "/m.ply";
  std::string err;
  ASSERT_TRUE(WritePly(m, 1.0f, path, &err)) << err;

  std::istringstream in(ReadAll(path));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "ply");
  std::getline(in, line);
  EXPECT_EQ(line, "format ascii 1.0");
  int nv = -1, nf = -1;
  while (std::getline(in, line) && line != "end_header") {
    std::sscanf(line.c_str(), "element vertex %d", &nv);
    std::sscanf(line.c_str(), "element face %d", &nf);
  }
  ASSERT_EQ(line, "end_header");
  ASSERT_EQ(nv, 7);
  ASSERT_EQ(nf, 2);
  std::vector<glm::dvec3> pos;
  std::vector<glm::ivec3> col;
  for (int i = 0; i < nv; ++i) {
    double x, y, z;
    int r, g, b;
    ASSERT_TRUE(in >> x >> y >> z >> r >> g >> b);
    pos.push_back({x, y, z});
    col.push_back({r, g, b});
  }
  EXPECT_EQ(col[0], glm::ivec3(188, 0, 255));
  EXPECT_EQ(col[4], glm::ivec3(137));
  EXPECT_EQ(glm::vec3(pos[5]), glm::vec3(2.5f, 0, 1e-4f));
  int count, a, b, c, d;
  ASSERT_TRUE(in >> count >> a >> b >> c >> d);
  EXPECT_EQ(glm::ivec4(count, a, b, c), glm::ivec4(4, 0, 1, 2));
  EXPECT_EQ(d, 3);
  ASSERT_TRUE(in >> count >> a >> b >> c);
  EXPECT_EQ(glm::ivec4(count, a, b, c), glm::ivec4(3, 4, 5, 6));
  std::string rest;
  EXPECT_FALSE(in >> rest);

  const std::string bad = dir_ + "/missing/m.ply";
  EXPECT_FALSE(WritePly(m, 1.0f, bad, &err));
  EXPECT_EQ(err.rfind(bad + ": ", 0), 0u) << err;
}

TEST_F(ImageFiles, WriteGltf) {
  ShadedMesh m;
  AddPoly(&m, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}},
          {glm::vec3(0.5f, 0, 2), glm::vec3(1), glm::vec3(1), glm::vec3(1)});
  AddPoly(&m, {{0, 0, 1e-4}, {2.5, 0, 1e-4}, {0, 3, 1e-4}}, {glm::vec3(0.25f)});
  const std::string gltf = dir_ + "/m.gltf", bin = dir_ + "/m.bin";
  std::string err;
  ASSERT_TRUE(WriteGltf(m, 1.0f, gltf, bin, &err)) << err;

  // 7 vertices: positions and colours, 7 x 12 bytes each; the quad as two
  // triangles and the triangle: 9 indices of 4 bytes.
  const std::string data = ReadAll(bin);
  ASSERT_EQ(data.size(), 7u * 12 + 7u * 12 + 9u * 4);
  std::vector<float> pos(21), col(21);
  std::vector<uint32_t> idx(9);
  std::memcpy(pos.data(), data.data(), 84);
  std::memcpy(col.data(), data.data() + 84, 84);
  std::memcpy(idx.data(), data.data() + 168, 36);
  EXPECT_EQ(glm::vec3(pos[15], pos[16], pos[17]), glm::vec3(2.5f, 0, 1e-4f));
  // Linear, exposed and clamped to [0, 1]: glTF colours are linear.
  EXPECT_EQ(glm::vec3(col[0], col[1], col[2]), glm::vec3(0.5f, 0, 1));
  EXPECT_EQ(col[12], 0.25f);
  EXPECT_EQ(idx, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 4, 5, 6}));

  const std::string json = ReadAll(gltf);
  EXPECT_NE(json.find("\"uri\": \"m.bin\", \"byteLength\": 204"), std::string::npos) << json;
  EXPECT_NE(json.find("\"count\": 7, \"type\": \"VEC3\", \"min\": [0, 0, 0], \"max\": [2.5, 3, "
                      "9.99999975e-05]"),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("\"componentType\": 5125, \"count\": 9, \"type\": \"SCALAR\""),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("\"byteOffset\": 168, \"byteLength\": 36, \"target\": 34963"),
            std::string::npos)
      << json;

  const std::string bad = dir_ + "/missing/m.bin";
  EXPECT_FALSE(WriteGltf(m, 1.0f, dir_ + "/missing/m.gltf", bad, &err));
  EXPECT_EQ(err.rfind(bad + ": ", 0), 0u) << err;
}

}  // namespace
