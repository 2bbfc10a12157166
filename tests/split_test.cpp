// Shooter division: SplitPatch (split.cpp), the solver's share of the
// unshot power (Solver::Split), the policy (Subdivider::SplitPass), and
// the edit on the wire and in checkpoints.
#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#include "checkpoint.h"
#include "groups.h"
#include "hemicube.h"
#include "protocol.h"
#include "scheduler.h"
#include "solver.h"
#include "subdivide.h"
#include "test_util.h"

namespace {

// A floor of 1 x 1 under a small emitting square: the floor's patches are
// lit unevenly (bright under the light, dark far off).
Scene Floor() {
  Scene s = EmptyScene();
  AddFace(&s, {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}}, glm::dvec3(0.6), glm::dvec3(0));
  AddFace(&s, {{0.4, 0.3, 0.4}, {0.6, 0.3, 0.4}, {0.6, 0.3, 0.6}, {0.4, 0.3, 0.6}},
          glm::dvec3(0.5), glm::dvec3(10.0));
  return s;
}

MeshOptions Coarse() {
  MeshOptions o;
  o.patch_size = 0.5;  // the floor: 2 x 2 patches of 2 x 2 elements
  return o;
}

double Sum(const std::vector<glm::dvec3>& unshot, const Mesh& m, int c) {
  double s = 0;
  for (size_t p = 0; p < unshot.size(); ++p) s += unshot[p][c] * m.patch_area[size_t(p)];
  return s;
}

TEST(Split, PiecesAreTheTopElementsThenTheirChildren) {
  Mesh m = MakeMesh(Floor(), Coarse());
  const size_t patches = m.patches.size();
  ASSERT_EQ(m.Tops(0).size(), 4u);
  const IdSpan span = m.Tops(0);
  const std::vector<int> tops(span.begin(), span.end());
  const double area = m.patch_area[size_t(0)];
  Divide(&m, tops[1]);  // divided before the split: its children follow it
  ASSERT_EQ(SplitPieces(m, 0), 4);
  SplitPatch(&m, 0);
  ASSERT_EQ(m.patches.size(), patches + 3);
  EXPECT_EQ(m.splits, (std::vector<int32_t>{0}));
  double sum = 0;
  for (int p : {0, int(patches), int(patches) + 1, int(patches) + 2}) {
    ASSERT_EQ(m.Tops(p).size(), 1u);
    sum += m.patch_area[size_t(p)];
    std::vector<int> leaves;
    m.Leaves(p, &leaves);
    for (int l : leaves) EXPECT_EQ(m.elems[l].patch, p);
    EXPECT_EQ(m.group_of[p], -1);
  }
  EXPECT_NEAR(sum, area, 1e-15);
  EXPECT_EQ(m.elems[m.elems[tops[1]].first_child].patch, int(patches));
  // A piece of one leaf cannot be split; one whose element is divided can.
  EXPECT_EQ(SplitPieces(m, 0), 0);
  EXPECT_EQ(SplitPieces(m, int(patches)), 4);
  SplitPatch(&m, int(patches));
  EXPECT_EQ(m.patches.size(), patches + 6);
  EXPECT_EQ(SplitPieces(m, -1), 0);
  EXPECT_EQ(SplitPieces(m, int(m.patches.size())), 0);
}

// A worker's mesh (KeepColumnsOnly) keeps no areas or patch centres: it
// computes a shooter's centre again, to the bit, and its columns are the
// master's, before and after the same divisions and splits.
TEST(Split, AMeshKeepingColumnsOnlyGivesTheSameCentresAndColumns) {
  Mesh master = MakeMesh(Floor(), Coarse());
  SplitPatch(&master, 1);
  Divide(&master, master.Tops(1)[0]);
  Mesh worker = master;
  worker.KeepColumnsOnly();
  EXPECT_TRUE(worker.elem_area.empty() && worker.parent.empty() && worker.patch_area.empty() &&
              worker.patch_center.empty() && worker.face_scene.empty());
  EXPECT_EQ(MeshHash(worker), MeshHash(master));
  for (Mesh* m : {&master, &worker}) {
    SplitPatch(m, 1);
    Divide(m, 3);
    SplitPatch(m, 2);
  }
  EXPECT_TRUE(worker.elem_area.empty() && worker.parent.empty() && worker.patch_area.empty() &&
              worker.patch_center.empty());
  EXPECT_EQ(MeshHash(worker), MeshHash(master));
  ASSERT_EQ(worker.patches.size(), master.patches.size());
  Hemicube hm(64), hw(64);
  std::vector<FormFactor> fm, fw;
  for (int p = 0; p < int(master.patches.size()); ++p) {
    const glm::dvec3 a = master.Center(p), b = worker.Center(p);
    EXPECT_TRUE(a.x == b.x && a.y == b.y && a.z == b.z) << p;
    ShotColumn(&hm, master, p, GroupOf(master, p), 0, true, 1, &fm);
    ShotColumn(&hw, worker, p, GroupOf(worker, p), 0, true, 1, &fw);
    ASSERT_EQ(fm.size(), fw.size()) << p;
    for (size_t i = 0; i < fm.size(); ++i) {
      EXPECT_EQ(fm[i].elem, fw[i].elem);
      EXPECT_EQ(fm[i].f, fw[i].f);
    }
  }
}

