// The master's scheduler against a fake transport: no processes, every
// assignment visible, losses and late columns on cue. Columns are real
// hemicube columns so that runs converge to real answers.
#include <algorithm>
#include <map>
#include <memory>
#include <set>

#include <gtest/gtest.h>

#include "groups.h"
#include "inprocess.h"
#include "results.h"
#include "scheduler.h"
#include "test_util.h"

namespace {

class FakeTransport : public Transport {
 public:
  FakeTransport(const Mesh& mesh, int workers, int resolution = 32)
      : mesh_(mesh), hemicube_(resolution), queue_(workers) {}
  int Workers() const override { return int(queue_.size()); }
  int Starting() const override { return joined_ ? 0 : int(queue_.size()); }
  std::string Name(int w) const override { return "fake " + std::to_string(w); }
  void Assign(int w, const proto::Assignment& a) override {
    ASSERT_FALSE(lost_.count(w)) << "assignment to a lost worker";
    queue_[w].push_back(a);
    log_.push_back({w, a.patch});
    sent_.push_back(a);
    max_outstanding_ = std::max(max_outstanding_, queue_[w].size());
    ++unsent_;
  }
  // Sent in Poll, as the worker pool sends: what was given out and not
  // yet sent when the master divides.
  void Divide(const std::vector<int32_t>&) override {
    ++divides_;
    unsent_at_divide_ += unsent_;
  }
  double Now() override { return now_ += now_step_; }
  void Send(std::vector<WorkerEvent>*) override {
    ++sends_;
    unsent_ = 0;
  }

  // Each Poll: the first joins everyone; later ones answer one assignment
  // of each worker in turn (round robin), as workers of equal speed would.
  void Poll(double, std::vector<WorkerEvent>* events) override {
    unsent_ = 0;
    now_ += 1e-3;
    if (!joined_) {
      joined_ = true;
      for (int w = 0; w < Workers(); ++w)
        if (!never_join_) events->push_back({WorkerEvent::kJoined, w, {}, ""});
        else events->push_back({WorkerEvent::kLost, w, {}, "never started"});
      if (never_join_) lost_all_ = true;
      return;
    }
    ++polls_;
    if (lose_at_.count(polls_)) {
      const int w = lose_at_[polls_];
      lost_.insert(w);
      queue_[w].clear();
      events->push_back({WorkerEvent::kLost, w, {}, "killed"});
    }
    // Everything computed meanwhile, read at once: after a long step
    // (burst_), or always, from workers far quicker than the master.
    if (burst_ || answer_all_) {
      burst_ = false;
      for (int w = 0; w < Workers(); ++w)
        while (!lost_.count(w) && !silent_.count(w) && !queue_[w].empty()) Answer(w, events);
      return;
    }
    if (quiet_every_ > 0 && polls_ % quiet_every_ == 0) return;
    for (int i = 0; i < Workers(); ++i) {
      const int w = (next_ + i) % Workers();
      if (lost_.count(w) || silent_.count(w) || queue_[w].empty()) continue;
      next_ = w + 1;
      Answer(w, events);
      if (duplicate_at_ == polls_) events->push_back(events->back());  // a late copy
      return;
    }
  }
  // Worker w's column for its oldest assignment.
  void Answer(int w, std::vector<WorkerEvent>* events) {
    const proto::Assignment a = queue_[w].front();
    queue_[w].erase(queue_[w].begin());
    WorkerEvent ev{WorkerEvent::kColumn, w, {}, ""};
    ev.column.patch = a.patch;
    ev.column.k = a.k;
    // Quick workers say so: their queues deepen to cover the round trip.
    ev.column.compute_s = answer_all_ ? 1e-6 : 1e-3;
    hemicube_.Column(mesh_, a.patch, a.Group(), 0.0, &ev.column.ff);
    events->push_back(std::move(ev));
  }

