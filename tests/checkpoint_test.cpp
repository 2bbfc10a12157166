// Checkpoints (checkpoint.h): the file format round trip; truncated,
// corrupt, foreign and other-version files refused with their reason; the
// division history read off a mesh; and a run resumed from any of its
// checkpoints ends with exactly the radiosity of the run uninterrupted.
#include "checkpoint.h"

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <random>

#include <gtest/gtest.h>

#include "mesh.h"
#include "temp_dir.h"
#include "test_util.h"
#include "wire_util.h"

namespace {

MeshOptions ShadowMesh() {
  MeshOptions o;
  o.patch_size = 0.5;
  return o;
}

RunOptions Options() {
  RunOptions o;
  o.resolution = 64;
  o.epsilon = 1e-3;
  return o;
}

SolveOptions Solve(const RunOptions& r, const MeshOptions& m) {
  SolveOptions s;
  s.overshoot = r.overshoot;
  s.resolution = r.resolution;
  s.rotate = r.rotate;
  s.seed = r.seed;
  s.mesh = m;
  return s;
}

// A checkpoint with something in every field.
Checkpoint Filled() {
  Checkpoint c;
  c.scene_hash = std::string(32, 'h');
  c.base_hash = 0x1122334455667788ull;
  c.base_elements = 12;
  c.mesh_hash = 99;
  c.elements = 16;
  c.patches = 3;
  c.options.resolution = 128;
  c.options.seed = 7;
  c.options.mesh.patch_size = 0.25;
  c.options.sub.max_level = 3;
  c.edits = {4, 0, 13, ~1};
  c.solver.b = {glm::dvec3(1, 2, 3), glm::dvec3(-0.0, 1e-300, 4.5)};
  c.solver.unshot = {glm::dvec3(0.5), glm::dvec3(0.25), glm::dvec3(0)};
  c.solver.lit = {1, 0, 1};
  c.solver.blind = {0, 0, 1};
  c.solver.times_shot = {3, 0, 1};
  c.solver.unshot_sum = glm::dvec3(0.1, 0.2, 0.3);
  c.solver.abs_sum = 0.6;
  c.solver.shots = 4;
  c.has_subdivider = true;
  c.subdivider.threshold = 0.35;
  c.subdivider.last_pass = 40;
  c.subdivider.wave_start_leaves = 12;
  c.subdivider.divided_in_wave = 3;
  c.subdivider.quiet = true;
  c.subdivider.passes = 2;
  c.subdivider.seconds = 0.01;
  c.subdivider.split_threshold = 0.4;
  c.subdivider.splits = 1;
  c.subdivider.measured = true;
  c.subdivider.direct_mean = 0.5;
  c.subdivider.spread = {0.25, 0, 0.9};
  c.subdivider.near = {0, 1, 0};
  c.run.wave = 2;
  c.run.wave_start = 30;
  c.run.best = HUGE_VAL;
  c.run.best_at = 31;
  c.run.seconds = 1.5;
  c.run.columns = 4;
  c.run.pending = {2, 1};
  c.log = "0.000000,0,1,12,1,,\n";
  return c;
}

// Filled() (whose bytes format 1 pins) with values a run could write,
// which DecodeCheckpoint checks: a B per element, counts within the shots.
Checkpoint Plausible() {
  Checkpoint c = Filled();
  c.solver.b.resize(c.elements, glm::dvec3(0.125));
  c.solver.noise.assign(c.elements, 0.5);
  c.solver.direct.assign(c.elements, 0.25f);
  c.solver.shots = 40;
  return c;
}

std::string Error(const std::string& bytes) {
  Checkpoint c;
  std::string err;
  EXPECT_FALSE(DecodeCheckpoint(bytes, &c, &err));
  return err;
}

TEST(Checkpoint, RoundTrip) {
  const Checkpoint a = Plausible();
  const std::string bytes = EncodeCheckpoint(a);
  EXPECT_EQ(bytes.substr(0, 8), "RADCKPT\n");
  Checkpoint b;
  std::string err;
  ASSERT_TRUE(DecodeCheckpoint(bytes, &b, &err)) << err;
  EXPECT_EQ(EncodeCheckpoint(b), bytes);
  EXPECT_EQ(b.scene_hash, a.scene_hash);
  EXPECT_EQ(b.edits, a.edits);
  EXPECT_EQ(b.solver.b, a.solver.b);
  EXPECT_TRUE(std::signbit(b.solver.b[1].x));
  EXPECT_EQ(b.solver.times_shot, a.solver.times_shot);
  EXPECT_EQ(b.solver.noise, a.solver.noise);
  EXPECT_EQ(b.solver.direct, a.solver.direct);
  EXPECT_EQ(b.subdivider.threshold, 0.35);
  EXPECT_TRUE(b.subdivider.quiet);
  EXPECT_EQ(b.run.best, HUGE_VAL);
  EXPECT_EQ(b.run.pending, a.run.pending);
  EXPECT_EQ(b.log, a.log);
  EXPECT_EQ(CompareOptions(a.options, b.options), "");
}

// Format 4 (format 1 plus the two group options, 9 bytes, in 2; plus the
// noise array, its 8-byte count here, the three shooter-division options,
// 17 bytes, and their state, 16, in 3; plus --split-near, 8, and the
// direct light array's count, 8, in 4) pinned byte for byte (the trailing
// SHA-256 covers every byte before it), and the scene and mesh hashes a
// checkpoint is checked against are those format 1 had.
TEST(Checkpoint, BytesAndHashesAreThoseOfFormat5) {
  const std::string bytes = EncodeCheckpoint(Filled());
  EXPECT_EQ(bytes.size(), 719u);
  EXPECT_EQ(Hex(bytes.substr(bytes.size() - 32)),
            "4c02883dff893dbf1347c2158cb99abcd4cfe45ae64c48131efb24ec618a9525");
  EXPECT_EQ(Hex(SceneHash(ShadowScene())),
            "e5ded178170e67915e7e2c974f2f76313e56922c54aa9ce557da0635a7ee8021");
  EXPECT_EQ(MeshHash(MakeMesh(ShadowScene(), ShadowMesh())), 0x4305479c346ad8daull);
}

TEST(Checkpoint, TruncatedAtAnyLengthIsRefused) {
  const std::string bytes = EncodeCheckpoint(Filled());
  for (size_t n = 0; n < bytes.size(); ++n) {
    const std::string err = Error(bytes.substr(0, n));
    if (n < 8) {
      EXPECT_EQ(err, "not a radiosity checkpoint (no RADCKPT magic)") << n;
    } else {
      EXPECT_EQ(err.rfind("truncated: ", 0), 0u) << n << ": " << err;
    }
  }
  EXPECT_EQ(Error(bytes + "x").rfind("bytes after the end: ", 0), 0u);
}

TEST(Checkpoint, EveryFlippedByteIsRefused) {
  const std::string bytes = EncodeCheckpoint(Filled());
  for (size_t i = 0; i < bytes.size(); ++i) {
    std::string bad = bytes;
    bad[i] = char(bad[i] ^ 0x20);
    const std::string err = Error(bad);
    EXPECT_FALSE(err.empty()) << i;
    if (i >= 24) {
      EXPECT_EQ(err, "corrupt: the SHA-256 checksum does not match") << i;
    }
  }
}

TEST(Checkpoint, ForeignAndOtherVersionsAreRefused) {
  std::mt19937 rng(5);
  std::string noise(4096, '\0');
  for (char& c : noise) c = char(rng());
  EXPECT_EQ(Error(noise), "not a radiosity checkpoint (no RADCKPT magic)");
  EXPECT_EQ(Error(""), "not a radiosity checkpoint (no RADCKPT magic)");
  std::string v1 = EncodeCheckpoint(Filled());
  v1[8] = 1;
  EXPECT_EQ(Error(v1), "checkpoint format version 1, this radiosity reads 5");
}

// An edited checkpoint, re-hashed so that its checksum holds: values no
// run writes are refused, each with its reason.
TEST(Checkpoint, ValuesAreCheckedAfterTheChecksum) {
  ASSERT_EQ(Error(EncodeCheckpoint(Filled())),
            "corrupt: solver arrays do not match the element and patch counts (the checksum "
            "holds: an edited file?)");
  struct Case {
    const char* why;
    void (*edit)(Checkpoint*);
  };
  const Case cases[] = {
      {"a radiosity that is not a finite number", [](Checkpoint* c) { c->solver.b[3].g = NAN; }},
      {"a radiosity that is not a finite number", [](Checkpoint* c) { c->solver.b[0].r = HUGE_VAL; }},
      {"an unshot radiosity that is not a finite number",
       [](Checkpoint* c) { c->solver.unshot[1].b = -HUGE_VAL; }},
      {"unshot sums not finite", [](Checkpoint* c) { c->solver.abs_sum = NAN; }},
      {"a noise variance that is not a finite number >= 0",
       [](Checkpoint* c) { c->solver.noise[2] = -1; }},
      {"the noise array does not match the element count",
       [](Checkpoint* c) { c->solver.noise.pop_back(); }},
      {"a negative shot count", [](Checkpoint* c) { c->solver.shots = -1; }},
      {"patch 2's flags or shot count out of range", [](Checkpoint* c) { c->solver.lit[2] = 7; }},
      {"patch 0's flags or shot count out of range", [](Checkpoint* c) { c->solver.times_shot[0] = 41; }},
      {"run state out of range", [](Checkpoint* c) { c->run.wave = 0; }},
      {"run state out of range", [](Checkpoint* c) { c->run.seconds = NAN; }},
      {"run state out of range", [](Checkpoint* c) { c->run.best = NAN; }},
      {"pending patch 3 out of range or listed twice", [](Checkpoint* c) { c->run.pending = {3}; }},
      {"pending patch 1 out of range or listed twice", [](Checkpoint* c) { c->run.pending = {1, 1}; }},
      {"subdivision state out of range", [](Checkpoint* c) { c->subdivider.seconds = -1; }},
      {"subdivision state out of range", [](Checkpoint* c) { c->subdivider.spread[1] = NAN; }},
      {"subdivision state out of range", [](Checkpoint* c) { c->subdivider.near.push_back(0); }},
      {"element and patch counts out of range", [](Checkpoint* c) { c->elements = 1u << 30; }},
      {"log rows that are not numbers", [](Checkpoint* c) { c->log = "\x1b[2J\n"; }},
  };
  for (const Case& k : cases) {
    Checkpoint c = Plausible();
    k.edit(&c);
    EXPECT_EQ(Error(EncodeCheckpoint(c)),
              std::string("corrupt: ") + k.why + " (the checksum holds: an edited file?)");
  }
}

TEST(Checkpoint, OptionsAreCompared) {
  SolveOptions a, b;
  EXPECT_EQ(CompareOptions(a, b), "");
  b.resolution = 128;
  EXPECT_EQ(CompareOptions(a, b), "--resolution 256 (this run: 128)");
  b = a;
  b.overshoot = false;
  EXPECT_EQ(CompareOptions(a, b), "--no-overshoot not given (this run: given)");
  b = a;
  b.mesh.patch_size = 0.5;
  EXPECT_EQ(CompareOptions(a, b), "--patch-size default (this run: 0.5)");
  b = a;
  b.mesh.groups = false;
  EXPECT_EQ(CompareOptions(a, b), "--no-groups not given (this run: given)");
  b = a;
  b.mesh.group_size = 0.5;
  EXPECT_EQ(CompareOptions(a, b), "--group-size default (this run: 0.5)");
  a.mesh.groups = b.mesh.groups = false;  // then the group size does not matter
  EXPECT_EQ(CompareOptions(a, b), "");
  a = b = SolveOptions();
  b.sub.max_level = 4;
  EXPECT_EQ(CompareOptions(a, b), "--max-level 2 (this run: 4)");
  a.subdivide = b.subdivide = false;  // then the subdivision limits do not matter
  EXPECT_EQ(CompareOptions(a, b), "");
}

TEST(Checkpoint, FileIsWrittenAtomicallyAndReadBack) {
  char dir[] = "/tmp/checkpoint_test.XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string path = std::string(dir) + "/ck";
  size_t bytes = 0;
  std::string err;
  ASSERT_TRUE(WriteCheckpoint(path, Plausible(), &bytes, &err)) << err;
  EXPECT_EQ(bytes, EncodeCheckpoint(Plausible()).size());
  EXPECT_NE(access((path + ".tmp").c_str(), F_OK), 0);  // renamed, nothing left beside it
  Checkpoint c;
  ASSERT_TRUE(ReadCheckpoint(path, &c, &err)) << err;
  EXPECT_EQ(c.edits, Filled().edits);
  EXPECT_FALSE(ReadCheckpoint(std::string(dir) + "/none", &c, &err));
  EXPECT_EQ(err, std::string(dir) + "/none: No such file or directory");
  EXPECT_FALSE(WriteCheckpoint(std::string(dir) + "/no/such/dir", Filled(), &bytes, &err));
  EXPECT_EQ(err, std::string(dir) + "/no/such/dir: cannot create a file in " + dir +
                     "/no/such: No such file or directory");
  std::remove(path.c_str());
  rmdir(dir);  // fails if a temporary was left beside the checkpoint
  EXPECT_NE(access(dir, F_OK), 0);
}

// A link planted where the old format wrote its temporary (FILE.tmp), or
// at FILE itself, never makes the checkpoint replace what it points to.
TEST(Checkpoint, PlantedLinksAreNotFollowed) {
  TempDir dir;
  const std::string victim = dir.Write("victim", "precious"), path = dir.path() + "/ck";
  ASSERT_EQ(symlink(victim.c_str(), (path + ".tmp").c_str()), 0);
  size_t bytes = 0;
  std::string err;
  ASSERT_TRUE(WriteCheckpoint(path, Filled(), &bytes, &err)) << err;
  std::ifstream in(victim);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "precious");
  const std::string link = dir.path() + "/link";
  ASSERT_EQ(symlink(victim.c_str(), link.c_str()), 0);
  EXPECT_FALSE(WriteCheckpoint(link, Filled(), &bytes, &err));
  EXPECT_EQ(err, link + ": is a symbolic link; not replaced");
  EXPECT_FALSE(WriteCheckpoint("/dev/null", Filled(), &bytes, &err));
  EXPECT_EQ(err, "/dev/null: is not a regular file; not replaced");
}

