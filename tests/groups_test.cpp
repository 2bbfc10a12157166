#include "groups.h"

#include <cmath>

#include <gtest/gtest.h>

#include "hemicube.h"
#include "protocol.h"
#include "results.h"
#include "scheduler.h"
#include "solver.h"
#include "test_util.h"
#include "wire_util.h"

namespace {

// A square of side s at height y facing up (+y), corner (x, z).
void Tile(Scene* s, double x, double y, double z, double side, glm::dvec3 kd) {
  AddFace(s, {{x, y, z}, {x, y, z + side}, {x + side, y, z + side}, {x + side, y, z}}, kd,
          glm::dvec3(0));
}

// The inside of the unit box, its floor cut into n x n tiles (the
// exporter's facets), the ceiling the light. Patch size 0.5: the tiles are
// small, the walls cut 2 x 2. jitter > 0: each tile raised by up to that
// (near-coplanar: they do not join, but may group).
Scene TiledBox(int n, double jitter = 0) {
  Scene s = Box(1.0, {glm::dvec3(0.6), glm::dvec3(0.5), glm::dvec3(0.7), glm::dvec3(0.4),
                      glm::dvec3(0.3), glm::dvec3(0.8, 0.5, 0.2)},
                {glm::dvec3(0), glm::dvec3(10), glm::dvec3(0), glm::dvec3(0), glm::dvec3(0),
                 glm::dvec3(0)});
  s.faces.erase(s.faces.begin());  // the floor, cut below instead
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      Tile(&s, double(i) / n, jitter * double((7 * i + 3 * j) % 5) / 4, double(j) / n, 1.0 / n,
           glm::dvec3(0.5 + 0.02 * ((i + j) % 3)));
  for (size_t f = 0; f < s.faces.size(); ++f) s.faces[f].index = int(f);
  return s;
}

MeshOptions Half() {
  MeshOptions o;
  o.patch_size = 0.5;
  return o;
}

bool Grouped(const Mesh& m, int a, int b) {
  return m.group_of[a] >= 0 && m.group_of[a] == m.group_of[b];
}

TEST(Groups, TilesOfOneFloorShootTogether) {
  const Mesh m = MakeMesh(TiledBox(10), Half());
  // What a floor tile lights nearest is a wall (the other tiles are in
  // its plane, the ceiling is 1 away): a group is no wider than the
  // distance from any member's centre to the nearest wall, so the ring of
  // tiles along the walls (0.05 from one, 0.14 across) shoots alone and
  // the groups grow towards the middle. Nothing else is small enough.
  auto to_wall = [](const glm::dvec3& c) {
    return std::min({c.x, 1 - c.x, c.z, 1 - c.z});
  };
  size_t members = 0;
  for (const PatchGroup& g : m.groups) {
    EXPECT_GE(g.members.size(), 2u);
    members += g.members.size();
    glm::dvec3 lo(1e9), hi(-1e9);
    double nearest = 1e9;
    for (int q : g.members) {
      EXPECT_EQ(m.Tops(q).size(), 4u);  // a tile, not a wall patch
      EXPECT_GT(to_wall(m.patch_center[size_t(q)]), 0.1);  // not along a wall
      nearest = std::min(nearest, to_wall(m.patch_center[size_t(q)]));
      for (int e : m.Tops(q))
        for (int k = 0; k < 4; ++k) {
          lo = glm::min(lo, m.verts[m.elems[e].v[k]]);
          hi = glm::max(hi, m.verts[m.elems[e].v[k]]);
        }
    }
    EXPECT_LE(glm::length(hi - lo), kGroupReach * nearest + 1e-12);
    EXPECT_NEAR(g.area, 0.01 * double(g.members.size()), 1e-12);
    EXPECT_NEAR(g.normal.y, 1.0, 1e-12);
    EXPECT_NEAR(g.center.y, 0.0, 1e-12);
    EXPECT_TRUE(std::is_sorted(g.members.begin(), g.members.end()));
    EXPECT_TRUE(IsShooter(m, g.members[0]));
    EXPECT_FALSE(IsShooter(m, g.members[1]));
  }
  // Pinned: the 36 tiles at least 0.25 from every wall (a pair is 0.22
  // across) shoot as 16 groups.
  EXPECT_EQ(m.groups.size(), 16u);
  EXPECT_EQ(members, 36u);
  EXPECT_EQ(Shooters(m), m.patches.size() - members + m.groups.size());
  // The same groups every time (a worker derives them alike), none when off.
  EXPECT_EQ(MakeMesh(TiledBox(10), Half()).group_of, m.group_of);
  MeshOptions off = Half();
  off.groups = false;
  const Mesh alone = MakeMesh(TiledBox(10), off);
  EXPECT_TRUE(alone.groups.empty());
  EXPECT_EQ(Shooters(alone), alone.patches.size());
}

// Only what faces a patch is its receiver: a panel 0.2 above the middle of
// the tiled floor, facing up, leaves its groups as they are (the search
// passes boxes whose elements all face away); facing down, it is the
// nearest receiver of the tiles under and around it (0.2 to 0.21 away),
// and no pair of tiles (0.22 across) groups.
TEST(Groups, OnlyReceiversFacingAPatchLimitItsGroups) {
  auto with_panel = [](bool up) {
    Scene s = TiledBox(10);
    const glm::dvec3 a(0.3, 0.2, 0.3), b(0.3, 0.2, 0.7), c(0.7, 0.2, 0.7), d(0.7, 0.2, 0.3);
    AddFace(&s, up ? std::vector<glm::dvec3>{a, b, c, d} : std::vector<glm::dvec3>{d, c, b, a},
            glm::dvec3(0.5), glm::dvec3(0));
    for (size_t f = 0; f < s.faces.size(); ++f) s.faces[f].index = int(f);
    return MakeMesh(s, Half());
  };
  const Mesh up = with_panel(true);
  size_t members = 0;
  for (const PatchGroup& g : up.groups) members += g.members.size();
  EXPECT_EQ(up.groups.size(), 16u);
  EXPECT_EQ(members, 36u);
  EXPECT_TRUE(with_panel(false).groups.empty());
}

// A valley of small tiles, tilted in no axis's plane: two halves 3 degrees
// up from the crease, each tile a face of its own. A tile's receivers are
// the other half's (each in front of the other), not its own half's
// (coplanar, up to rounding); bounding boxes across both, the search can
// pass its own half's only by their planes (Worth's slab), and must not
// pass the other half's. So a group is no wider than the distance from any
// member's centre to the nearest box of the other half's elements, and
// never spans the crease; far from it, groups form.
TEST(Groups, TilesOfATiltedValleyGroupOnlyAsFarAsTheOtherSide) {
  const int n = 12;
  const double slope = std::tan(3 * M_PI / 180);
  // Turned 0.6 about x, then 0.4 about z (glm's matrices: by columns).
  const double c1 = std::cos(0.6), s1 = std::sin(0.6), c2 = std::cos(0.4), s2 = std::sin(0.4);
  const glm::dmat3 turn = glm::dmat3(c2, s2, 0, -s2, c2, 0, 0, 0, 1) *
                          glm::dmat3(1, 0, 0, 0, c1, s1, 0, -s1, c1);
  auto at = [&](double x, double z) {
    return turn * glm::dvec3(x, slope * std::abs(x - 0.5), z) + glm::dvec3(3, -2, 1);
  };
  Scene s = EmptyScene();
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = double(i) / n, z = double(j) / n, d = 1.0 / n;
      AddFace(&s, {at(x, z), at(x, z + d), at(x + d, z + d), at(x + d, z)}, glm::dvec3(0.5),
              glm::dvec3(0));
    }
  for (size_t f = 0; f < s.faces.size(); ++f) s.faces[f].index = int(f);
  MeshOptions o = Half();
  o.join = false;
  const Mesh m = MakeMesh(s, o);
  ASSERT_EQ(m.patches.size(), size_t(n * n));  // a patch a tile, in face order
  auto left = [&](int p) { return p / n < n / 2; };
  auto box = [&](int e, glm::dvec3* lo, glm::dvec3* hi) {
    const Element& el = m.elems[e];
    *lo = *hi = m.verts[el.v[0]];
    for (int k = 1; k < (el.IsTriangle() ? 3 : 4); ++k) {
      *lo = glm::min(*lo, m.verts[el.v[k]]);
      *hi = glm::max(*hi, m.verts[el.v[k]]);
    }
  };
  size_t members = 0;
  for (const PatchGroup& g : m.groups) {
    members += g.members.size();
    glm::dvec3 lo(1e9), hi(-1e9), a, b;
    double nearest = 1e9;
    for (int q : g.members) {
      EXPECT_EQ(left(q), left(g.members[0]));
      for (int e : m.Tops(q)) {
        box(e, &a, &b);
        lo = glm::min(lo, a);
        hi = glm::max(hi, b);
      }
      for (size_t e = 0; e < m.elems.size(); ++e)
        if (left(m.elems[e].patch) != left(q)) {
          box(int(e), &a, &b);
          const glm::dvec3 c = m.patch_center[size_t(q)];
          nearest = std::min(nearest, glm::length(glm::max(glm::max(a - c, c - b), 0.0)));
        }
    }
    EXPECT_LE(glm::length(hi - lo), kGroupReach * nearest);
  }
  EXPECT_GE(m.groups.size(), 8u);
  EXPECT_GE(members, 24u);
}