  const Mesh& mesh_;
  Hemicube hemicube_;
  std::vector<std::vector<proto::Assignment>> queue_;
  std::vector<std::pair<int, int>> log_;  // (worker, patch) in assignment order
  std::vector<proto::Assignment> sent_;   // the assignments themselves, in that order
  std::map<long, int> lose_at_;           // poll number -> worker lost then
  std::set<int> lost_;
  std::set<int> silent_;                  // workers that never answer (SIGSTOP)
  long duplicate_at_ = -1;
  bool never_join_ = false, joined_ = false, lost_all_ = false;
  bool answer_all_ = false;  // each Poll answers every assignment
  size_t max_outstanding_ = 0;
  long polls_ = 0, sends_ = 0;
  long unsent_ = 0, divides_ = 0, unsent_at_divide_ = 0;
  // Every so many polls bring nothing (the workers still computing):
  // then the columns waiting are shot and the master may divide.
  long quiet_every_ = 0;
  bool burst_ = false;  // the next Poll answers every assignment (after a long step)
  int next_ = 0;
  double now_ = 0;
  double now_step_ = 0;  // Now() moves on this much at every call
};

// A closed box whose six walls are lights of different strength, so that
// the order of the first selections is known: strongest first.
Scene Lights() {
  return Box(1.0, {glm::dvec3(0.5)},
             {glm::dvec3(6), glm::dvec3(5), glm::dvec3(4), glm::dvec3(3), glm::dvec3(2),
              glm::dvec3(1)});
}

MeshOptions OnePatchPerFace() {
  MeshOptions o;
  o.patch_size = 2.0;  // each wall is one patch
  return o;
}

RunOptions Opts() {
  RunOptions o;
  o.resolution = 32;
  o.epsilon = 1e-3;
  o.rotate = false;
  return o;
}

TEST(Scheduler, FirstLightsGoToDifferentWorkers) {
  Scene s = Lights();
  Mesh m = MakeMesh(s, OnePatchPerFace());
  ASSERT_EQ(m.patches.size(), 6u);
  FakeTransport t(m, 3);
  Solver solver(m, true);
  RunOptions o = Opts();
  o.queue = 2;
  o.max_shots = 1;
  RunMaster(&m, o, &solver, nullptr, &t, nullptr, nullptr);
  // Cyclic fill: worker 0 gets the strongest light, worker 1 the second,
  // worker 2 the third, then round again.
  ASSERT_GE(t.log_.size(), 6u);
  std::vector<int> first_of(3, -1);
  for (auto [w, p] : t.log_)
    if (first_of[w] < 0) first_of[w] = p;
  EXPECT_EQ(m.patches[first_of[0]].face, 0);
  EXPECT_EQ(m.patches[first_of[1]].face, 1);
  EXPECT_EQ(m.patches[first_of[2]].face, 2);
}

// Early in a run only the lights have power to shoot, so the fill runs out
// of patches before every queue is served: what it did prepare must still
// be sent (a run with one light and two workers once waited for ever).
TEST(Scheduler, FillThatRunsOutStillSends) {
  const glm::dvec3 dark(0.0);
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0), dark, dark, dark, dark, dark});
  Mesh m = MakeMesh(s, OnePatchPerFace());
  FakeTransport t(m, 2);
  Solver solver(m, true);
  RunOptions o = Opts();
  o.max_seconds = 5;  // on the fake's clock: a hang ends as kLimit
  RunResult r = RunMaster(&m, o, &solver, nullptr, &t, nullptr, nullptr);
  EXPECT_EQ(r.status, RunStatus::kConverged) << r.why;
}

// Worker 0 never answers, as if stopped. The cyclic fill gives it the
// lights of faces 0, 2 and 4, two sent and face 4's prepared; worker 1
// gets 1, 3 and 5. Once worker 1 has shot its own, everything with power
// is owned: it must take over face 4's light, which worker 0 was never
// sent, instead of waiting for worker 0.
TEST(Scheduler, AStarvingWorkerTakesOverPatchesNotYetSentToAnother) {
  Scene s = Lights();
  Mesh m = MakeMesh(s, OnePatchPerFace());
  FakeTransport t(m, 2);
  t.silent_.insert(0);
  Solver solver(m, true);
  RunOptions o = Opts();
  o.queue = 6;
  o.max_seconds = 1;  // on the fake's clock: worker 0's two never come back
  RunMaster(&m, o, &solver, nullptr, &t, nullptr, nullptr);
  std::vector<int> to(6, -1);  // the worker each face's patch first went to
  for (auto [w, p] : t.log_)
    if (to[m.patches[p].face] < 0) to[m.patches[p].face] = w;
  EXPECT_EQ(to[0], 0);
  EXPECT_EQ(to[2], 0);
  EXPECT_EQ(to[4], 1);
  EXPECT_EQ(to[1], 1);
  for (auto [w, p] : t.log_) EXPECT_FALSE(w == 0 && m.patches[p].face == 4);
}