TEST(Checkpoint, DivideHistoryReplaysToTheSameMesh) {
  const Scene s = ShadowScene();
  Mesh m = MakeMesh(s, ShadowMesh());
  const Mesh built = m;
  // Divide in an order that is not increasing, children of children too.
  Divide(&m, 7);
  Divide(&m, 2);
  Divide(&m, m.elems[7].first_child + 1);
  Divide(&m, 0);
  const std::vector<int32_t> edits = DivideHistory(m);
  EXPECT_EQ(edits, (std::vector<int32_t>{7, 2, m.elems[7].first_child + 1, 0}));
  Mesh again = built;
  std::string err;
  ASSERT_TRUE(ReplayDivisions(&again, edits, &err)) << err;
  EXPECT_EQ(MeshHash(again), MeshHash(m));
  Mesh bad = built;
  EXPECT_FALSE(ReplayDivisions(&bad, {2, 2}, &err));
  EXPECT_EQ(err, "division 2 of 2 names element 2, which is not a leaf of the mesh");
  EXPECT_FALSE(ReplayDivisions(&bad, {~int32_t(built.patches.size())}, &err));
}

TEST(Checkpoint, IdentityRefusesAnotherSceneAndOtherOptions) {
  const Scene s = ShadowScene();
  const Mesh m = MakeMesh(s, ShadowMesh());
  const RunIdentity id = Identify(s, m, Solve(Options(), ShadowMesh()));
  Checkpoint c;
  c.scene_hash = id.scene_hash;
  c.base_hash = id.base_hash;
  c.base_elements = id.base_elements;
  c.options = id.options;
  c.has_subdivider = true;
  std::string err;
  EXPECT_TRUE(CheckIdentity(c, id, &err)) << err;
  Scene other = s;
  other.materials[4].ke = glm::dvec3(50);  // the light, dimmer
  EXPECT_FALSE(CheckIdentity(c, Identify(other, m, id.options), &err));
  EXPECT_EQ(err, "a checkpoint of another scene (its faces or materials differ)");
  SolveOptions o = id.options;
  o.seed = 2;
  EXPECT_FALSE(CheckIdentity(c, Identify(s, m, o), &err));
  EXPECT_EQ(err, "made with other options: --seed 1 (this run: 2); resume with the options of "
                 "that run");
}