// Every group keeps the rule against its members' nearest receivers found
// by brute force (every element, groups.h's test of lighting) wherever
// they lie in the search's tree: a fine tiled floor under small panels
// facing down, scattered at heights and places that no order of the tree
// keeps beside the tiles under them. A search that passed a receiver (its
// box in the tree far from the tile's own leaf) grew a group too wide.
TEST(Groups, GroupsStayWithinTheirNearestReceiversFoundByBruteForce) {
  Scene s = TiledBox(40);
  for (int k = 0; k < 23; ++k) {
    const double x = 0.05 + 0.85 * double((37 * k) % 23) / 23, z = 0.05 + 0.85 * double((11 * k + 5) % 23) / 23;
    const double y = 0.08 + 0.6 * double((13 * k) % 7) / 7, w = 0.04;
    AddFace(&s, {{x, y, z}, {x + w, y, z}, {x + w, y, z + w}, {x, y, z + w}}, glm::dvec3(0.5),
            glm::dvec3(0));
  }
  for (size_t f = 0; f < s.faces.size(); ++f) s.faces[f].index = int(f);
  const Mesh m = MakeMesh(s, Half());
  const double eps = 1e-9 * std::max(m.scene_diagonal, m.patch_size);
  auto plane = [&](int p) -> const MeshFace& { return m.faces[size_t(m.patches[size_t(p)].face)]; };
  auto corners = [&](int e, auto f) {
    const Element& el = m.elems[size_t(e)];
    bool any = false;
    for (int k = 0; k < (el.IsTriangle() ? 3 : 4); ++k) any = any || f(m.verts[size_t(el.v[k])]);
    return any;
  };
  auto nearest = [&](int q) {
    const MeshFace& fq = plane(q);
    double d = 1e9;
    for (size_t e = 0; e < m.elems.size(); ++e) {
      const int p = m.elems[e].patch;
      if (p == q) continue;
      const MeshFace& fe = plane(p);
      if (!corners(int(e), [&](const glm::dvec3& v) { return glm::dot(fq.normal, v) - fq.offset > eps; }))
        continue;
      bool faces = false;
      for (int t : m.Tops(q))
        faces = faces || corners(t, [&](const glm::dvec3& v) {
                  return glm::dot(fe.normal, v) - fe.offset > eps;
                });
      if (!faces) continue;
      glm::dvec3 lo(1e9), hi(-1e9);
      corners(int(e), [&](const glm::dvec3& v) {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
        return false;
      });
      const glm::dvec3 c = m.patch_center[size_t(q)];
      d = std::min(d, glm::length(glm::max(glm::max(lo - c, c - hi), 0.0)));
    }
    return d;
  };
  size_t members = 0;
  for (const PatchGroup& g : m.groups) {
    members += g.members.size();
    glm::dvec3 lo(1e9), hi(-1e9);
    for (int q : g.members)
      for (int t : m.Tops(q))
        corners(t, [&](const glm::dvec3& v) {
          lo = glm::min(lo, v);
          hi = glm::max(hi, v);
          return false;
        });
    for (int q : g.members) EXPECT_LE(glm::length(hi - lo), kGroupReach * nearest(q));
  }
  // Some tiles are far enough from the panels and the walls to group.
  EXPECT_GE(m.groups.size(), 4u);
  EXPECT_GE(members, 8u);
}

