// Unit tests of the OBJ + MTL loader: every accepted variant and every
// rejected input, with the file and line the error must name.
#include "scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <sys/stat.h>

#include <gtest/gtest.h>

#include "temp_dir.h"

namespace {

struct Loaded {
  bool ok = false;
  Scene scene;
  std::string err;
  std::vector<std::string> warnings;
};

Loaded Load(const std::string& path) {
  Loaded r;
  r.ok = LoadScene(path, &r.scene, &r.err, &r.warnings);
  return r;
}

// The two-parallel-unit-squares scene: an emitter at z=0 facing up and a
// white receiver at z=1 facing down.
const char kSquaresMtl[] =
    "newmtl light\nKd 0\nKe 1 1 1\n"
    "newmtl white\nKd 1 1 1\n";
const char kSquaresVerts[] =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "v 0 0 1\nv 0 1 1\nv 1 1 1\nv 1 0 1\n";

std::string SquaresObj() {
  return std::string("mtllib squares.mtl\n") + kSquaresVerts +
         "usemtl light\nf 1 2 3 4\nusemtl white\nf 5 6 7 8\n";
}

void ExpectSquares(const Loaded& r) {
  ASSERT_TRUE(r.ok) << r.err;
  ASSERT_EQ(r.scene.faces.size(), 2u);
  const Face& a = r.scene.faces[0];
  const Face& b = r.scene.faces[1];
  EXPECT_EQ(a.verts.size(), 4u);
  EXPECT_EQ(b.verts.size(), 4u);
  EXPECT_NEAR(a.area, 1.0, 1e-12);
  EXPECT_NEAR(b.area, 1.0, 1e-12);
  EXPECT_NEAR(glm::distance(a.normal, glm::dvec3(0, 0, 1)), 0.0, 1e-12);
  EXPECT_NEAR(glm::distance(b.normal, glm::dvec3(0, 0, -1)), 0.0, 1e-12);
  EXPECT_EQ(r.scene.materials[a.material].name, "light");
  EXPECT_EQ(r.scene.materials[b.material].name, "white");
  EXPECT_EQ(r.scene.materials[a.material].kd, glm::dvec3(0.0));
  EXPECT_EQ(r.scene.materials[a.material].ke, glm::dvec3(1.0));
  EXPECT_EQ(r.scene.materials[b.material].kd, glm::dvec3(1.0));
  EXPECT_EQ(r.scene.materials[b.material].ke, glm::dvec3(0.0));
  EXPECT_EQ(r.scene.lo, glm::dvec3(0.0));
  EXPECT_EQ(r.scene.hi, glm::dvec3(1.0));
  EXPECT_TRUE(r.warnings.empty());
}

// Loads an OBJ (with the squares MTL beside it) that must fail on LINE
// with a message containing WHAT.
void ExpectError(const std::string& obj, int line, const std::string& what) {
  TempDir dir;
  dir.Write("squares.mtl", kSquaresMtl);
  std::string path = dir.Write("bad.obj", obj);
  Loaded r = Load(path);
  ASSERT_FALSE(r.ok);
  std::string where = path + ":" + std::to_string(line) + ": ";
  EXPECT_EQ(r.err.compare(0, where.size(), where), 0) << r.err << "\n  expected prefix: " << where;
  EXPECT_NE(r.err.find(what), std::string::npos) << r.err << "\n  expected: " << what;
  EXPECT_EQ(r.err.find('\n'), std::string::npos) << r.err;
}

// An MTL that must fail on LINE with a message containing WHAT.
void ExpectMtlError(const std::string& mtl, int line, const std::string& what) {
  TempDir dir;
  dir.Write("bad.mtl", mtl);
  std::string path =
      dir.Write("bad.obj", std::string("mtllib bad.mtl\n") + kSquaresVerts + "f 1 2 3 4\n");
  Loaded r = Load(path);
  ASSERT_FALSE(r.ok);
  std::string where = dir.path() + "/bad.mtl:" + std::to_string(line) + ": ";
  EXPECT_EQ(r.err.compare(0, where.size(), where), 0) << r.err << "\n  expected prefix: " << where;
  EXPECT_NE(r.err.find(what), std::string::npos) << r.err << "\n  expected: " << what;
}

std::string Fmt7(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.7g", x);
  return buf;
}

std::string V(const glm::dvec3& p) {
  return "v " + Fmt7(p.x) + " " + Fmt7(p.y) + " " + Fmt7(p.z) + "\n";
}

}  // namespace

// ---- accepted input -------------------------------------------------------