// Divisions and splits commute: replayed divisions first, then splits, as
// checkpoints and late workers do, they give the mesh made interleaved.
TEST(Split, ReplayedInAnyInterleavingGivesTheSameMesh) {
  const Mesh built = MakeMesh(Floor(), Coarse());
  Mesh m = built;
  SplitPatch(&m, 1);
  Divide(&m, m.Tops(1)[0]);
  SplitPatch(&m, 1);
  Divide(&m, 3);
  SplitPatch(&m, 2);
  const std::vector<int32_t> edits = DivideHistory(m);
  EXPECT_EQ(edits.back(), ~2);
  Mesh again = built;
  std::string err;
  ASSERT_TRUE(ReplayDivisions(&again, edits, &err)) << err;
  EXPECT_EQ(MeshHash(again), MeshHash(m));
  EXPECT_NE(MeshHash(again), MeshHash(built));
  Mesh bad = built;
  EXPECT_FALSE(ReplayDivisions(&bad, {~int32_t(built.patches.size())}, &err));
  EXPECT_EQ(err, "edit 1 of 1 splits patch " + std::to_string(built.patches.size()) +
                     ", which cannot be split");
}

TEST(Split, EditsTravelInOrderOnTheWire) {
  const std::vector<int32_t> edits{5, ~3, 0, ~0, 2147483647, ~2147483647};
  std::string frame;
  proto::EncodeDivide(edits, &frame);
  std::vector<int32_t> back;
  std::string err;
  ASSERT_TRUE(proto::DecodeDivide(frame.substr(proto::kHeaderSize), &back, &err)) << err;
  EXPECT_EQ(back, edits);
}

// The unshot power is shared, not made or lost; the pieces' shares follow
// what their leaves received.
TEST(Split, SolverKeepsTheUnshotPower) {
  Mesh m = MakeMesh(Floor(), Coarse());
  Solver solver(m, false);  // no overshooting: every unshot power >= 0
  Hemicube h(64);
  std::vector<FormFactor> col;
  for (int i = 0; i < 3; ++i) {  // the light's patch, then a floor patch or two
    const int p = solver.Select();
    ShotColumn(&h, m, p, GroupOf(m, p), solver.TimesShot(p), true, 1, &col);
    solver.Shoot(p, col);
  }
  int p = 0;
  while (m.Emission(m.faces[m.patches[p].face]) != glm::dvec3(0) ||
         solver.unshot()[p].r == 0)
    ++p;
  const glm::dvec3 before(Sum(solver.unshot(), m, 0), Sum(solver.unshot(), m, 1),
                          Sum(solver.unshot(), m, 2));
  const size_t patches = m.patches.size();
  const double whole = solver.unshot()[p].r * m.patch_area[size_t(p)];
  ASSERT_GT(whole, 0);
  SplitPatch(&m, p);
  solver.Split(p);
  solver.SplitsDone();
  ASSERT_EQ(solver.unshot().size(), m.patches.size());
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(Sum(solver.unshot(), m, c), before[c], 1e-13 * before[c]);
  // By received radiosity: the brightest piece holds the most.
  std::vector<int> pieces{p};
  for (size_t q = patches; q < m.patches.size(); ++q) pieces.push_back(int(q));
  double got = 0;
  for (int q : pieces) got += solver.unshot()[q].r * m.patch_area[size_t(q)];
  EXPECT_NEAR(got, whole, 1e-13 * whole);
  int brightest = -1, richest = -1;
  double bb = -1, rb = -1;
  for (int q : pieces) {
    const int e = m.Tops(q)[0];
    if (solver.radiosity()[e].r > bb) bb = solver.radiosity()[e].r, brightest = q;
    if (solver.unshot()[q].r > rb) rb = solver.unshot()[q].r, richest = q;
  }
  EXPECT_EQ(richest, brightest);
  // And shooting goes on: the pieces are selected like any patch.
  for (int i = 0; i < 20; ++i) {
    const int s = solver.Select();
    ASSERT_GE(s, 0);
    ShotColumn(&h, m, s, GroupOf(m, s), solver.TimesShot(s), true, 1, &col);
    solver.Shoot(s, col);
  }
}

