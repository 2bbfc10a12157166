// Run-time subdivision: Divide() and its bookkeeping, the Solver's side
// (sharing radiosity by gradient, old columns, waves), the hemicube and
// the shading across T-vertices, and the policy on scenes with smooth and
// with sharp light.
#include "subdivide.h"

#include <cmath>

#include <gtest/gtest.h>

#include "groups.h"
#include "hemicube.h"
#include "scheduler.h"
#include "results.h"
#include "test_util.h"

namespace {

double Sum(const std::vector<FormFactor>& col) {
  double s = 0;
  for (const auto& f : col) s += f.f;
  return s;
}

// One unit square (face 0) cut into n x n elements, one patch.
Mesh Square(int n) {
  Scene s = EmptyScene();
  AddFace(&s, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, glm::dvec3(0.5), glm::dvec3(0));
  MeshOptions o;
  o.patch_size = 10;
  o.elements_per_patch = n;
  return MakeMesh(s, o);
}

int LeafAt(const Mesh& m, const glm::dvec3& p) {
  int best = -1;
  double d = HUGE_VAL;
  for (size_t e = 0; e < m.elems.size(); ++e)
    if (m.elems[e].IsLeaf() && glm::length(m.Centroid(int(e)) - p) < d) {
      d = glm::length(m.Centroid(int(e)) - p);
      best = int(e);
    }
  return best;
}

TEST(Divide, QuadAndTriangleChildrenTileTheParent) {
  Scene s = EmptyScene();
  AddFace(&s, {{0, 0, 0}, {2, 0, 0}, {2.5, 1, 0}, {0.2, 1.4, 0}}, glm::dvec3(0.5), glm::dvec3(0));
  AddFace(&s, {{0, 0, 1}, {3, 0, 1}, {0, 2, 1}}, glm::dvec3(0.5), glm::dvec3(0));
  MeshOptions o;
  o.patch_size = 10;
  o.elements_per_patch = 1;
  Mesh m = MakeMesh(s, o);
  ASSERT_EQ(m.elems.size(), 2u);
  for (int e : {0, 1}) {
    Divide(&m, e);
    const Element& p = m.elems[e];
    ASSERT_FALSE(p.IsLeaf());
    double a = 0;
    for (int k = 0; k < kChildren; ++k) {
      const Element& c = m.elems[p.first_child + k];
      EXPECT_EQ(c.level, 1);
      EXPECT_EQ(m.parent[size_t(p.first_child + k)], e);
      EXPECT_EQ(c.patch, p.patch);
      EXPECT_EQ(c.IsTriangle(), p.IsTriangle());
      EXPECT_GT(m.elem_area[size_t(p.first_child + k)], 0);
      a += m.elem_area[size_t(p.first_child + k)];
      std::vector<glm::dvec3> poly;
      for (int v = 0; v < (c.IsTriangle() ? 3 : 4); ++v) poly.push_back(m.verts[c.v[v]]);
      EXPECT_GT(glm::dot(AreaVector(poly), m.FaceOf(e).normal), 0) << "child faces its face's way";
    }
    EXPECT_NEAR(a, m.elem_area[size_t(e)], 1e-12 * m.elem_area[size_t(e)]);
  }
  EXPECT_EQ(m.LeafCount(), 8);
}

// Neighbours divided one after the other share their common midpoint
// (one vertex id); before the second is divided, it holds it as a
// T-vertex; LeafNeighbours sees alike, finer and coarser neighbours.
TEST(Divide, NeighboursShareMidpointsAndSeeTVertices) {
  Mesh m = Square(2);  // elements 0..3: (0,0) (1,0) (0,1) (1,1)
  const int a = LeafAt(m, {0.25, 0.25, 0}), b = LeafAt(m, {0.75, 0.25, 0});
  Divide(&m, a);
  const int mid = MidpointOf(m, m.elems[a].v[1], m.elems[a].v[2]);
  EXPECT_EQ(m.verts[mid], glm::dvec3(0.5, 0.25, 0));
  int tvs = 0;
  for (int v : m.Mids(b)) tvs += v == mid;
  EXPECT_EQ(tvs, 1) << "b holds a's midpoint as a T-vertex";
  std::vector<int> nb;
  LeafNeighbours(m, b, &nb);
  EXPECT_EQ(nb.size(), 3u) << "two finer children of a, and the element above";
  const int child = LeafAt(m, {0.375, 0.125, 0});
  LeafNeighbours(m, child, &nb);
  EXPECT_NE(std::find(nb.begin(), nb.end(), b), nb.end()) << "the coarser neighbour";
  const size_t verts = m.verts.size();
  Divide(&m, b);
  EXPECT_EQ(m.verts.size(), verts + 4) << "3 new midpoints and a centre, the shared one reused";
  for (int k = 0; k < kChildren; ++k)
    for (int v : m.Mids(m.elems[b].first_child + k)) EXPECT_LT(v, 0);
}

TEST(Divide, SameEditsGiveTheSameMesh) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  Mesh a = MakeMesh(s), b = MakeMesh(s);
  for (int e : {5, 6, 7, 105, 2400, 2401, 2405, 300}) {
    Divide(&a, e);
    Divide(&b, e);
  }
  ASSERT_EQ(a.verts.size(), b.verts.size());
  ASSERT_EQ(a.elems.size(), b.elems.size());
  for (size_t v = 0; v < a.verts.size(); ++v) EXPECT_EQ(a.verts[v], b.verts[v]);
  for (size_t e = 0; e < a.elems.size(); ++e) {
    EXPECT_EQ(a.elems[e].v, b.elems[e].v);
    EXPECT_EQ(a.Mids(int(e)), b.Mids(int(e)));
    EXPECT_EQ(a.elems[e].first_child, b.elems[e].first_child);
  }
}

