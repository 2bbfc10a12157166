// The master's side of progressive refinement radiosity: choosing
// shooters, shooting with ambient overshooting, deciding when to stop.
//
// Numbers: radiosity, unshot radiosity, areas and the ambient sums are
// double. Overshooting subtracts nearly equal quantities (unshot minus what
// was shot in advance) and ρ → 1 scenes amplify any error by 1/(1−ρ), so
// float's 7 digits would show in the answer; form factors arrive as float.
#ifndef RADIOSITY_MASTER_H
#define RADIOSITY_MASTER_H

#include <cmath>
#include <csignal>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "hemicube.h"
#include "mesh.h"
#include "subdivide.h"

// Everything a Solver holds that is not derived from the mesh: what a
// checkpoint keeps (checkpoint.h) to go on later exactly where it stood.
struct SolverState {
  std::vector<glm::dvec3> b;          // per element (divided ones too)
  std::vector<glm::dvec3> unshot;     // per patch
  std::vector<uint8_t> lit, blind;    // per patch
  std::vector<int32_t> times_shot;    // per patch
  glm::dvec3 unshot_sum{0.0};         // the running sums as they are, drift
  double abs_sum = 0;                 // included, so that a resumed run
  long shots = 0;                     // makes the same choices bit for bit
};

class Solver {
 public:
  // overshoot: ambient overshooting (Feda & Purgathofer 1992).
  Solver(const Mesh& mesh, bool overshoot);

  // The patch with the largest power still to shoot (|unshot + overshoot
  // estimate| × area, channels summed) among those not marked in `taken`
  // (may be null), or -1 when there is nothing left to shoot.
  int Select(const std::vector<char>* taken = nullptr) const;

  // Shoots patch p along its column. The overshooting estimate is taken
  // here, from the ambient term as it is now (paper §4.2), not when p was
  // selected. The column may predate divisions (a worker computed it
  // before it heard of them): what an element since divided receives goes
  // to every leaf under it alike.
  void Shoot(int p, const std::vector<FormFactor>& column);

  // Divide() was applied to the mesh for these elements (in this order):
  // their children get the parent's radiosity shaped by its gradient
  // (paper §4.4), fitted to the neighbours and limited to their range,
  // keeping Σ B·area. Unshot radiosity is per patch and stays.
  void Divided(const std::vector<int32_t>& elems);
  // A new wave (paper §4.4): all computed radiosity is thrown away and the
  // solution starts again from the emitters, on the mesh as it is now.
  void NewWave();

  // Σ|unshot|·area / Σ emitted·area, channels summed; 0 for a dark scene.
  double UnshotFraction() const;
  // Σ B·area over all elements / Σ emitted·area: grows without bound when
  // a closed scene reflects everything.
  double PowerRatio() const;
  bool Dark() const { return emitted_ == 0; }
  long shots() const { return shots_; }
  int TimesShot(int p) const { return times_shot_[p]; }
  const std::vector<glm::dvec3>& radiosity() const { return b_; }  // per element
  const std::vector<glm::dvec3>& unshot() const { return unshot_; } // per patch
  glm::dvec3 Ambient() const;  // the overshooting estimate before ρ

  SolverState State() const;
  // Takes a State() of a solver of this mesh (divided alike since): false
  // with *err when the sizes do not match the mesh.
  bool Restore(const SolverState& s, std::string* err);

 private:
  glm::dvec3 ToShoot(int p) const;
  void Resum();
  void Grow();

  const Mesh& mesh_;
  bool overshoot_;
  std::vector<int> leaves_;         // scratch for Shoot
  std::vector<glm::dvec3> b_;       // per element
  std::vector<glm::dvec3> rho_per_area_;  // per element: ρ / A, for Shoot
  std::vector<int32_t> patch_of_;   // per element, compact for Shoot
  std::vector<glm::dvec3> unshot_;  // per patch
  std::vector<double> fsum_;        // per patch: Σ F within one Shoot
  std::vector<int32_t> touched_;    // patches with fsum_ != 0
  std::vector<uint8_t> lit_;        // per patch: emits, or light reached it
  std::vector<uint8_t> blind_;      // per patch: its column was empty
  std::vector<int> times_shot_;
  glm::dvec3 unshot_sum_{0.0};      // Σ unshot·area, kept incrementally
  double abs_sum_ = 0;              // Σ |unshot|·area (channels summed), too
  glm::dvec3 reflect_{1.0};         // 1/(1−ρ̄): ambient interreflection factor
  double total_area_ = 0, emitted_ = 0;
  long shots_ = 0;
};

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
  // Checkpoints: `checkpoint` (may be empty) is called every
  // `checkpoint_every` seconds between shots (0: never) and once when the
  // run stops, before the last log sample, with where the run stands.
  double checkpoint_every = 0;
  std::function<void(const RunState&)> checkpoint;
  // Go on from a checkpoint's state (the solver, subdivider and mesh
  // already restored): no first log sample, the clock and waves go on.
  const RunState* resume = nullptr;
};

struct Sample {
  double seconds;
  long shots;
  int wave;
  long elements;
  double unshot;
  int workers = 0;  // alive; 0 when the master computes the columns itself
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
};

// The hemicube angle for the k-th shot of patch p: a hash, so that any
// process computing that column turns the hemicube alike.
double ShotAngle(unsigned seed, int patch, int k);

// Subdivision between two shots, for any run loop: a division pass if
// one is due after `shots_in_wave` shots of this wave; the ids it divided,
// in order, replace *edits (what workers must apply alike). Returns true
// when the wave is over: the caller ends it (RunOptions::wave_end), then
// calls solver->NewWave() and subdivider->StartWave(*mesh).
bool Refine(Mesh* mesh, Solver* solver, Subdivider* subdivider, long shots_in_wave,
            std::vector<int32_t>* edits);

class Transport;

// The master (paper §4): selects patches into per-worker queues, keeps
// the workers busy, shoots the columns they return, divides elements
// between shots (subdivider may be null: the mesh stays, one wave) and
// sends the edits to the workers, stops by the rules of RunOptions.
// Drives any Transport; an InProcessTransport gives the sequential
// algorithm. `sample` (may be empty) is called every log_every shots and
// once at the end; `note` (may be empty) gets one line when a worker
// joins, or, as a warning, when one is lost.
RunResult RunMaster(Mesh* mesh, const RunOptions& opts, Solver* solver, Subdivider* subdivider,
                    Transport* transport, const std::function<void(const Sample&)>& sample,
                    const std::function<void(const std::string&, bool warning)>& note);

// RunMaster() with the master's own process as the only worker.
RunResult RunSequential(Mesh* mesh, const RunOptions& opts, Solver* solver,
                        Subdivider* subdivider,
                        const std::function<void(const Sample&)>& sample);

#endif
