#include "hemicube.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "groups.h"
#include "test_util.h"

namespace {

double Sum(const std::vector<FormFactor>& col) {
  double s = 0;
  for (const auto& f : col) s += f.f;
  return s;
}

double SumOverFace(const Mesh& m, const std::vector<FormFactor>& col, int face) {
  double s = 0;
  for (const auto& f : col)
    if (m.patches[m.elems[f.elem].patch].face == face) s += f.f;
  return s;
}

// Two columns the same bit for bit: the same elements, each with the same
// form factor (compared as floats).
::testing::AssertionResult SameColumn(const std::vector<FormFactor>& a,
                                      const std::vector<FormFactor>& b) {
  if (a.size() != b.size())
    return ::testing::AssertionFailure() << a.size() << " form factors against " << b.size();
  for (size_t k = 0; k < a.size(); ++k)
    if (a[k].elem != b[k].elem || a[k].f != b[k].f)
      return ::testing::AssertionFailure() << "entry " << k << ": element " << a[k].elem << " F "
                                           << a[k].f << " against element " << b[k].elem << " F "
                                           << b[k].f;
  return ::testing::AssertionSuccess();
}

// Differential area to a parallel rectangle [0,a]x[0,b] at height c, with
// the corner above the point (Howell B-3).
double CornerParallel(double a, double b, double c) {
  double X = a / c, Y = b / c;
  return (X / std::sqrt(1 + X * X) * std::atan(Y / std::sqrt(1 + X * X)) +
          Y / std::sqrt(1 + Y * Y) * std::atan(X / std::sqrt(1 + Y * Y))) /
         (2 * M_PI);
}

TEST(Hemicube, ClosedBoxColumnsSumToOne) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  for (int res : {64, 256}) {
    Hemicube h(res);
    std::vector<FormFactor> col;
    for (size_t p = 0; p < m.patches.size(); p += 7)
      for (double angle : {0.0, 0.3, 1.1}) {
        h.Column(m, int(p), GroupOf(m, int(p)), angle, &col);
        EXPECT_NEAR(Sum(col), 1.0, 1e-5) << "patch " << p << " R " << res;
      }
  }
}

TEST(Hemicube, PointToParallelSquareMatchesAnalytic) {
  // A small emitter patch at the origin facing up; a square of half-size
  // `half` centred above it at height 1. Large squares reach the side faces.
  for (double half : {0.25, 1.0, 3.0}) {
    Scene s = EmptyScene();
    const double e = 1e-3;
    AddFace(&s, {{-e, -e, 0}, {e, -e, 0}, {e, e, 0}, {-e, e, 0}}, glm::dvec3(0), glm::dvec3(1));
    AddFace(&s, {{-half, -half, 1}, {-half, half, 1}, {half, half, 1}, {half, -half, 1}},
            glm::dvec3(1), glm::dvec3(0));
    MeshOptions o;
    o.patch_size = 100;  // one patch per face
    o.elements_per_patch = 16;
    Mesh m = MakeMesh(s, o);
    ASSERT_EQ(m.FacePatches(m.faces[0]).size(), 1u);
    Hemicube h(256);
    std::vector<FormFactor> col;
    h.Column(m, m.FacePatches(m.faces[0])[0], nullptr, 0.2, &col);  // alone
    const double exact = 4 * CornerParallel(half, half, 1.0);
    EXPECT_NEAR(SumOverFace(m, col, 1), exact, 0.005 * exact) << "half " << half;
  }
}