TEST(Scene, TwoSquares) {
  TempDir dir;
  dir.Write("squares.mtl", kSquaresMtl);
  Loaded r = Load(dir.Write("squares.obj", SquaresObj()));
  ExpectSquares(r);
  EXPECT_EQ(r.scene.faces[0].index, 0);
  EXPECT_EQ(r.scene.faces[1].index, 1);
  EXPECT_EQ(r.scene.faces[0].line, 11);
  EXPECT_EQ(r.scene.faces[1].line, 13);
  EXPECT_EQ(r.scene.objects, std::vector<std::string>{"default"});
  EXPECT_EQ(r.scene.faces[0].object, 0);
  EXPECT_EQ(r.scene.materials[0].name, "default");
  EXPECT_FALSE(r.scene.has_camera);
  EXPECT_EQ(r.scene.path, dir.path() + "/squares.obj");
}

TEST(Scene, CrlfTabsSpacesLeadingWhitespaceNoTrailingNewline) {
  TempDir dir;
  dir.Write("squares.mtl", "newmtl light\r\n\tKd  0\r\n  Ke\t1 1 1\r\nnewmtl white\r\nKd 1 1 1");
  Loaded r = Load(dir.Write(
      "squares.obj",
      "mtllib squares.mtl\r\n"
      "  v\t0 0 0\r\nv  1   0 0  \r\n\tv 1 1 0\r\nv 0\t\t1 0\r\n"
      "v 0 0 1\r\nv 0 1 1\r\nv 1 1 1\r\nv 1 0 1\r\n\r\n"
      "usemtl light\r\n f\t1  2 3\t4 \r\nusemtl white\r\nf 5 6 7 8"));
  ExpectSquares(r);
}

TEST(Scene, Utf8ByteOrderMark) {
  TempDir dir;
  dir.Write("squares.mtl", std::string("\xEF\xBB\xBF") + kSquaresMtl);
  ExpectSquares(Load(dir.Write("squares.obj", "\xEF\xBB\xBF" + SquaresObj())));
}

TEST(Scene, FaceFormsAndIgnoredStatements) {
  TempDir dir;
  dir.Write("squares.mtl", kSquaresMtl);
  Loaded r = Load(dir.Write(
      "squares.obj",
      std::string("mtllib squares.mtl\n") + kSquaresVerts +
          "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nvp 0.5\ns 1\ns off\nl 1 2\np 3\ncstype bezier\n"
          "deg 3\nwhatever 1 2 3\n"
          "usemtl light\nf 1/1 2/2 3/3/1 4//1\nusemtl white\nf 5/1/1 6/2/1 7//1 8\n"));
  ExpectSquares(r);
  EXPECT_EQ(r.scene.faces[0].line, 23);
}

TEST(Scene, VertexWIgnoredAndInlineComments) {
  TempDir dir;
  dir.Write("squares.mtl", kSquaresMtl);
  ExpectSquares(Load(dir.Write("squares.obj",
                               "mtllib squares.mtl  # materials\n"
                               "v 0 0 0 1\nv 1 0 0 0.5\nv 1 1 0 1\nv 0 1 0 1 # w\n"
                               "v 0 0 1\nv 0 1 1\nv 1 1 1\nv 1 0 1\n"
                               "usemtl light # the emitter\nf 1 2 3 4\n"
                               "usemtl white\nf 5 6 7 8 # end\n")));
}

TEST(Scene, NegativeIndices) {
  TempDir dir;
  dir.Write("squares.mtl", kSquaresMtl);
  ExpectSquares(Load(dir.Write("squares.obj",
                               "mtllib squares.mtl\n"
                               "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                               "usemtl light\nf -4 -3 -2/-1 -1//-1\n"
                               "v 0 0 1\nv 0 1 1\nv 1 1 1\nv 1 0 1\nusemtl white\nf -4 6 -2 8\n")));
}

TEST(Scene, NgonKeptWithCollinearMidpoints) {
  TempDir dir;
  Loaded r = Load(dir.Write("hex.obj",
                            "v 0 0 0\nv 0.5 0 0\nv 1 0 0\nv 1 1 0\nv 0.5 1 0\nv 0 1 0\n"
                            "f 1 2 3 4 5 6\n"
                            "v 2 0 0\nv 3 0 0\nv 3.5 1 0\nv 3 2 0\nv 2 2 0\nv 1.5 1 0\n"
                            "f 7 8 9 10 11 12\n"));
  ASSERT_TRUE(r.ok) << r.err;
  ASSERT_EQ(r.scene.faces.size(), 2u);
  EXPECT_EQ(r.scene.faces[0].verts.size(), 6u);
  EXPECT_NEAR(r.scene.faces[0].area, 1.0, 1e-12);
  EXPECT_EQ(r.scene.faces[0].verts[1], glm::dvec3(0.5, 0, 0));
  EXPECT_EQ(r.scene.faces[1].verts.size(), 6u);
  EXPECT_NEAR(r.scene.faces[1].area, 3.0, 1e-12);
  EXPECT_NEAR(glm::distance(r.scene.faces[1].normal, glm::dvec3(0, 0, 1)), 0.0, 1e-12);
  EXPECT_EQ(r.scene.faces[0].material, 0);
  EXPECT_EQ(r.scene.materials[0].kd, glm::dvec3(0.5));
  EXPECT_EQ(r.scene.materials[0].ke, glm::dvec3(0.0));
}