// A closed box divided unevenly (levels 0 and 1 side by side, T-vertices
// inside faces and where faces meet): columns still sum to 1, also with
// the hemicube aligned with the edges (angle 0), where a crack would
// catch whole rows of pixel centres.
TEST(Divide, HemicubeSeesNoCracks) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  for (int e = 0; e < 2400; e += 3) Divide(&m, e);
  for (int res : {64, 256}) {
    Hemicube h(res);
    std::vector<FormFactor> col;
    for (size_t p = 0; p < m.patches.size(); p += 7)
      for (double angle : {0.0, 0.3, 1.1}) {
        h.Column(m, int(p), GroupOf(m, int(p)), angle, &col);
        EXPECT_NEAR(Sum(col), 1.0, 1e-5) << "patch " << p << " R " << res;
        for (const FormFactor& f : col) ASSERT_TRUE(m.elems[f.elem].IsLeaf());
      }
  }
}

// Shading: a T-vertex has the value halfway along the coarser edge.
TEST(Divide, ShadingInterpolatesAtTVertices) {
  Mesh m = Square(2);
  const int a = LeafAt(m, {0.25, 0.25, 0});
  Divide(&m, a);
  std::vector<glm::dvec3> b(m.elems.size());
  for (size_t e = 0; e < b.size(); ++e) b[e] = glm::dvec3(m.Centroid(int(e)).x * 3 + 1);
  ShadedMesh sh = Shade(m, b);
  for (size_t i = 0; i < m.elems.size(); ++i) {
    const Element& e = m.elems[i];
    if (!e.IsLeaf()) continue;
    const std::array<int, 4> mids = m.Mids(int(i));
    for (int k = 0; k < 4; ++k)
      if (mids[k] >= 0) {
        const glm::vec3 want = 0.5f * (sh.colors[e.v[k]] + sh.colors[e.v[(k + 1) % 4]]);
        EXPECT_FLOAT_EQ(sh.colors[mids[k]].r, want.r);
      }
  }
}

// Closed box, light from one wall: a solver state with real gradients.
struct Lit {
  Scene scene = Box(1.0, {glm::dvec3(0.6)}, {glm::dvec3(0), glm::dvec3(4), glm::dvec3(0),
                                             glm::dvec3(0), glm::dvec3(0), glm::dvec3(0)});
  Mesh mesh = MakeMesh(scene);
};

TEST(Solver, DividedKeepsPowerAndFollowsTheGradient) {
  Lit lit;
  Solver solver(lit.mesh, true);
  RunOptions o;
  o.resolution = 64;
  o.max_shots = 150;
  RunSequential(&lit.mesh, o, &solver, nullptr, nullptr);
  const std::vector<glm::dvec3> before = solver.radiosity();
  std::vector<int32_t> edits;
  for (int e = 0; e < 2400; e += 5) edits.push_back(e);
  for (int32_t e : edits) Divide(&lit.mesh, e);
  solver.Divided(edits);
  const auto& b = solver.radiosity();
  ASSERT_EQ(b.size(), lit.mesh.elems.size());
  int shaped = 0;
  for (int32_t e : edits) {
    const Element& p = lit.mesh.elems[e];
    glm::dvec3 power(0.0);
    for (int k = 0; k < kChildren; ++k) {
      const int c = p.first_child + k;
      power += b[c] * lit.mesh.elem_area[size_t(c)];
      for (int ch = 0; ch < 3; ++ch) EXPECT_GE(b[c][ch], 0);
      shaped += std::abs(b[c].r - before[e].r) > 1e-9 * before[e].r;
    }
    for (int ch = 0; ch < 3; ++ch)
      EXPECT_NEAR(power[ch], before[e][ch] * lit.mesh.elem_area[size_t(e)],
                  1e-12 * before[e][ch] * lit.mesh.elem_area[size_t(e)]) << e;
  }
  EXPECT_GT(shaped, int(edits.size())) << "children differ where the light does";
}