// A column computed before its receiver was divided and then split into
// the divided element's children: each leaf gains what the element
// would have, and each piece the unshot power of its leaf's share.
TEST(Split, AColumnFromBeforeADivisionAndASplitFeedsEachPiece) {
  Mesh m = MakeMesh(Floor(), Coarse());
  Solver solver(m, false);
  Hemicube h(64);
  const int p = solver.Select();  // the light
  const double shot = solver.unshot()[p].r * m.patch_area[size_t(p)];
  std::vector<FormFactor> col;
  ShotColumn(&h, m, p, GroupOf(m, p), solver.TimesShot(p), true, 1, &col);
  const FormFactor hit = col[col.size() / 2];
  const int t = hit.elem, fp = m.elems[t].patch;
  ASSERT_EQ(m.Tops(fp).size(), 4u);
  SplitPatch(&m, fp);  // one piece per top element; t's is fp or a new one
  solver.Split(fp);
  solver.SplitsDone();
  const int piece = m.elems[t].patch;
  Divide(&m, t);
  solver.Divided({t});
  ASSERT_EQ(SplitPieces(m, piece), 4);
  SplitPatch(&m, piece);  // now one piece per child of t
  solver.Split(piece);
  solver.SplitsDone();
  std::vector<int> leaves;
  m.LeavesUnder(t, &leaves);
  ASSERT_EQ(leaves.size(), 4u);
  const std::vector<glm::dvec3> b0(solver.radiosity().begin(), solver.radiosity().end());
  const std::vector<glm::dvec3> u0 = solver.unshot();
  solver.Shoot(p, col);
  const std::vector<glm::dvec3> u1 = solver.unshot();
  const double rho = m.Rho(m.FaceOf(t)).r;
  const double gain = rho * shot * hit.f / m.elem_area[size_t(t)];
  std::vector<int> pieces;
  for (int l : leaves) {
    EXPECT_NEAR(solver.radiosity()[l].r - b0[size_t(l)].r, gain, 1e-12 * gain);
    const int q = m.elems[l].patch;
    pieces.push_back(q);
    // Each piece is this leaf alone and reached by no other element.
    EXPECT_NEAR((u1[size_t(q)].r - u0[size_t(q)].r) * m.patch_area[size_t(q)],
                gain * m.elem_area[size_t(l)], 1e-12 * gain * m.elem_area[size_t(l)]);
  }
  std::sort(pieces.begin(), pieces.end());
  EXPECT_EQ(std::unique(pieces.begin(), pieces.end()), pieces.end());
  // And the power reflected is what the column says.
  double want = 0;
  for (const FormFactor& f : col) want += m.Rho(m.FaceOf(f.elem)).r * shot * f.f;
  EXPECT_NEAR(Sum(u1, m, 0) - (Sum(u0, m, 0) - shot), want, 1e-12 * want);
}

// A pass's splits brought up to date once (SplitsDone) leave the solver
// as one call after each split does: the same state and the same shots.
TEST(Split, OneSplitsDoneAPassIsOneASplit) {
  Mesh once = MakeMesh(Floor(), Coarse());
  Mesh each = once;
  Solver a(once, true), b(each, true);
  Hemicube h(64);
  std::vector<FormFactor> col;
  auto shoot = [&](Solver* s, const Mesh& m) {
    const int p = s->Select();
    ASSERT_GE(p, 0);
    ShotColumn(&h, m, p, GroupOf(m, p), s->TimesShot(p), true, 1, &col);
    s->Shoot(p, col);
  };
  for (int i = 0; i < 3; ++i) shoot(&a, once), shoot(&b, each);
  for (int p : {0, 1, 2}) {
    if (once.Emission(once.faces[once.patches[p].face]) != glm::dvec3(0)) continue;
    SplitPatch(&once, p), a.Split(p);
    SplitPatch(&each, p), b.Split(p), b.SplitsDone();
  }
  a.SplitsDone();
  ASSERT_GT(once.patches.size(), 5u);
  for (int i = 0; i < 30; ++i) {
    const SolverState sa = a.State(), sb = b.State();
    ASSERT_EQ(sa.b, sb.b);
    ASSERT_EQ(sa.unshot, sb.unshot);
    ASSERT_EQ(sa.unshot_sum, sb.unshot_sum);
    ASSERT_EQ(sa.abs_sum, sb.abs_sum);
    ASSERT_EQ(a.Select(), b.Select());
    shoot(&a, once), shoot(&b, each);
  }
}