struct ShadowRun {
  explicit ShadowRun(const Scene& s) : mesh(MakeMesh(s, ShadowMesh())), solver(mesh, true),
                                 sub(&mesh, SubdivideOptions()) {}
  Mesh mesh;
  Solver solver;
  Subdivider sub;
};

// The shadow scene with 3 x 3 small tiles beside the floor, far from what
// they light: they shoot as a group (groups.h).
Scene TiledShadowScene() {
  Scene s = ShadowScene();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double x = 2.1 + 0.1 * i, y = 0.1 * j;
      AddFace(&s, {{x, y, 0}, {x + 0.1, y, 0}, {x + 0.1, y + 0.1, 0}, {x, y + 0.1, 0}},
              glm::dvec3(0.5), glm::dvec3(0));
    }
  return s;
}

// The run of scene s, checkpointed after every shot, and resumed from a
// checkpoint in each wave and from the last one: the resumed runs end
// with the uninterrupted run's radiosity, bit for bit, and its log.
void ResumedRunEndsExactlyLikeTheWholeRun(const Scene& s) {
  const RunIdentity id = Identify(s, MakeMesh(s, ShadowMesh()), Solve(Options(), ShadowMesh()));
  ShadowRun whole(s);
  std::vector<std::string> saved;
  std::vector<int> wave_of;
  std::vector<long> log;  // shots of each sample
  RunOptions o = Options();
  o.checkpoint_every = 1e-12;  // after every shot
  o.checkpoint = [&](const RunState& st) {
    saved.push_back(EncodeCheckpoint(Capture(id, whole.mesh, whole.solver, &whole.sub, st, "")));
    wave_of.push_back(st.wave);
  };
  RunResult r = RunSequential(&whole.mesh, o, &whole.solver, &whole.sub,
                              [&](const Sample& x) { log.push_back(x.shots); });
  ASSERT_EQ(r.status, RunStatus::kConverged);
  ASSERT_GE(r.waves, 2);
  ASSERT_GT(whole.mesh.LeafCount(), long(MakeMesh(s, ShadowMesh()).elems.size()));
  ASSERT_EQ(long(saved.size()), r.shots + 1);  // each shot, and the end
  std::vector<size_t> from = {saved.size() / 5, saved.size() - 1};
  for (size_t i = 1; i < saved.size(); ++i)
    if (wave_of[i] != wave_of[i - 1]) from.push_back(i + 3);
  for (size_t i : from) {
    SCOPED_TRACE("resumed from checkpoint " + std::to_string(i));
    ASSERT_LT(i, saved.size());
    Checkpoint c;
    std::string err;
    ASSERT_TRUE(DecodeCheckpoint(saved[i], &c, &err)) << err;
    ShadowRun part(s);
    ASSERT_TRUE(CheckIdentity(c, id, &err)) << err;
    ASSERT_TRUE(ApplyCheckpoint(c, &part.mesh, &part.solver, &part.sub, &err)) << err;
    RunOptions p = Options();
    p.resume = &c.run;
    std::vector<long> rest;
    RunResult q = RunSequential(&part.mesh, p, &part.solver, &part.sub,
                                [&](const Sample& x) { rest.push_back(x.shots); });
    EXPECT_EQ(q.status, RunStatus::kConverged);
    EXPECT_EQ(q.shots, r.shots);
    EXPECT_EQ(q.waves, r.waves);
    EXPECT_EQ(MeshHash(part.mesh), MeshHash(whole.mesh));
    EXPECT_TRUE(part.solver.radiosity() == whole.solver.radiosity());
    // The samples after the checkpoint are the whole run's last ones.
    ASSERT_LE(rest.size(), log.size());
    EXPECT_TRUE(std::equal(rest.begin(), rest.end(), log.end() - long(rest.size())));
  }
}

TEST(Checkpoint, ResumedRunEndsExactlyLikeTheWholeRun) {
  ResumedRunEndsExactlyLikeTheWholeRun(ShadowScene());
}

TEST(Checkpoint, ResumedRunWithGroupsEndsExactlyLikeTheWholeRun) {
  const Scene s = TiledShadowScene();
  const Mesh m = MakeMesh(s, ShadowMesh());
  ASSERT_EQ(m.groups.size(), 1u);
  ASSERT_EQ(m.groups[0].members.size(), 9u);
  ResumedRunEndsExactlyLikeTheWholeRun(s);
}

}  // namespace
