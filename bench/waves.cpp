// radiosity-waves: adaptive subdivision and waves against uniform meshes,
// for one scene, as table rows on stdout and curves in CSV (bench/waves.sh
// adds headers and draws the SVGs).
//   radiosity-waves SCENE.obj CURVES.csv [REF_ELEMENTS]
// The reference is a converged uniform mesh of REF_ELEMENTS x REF_ELEMENTS
// elements per patch (default 12: finer than the adaptive run's level 2),
// and the error is FieldError's (per point: a face's mean does not depend
// on how its elements are cut). Runs, each to the default epsilon 1e-3:
//   coarse   - the default mesh (2 x 2 per patch), no subdivision
//   adaptive - the default mesh, subdivision and waves
//   fine     - uniform, N x N per patch with N such that it has about as
//              many elements as the adaptive run ends with
// The error is sampled every patches/20 shots; the time spent measuring it
// is left out of the time axis.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/load.h"
#include "clock.h"
#include "mesh.h"
#include "results.h"
#include "scene.h"
#include "scheduler.h"
#include "solver.h"
#include "subdivide.h"

namespace {

struct Point {
  double seconds, unshot, rel;
  long shots, elements;
  int wave;
};

struct Curve {
  std::vector<Point> points;
  RunResult result;
  long elements = 0;
};

Curve Run(const Scene& scene, int epp, bool subdivide, const Mesh& ref,
          const std::vector<glm::dvec3>& ref_b) {
  Mesh mesh;
  MeshOptions mo;
  mo.elements_per_patch = epp;
  BuildMeshOrDie("radiosity-waves", scene, mo, &mesh);
  Solver solver(mesh, true);
  Subdivider sub(&mesh, SubdivideOptions());
  RunOptions o;
  o.log_every = std::max<long>(1, long(mesh.patches.size()) / 20);
  Curve c;
  double measuring = 0;  // seconds spent in the callback so far
  c.result = RunSequential(&mesh, o, &solver, subdivide ? &sub : nullptr, [&](const Sample& s) {
    const double t0 = MonotonicSeconds();
    double rms, rel;
    FieldError(mesh, solver.radiosity(), ref, ref_b, &rms, &rel);
    c.points.push_back({s.seconds - measuring, s.unshot, rel, s.shots, s.elements, s.wave});
    measuring += MonotonicSeconds() - t0;
  });
  c.result.seconds -= measuring;
  c.elements = mesh.LeafCount();
  return c;
}

// The first sample time at which the curve's error is at most `target`.
double TimeTo(const Curve& c, double target) {
  for (const Point& p : c.points)
    if (p.rel <= target) return p.seconds;
  return NAN;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: radiosity-waves SCENE.obj CURVES.csv [REF_ELEMENTS]\n");
    return 2;
  }
  Scene scene;
  LoadSceneOrDie("radiosity-waves", argv[1], &scene);
  std::string name = argv[1];
  name = name.substr(name.find_last_of('/') + 1);
  name = name.substr(0, name.find('.'));
  const int ref_epp = argc > 3 ? std::atoi(argv[3]) : 12;

  Mesh ref;
  MeshOptions mo;
  mo.elements_per_patch = ref_epp;
  BuildMeshOrDie("radiosity-waves", scene, mo, &ref);
  Solver ref_solver(ref, true);
  RunOptions ro;
  ro.epsilon = 1e-4;
  RunResult rr = RunSequential(&ref, ro, &ref_solver, nullptr, nullptr);
  std::printf("reference | %s | %ld | %ld | %.1f\n", name.c_str(), ref.LeafCount(), rr.shots,
              rr.seconds);
  std::fflush(stdout);

  const Curve coarse = Run(scene, 2, false, ref, ref_solver.radiosity());
  const Curve adaptive = Run(scene, 2, true, ref, ref_solver.radiosity());
  // Uniform N x N per patch with about the adaptive run's element count.
  const int n = std::max(2, int(std::lround(2 * std::sqrt(double(adaptive.elements) /
                                                          coarse.elements))));
  const Curve fine = Run(scene, n, false, ref, ref_solver.radiosity());

  std::FILE* f = std::fopen(argv[2], "a");
  if (!f) {
    std::perror(argv[2]);
    return 1;
  }
  const double fine_final = fine.points.back().rel;
  for (auto [method, c] : {std::pair<const char*, const Curve*>{"coarse", &coarse},
                           {"adaptive", &adaptive},
                           {"fine", &fine}}) {
    for (const Point& p : c->points)
      std::fprintf(f, "%s,%s,%.4f,%ld,%d,%ld,%.6g,%.6g\n", name.c_str(), method, p.seconds,
                   p.shots, p.wave, p.elements, p.unshot, p.rel);
    const double to = TimeTo(*c, fine_final);
    std::printf("run | %s | %s | %ld | %d | %ld | %.2f | %ld | %.1f | %.4f | %.2f | %.2f\n",
                name.c_str(), method, c->elements, c->result.waves, c->result.shots,
                c->result.seconds, c->result.passes,
                c->result.passes ? 1e3 * c->result.subdivide_s / c->result.passes : 0.0,
                c->points.back().rel, to, to / fine.result.seconds);
  }
  std::fclose(f);
  return 0;
}