// A face of more than 65,536 vertices: the cache's outlines take 32-bit
// indices there (16 bits elsewhere), and the column is the same analytic one.
TEST(Hemicube, FaceOfManyVerticesMatchesAnalytic) {
  Scene s = EmptyScene();
  const double e = 1e-3;
  AddFace(&s, {{-e, -e, 0}, {e, -e, 0}, {e, e, 0}, {-e, e, 0}}, glm::dvec3(0), glm::dvec3(1));
  AddFace(&s, {{-1, -1, 1}, {-1, 1, 1}, {1, 1, 1}, {1, -1, 1}}, glm::dvec3(1), glm::dvec3(0));
  MeshOptions o;
  o.patch_size = 100;  // one patch per face
  o.elements_per_patch = 260;
  Mesh m = MakeMesh(s, o);
  ASSERT_GT(m.faces[1].vend - m.faces[1].vbegin, 65536);
  Hemicube h(256);
  std::vector<FormFactor> col;
  h.Column(m, m.FacePatches(m.faces[0])[0], nullptr, 0.2, &col);  // alone
  const double exact = 4 * CornerParallel(1.0, 1.0, 1.0);
  EXPECT_NEAR(SumOverFace(m, col, 1), exact, 0.005 * exact);
}

// A released cache is built again at the next column, which is the same.
TEST(Hemicube, ReleasedCacheGivesTheSameColumn) {
  const Mesh m = MakeMesh(Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}));
  Hemicube h(64);
  std::vector<FormFactor> before, after;
  h.Column(m, 5, GroupOf(m, 5), 0.3, &before);
  h.ReleaseCache();
  h.Column(m, 5, GroupOf(m, 5), 0.3, &after);
  ASSERT_FALSE(before.empty());
  EXPECT_TRUE(SameColumn(before, after));
}

