#include "scheduler.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <memory>
#include <thread>

#include "clock.h"
#include "groups.h"
#include "idle.h"
#include "inprocess.h"
#include "queues.h"
#include "quiet_thread.h"

namespace {

// Subdivision between two shots: a division pass if one is due after
// `shots_in_wave` shots of this wave; the ids it divided and ~the
// patches it split, in order, replace *edits (what workers must apply
// alike). Returns true when the
// wave is over.
bool Refine(Mesh* mesh, Solver* solver, Subdivider* subdivider, long shots_in_wave,
            std::vector<int32_t>* changed, std::vector<int32_t>* edits) {
  edits->clear();
  const bool due = subdivider->Due(shots_in_wave);
  if (!due && !subdivider->SplitDue(solver->DirectDone())) return false;
  const double t0 = ThreadCpuSeconds();
  if (due) {
    solver->TakeChanged(changed);
    // The adjacency (some 40 bytes an element) from the first pass on, not
    // from the start: with -j 0 the hemicube's cache is built at the first
    // shot, larger while it is built than after, and they need not meet.
    ConnectEdges(mesh);
    *edits = subdivider->Pass(*mesh, solver->radiosity(), solver->noise(), solver->Ambient(),
                              shots_in_wave, *changed);
    for (int32_t e : *edits) Divide(mesh, e);
    solver->Divided(*edits);
  }
  // Shooter division: a split of patch p travels as the edit ~p, after
  // the pass's divisions (doc/protocol.txt, divide).
  const std::vector<int32_t> splits =
      subdivider->SplitPass(*mesh, solver->direct(), solver->DirectDone(), solver->times_shot());
  ReserveSplits(mesh, splits);
  for (int32_t p : splits) {
    SplitPatch(mesh, p);
    solver->Split(p);
    edits->push_back(~p);
  }
  if (!splits.empty()) solver->SplitsDone();
  subdivider->CountTime(ThreadCpuSeconds() - t0);
  // Splits alone (subdivision over) do not start a wave.
  return due && subdivider->WaveOver();
}

// A worker as the scheduler keeps it (paper §4.1): the patches sent and
// not yet answered, and the queue prepared for it. A patch in either is
// owned by this worker and no other.
struct Slot {
  bool alive = false;
  struct Sent {
    proto::Assignment a;
    double at;
    double out = -1;  // when the transport sent it (its next Poll); -1: not yet
  };
  std::deque<Sent> sent;
  std::deque<int> prepared;
  Pace pace;               // its queue's sizes and what they are set from
  // Columns more, sent and owned, held while the master is about to stop
  // feeding it for a long step of its own (Scheduler::Reserve).
  int reserve = 0;
  long columns = 0;
  int waiting = 0;         // its columns received and not yet shot
  long retry_at = 0;       // shots: no patch far enough down for it until then
  RunResult::Worker report;
  double free_at = 0;     // when it was done with the columns read so far (idle accounting)
  size_t Owned() const { return sent.size() + prepared.size(); }
  // What the watermarks count: its columns waiting to be shot too, so
  // that a master slower than its workers stops feeding them. Otherwise
  // columns pile up, shot in arrival order (ever lower priority), and the
  // master, decoding more than it shoots, falls further behind: 15
  // simulated workers on the room at R 64 once received 1175 columns for
  // 500 shots at 108 us a shot instead of 30.
  size_t Queued() const { return Owned() + size_t(waiting); }
  bool Low() const { return Queued() < size_t(pace.low); }
  // Its high mark and depth with the reserve: what Fill fills it to and
  // Assign sends it.
  size_t High() const { return size_t(pace.high + reserve); }
  size_t Depth() const { return size_t(pace.depth + reserve); }
  // Fill is due: under its low mark, or under a reserve just given.
  bool Short() const { return Low() || (reserve > 0 && Queued() < High()); }
};

// The master's parts are timed with the monotonic clock: the thread's CPU
// clock is a system call (0.6 us here when idle, 8 us on a loaded virtual
// machine, where it was 6% of a master fed columns as fast as it takes
// them: bench/feed.sh), dearer than the work it would time. So it is read
// only at the end of a turn whose Poll could wait for workers: the wall
// time since the last reading that was not CPU time was spent blocked, in
// that Poll (or preempted), counted as waiting up to the Poll's wall time;
// the rest of the Poll is receiving. A Poll that could not wait is all
// receiving, and a master with columns to shoot never reads the clock.
class TurnTimer {
 public:
  TurnTimer() : wall_(MonotonicSeconds()), cpu_(ThreadCpuSeconds()) {}
  // Several Polls and Sends may make one turn (work sent before a pass or
  // a picture): their times add up, and the turn could wait if any could.
  void Polled(double seconds, bool could_wait) {
    poll_s_ += seconds;
    could_wait_ |= could_wait;
  }
  void EndTurn(RunResult* r) {
    if (!could_wait_) {
      r->receive_s += poll_s_;
      poll_s_ = 0;
      return;
    }
    const double wall = MonotonicSeconds(), cpu = ThreadCpuSeconds();
    const double blocked = std::clamp((wall - wall_) - (cpu - cpu_), 0.0, poll_s_);
    r->wait_s += blocked;
    r->receive_s += poll_s_ - blocked;
    wall_ = wall;
    cpu_ = cpu;
    poll_s_ = 0;
    could_wait_ = false;
  }