TEST(Scheduler, QueuesStayWithinTheHighMark) {
  Scene s = Box(1.0, {glm::dvec3(0.6)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  FakeTransport t(m, 2);
  Solver solver(m, true);
  RunOptions o = Opts();
  o.queue = 4;
  RunResult r = RunMaster(&m, o, &solver, nullptr, &t, nullptr, nullptr);
  EXPECT_EQ(r.status, RunStatus::kConverged);
  EXPECT_LE(t.max_outstanding_, 4u);
  EXPECT_GE(t.max_outstanding_, 2u);  // the pipeline was used
  EXPECT_EQ(r.columns, r.shots);
}

// A recycled form factor list is where the next column goes (no new
// storage), and the column is what a fresh list gets.
TEST(Scheduler, RecycledColumnStorageGetsTheSameColumn) {
  const glm::dvec3 dark(0.0);
  Scene s = Box(1.0, {glm::dvec3(0.7)}, {glm::dvec3(1.0), dark, dark, dark, dark, dark});
  Mesh m = MakeMesh(s);
  InProcessTransport in(m, 32, false, 1);
  std::vector<WorkerEvent> ev;
  in.Poll(0, &ev);  // joined
  ASSERT_EQ(ev.size(), 1u);
  in.Assign(0, {0, 0});
  in.Poll(0, &ev);
  ASSERT_EQ(ev.size(), 2u);
  const std::vector<FormFactor> fresh = ev[1].column.ff;
  ASSERT_FALSE(fresh.empty());
  // Stale contents and a larger size than the column: none of it shows.
  std::vector<FormFactor> old(fresh.size() + 50, FormFactor{7, 0.5f});
  const FormFactor* const storage = old.data();
  in.Recycle(std::move(old));
  in.Assign(0, {0, 0});
  in.Poll(0, &ev);
  ASSERT_EQ(ev.size(), 3u);
  EXPECT_EQ(ev[2].column.ff.data(), storage);
  ASSERT_EQ(ev[2].column.ff.size(), fresh.size());
  for (size_t i = 0; i < fresh.size(); ++i) {
    EXPECT_EQ(ev[2].column.ff[i].elem, fresh[i].elem);
    EXPECT_EQ(ev[2].column.ff[i].f, fresh[i].f);
  }
}

// With more columns at hand than the one it shoots next, the master only
// sends work between Polls, until kHearEvery (100 us) has passed since
// the last: the workers here answer everything at each Poll, so a Poll
// brings up to a queue's worth. On a clock that moves 1 ms a reading it
// hears them every turn.
TEST(Scheduler, ColumnsAtHandAreShotBeforeWorkersAreHeardAgain) {
  Scene s = Box(1.0, {glm::dvec3(0.6)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  RunOptions o = Opts();
  o.queue = 8;
  o.max_shots = 200;
  auto run = [&](double step, long* polls, long* sends) {
    FakeTransport t(m, 1);
    t.answer_all_ = true;
    t.now_step_ = step;
    Solver solver(m, true);
    RunResult r = RunMaster(&m, o, &solver, nullptr, &t, nullptr, nullptr);
    EXPECT_EQ(r.shots, 200);
    EXPECT_EQ(r.columns, r.shots);
    *polls = t.polls_;
    *sends = t.sends_;
  };
  long polls, sends;
  run(0.0, &polls, &sends);
  EXPECT_LT(polls, 200 / 3);
  EXPECT_GT(sends, 200 / 2);
  run(1e-3, &polls, &sends);
  EXPECT_GE(polls, 200);
  EXPECT_EQ(sends, 0);
}

// The same answer as the sequential run, and every assignment shot once.
TEST(Scheduler, LostWorkerLosesNothing) {
  const glm::dvec3 dark(0.0);
  Scene s = Box(1.0, {glm::dvec3(0.7)}, {glm::dvec3(1.0), dark, dark, dark, dark, dark});
  Mesh m = MakeMesh(s);
  Solver seq(m, true);
  RunOptions o = Opts();
  o.epsilon = 1e-4;
  InProcessTransport in(m, 32, false, 1);
  ASSERT_EQ(RunMaster(&m, o, &seq, nullptr, &in, nullptr, nullptr).status, RunStatus::kConverged);

  FakeTransport t(m, 3);
  t.lose_at_[5] = 1;
  t.lose_at_[40] = 2;
  Solver par(m, true);
  std::vector<std::string> notes;
  RunResult r = RunMaster(&m, o, &par, nullptr, &t, nullptr,
                    [&](const std::string& line, bool warning) {
                      if (warning) notes.push_back(line);
                    });
  ASSERT_EQ(r.status, RunStatus::kConverged) << r.why;
  EXPECT_EQ(r.lost, 2);
  ASSERT_EQ(notes.size(), 2u);
  EXPECT_NE(notes[0].find("fake 1: lost (killed)"), std::string::npos) << notes[0];
  const auto a = FaceRadiosity(m, seq.radiosity()), b = FaceRadiosity(m, par.radiosity());
  for (size_t f = 0; f < a.size(); ++f)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(b[f][c], a[f][c], 0.005 * a[f][c] + 1e-9) << f;
  // Worker 1's patches went to others: each (patch, k) assigned at most
  // once to a worker that answered it.
  long shots = 0;
  for (size_t p = 0; p < m.patches.size(); ++p) shots += par.TimesShot(int(p));
  EXPECT_EQ(shots, r.shots);
}

// Workers form no shooter groups: every assignment of a group's first
// member carries the group (groups.h), one resent after its worker was
// lost too, and no other assignment carries one.
TEST(Scheduler, EveryAssignmentOfAGroupCarriesItResentOnesToo) {
  // The box's floor cut into 10 x 10 tiles, the ceiling the light: with
  // patch size 0.5 the tiles away from the walls group (groups_test).
  const glm::dvec3 dark(0.0);
  Scene s = Box(1.0, {glm::dvec3(0.6)}, {dark, glm::dvec3(10), dark, dark, dark, dark});
  s.faces.erase(s.faces.begin());
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) {
      const double x = i / 10.0, z = j / 10.0;
      AddFace(&s, {{x, 0, z}, {x, 0, z + 0.1}, {x + 0.1, 0, z + 0.1}, {x + 0.1, 0, z}},
              glm::dvec3(0.5), dark);
    }
  for (size_t f = 0; f < s.faces.size(); ++f) s.faces[f].index = int(f);
  MeshOptions half;
  half.patch_size = 0.5;
  Mesh m = MakeMesh(s, half);
  ASSERT_FALSE(m.groups.empty());
  FakeTransport t(m, 3);
  t.lose_at_[30] = 1;
  t.lose_at_[80] = 2;
  Solver par(m, true);
  RunOptions o = Opts();
  o.max_shots = 200;
  RunResult r = RunMaster(&m, o, &par, nullptr, &t, nullptr, nullptr);
  EXPECT_EQ(r.lost, 2);
  std::map<std::pair<int, int>, int> times;  // (patch, k) -> assignments
  size_t grouped = 0, resent_groups = 0;
  for (const proto::Assignment& a : t.sent_) {
    const PatchGroup* g = GroupOf(m, a.patch);
    ASSERT_EQ(a.Group() != nullptr, g != nullptr) << a.patch;
    if (++times[{a.patch, a.k}] == 2 && g) ++resent_groups;
    if (!g) continue;
    ++grouped;
    EXPECT_EQ(a.group.members, g->members);
    EXPECT_EQ(a.group.center, g->center);
    EXPECT_EQ(a.group.normal, g->normal);
  }
  EXPECT_GT(grouped, 0u);
  EXPECT_GT(resent_groups, 0u);
}

TEST(Scheduler, LateCopyOfAColumnIsNotShotTwice) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  FakeTransport t(m, 2);
  t.duplicate_at_ = 3;
  Solver solver(m, true);
  RunResult r = RunMaster(&m, Opts(), &solver, nullptr, &t, nullptr, nullptr);
  EXPECT_EQ(r.stale, 1);
  EXPECT_EQ(r.columns, r.shots);
}

// A lit box and two fake workers, both lost early in the run.
struct BothLost {
  BothLost() { t.lose_at_ = {{3, 0}, {4, 1}}; }
  Mesh m = MakeMesh(Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}));
  FakeTransport t{m, 2};
  Solver solver{m, true};
};

