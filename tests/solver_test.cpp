#include "solver.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "groups.h"
#include "results.h"
#include "scheduler.h"
#include "test_util.h"

namespace {

// Two solvers' B, element by element, to the bit.
void ExpectSameB(const Solver& x, const Solver& y) {
  const ElemB a = x.radiosity(), b = y.radiosity();
  ASSERT_EQ(a.size(), b.size());
  for (size_t e = 0; e < a.size(); ++e)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(a[e][k], b[e][k]) << "element " << e;
}

RunResult Solve(Mesh& m, Solver* s, double eps, int res = 64) {
  RunOptions o;
  o.resolution = res;
  o.epsilon = eps;
  return RunSequential(&m, o, s, nullptr, nullptr);
}

// Closed box, ρ and Ke everywhere: B = Ke / (1 − ρ) exactly.
TEST(Solver, FurnaceMatchesClosedForm) {
  struct Case { glm::dvec3 rho; double tol; };
  for (Case c : {Case{glm::dvec3(0.5), 0.005}, Case{glm::dvec3(0.9), 0.005},
                 Case{glm::dvec3(0.99), 0.005}, Case{glm::dvec3(0.999), 0.025},
                 Case{glm::dvec3(0.3, 0.6, 0.9), 0.005}}) {
    Scene s = Box(1.0, {c.rho}, {glm::dvec3(1.0)});
    Mesh m = MakeMesh(s);
    Solver solver(m, true);
    RunResult r = Solve(m, &solver, 1e-4);
    ASSERT_EQ(r.status, RunStatus::kConverged) << r.why;
    const glm::dvec3 exact = 1.0 / (1.0 - c.rho);
    for (const glm::dvec3& b : FaceRadiosity(m, solver.radiosity()))
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(b[k], exact[k], c.tol * exact[k]) << "rho " << c.rho[k];
  }
}

// Two squares facing each other inside nothing: an open scene, where the
// ambient estimate is wrong most and overshooting must still agree.
TEST(Solver, OvershootingDoesNotChangeTheAnswer) {
  Scene s = Box(1.0, {glm::dvec3(0.7), glm::dvec3(0.4), glm::dvec3(0.8), glm::dvec3(0.2),
                      glm::dvec3(0.6), glm::dvec3(0.5)},
                {glm::dvec3(0), glm::dvec3(5), glm::dvec3(0), glm::dvec3(0), glm::dvec3(0),
                 glm::dvec3(0)});
  s.faces.pop_back();  // open the box: light escapes through z = 1
  Mesh m = MakeMesh(s);
  Solver on(m, true), off(m, false);
  ASSERT_EQ(Solve(m, &on, 1e-5).status, RunStatus::kConverged);
  ASSERT_EQ(Solve(m, &off, 1e-5).status, RunStatus::kConverged);
  auto a = FaceRadiosity(m, on.radiosity()), b = FaceRadiosity(m, off.radiosity());
  for (size_t f = 0; f < a.size(); ++f) EXPECT_NEAR(a[f].r, b[f].r, 0.005 * b[f].r) << f;
}

// In a closed box all emitted power is absorbed: Σ A (1−ρ)/ρ (B − Ke) = Σ A Ke.
TEST(Solver, ClosedBoxAbsorbsWhatItEmits) {
  Scene s = Box(1.0, {glm::dvec3(0.8), glm::dvec3(0.5), glm::dvec3(0.2), glm::dvec3(0.6),
                      glm::dvec3(0.6), glm::dvec3(0.9, 0.5, 0.1)},
                {glm::dvec3(0), glm::dvec3(10), glm::dvec3(0), glm::dvec3(0), glm::dvec3(0),
                 glm::dvec3(0)});
  Mesh m = MakeMesh(s);
  for (bool over : {true, false}) {
    Solver solver(m, over);
    ASSERT_EQ(Solve(m, &solver, 1e-6).status, RunStatus::kConverged);
    auto b = FaceRadiosity(m, solver.radiosity());
    glm::dvec3 absorbed, emitted;
    PowerBalance(s, b, &absorbed, &emitted);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(absorbed[k], emitted[k], 0.01 * emitted[k]);
    for (const auto& e : solver.radiosity())
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(std::isfinite(e[k]) && e[k] >= 0);
  }
}

TEST(Solver, ReflectingEverythingDoesNotConverge) {
  Scene s = Box(1.0, {glm::dvec3(1.0)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  for (bool over : {true, false}) {
    Solver solver(m, over);
    RunResult r = Solve(m, &solver, 1e-3, 16);
    EXPECT_EQ(r.status, RunStatus::kNotConverged) << "overshoot " << over;
    EXPECT_FALSE(r.why.empty());
  }
}

TEST(Solver, SelectSkipsTakenPatches) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(0), glm::dvec3(3), glm::dvec3(0),
                                         glm::dvec3(0), glm::dvec3(0), glm::dvec3(0)});
  Mesh m = MakeMesh(s);
  Solver solver(m, true);
  int first = solver.Select();
  ASSERT_GE(first, 0);
  EXPECT_EQ(m.patches[first].face, 1);  // the ceiling emits
  std::vector<char> taken(m.patches.size(), 0);
  taken[first] = 1;
  int second = solver.SelectByScan(&taken);
  EXPECT_NE(second, first);
  EXPECT_EQ(m.patches[second].face, 1);
  solver.Take(first);
  EXPECT_EQ(solver.Select(), second);
  solver.Release(first);
  EXPECT_EQ(solver.Select(), first);
}