 private:
  double wall_, cpu_, poll_s_ = 0;
  bool could_wait_ = false;
};

class Scheduler {
 public:
  Scheduler(Mesh* mesh, const RunOptions& opts, Solver* solver, Subdivider* sub, Transport* t,
            const std::function<void(const Sample&)>& sample,
            const std::function<void(const std::string&, bool)>& note)
      : mesh_(*mesh), mutable_mesh_(mesh), opts_(opts), solver_(solver), sub_(sub), t_(t),
        first_(t), sample_(sample), note_(note) {
    if (const RunState* r = opts.resume) {
      wave_ = r->wave;
      wave_start_ = r->wave_start;
      best_ = r->best;
      best_at_ = r->best_at;
      before_ = r->seconds;
      r_.columns = r->columns;
      pending_.assign(r->pending.begin(), r->pending.end());
    }
    // The dividing factor discounts the hemicube's noise (subdivide.h).
    if (sub) solver->TrackNoise(opts.resolution);
    // Shooter division measures the emitters' first light (split.cpp).
    if (sub && sub->splitting()) solver->TrackDirect();
  }
  ~Scheduler() { JoinAhead(); }
  RunResult Run();

 private:
  // The steps of Run(), in the order of one turn of its loop.
  void Begin();
  void EndConvergedWave();
  bool Stop();
  void Receive();
  void SendNow();
  void MarkSent();
  void Transmit();
  void Poll(double timeout);
  bool FallBack();
  void Distribute();
  void Fill();
  void Assign();
  bool Exhausted();
  void ShootNext();
  void Subdivide();
  void Reserve(bool on);
  void StartAhead();
  void JoinAhead();
  void CheckpointIfDue();
  RunResult Finish();

  double Elapsed() { return before_ + t_->Now() - base_; }
  void Note(const std::string& line, bool warning) {
    if (note_) note_(line, warning);
  }
  bool Alive() const {
    for (const Slot& s : slots_)
      if (s.alive) return true;
    return false;
  }
  bool Pipelined() const { return !t_->Caps().computes_in_poll; }
  void Sizes(Slot* s);
  void Deferrals();
  void Reclaim();
  void Handle(WorkerEvent& ev);
  void Release(Slot* s);
  // Its RunResult::Worker into r_ (a worker that joined, once).
  void Report(Slot* s) {
    if (s->report.name.empty()) return;
    s->report.depth = s->pace.depth;
    s->report.column_s = s->pace.column_s;
    s->report.wire_s = s->pace.wire_s;
    s->report.interval_s = s->pace.interval_s;
    r_.workers.push_back(std::move(s->report));
    s->report.name.clear();
  }
  void NextWave();
  int NextPatch();
  RunState State();
  void Checkpoint() {
    if (opts_.checkpoint) opts_.checkpoint(State());
    last_checkpoint_ = t_->Now();
  }
  void Emit() {
    if (!sample_) return;
    int alive = 0;
    if (Pipelined())
      for (const Slot& s : slots_) alive += s.alive;
    sample_({Elapsed(), solver_->shots(), wave_, mesh_.LeafCount(), unshot_, alive, last_patch_, last_k_});
  }

