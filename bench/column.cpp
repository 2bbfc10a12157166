// radiosity-column: the form-factor column alone, at any scene size, as
// one table row on stdout (bench/column.sh adds the headers and runs it
// for the program before and after a change, side by side).
//   radiosity-column [--first] SCENE.obj R COLUMNS [PATCH_SIZE [ELEMENTS_PER_PATCH [JOIN]]]
// COLUMNS shooters spread evenly over the patches, or with --first the
// first COLUMNS a run shoots (-j 0's order, no subdivision): the lights
// and the large surfaces that see most of the scene, dearer than the
// average shooter on a big scene; per column: CPU time,
// split into the stages in the proportions ColumnStats measures, the cost
// model (15 ns/element + 70 ns/covered element + 3 ns/pixel) and how many
// elements the column visited (on faces it did not cull) out of all. Uses only what
// hemicube.h has had since the cost model was set, so that the same file
// builds against the old column for the before figures, but for
// ShotColumn's group argument (since protocol 5: before it, drop it).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/load.h"
#include "clock.h"
#include "groups.h"
#include "hemicube.h"
#include "mesh.h"
#include "scene.h"
#include "solver.h"

int main(int argc, char** argv) {
  const bool first = argc > 1 && std::string(argv[1]) == "--first";
  if (first) {
    --argc;
    ++argv;
  }
  if (argc < 4) {
    std::fprintf(stderr,
                 "usage: radiosity-column [--first] SCENE.obj R COLUMNS [PATCH_SIZE [ELEMENTS_PER_PATCH [JOIN]]]\n");
    return 2;
  }
  Scene scene;
  MeshOptions mo;
  if (argc > 4) mo.patch_size = std::atof(argv[4]);
  if (argc > 5) mo.elements_per_patch = std::atoi(argv[5]);
  // JOIN 0: a tessellated scene's faces stay apart (--no-join), so that
  // the column sees a finely cut mesh rather than its joined surfaces.
  if (argc > 6) mo.join = std::atoi(argv[6]) != 0;
  Mesh mesh;
  LoadMeshOrDie("radiosity-column", argv[1], &scene, &mesh, mo);
  std::string name = argv[1];
  name = name.substr(name.find_last_of('/') + 1);
  const int res = std::atoi(argv[2]);
  const int want = std::max(1, std::atoi(argv[3]));
  Hemicube hc(res);
  std::vector<FormFactor> col;
  const int n = int(mesh.patches.size());
  const int step = std::max(1, n / want);
  std::vector<int> shooters;
  if (first) {
    Solver solver(mesh, true);
    while (int(shooters.size()) < want) {
      const int p = solver.Select();
      if (p < 0) break;
      ShotColumn(&hc, mesh, p, GroupOf(mesh, p), solver.TimesShot(p), true, 1, &col);
      solver.Shoot(p, col);
      shooters.push_back(p);
    }
  } else {
    for (int p = 0; p < n && int(shooters.size()) < want; p += step) shooters.push_back(p);
  }
  // One column first, untimed: buffers and any per-mesh setup are a
  // once-per-run cost, not a column's.
  ShotColumn(&hc, mesh, 0, GroupOf(mesh, 0), 0, true, 1, &col);
  // Twice over the same shooters: without stats for the time (the stage
  // clocks cost a little per face), then with them for the split, shown as
  // shares of that time (CPU time: the machine may be shared).
  const int columns = int(shooters.size());
  const double t0 = ThreadCpuSeconds();
  for (int p : shooters) ShotColumn(&hc, mesh, p, GroupOf(mesh, p), 0, true, 1, &col);
  const double per = (ThreadCpuSeconds() - t0) / columns;
  ColumnStats st;
  for (int p : shooters) ShotColumn(&hc, mesh, p, GroupOf(mesh, p), 0, true, 1, &col, &st);
  const double staged = std::max(1e-12, st.transform_s + st.raster_s + st.readback_s);
  const double elems = double(mesh.elems.size());
  const double model =
      (15e-9 * elems * columns + 70e-9 * double(st.covered) + 3e-9 * double(st.pixels)) / columns;
  std::printf("%s | %d | %.0f | %.0f | %.1f%% | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f\n",
              name.c_str(), res, elems, double(st.covered) / columns,
              100.0 * double(st.elements) / columns / elems, 1e3 * per,
              1e3 * per * st.transform_s / staged, 1e3 * per * st.raster_s / staged,
              1e3 * per * st.readback_s / staged, 1e3 * model, per / model);
  return 0;
}
