// radiosity-throttle: the cluster simulation (sim.h) of one quick worker
// beside one behind a slow link of its own (SimOptions::link_bps), as
// table rows on stdout (bench/throttle.sh adds the headers).
//   radiosity-throttle SCENE.obj SHOTS R LINK_BPS...
// Per link rate, and for the quick worker alone: simulated seconds to
// converge (epsilon 1e-3, subdivision and waves as the program's
// defaults) and to SHOTS shots (no subdivision), the slow worker's share
// of the columns, the patches deferred to it and taken back, and its
// queue (sent at once, least..most) in the converging run. The medium is 1 Gbit/s with
// 100 us latency. Every column is computed for real (so the shooting
// order and the bytes are a real run's), but charged a fixed cost, the
// mean of a first run of SHOTS shots with measured costs, as is the
// master per Poll: the table is the same on a busy machine, and each row
// differs from the others only by the link.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/load.h"
#include "scheduler.h"
#include "sim.h"
#include "solver.h"
#include "subdivide.h"

namespace {

struct Row {
  RunResult r;
  RunResult::Worker slow;
};

struct Costs {
  double column_s = -1, master_s = -1;  // < 0: measured
};

Row Run(const Scene& scene, int res, const Costs& costs, double link_bps, bool divide,
        long shots, double* master_s = nullptr) {
  Mesh mesh;
  BuildMeshOrDie("radiosity-throttle", scene, MeshOptions(), &mesh);
  SimOptions so;
  so.workers = link_bps > 0 ? 2 : 1;
  so.resolution = res;
  so.column_cost_s = costs.column_s;
  so.master_cost_s = costs.master_s;
  if (link_bps > 0) so.link_bps = {0, link_bps};
  SimTransport t(mesh, so);
  Solver solver(mesh, true);
  Subdivider sub(&mesh, SubdivideOptions());
  RunOptions o;
  o.resolution = res;
  o.epsilon = divide ? 1e-3 : 1e-12;
  o.max_shots = divide ? 0 : shots;
  Row row;
  row.r = RunMaster(&mesh, o, &solver, divide ? &sub : nullptr, &t, nullptr, nullptr);
  for (const RunResult::Worker& w : row.r.workers)
    if (w.name == t.Name(1)) row.slow = w;
  if (master_s) *master_s = t.MasterSeconds();
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: radiosity-throttle SCENE.obj SHOTS R LINK_BPS...\n");
    return 2;
  }
  const long shots = std::atol(argv[2]);
  const int res = std::atoi(argv[3]);
  Scene scene;
  LoadSceneOrDie("radiosity-throttle", argv[1], &scene);
  std::string name = argv[1];
  name = name.substr(name.find_last_of('/') + 1);
  std::vector<double> rates = {0};
  for (int i = 4; i < argc; ++i) rates.push_back(std::atof(argv[i]));
  Costs costs;
  double master_s = 0;
  const RunResult m = Run(scene, res, costs, 0, false, shots, &master_s).r;
  costs.column_s = m.worker_s / double(m.columns);
  costs.master_s = master_s / double(m.shots);
  std::fprintf(stderr, "radiosity-throttle: %s R %d: %.3f ms a column, %.1f us of master a shot\n",
               name.c_str(), res, 1e3 * costs.column_s, 1e6 * costs.master_s);
  for (double bps : rates) {
    const Row c = Run(scene, res, costs, bps, true, 0);
    const Row n = Run(scene, res, costs, bps, false, shots);
    std::string link = "alone";
    char buf[64];
    if (bps > 0) {
      std::snprintf(buf, sizeof buf, "+ one at %g Mbit/s", bps / 1e6);
      link = buf;
    }
    std::printf("| %s | %d | %s | %.3f | %ld | %.3f | ", name.c_str(), res, link.c_str(),
                c.r.seconds, c.r.shots, n.r.seconds);
    if (bps > 0)
      std::printf("%ld of %ld | %ld | %ld | %d..%d | %.1f |\n", c.slow.columns, c.r.columns,
                  c.slow.deferred, c.slow.reclaimed, c.slow.depth_min, c.slow.depth_max,
                  1e3 * c.slow.interval_s);
    else
      std::printf("| | | | |\n");
    std::fflush(stdout);
  }
  return 0;
}
