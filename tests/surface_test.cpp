#include "surface.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <utility>

#include <gtest/gtest.h>

#include "mesh.h"
#include "radix_sort.h"
#include "results.h"
#include "scheduler.h"
#include "solver.h"
#include "test_util.h"

namespace {

// A face of material `mat` (AddFace gives each face a material of its own).
void Add(Scene* s, std::vector<glm::dvec3> verts, int mat) {
  AddFace(s, std::move(verts), glm::dvec3(0.5), glm::dvec3(0));
  s->faces.back().material = mat;
}

glm::dvec3 Bilinear(const std::vector<glm::dvec3>& q, double u, double v) {
  return (1 - u) * (1 - v) * q[0] + u * (1 - v) * q[1] + u * v * q[2] + (1 - u) * v * q[3];
}

// Every quad of `plain` cut k x k, each cell two triangles, as an exporter
// writes it: the same materials, each face's pieces in a row.
Scene Tessellate(const Scene& plain, int k) {
  Scene s = EmptyScene();
  s.materials = plain.materials;
  for (const Face& f : plain.faces)
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < k; ++i) {
        auto at = [&](int a, int b) { return Bilinear(f.verts, double(a) / k, double(b) / k); };
        Add(&s, {at(i, j), at(i + 1, j), at(i + 1, j + 1)}, f.material);
        Add(&s, {at(i, j), at(i + 1, j + 1), at(i, j + 1)}, f.material);
      }
  return s;
}

const std::vector<glm::dvec3> kSquare = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};

TEST(Surface, TessellatedBoxMeshesAndSolvesAsThePlainOne) {
  const Scene plain = Box(1.0,
                          {glm::dvec3(0.7), glm::dvec3(0.8), glm::dvec3(0.6, 0.2, 0.2),
                           glm::dvec3(0.2, 0.6, 0.2), glm::dvec3(0.5), glm::dvec3(0.4)},
                          {glm::dvec3(0), glm::dvec3(1), glm::dvec3(0), glm::dvec3(0),
                           glm::dvec3(0), glm::dvec3(0)});
  const int k = 4;
  const Scene tess = Tessellate(plain, k);
  ASSERT_EQ(tess.faces.size(), plain.faces.size() * 2 * k * k);
  MeshOptions o;
  o.patch_size = 0.2;
  const Mesh a = MakeMesh(plain, o), b = MakeMesh(tess, o);
  EXPECT_EQ(b.faces.size(), a.faces.size());
  EXPECT_EQ(b.patches.size(), a.patches.size());
  EXPECT_EQ(b.elems.size(), a.elems.size());
  o.join = false;
  EXPECT_EQ(MakeMesh(tess, o).faces.size(), tess.faces.size());

  std::vector<glm::dvec3> fa, fb;
  for (const auto& [mesh, out] : {std::make_pair(&a, &fa), std::make_pair(&b, &fb)}) {
    Mesh m = *mesh;
    Solver solver(m, true);
    RunOptions ro;
    ro.resolution = 64;
    ro.epsilon = 1e-3;
    ASSERT_EQ(RunSequential(&m, ro, &solver, nullptr, nullptr).status, RunStatus::kConverged);
    *out = FaceRadiosity(m, solver.radiosity());
  }
  ASSERT_EQ(fa.size(), plain.faces.size());
  ASSERT_EQ(fb.size(), tess.faces.size());
  for (size_t f = 0; f < plain.faces.size(); ++f) {
    glm::dvec3 sum(0.0);
    double area = 0;
    for (size_t p = f * 2 * k * k; p < (f + 1) * 2 * k * k; ++p) {
      sum += fb[p] * tess.faces[p].area;
      area += tess.faces[p].area;
    }
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c] / area, fa[f][c], 0.01 * fa[f][c]) << f;
  }
}

