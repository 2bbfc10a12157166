// radiosity-bench: the engine's figures for one scene, as table rows on
// stdout (bench/run.sh adds the headers).
//   radiosity-bench SCENE.obj R [R...]
// Per resolution: mean form-factor column time split into stages against
// the cost model (15 ns/element + 70 ns/covered element + 3 ns/pixel),
// master time per shot, and shots and seconds to 1% relative RMS against
// the scene's converged solution, with and without overshooting.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/load.h"
#include "clock.h"
#include "groups.h"
#include "hemicube.h"
#include "scheduler.h"
#include "solver.h"
#include "mesh.h"
#include "results.h"
#include "scene.h"

namespace {

struct ToTarget {
  long shots = -1;
  double seconds = 0, master_per_shot_us = 0;
};

// Shots to reach rel RMS <= target (sampled every shot), then the same run
// again without sampling to time it.
ToTarget Reach(const Scene& scene, Mesh* mesh, int res, bool overshoot,
               const std::vector<glm::dvec3>& ref, double target) {
  ToTarget t;
  RunOptions o;
  o.resolution = res;
  o.overshoot = overshoot;
  o.epsilon = 1e-12;
  o.log_every = 1;
  o.max_shots = 200 * long(mesh->patches.size());
  volatile std::sig_atomic_t stop = 0;
  o.stop = &stop;
  Solver s(*mesh, overshoot);
  RunSequential(mesh, o, &s, nullptr, [&](const Sample& smp) {
    double rms, rel;
    RmsError(scene, FaceRadiosity(*mesh, s.radiosity()), ref, &rms, &rel);
    if (rel <= target && !stop) {
      t.shots = smp.shots;
      stop = 1;
    }
  });
  if (t.shots < 0) return t;
  o.log_every = 1L << 40;
  o.max_shots = std::max(1L, t.shots);
  o.stop = nullptr;
  Solver s2(*mesh, overshoot);
  RunResult r = RunSequential(mesh, o, &s2, nullptr, nullptr);
  t.seconds = r.seconds;
  t.master_per_shot_us = 1e6 * (r.distribute_s + r.shoot_s) / std::max(1L, r.shots);
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench SCENE.obj R [R...]\n");
    return 2;
  }
  Scene scene;
  Mesh mesh;
  LoadMeshOrDie("bench", argv[1], &scene, &mesh);
  std::string name = argv[1];
  name = name.substr(name.find_last_of('/') + 1);
  for (int a = 2; a < argc; ++a) {
    const int res = std::atoi(argv[a]);
    Hemicube hc(res);
    ColumnStats st;
    std::vector<FormFactor> col;
    const int n = int(mesh.patches.size());
    const int step = std::max(1, n / 400);
    int columns = 0;
    const double t0 = MonotonicSeconds();
    for (int p = 0; p < n; p += step, ++columns)
      ShotColumn(&hc, mesh, p, GroupOf(mesh, p), 0, true, 1, &col, &st);
    const double total = MonotonicSeconds() - t0;
    const double per = total / columns;
    const double model =
        (15e-9 * double(mesh.elems.size()) * columns + 70e-9 * st.covered + 3e-9 * st.pixels) /
        columns;
    std::printf("column | %s | %d | %zu | %.0f | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f\n",
                name.c_str(), res, mesh.elems.size(), double(st.covered) / columns, 1e3 * per,
                1e3 * st.transform_s / columns, 1e3 * st.raster_s / columns,
                1e3 * st.readback_s / columns, 1e3 * model, per / model);
    std::fflush(stdout);

    // The converged answer: overshooting, run far past the default epsilon.
    RunOptions o;
    o.resolution = res;
    o.epsilon = 1e-6;
    Solver ref_solver(mesh, true);
    RunResult rr = RunSequential(&mesh, o, &ref_solver, nullptr, nullptr);
    std::vector<glm::dvec3> ref = FaceRadiosity(mesh, ref_solver.radiosity());
    for (bool over : {true, false}) {
      ToTarget t = Reach(scene, &mesh, res, over, ref, 0.01);
      std::printf("converge | %s | %d | %s | %ld | %.3f | %.1f | %ld | %.1f\n", name.c_str(), res,
                  over ? "overshooting" : "plain", t.shots, t.seconds, t.master_per_shot_us,
                  rr.shots, rr.seconds);
      std::fflush(stdout);
    }
  }
  return 0;
}