TEST(Scene, ConsecutiveDuplicatesDropped) {
  TempDir dir;
  // Repeated indices, a repeated position under another index, and a
  // closing vertex equal to the first.
  Loaded r = Load(dir.Write("dup.obj",
                            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 0\n"
                            "f 1 1 2 5 2 3 4 4 1 1\n"));
  ASSERT_TRUE(r.ok) << r.err;
  ASSERT_EQ(r.scene.faces.size(), 1u);
  EXPECT_EQ(r.scene.faces[0].verts.size(), 4u);
  EXPECT_NEAR(r.scene.faces[0].area, 1.0, 1e-12);
}

TEST(Scene, ClockwiseFaceFacesDown) {
  TempDir dir;
  Loaded r = Load(dir.Write("cw.obj", "v 0 0 0\nv 2 0 0\nv 0 3 0\nf 1 3 2\n"));
  ASSERT_TRUE(r.ok) << r.err;
  EXPECT_NEAR(glm::distance(r.scene.faces[0].normal, glm::dvec3(0, 0, -1)), 0.0, 1e-12);
  EXPECT_NEAR(r.scene.faces[0].area, 3.0, 1e-12);
}

TEST(Scene, ZeroAreaFaceSkippedWithWarning) {
  TempDir dir;
  std::string path = dir.Write("zero.obj",
                               "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 1 1 0\nv 1e-14 1e-14 0\n"
                               "f 1 2 4\n"
                               "f 1 2 3\n"      // collinear
                               "f 1 5 2\n"      // sliver far below 1e-12 of its extent squared
                               "f 2 3 4\n");
  Loaded r = Load(path);
  ASSERT_TRUE(r.ok) << r.err;
  ASSERT_EQ(r.scene.faces.size(), 2u);
  EXPECT_EQ(r.scene.faces[0].index, 0);
  EXPECT_EQ(r.scene.faces[1].index, 3);
  EXPECT_EQ(r.scene.faces[1].line, 9);
  ASSERT_EQ(r.warnings.size(), 2u);
  EXPECT_EQ(r.warnings[0], path + ":7: zero-area face skipped");
  EXPECT_EQ(r.warnings[1], path + ":8: zero-area face skipped");
  EXPECT_EQ(r.scene.lo, glm::dvec3(0.0));
  EXPECT_EQ(r.scene.hi, glm::dvec3(2, 1, 0));
}

TEST(Scene, WarningsMayBeNull) {
  TempDir dir;
  Scene s;
  std::string err;
  std::string path = dir.Write("z.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n");
  EXPECT_TRUE(LoadScene(path, &s, &err, nullptr)) << err;
  EXPECT_EQ(s.faces.size(), 1u);
}

TEST(Scene, ObjectNames) {
  TempDir dir;
  Loaded r = Load(dir.Write("obj.obj",
                            "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                            "f 1 2 3\n"          // default
                            "g walls\nf 1 2 3\n"  // walls
                            "o box  one\nf 1 2 3\n"  // o wins over g; spaces kept inside
                            "g floor\nf 1 2 3\n"  // still box one
                            "o walls\nf 1 2 3\n"  // deduplicated with the g name
                            "o\nf 1 2 3\n"       // o cleared: back to the g name
                            "g\nf 1 2 3\n"       // both cleared: default
                            "g default\nf 1 2 3\n"));
  ASSERT_TRUE(r.ok) << r.err;
  ASSERT_EQ(r.scene.faces.size(), 8u);
  EXPECT_EQ(r.scene.objects, (std::vector<std::string>{"default", "walls", "box  one", "floor"}));
  std::vector<int> want = {0, 1, 2, 2, 1, 3, 0, 0};
  for (size_t i = 0; i < want.size(); ++i) EXPECT_EQ(r.scene.faces[i].object, want[i]) << i;
}