// A column computed before a division: what a divided element receives
// goes to every leaf under it alike, and the power shot is the same.
TEST(Solver, ShootsColumnsOfAnOlderHierarchy) {
  Lit lit;
  Mesh& m = lit.mesh;
  Hemicube h(64);
  Solver solver(m, false);
  const int p = solver.Select();
  std::vector<FormFactor> col;
  h.Column(m, p, GroupOf(m, p), 0.0, &col);
  std::vector<int32_t> edits;
  for (const FormFactor& f : col)
    if (f.elem % 3 == 0) edits.push_back(f.elem);
  ASSERT_FALSE(edits.empty());
  for (int32_t e : edits) Divide(&m, e);
  solver.Divided(edits);
  const std::vector<glm::dvec3> before = solver.radiosity();
  solver.Shoot(p, col);
  const auto& after = solver.radiosity();
  double got = 0, want = 0;
  std::vector<int> leaves;
  for (const FormFactor& f : col) {
    const double rho = m.Rho(m.FaceOf(f.elem)).r;
    want += rho * 4 * f.f * m.patch_area[size_t(p)];
    m.LeavesUnder(f.elem, &leaves);
    for (int l : leaves) {
      EXPECT_NEAR(after[l].r - before[l].r, rho * 4 * f.f * m.patch_area[size_t(p)] / m.elem_area[size_t(f.elem)], 1e-9);
      got += (after[l].r - before[l].r) * m.elem_area[size_t(l)];
    }
  }
  EXPECT_NEAR(got, want, 1e-9 * want);
}

TEST(Solver, NewWaveStartsFromTheEmitters) {
  Lit lit;
  Solver solver(lit.mesh, true);
  RunOptions o;
  o.resolution = 32;
  o.max_shots = 20;
  RunSequential(&lit.mesh, o, &solver, nullptr, nullptr);
  Divide(&lit.mesh, 7);
  solver.Divided({7});
  solver.NewWave();
  EXPECT_EQ(solver.UnshotFraction(), 1.0);
  for (size_t e = 0; e < lit.mesh.elems.size(); ++e)
    EXPECT_EQ(solver.radiosity()[e], lit.mesh.Emission(lit.mesh.FaceOf(int(e))));
  for (size_t p = 0; p < lit.mesh.patches.size(); ++p) EXPECT_EQ(solver.TimesShot(int(p)), 0);
}

RunResult Adaptive(Mesh* m, Solver* s, Subdivider* sub, double eps, int res = 64,
                   std::vector<int>* wave_ends = nullptr) {
  RunOptions o;
  o.resolution = res;
  o.epsilon = eps;
  if (wave_ends) o.wave_end = [&](int w) { wave_ends->push_back(w); };
  return RunSequential(m, o, s, sub, nullptr);
}

// Smooth light is never divided: the furnace (and FarSquares, below).
TEST(Subdivider, SmoothLightIsNotDivided) {
  {
    Scene s = Box(1.0, {glm::dvec3(0.9)}, {glm::dvec3(1.0)});
    Mesh m = MakeMesh(s);
    Solver solver(m, true);
    Subdivider sub(&m, SubdivideOptions());
    RunResult r = Adaptive(&m, &solver, &sub, 1e-4);
    ASSERT_EQ(r.status, RunStatus::kConverged);
    EXPECT_EQ(m.LeafCount(), 2400);
    EXPECT_GT(r.passes, 0);
    EXPECT_TRUE(sub.finished());
    EXPECT_EQ(r.waves, 1);
    for (const glm::dvec3& b : FaceRadiosity(m, solver.radiosity())) EXPECT_NEAR(b.r, 10, 0.05);
  }
}