// The policy: a patch whose top elements' direct light differs strongly
// is split, once the emitters have shot, an even one is not, nor an
// emitter, and the threshold goes down to the floor.
TEST(Split, PolicySplitsUnevenPatchesOnly) {
  Mesh m = MakeMesh(Floor(), Coarse());
  SubdivideOptions so;
  so.split = true;
  so.split_near = 0;  // by light only here
  Subdivider sub(&m, so);
  std::vector<float> d(m.elems.size(), 1.0f);
  std::vector<int> shot(m.patches.size(), 0);
  d[size_t(m.Tops(2)[0])] = 0.0f;  // patch 2: one dark piece, spread 0.85
  d[size_t(m.Tops(1)[3])] = 0.1f;  // patch 1: spread 0.77
  for (int p : m.FacePatches(m.faces[1]))  // the light: uneven, never split
    d[size_t(m.Tops(p)[0])] = 0.0f;
  // Before every emitter shot, nothing, and the threshold waits.
  EXPECT_TRUE(sub.SplitPass(m, d, false, shot).empty());
  EXPECT_EQ(sub.State().split_threshold, so.split_threshold);
  EXPECT_TRUE(sub.SplitPass(m, d, true, shot).empty());  // 0.85 < 0.9
  EXPECT_EQ(sub.SplitPass(m, d, true, shot), (std::vector<int32_t>{2}));  // at the floor, 0.8
  SplitPatch(&m, 2);  // into pieces of one leaf each: none splits again
  d.resize(m.elems.size(), 1.0f);
  shot.resize(m.patches.size(), 0);
  // Measured once a wave: a change since counts from the next wave.
  d[size_t(m.Tops(3)[0])] = 0.0f;
  EXPECT_TRUE(sub.SplitPass(m, d, true, shot).empty());
  EXPECT_EQ(sub.splits(), 1);
  EXPECT_EQ(sub.State().split_threshold, so.split_floor);
  sub.StartWave(m);
  EXPECT_EQ(sub.SplitPass(m, d, true, shot), (std::vector<int32_t>{3}));
  so.split = false;
  Subdivider off(&m, so);
  EXPECT_TRUE(off.SplitPass(m, d, true, shot).empty());
}

// The floor with a small face hanging just over one of its patches,
// facing it (closeness splits that patch).
Scene FloorUnderAFace() {
  Scene s = Floor();
  AddFace(&s, {{0.1, 0.05, 0.1}, {0.2, 0.05, 0.1}, {0.2, 0.05, 0.2}, {0.1, 0.05, 0.2}},
          glm::dvec3(0.5), glm::dvec3(0));  // facing down
  return s;
}

// Closeness: a face hanging just over one floor patch, facing it, splits
// that patch at the first pass whatever the light; the others stay.
TEST(Split, CloseReceiversSplitAPatch) {
  Mesh m = MakeMesh(FloorUnderAFace(), Coarse());
  int under = -1;
  for (int p : m.FacePatches(m.faces[0]))
    if (glm::length(m.patch_center[size_t(p)] - glm::dvec3(0.25, 0, 0.25)) < 1e-9) under = p;
  ASSERT_GE(under, 0);
  SubdivideOptions so;
  so.split = true;
  Subdivider sub(&m, so);
  const std::vector<float> d(m.elems.size(), 1.0f);
  const std::vector<int> shot(m.patches.size(), 0);
  std::vector<int32_t> got = sub.SplitPass(m, d, false, shot);
  EXPECT_NE(std::find(got.begin(), got.end(), under), got.end());
  for (int p : m.FacePatches(m.faces[0])) {
    if (p == under) continue;
    EXPECT_EQ(std::find(got.begin(), got.end(), p), got.end()) << p;
  }
  so.split_near = 0;
  Subdivider far(&m, so);
  EXPECT_TRUE(far.SplitPass(m, d, false, shot).empty());
}