  const Mesh& mesh_;
  Mesh* mutable_mesh_;  // changed only by Subdivide()
  const RunOptions& opts_;
  Solver* solver_;
  Subdivider* sub_;     // null: no subdivision, one wave
  // The first pass's work made ahead (StartAhead): until joined, the
  // mesh's adjacency and the subdivider's closeness search are its.
  std::thread ahead_;
  bool ahead_tried_ = false;
  double ahead_s_ = 0;  // its CPU seconds, written by it, read after the join
  Transport* t_;
  Transport* first_;    // the transport given (t_ may become the fallback)
  std::unique_ptr<Transport> fallback_;
  const std::function<void(const Sample&)>& sample_;
  const std::function<void(const std::string&, bool)>& note_;
  std::vector<Slot> slots_;
  struct Ready {
    proto::Column column;
    int from;  // the slot it came from (-1: that slot is gone)
  };
  std::deque<Ready> ready_;  // columns received, to be shot in order
  std::vector<WorkerEvent> events_;   // of the last Poll
  std::vector<long> skip_;            // per slot, Deferrals()'
  std::vector<const Pace*> paces_;    // Deferrals()' scratch
  std::vector<int> held_;             // PatchBelow's scratch
  TurnTimer timer_;
  long log_every_ = 1;                // shots between samples
  double unshot_ = 0;                 // the solver's UnshotFraction() as of the last step
  double base_ = 0, before_ = 0;      // clock: Elapsed() survives a fallback
  double best_ = HUGE_VAL;            // stall detection, per wave
  long best_at_ = 0;
  int wave_ = 1;
  long wave_start_ = 0;               // shots before this wave
  std::vector<int32_t> edits_;
  std::vector<int32_t> changed_;      // Refine's scratch
  std::deque<int> pending_;           // RunState::pending of a resumed run
  double last_checkpoint_ = 0;        // on t_'s clock
  int last_patch_ = -1, last_k_ = 0;  // the last shot (Sample)
  double looked_ = 0;                 // t_'s clock when the last Poll returned
  double busy_ = 0;                   // and from then to the next Poll
  RunResult r_;

