#include "mesh.h"

#include <cmath>
#include <map>
#include <utility>

#include <gtest/gtest.h>

#include "point_ids.h"
#include "test_util.h"

namespace {

double LeafArea(const Mesh& m, int face) {
  double a = 0;
  std::vector<int> leaves;
  m.FaceLeaves(m.faces[face], &leaves);
  for (int e : leaves) a += m.elem_area[size_t(e)];
  return a;
}

double MaxEdge(const Mesh& m, int patch) {
  // Extent of a patch: the largest distance between two of its corners.
  std::vector<glm::dvec3> pts;
  for (int e : m.Tops(patch))
    for (int k = 0; k < (m.elems[e].IsTriangle() ? 3 : 4); ++k) pts.push_back(m.verts[m.elems[e].v[k]]);
  double d = 0;
  for (const auto& a : pts)
    for (const auto& b : pts) d = std::max(d, glm::length(a - b));
  return d;
}

TEST(Mesh, DefaultRuleCutsToADiagonalSixteenth) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  EXPECT_NEAR(m.scene_diagonal, std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(m.patch_size, std::sqrt(3.0) / 16, 1e-12);
  // 1 / (sqrt(3)/16) = 9.24 -> 10 x 10 patches a face, 2 x 2 elements each.
  EXPECT_EQ(m.patches.size(), 6u * 100);
  EXPECT_EQ(m.elems.size(), 6u * 400);
  for (size_t p = 0; p < m.patches.size(); ++p) {
    EXPECT_LE(MaxEdge(m, int(p)), m.patch_size * std::sqrt(2.0) + 1e-12);
    EXPECT_EQ(m.Tops(p).size(), 4u);
  }
}

TEST(Mesh, ElementsTileEveryFaceExactly) {
  Scene s = EmptyScene();
  AddFace(&s, {{0, 0, 0}, {3, 0, 0}, {0, 2, 0}}, glm::dvec3(0.5), glm::dvec3(0));  // triangle
  AddFace(&s, {{0, 0, 1}, {2, 0, 1}, {2.5, 1, 1}, {0.2, 1.4, 1}}, glm::dvec3(0.5),
          glm::dvec3(0));  // convex quad, not a parallelogram
  AddFace(&s, {{0, 0, 2}, {2, 0, 2}, {2, 2, 2}, {1, 1, 2}, {0, 2, 2}}, glm::dvec3(0.5),
          glm::dvec3(0));  // concave pentagon
  AddFace(&s, {{0, 0, 3}, {2, 0, 3}, {3, 1, 3}, {2, 2, 3}, {0, 2, 3}, {-1, 1, 3}},
          glm::dvec3(0.5), glm::dvec3(0));  // hexagon
  MeshOptions o;
  o.patch_size = 0.3;
  o.elements_per_patch = 3;
  Mesh m = MakeMesh(s, o);
  for (size_t f = 0; f < s.faces.size(); ++f) {
    EXPECT_NEAR(LeafArea(m, int(f)), s.faces[f].area, 1e-9 * s.faces[f].area) << "face " << f;
    double pa = 0;
    for (int p : m.FacePatches(m.faces[f])) pa += m.patch_area[size_t(p)];
    EXPECT_NEAR(pa, s.faces[f].area, 1e-9 * s.faces[f].area);
  }
  // Every element faces the way its face does.
  for (size_t e = 0; e < m.elems.size(); ++e) {
    const Element& el = m.elems[e];
    std::vector<glm::dvec3> poly;
    for (int k = 0; k < (el.IsTriangle() ? 3 : 4); ++k) poly.push_back(m.verts[el.v[k]]);
    EXPECT_GT(glm::dot(AreaVector(poly), m.FaceOf(int(e)).normal), 0) << "element " << e;
  }
}

// Two faces cut alike along a common edge get bit-identical points there,
// whichever way each walks the edge: the hemicube then sees no crack.
TEST(Mesh, CommonEdgePointsAreBitIdentical) {
  Scene s = EmptyScene();
  AddFace(&s, {{0, 0, 0}, {0.7, 0, 0.1}, {0.7, 0.9, 0.1}, {0, 0.9, 0}}, glm::dvec3(0.5),
          glm::dvec3(0));
  // Listed from the edge's other end, so its grid walks the edge backwards.
  AddFace(&s, {{0.7, 0.9, 0.1}, {0.7, 0, 0.1}, {1.3, 0.1, 0.9}, {1.3, 1.0, 0.9}},
          glm::dvec3(0.5), glm::dvec3(0));
  MeshOptions o;
  o.patch_size = 0.1;
  Mesh m = MakeMesh(s, o);
  auto on_edge = [](const glm::dvec3& p) {
    return std::abs(p.x - 0.7) < 1e-9 && std::abs(p.z - 0.1) < 1e-9;
  };
  std::map<double, int> count;  // y -> faces with a vertex there
  for (const MeshFace& f : m.faces)
    for (int v = f.vbegin; v < f.vend; ++v)
      if (on_edge(m.verts[v]) && m.verts[v].x == 0.7 && m.verts[v].z == 0.1) ++count[m.verts[v].y];
  ASSERT_GT(count.size(), 5u);
  for (const auto& [y, n] : count) EXPECT_EQ(n, 2) << "y " << y;
}

TEST(Mesh, PatchCentresLieOnTheirFace) {
  Scene s = Box(2.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  for (size_t p = 0; p < m.patches.size(); ++p) {
    const MeshFace& f = m.faces[m.patches[p].face];
    EXPECT_NEAR(glm::dot(f.normal, m.patch_center[p]), f.offset, 1e-12);
  }
}

TEST(Mesh, RefusesAbsurdElementCounts) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  MeshOptions o;
  o.patch_size = 1e-5;
  Mesh m;
  std::string err;
  EXPECT_FALSE(BuildMesh(s, o, &m, &err));
  EXPECT_NE(err.find("elements"), std::string::npos) << err;
}

TEST(Mesh, MeshHashSeesGeometryAndHierarchy) {
  const Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  const Mesh a = MakeMesh(s);
  const uint64_t h = MeshHash(a);
  EXPECT_EQ(MeshHash(MakeMesh(s)), h);
  MeshOptions o;
  o.elements_per_patch = 3;
  EXPECT_NE(MeshHash(MakeMesh(s, o)), h);
  Mesh b = a;
  b.verts[17].y = std::nextafter(b.verts[17].y, 2.0);  // one bit of one coordinate
  EXPECT_NE(MeshHash(b), h);
  b = a;
  std::swap(b.elems[3].v[0], b.elems[3].v[1]);
  EXPECT_NE(MeshHash(b), h);
  b = a;
  b.elems[5].first_child = int(b.elems.size());  // as if divided
  EXPECT_NE(MeshHash(b), h);
  b = a;
  // One more element, with the arrays kept beside the elements (its
  // parent, its area) grown alike, as every change to the mesh does.
  b.elems.push_back(b.elems.back());
  b.parent.push_back(b.parent.back());
  b.elem_area.push_back(b.elem_area.back());
  EXPECT_NE(MeshHash(b), h);
  Scene moved = s;
  for (auto& f : moved.faces)
    for (auto& v : f.verts) v.x += 1;
  moved.lo.x += 1;
  moved.hi.x += 1;
  EXPECT_NE(MeshHash(MakeMesh(moved)), h);
}

// A face's leaves are its patches' in turn, divided and split too, and
// every leaf is one face's; each call replaces what the vector held.
TEST(Mesh, FaceLeavesAreItsPatchesLeavesInTurn) {
  MeshOptions o;
  o.elements_per_patch = 2;
  Mesh m = MakeMesh(Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}), o);
  Divide(&m, 0);
  Divide(&m, m.elems[0].first_child + 2);
  const int split = m.elems[0].patch;
  ASSERT_GT(SplitPieces(m, split), 1);
  SplitPatch(&m, split);
  std::vector<int> got{-1}, want, leaves{-1};
  size_t total = 0;
  for (const MeshFace& f : m.faces) {
    m.FaceLeaves(f, &got);
    want.clear();
    for (int p : m.FacePatches(f)) {
      m.Leaves(p, &leaves);
      want.insert(want.end(), leaves.begin(), leaves.end());
    }
    EXPECT_EQ(got, want);
    total += got.size();
  }
  EXPECT_EQ(long(total), m.LeafCount());
}

}  // namespace

