// radiosity-master: the master's own work per shot on one scene, as one
// table row on stdout (bench/master.sh adds the headers).
//   radiosity-master SCENE.obj SHOTS [R] [--no-overshoot] [--divide [--every-leaf]]
//                    [--rounds N] [--thread-cpu] [--stir]
// Each shot as the master does it with workers: select the next patch,
// decode the column that comes back (the frame a worker sends, made here
// by ShotColumn and EncodeColumn, which are not timed: a worker's work),
// shoot it. Timed on the monotonic clock per part and compared with issue
// 14's target, 10 us + 5 ns per covered element (form factors in the
// column). --divide: a division pass every 10 shots after the first 20
// (without waves), timed per pass, with the share of the leaves it
// evaluated; --every-leaf: every leaf every pass, as before issue 14.
// Then the memory floor (not with --divide): each shot's cache lines
// touched alone, per shot and per line. --rounds N: N replays instead of 3,
// the quickest kept; --thread-cpu:
// each part timed on the thread's CPU clock (a system call, about half a
// microsecond a read, four a shot) rather than the wall clock scaled to
// the round's CPU time: steadier on a machine shared with other work.
// --stir: between shots (not timed) a real column is computed in this
// thread, as the cluster simulation computes its workers' columns in the
// master's process: what the hemicube's work does to the master's caches
// (on this machine a thread on the other core does the same: its two
// cores share them), which a master on its own machine does not pay.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "clock.h"
#include "bench/load.h"
#include "bench/record.h"
#include "mesh.h"
#include "protocol.h"
#include "scene.h"
#include "solver.h"
#include "subdivide.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: radiosity-master SCENE.obj SHOTS [R] [--no-overshoot] [--divide "
                 "[--every-leaf]] [--rounds N] [--thread-cpu] [--stir]\n");
    return 2;
  }
  const long shots = std::atol(argv[2]);
  int res = 256, rounds = 3;
  bool overshoot = true, divide = false, every_leaf = false, thread_cpu = false, stir = false;
  for (int i = 3; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--no-overshoot")) overshoot = false;
    else if (!std::strcmp(argv[i], "--thread-cpu")) thread_cpu = true;
    else if (!std::strcmp(argv[i], "--rounds") && i + 1 < argc) rounds = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--divide")) divide = true;
    else if (!std::strcmp(argv[i], "--every-leaf")) every_leaf = true;
    else if (!std::strcmp(argv[i], "--stir")) stir = true;
    else res = std::atoi(argv[i]);
  }
  Scene scene;
  Mesh mesh;
  LoadMeshOrDie("radiosity-master", argv[1], &scene, &mesh);
  std::string err;
  const long patches = long(mesh.patches.size()), built = long(mesh.elems.size());
  // First the columns, in the order the run shoots them (a worker's work,
  // not timed); then the master's work alone on them, three times on
  // fresh solvers (the same choices: deterministic), the quickest kept,
  // with the caches its own as a master's are beside its workers.
  const std::vector<std::string> frames = RecordFrames("radiosity-master", mesh, shots, res, overshoot);
  double select_s = HUGE_VAL / 4, decode_s = 0, shoot_s = 0, pass_s = 0, pass_max = 0, policy_s = 0;
  long covered = 0, done = 0, passes = 0, divided = 0, evaluated = 0, leaves = 0;
  std::vector<int32_t> changed;
  const auto clock = thread_cpu ? ThreadCpuSeconds : MonotonicSeconds;
  for (int round = 0; round < (divide ? 1 : rounds); ++round) {
    Solver solver(mesh, overshoot);
    if (divide) solver.TrackNoise(res);  // as the run loop does when it divides
    SubdivideOptions so;
    so.waves = false;
    so.incremental = !every_leaf;
    Subdivider sub(&mesh, so);
    proto::Column got;
    proto::FrameReader reader;
    std::string_view payload;
    double sel = 0, dec = 0, sho = 0;
    covered = 0;
    const double cpu0 = ThreadCpuSeconds(), wall0 = MonotonicSeconds();
    const std::unique_ptr<Hemicube> stir_cube = stir ? std::make_unique<Hemicube>(res) : nullptr;
    std::vector<FormFactor> stirred;
    for (done = 0; done < long(frames.size()); ++done) {
      if (stir)  // patches spread over the scene, as many workers' would be
        ShotColumn(stir_cube.get(), mesh, int(done * 7919 % patches), nullptr, 0, true, 1, &stirred);
      double t0 = clock();
      const int p = solver.Select();
      solver.Take(p);
      const double t1 = clock();
      reader.Append(frames[size_t(done)].data(), frames[size_t(done)].size());
      proto::Msg type;
      if (reader.Next(&type, &payload, &err) != proto::FrameReader::kFrame ||
          !proto::DecodeColumn(payload, &got, &err) || got.patch != p) {
        std::fprintf(stderr, "radiosity-master: %s (patch %d, recorded %d)\n", err.c_str(), p,
                     got.patch);
        return 1;
      }
      const double t2 = clock();
      solver.Shoot(p, got.ff);
      solver.Release(p);
      const double t3 = clock();
      sel += t1 - t0;
      dec += t2 - t1;
      sho += t3 - t2;
      covered += long(got.ff.size());
      // The recorded columns predate the divisions, as columns from
      // workers may: Shoot gives a divided element's share to its leaves.
      if (divide && sub.Due(done + 1)) {
        t0 = ThreadCpuSeconds();  // a pass takes milliseconds: the CPU clock's cost is nothing
        solver.TakeChanged(&changed);
        ConnectEdges(&mesh);  // at the first pass, as Refine makes the adjacency
        const std::vector<int32_t> edits =
            sub.Pass(mesh, solver.radiosity(), solver.noise(), solver.Ambient(), done + 1, changed);
        evaluated += sub.evaluated();
        leaves += mesh.LeafCount();
        policy_s += ThreadCpuSeconds() - t0;
        for (int32_t e : edits) Divide(&mesh, e);
        solver.Divided(edits);
        const double t = ThreadCpuSeconds() - t0;
        pass_s += t;
        pass_max = std::max(pass_max, t);
        ++passes;
        divided += long(edits.size());
      }
    }
    // On a shared machine the wall clock runs on while the thread waits
    // for a core: the parts' shares of the round's wall time, scaled to
    // its CPU time (unless --thread-cpu: the thread's clock costs about a
    // microsecond a shot read per part).
    const double scale = thread_cpu ? 1 : (ThreadCpuSeconds() - cpu0) / (MonotonicSeconds() - wall0);
    sel *= scale;
    dec *= scale;
    sho *= scale;
    if (sel + dec + sho < select_s + decode_s + shoot_s) {
      select_s = sel;
      decode_s = dec;
      shoot_s = sho;
    }
  }
  // The memory floor: rounds more in which each shot's cache lines
  // (Solver::ShotLines: its elements' and patches' records, their patch
  // ids, the queue's leaves and flags; listed for every shot first, so
  // that listing them does not stir the caches between shots) are
  // touched alone, as Shoot touches them: those it writes read and
  // written back, then those it only reads, each in address order and
  // fetched 32 ahead as Shoot fetches them, timed; then the shot, not
  // timed. At 10^5 elements and more the lines are scattered over arrays
  // larger than the caches: the time the memory takes to deliver them and
  // take back the dirty ones, which no arrangement of the work on them
  // goes below.
  double floor_s = HUGE_VAL;
  long lines = 0;
  for (int round = 0; round < (divide ? 0 : rounds); ++round) {
    Solver solver(mesh, overshoot);  // without divisions its layout stays as it is now
    std::vector<proto::Column> cols(frames.size());
    std::vector<std::vector<const char*>> written(frames.size()), read(frames.size());
    lines = 0;
    for (size_t i = 0; i < frames.size(); ++i) {
      DecodeFrame("radiosity-master", frames[i], &cols[i]);
      solver.ShotLines(cols[i].ff, &written[i], &read[i]);
      lines += long(written[i].size() + read[i].size());
    }
    unsigned sum = 0;
    double touch_s = 0;
    const double cpu0 = ThreadCpuSeconds(), wall0 = MonotonicSeconds();
    for (size_t k = 0; k < frames.size(); ++k) {
      const int p = solver.Select();
      const std::vector<const char*>& w = written[k];
      const std::vector<const char*>& r = read[k];
      const double t0 = clock();
      for (size_t i = 0; i < w.size(); ++i) {
        if (i + 32 < w.size()) __builtin_prefetch(w[i + 32], 1);
        // The byte as it is, written back: the line dirty as Shoot leaves it.
        volatile char* c = const_cast<char*>(w[i]);
        *c = *c;
      }
      for (size_t i = 0; i < r.size(); ++i) {
        if (i + 32 < r.size()) __builtin_prefetch(r[i + 32]);
        sum += *reinterpret_cast<const volatile unsigned char*>(r[i]);
      }
      touch_s += clock() - t0;
      solver.Shoot(p, cols[k].ff);
    }
    if (!thread_cpu) touch_s *= (ThreadCpuSeconds() - cpu0) / (MonotonicSeconds() - wall0);
    floor_s = std::min(floor_s, touch_s);
    if (sum == 1) std::fprintf(stderr, " ");  // the reads are used
  }
  const double n = double(std::max(1L, done)), per = double(covered) / n;
  const double total = 1e6 * (select_s + decode_s + shoot_s) / n;
  std::string name = argv[1];
  name = name.substr(name.find_last_of('/') + 1);
  std::printf("| %s | %s | %ld | %ld | %ld | %.0f | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f |",
              name.c_str(), overshoot ? "on" : "off", patches, built, done, per,
              1e6 * select_s / n, 1e6 * decode_s / n, 1e6 * shoot_s / n, total,
              10 + 0.005 * per, 1e3 * (total - 10) / std::max(1.0, per));
  if (!divide) {
    const double shots_n = double(std::max<size_t>(1, frames.size()));
    std::printf(" %.0f | %.2f | %.2f |", double(lines) / shots_n, 1e6 * floor_s / shots_n,
                1e9 * floor_s / double(std::max(1L, lines)));
  } else {
    std::printf(" %ld | %ld | %.3f | %.2f | %.2f | %.2f |", passes, divided,
                double(evaluated) / double(std::max(1L, leaves)),
                1e3 * policy_s / double(std::max(1L, passes)),
                1e3 * pass_s / double(std::max(1L, passes)), 1e3 * pass_max);
  }
  std::printf("\n");
  return 0;
}