// A group's shot: the members give up exactly their unshot power, what the
// receivers gain is ρ·ΣxA·F, and no member receives from its own group;
// on coplanar tiles and on tiles up to 0.003 above one another.
class GroupShot : public testing::TestWithParam<double> {};
INSTANTIATE_TEST_SUITE_P(Groups, GroupShot, testing::Values(0.0, 0.003));
TEST_P(GroupShot, KeepsEnergyExactly) {
  const Mesh m = MakeMesh(TiledBox(10, GetParam()), Half());
  ASSERT_FALSE(m.groups.empty());
  Solver solver(m, false);
  Hemicube hc(64);
  std::vector<FormFactor> col;
  auto unshot_power = [&] {
    glm::dvec3 u(0.0);
    for (size_t p = 0; p < m.patches.size(); ++p) u += solver.unshot()[p] * m.patch_area[size_t(p)];
    return u;
  };
  // The light and the walls first, until a group of the lit floor comes up.
  int p = solver.Select();
  for (int shots = 0; !GroupOf(m, p) && shots < 40; ++shots, p = solver.Select()) {
    ShotColumn(&hc, m, p, GroupOf(m, p), 0, true, 1, &col);
    solver.Shoot(p, col);
  }
  const PatchGroup* g = GroupOf(m, p);
  ASSERT_NE(g, nullptr);
  glm::dvec3 xa(0.0);
  for (int q : g->members) xa += solver.unshot()[q] * m.patch_area[size_t(q)];
  ShotColumn(&hc, m, p, GroupOf(m, p), 0, true, 1, &col);
  ASSERT_FALSE(col.empty());
  glm::dvec3 gain(0.0);
  for (const FormFactor& ff : col) {
    EXPECT_NE(m.group_of[m.elems[ff.elem].patch], m.group_of[p]) << "a member received";
    gain += m.Rho(m.FaceOf(ff.elem)) * xa * double(ff.f);
  }
  const glm::dvec3 before = unshot_power();
  solver.Shoot(p, col);
  for (int q : g->members) EXPECT_EQ(solver.unshot()[q], glm::dvec3(0.0)) << q;
  const glm::dvec3 after = unshot_power();
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(after[k], before[k] - xa[k] + gain[k], 1e-12 * before[k]);
  EXPECT_EQ(solver.TimesShot(p), 1);
  EXPECT_EQ(solver.TimesShot(g->members[1]), 0);
}