TEST(Scheduler, MasterTakesOverWhenAllWorkersAreLost) {
  BothLost x;
  RunOptions o = Opts();
  o.fallback = [&] { return std::make_unique<InProcessTransport>(x.m, 32, false, 1); };
  RunResult r = RunMaster(&x.m, o, &x.solver, nullptr, &x.t, nullptr, nullptr);
  EXPECT_EQ(r.status, RunStatus::kConverged);
  EXPECT_TRUE(r.fell_back);
  EXPECT_LT(x.solver.UnshotFraction(), 1e-3);
}

// The fallback is the caller's: made once, when the last worker is lost,
// and from then on the only transport the scheduler drives.
TEST(Scheduler, TheInjectedFallbackIsWhatTakesOver) {
  // Counts its assignments where the test can read them: the scheduler
  // owns the fallback and deletes it when the run ends.
  struct Counting : FakeTransport {
    Counting(const Mesh& m, long* n) : FakeTransport(m, 1), n_(n) {}
    void Assign(int w, const proto::Assignment& a) override {
      ++*n_;
      FakeTransport::Assign(w, a);
    }
    long* n_;
  };
  BothLost x;
  int calls = 0;
  long assigned = 0;
  RunOptions o = Opts();
  o.fallback = [&] {
    ++calls;
    return std::make_unique<Counting>(x.m, &assigned);
  };
  std::vector<std::string> notes;
  RunResult r = RunMaster(&x.m, o, &x.solver, nullptr, &x.t, nullptr,
                          [&](const std::string& line, bool) { notes.push_back(line); });
  ASSERT_EQ(calls, 1);
  EXPECT_EQ(r.status, RunStatus::kConverged) << r.why;
  EXPECT_TRUE(r.fell_back);
  EXPECT_EQ(r.lost, 2);
  EXPECT_EQ(r.joined, 3);  // the fallback's worker joined like any other
  EXPECT_GT(assigned, 0);
  EXPECT_NE(std::find(notes.begin(), notes.end(),
                      "no workers left: the master computes the form factors itself"),
            notes.end());
}