// BuildMesh's `read` hook comes after the last read of the faces'
// vertices: a caller that frees them there (the worker) gets the same mesh,
// joined surfaces included, and the corners they keep.
TEST(Mesh, VerticesFreedAtTheReadHookChangeNothing) {
  size_t corners = 0;
  for (const char* name : {"cornell", "cornell-holes", "room", "maze", "blender"}) {
    Scene scene = ShippedScene(name);
    std::string err;
    const Mesh want = MakeMesh(scene);
    Mesh got;
    int calls = 0;
    ASSERT_TRUE(BuildMesh(scene, MeshOptions(), &got, &err, [&] {
      ++calls;
      DropVertices(&scene);
    })) << err;
    EXPECT_EQ(calls, 1) << name;
    EXPECT_EQ(MeshHash(got), MeshHash(want)) << name;
    EXPECT_EQ(got.face_corners, want.face_corners) << name;
    corners += want.face_corners.size();
    EXPECT_TRUE(scene.faces[0].verts.empty()) << name;
  }
  EXPECT_GT(corners, 0u);  // some faces joined into surfaces
}

// Surfaces consumed as they are cut (the worker's BuildMesh): the same
// mesh, links to the scene's faces included, and the surfaces freed,
// their array too.
TEST(Mesh, SurfacesConsumedAsCutChangeNothing) {
  for (const char* name : {"cornell", "cornell-holes", "room", "maze", "blender"}) {
    Scene scene = ShippedScene(name);
    std::string err;
    const std::vector<Surface> surfaces = BuildSurfaces(scene, true);
    Mesh want, got;
    ASSERT_TRUE(BuildMesh(scene, surfaces, MeshOptions(), &want, &err)) << err;
    std::vector<Surface> consumed = surfaces;
    ASSERT_TRUE(BuildMesh(scene, std::move(consumed), MeshOptions(), &got, &err)) << err;
    EXPECT_EQ(MeshHash(got), MeshHash(want)) << name;
    EXPECT_EQ(got.face_scene, want.face_scene) << name;
    EXPECT_EQ(got.face_corners, want.face_corners) << name;
    EXPECT_EQ(consumed.capacity(), 0u) << name;
  }
}

// Joining sizes the weld table once for every corner: the same ids as a
// table grown point by point, the first point seen getting the next id.
TEST(Mesh, PointIdsReservedWeldAsGrown) {
  std::vector<glm::dvec3> grown_pts, reserved_pts;
  PointIds grown(&grown_pts), reserved(&reserved_pts);
  reserved.Reserve(3000);
  for (int i = 0; i < 3000; ++i) {
    const glm::dvec3 p(i % 37, (i * 7) % 41, i % 2 ? 0.0 : -0.0);  // repeats, and -0 as 0
    const int id = grown.Id(p);
    EXPECT_EQ(reserved.Id(p), id);
    EXPECT_EQ(grown_pts[size_t(id)], p);
  }
  EXPECT_EQ(reserved_pts, grown_pts);
  EXPECT_LT(grown_pts.size(), 3000u);
}