// Closeness, found in a grid of every top element (many patches to
// search: the first pass) or by streaming the top elements past the
// patches (a few: the pieces of the last splits), is what a search of
// every top element for each patch finds, pass after pass of splits that
// hand divided tops' places to their children.
TEST(Split, CloseReceiversAreWhatEveryTopFinds) {
  const Scene scene = ShippedScene("room");
  MeshOptions o;
  o.elements_per_patch = 3;  // 9 top elements a patch
  Mesh m = MakeMesh(scene, o);
  SubdivideOptions so;
  so.split = true;
  Subdivider sub(&m, so);
  auto close_to = [&](int p) {
    const glm::dvec3 c0 = m.patch_center[size_t(p)];
    const int face = m.patches[size_t(p)].face;
    const glm::dvec3 normal = m.faces[size_t(face)].normal;
    const double r = so.split_near * std::sqrt(m.patch_area[size_t(p)]);
    for (size_t q = 0; q < m.patches.size(); ++q)
      for (int e : m.Tops(int(q))) {
        if (m.patches[q].face == face) continue;
        const glm::dvec3 d = m.Centroid(e) - c0;
        if (glm::dot(d, normal) > 0 && glm::dot(m.FaceOf(e).normal, d) < 0 && glm::dot(d, d) < r * r)
          return true;
      }
    return false;
  };
  size_t from = 0, gridded = 0, streamed = 0;
  for (int pass = 0; pass < 3; ++pass) {
    const std::vector<float> d(m.elems.size(), 1.0f);
    const std::vector<int> shot(m.patches.size(), 0);
    size_t tops = 0, searchers = 0;
    for (size_t p = 0; p < m.patches.size(); ++p) tops += m.Tops(int(p)).size();
    std::vector<int32_t> want;
    for (size_t p = from; p < m.patches.size(); ++p) {
      const glm::dvec3& ke = m.Emission(m.faces[size_t(m.patches[p].face)]);
      if (!(ke == glm::dvec3(0) && SplitPieces(m, int(p)) > 1)) continue;
      ++searchers;
      if (close_to(int(p))) want.push_back(int32_t(p));
    }
    (searchers * Subdivider::kStreamBelow < tops ? streamed : gridded) += 1;
    const std::vector<int32_t> got = sub.SplitPass(m, d, false, shot);
    ASSERT_EQ(got, want) << "pass " << pass;
    if (pass < 2) {
      ASSERT_FALSE(got.empty()) << "pass " << pass;
    }
    from = m.patches.size();
    // Each split's first new piece (one top element) divided: the next
    // pass searches it, and its split gives the children its place.
    for (int32_t p : got) {
      const size_t first = m.patches.size();
      SplitPatch(&m, p);
      if (m.elems[size_t(m.Tops(int(first))[0])].IsLeaf()) Divide(&m, m.Tops(int(first))[0]);
    }
  }
  EXPECT_EQ(gridded, 1u);
  EXPECT_EQ(streamed, 2u);
}

// The closeness search made ahead of the first pass, on another thread
// beside the edges' adjacency as the scheduler makes it (Subdivider::
// Prepare), finds what the pass's own search finds; and one made ahead
// of a later pass searches only the pieces the pass would.
TEST(Split, ClosenessSearchedAheadIsWhatThePassFinds) {
  const Scene scene = ShippedScene("room");
  MeshOptions o;
  o.elements_per_patch = 3;
  Mesh plain = MakeMesh(scene, o), ahead = MakeMesh(scene, o);
  SubdivideOptions so;
  so.split = true;
  Subdivider sub_plain(&plain, so), sub_ahead(&ahead, so);
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 0) {
      std::thread t([&] {
        ConnectEdges(&ahead);
        sub_ahead.Prepare(ahead);
      });
      t.join();
      EXPECT_TRUE(ahead.connected);
    } else {
      sub_ahead.Prepare(ahead);
    }
    const std::vector<float> d(plain.elems.size(), 1.0f);
    const std::vector<int> shot(plain.patches.size(), 0);
    const std::vector<int32_t> want = sub_plain.SplitPass(plain, d, false, shot);
    ASSERT_FALSE(want.empty()) << "pass " << pass;
    ASSERT_EQ(sub_ahead.SplitPass(ahead, d, false, shot), want) << "pass " << pass;
    // As in the test above: each split's first piece divided, so that
    // the next pass has close pieces to find.
    for (int32_t p : want)
      for (Mesh* m : {&plain, &ahead}) {
        const size_t first = m->patches.size();
        SplitPatch(m, p);
        if (m->elems[size_t(m->Tops(int(first))[0])].IsLeaf()) Divide(m, m->Tops(int(first))[0]);
      }
  }
}