TEST(Hemicube, IndependentOfScale) {
  std::vector<double> sums;
  for (double scale : {1e-4, 1.0, 1e4}) {
    Scene s = Box(scale, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
    Mesh m = MakeMesh(s);
    Hemicube h(128);
    std::vector<FormFactor> col;
    h.Column(m, 5, GroupOf(m, 5), 0.0, &col);
    sums.push_back(SumOverFace(m, col, 1) + 2 * SumOverFace(m, col, 3));
  }
  EXPECT_NEAR(sums[0], sums[1], 1e-5);
  EXPECT_NEAR(sums[2], sums[1], 1e-5);
}

// Element by element, not only summed: the near plane and the depths are
// relative to the scene, so a box at 1e-4 and at 1e4 gives the same column
// up to float rounding of the scaled coordinates, which can move a pixel
// whose centre lies on a shared edge to the neighbour: at most one pixel's
// delta form factor ((2/R)²/π, 7.8e-5 at R = 128) per element.
TEST(Hemicube, SameColumnAtAnyScale) {
  std::vector<std::vector<FormFactor>> cols;
  for (double scale : {1e-4, 1.0, 1e4}) {
    Scene s = Box(scale, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
    Mesh m = MakeMesh(s);
    Hemicube h(128);
    cols.emplace_back();
    h.Column(m, 5, GroupOf(m, 5), ShotAngle(1, 5, 0), &cols.back());
  }
  for (int k : {0, 2}) {
    ASSERT_EQ(cols[k].size(), cols[1].size()) << "scale index " << k;
    for (size_t i = 0; i < cols[1].size(); ++i) {
      EXPECT_EQ(cols[k][i].elem, cols[1][i].elem);
      EXPECT_NEAR(cols[k][i].f, cols[1][i].f, 4.0 / (128 * 128) / M_PI) << "element " << cols[1][i].elem;
    }
    EXPECT_NEAR(Sum(cols[k]), Sum(cols[1]), 1e-6);
  }
}

TEST(Hemicube, BackFacesAndFacesBehindGetNothing) {
  Scene s = EmptyScene();
  AddFace(&s, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, glm::dvec3(0), glm::dvec3(1));
  // Above but facing up (away from the shooter), and below facing down.
  AddFace(&s, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}, glm::dvec3(1), glm::dvec3(0));
  AddFace(&s, {{0, 0, -1}, {0, 1, -1}, {1, 1, -1}, {1, 0, -1}}, glm::dvec3(1), glm::dvec3(0));
  Mesh m = MakeMesh(s);
  Hemicube h(64);
  std::vector<FormFactor> col;
  for (int p : m.FacePatches(m.faces[0])) {
    h.Column(m, p, GroupOf(m, p), 0.0, &col);
    EXPECT_TRUE(col.empty());
  }
}

TEST(Hemicube, ColumnIsSortedAndPositive) {
  Scene s = Box(2.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  Hemicube h(64);
  std::vector<FormFactor> col;
  h.Column(m, 3, GroupOf(m, 3), ShotAngle(1, 3, 0), &col);
  ASSERT_FALSE(col.empty());
  for (size_t i = 0; i < col.size(); ++i) {
    EXPECT_GT(col[i].f, 0.0f);
    if (i) {
      EXPECT_LT(col[i - 1].elem, col[i].elem);
    }
  }
}

// Culling changes what is read, never the answer: bit for bit the column a
// plain z-buffer over every front-facing face gives, on every shipped scene
// from shooters all over it, turned and not, and after divisions (which the
// hemicube's cached copy of the mesh must notice). And it does cull: in the
// maze, whose walls hide most of it from most shooters, far fewer elements
// are read.
TEST(Hemicube, CullingGivesThePlainZBuffersColumns) {
  for (const char* name : {"cornell", "maze", "room", "blender"}) {
    Mesh m = ShippedMesh(name);
    Hemicube culled(128), plain(128);
    plain.set_culling(false);
    for (int pass = 0; pass < 2; ++pass) {
      ColumnStats cs, ps;
      std::vector<FormFactor> a, b;
      const int n = int(m.patches.size());
      for (int i = 0; i < 24; ++i) {
        const int p = i * (n - 1) / 23;
        const double angle = i % 2 ? ShotAngle(1, p, 0) : 0.0;
        culled.Column(m, p, GroupOf(m, p), angle, &a, &cs);
        plain.Column(m, p, GroupOf(m, p), angle, &b, &ps);
        ASSERT_TRUE(SameColumn(a, b)) << name << " pass " << pass << " patch " << p;
      }
      EXPECT_LT(cs.elements, ps.elements) << name;
      if (std::string(name) == "maze") {
        EXPECT_LT(cs.elements, ps.elements * 3 / 4);
      }
      // Then again on a mesh divided here and there, T-vertices included.
      for (int e = 0, n0 = int(m.elems.size()); e < n0; e += 5)
        if (m.elems[e].IsLeaf()) Divide(&m, e);
    }
  }
}

// Divisions add leaves within faces, not faces: the cache rebuilt after
// them (released first, as a worker's is) keeps the hierarchy over the
// faces, and its columns are a fresh cache's, bit for bit.
TEST(Hemicube, ADivisionKeepsTheHierarchy) {
  for (const char* name : {"cornell", "maze"}) {
    Mesh m = ShippedMesh(name);
    Hemicube kept(128);
    std::vector<FormFactor> a, b;
    const int n = int(m.patches.size());
    kept.Column(m, 0, GroupOf(m, 0), 0.0, &a);
    EXPECT_EQ(kept.HierarchyBuilds(), 1);
    for (int round = 0; round < 2; ++round) {
      // Here and there, T-vertices included, and some of the new leaves again.
      kept.ReleaseCache();
      for (int e = round, n0 = int(m.elems.size()); e < n0; e += 7)
        if (m.elems[e].IsLeaf()) Divide(&m, e);
      for (int i = 0; i < 12; ++i) {
        const int p = i * (n - 1) / 11;
        Hemicube fresh(128);
        kept.Column(m, p, GroupOf(m, p), 0.3, &a);
        fresh.Column(m, p, GroupOf(m, p), 0.3, &b);
        ASSERT_TRUE(SameColumn(a, b)) << name << " round " << round << " patch " << p;
      }
      EXPECT_EQ(kept.HierarchyBuilds(), 1) << name << " round " << round;
      EXPECT_EQ(kept.CacheUpdates(), round + 1) << name << " round " << round;
    }
  }
  // Another mesh of as many faces: kept where its faces lie within the
  // nodes' boxes (a box of half the size inside the first, which then
  // gives a fresh cache's columns too), built again where they do not.
  Hemicube h(128);
  std::vector<FormFactor> a, b;
  const Mesh unit = MakeMesh(Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}));
  const Mesh half = MakeMesh(Box(0.5, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}));
  const Mesh twice = MakeMesh(Box(2.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}));
  h.Column(unit, 5, GroupOf(unit, 5), 0.0, &a);
  EXPECT_EQ(h.HierarchyBuilds(), 1);
  for (int p : {0, 5, 9}) {
    Hemicube fresh(128);
    h.Column(half, p, GroupOf(half, p), 0.0, &a);
    fresh.Column(half, p, GroupOf(half, p), 0.0, &b);
    EXPECT_TRUE(SameColumn(a, b)) << "patch " << p;
  }
  EXPECT_EQ(h.HierarchyBuilds(), 1);
  h.Column(twice, 5, GroupOf(twice, 5), 0.0, &a);
  EXPECT_EQ(h.HierarchyBuilds(), 2);
}