TEST(Scene, MaterialVariants) {
  TempDir dir;
  dir.Write("sub/a.mtl",
            "# a comment\nnewmtl grey\nNs 10\nKa 1 1 1\nKd 0.25\nKs 0.5 0.5 0.5\nillum 2\n"
            "map_Kd tex.png\nd 1\nTr 0\nNi 1.5\nKe 2\n"
            "newmtl nokE\nKd 0.1 0.2 0.3\n"
            "newmtl bright\nKd 1 0 1\nKe 0 1e3 0.5\n");
  dir.Write("sub/b.mtl", "newmtl other name\nKd 0.75 0.75 0.75\n");
  Loaded r = Load(dir.Write("sub/m.obj",
                            "mtllib a.mtl b.mtl\nmtllib a.mtl\n"  // the second naming is a no-op
                            "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                            "f 1 2 3\nusemtl grey\nf 1 2 3\nusemtl nokE\nf 1 2 3\n"
                            "usemtl bright\nf 1 2 3\nusemtl other name\nf 1 2 3\n"
                            "usemtl default\nf 1 2 3\n"));
  ASSERT_TRUE(r.ok) << r.err;
  ASSERT_EQ(r.scene.faces.size(), 6u);
  auto mat = [&](int i) { return r.scene.materials[r.scene.faces[i].material]; };
  EXPECT_EQ(mat(0).name, "default");
  EXPECT_EQ(mat(1).name, "grey");
  EXPECT_EQ(mat(1).kd, glm::dvec3(0.25));
  EXPECT_EQ(mat(1).ke, glm::dvec3(2.0));
  EXPECT_EQ(mat(2).kd, glm::dvec3(0.1, 0.2, 0.3));
  EXPECT_EQ(mat(2).ke, glm::dvec3(0.0));
  EXPECT_EQ(mat(3).kd, glm::dvec3(1, 0, 1));
  EXPECT_EQ(mat(3).ke, glm::dvec3(0, 1e3, 0.5));
  EXPECT_EQ(mat(4).name, "other name");
  EXPECT_EQ(mat(4).kd, glm::dvec3(0.75));
  EXPECT_EQ(r.scene.faces[5].material, 0);
  EXPECT_EQ(r.scene.materials.size(), 5u);
}

TEST(Scene, MtllibRelativeToObjDirectory) {
  TempDir dir;
  dir.Write("scenes/squares.mtl", kSquaresMtl);
  std::string obj = dir.Write("scenes/squares.obj", SquaresObj());
  ExpectSquares(Load(obj));
  // And named by a relative path from the working directory.
  std::filesystem::path cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir.path());
  Loaded r = Load("scenes/squares.obj");
  std::filesystem::current_path(cwd);
  ExpectSquares(r);
}