// A split ends the wave only where the patch has already shot in it: a
// patch that has not loses nothing (its unshot power goes to the pieces),
// and a converged wave with only such splits is the last one.
TEST(Split, OnlySplitsOfShotPatchesEndTheWave) {
  Mesh m = MakeMesh(FloorUnderAFace(), Coarse());
  SubdivideOptions so;
  so.split = true;
  const std::vector<float> d(m.elems.size(), 1.0f);
  Subdivider fresh(&m, so);
  std::vector<int> shot(m.patches.size(), 0);
  const std::vector<int32_t> got = fresh.SplitPass(m, d, false, shot);
  ASSERT_FALSE(got.empty());
  EXPECT_FALSE(fresh.WaveOver(true));
  Subdivider again(&m, so);
  shot[size_t(got[0])] = 1;
  EXPECT_EQ(again.SplitPass(m, d, false, shot), got);
  EXPECT_TRUE(again.WaveOver(true));
}

// The direct light is the emitters' first shots' and nothing else: two
// lights shot in either order, with other patches' shots between or not,
// leave the same direct() (two float terms: the same sum either way), and
// DirectDone() once both shot.
TEST(Split, DirectLightDoesNotDependOnShotOrder) {
  Scene s = Floor();
  AddFace(&s, {{0.1, 0.5, 0.1}, {0.3, 0.5, 0.1}, {0.3, 0.5, 0.3}, {0.1, 0.5, 0.3}},
          glm::dvec3(0.5), glm::dvec3(4.0));
  const Mesh m = MakeMesh(s, Coarse());
  const int l1 = m.FacePatches(m.faces[1])[0], l2 = m.FacePatches(m.faces[2])[0];
  ASSERT_EQ(m.FacePatches(m.faces[1]).size(), 1u);
  ASSERT_EQ(m.FacePatches(m.faces[2]).size(), 1u);
  Hemicube h(64);
  std::vector<FormFactor> col;
  auto shoot = [&](Solver* solver, int p) {
    ShotColumn(&h, m, p, GroupOf(m, p), solver->TimesShot(p), true, 1, &col);
    solver->Shoot(p, col);
  };
  Solver a(m, true), b(m, true);
  a.TrackDirect();
  b.TrackDirect();
  EXPECT_FALSE(a.DirectDone());
  shoot(&a, l1);
  EXPECT_FALSE(a.DirectDone());
  shoot(&a, l2);
  EXPECT_TRUE(a.DirectDone());
  shoot(&b, l2);
  shoot(&b, m.FacePatches(m.faces[0])[1]);  // a floor patch, lit by l2, between
  shoot(&b, l1);
  shoot(&b, l2);  // a second shot of a light is not its first light
  EXPECT_TRUE(b.DirectDone());
  EXPECT_EQ(a.direct(), b.direct());
  double lit = 0;
  for (float x : a.direct()) lit += x;
  EXPECT_GT(lit, 0);
  // And a new wave starts it again.
  a.NewWave();
  EXPECT_FALSE(a.DirectDone());
  for (float x : a.direct()) EXPECT_EQ(x, 0.0f);
}

// A furnace splits nothing, through a whole run with its division passes.
TEST(Split, FurnaceSplitsNothing) {
  const Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  MeshOptions mo;
  mo.patch_size = 0.25;
  Mesh m = MakeMesh(s, mo);
  const size_t built = m.patches.size();
  Solver solver(m, true);
  SubdivideOptions so;
  so.split = true;
  Subdivider sub(&m, so);
  RunOptions ro;
  ro.resolution = 128;
  ro.epsilon = 1e-4;
  ASSERT_EQ(RunSequential(&m, ro, &solver, &sub, nullptr).status, RunStatus::kConverged);
  EXPECT_GT(sub.passes(), 0);
  EXPECT_EQ(m.patches.size(), built);
  EXPECT_EQ(sub.splits(), 0);
}

}  // namespace
