// Pacing the per-worker queues (paper §4.1: "3-10 patches according to
// network size"): what the master measures of each worker's columns, the
// queue sizes it sets from that, and which workers are given patches from
// further down the shooting order. It knows times, counts and the
// solver's order; not sockets, the mesh, the protocol or which patches a
// worker holds (the scheduler keeps those and calls in here).
#ifndef RADIOSITY_QUEUES_H
#define RADIOSITY_QUEUES_H

#include <algorithm>
#include <vector>

class Solver;

constexpr int kMaxDepth = 32, kMaxHigh = 64;  // kMaxHigh: --queue's bound

// One worker's queue as its columns pace it. Times in seconds, smoothed
// (double: differences of clock readings); 0: not measured yet.
struct Pace {
  int depth = 2;          // sent and unanswered, at most
  int high = 3, low = 2;  // watermarks on what it owns and has not had shot
  double column_s = 0;    // compute time per column
  double wire_s = 0;      // a column's time on the wire (its work's way
                          // out, its own way back), not counting a wait
                          // behind its own earlier columns on a slow link
  double interval_s = 0;  // between two of its columns while it held more
  double last_arrival = -1;

  // Seconds between its columns as it runs: the slower of its CPU and its
  // link.
  double Service() const { return std::max(column_s, interval_s); }
  // How long a patch sent to it is held: behind a full pipeline, then on
  // the wire. 0: not measured yet.
  double Turnaround() const { return column_s > 0 ? wire_s + depth * Service() : 0; }
  // A patch sent to it at sent_at comes back after one sent `now` to a
  // worker whose Turnaround() is `quickest`. One overdue is taken to need
  // a Service() more: not back when due (behind pv -L, whose output comes
  // in bursts, a light came back 1.5 s late and the run waited: twice the
  // shots in 4 of 20 runs), it is no sooner for that.
  bool ReturnsAfter(double sent_at, double now, double quickest) const {
    const double due = sent_at + Turnaround() - now;
    return (due > 0 ? due : Service()) > quickest;
  }
  // A column arrived at `now` for work sent at `sent_at`, having waited
  // wait_s in the worker and taken compute_s there; `first`: its first
  // column; `busy`: how long the master was busy before the Poll that
  // read it.
  void Measure(double now, double sent_at, double wait_s, double compute_s, bool first,
               double busy);
  // depth, high and low from the measurements; `workers` in the run,
  // `queue`: --queue's high mark (0: automatic).
  void Size(int workers, int queue);
};

// Patches deferred per worker into *skip (one per entry of `paces`; null:
// not alive), at most `most` each: how far down the shooting order its
// next patch is taken from (0: the top).
void Deferrals(const std::vector<const Pace*>& paces, long most, std::vector<long>* skip);

// The patch `skip` places down `solver`'s shooting order, or -1 when
// fewer have power to shoot. *held: scratch.
int PatchBelow(Solver* solver, long skip, std::vector<int>* held);

#endif
