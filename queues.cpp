// Pacing the per-worker queues: Little's law for their depths, smoothed
// measurements of each worker's columns, deferrals for slow workers. It
// knows times, counts and the solver's order; not sockets, the mesh or
// the scheduler's queues themselves.
#include "queues.h"

#include <cmath>

#include "solver.h"

// Queue sizes from what Measure() keeps. depth covers the round trip:
// while one column travels back and the next assignment travels out, the
// worker computes the ones it holds, one per Service() time; on a link
// slower than the worker's CPU the link paces it, and more than the round
// trip's worth would only wait in its buffers, held from the other
// workers. Up to kMaxDepth: a link of 25 ms each way needs some 32 in flight
// to keep a worker of 1.6 ms a column busy (the paper's 10 kept it busy
// a third of the time). high adds enough prepared patches to refill
// that pipeline twice, more with many workers (the master then takes
// longer to come round to each).
void Pace::Size(int workers, int queue) {
  if (column_s > 0) {
    // Little's law: in flight = round trip / service time. The wire's
    // samples leave out a column that waited for a slow link (Measure),
    // so where the link paces the worker the trip counts its transfer
    // (the time between columns) besides. (1.25: a worker sharing a busy
    // core also takes longer in wall time than its CPU time says.)
    const bool link_paced = interval_s > 1.25 * column_s;
    const double trip = column_s + wire_s + (link_paced ? interval_s : 0);
    depth = std::clamp(int(std::ceil(trip / Service())), 2, kMaxDepth);
  }
  if (queue > 0) {
    high = queue;
    depth = std::min(depth, high);
  } else {
    high = std::clamp(2 * depth + workers / 32, 3, kMaxHigh);
  }
  low = std::max(1, (high + 1) / 2);
}

// A column's times, smoothed (a quarter each new one: a link that slows
// shows within a few columns, one late column on a loaded machine does
// not swing the queue). Its time on the wire is the round trip less its
// wait and compute time in the worker (sent + wait + compute: when it was
// ready, on the master's clock): its work's way out and its own way back.
// Only a column that was ready after the one before it arrived counts:
// one ready before then waited for that one to get through a link slower
// than the worker's CPU, a wait that grows with the queue (taken for a
// longer wire, it deepened the queue, which queued more there, and so on
// up to the bound: one sample of the round trip put 10 in flight to a
// worker behind pv -L 50k); what such a link takes is the time between
// its columns. That time is the worker's service time only when it held
// this one's work before the other arrived; otherwise it waited for work.
void Pace::Measure(double now, double sent_at, double wait_s, double compute_s, bool first,
                   double busy) {
  const double ready = sent_at + wait_s + compute_s;
  // (ready is early by the work's way out: about half the wire.)
  const bool queued = last_arrival > ready + wire_s / 2;
  const bool backlogged = last_arrival > sent_at;
  const double interval = now - last_arrival;
  last_arrival = now;
  // The first column also builds the hemicube's buffers: not a sample.
  if (first || compute_s <= 0) return;
  auto smooth = [](double* v, double x) { *v = *v > 0 ? *v + (x - *v) / 4 : x; };
  smooth(&column_s, compute_s);
  // A column seen after the master was busy for longer than the column
  // took (a division pass, a wave's picture) may have waited for it
  // unread: the master's time, not the link's (one 100 ms picture gave a
  // local worker 19 in flight).
  if (busy > compute_s) return;
  if (!queued) smooth(&wire_s, std::max(0.0, now - ready));
  if (backlogged) {
    smooth(&interval_s, interval);
  } else if (!queued && interval_s > 0) {
    // Not behind another column, it bounds the time between columns from
    // above: its own compute and round trip. Without that bound a time
    // between columns measured while it stalled (stopped for a while, a
    // link busy for a while) stayed, and kept the worker deferred for the
    // rest of the run, since a deferred worker is rarely backlogged.
    smooth(&interval_s, std::min(interval_s, compute_s + std::max(0.0, now - ready)));
  }
}

// A patch given to a worker comes back after its Turnaround(); the other
// workers shoot about Σ 1/Service() patches a second meanwhile. A worker
// that holds patches more than four times as long as the quickest is
// given the patch as many places down the order as the others shoot in
// the difference, not the one with the most power: that one they shoot
// sooner. Otherwise a worker behind a slow link took the lights at the
// start of every wave and the run waited for them (the room beside a
// worker behind 1 Mbit/s in the simulation: 5,860 shots to converge,
// 6.16 s, against 3,074 and 3.29 s alone; bench/throttle.sh). Equal
// workers defer nothing, as in the paper's cyclic fill. (Four: equal
// local workers on two busy cores differ by up to twice for a while.)
void Deferrals(const std::vector<const Pace*>& paces, long most, std::vector<long>* skip) {
  skip->assign(paces.size(), 0);
  double quickest = HUGE_VAL, rate = 0, steadiest = HUGE_VAL;
  for (const Pace* p : paces) {
    if (!p || p->Turnaround() <= 0) continue;
    quickest = std::min(quickest, p->Turnaround());
    steadiest = std::min(steadiest, p->Service());
    rate += 1 / p->Service();
  }
  // Slow is also slower to deliver columns, not only held longer: where
  // every worker waits on one shared link (100 simulated workers on
  // 10 Mbit/s) the deeper queues alone made turnarounds differ fourfold,
  // and patches taken back from them made a quarter of the columns stale.
  for (size_t w = 0; w < paces.size(); ++w) {
    const Pace* p = paces[w];
    if (!p || p->Turnaround() <= 4 * quickest || p->Service() <= 4 * steadiest) continue;
    const double others = rate - 1 / p->Service();
    (*skip)[w] = std::min(most, long(others * (p->Turnaround() - quickest)));
  }
}

int PatchBelow(Solver* solver, long skip, std::vector<int>* held) {
  held->clear();
  int p;
  while ((p = solver->Select()) >= 0 && long(held->size()) < skip) {
    solver->Take(p);
    held->push_back(p);
  }
  for (int q : *held) solver->Release(q);
  return p;
}