// A worker forms no groups: it builds its mesh with them off and takes
// each from its shooter's assignment. Its columns, for every shooter
// (turned, twice), are the master's bit for bit, drawn on the master's
// mesh with its groups.
TEST_P(GroupShot, AWorkersColumnFromTheSentGroupIsTheMasters) {
  const Mesh m = MakeMesh(TiledBox(10, GetParam()), Half());
  ASSERT_FALSE(m.groups.empty());
  MeshOptions off = Half();
  off.groups = false;
  Mesh worker = MakeMesh(TiledBox(10, GetParam()), off);
  ASSERT_TRUE(worker.groups.empty());
  EXPECT_EQ(MeshHash(worker), MeshHash(m));  // the worker's Ready agrees
  worker.KeepColumnsOnly();
  Hemicube hm(64), hw(64);
  std::vector<FormFactor> want, got;
  size_t grouped = 0;
  for (int p = 0; p < int(m.patches.size()); ++p) {
    if (!IsShooter(m, p)) continue;
    for (int k = 0; k < 2; ++k) {
      proto::Assignment a{p, k};
      if (const PatchGroup* g = GroupOf(m, p)) a.group = *g;
      std::string frame, err;
      proto::EncodeWork({a}, &frame);
      std::vector<proto::Assignment> d;
      ASSERT_TRUE(proto::DecodeWork(std::string_view(frame).substr(proto::kHeaderSize), &d, &err))
          << err;
      ASSERT_EQ(d.size(), 1u);
      grouped += d[0].Group() != nullptr;
      ShotColumn(&hm, m, p, GroupOf(m, p), k, true, 1, &want);
      ShotColumn(&hw, worker, p, d[0].Group(), k, true, 1, &got);
      ASSERT_EQ(got.size(), want.size()) << p;
      for (size_t i = 0; i < want.size(); ++i) {
        ASSERT_EQ(got[i].elem, want[i].elem) << p << " " << i;
        ASSERT_EQ(Bits(got[i].f), Bits(want[i].f)) << p << " " << i;
      }
    }
  }
  EXPECT_EQ(grouped, 2 * m.groups.size());
}

