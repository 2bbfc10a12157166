// radiosity-cluster: the cluster simulation (sim.h) on any scene, as table
// rows on stdout (bench/master.sh adds the headers).
//   radiosity-cluster [--one-thread] [--divide] [--master-us US] SCENE.obj SHOTS [R] [WORKERS...]
// The real scheduler and solver drive simulated workers (every column
// computed for real, the master charged its own measured CPU time, its
// wake-ups and its system calls) on a
// shared link of 1 and 10 Gbit/s with 100 us latency, from 1 worker up
// (default 8 32 64 128). Per run: simulated seconds for SHOTS shots, the
// speedup over one simulated worker on the same link, the efficiency, the
// master's charged time per shot, and the most speedup the master's time
// allows (paper graph 2: a worker's time per column / the master's per
// shot). Without subdivision, so that every run shoots the same mesh;
// --divide: with it (the default SubdivideOptions, each run on a copy of
// the mesh as built), and three more columns: the workers' seconds idle
// in division passes (RunResult::idle), summed over the workers, the
// division passes and the waves.
// --one-thread: the master reads and writes on its own thread, as before
// pool_thread.h (SimOptions::pool_thread false), to compare.
// --master-us US: the master is charged US microseconds a turn of its loop
// instead of its measured time (its system calls and wake-ups still as
// measured): a what-if for a master whose caches are its own. Measured in
// this process it also pays for the simulated workers' hemicubes stirring
// its caches between turns, which a cluster's master does not: about 1.4
// times its cost on the room and 1.7 at 10^5 elements (radiosity-master
// --stir, README "The simulation held to the real runs").
// It uses only RunMaster, Solver and SimTransport, and SimOptions::pool_thread
// (--one-thread): a build of an older program (bench/master.sh's
// CLUSTER_BEFORE) is this file without that line.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "bench/load.h"
#include "mesh.h"
#include "scene.h"
#include "scheduler.h"
#include "sim.h"
#include "solver.h"
#include "subdivide.h"

int main(int argc, char** argv) {
  double master_us = -1;
  bool ok = true;
  const bool one_thread = argc > 1 && std::strcmp(argv[1], "--one-thread") == 0;
  if (one_thread) {
    ++argv;
    --argc;
  }
  const bool divide = argc > 1 && std::strcmp(argv[1], "--divide") == 0;
  if (divide) {
    ++argv;
    --argc;
  }
  if (argc > 2 && std::strcmp(argv[1], "--master-us") == 0) {
    char* end;
    master_us = std::strtod(argv[2], &end);
    ok = *end == 0 && master_us >= 0 && std::isfinite(master_us);
    argv += 2;
    argc -= 2;
  }
  if (argc < 3 || !ok) {
    std::fprintf(stderr, "usage: radiosity-cluster [--one-thread] [--divide] [--master-us US] SCENE.obj SHOTS [R] "
                 "[WORKERS...]\n");
    return 2;
  }
  const long shots = std::atol(argv[2]);
  const int res = argc > 3 ? std::atoi(argv[3]) : 256;
  std::vector<int> counts;
  for (int i = 4; i < argc; ++i) counts.push_back(std::atoi(argv[i]));
  if (counts.empty()) counts = {8, 32, 64, 128};
  Scene scene;
  Mesh mesh;
  LoadMeshOrDie("radiosity-cluster", argv[1], &scene, &mesh);
  std::string name = argv[1];
  name = name.substr(name.find_last_of('/') + 1);
  // What a real master pays and the simulated one does not: its wake-ups
  // and its system calls, on this machine (sim.h).
  const double wake = MeasureWakeup();
  const SimOptions::Io io = MeasureIo();
  for (double bps : {1e9, 1e10}) {
    double one = 0;
    std::vector<int> runs = {1};
    runs.insert(runs.end(), counts.begin(), counts.end());
    for (int w : runs) {
      SimOptions so;
      so.workers = w;
      so.bandwidth_bps = bps;
      so.resolution = res;
      so.wakeup_s = wake;
      so.io = io;
      so.pool_thread = !one_thread;
      if (master_us >= 0) so.master_cost_s = master_us * 1e-6;
      Mesh run_mesh = mesh;  // --divide changes it
      SimTransport t(run_mesh, so);
      Solver solver(run_mesh, true);
      std::unique_ptr<Subdivider> sub;
      if (divide) sub = std::make_unique<Subdivider>(&run_mesh, SubdivideOptions());
      RunOptions o;
      o.resolution = res;
      o.epsilon = 1e-12;
      o.max_shots = shots;
      const RunResult r = RunMaster(&run_mesh, o, &solver, sub.get(), &t, nullptr, nullptr);
      const double per_shot = t.MasterSeconds() / double(r.shots);
      const double column = r.worker_s / double(r.columns);
      if (w == 1) one = r.seconds;
      std::printf("| %s | %ld | %ld | %.0f Gbit/s | %d | %.3f | %.1f | %.2f | %.1f | %.0f |",
                  name.c_str(), long(run_mesh.elems.size()), r.shots, bps / 1e9, w, r.seconds,
                  one / r.seconds, one / r.seconds / w, 1e6 * per_shot, column / per_shot);
      if (divide) std::printf(" %.3f | %ld | %d |", r.idle.pass, r.passes, r.waves);
      std::printf("\n");
      std::fflush(stdout);
    }
  }
  return 0;
}