  IdleAccount idle_;                  // RunResult::idle
  std::vector<int> unsent_;           // slots given work since the last Poll
  double polled_ = 0;                 // when the Poll before the last returned (Handle's bound)
  double pass_s_ = -1;                // the last division pass's time (t_'s clock); -1: none yet
  long due_at_ = -1;                  // shots when the next pass fell due; -1: not yet
  void CountIdle(double from, double to);
};

// A worker idle from `from` to `to`; no gap starts before the oldest
// free_at of a live worker.
void Scheduler::CountIdle(double from, double to) {
  if (!Pipelined()) return;
  double oldest = from;
  for (const Slot& s : slots_)
    if (s.alive) oldest = std::min(oldest, s.free_at);
  idle_.Count(from, to, oldest);
}

// The next patch to hand out: first those a resumed run's checkpoint had
// selected and not shot, then the one with the most power to shoot.
int Scheduler::NextPatch() {
  while (!pending_.empty()) {
    const int p = pending_.front();
    pending_.pop_front();
    if (p >= 0 && size_t(p) < mesh_.patches.size() && !solver_->Taken(p)) return p;
  }
  return solver_->Select();
}

RunState Scheduler::State() {
  JoinAhead();  // the caller reads the subdivider's state
  RunState s;
  s.wave = wave_;
  s.wave_start = wave_start_;
  s.best = best_;
  s.best_at = best_at_;
  s.seconds = Elapsed();
  s.columns = r_.columns;
  // Columns waiting are shot first; then the workers' patches, sent before
  // prepared, taken in turns as their columns would come back.
  for (const Ready& r : ready_) s.pending.push_back(r.column.patch);
  for (size_t i = 0;; ++i) {
    bool any = false;
    for (const Slot& w : slots_) {
      if (!w.alive || i >= w.Owned()) continue;
      any = true;
      s.pending.push_back(i < w.sent.size() ? w.sent[i].a.patch : w.prepared[i - w.sent.size()]);
    }
    if (!any) break;
  }
  for (int p : pending_) s.pending.push_back(p);
  return s;
}

// Queue sizes (Pace::Size) and their range in its report.
void Scheduler::Sizes(Slot* s) {
  Pace& q = s->pace;
  if (!Pipelined())  // select right before computing: sequential order
    q.depth = q.high = q.low = 1;
  else
    q.Size(t_->Workers(), opts_.queue);
  RunResult::Worker& r = s->report;
  r.depth_min = r.depth_min ? std::min(r.depth_min, q.depth) : q.depth;
  r.depth_max = std::max(r.depth_max, q.depth);
  r.high_max = std::max(r.high_max, q.high);
}

// Patches deferred per worker (skip_, queues.cpp): a worker that holds
// patches far longer than the quickest is given the patch some places
// down the order.
void Scheduler::Deferrals() {
  paces_.clear();
  for (const Slot& s : slots_) paces_.push_back(s.alive ? &s.pace : nullptr);
  ::Deferrals(paces_, long(mesh_.patches.size()), &skip_);
}

// Deferral keeps the lights from a slow worker, not the light that its
// patches gather while they wait there: near the end of a wave the run
// cannot converge without them. A patch sent to a deferred worker that
// now has more power to shoot than any patch not owned, and that the
// quickest worker would return before it (by their Turnaround()), goes
// to the quickest worker with the shortest queue, first in its queue;
// the column the slow worker sends for it is stale. (Without the second
// condition nearly every deferred patch came back this way, when the
// others had shot those above it: 1,735 of 1,784 behind pv -L 200k.) (The room beside a worker
// behind 0.2 Mbit/s in the simulation, deferred: 5,910 shots to converge,
// 7.33 s, against 3,074 and 3.83 s alone; taken back too, 2,907 and
// 3.51 s against 3.72 s alone: bench/throttle.sh.)
void Scheduler::Reclaim() {
  Slot* to = nullptr;
  double quickest = HUGE_VAL;
  for (size_t w = 0; w < slots_.size(); ++w) {
    Slot& s = slots_[w];
    if (!s.alive || skip_[w] != 0 || s.pace.Turnaround() <= 0) continue;
    quickest = std::min(quickest, s.pace.Turnaround());
    if (!to || s.Queued() < to->Queued()) to = &s;
  }
  if (!to) return;
  const double now = t_->Now();
  double top = -1;  // selected at the first deferred worker: a selection a turn was a tenth
                    // of the master's work with 100 simulated workers and none deferred
  for (size_t w = 0; w < slots_.size(); ++w) {
    Slot& s = slots_[w];
    if (!s.alive || skip_[w] == 0) continue;
    if (top < 0) {
      const int best = solver_->Select();
      top = best >= 0 ? solver_->PowerToShoot(best) : 0;
    }
    for (auto it = s.sent.begin(); it != s.sent.end();) {
      if (!s.pace.ReturnsAfter(it->at, now, quickest) ||
          solver_->PowerToShoot(it->a.patch) <= top) {
        ++it;
        continue;
      }
      to->prepared.push_front(it->a.patch);
      ++s.report.reclaimed;
      it = s.sent.erase(it);
    }
  }
}

void Scheduler::Release(Slot* s) {
  for (const Slot::Sent& x : s->sent) solver_->Release(x.a.patch);
  for (int p : s->prepared) solver_->Release(p);
  s->sent.clear();
  s->prepared.clear();
}

void Scheduler::Handle(WorkerEvent& ev) {
  if (ev.worker >= int(slots_.size())) slots_.resize(ev.worker + 1);
  Slot& s = slots_[ev.worker];
  switch (ev.kind) {
    case WorkerEvent::kJoined:
      s.alive = true;
      s.free_at = t_->Now();
      ++r_.joined;
      s.report.name = t_->Name(ev.worker);
      Sizes(&s);
      if (Pipelined()) Note(t_->Name(ev.worker) + ": joined", false);
      return;
    case WorkerEvent::kLost: {
      if (!s.alive) {  // never joined: nothing of it to give back
        Note(t_->Name(ev.worker) + ": " + ev.why, true);
        return;
      }
      s.alive = false;
      ++r_.lost;
      const size_t n = s.Owned();
      Release(&s);
      Note(t_->Name(ev.worker) + ": lost (" + ev.why + "); its " + std::to_string(n) +
           " patches go to the others", true);
      return;
    }
    case WorkerEvent::kColumn: {
      const proto::Column& c = ev.column;
      auto it = std::find_if(s.sent.begin(), s.sent.end(), [&](const Slot::Sent& x) {
        return x.a.patch == c.patch && x.a.k == c.k;
      });
      // Only an outstanding assignment is shot: never the same patch twice.
      if (!s.alive || it == s.sent.end()) {
        ++r_.stale;
        r_.stale_s += c.compute_s;
        return;
      }
      if (Pipelined()) {
        s.pace.Measure(t_->Now(), it->at, c.wait_s, c.compute_s, s.columns == 0, busy_);
        Sizes(&s);
      }
      CountIdle(s.free_at, it->out);
      s.free_at = DoneAt(s.free_at, it->out, c.compute_s, polled_, t_->Now());
      ++s.columns;
      ++s.report.columns;
      ++s.waiting;
      s.sent.erase(it);
      r_.worker_s += c.compute_s;
      ready_.push_back({std::move(ev.column), ev.worker});
      return;
    }
  }
}

// Cyclic fill (paper §4.1): when any queue is under its low mark, go round
// the workers not yet at their high mark, one patch each per turn, always
// the patch with the most power to shoot, so that the first lights of a
// run go to different workers. Then assign what each pipeline has room for.
void Scheduler::Distribute() {
  const double t0 = MonotonicSeconds();
  Fill();
  Assign();
  // A queue still under its low mark: nothing was left to select.
  bool dry = false;
  for (const Slot& s : slots_) dry |= s.alive && s.Low();
  idle_.Dry(dry, t_->Now());
  r_.distribute_s += MonotonicSeconds() - t0;
}

void Scheduler::Fill() {
  const long shots = solver_->shots();
  bool low = false;
  for (const Slot& s : slots_)
    low |= s.alive && s.Short() && shots >= s.retry_at;
  if (!low) return;
  Deferrals();
  Reclaim();
  for (bool more = true; more;) {
    more = false;
    for (size_t w = 0; w < slots_.size(); ++w) {
      Slot& s = slots_[w];
      if (!s.alive || s.Queued() >= s.High() || shots < s.retry_at) continue;
      if (skip_[w] > 0 && pending_.empty()) {
        int p = PatchBelow(solver_, skip_[w], &held_);
        // Fewer have power than it should skip. With nothing of its own it
        // takes the last of them, the others the top: without columns its
        // pace was never measured again, and a worker stalled once (two
        // seconds stopped, a link busy for a while) stood idle to the end
        // of the run (Sim.AWorkerStalledForAWhileGetsWorkAgain: 54 of
        // 4,002 columns). One truly slow holds that one patch, and gives
        // it back should it come to matter (Reclaim).
        if (p < 0 && s.Owned() == 0 && held_.size() >= 2) p = held_.back();
        if (p < 0) {
          // Not that many have power (the start of a wave): nothing for it
          // until the others have shot some; tried again in a while, so
          // that the search does not cost the master a pass a shot.
          s.retry_at = shots + 1 + skip_[w] / 4;
          continue;
        }
        solver_->Take(p);
        s.prepared.push_back(p);
        ++s.report.deferred;
        more = true;
        continue;
      }
      const int p = NextPatch();
      if (p < 0) break;  // nothing left with power to shoot: send what is prepared
      solver_->Take(p);  // owned by this worker until shot or lost
      s.prepared.push_back(p);
      more = true;
    }
  }
  // A queue still under its low mark means nothing is left to select:
  // every patch with power is owned. Then it takes over patches prepared
  // and not yet sent for another worker, the last one of the longest
  // such queue while that worker owns more than it does. Otherwise, at
  // the start of a wave (only the lights have power), a stopped or slow
  // worker whose queue took the lights held up the whole run until its
  // columns came back or it was dropped (tests/parallel.sh, SIGSTOP).
  // A worker whose patches are deferred takes over none: the others
  // shoot them sooner.
  for (size_t w = 0; w < slots_.size(); ++w) {
    Slot& s = slots_[w];
    while (s.alive && s.Low() && skip_[w] == 0 && shots >= s.retry_at) {
      Slot* from = nullptr;
      for (Slot& t : slots_)
        if (&t != &s && t.alive && !t.prepared.empty() && t.Queued() > s.Queued() + 1 &&
            (!from || t.prepared.size() > from->prepared.size()))
          from = &t;
      if (!from) break;
      s.prepared.push_back(from->prepared.back());
      from->prepared.pop_back();
    }
  }
}

// Assigns what each pipeline has room for (the transport sends it at the
// next Poll or Transmit).
void Scheduler::Assign() {
  for (size_t w = 0; w < slots_.size(); ++w) {
    Slot& s = slots_[w];
    while (s.alive && !s.prepared.empty() && s.sent.size() < s.Depth()) {
      const int p = s.prepared.front();
      s.prepared.pop_front();
      // A group goes with its shooter's every assignment, a resent one
      // too (a lost worker's patches come back through `prepared`).
      proto::Assignment a{p, solver_->TimesShot(p)};
      if (const PatchGroup* g = GroupOf(mesh_, p)) a.group = *g;
      s.sent.push_back({a, t_->Now()});
      t_->Assign(int(w), a);
      if (unsent_.empty() || unsent_.back() != int(w)) unsent_.push_back(int(w));
    }
  }
}

bool Scheduler::Stop() {
  const double unshot = unshot_;
  const long shots = solver_->shots();
  if (solver_->Dark()) {
    r_.status = RunStatus::kConverged;
    r_.why = "the scene emits no light";
  } else if (unshot < opts_.epsilon) {
    r_.status = RunStatus::kConverged;
  } else if (opts_.stop && *opts_.stop) {
    r_.status = RunStatus::kStopped;
  } else if (opts_.max_shots > 0 && shots >= opts_.max_shots) {
    r_.status = RunStatus::kLimit;
    r_.why = "shot limit reached";
  } else if (opts_.max_seconds > 0 && Elapsed() >= opts_.max_seconds) {
    r_.status = RunStatus::kLimit;
    r_.why = "time limit reached";
  } else if (!std::isfinite(unshot) || unshot > 1e12) {
    r_.status = RunStatus::kNotConverged;
    r_.why = "unshot energy grows without bound (does the scene reflect all light?)";
  } else {
    // Not converging: the unshot fraction has not fallen by 1% for this
    // many shots (20 sweeps over the patches). Progress that slow (ρ → 1
    // without overshooting) or none at all (ρ = 1) would not finish in
    // useful time.
    const long stall = std::max(1000L, 20 * long(mesh_.patches.size()));
    if (unshot < best_ * 0.99) {
      best_ = unshot;
      best_at_ = shots;
      return false;
    }
    if (shots - best_at_ <= stall) return false;
    r_.status = RunStatus::kNotConverged;
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "unshot energy still %.3g of emitted and not falling for %ld shots "
                  "(reflectance too close to 1?)",
                  unshot, stall);
    r_.why = buf;
  }
  return true;
}