TEST(Scene, CameraComment) {
  TempDir dir;
  Loaded r = Load(dir.Write("cam.obj",
                            "# a scene\n#camera 9 9 9 0 0 0 10\n"
                            "  #  camera\t1 2 3   0 0.5 0  60\n"
                            "# cameras are not this\n"
                            "v 0 0 0 # camera is not here either\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  ASSERT_TRUE(r.ok) << r.err;
  EXPECT_TRUE(r.scene.has_camera);
  EXPECT_EQ(r.scene.camera.eye, glm::dvec3(1, 2, 3));
  EXPECT_EQ(r.scene.camera.target, glm::dvec3(0, 0.5, 0));
  EXPECT_EQ(r.scene.camera.fov_deg, 60.0);
}

TEST(Scene, LongLines) {
  TempDir dir;
  std::string longname(200000, 'n');
  dir.Write("squares.mtl", "# " + std::string(100000, 'x') + "\n" + kSquaresMtl);
  std::string obj = "# " + std::string(100000, 'c') + "\n" + SquaresObj() + "o " + longname +
                    "\nv 0 0" + std::string(100000, ' ') + "1\n";
  obj += "f";
  // a square wound 250 times, the most vertices a polygon may have
  for (int i = 0; i < 250; ++i) obj += " 1 2 3 4" + std::string(400, ' ');
  obj += "\n";
  Loaded r = Load(dir.Write("squares.obj", obj));
  ASSERT_TRUE(r.ok) << r.err;
  ASSERT_EQ(r.scene.faces.size(), 3u);
  EXPECT_EQ(r.scene.faces[2].verts.size(), 1000u);  // duplicates only when consecutive
  EXPECT_EQ(r.scene.objects[r.scene.faces[2].object], longname);
}

// A box room with a rotated block and a small quad far from the origin,
// rotated by an arbitrary rotation and printed with 7 significant digits,
// at several scales: it must load, with the areas and normals it had.
TEST(Scene, RotatedAndRoundedStaysPlanar) {
  const glm::dvec3 axis = glm::normalize(glm::dvec3(0.3, -0.7, 0.2));
  const double angle = 0.98765;
  auto rotate = [&](glm::dvec3 p) {  // Rodrigues
    return p * std::cos(angle) + glm::cross(axis, p) * std::sin(angle) +
           axis * glm::dot(axis, p) * (1 - std::cos(angle));
  };
  std::vector<std::vector<glm::dvec3>> quads;
  auto box = [&](glm::dvec3 lo, glm::dvec3 hi, double turn, bool inward) {
    auto at = [&](double x, double y, double z) {
      glm::dvec3 c = (lo + hi) * 0.5, p(x, y, z);
      glm::dvec3 d = p - c;
      return c + glm::dvec3(d.x * std::cos(turn) - d.y * std::sin(turn),
                            d.x * std::sin(turn) + d.y * std::cos(turn), d.z);
    };
    glm::dvec3 a = lo, b = hi;
    std::vector<std::vector<glm::dvec3>> f = {
        {at(a.x, a.y, a.z), at(a.x, b.y, a.z), at(b.x, b.y, a.z), at(b.x, a.y, a.z)},
        {at(a.x, a.y, b.z), at(b.x, a.y, b.z), at(b.x, b.y, b.z), at(a.x, b.y, b.z)},
        {at(a.x, a.y, a.z), at(b.x, a.y, a.z), at(b.x, a.y, b.z), at(a.x, a.y, b.z)},
        {at(b.x, b.y, a.z), at(a.x, b.y, a.z), at(a.x, b.y, b.z), at(b.x, b.y, b.z)},
        {at(a.x, b.y, a.z), at(a.x, a.y, a.z), at(a.x, a.y, b.z), at(a.x, b.y, b.z)},
        {at(b.x, a.y, a.z), at(b.x, b.y, a.z), at(b.x, b.y, b.z), at(b.x, a.y, b.z)}};
    for (auto& q : f) {
      if (inward) std::reverse(q.begin(), q.end());
      quads.push_back(q);
    }
  };
  box(glm::dvec3(0), glm::dvec3(556, 559, 548), 0, true);
  box(glm::dvec3(265, 296, 0), glm::dvec3(430, 461, 330), 0.29, false);
  box(glm::dvec3(500, 500, 500), glm::dvec3(500.01, 500.013, 500.007), 1.1, false);
  for (double scale : {1e-4, 1.0, 1e4}) {
    std::string obj;
    int n = 0;
    for (const auto& q : quads) {
      for (const glm::dvec3& p : q) obj += V(rotate(p * scale) + glm::dvec3(123.4, -56, 7) * scale);
      obj += "f " + std::to_string(n + 1) + " " + std::to_string(n + 2) + " " +
             std::to_string(n + 3) + " " + std::to_string(n + 4) + "\n";
      n += 4;
    }
    TempDir dir;
    Loaded r = Load(dir.Write("rot.obj", obj));
    ASSERT_TRUE(r.ok) << "scale " << scale << ": " << r.err;
    ASSERT_EQ(r.scene.faces.size(), quads.size());
    for (size_t i = 0; i < quads.size(); ++i) {
      const auto& q = quads[i];
      glm::dvec3 n0 = glm::cross(q[1] - q[0], q[2] - q[1]);
      double area = glm::length(n0) * scale * scale;
      // The small box's corners lose ~3 of their 7 digits to its offset.
      const double tol = i < 12 ? 1e-5 : 3e-2;
      EXPECT_NEAR(r.scene.faces[i].area / area, 1.0, tol) << "scale " << scale << " face " << i;
      EXPECT_GT(glm::dot(r.scene.faces[i].normal, rotate(glm::normalize(n0))), 1 - tol)
          << "scale " << scale << " face " << i;
    }
  }
}

// ---- rejected input -------------------------------------------------------

TEST(Scene, BentQuadRejected) {
  for (double scale : {1e-4, 1.0, 1e4}) {
    std::string obj = V(glm::dvec3(0, 0, 0) * scale) + V(glm::dvec3(1, 0, 0) * scale) +
                      V(glm::dvec3(1, 1, 0.05) * scale) + V(glm::dvec3(0, 1, 0) * scale) +
                      "f 1 2 3\nf 1 2 3 4\n";
    ExpectError(obj, 6, "not planar");
  }
}

TEST(Scene, SlightlyBentQuadAccepted) {
  TempDir dir;
  Loaded r = Load(dir.Write("ok.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0.0001\nv 0 1 0\nf 1 2 3 4\n"));
  EXPECT_TRUE(r.ok) << r.err;
}

TEST(Scene, FileErrors) {
  TempDir dir;
  std::string missing = dir.path() + "/missing.obj";
  Loaded r = Load(missing);
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, missing + ": cannot open: No such file or directory");

  r = Load(dir.path());
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, dir.path() + ": cannot open: not a regular file");

  std::string empty = dir.Write("empty.obj", "");
  r = Load(empty);
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, empty + ": no faces");

  std::string nofaces = dir.Write("nofaces.obj", "# nothing\nv 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n");
  r = Load(nofaces);
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, nofaces + ": no faces");

  std::string allzero = dir.Write("zero.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 3 2 1\n");
  r = Load(allzero);
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, allzero + ": no faces left (2 zero-area faces skipped)");
}