// "No work on faces that see nothing": a lamp facing down on a floor,
// with two squares above it facing up into the void. The dark one never
// receives light, so it is never overshot or shot; the glowing one sees
// nothing, so it shoots once (its light leaves the scene) and never again.
TEST(Solver, FacesThatSeeNothingAreNotWorkedOn) {
  Scene s = EmptyScene();
  const glm::dvec3 white(0.8), black(0.0), glow(2.0), lamp(5.0);
  AddFace(&s, {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}}, white, black);    // floor, up
  AddFace(&s, {{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}}, black, lamp);     // lamp, down
  AddFace(&s, {{0, 2, 0}, {0, 2, 1}, {1, 2, 1}, {1, 2, 0}}, white, black);    // dark, up
  AddFace(&s, {{0, 3, 0}, {0, 3, 1}, {1, 3, 1}, {1, 3, 0}}, white, glow);     // glowing, up
  MeshOptions one;
  one.patch_size = 2.0;  // a patch per face
  Mesh m = MakeMesh(s, one);
  ASSERT_EQ(m.patches.size(), 4u);
  Solver solver(m, true);
  RunResult r = Solve(m, &solver, 1e-6);
  ASSERT_EQ(r.status, RunStatus::kConverged) << r.why;
  EXPECT_EQ(solver.TimesShot(2), 0);
  EXPECT_EQ(solver.TimesShot(3), 1);
  const auto b = FaceRadiosity(m, solver.radiosity());
  EXPECT_EQ(b[2], black);
  EXPECT_EQ(b[3], glow);
  EXPECT_GT(b[0].r, 0.5);  // the floor is lit by the lamp
}

// The queue's choice is the full scan's on every shot of the shipped
// scenes, with overshooting on and off: patches taken three at a time as
// a worker's queue holds them, divisions, and a new wave halfway.
TEST(Solver, SelectIsTheFullScanOnTheShippedScenes) {
  for (const char* name : {"cornell", "room", "maze", "blender"}) {
    const Mesh m = ShippedMesh(name);
    Hemicube h(32);
    for (bool over : {true, false}) {
      Solver solver(m, over);
      std::vector<char> taken(m.patches.size(), 0);
      std::deque<int> queue;
      std::vector<FormFactor> column;
      long checked = 0;
      for (int shot = 0; shot < 400; ++shot) {
        while (queue.size() < 3) {
          const int p = solver.Select();
          ASSERT_EQ(p, solver.SelectByScan(&taken)) << name << " shot " << shot;
          if (p < 0) break;
          ++checked;
          solver.Take(p);
          taken[p] = 1;
          queue.push_back(p);
        }
        if (queue.empty()) break;
        const int p = queue.front();
        queue.pop_front();
        ShotColumn(&h, m, p, GroupOf(m, p), solver.TimesShot(p), true, 1, &column);
        solver.Shoot(p, column);
        solver.Release(p);
        taken[p] = 0;
        if (shot == 200) solver.NewWave();
      }
      EXPECT_GT(checked, 400) << name;
    }
  }
}

// Shoot's loop over a column comes in two forms, without and with what
// only subdivision needs (noise, first light, the changed list): the same
// choices and B to the bit either way, on a shipped scene.
TEST(Solver, TrackingDoesNotChangeWhatShootGives) {
  const Mesh m = ShippedMesh("room");
  Hemicube h(32);
  Solver plain(m, true), tracked(m, true);
  tracked.TrackNoise(32);
  tracked.TrackDirect();
  std::vector<int32_t> changed;
  tracked.TakeChanged(&changed);
  std::vector<FormFactor> column;
  for (int shot = 0; shot < 300; ++shot) {
    const int p = plain.Select();
    ASSERT_EQ(p, tracked.Select()) << "shot " << shot;
    if (p < 0) break;
    ShotColumn(&h, m, p, GroupOf(m, p), plain.TimesShot(p), true, 1, &column);
    plain.Shoot(p, column);
    tracked.Shoot(p, column);
  }
  tracked.TakeChanged(&changed);
  EXPECT_FALSE(changed.empty());
  ExpectSameB(plain, tracked);
}