// A division pass (paper §4.3) when one is due, once every worker's
// queue holds at least its low mark and no column waits to be shot (or
// 10 shots after it fell due), so that the workers stay busy while the
// master divides. The edits go to every worker in the order they were
// made.
void Scheduler::Subdivide() {
  if (!sub_) return;
  StartAhead();
  const long shots_in_wave = solver_->shots() - wave_start_;
  if (!sub_->Due(shots_in_wave) && !sub_->SplitDue(solver_->DirectDone())) return;
  // It waits for the columns at hand to be shot and for every queue to
  // hold its low mark, but not for more than kPassWaitShots shots: a
  // master as busy as 64 simulated workers keep it (boxes3800) always had
  // a column at hand and never divided. Columns at hand then are shot
  // after the pass as columns in flight are. Such a master is what the
  // workers wait for, not the pass: it gives them no more for it (columns
  // computed before a pass are shot the slower way, Reserve).
  constexpr long kPassWaitShots = 10;
  if (due_at_ < 0) due_at_ = solver_->shots();
  const bool overdue = solver_->shots() - due_at_ >= kPassWaitShots;
  if (!ready_.empty() && !overdue) return;
  if (ready_.empty()) Reserve(true);
  for (const Slot& s : slots_)
    if (s.alive && Pipelined() && s.Low() && !overdue) return;
  SendNow();
  const double start = t_->Now();
  if (opts_.mesh_changes) {
    opts_.mesh_changes();
    idle_.Busy(IdleAccount::kPicture, start, t_->Now());
  }
  JoinAhead();
  const double t0 = MonotonicSeconds(), now = t_->Now();
  const long passes = sub_->passes();
  const bool over =
      Refine(mutable_mesh_, solver_, sub_, shots_in_wave, &changed_, &edits_);
  if (!edits_.empty()) t_->Divide(edits_);
  r_.subdivide_s += MonotonicSeconds() - t0;
  if (sub_->passes() != passes || !edits_.empty()) idle_.Busy(IdleAccount::kPass, now, t_->Now());
  pass_s_ = t_->Now() - start;
  due_at_ = -1;
  Reserve(false);
  if (over) NextWave();
  unshot_ = solver_->UnshotFraction();
}

