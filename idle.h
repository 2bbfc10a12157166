// The workers' idle time as the master reconstructs it (RunResult::Idle):
// the master's own steps (a wave's picture, a division pass) and the
// times it had nothing to select are kept as spans, and each gap a
// worker had between columns is counted by the spans it overlaps. It
// knows times only; not workers, queues, sockets or the mesh (the
// scheduler says when each worker was free and when its work went out).
#ifndef RADIOSITY_IDLE_H
#define RADIOSITY_IDLE_H

#include <deque>

#include "scheduler.h"

class IdleAccount {
 public:
  enum Cause { kPicture, kPass, kDry };
  // A step of the master's own from t0 to t1 (kPicture or kPass).
  void Busy(Cause cause, double t0, double t1);
  // Whether, as of `now`, a worker's queue stays under its low mark
  // because nothing is left to select.
  void Dry(bool dry, double now);
  // A worker idle from `from` to `to`. `oldest`: the earliest a live
  // worker has been free since (no gap starts before it any more).
  void Count(double from, double to, double oldest);
  // A worker idle from its last column to the end of the run.
  void End(double seconds) { idle_.end += seconds; }
  const RunResult::Idle& idle() const { return idle_; }

 private:
  struct Span {
    double t0, t1;
    Cause cause;
  };
  std::deque<Span> spans_;  // disjoint, in time order
  double dry_from_ = -1;    // nothing to select since; -1: not dry
  RunResult::Idle idle_;
};

// When a worker is done with a column: it took it up when it had it
// (`out`, when the work was sent) and was done with the one before
// (`free_at`), and was done after compute_s (CPU: more wall time when its
// core is shared), but after the Poll before the one that read it
// (`polled`, which read everything there was) and before `now`.
double DoneAt(double free_at, double out, double compute_s, double polled, double now);

#endif