// EndWave (before a wave's picture) frees the noise and direct-light
// tracks; NewWave then starts them again as it does without it: the same
// tracks, choices and B to the bit through the next wave.
TEST(Solver, EndWaveFreesTheTracksNewWaveStartsAgain) {
  const Mesh m = ShippedMesh("room");
  Hemicube h(32);
  Solver kept(m, true), ended(m, true);
  for (Solver* s : {&kept, &ended}) s->TrackNoise(32), s->TrackDirect();
  std::vector<FormFactor> column;
  auto shoot = [&](int shots) {
    for (int shot = 0; shot < shots; ++shot) {
      const int p = kept.Select();
      ASSERT_EQ(p, ended.Select()) << "shot " << shot;
      if (p < 0) break;
      ShotColumn(&h, m, p, GroupOf(m, p), kept.TimesShot(p), true, 1, &column);
      kept.Shoot(p, column);
      ended.Shoot(p, column);
    }
  };
  shoot(100);
  ASSERT_FALSE(ended.noise().empty());
  ended.EndWave();
  EXPECT_TRUE(ended.noise().empty());
  EXPECT_TRUE(ended.direct().empty());
  kept.NewWave();
  ended.NewWave();
  EXPECT_EQ(kept.noise(), ended.noise());
  EXPECT_EQ(kept.direct(), ended.direct());
  EXPECT_EQ(ended.noise().size(), m.elems.size());
  shoot(100);
  EXPECT_EQ(kept.noise(), ended.noise());
  EXPECT_EQ(kept.direct(), ended.direct());
  ExpectSameB(kept, ended);
}

// ShotLines (bench/master.cpp's memory floor) lists each line Shoot
// touches once, in address order, written or only read: an element alone
// is three written (its record, its patch's, the queue's leaf) and two
// read (its patch id, the queue's taken flag), and a column's include
// every element's B and one record per patch reached among those written.
TEST(Solver, ShotLinesAreTheLinesShootTouches) {
  const Mesh m = ShippedMesh("room");
  Hemicube h(32);
  Solver s(m, true);
  std::vector<FormFactor> column;
  const int p = s.Select();
  ShotColumn(&h, m, p, GroupOf(m, p), 0, true, 1, &column);
  ASSERT_GT(column.size(), 100u);
  auto line = [](const void* a) {
    return reinterpret_cast<const char*>(reinterpret_cast<uintptr_t>(a) & ~uintptr_t(63));
  };
  std::vector<const char*> written, read;
  s.ShotLines({column[0]}, &written, &read);
  ASSERT_EQ(written.size(), 3u);
  EXPECT_EQ(read.size(), 2u);
  EXPECT_TRUE(std::count(written.begin(), written.end(), line(&s.radiosity()[size_t(column[0].elem)])));
  s.ShotLines(column, &written, &read);
  std::set<int32_t> patches;
  for (const FormFactor& ff : column) {
    patches.insert(m.elems[size_t(ff.elem)].patch);
    EXPECT_TRUE(std::binary_search(written.begin(), written.end(), line(&s.radiosity()[size_t(ff.elem)])));
  }
  EXPECT_GE(written.size(), patches.size() + 1);  // and the queue's leaves
  EXPECT_GE(read.size(), 2u);                     // patch ids, taken flags
  EXPECT_LE(written.size() + read.size(), 5 * column.size());
  for (const std::vector<const char*>* v : {&written, &read})
    for (size_t i = 0; i < v->size(); ++i) {
      EXPECT_EQ(reinterpret_cast<uintptr_t>((*v)[i]) % 64, 0u);
      if (i > 0) {
        EXPECT_LT((*v)[i - 1], (*v)[i]);
      }
    }
  for (const char* a : read) EXPECT_FALSE(std::binary_search(written.begin(), written.end(), a));
}

TEST(Solver, DarkSceneConvergesToBlack) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(0.0)});
  Mesh m = MakeMesh(s);
  Solver solver(m, true);
  RunResult r = Solve(m, &solver, 1e-3, 16);
  EXPECT_EQ(r.status, RunStatus::kConverged);
  EXPECT_EQ(r.shots, 0);
  for (const auto& b : FaceRadiosity(m, solver.radiosity())) EXPECT_EQ(b.r, 0.0);
}

}  // namespace