// What the first pass would do first that depends on the mesh as built
// alone: its edges' adjacency (ConnectEdges) and the split pass's
// closeness search of every patch (Subdivider::Prepare), on a thread of
// their own beside the first wave, where the master mostly waits for
// columns. On the room of 40,000 boxes (10^6 elements) they took 0.27 and
// 0.44 s of a first pass that every worker waited out, 10 to 15 shots in.
// Started as the run begins, while workers still mesh the scene; with
// -j 0 after the first shot, which builds the hemicube's cache, larger
// while it is built: the adjacency (some 45 bytes an element) need not
// meet it. The same work as the pass would do: the same answer.
void Scheduler::StartAhead() {
  if (ahead_tried_ || (!Pipelined() && solver_->shots() == 0)) return;
  ahead_tried_ = true;
  if (mesh_.connected) return;  // resumed, or divided already
  ahead_ = QuietThread([this] {
    const double t0 = ThreadCpuSeconds();
    ConnectEdges(mutable_mesh_);
    sub_->Prepare(mesh_);
    ahead_s_ = ThreadCpuSeconds() - t0;
  });
}

// Before the mesh changes or the subdivider's state is read: counted as
// the passes' time (Subdivider::seconds), which it is.
void Scheduler::JoinAhead() {
  if (!ahead_.joinable()) return;
  ahead_.join();
  sub_->CountTime(ahead_s_);
}