// The closed box with its tiled floor: what is absorbed is what is emitted,
// with groups as without, and the answers agree per face.
TEST(Groups, ClosedBoxAbsorbsWhatItEmitsWithGroups) {
  const Scene s = TiledBox(10);
  std::vector<glm::dvec3> with, without;
  for (bool groups : {true, false}) {
    MeshOptions o = Half();
    o.groups = groups;
    Mesh m = MakeMesh(s, o);
    ASSERT_EQ(m.groups.empty(), !groups);
    Solver solver(m, true);
    RunOptions ro;
    ro.resolution = 64;
    ro.epsilon = 1e-6;
    ASSERT_EQ(RunSequential(&m, ro, &solver, nullptr, nullptr).status, RunStatus::kConverged);
    const auto b = FaceRadiosity(m, solver.radiosity());
    glm::dvec3 absorbed, emitted;
    PowerBalance(s, b, &absorbed, &emitted);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(absorbed[k], emitted[k], 0.01 * emitted[k]);
    (groups ? with : without) = b;
  }
  double rms, rel;
  RmsError(s, with, without, &rms, &rel);
  EXPECT_LT(rel, 0.01);
}

// Small tiles in pairs: which pairs may shoot together.
TEST(Groups, NeverAcrossAWallNorFacingAwayNorOneBehindTheOther) {
  const glm::dvec3 grey(0.5);
  Scene s = EmptyScene();
  // A room for scale (patch size 0.5 over a 4-unit scene): a big floor far below.
  AddFace(&s, {{-2, -1, -2}, {-2, -1, 2}, {2, -1, 2}, {2, -1, -2}}, grey, glm::dvec3(0));
  auto pair = [&](std::vector<glm::dvec3> a, std::vector<glm::dvec3> b) {
    AddFace(&s, a, grey, glm::dvec3(0));
    AddFace(&s, b, grey, glm::dvec3(0));
    return int(s.faces.size()) - 2;
  };
  // Side by side, coplanar, facing up: together.
  const int plain = pair({{0.0, 0, 0}, {0.0, 0, 0.1}, {0.1, 0, 0.1}, {0.1, 0, 0}},
                         {{0.2, 0, 0}, {0.2, 0, 0.1}, {0.3, 0, 0.1}, {0.3, 0, 0}});
  // The same 1 unit over, with a thin two-sided wall between them.
  const int walled = pair({{1.0, 0, 0}, {1.0, 0, 0.1}, {1.1, 0, 0.1}, {1.1, 0, 0}},
                          {{1.2, 0, 0}, {1.2, 0, 0.1}, {1.3, 0, 0.1}, {1.3, 0, 0}});
  AddFace(&s, {{1.15, 0, -0.1}, {1.15, 0.2, -0.1}, {1.15, 0.2, 0.2}, {1.15, 0, 0.2}}, grey,
          glm::dvec3(0));
  AddFace(&s, {{1.15, 0, -0.1}, {1.15, 0, 0.2}, {1.15, 0.2, 0.2}, {1.15, 0.2, -0.1}}, grey,
          glm::dvec3(0));
  // Back to back: one up, one down, side by side.
  const int away = pair({{0.0, 0, 1.0}, {0.0, 0, 1.1}, {0.1, 0, 1.1}, {0.1, 0, 1.0}},
                        {{0.2, 0, 1.0}, {0.3, 0, 1.0}, {0.3, 0, 1.1}, {0.2, 0, 1.1}});
  // Facing each other: a tile over a tile, the upper one facing down.
  const int facing = pair({{1.0, 0, 1.0}, {1.0, 0, 1.1}, {1.1, 0, 1.1}, {1.1, 0, 1.0}},
                          {{1.0, 0.1, 1.0}, {1.1, 0.1, 1.0}, {1.1, 0.1, 1.1}, {1.0, 0.1, 1.1}});
  // Both up, one a step (0.1, more than 0.5/16) above the other: one behind
  // the other's plane.
  const int step = pair({{0.0, 0, -1.0}, {0.0, 0, -0.9}, {0.1, 0, -0.9}, {0.1, 0, -1.0}},
                        {{0.2, 0.1, -1.0}, {0.2, 0.1, -0.9}, {0.3, 0.1, -0.9}, {0.3, 0.1, -1.0}});
  // Both up, 0.01 apart in height: near-coplanar, together.
  const int near = pair({{1.0, 0, -1.0}, {1.0, 0, -0.9}, {1.1, 0, -0.9}, {1.1, 0, -1.0}},
                        {{1.2, 0.01, -1.0}, {1.2, 0.01, -0.9}, {1.3, 0.01, -0.9}, {1.3, 0.01, -1.0}});
  // Side by side like `plain`, but a small upright face above and beside
  // them, facing them, lights nearer (0.23) than the pair is wide (0.32):
  // apart. The same pair with it 0.61 away: together.
  const int crowded = pair({{-1.0, 0, 1.0}, {-1.0, 0, 1.1}, {-0.9, 0, 1.1}, {-0.9, 0, 1.0}},
                           {{-0.8, 0, 1.0}, {-0.8, 0, 1.1}, {-0.7, 0, 1.1}, {-0.7, 0, 1.0}});
  AddFace(&s, {{-0.9, 0.1, 1.25}, {-0.9, 0.2, 1.25}, {-0.8, 0.2, 1.25}, {-0.8, 0.1, 1.25}}, grey,
          glm::dvec3(0));
  const int spaced = pair({{-1.0, 0, -1.0}, {-1.0, 0, -0.9}, {-0.9, 0, -0.9}, {-0.9, 0, -1.0}},
                          {{-0.8, 0, -1.0}, {-0.8, 0, -0.9}, {-0.7, 0, -0.9}, {-0.7, 0, -1.0}});
  AddFace(&s, {{-0.9, 0.5, -0.6}, {-0.9, 0.6, -0.6}, {-0.8, 0.6, -0.6}, {-0.8, 0.5, -0.6}}, grey,
          glm::dvec3(0));
  // Tilted 40 degrees against each other (roof-like, both facing out): apart.
  const double c = std::cos(40 * M_PI / 180) * 0.1, h = std::sin(40 * M_PI / 180) * 0.1;
  const int tilted =
      pair({{-1.0, 0.2, 0.0}, {-1.0, 0.2, 0.1}, {-0.9, 0.2, 0.1}, {-0.9, 0.2, 0.0}},
           {{-0.9, 0.2, 0.0}, {-0.9, 0.2, 0.1}, {-0.9 + c, 0.2 - h, 0.1}, {-0.9 + c, 0.2 - h, 0.0}});
  for (size_t f = 0; f < s.faces.size(); ++f) s.faces[f].index = int(f);
  MeshOptions o;
  o.patch_size = 0.5;
  const Mesh m = MakeMesh(s, o);
  // One patch per small face, in face order after the floor's 8 x 8.
  auto patch = [&](int face) { return m.FacePatches(m.faces[face])[0]; };
  auto together = [&](int first) { return Grouped(m, patch(first), patch(first + 1)); };
  EXPECT_TRUE(together(plain));
  EXPECT_FALSE(together(walled));
  EXPECT_FALSE(together(away));
  EXPECT_FALSE(together(facing));
  EXPECT_FALSE(together(step));
  EXPECT_TRUE(together(near));
  EXPECT_FALSE(together(tilted));
  EXPECT_FALSE(together(crowded));
  EXPECT_TRUE(together(spaced));
  // The wall's own two faces face away from each other.
  EXPECT_FALSE(Grouped(m, patch(walled + 2), patch(walled + 3)));
  // The big floor's patches are the patch size: no candidates, though
  // what they light (what faces down) is 1 and more away.
  for (int q : m.FacePatches(m.faces[0])) EXPECT_EQ(m.group_of[q], -1);
}

}  // namespace
