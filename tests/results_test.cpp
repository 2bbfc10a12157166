#include "results.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "test_util.h"

namespace {

std::string TempPath(const char* name) {
  static std::string dir = [] {
    char tmpl[] = "/tmp/results_test.XXXXXX";
    return std::string(mkdtemp(tmpl));
  }();
  return dir + "/" + name;
}

TEST(Results, FaceRadiosityIsTheAreaWeightedMean) {
  Scene s = EmptyScene();
  AddFace(&s, {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}}, glm::dvec3(0.5), glm::dvec3(0));
  MeshOptions o;
  o.patch_size = 1;  // two patches of 2 x 2 equal elements
  Mesh m = MakeMesh(s, o);
  ASSERT_EQ(m.elems.size(), 8u);
  std::vector<glm::dvec3> b(m.elems.size());
  for (size_t e = 0; e < b.size(); ++e) b[e] = glm::dvec3(double(e), 1.0, -1e-12);
  auto fb = FaceRadiosity(m, b);
  EXPECT_NEAR(fb[0].r, 3.5, 1e-12);
  EXPECT_EQ(fb[0].g, 1.0);
  EXPECT_EQ(fb[0].b, 0.0);  // rounding residue below 0 is clamped
}

TEST(Results, ReferenceRoundTripsAndRmsIsExact) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  s.objects.push_back("wall, \"north\"");
  s.faces[2].object = 1;
  std::vector<glm::dvec3> fb;
  for (size_t f = 0; f < s.faces.size(); ++f) fb.push_back(glm::dvec3(1.0 + f, 2.0, 3.0));
  std::string err;
  const std::string path = TempPath("result.csv");
  ASSERT_TRUE(WriteResultCsv(path, s, fb, &err)) << err;
  std::vector<glm::dvec3> ref;
  ASSERT_TRUE(ReadReference(path, s, &ref, &err)) << err;
  ASSERT_EQ(ref.size(), fb.size());
  for (size_t f = 0; f < fb.size(); ++f) EXPECT_EQ(ref[f], fb[f]);
  double rms, rel;
  RmsError(s, fb, ref, &rms, &rel);
  EXPECT_EQ(rms, 0.0);
  // Off by 0.3 in red on every face of equal area: rms = sqrt(0.09 / 3).
  std::vector<glm::dvec3> off = fb;
  for (auto& v : off) v.r += 0.3;
  RmsError(s, off, ref, &rms, &rel);
  EXPECT_NEAR(rms, std::sqrt(0.09 / 3), 1e-12);
  double mean = 0;
  for (const auto& v : fb) mean += (v.r + v.g + v.b) / 3 / fb.size();
  EXPECT_NEAR(rel, rms / mean, 1e-12);
}

TEST(Results, ReferenceOfAnotherSceneIsRefusedWithItsLine) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  std::string err;
  std::vector<glm::dvec3> ref;
  const std::string p = TempPath("bad.csv");
  const std::string header = "face,object,area,B_r,B_g,B_b\n";
  const struct {
    std::string text, error;
  } cases[] = {
      {header + "0,default,1,1,1,1\n", ":3: has 1 rows, the scene 6 faces"},
      {header + "0,default,2,1,1,1\n", ":2: face area differs"},
      {header + "0,default,1,1,nan,1\n", ":2: bad number 'nan'"},
      {"time_s,shots\n", ":1: not a result.csv header"},
      {header + "0,\"open,1,1,1,1\n", ":2: unterminated quote"},
  };
  for (const auto& c : cases) {
    std::ofstream(p) << c.text;
    EXPECT_FALSE(ReadReference(p, s, &ref, &err)) << c.text;
    EXPECT_NE(err.find(c.error), std::string::npos) << err;
  }
  EXPECT_FALSE(ReadReference(TempPath("missing.csv"), s, &ref, &err));
  EXPECT_NE(err.find("missing.csv: No such file or directory"), std::string::npos) << err;
  EXPECT_FALSE(ReadReference("/dev/zero", s, &ref, &err));  // refused, not read for ever
  EXPECT_EQ(err, "/dev/zero: not a regular file");
}

TEST(Results, ShadingAveragesWithinAFaceAndAcrossCoplanarNeighbours) {
  Scene s = EmptyScene();
  // Two coplanar squares of one material side by side, and a third at
  // right angles sharing an edge: only the first two blend.
  AddFace(&s, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, glm::dvec3(0.5), glm::dvec3(0));
  AddFace(&s, {{1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}}, glm::dvec3(0.5), glm::dvec3(0));
  AddFace(&s, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}, glm::dvec3(0.5), glm::dvec3(0));
  s.faces[1].material = s.faces[0].material;
  MeshOptions o;
  o.patch_size = 10;
  o.elements_per_patch = 1;
  o.join = false;  // as the pieces of a surface that is not convex are
  Mesh m = MakeMesh(s, o);
  std::vector<glm::dvec3> b = {glm::dvec3(1.0), glm::dvec3(3.0), glm::dvec3(10.0)};
  ShadedMesh sh = Shade(m, b);
  for (size_t v = 0; v < sh.positions().size(); ++v) {
    const glm::dvec3& p = sh.positions()[v];
    const int face = v < size_t(m.faces[1].vbegin) ? 0 : v < size_t(m.faces[2].vbegin) ? 1 : 2;
    if (face == 2) EXPECT_EQ(sh.colors[v].r, 10.0f);
    else if (p.x == 1.0) EXPECT_EQ(sh.colors[v].r, 2.0f);  // the shared edge
    else EXPECT_EQ(sh.colors[v].r, face == 0 ? 1.0f : 3.0f);
  }
}

}  // namespace