// Before a division pass each worker is given work for the pass's length
// besides its queue: a queue sized for the round trip (2 to 6 columns of
// 15 to 60 ms on boxes20000) ran dry in passes of 30 to 240 ms, and the
// workers waited out most of each (0.9 worker-seconds in 300 shots). The
// length is the last pass's (the wait for a wave's picture to be drawn
// with it; a wave's end, once a wave, not), or until one has been timed,
// kFirstPassPerElement a leaf. The columns come back after the pass,
// computed on the mesh before it, and are shot as columns in flight are
// (Solver::Shoot: a divided element's leaves gain alike). Not with
// --queue: the user's high mark is the bound.
void Scheduler::Reserve(bool on) {
  // boxes20000's first pass (with the shooter splits' first search):
  // 0.24 s at 529,260 elements.
  constexpr double kFirstPassPerElement = 0.45e-6;
  if (!Pipelined() || opts_.queue > 0) return;
  const double pass = pass_s_ >= 0 ? pass_s_ : kFirstPassPerElement * double(mesh_.LeafCount());
  bool more = false;
  for (Slot& s : slots_) {
    const double service = s.pace.Service();
    const int want = on && s.alive && service > 0
                         ? std::min(kMaxDepth, int(std::ceil(pass / service)))
                         : 0;
    more |= want > s.reserve;
    s.reserve = want;
    if (want > s.report.reserve_max) s.report.reserve_max = want;
  }
  if (more) Distribute();
}

// The end of a wave (paper §4.4): a picture of it, then the radiosity is
// thrown away and shooting starts again from the emitters on the finer
// mesh. Columns in flight are still shot: they are columns of the same
// geometry. Patches prepared and not yet sent go back: they were chosen
// by the old wave's powers and now have next to none, and while they
// filled a queue the new wave's lights went to whichever worker had room,
// a stopped one too, which then held all the power until it was dropped
// (tests/parallel.sh's SIGSTOP case, about 1 run in 15).
void Scheduler::NextWave() {
  solver_->EndWave();
  if (opts_.wave_end) {
    SendNow();
    const double t0 = t_->Now();
    opts_.wave_end(wave_);
    idle_.Busy(IdleAccount::kPicture, t0, t_->Now());
  }
  solver_->NewWave();
  for (Slot& s : slots_) {
    for (int p : s.prepared) solver_->Release(p);
    s.prepared.clear();
  }
  sub_->StartWave(mesh_);
  ++wave_;
  wave_start_ = best_at_ = solver_->shots();
  due_at_ = -1;
  Reserve(false);  // a new wave's lights are dealt out to the queues as they are
  best_ = HUGE_VAL;
  unshot_ = solver_->UnshotFraction();
  Emit();
}

void Scheduler::Begin() {
  timer_ = TurnTimer();
  base_ = looked_ = t_->Now();
  log_every_ =
      opts_.log_every > 0 ? opts_.log_every : std::max(1L, mesh_.BuiltPatches() / 100);
  unshot_ = solver_->UnshotFraction();
  if (!opts_.resume) Emit();
  last_checkpoint_ = t_->Now();
  if (sub_) StartAhead();
}

// A wave whose light is shot but whose subdivision is not done goes on as
// a new wave on the finer mesh.
void Scheduler::EndConvergedWave() {
  if (unshot_ < opts_.epsilon && sub_ && sub_->WaveOver(true)) NextWave();
}

// Waits for workers only when there is nothing to shoot. With more than
// the next column to shoot at hand, the workers are heard at most every
// kHearEvery seconds and only sent their work in between: a master as busy
// as a cluster makes it (bench/feed.sh) spent a tenth of its time in
// poll(2) finding nothing new, every column. What arrives meanwhile is
// read at the next Poll, in one read per worker; the column shot next
// is already here.
void Scheduler::Receive() {
  constexpr double kHearEvery = 100e-6;
  if (ready_.size() >= 2 && t_->Now() - looked_ < kHearEvery)
    Transmit();
  else
    Poll(ready_.empty() ? 0.25 : 0.0);
}

// Before a long step of the master's own (a division pass, a wave's
// picture): the work Distribute gave out goes to the workers now, not at
// the next turn's Poll after the step, when they may long have run dry.
void Scheduler::SendNow() {
  if (Pipelined() && !unsent_.empty()) Transmit();
}

// What Distribute gave since the last Poll or Transmit goes out in this one.
void Scheduler::MarkSent() {
  const double out = t_->Now();
  for (int w : unsent_) {
    std::deque<Slot::Sent>& sent = slots_[size_t(w)].sent;
    for (auto it = sent.rbegin(); it != sent.rend() && it->out < 0; ++it) it->out = out;
  }
  unsent_.clear();
}

// Sends the work given out, reading nothing (a worker lost in sending is
// the one event).
void Scheduler::Transmit() {
  const double t0 = MonotonicSeconds();
  events_.clear();
  MarkSent();
  t_->Send(&events_);
  timer_.Polled(MonotonicSeconds() - t0, false);
  for (WorkerEvent& ev : events_) Handle(ev);
}

void Scheduler::Poll(double timeout) {
  const double t0 = MonotonicSeconds();
  events_.clear();
  MarkSent();
  busy_ = t_->Now() - looked_;
  t_->Poll(timeout, &events_);
  polled_ = looked_;
  looked_ = t_->Now();
  timer_.Polled(MonotonicSeconds() - t0, timeout > 0);
  for (WorkerEvent& ev : events_) Handle(ev);
}