TEST(Scene, VertexIndexErrors) {
  const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  ExpectError(v + "f 1 2 3\nf 0 1 2\n", 5, "vertex index 0");
  ExpectError(v + "f 1 2 4\n", 4, "vertex index 4 is out of range (3 vertices defined so far)");
  ExpectError(v + "f 1 2 -4\n", 4, "vertex index -4 is out of range");
  ExpectError("f 1 2 3\n" + v, 1, "vertex index 1 is out of range (0 vertices defined so far)");
  ExpectError("f -1 -2 -3\n" + v, 1, "out of range");
  ExpectError(v + "f 1 2 3 4\nv 1 1 0\n", 4, "vertex index 4 is out of range");
  ExpectError(v + "f 1 2 99999999999999999999\n", 4, "'99999999999999999999' is out of range");
  ExpectError(v + "f 1 2 -99999999999999999999\n", 4, "out of range");
  ExpectError(v + "f 1 2 4294967297\n", 4, "out of range");
  ExpectError(v + "f 1 2 x\n", 4, "'x' is not an integer");
  ExpectError(v + "f 1 2 3.0\n", 4, "'3.0' is not an integer");
  ExpectError(v + "f 1 2 3a\n", 4, "'3a' is not an integer");
  ExpectError(v + "f 1 2 /3\n", 4, "malformed vertex reference '/3'");
  ExpectError(v + "f 1 2 3/1/1/1\n", 4, "malformed vertex reference '3/1/1/1'");
  ExpectError(v + "f 1 2 3/\n", 4, "malformed vertex reference");
  ExpectError(v + "f 1 2 3//\n", 4, "malformed vertex reference");
  ExpectError(v + "f 1 2 3/x\n", 4, "malformed vertex reference");
  ExpectError(v + "f 1 2 3/1/y\n", 4, "malformed vertex reference");
}

TEST(Scene, FaceVertexCountErrors) {
  const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 0\n";
  ExpectError(v + "f 1 2\n", 5, "f: a face needs at least 3 vertices, got 2");
  ExpectError(v + "f\n", 5, "got 0");
}

// A face that names fewer than 3 distinct points (issue 16: f 5 5 6) has
// no area: skipped with the zero-area warning, not an error; the faces
// after it keep their numbers.
TEST(Scene, RepeatedVerticesAreAZeroAreaFace) {
  TempDir dir;
  const std::string path = dir.Write("rep.obj",
                                     "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 0\n"
                                     "f 1 2 2\n"       // line 5
                                     "f 1 2 1\n"       // back to the first
                                     "f 1 2 4\n"       // 4 is at 2's position
                                     "f 3 3 3 3\n"     // one point
                                     "f 1 2 3\n");     // face 4, line 9
  Loaded r = Load(path);
  ASSERT_TRUE(r.ok) << r.err;
  ASSERT_EQ(r.scene.faces.size(), 1u);
  EXPECT_EQ(r.scene.faces[0].index, 4);
  EXPECT_EQ(r.scene.faces[0].line, 9);
  ASSERT_EQ(r.warnings.size(), 4u);
  EXPECT_EQ(r.warnings[0], path + ":5: zero-area face skipped (2 distinct vertices)");
  EXPECT_EQ(r.warnings[1], path + ":6: zero-area face skipped (2 distinct vertices)");
  EXPECT_EQ(r.warnings[2], path + ":7: zero-area face skipped (2 distinct vertices)");
  EXPECT_EQ(r.warnings[3], path + ":8: zero-area face skipped (1 distinct vertex)");

  // Only repeats: the file has no faces left, as with any zero-area faces.
  const std::string only = dir.Write("only.obj", "v 0 0 0\nv 1 0 0\nf 1 1 2\n");
  r = Load(only);
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, only + ": no faces left (1 zero-area faces skipped)");
}

TEST(Scene, VertexCoordinateErrors) {
  ExpectError("v 0 0 0\nv 1 nan 0\n", 2, "v: 'nan' is not a finite number");
  ExpectError("v 0 0 0\nv 1 0 NaN\n", 2, "not a finite number");
  ExpectError("v inf 0 0\n", 1, "'inf' is not a finite number");
  ExpectError("v -infinity 0 0\n", 1, "not a finite number");
  ExpectError("v 1e999 0 0\n", 1, "'1e999' is out of range");
  ExpectError("v 0 -1e400 0\n", 1, "out of range");
  ExpectError("v 0 abc 0\n", 1, "'abc' is not a number");
  ExpectError("v 0 1,5 0\n", 1, "'1,5' is not a number");
  ExpectError("v 0 1.5.2 0\n", 1, "not a number");
  ExpectError("v 0 0\n", 1, "expected 3 coordinates (and an optional w), got 2");
  ExpectError("v\n", 1, "got 0");
  ExpectError("v 0 0 0 1 5\n", 1, "got 5");
  ExpectError("v 0 0 0 w\n", 1, "'w' is not a number");
}

// An error about a file names it whole (issue 16: a long mtllib path was
// cut in the middle, losing the missing file's own name).
TEST(Scene, LongFileNamesAreWhole) {
  TempDir dir;
  // Parts under NAME_MAX (255): the file is missing, the name is legal.
  const std::string deep = "/" + std::string(90, 'd') + "/" + std::string(90, 'e') + "/" +
                           std::string(90, 'f');
  const std::string mtl = dir.path() + deep + "/does_not_exist.mtl";
  ASSERT_GE(mtl.size(), 300u);
  Loaded r = Load(dir.Write("m.obj", "mtllib " + mtl + "\n" + kSquaresVerts + "f 1 2 3 4\n"));
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, dir.path() + "/m.obj:1: mtllib: cannot open '" + mtl +
                       "': No such file or directory");
  const std::string obj = dir.path() + deep + "/does_not_exist.obj";
  r = Load(obj);
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, obj + ": cannot open: No such file or directory");
}