// Without a fallback, losing every worker ends the run.
TEST(Scheduler, WithoutAFallbackLosingEveryWorkerEndsTheRun) {
  BothLost x;
  RunResult r = RunMaster(&x.m, Opts(), &x.solver, nullptr, &x.t, nullptr, nullptr);
  EXPECT_EQ(r.status, RunStatus::kNoWorkers);
  EXPECT_EQ(r.why, "every worker was lost");
  EXPECT_FALSE(r.fell_back);
  EXPECT_GT(r.shots, 0);
}

// The in-process transport says that it computes inside Poll: the
// scheduler then selects one patch at a time (no pipeline), in the
// sequential algorithm's order, and reports no workers.
TEST(Scheduler, ComputingInPollMeansOnePatchAtATime) {
  Scene s = Lights();
  Mesh m = MakeMesh(s, OnePatchPerFace());
  InProcessTransport in(m, 32, false, 1);
  EXPECT_TRUE(in.Caps().computes_in_poll);
  FakeTransport fake(m, 1);
  EXPECT_FALSE(fake.Caps().computes_in_poll);
  Solver solver(m, true);
  RunOptions o = Opts();
  o.log_every = 1;
  std::vector<int> workers;
  RunResult r = RunMaster(&m, o, &solver, nullptr, &in,
                          [&](const Sample& smp) { workers.push_back(smp.workers); }, nullptr);
  EXPECT_EQ(r.status, RunStatus::kConverged);
  ASSERT_FALSE(workers.empty());
  EXPECT_EQ(*std::max_element(workers.begin(), workers.end()), 0);
}

TEST(Scheduler, NoWorkerAtAll) {
  Scene s = Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)});
  Mesh m = MakeMesh(s);
  FakeTransport t(m, 2);
  t.never_join_ = true;
  Solver solver(m, true);
  RunResult r = RunMaster(&m, Opts(), &solver, nullptr, &t, nullptr, nullptr);
  EXPECT_EQ(r.status, RunStatus::kNoWorkers);
  EXPECT_EQ(r.shots, 0);
}

// The master's own long steps (a division pass, a wave's picture) come
// after the work given out has gone to the workers: with the transport
// sending in Poll, that work used to wait until the step was over, and
// the workers with it.
// Two fake workers on the shadow scene at R 128, dividing, in waves: the
// runs of the two tests below.
struct DividingRun {
  static MeshOptions Patches() {
    MeshOptions mo;
    mo.patch_size = 0.25;
    return mo;
  }
  static RunOptions Options() {
    RunOptions o = Opts();
    o.resolution = 128;
    return o;
  }
  RunResult Run() { return RunMaster(&m, o, &solver, &sub, &t, nullptr, nullptr); }
  Mesh m = MakeMesh(ShadowScene(), Patches());
  Solver solver{m, true};
  Subdivider sub{&m, SubdivideOptions()};
  FakeTransport t{m, 2, 128};
  RunOptions o = Options();
};