TEST(Surface, NearCoplanarFacesThatMustStayApart) {
  auto surfaces = [](const Scene& s) { return BuildSurfaces(s, true).size(); };
  auto pair = [](double fold) {  // a second unit square past x = 1, turned up by `fold`
    Scene s = EmptyScene();
    Add(&s, kSquare, 0);
    const double c = std::cos(fold), z = std::sin(fold);
    Add(&s, {{1, 0, 0}, {1 + c, 0, z}, {1 + c, 1, z}, {1, 1, 0}}, 0);
    return s;
  };
  EXPECT_EQ(surfaces(pair(1e-6)), 1u);  // within the tolerance
  EXPECT_EQ(surfaces(pair(1e-3)), 2u);  // a fold
  EXPECT_EQ(surfaces(pair(0.5)), 2u);

  Scene mats = pair(0);
  mats.faces[1].material = 1;
  EXPECT_EQ(surfaces(mats), 2u);

  Scene back = EmptyScene();  // a wall and its back, on the same corners
  Add(&back, kSquare, 0);
  Add(&back, {kSquare[3], kSquare[2], kSquare[1], kSquare[0]}, 0);
  EXPECT_EQ(surfaces(back), 2u);

  Scene flipped = EmptyScene();  // side by side, the second facing down
  Add(&flipped, kSquare, 0);
  Add(&flipped, {{1, 1, 0}, {2, 1, 0}, {2, 0, 0}, {1, 0, 0}}, 0);
  EXPECT_EQ(surfaces(flipped), 2u);

  Scene corner = EmptyScene();  // touching at one vertex
  Add(&corner, kSquare, 0);
  Add(&corner, {{1, 1, 0}, {2, 1, 0}, {2, 2, 0}, {1, 2, 0}}, 0);
  EXPECT_EQ(surfaces(corner), 2u);

  // A wall standing on the edge where the floor was cut.
  Scene wall = pair(0);
  Add(&wall, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}, 0);
  EXPECT_EQ(surfaces(wall), 3u);

  // An L of three squares is not convex: two surfaces, all of its area.
  Scene ell = corner;
  Add(&ell, {{1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}}, 0);
  const std::vector<Surface> l = BuildSurfaces(ell, true);
  ASSERT_EQ(l.size(), 2u);
  EXPECT_EQ(l[0].faces.size() + l[1].faces.size(), 3u);
  for (const Surface& s : l) EXPECT_NEAR(glm::length(AreaVector(s.poly)), s.area, 1e-12);
}

// A ceiling cut into 8 squares round a hole: a few convex pieces that
// cover it all.
TEST(Surface, SurfaceWithAHoleBecomesAFewConvexPieces) {
  Scene s = EmptyScene();
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i)
      if (i != 1 || j != 1) Add(&s, {{i, j, 0}, {i + 1, j, 0}, {i + 1, j + 1, 0}, {i, j + 1, 0}}, 0);
  const std::vector<Surface> out = BuildSurfaces(s, true);
  EXPECT_LE(out.size(), 4u);
  double area = 0;
  size_t faces = 0;
  for (const Surface& p : out) {
    const size_t n = p.poly.size();
    for (size_t k = 0; k < n; ++k) {
      const glm::dvec3 a = p.poly[k], b = p.poly[(k + 1) % n], c = p.poly[(k + 2) % n];
      EXPECT_GT(glm::dot(glm::cross(b - a, c - b), p.normal), 0) << "convex, no straight corner";
    }
    EXPECT_NEAR(glm::length(AreaVector(p.poly)), p.area, 1e-12);
    area += p.area;
    faces += p.faces.size();
  }
  EXPECT_EQ(faces, 8u);
  EXPECT_NEAR(area, 8.0, 1e-12);
}

// 7 significant digits, as many exporters print.
double Digits7(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.7g", x);
  return std::strtod(buf, nullptr);
}

TEST(Surface, RotatedSquarePrintedToSevenDigitsStillJoins) {
  const glm::dvec3 axis = glm::normalize(glm::dvec3(1, 2, 3)), shift(103.7, -51.3, 22.9);
  const double t = 0.7;
  auto place = [&](const glm::dvec3& p) {  // Rodrigues' rotation, then rounded
    const glm::dvec3 r = p * std::cos(t) + glm::cross(axis, p) * std::sin(t) +
                         axis * glm::dot(axis, p) * (1 - std::cos(t)) + shift;
    return glm::dvec3(Digits7(r.x), Digits7(r.y), Digits7(r.z));
  };
  Scene flat = EmptyScene();
  Add(&flat, kSquare, 0);
  Scene s = Tessellate(flat, 4);
  for (Face& f : s.faces) {
    for (glm::dvec3& v : f.verts) v = place(v);
    const glm::dvec3 n = AreaVector(f.verts);
    f.area = glm::length(n);
    f.normal = n / f.area;
  }
  const std::vector<Surface> out = BuildSurfaces(s, true);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].faces.size(), 32u);
  EXPECT_EQ(out[0].poly.size(), 4u);  // the grid points on its edges left out
  EXPECT_NEAR(out[0].area, 1.0, 2e-4);  // the corners moved by their rounding
}