TEST(Scene, MaterialReferenceErrors) {
  const std::string sq = std::string(kSquaresVerts) + "f 1 2 3 4\n";
  ExpectError("mtllib missing.mtl\n" + sq, 1, "mtllib: cannot open");
  ExpectError("mtllib squares.mtl missing.mtl\n" + sq, 1,
              "missing.mtl': No such file or directory");
  ExpectError("mtllib\n" + sq, 1, "mtllib: missing file name");
  ExpectError("#\nmtllib .\n" + sq, 2, "mtllib: cannot open '");
  ExpectError("mtllib squares.mtl\n" + sq + "usemtl blue\nf 1 2 3\n", 11,
              "usemtl: material 'blue' is not defined");
  ExpectError(sq + "usemtl light\n", 10, "(no mtllib before it)");
  ExpectError("usemtl\n" + sq, 1, "usemtl: missing material name");
}

TEST(Scene, MtlErrors) {
  ExpectMtlError("newmtl a\nKd 1.5 0 0\n", 2, "Kd: '1.5' is outside [0, 1]");
  ExpectMtlError("newmtl a\nKd 0 -0.1 0\n", 2, "outside [0, 1]");
  ExpectMtlError("newmtl a\nKd 1.0000001\n", 2, "outside [0, 1]");
  ExpectMtlError("newmtl a\nKd nan 0 0\n", 2, "Kd: 'nan' is not a finite number");
  ExpectMtlError("newmtl a\nKd 0.5 x 0\n", 2, "Kd: 'x' is not a number");
  ExpectMtlError("newmtl a\nKd 0.5 0.5\n", 2, "Kd: expected 1 or 3 numbers, got 2");
  ExpectMtlError("newmtl a\nKd\n", 2, "got 0");
  ExpectMtlError("newmtl a\nKd spectral file.spd\n", 2, "got 2");
  ExpectMtlError("newmtl a\nKe -1 0 0\n", 2, "Ke: '-1' is negative");
  ExpectMtlError("newmtl a\nKe inf\n", 2, "Ke: 'inf' is not a finite number");
  ExpectMtlError("newmtl a\nKe 1e999 0 0\n", 2, "Ke: '1e999' is out of range");
  ExpectMtlError("newmtl a\nKe 1 1 1 1\n", 2, "got 4");
  ExpectMtlError("Kd 0.5\n", 1, "Kd before any newmtl");
  ExpectMtlError("\nKe 1\n", 2, "Ke before any newmtl");
  ExpectMtlError("newmtl\n", 1, "newmtl: missing material name");
  ExpectMtlError("newmtl a\nKd 1\nnewmtl a\n", 3, "material 'a' is already defined");
  ExpectMtlError("newmtl default\n", 1, "built-in");
  ExpectMtlError("newmtl a\nKd 0.5 0\x01 0.5\n", 2, "control byte 0x01");
}

TEST(Scene, CameraErrors) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  ExpectError(tri + "# camera 1 2 3\n", 5, "camera: expected 7 numbers");
  ExpectError("# camera 0 0 5 0 0 0 180\n" + tri, 1, "camera: fov");
  ExpectError("# camera\n" + tri, 1, "camera: expected 7 numbers");
  ExpectError("\n#camera 0 0 5 0 0 0 x\n" + tri, 2, "camera: 'x' is not a number");
  ExpectError("# camera 1 1 1 1 1 1 45\n" + tri, 1, "camera: eye and target are the same point");
}

TEST(Scene, BinaryGarbage) {
  std::mt19937 rng(12345);
  for (int round = 0; round < 20; ++round) {
    std::string bytes(4096, '\0');
    for (char& c : bytes) c = static_cast<char>(rng());
    TempDir dir;
    std::string path = dir.Write("bad.obj", bytes);
    Loaded r = Load(path);
    ASSERT_FALSE(r.ok);
    // FILE:LINE: with a positive line number.
    ASSERT_EQ(r.err.compare(0, path.size() + 1, path + ":"), 0) << r.err;
    char* end = nullptr;
    long line = std::strtol(r.err.c_str() + path.size() + 1, &end, 10);
    EXPECT_GT(line, 0) << r.err;
    EXPECT_EQ(std::string(end, 2), ": ") << r.err;
  }
}

TEST(Scene, NulAndControlBytes) {
  ExpectError(std::string("v 0 0 0\nv 1 0\0 0\n", 17), 2, "control byte 0x00");
  ExpectError(std::string("v 0 0 0\n# comment \0\n", 20), 2, "control byte 0x00");
  ExpectError("v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\r", 1, "control byte 0x0d");
  ExpectError("v 0 0 0\nv 1\v0 0\n", 2, "control byte 0x0b");
  Loaded r = Load("/dev/zero");  // must not read forever
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, "/dev/zero: cannot open: not a regular file");
}