// No worker is alive or on its way and no column waits: the fallback
// computes the columns from here on, on a clock of its own that Elapsed()
// continues. False when the run ends instead.
bool Scheduler::FallBack() {
  if (r_.joined == 0 || !opts_.fallback) {
    r_.status = RunStatus::kNoWorkers;
    r_.why = r_.joined == 0 ? "no worker could be started" : "every worker was lost";
    return false;
  }
  Note("no workers left: the master computes the form factors itself", true);
  r_.fell_back = true;
  before_ = Elapsed();
  fallback_ = opts_.fallback();
  t_ = fallback_.get();
  base_ = last_checkpoint_ = t_->Now();
  for (Slot& s : slots_) Report(&s);
  slots_.clear();
  unsent_.clear();
  for (Ready& r : ready_) r.from = -1;
  return true;
}

// Nothing waits to be shot: true (the run has converged) when nothing is
// owned either and workers are alive, so nothing has power left to shoot.
bool Scheduler::Exhausted() {
  bool owned = false;
  for (const Slot& s : slots_) owned |= s.Owned() > 0;
  if (owned || !Alive()) return false;
  r_.status = RunStatus::kConverged;
  return true;
}

// Shoots the oldest column received, and samples the run every log_every_
// shots.
void Scheduler::ShootNext() {
  const double t0 = MonotonicSeconds();
  proto::Column c = std::move(ready_.front().column);
  Slot* from = ready_.front().from >= 0 ? &slots_[size_t(ready_.front().from)] : nullptr;
  ready_.pop_front();
  if (from) --from->waiting;
  solver_->Shoot(c.patch, c.ff);
  solver_->Release(c.patch);
  last_patch_ = c.patch;
  last_k_ = c.k;
  t_->Recycle(std::move(c.ff));
  ++r_.columns;
  unshot_ = solver_->UnshotFraction();
  r_.shoot_s += MonotonicSeconds() - t0;
  // The shot made room in its worker's queue: refill it before Poll
  // blocks, as the arrival of the column no longer did.
  if (from && from->alive && from->Low()) Distribute();
  if (solver_->shots() % log_every_ == 0) Emit();
}

void Scheduler::CheckpointIfDue() {
  if (opts_.checkpoint_every > 0 && t_->Now() - last_checkpoint_ >= opts_.checkpoint_every)
    Checkpoint();
}

RunResult Scheduler::Finish() {
  JoinAhead();
  // A worker with nothing left to compute idles to the end.
  const double now = t_->Now();
  for (const Slot& s : slots_)
    if (s.alive && Pipelined() && s.sent.empty()) idle_.End(std::max(0.0, now - s.free_at));
  r_.idle = idle_.idle();
  Checkpoint();  // before the last sample, which a resumed run then writes
  if (solver_->shots() % log_every_ != 0) Emit();  // the last state, once
  r_.shots = solver_->shots();
  r_.seconds = Elapsed();
  r_.unshot = unshot_;
  r_.bytes_sent = first_->BytesSent();
  r_.bytes_received = first_->BytesReceived();
  r_.waves = wave_;
  if (sub_) r_.passes = sub_->passes();
  for (Slot& s : slots_) Report(&s);
  return r_;
}

RunResult Scheduler::Run() {
  Begin();
  for (;;) {
    EndConvergedWave();
    timer_.EndTurn(&r_);
    if (Stop()) break;
    Receive();
    if (!Alive() && t_->Starting() == 0 && ready_.empty()) {
      if (!FallBack()) break;
      continue;
    }
    // Sending work comes before shooting, so that workers never starve.
    Distribute();
    if (ready_.empty()) {
      if (Exhausted()) break;
      continue;
    }
    ShootNext();
    Subdivide();
    CheckpointIfDue();
  }
  return Finish();
}

}  // namespace

RunResult RunMaster(Mesh* mesh, const RunOptions& opts, Solver* solver, Subdivider* subdivider,
                    Transport* transport, const std::function<void(const Sample&)>& sample,
                    const std::function<void(const std::string&, bool)>& note) {
  Scheduler s(mesh, opts, solver, subdivider, transport, sample, note);
  return s.Run();
}

RunResult RunSequential(Mesh* mesh, const RunOptions& opts, Solver* solver,
                        Subdivider* subdivider,
                        const std::function<void(const Sample&)>& sample) {
  InProcessTransport t(*mesh, opts.resolution, opts.rotate, opts.seed);
  return RunMaster(mesh, opts, solver, subdivider, &t, sample, nullptr);
}