// Two squares 4 apart, one the light: the other is lit within 6%, and at
// R 64 its elements are about a pixel of each shot, counted ±100%. The
// dividing factor takes that for noise, not light (subdivide.h), at every
// resolution.
Scene FarSquares() {
  Scene s = EmptyScene();
  AddFace(&s, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, glm::dvec3(0), glm::dvec3(1));
  AddFace(&s, {{0, 0, 4}, {0, 1, 4}, {1, 1, 4}, {1, 0, 4}}, glm::dvec3(1), glm::dvec3(0));
  return s;
}

TEST(Subdivider, UniformLightIsNotDividedAtAnyResolution) {
  for (int res : {64, 128, 256, 512}) {
    Mesh m = MakeMesh(FarSquares());
    const long n = m.LeafCount();
    Solver solver(m, true);
    Subdivider sub(&m, SubdivideOptions());
    ASSERT_EQ(Adaptive(&m, &solver, &sub, 1e-6, res).status, RunStatus::kConverged);
    EXPECT_GT(sub.passes(), 0);
    EXPECT_EQ(m.LeafCount(), n) << "R " << res;
  }
}

// The variance Shoot adds (Solver::TrackNoise) against the spread of what
// the squares' receiver gets from one light patch over 64 turns of the
// hemicube: summed over its elements, the model is 1 to 5 times the
// measured variance (its sigma 1 to 2.2 times; it errs toward dividing
// less: straight outlines lose and gain fewer pixels than random ones)
// at R 64 and R 256.
TEST(Solver, NoiseIsAboutTheSpreadOfTurnedHemicubes) {
  const Mesh m = MakeMesh(FarSquares());
  for (int res : {64, 256}) {
    Hemicube h(res);
    std::vector<double> sum(m.elems.size()), sum2(m.elems.size()), model(m.elems.size());
    constexpr int kTurns = 64;
    std::vector<FormFactor> col;
    for (int k = 0; k < kTurns; ++k) {
      Solver solver(m, false);
      solver.TrackNoise(res);
      ShotColumn(&h, m, 0, GroupOf(m, 0), k, true, 1, &col);
      solver.Shoot(0, col);
      for (size_t e = 0; e < m.elems.size(); ++e) {
        const glm::dvec3& b = solver.radiosity()[e];
        const double lum = (b.r + b.g + b.b) / 3;
        sum[e] += lum;
        sum2[e] += lum * lum;
        model[e] += solver.noise()[e];
      }
    }
    double measured = 0, modelled = 0;
    for (size_t e = 0; e < m.elems.size(); ++e) {
      if (m.patches[m.elems[e].patch].face != 1) continue;
      const double mean = sum[e] / kTurns;
      measured += sum2[e] / kTurns - mean * mean;
      modelled += model[e] / kTurns;
    }
    EXPECT_GT(modelled, measured) << "R " << res;
    EXPECT_LT(modelled, 5 * measured) << "R " << res;
    std::printf("R %d: modelled variance %.3g, measured %.3g\n", res, modelled, measured);
  }
}

// The shadow's floor elements are 1/16 of their distance from the light
// across: about 4 of its pixels at R 64, where one shot counts them ±25%
// and even the shadow's full edge is at the limit of what the dividing
// factor takes for light (subdivide.h); at R 128, 16 pixels, it is far
// beyond.
constexpr int kShadowRes = 128;