// The cache is updated after divisions and shooter splits, reading again
// only the faces they touched (UpdateCache), as a worker's is after each
// pass: it is laid out as a fresh cache is, array by array (a split only
// reorders its face's leaves, a neighbour's midpoint only adds a T-vertex
// to an outline: neither would change a column but for depth ties), and
// its columns are a fresh cache's, bit for bit, pass after pass.
TEST(Hemicube, AnUpdatedCacheGivesAFreshOnesColumns) {
  const Scene scene = ShippedScene("room");
  MeshOptions o;
  o.elements_per_patch = 3;  // patches that can split
  Mesh m = MakeMesh(scene, o);
  Hemicube kept(128);
  std::vector<FormFactor> a, b;
  kept.Column(m, 0, GroupOf(m, 0), 0.0, &a);
  for (int pass = 0; pass < 3; ++pass) {
    kept.ReleaseCache();
    const int n0 = int(m.patches.size());
    for (int p = pass; p < n0; p += 9)
      if (SplitPieces(m, p) > 1) SplitPatch(&m, p);
    for (int e = pass, e0 = int(m.elems.size()); e < e0; e += 11)
      if (m.elems[size_t(e)].IsLeaf()) Divide(&m, e);
    const int n = int(m.patches.size());
    for (int i = 0; i < 12; ++i) {
      const int p = i * (n - 1) / 11;
      Hemicube fresh(128);
      kept.Column(m, p, GroupOf(m, p), 0.7, &a);
      fresh.Column(m, p, GroupOf(m, p), 0.7, &b);
      ASSERT_TRUE(SameColumn(a, b)) << "pass " << pass << " patch " << p;
      if (i == 0) {
        EXPECT_TRUE(kept.SameCache(fresh)) << "pass " << pass;
      }
    }
    EXPECT_EQ(kept.CacheUpdates(), pass + 1);
    EXPECT_EQ(kept.HierarchyBuilds(), 1);
  }
}

// Quad a b c d (counter-clockwise seen from its front) cut k x k and each
// cell into two triangles, every one a face of its own (as scenegen
// tessellate --tri makes them, meshed without joining).
void AddTessellated(Scene* s, const glm::dvec3 (&q)[4], int k) {
  auto at = [&](int i, int j) {
    const double u = double(i) / k, v = double(j) / k;
    return (1 - v) * ((1 - u) * q[0] + u * q[1]) + v * ((1 - u) * q[3] + u * q[2]);
  };
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) {
      AddFace(s, {at(i, j), at(i + 1, j), at(i + 1, j + 1)}, glm::dvec3(0.5), glm::dvec3(0));
      AddFace(s, {at(i, j), at(i + 1, j + 1), at(i, j + 1)}, glm::dvec3(0.5), glm::dvec3(0));
    }
}