// The check reads a line eight bytes at a time: a control byte is found
// at any place of a long line, in a word or in the tail; a tab, bytes of
// UTF-8 and the bytes just above 0x1f and below 0x7f are text.
TEST(Scene, ControlBytesAtEveryPlaceOfALine) {
  const std::string text = "v 0 0 0 # \t" "\xc3\xa9 ~ \x20!0123456789abcdefghijkl";
  TempDir dir;
  dir.Write("squares.mtl", kSquaresMtl);
  Loaded ok = Load(dir.Write("ok.obj", SquaresObj() + text + "\n"));
  EXPECT_TRUE(ok.ok) << ok.err;
  for (size_t at = 0; at < text.size(); ++at)
    for (const char c : {'\x01', '\x1f', '\x7f'}) {
      std::string line = text;
      line[at] = c;
      char want[40];
      std::snprintf(want, sizeof want, "control byte 0x%02x", (unsigned char)c);
      ExpectError(std::string(kSquaresVerts) + line + "\n", 9, want);
    }
}

// ---- ParseCamera ----------------------------------------------------------

TEST(Scene, ParseCamera) {
  Camera c;
  std::string err;
  ASSERT_TRUE(ParseCamera("  1 2 3\t4 5 6  35.5 ", &c, &err)) << err;
  EXPECT_EQ(c.eye, glm::dvec3(1, 2, 3));
  EXPECT_EQ(c.target, glm::dvec3(4, 5, 6));
  EXPECT_EQ(c.fov_deg, 35.5);
  EXPECT_TRUE(ParseCamera("0 0 0 0 0 -1 179.9", &c, &err)) << err;
  EXPECT_TRUE(ParseCamera("0 0 0 0 0 -1 0.001", &c, &err)) << err;

  const Camera before = c;
  for (const char* bad : {"", "1 2 3 4 5 6", "1 2 3 4 5 6 7 8", "1 2 3 4 5 6 x", "1 2 3 4 5 6 45x",
                          "nan 0 0 0 0 1 45", "0 inf 0 0 0 1 45", "0 0 1e999 0 0 1 45",
                          "0 0 0 0 0 1 0", "0 0 0 0 0 1 180", "0 0 0 0 0 1 -45", "0 0 0 0 0 1 nan",
                          "1 2 3 1 2 3 45", "1,2,3 4,5,6 45"}) {
    err.clear();
    EXPECT_FALSE(ParseCamera(bad, &c, &err)) << bad;
    EXPECT_FALSE(err.empty()) << bad;
    EXPECT_EQ(err.find(':'), std::string::npos) << "no file:line context: " << err;
    EXPECT_EQ(c.eye, before.eye) << "unchanged on failure: " << bad;
  }
  ParseCamera("1 2 3 4 5 6", &c, &err);
  EXPECT_EQ(err, "expected 7 numbers \"ex ey ez tx ty tz fov\", got 6");
  ParseCamera("0 0 0 0 0 1 180", &c, &err);
  EXPECT_EQ(err, "fov must be between 0 and 180 degrees, exclusive, got 180");
}

// ---- Hostile input: bounds and files that could block ---------------------

TEST(Scene, APolygonPastTheVertexLimitIsRefused) {
  std::string ok = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf";
  for (int i = 0; i < 333; ++i) ok += " 1 2 3";  // 999 references, 3 distinct vertices
  ExpectError(ok + " 1 2\n", 4, "f: a polygon of 1001 vertices (the limit is 1000)");
}

TEST(Scene, AnOverflowingAreaIsNotCalledZero) {
  ExpectError("v 0 0 0\nv 1e200 0 0\nv 0 1e200 0\nf 1 2 3\n", 4,
              "f: face too large: its area is not a finite number");
}

TEST(Scene, AHugeKeIsRefusedWhereItIsWritten) {
  TempDir dir;
  dir.Write("squares.mtl", "newmtl light\nKd 0\nKe 1e308 1 1\n");
  Loaded r = Load(dir.Write("s.obj", SquaresObj()));
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, dir.path() + "/squares.mtl:3: Ke: '1e308' is too large (at most 1e+30)");
}

TEST(Scene, AFifoIsRefusedWithoutBlocking) {
  TempDir dir;
  const std::string fifo = dir.path() + "/fifo.obj";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  Loaded r = Load(fifo);  // no writer: an open that waited would never return
  ASSERT_FALSE(r.ok);
  EXPECT_EQ(r.err, fifo + ": cannot open: not a regular file");
  ASSERT_EQ(mkfifo((dir.path() + "/fifo.mtl").c_str(), 0600), 0);
  r = Load(dir.Write("s.obj", "mtllib fifo.mtl\n"));
  ASSERT_FALSE(r.ok);
  EXPECT_NE(r.err.find(":1: mtllib: cannot open '" + dir.path() + "/fifo.mtl': not a regular file"),
            std::string::npos)
      << r.err;
}