TEST(Subdivider, SharpShadowIsDividedAlongItsEdge) {
  Scene s = ShadowScene();
  MeshOptions o;
  o.patch_size = 0.25;
  Mesh m = MakeMesh(s, o);
  Solver solver(m, true);
  Subdivider sub(&m, SubdivideOptions());
  std::vector<int> ends;
  RunResult r = Adaptive(&m, &solver, &sub, 1e-3, 256, &ends);
  ASSERT_EQ(r.status, RunStatus::kConverged);
  EXPECT_GT(r.waves, 1);
  ASSERT_EQ(int(ends.size()), r.waves - 1);
  for (size_t i = 0; i < ends.size(); ++i) EXPECT_EQ(ends[i], int(i) + 1);
  double near_n = 0, near_a = 0, far_n = 0, far_a = 0;
  for (size_t e = 0; e < m.elems.size(); ++e) {
    const Element& el = m.elems[e];
    if (!el.IsLeaf() || m.patches[el.patch].face != 0) continue;
    const glm::dvec3 c = m.Centroid(int(e));
    const double d = std::max(std::abs(c.x - 0.5), std::abs(c.y - 0.5));
    const bool near = std::abs(d - 0.4) < 0.1;
    (near ? near_n : far_n) += 1;
    (near ? near_a : far_a) += m.elem_area[size_t(e)];
  }
  const double density_near = near_n / near_a, density_far = far_n / far_a;
  EXPECT_GT(density_near, 4 * density_far) << near_n << " near, " << far_n << " elsewhere";

  // Against a converged uniform fine mesh, point by point, it is closer
  // than the same run without subdivision.
  MeshOptions fine = o;
  fine.elements_per_patch = 16;
  Mesh ref = MakeMesh(s, fine);
  Solver ref_solver(ref, true);
  ASSERT_EQ(Adaptive(&ref, &ref_solver, nullptr, 1e-4, 256).status, RunStatus::kConverged);
  Mesh plain = MakeMesh(s, o);
  Solver plain_solver(plain, true);
  ASSERT_EQ(Adaptive(&plain, &plain_solver, nullptr, 1e-3, 256).status, RunStatus::kConverged);
  double rms, adaptive_err, plain_err;
  FieldError(m, solver.radiosity(), ref, ref_solver.radiosity(), &rms, &adaptive_err);
  FieldError(plain, plain_solver.radiosity(), ref, ref_solver.radiosity(), &rms, &plain_err);
  EXPECT_LT(adaptive_err, 0.7 * plain_err) << "adaptive " << adaptive_err << ", plain " << plain_err;
  std::printf("sharp shadow: %ld -> %ld elements in %d waves, %.0f near the edge, %.0f elsewhere; "
              "error per point %.4f (plain %.4f)\n",
              plain.LeafCount(), m.LeafCount(), r.waves, near_n, far_n, adaptive_err, plain_err);
}

// A wave's picture is drawn on another thread while the next wave shoots
// (app.cpp), from the mesh's points: the mesh stays as it was at the
// wave's end until mesh_changes has been called, and a pass that divides
// calls it first.
TEST(Subdivider, TheMeshStaysUntilMeshChangesIsCalled) {
  Scene s = ShadowScene();
  MeshOptions mo;
  mo.patch_size = 0.25;
  Mesh m = MakeMesh(s, mo);
  Solver solver(m, true);
  Subdivider sub(&m, SubdivideOptions());
  RunOptions o;
  o.resolution = 128;
  o.epsilon = 1e-3;
  size_t drawn = 0;  // elements at the wave's end; 0: no picture being drawn
  int pictures = 0, calls = 0;
  o.wave_end = [&](int) {
    drawn = m.elems.size();
    ++pictures;
  };
  o.mesh_changes = [&] {
    if (drawn) {
      EXPECT_EQ(m.elems.size(), drawn) << "the mesh changed under a picture";
    }
    drawn = 0;
    ++calls;
  };
  const RunResult r = RunSequential(&m, o, &solver, &sub, [&](const Sample&) {
    if (drawn) {
      EXPECT_EQ(m.elems.size(), drawn) << "the mesh changed under a picture";
    }
  });
  ASSERT_EQ(r.status, RunStatus::kConverged);
  EXPECT_GT(pictures, 0);
  EXPECT_GT(m.LeafCount(), MakeMesh(s, mo).LeafCount());  // it divided
  EXPECT_GE(calls, r.passes);
}

TEST(Subdivider, WithoutWavesOneWave) {
  Scene s = ShadowScene();
  MeshOptions o;
  o.patch_size = 0.25;
  Mesh m = MakeMesh(s, o);
  Solver solver(m, true);
  SubdivideOptions so;
  so.waves = false;
  Subdivider sub(&m, so);
  RunResult r = Adaptive(&m, &solver, &sub, 1e-3, kShadowRes);
  EXPECT_EQ(r.status, RunStatus::kConverged);
  EXPECT_EQ(r.waves, 1);
  EXPECT_GT(m.LeafCount(), int(m.patches.size()) * 4);
}

// The element cap: a pass that would pass max_elements divides nothing and
// ends subdivision; the run still converges on the mesh it has.
TEST(Subdivider, StopsAtTheElementCap) {
  Scene s = ShadowScene();
  MeshOptions o;
  o.patch_size = 0.25;
  Mesh m = MakeMesh(s, o);
  const size_t built = m.elems.size();
  Solver solver(m, true);
  SubdivideOptions so;
  so.max_elements = long(built) + 2 * kChildren;  // room for two divisions, not a pass
  Subdivider sub(&m, so);
  RunResult r = Adaptive(&m, &solver, &sub, 1e-3, kShadowRes);
  EXPECT_EQ(r.status, RunStatus::kConverged);
  EXPECT_TRUE(sub.capped());
  EXPECT_TRUE(sub.finished());
  EXPECT_EQ(m.elems.size(), built);
}

