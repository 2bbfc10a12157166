// The master's loop (paper §4) over a Transport: per-worker queues with
// watermarks, the cyclic fill, shooting the columns that come back,
// subdivision between shots, waves, checkpoints, lost workers and the
// fallback, and the rules that stop a run. The mathematics is the
// Solver's (solver.h).
#ifndef RADIOSITY_SCHEDULER_H
#define RADIOSITY_SCHEDULER_H

#include <cmath>
#include <csignal>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "mesh.h"
#include "solver.h"
#include "subdivide.h"
#include "transport.h"

// Where a run stands besides the solver and the subdivider: the rest of
// what a checkpoint keeps, so that RunMaster can go on from there.
struct RunState {
  int wave = 1;
  long wave_start = 0;       // shots before this wave
  double best = HUGE_VAL;    // stall detection: lowest unshot fraction of
  long best_at = 0;          // the wave, and the shot it was reached at
  double seconds = 0;        // run time so far
  long columns = 0;          // columns shot
  // Patches selected and not yet shot (owned by workers, columns waiting),
  // in about the order they would have been shot: handed out first on
  // resume, so that a sequential run goes on in exactly its own order.
  std::vector<int32_t> pending;
};

struct RunOptions {
  bool overshoot = true;
  int resolution = 256;     // hemicube pixels across
  double epsilon = 1e-3;    // stop when UnshotFraction() < epsilon
  long max_shots = 0;       // 0: no limit
  double max_seconds = 0;   // 0: no limit
  bool rotate = true;       // turn the hemicube per shot against aliasing
  unsigned seed = 1;
  long log_every = 0;       // shots between samples; 0: patches / 100
  int queue = 0;            // patches owned per worker (high mark); 0: automatic
  const volatile std::sig_atomic_t* stop = nullptr;  // set by SIGINT/SIGTERM
  // Called at the end of every wave but the last (whose end is the run's),
  // before its radiosity is thrown away. May be empty.
  std::function<void(int wave)> wave_end;
  // Called before a division pass changes the mesh: what still reads it
  // from a wave_end (a picture drawn on another thread) is done when this
  // returns. May be empty.
  std::function<void()> mesh_changes;
  // Checkpoints: `checkpoint` (may be empty) is called every
  // `checkpoint_every` seconds between shots (0: never) and once when the
  // run stops, before the last log sample, with where the run stands.
  double checkpoint_every = 0;
  std::function<void(const RunState&)> checkpoint;
  // Go on from a checkpoint's state (the solver, subdivider and mesh
  // already restored): no first log sample, the clock and waves go on.
  const RunState* resume = nullptr;
  // What computes the columns when every worker is lost (the master's own
  // process, made by the caller); empty: the run ends as kNoWorkers.
  std::function<std::unique_ptr<Transport>()> fallback;
};

struct Sample {
  double seconds;
  long shots;
  int wave;
  long elements;
  double unshot;
  int workers = 0;  // alive; 0 when the master computes the columns itself
  int last_patch = -1, last_k = 0;  // the shot just before (-1: none yet)
};

enum class RunStatus { kConverged, kLimit, kStopped, kNotConverged, kNoWorkers };

struct RunResult {
  RunStatus status = RunStatus::kConverged;
  std::string why;          // for kNotConverged, kLimit and kNoWorkers
  long shots = 0;
  double seconds = 0;
  double unshot = 0;
  // The master's time (paper graph 1) in seconds of the monotonic clock
  // while it works (the scheduler's loop says how blocking is told apart).
  double distribute_s = 0;  // selecting patches and queueing them
  double receive_s = 0;     // transport: reading, decoding, sending
  double shoot_s = 0;       // shooting columns
  double subdivide_s = 0;   // adaptive subdivision
  double wait_s = 0;        // blocked waiting for workers (or preempted)
  // The workers' side.
  double worker_s = 0;      // Σ column compute time (CPU)
  long columns = 0;         // columns received and shot
  long stale = 0;           // columns for assignments no longer outstanding
  int joined = 0, lost = 0; // workers that joined, that were lost
  bool fell_back = false;   // every worker was lost: the master computed
  uint64_t bytes_sent = 0, bytes_received = 0;
  long passes = 0;          // division passes
  int waves = 1;
  // Per worker that joined (pipelined transports only), as its queue was
  // set from what the master measured (queues.h, Pace).
  struct Worker {
    std::string name;
    long columns = 0;
    int depth_min = 0, depth_max = 0;  // patches sent and unanswered, at most
    int depth = 0;                     // the last, at the end of the run
    int high_max = 0;                  // the high watermark's largest
    int reserve_max = 0;               // the most columns held more before a pass
    double column_s = 0;    // its compute time per column (smoothed)
    double wire_s = 0;      // a column's time on the wire (smoothed)
    double interval_s = 0;  // between its columns while it had more (smoothed)
    long deferred = 0;      // patches it was given from below the top
    long reclaimed = 0;     // patches sent to it, then given to another
  };
  std::vector<Worker> workers;
  // The workers' idle time (worker-seconds) as the master reconstructs it:
  // a worker computes its assignments in the order sent, starting each
  // when it has arrived and the one before is done (done: its compute
  // time after its start, or its arrival at the master if sooner). The
  // gaps, by what the master was doing meanwhile (first that applies):
  struct Idle {
    double picture = 0;  // in RunOptions::wave_end (a wave's picture)
    double pass = 0;     // dividing (a division pass, shooter splits)
    double dry = 0;      // nothing left to select: every patch with power owned
    double other = 0;    // the rest: receiving, shooting, a queue too shallow
    double end = 0;      // after its last column, to the end of the run
    double Sum() const { return picture + pass + dry + other + end; }
  } idle;
  double stale_s = 0;       // compute time of the stale columns (thrown away)
};

// The master (paper §4): selects patches into per-worker queues, keeps
// the workers busy, shoots the columns they return, divides elements
// between shots (subdivider may be null: the mesh stays, one wave) and
// sends the edits to the workers, stops by the rules of RunOptions.
// Drives any Transport; an InProcessTransport gives the sequential
// algorithm, and RunOptions::fallback takes over when every worker is
// lost. `sample` (may be empty) is called every log_every shots and once
// at the end; `note` (may be empty) gets one line when a worker joins,
// or, as a warning, when one is lost.
RunResult RunMaster(Mesh* mesh, const RunOptions& opts, Solver* solver, Subdivider* subdivider,
                    Transport* transport, const std::function<void(const Sample&)>& sample,
                    const std::function<void(const std::string&, bool warning)>& note);

// RunMaster() with the master's own process as the only worker (which is
// never lost: no fallback needed).
RunResult RunSequential(Mesh* mesh, const RunOptions& opts, Solver* solver,
                        Subdivider* subdivider,
                        const std::function<void(const Sample&)>& sample);

#endif