TEST(Scheduler, WorkGoesOutBeforeAPassOrAPicture) {
  DividingRun run;
  FakeTransport& t = run.t;
  t.quiet_every_ = 5;  // 3 or 4: the fake never gave work just before a pass
  std::vector<long> unsent_at_picture;
  run.o.wave_end = [&](int) { unsent_at_picture.push_back(t.unsent_); };
  const RunResult r = run.Run();
  ASSERT_EQ(r.status, RunStatus::kConverged);
  ASSERT_GT(t.divides_, 0) << r.shots << " shots, " << r.passes << " passes, status " << int(r.status);
  ASSERT_GT(r.waves, 1);
  EXPECT_EQ(t.unsent_at_divide_, 0);
  EXPECT_EQ(unsent_at_picture, std::vector<long>(size_t(r.waves - 1), 0));
}

// Before a division pass each worker is given work for as long as the
// last pass took (50 ms here, its columns 1 ms each and answered one
// worker a Poll): the two held 10 or more between them at every pass
// after the first (4 to 8 without), and each was given 5 or more at some
// pass. Not with --queue.
TEST(Scheduler, WorkersHoldWorkForAPass) {
  for (const int queue : {0, 4}) {
    DividingRun run;
    FakeTransport& t = run.t;
    t.quiet_every_ = 5;
    run.o.queue = queue;
    std::vector<size_t> held;  // per pass: the assignments the workers held
    run.o.mesh_changes = [&] {
      size_t sum = 0;
      for (const auto& q : t.queue_) sum += q.size();
      held.push_back(sum);
      t.now_ += 0.05;
    };
    const RunResult r = run.Run();
    ASSERT_EQ(r.status, RunStatus::kConverged);
    ASSERT_GE(held.size(), 3u);
    // The first pass, not timed yet, is taken to be short on this mesh.
    const size_t later = *std::min_element(held.begin() + 1, held.end());
    if (queue == 0) {
      EXPECT_GE(later, 10u);
      for (const RunResult::Worker& w : r.workers) EXPECT_GE(w.reserve_max, 5);
    } else {
      EXPECT_LE(t.max_outstanding_, size_t(queue));
      for (const RunResult::Worker& w : r.workers) EXPECT_EQ(w.reserve_max, 0);
    }
  }
}

// A master that always has a column at hand still divides: a pass waits
// for the columns at hand to be shot for 10 shots at most. Before, a
// master as busy as 64 simulated workers kept it never divided.
TEST(Scheduler, AMasterBehindItsWorkersStillDivides) {
  DividingRun run;
  FakeTransport& t = run.t;
  t.answer_all_ = true;
  const RunResult r = run.Run();
  ASSERT_EQ(r.status, RunStatus::kConverged);
  EXPECT_GT(r.passes, 2);
  EXPECT_GT(t.divides_, 0);
}

// Idle accounting: a picture that takes the master a second leaves both
// workers idle for about that second (their queues hold a few
// milliseconds of work), counted as the picture's; pictures that take no
// time leave none.
TEST(Scheduler, IdleWorkersAreCountedByWhatTheMasterDid) {
  for (const double picture_s : {1.0, 0.0}) {
    DividingRun run;
    FakeTransport& t = run.t;
    t.quiet_every_ = 3;
    run.o.wave_end = [&](int) {
      t.now_ += picture_s;
      t.burst_ = true;
    };
    const RunResult r = run.Run();
    ASSERT_EQ(r.status, RunStatus::kConverged);
    ASSERT_GT(r.waves, 1);
    const double pictures = 2 * picture_s * (r.waves - 1);  // worker-seconds
    EXPECT_GE(r.idle.picture, 0.97 * pictures);
    EXPECT_LE(r.idle.picture, pictures);
    EXPECT_LT(r.idle.Sum() - r.idle.picture, 0.05)
        << "pass " << r.idle.pass << ", dry " << r.idle.dry << ", other " << r.idle.other
        << ", end " << r.idle.end;
  }
}

}  // namespace