// No division makes an edge shorter than min_size: a strip whose elements
// are 0.05 x 0.125 across the shadow's edges is divided with min_size
// 0.02, and not at all with 0.04 (half its long edge would pass, half its
// short edge not), while the floor's 0.125 squares still are.
TEST(Subdivider, ThinElementsAreNotDivided) {
  Scene s = ShadowScene();
  AddFace(&s, {{-1, 0.45, 0.5}, {2, 0.45, 0.5}, {2, 0.55, 0.5}, {-1, 0.55, 0.5}}, glm::dvec3(0.6),
          glm::dvec3(0));  // faces up, under the blocker
  const int strip = int(s.faces.size()) - 1;
  MeshOptions o;
  o.patch_size = 0.25;
  for (double min_size : {0.02, 0.04}) {
    Mesh m = MakeMesh(s, o);
    auto leaves = [&m](int face) {
      long n = 0;
      for (const Element& el : m.elems) n += el.IsLeaf() && m.patches[el.patch].face == face;
      return n;
    };
    const long strip0 = leaves(strip), floor0 = leaves(0);
    Solver solver(m, true);
    SubdivideOptions so;
    so.min_size = min_size;
    Subdivider sub(&m, so);
    ASSERT_EQ(Adaptive(&m, &solver, &sub, 1e-3, kShadowRes).status, RunStatus::kConverged);
    EXPECT_GT(leaves(0), floor0) << "min_size " << min_size;
    if (min_size < 0.025) EXPECT_GT(leaves(strip), strip0);
    else EXPECT_EQ(leaves(strip), strip0);
  }
}

// Incremental passes divide exactly what evaluating every leaf divides:
// the same mesh, bit for bit the same radiosity, through the waves of a
// sharp shadow with overshooting on and off, evaluating fewer leaves.
TEST(Subdivider, IncrementalPassesDivideAsEvaluatingEveryLeaf) {
  const Scene scene = ShadowScene();
  MeshOptions mo;
  mo.patch_size = 0.25;
  for (bool over : {true, false}) {
    Mesh m[2];
    long passes[2] = {0, 0}, evaluated[2] = {0, 0};
    std::vector<glm::dvec3> b[2];
    for (int i = 0; i < 2; ++i) {
      m[i] = MakeMesh(scene, mo);
      SubdivideOptions so;
      so.incremental = i == 0;
      Subdivider sub(&m[i], so);
      Solver solver(m[i], over);
      RunOptions o;
      o.resolution = kShadowRes;
      o.overshoot = over;
      o.epsilon = 1e-3;
      o.log_every = 1;
      RunSequential(&m[i], o, &solver, &sub, [&](const Sample&) {
        if (sub.passes() > passes[i]) evaluated[i] += sub.evaluated();
        passes[i] = sub.passes();
      });
      passes[i] = sub.passes();
      b[i] = solver.radiosity();
    }
    EXPECT_GT(passes[0], 5);
    EXPECT_EQ(passes[0], passes[1]);
    EXPECT_LT(evaluated[0], evaluated[1]);
    EXPECT_EQ(MeshHash(m[0]), MeshHash(m[1]));
    EXPECT_TRUE(b[0] == b[1]) << "overshoot " << over;
  }
}

// Division by light, not by noise: the shadow scene divides about as much
// at R 128 as at R 256 (paper-size elements see 16 and 64 pixels of the
// light: the same edges are resolved at both).
TEST(Subdivider, ElementsAtR128AndR256AreAlike) {
  long leaves[2];
  for (int i = 0; i < 2; ++i) {
    MeshOptions o;
    o.patch_size = 0.25;
    Mesh m = MakeMesh(ShadowScene(), o);
    Solver solver(m, true);
    Subdivider sub(&m, SubdivideOptions());
    ASSERT_EQ(Adaptive(&m, &solver, &sub, 1e-3, i ? 256 : 128).status, RunStatus::kConverged);
    leaves[i] = m.LeafCount();
  }
  EXPECT_LT(std::max(leaves[0], leaves[1]), 1.5 * double(std::min(leaves[0], leaves[1])))
      << "R 128: " << leaves[0] << ", R 256: " << leaves[1];
  std::printf("shadow: %ld elements at R 128, %ld at R 256\n", leaves[0], leaves[1]);
}

}  // namespace