// Two triangles joined into one square of 2 x 2 elements: each triangle's
// result weighs the elements by the part of them it covers.
TEST(Surface, ResultsWeighElementsByTheirOverlapWithEachFace) {
  Scene s = EmptyScene();
  Add(&s, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, 0);
  Add(&s, {{0, 0, 0}, {1, 1, 0}, {0, 1, 0}}, 0);
  MeshOptions o;
  o.patch_size = 10;
  Mesh m = MakeMesh(s, o);
  ASSERT_EQ(m.faces.size(), 1u);
  ASSERT_EQ(m.elems.size(), 4u);
  std::vector<glm::dvec3> b(m.elems.size());
  double by_cell[2][2];
  for (size_t e = 0; e < b.size(); ++e) {
    const glm::dvec3 c = m.Centroid(int(e));
    const int i = c.x > 0.5, j = c.y > 0.5;
    by_cell[i][j] = 1 + i + 4 * j;
    b[e] = glm::dvec3(by_cell[i][j]);
  }
  const std::vector<glm::dvec3> f = FaceRadiosity(m, b);
  ASSERT_EQ(f.size(), 2u);
  // Below the diagonal: half of (0,0), all of (1,0), half of (1,1).
  EXPECT_NEAR(f[0].r, (0.5 * by_cell[0][0] + by_cell[1][0] + 0.5 * by_cell[1][1]) / 2, 1e-12);
  EXPECT_NEAR(f[1].r, (0.5 * by_cell[0][0] + by_cell[0][1] + 0.5 * by_cell[1][1]) / 2, 1e-12);

  // Divided elements: the leaves are weighed, not their parents.
  Divide(&m, 0);
  b.resize(m.elems.size());
  for (size_t e = 4; e < m.elems.size(); ++e) b[e] = glm::dvec3(double(e));
  const std::vector<glm::dvec3> g = FaceRadiosity(m, b);
  std::vector<int> leaves;
  double sum = 0, area = 0;
  for (int p = 0; p < int(m.patches.size()); ++p) {
    m.Leaves(p, &leaves);
    for (int e : leaves) {
      sum += b[e].r * m.elem_area[size_t(e)];
      area += m.elem_area[size_t(e)];
    }
  }
  EXPECT_NEAR(0.5 * (g[0].r + g[1].r), sum / area, 1e-12);  // equal areas
}

TEST(Surface, OverlapAreaOfClippedPolygons) {
  const std::vector<glm::dvec2> sq = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  EXPECT_NEAR(OverlapArea(sq, sq), 1.0, 1e-15);
  EXPECT_NEAR(OverlapArea(sq, {{0.5, -1}, {2, -1}, {2, 2}, {0.5, 2}}), 0.5, 1e-15);
  EXPECT_NEAR(OverlapArea(sq, {{0, 0}, {1, 0}, {1, 1}}), 0.5, 1e-15);
  EXPECT_EQ(OverlapArea(sq, {{2, 2}, {3, 2}, {3, 3}}), 0.0);
}

// Joining makes pieces only for faces that can join; the surfaces still
// come in order of their first face, joined ones among those alone.
TEST(Surface, FacesAloneAndJoinedKeepTheirFirstFacesOrder) {
  Scene s = EmptyScene();
  Add(&s, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, 0);     // 0: half of a square
  Add(&s, {{5, 0, 0}, {5, 0, 1}, {5, 1, 1}}, 0);     // 1: alone, another plane
  Add(&s, {{0, 0, 0}, {1, 1, 0}, {0, 1, 0}}, 0);     // 2: the square's other half
  Add(&s, {{9, 0, 0}, {10, 0, 0}, {10, 1, 0}}, 0);   // 3: alone, its edges its own
  const std::vector<Surface> out = BuildSurfaces(s, true);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].faces, (std::vector<int>{0, 2}));
  EXPECT_EQ(out[0].poly.size(), 4u);
  EXPECT_EQ(out[1].faces, (std::vector<int>{1}));
  EXPECT_EQ(out[1].poly, s.faces[1].verts);  // as read
  EXPECT_EQ(out[2].faces, (std::vector<int>{3}));
  EXPECT_EQ(out[2].poly, s.faces[3].verts);
}

// radix_sort.h sorts by the key's bits from `from` up and keeps the order
// of equal keys, as std::stable_sort would.
TEST(Surface, RadixSortIsAStableSortByKey) {
  std::mt19937_64 rng(7);
  for (int from : {0, 24}) {
    std::vector<std::pair<uint64_t, int>> items(5000), want;
    for (size_t i = 0; i < items.size(); ++i)
      items[i] = {rng() % 64 << 40 | rng() % 3 << 20 | (rng() & 0xffffff), int(i)};
    items.push_back({~uint64_t{0}, -1});  // the top byte in use, too
    want = items;
    std::stable_sort(want.begin(), want.end(), [&](const auto& a, const auto& b) {
      return a.first >> from < b.first >> from;
    });
    RadixSort(&items, [](const std::pair<uint64_t, int>& x) { return x.first; }, from);
    EXPECT_EQ(items, want) << "from bit " << from;
  }
}

}  // namespace