// The same on a finely cut scene, where most leaves are smaller than a
// pixel and most faces are two triangles: a closed room cut 24 x 24 a
// wall, a box in it hiding part of it, faces kept apart. With the
// hierarchy's boxes in float, the column is the plain z-buffer's bit for
// bit, and culling reads fewer elements.
TEST(Hemicube, CullingGivesThePlainZBuffersColumnsOnATessellatedScene) {
  Scene s = EmptyScene();
  const Scene room = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(0)});
  for (const Face& f : room.faces) AddTessellated(&s, {f.verts[0], f.verts[1], f.verts[2], f.verts[3]}, 24);
  // The box [0.3, 0.6]^3 facing out: the room's faces shrunk, turned round.
  for (const Face& f : room.faces) {
    glm::dvec3 q[4];
    for (int i = 0; i < 4; ++i) q[i] = glm::dvec3(0.3) + 0.3 * f.verts[3 - i];
    AddTessellated(&s, q, 8);
  }
  s.materials[1].ke = glm::dvec3(1.0);  // a light, so that the mesh has a shooter to start from
  MeshOptions o;
  o.join = false;
  Mesh m = MakeMesh(s, o);
  ASSERT_GT(m.elems.size(), 20000u);
  Hemicube culled(64), plain(64);
  plain.set_culling(false);
  ColumnStats cs, ps;
  std::vector<FormFactor> a, b;
  const int n = int(m.patches.size());
  for (int i = 0; i < 16; ++i) {
    const int p = int((int64_t(i) * 7919) % n);
    const double angle = ShotAngle(1, p, 0);
    culled.Column(m, p, GroupOf(m, p), angle, &a, &cs);
    plain.Column(m, p, GroupOf(m, p), angle, &b, &ps);
    ASSERT_FALSE(a.empty());
    ASSERT_TRUE(SameColumn(a, b)) << "patch " << p;
  }
  EXPECT_LT(cs.elements, ps.elements);
  // Most leaves are below a pixel: far fewer are covered than drawn.
  EXPECT_LT(cs.covered * 2, ps.elements);
}

// The one column function every process calls: turned by the shot's hash
// angle when rotating, not at all otherwise; the hash depends on seed,
// patch and k, so that a patch's shots turn differently.
TEST(Hemicube, ShotColumnTurnsByTheShotsAngle) {
  Scene s = Box(2.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  Hemicube h(64), g(64);
  std::vector<FormFactor> a, b;
  auto same = [](const std::vector<FormFactor>& x, const std::vector<FormFactor>& y) {
    if (x.size() != y.size()) return false;
    for (size_t i = 0; i < x.size(); ++i)
      if (x[i].elem != y[i].elem || x[i].f != y[i].f) return false;
    return true;
  };
  ShotColumn(&h, m, 3, GroupOf(m, 3), 2, true, 7, &a);
  g.Column(m, 3, GroupOf(m, 3), ShotAngle(7, 3, 2), &b);
  EXPECT_TRUE(same(a, b));
  ShotColumn(&h, m, 3, GroupOf(m, 3), 2, false, 7, &a);
  g.Column(m, 3, GroupOf(m, 3), 0.0, &b);
  EXPECT_TRUE(same(a, b));
  EXPECT_NE(ShotAngle(7, 3, 2), ShotAngle(7, 3, 3));
  EXPECT_NE(ShotAngle(7, 3, 2), ShotAngle(8, 3, 2));
  EXPECT_NE(ShotAngle(7, 3, 2), ShotAngle(7, 4, 2));
  for (int k = 0; k < 100; ++k) {
    const double angle = ShotAngle(1, 5, k);
    EXPECT_GE(angle, 0.0);
    EXPECT_LT(angle, 2 * M_PI);
  }
}

}  // namespace
