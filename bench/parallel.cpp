// radiosity-parallel: the paper's section 5 reproduced, as tables on
// stdout, CSV and SVG graphs in OUT_DIR.
//   radiosity-parallel [--repeat N] [--quick | --validation] [--cores N] RADIOSITY OUT_DIR
// RADIOSITY is the program whose --worker mode the real runs start (as
// `radiosity -j N` does). Scenes come from scenes/ and converged answers
// are cached in bench/results/tmp/, so run it from the repository's top
// (bench/run.sh does).
//  * Graphs 1 and 2: the master's CPU time per shot split into work
//    distribution, shooting and subdivision, and the master/worker time
//    ratio with the maximum speedup it allows, from real runs with one
//    worker process (the first 250 shots).
//  * Graphs 3-5: speedup and efficiency by shots (time for 500 shots) and
//    by RMS error (time to the RMS error one worker has after 500 shots),
//    bytes on the wire per shot: real runs with 1, 2, 4 ... --cores worker
//    processes on this machine (default 2 cores), the simulation of this
//    machine next to them (the validation), and the simulated cluster up
//    to 128 workers on three networks (10 Gbit/s, 1 Gbit/s, 10 Mbit/s):
//    the room and the maze; without --quick the other shipped scenes on
//    this machine too, for the validation (--quick: the room alone;
//    --validation: this machine's rows of every shipped scene alone).
// Times run from the first shot, so that start-up (process start, the
// scene's transfer, mesh building, the first round trip) is left out alike
// everywhere: the figures are those of a run under way. The simulated
// workers therefore all start at once with the scene in hand: a scene sent
// to 100 workers one after another over the shared link would hold it for
// longer than the 500 shots take (room: 100 x 0.2 MB at 1 Gbit/s = 0.2 s)
// and measure the broadcast instead; its time is printed beside the table.
// Real timings, and those of the simulation of this machine next to them,
// are the minimum of --repeat runs (default 3): other work on the machine
// only ever adds time.
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "bench/load.h"
#include "check.h"
#include "hemicube.h"
#include "mesh.h"
#include "pool.h"
#include "pool_thread.h"
#include "protocol.h"
#include "results.h"
#include "scene.h"
#include "scheduler.h"
#include "sim.h"
#include "solver.h"
#include "svg.h"
#include "transport.h"

namespace {

[[noreturn]] void Die(const std::string& msg) {
  std::fprintf(stderr, "radiosity-parallel: %s\n", msg.c_str());
  std::exit(1);
}

struct SceneData {
  std::string name, path;
  Scene scene;
  Mesh mesh;
};

SceneData Load(const std::string& name) {
  SceneData s;
  s.name = name;
  s.path = "scenes/" + name + ".obj";
  LoadMeshOrDie("radiosity-parallel", s.path, &s.scene, &s.mesh);
  return s;
}

// What a run leaves for the measurements: when each shot happened on the
// transport's clock, and which columns were shot, to replay them for the
// RMS error afterwards (computing it during the run would cost the master
// time that is no part of its work).
struct Trace {
  RunResult r;
  std::vector<double> shot_at;          // [i]: shot i + 1 done
  std::vector<proto::Assignment> shot;  // in the order shot
  std::vector<glm::dvec3> b;            // the radiosity at the end
  double sim_master_s = 0;              // simulation: CPU charged to the master
  bool stalled = false;                 // ended by kStall before its shots
  // Seconds from the first shot to the end of shot k.
  double Until(size_t k) const { return shot_at[k - 1] - shot_at[0]; }
};

// The longest a run may take (the slowest, at 10 Mbit/s, take ~20 s of
// virtual time): a run whose scheduler stops sending work would otherwise
// wait for columns for ever.
constexpr double kStall = 120;

RunOptions Options(int res, long shots) {
  RunOptions o;
  o.resolution = res;
  o.max_shots = shots;
  o.max_seconds = kStall;
  o.epsilon = 1e-9;  // the shot limit ends every run
  o.log_every = 1;
  return o;
}

Trace Record(const SceneData& s, const RunOptions& o, Transport* t) {
  Trace tr;
  // The master's own copy: RunMaster may divide it (not here: these runs
  // measure the scheduler on the mesh as built).
  Mesh mesh = s.mesh;
  Solver solver(mesh, o.overshoot);
  tr.r = RunMaster(&mesh, o, &solver, nullptr, t,
                   [&](const Sample& smp) {
                     if (smp.shots > long(tr.shot_at.size())) {
                       tr.shot_at.push_back(t->Now());
                       tr.shot.push_back({smp.last_patch, smp.last_k});
                     }
                   },
                   [](const std::string& line, bool warning) {
                     if (warning) std::fprintf(stderr, "radiosity-parallel: %s\n", line.c_str());
                   });
  tr.stalled = tr.r.shots < o.max_shots;
  // A column is stale only for a patch taken back from a worker that held
  // it too long (scheduler.cpp, Reclaim): one at most for each.
  long reclaimed = 0;
  for (const RunResult::Worker& w : tr.r.workers) reclaimed += w.reclaimed;
  if (tr.r.status != RunStatus::kLimit || tr.r.stale > reclaimed || tr.r.lost || tr.r.fell_back)
    Die(s.name + ": a run went wrong: " + tr.r.why + ", " + std::to_string(tr.r.stale) +
        " stale (" + std::to_string(reclaimed) + " taken back), " + std::to_string(tr.r.lost) +
        " lost");

  tr.b = solver.radiosity();
  return tr;
}

proto::SceneSetup Setup(const SceneData& s, const RunOptions& o) {
  return {s.scene, MeshOptions(), o.resolution, o.rotate, o.seed};
}

// The master in this process and `workers` worker processes of `exe`, as
// `radiosity -j N` runs them.
// The pool as the program would have it on a machine of `cores` with
// these local workers: on a thread of its own when a core is free for it.
Trace RealRun(const SceneData& s, int res, int workers, long shots, const std::string& exe,
              int cores) {
  const RunOptions o = Options(res, shots);
  auto pool = std::make_unique<WorkerPool>(Setup(s, o), s.mesh, PoolOptions());
  for (int i = 0; i < workers; ++i) {
    pid_t pid = 0;
    std::string err;
    std::unique_ptr<Conn> conn = SpawnLocal({exe, "--worker"}, &pid, &err);
    if (!conn) Die(exe + ": " + err);
    pool->Add(std::move(conn), "worker " + std::to_string(i) + " (pid " + std::to_string(pid) + ")");
  }
  if (UsePoolThread(-1, workers, cores)) {
    ThreadedPool threaded(std::move(pool), s.mesh);
    Trace trace = Record(s, o, &threaded);
    threaded.Shutdown();
    return trace;
  }
  Trace trace = Record(s, o, pool.get());
  pool->Shutdown();
  return trace;
}

Trace SimRun(const SceneData& s, int res, SimOptions so, long shots) {
  const RunOptions o = Options(res, shots);
  so.resolution = o.resolution;
  so.rotate = o.rotate;
  so.seed = o.seed;
  SimTransport sim(s.mesh, so);
  Trace t = Record(s, o, &sim);
  t.sim_master_s = sim.MasterSeconds();
  return t;
}

// Bytes the master sends each worker before the first shot (hello and
// scene): left out of the bytes per shot.
uint64_t SetupBytes(const SceneData& s, int res) {
  std::string f;
  proto::EncodeHello(proto::Hello(), &f);
  proto::EncodeScene(Setup(s, Options(res, 1)), &f);
  return f.size();
}

// Replays the shots of traces of one scene and resolution for the RMS
// error after each, with the columns as the master had them (quantised by
// the wire format), cached: runs of any worker count shoot mostly the same
// (patch, k).
class Replayer {
 public:
  Replayer(const SceneData& s, int res, const std::vector<glm::dvec3>& ref)
      : s_(s), res_(res), ref_(ref), hemicube_(res) {}
  // [i]: relative RMS error after shot i + 1.
  std::vector<double> Rms(const Trace& t) {
    Solver solver(s_.mesh, true);
    std::vector<double> out;
    for (size_t i = 0; i < t.shot_at.size(); ++i) {
      solver.Shoot(t.shot[i].patch, Column(t.shot[i]));
      double rms, rel;
      RmsError(s_.scene, FaceRadiosity(s_.mesh, solver.radiosity()), ref_, &rms, &rel);
      out.push_back(rel);
    }
    CHECK(solver.radiosity() == t.b);  // the replay is the run
    return out;
  }

 private:
  const std::vector<FormFactor>& Column(const proto::Assignment& a) {
    auto it = cache_.find({a.patch, a.k});
    if (it != cache_.end()) return it->second;
    proto::Column c;
    c.patch = a.patch;
    c.k = a.k;
    ShotColumn(&hemicube_, s_.mesh, a.patch, a.Group(), a.k, true, 1, &c.ff);
    std::string frame, payload, err;
    proto::EncodeColumn(c, &frame);
    proto::FrameReader reader;
    reader.Append(frame.data(), frame.size());
    proto::Msg type;
    CHECK(reader.Next(&type, &payload, &err) == proto::FrameReader::kFrame);
    CHECK(proto::DecodeColumn(payload, &c, &err));
    return cache_[{a.patch, a.k}] = std::move(c.ff);
  }

  const SceneData& s_;
  int res_;
  const std::vector<glm::dvec3>& ref_;
  Hemicube hemicube_;
  std::map<std::pair<int, int>, std::vector<FormFactor>> cache_;
};

const std::string kCache = "bench/results/tmp";

double MTime(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 ? double(st.st_mtime) : -1;
}

// The converged answer (overshooting to epsilon 1e-6, as bench.cpp's),
// kept while newer than this program and the scene.
std::vector<glm::dvec3> Reference(const SceneData& s, int res) {
  const std::string path = kCache + "/ref-" + s.name + "-" + std::to_string(res) + ".csv";
  const double t = MTime(path);
  std::vector<glm::dvec3> ref;
  std::string err;
  if (t > MTime(SelfExe()) && t > MTime(s.path) &&
      t > MTime(s.path.substr(0, s.path.size() - 3) + "mtl") &&
      ReadReference(path, s.scene, &ref, &err))
    return ref;
  RunOptions o;
  o.resolution = res;
  o.epsilon = 1e-6;
  Mesh mesh = s.mesh;
  Solver solver(mesh, true);
  RunSequential(&mesh, o, &solver, nullptr, nullptr);
  ref = FaceRadiosity(mesh, solver.radiosity());
  if (!WriteResultCsv(path, s.scene, ref, &err)) Die(err);
  return ref;
}

std::FILE* OpenCsv(const std::string& path, const char* header) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) Die(path + ": " + std::strerror(errno));
  std::fprintf(f, "%s\n", header);
  return f;
}

void CloseCsv(std::FILE* f, const std::string& path) {
  if (std::fclose(f) != 0) Die(path + ": " + std::strerror(errno));
}

void Svg(bool ok, const std::string& err) {
  if (!ok) Die(err);
}

struct Config {
  std::string exe, out;
  int repeat = 3;
  bool quick = false;
  bool validation = false;  // this machine's rows alone: the validation
  int cores = 2;  // this machine's, shared by the master and the real workers
  // Real worker counts: 1, 2, 4, ... below cores, then cores.
  std::vector<int> RealCounts() const {
    std::vector<int> n;
    for (int k = 1; k < cores; k *= 2) n.push_back(k);
    n.push_back(cores);
    return n;
  }
};

// ---------------------------------------------------------------------------
// Graphs 1 and 2: the master's time, and its ratio to a worker's.

struct MasterRow {
  std::string scene;
  int res;
  double distribute, receive, shoot, subdivide;  // CPU s for the first 250 shots
  double worker;                                 // CPU s per column
  double bytes;                                  // per column, received
  long shots;
  double Master() const { return (distribute + receive + shoot + subdivide) / double(shots); }
};

std::vector<MasterRow> MasterTimes(const Config& c, const std::vector<SceneData>& scenes,
                                   const std::vector<int>& resolutions) {
  constexpr long kShots = 250;
  std::vector<MasterRow> rows;
  std::printf("Graphs 1-2: the master's CPU time per shot (real runs, 1 worker process, first "
              "%ld shots; the run with the least master time of %d)\n",
              kShots, c.repeat);
  std::printf("| scene | R | distribute us | receive us | shoot us | subdivide us | master us/shot "
              "| worker us/column | master/worker | max speedup | bytes/column |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const SceneData& s : scenes)
    for (int res : resolutions) {
      MasterRow best{};
      double worker = HUGE_VAL;
      for (int i = 0; i < c.repeat; ++i) {
        const Trace t = RealRun(s, res, 1, kShots, c.exe, c.cores);
        const RunResult& r = t.r;
        MasterRow row{s.name, res, r.distribute_s, r.receive_s, r.shoot_s, r.subdivide_s,
                      r.worker_s / double(r.columns),
                      double(r.bytes_received) / double(r.columns), r.shots};
        if (i == 0 || row.Master() < best.Master()) best = row;
        worker = std::min(worker, row.worker);
      }
      best.worker = worker;
      const double n = 1e6 / double(best.shots);
      std::printf("| %s | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.0f | %.4f | %.1f | %.0f |\n",
                  s.name.c_str(), res, best.distribute * n, best.receive * n, best.shoot * n,
                  best.subdivide * n, 1e6 * best.Master(), 1e6 * best.worker,
                  best.Master() / best.worker, best.worker / best.Master(), best.bytes);
      std::fflush(stdout);
      rows.push_back(best);
    }
  std::printf("\n");

  const std::string p2 = c.out + "/graph2_ratio.csv";
  std::FILE* f = OpenCsv(p2, "scene,R,distribute_us,receive_us,shoot_us,subdivide_us,"
                             "master_us_per_shot,worker_us_per_column,master_worker_ratio,"
                             "max_speedup,bytes_per_column");
  for (const MasterRow& r : rows) {
    const double n = 1e6 / double(r.shots);
    std::fprintf(f, "%s,%d,%.2f,%.2f,%.2f,%.2f,%.2f,%.1f,%.5f,%.2f,%.0f\n", r.scene.c_str(),
                 r.res, r.distribute * n, r.receive * n, r.shoot * n, r.subdivide * n,
                 1e6 * r.Master(), 1e6 * r.worker, r.Master() / r.worker, r.worker / r.Master(),
                 r.bytes);
  }
  CloseCsv(f, p2);

  // Graph 1 at R = 256 (the default), or the largest resolution measured.
  const int g1 = std::count(resolutions.begin(), resolutions.end(), 256) ? 256 : resolutions.back();
  const std::string p1 = c.out + "/graph1_master.csv";
  f = OpenCsv(p1, "scene,R,shots,distribution_ms,shooting_ms,subdivision_ms");
  std::vector<std::string> groups;
  std::vector<std::vector<double>> bars;
  double top = 0;
  for (const MasterRow& r : rows) {
    if (r.res != g1) continue;
    std::fprintf(f, "%s,%d,%ld,%.3f,%.3f,%.3f\n", r.scene.c_str(), r.res, r.shots,
                 1e3 * (r.distribute + r.receive), 1e3 * r.shoot, 1e3 * r.subdivide);
    groups.push_back(r.scene);
    bars.push_back({1e3 * (r.distribute + r.receive), 1e3 * r.shoot, 1e3 * r.subdivide});
    top = std::max(top, bars.back()[0] + bars.back()[1] + bars.back()[2]);
  }
  CloseCsv(f, p1);
  std::string err;
  const double step = top > 20 ? 5 : top > 8 ? 2 : 1;
  Axis y{"master CPU ms, first 250 shots", {}, false};
  for (double v = 0; v < top + step; v += step) y.ticks.push_back(v);
  Svg(WriteStackedBars(c.out + "/graph1_master.svg",
                       "Graph 1: master time, first 250 shots (R " + std::to_string(g1) + ")", y,
                       groups, {"work distribution", "shooting", "subdivision"}, bars, &err),
      err);

  std::vector<Series> series;
  double hi = 1;
  for (const SceneData& s : scenes) {
    Series se{s.name, {}, {}, false, true};
    for (const MasterRow& r : rows)
      if (r.scene == s.name) {
        se.x.push_back(r.res);
        se.y.push_back(r.worker / r.Master());
        hi = std::max(hi, se.y.back());
      }
    series.push_back(se);
  }
  Axis ya{"maximum speedup = worker time / master time", {1}, true};
  while (ya.ticks.back() <= std::max(hi, 100.0)) ya.ticks.push_back(ya.ticks.back() * 10);
  Axis xa{"hemicube resolution R", {}, true};
  for (int r : resolutions) xa.ticks.push_back(r);
  series.push_back({"target: room at 256", {256}, {100}, false, false});
  Svg(WriteLineChart(c.out + "/graph2_speedup_limit.svg",
                     "Graph 2: maximum possible speedup (real runs, 1 worker)", xa, ya, series,
                     &err),
      err);
  return rows;
}

// ---------------------------------------------------------------------------
// Graphs 3-5: speedup and efficiency, by shots and by RMS error.

constexpr long kShots = 500;

struct Net {
  std::string name, tag;  // for tables; for file names
  SimOptions model;
  bool real;              // this machine: real runs to compare with
};

SimOptions Link(double bps, double latency_s, int host_cores, double wakeup_s,
                const SimOptions::Io& io) {
  SimOptions o;
  o.bandwidth_bps = bps;
  o.latency_s = latency_s;
  o.host_cores = host_cores;
  o.wakeup_s = wakeup_s;
  o.io = io;
  return o;
}

struct Point {
  std::string scene, net;
  int res, workers;
  bool real;
  double t_shots = NAN, t_rms = NAN;  // seconds to 500 shots, to the RMS target
  long shots_rms = -1;                // shots to the RMS target
  double speedup_shots = NAN, speedup_rms = NAN;
  double bytes = NAN;                 // per shot, both ways, start-up left out
  double master_us = NAN;             // per shot: measured (real) or charged (simulation)
  long stalled = -1;                  // a run stopped making progress after this many shots
  double Eff(double speedup) const { return speedup / workers; }
};

// Runs until 500 shots and the RMS target are both reached (or a cap), the
// quickest of `repeat` runs for each.
template <typename RunFn>
Point Measure(const std::string& scene, const std::string& net, int res, int workers, bool real,
              int repeat, double target, Replayer* replay, uint64_t setup_bytes, RunFn run,
              double* rms_at_500) {
  Point p{scene, net, res, workers, real};
  for (int i = 0; i < repeat; ++i) {
    Trace t;
    std::vector<double> rms;
    for (long cap = target > 0 ? 2 * kShots : kShots;; cap *= 4) {
      t = run(cap);
      rms = replay->Rms(t);
      if (t.stalled || target <= 0 || rms.back() <= target || cap >= 8 * kShots) break;
    }
    if (t.stalled) p.stalled = t.r.shots;
    if (t.r.shots < kShots) continue;
    const double ts = t.Until(kShots);
    if (std::isnan(p.t_shots) || ts < p.t_shots) {
      p.t_shots = ts;
      if (rms_at_500) *rms_at_500 = rms[kShots - 1];
      const double per = 1e6 / double(t.r.shots);
      p.master_us = real ? (t.r.distribute_s + t.r.receive_s + t.r.shoot_s + t.r.subdivide_s) * per
                         : t.sim_master_s * per;
      p.bytes = double(t.r.bytes_sent + t.r.bytes_received - setup_bytes * workers) /
                double(t.r.shots);
    }
    const double goal = target > 0 ? target : rms[kShots - 1];
    for (size_t k = 0; k < rms.size(); ++k)
      if (rms[k] <= goal) {
        if (std::isnan(p.t_rms) || t.Until(k + 1) < p.t_rms) {
          p.t_rms = t.Until(k + 1);
          p.shots_rms = long(k + 1);
        }
        break;
      }
  }
  return p;
}

std::string Fmt(double v, const char* f = "%.2f") {
  if (!std::isfinite(v)) return "n/a";
  char buf[32];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string Note(const Point& p) {
  return p.stalled < 0 ? "" : "stalled after " + std::to_string(p.stalled) + " shots";
}

void SpeedupGraphs(const Config& c, const std::vector<Point>& pts, const Net& net,
                   const std::vector<int>& counts) {
  std::string err;
  Axis xa{"workers", {}, true};
  for (int n : net.real ? c.RealCounts() : counts) xa.ticks.push_back(n);
  if (xa.ticks.size() < 2) xa.ticks.push_back(2);  // one core: the axis still needs two ends
  std::vector<Series> sp, eff, rms;
  double hi = 1;
  for (const Point& p : pts)
    if (p.net == net.name) hi = std::max(hi, p.speedup_shots);
  if (!net.real) sp.push_back({"ideal", {xa.ticks.front(), xa.ticks.back()},
                               {xa.ticks.front(), xa.ticks.back()}, true, true});
  // Appends (x, y) to the series called `name`, made on first use.
  auto add = [](std::vector<Series>* v, const std::string& name, bool dashed, bool line,
                double x, double y) {
    auto it = std::find_if(v->begin(), v->end(), [&](const Series& s) { return s.name == name; });
    if (it == v->end()) it = v->insert(v->end(), Series{name, {}, {}, dashed, line});
    it->x.push_back(x);
    it->y.push_back(y);
  };
  for (const Point& p : pts) {
    if (p.net != net.name) continue;
    const std::string what =
        p.scene + " R " + std::to_string(p.res) + (net.real ? p.real ? " real" : " sim" : "");
    const bool line = !net.real || !p.real;
    add(&sp, what, false, line, p.workers, p.speedup_shots);
    add(&eff, what, false, line, p.workers, p.Eff(p.speedup_shots));
    add(&rms, what + " by shots", false, line, p.workers, p.Eff(p.speedup_shots));
    add(&rms, what + " by RMS", true, line, p.workers, p.Eff(p.speedup_rms));
  }
  Axis ya{"speedup (time for 500 shots)", {1}, true};
  while (ya.ticks.back() < hi) ya.ticks.push_back(ya.ticks.back() * 2);
  Axis ye{"efficiency", {0, 0.25, 0.5, 0.75, 1, 1.25}, false};
  const std::string on = " (" + net.name + ")";
  Svg(WriteLineChart(c.out + "/graph3_speedup_" + net.tag + ".svg", "Graph 3: speedup" + on, xa,
                     ya, sp, &err),
      err);
  Svg(WriteLineChart(c.out + "/graph4_efficiency_" + net.tag + ".svg",
                     "Graph 4: efficiency by shots" + on, xa, ye, eff, &err),
      err);
  Svg(WriteLineChart(c.out + "/graph5_efficiency_rms_" + net.tag + ".svg",
                     "Graph 5: efficiency by shots and by RMS error" + on, xa, ye, rms, &err),
      err);
}

struct Targets {
  std::vector<std::string> lines;
  void Add(bool met, const std::string& what) {
    lines.push_back(std::string(met ? "MET     " : "MISSED  ") + what);
  }
};

// `validate`: scenes run on this machine only, real and simulated, for
// the validation table (the issue asks it of every shipped scene; the
// speedup tables are the room's and the maze's).
std::vector<Point> Speedups(const Config& c, const std::vector<SceneData>& scenes,
                            const std::vector<SceneData>& validate,
                            const std::vector<int>& resolutions, const std::vector<Net>& nets,
                            const std::vector<int>& counts, Targets* targets) {
  std::vector<Point> pts;
  std::printf("Graphs 3-5: speedup and efficiency by shots (time for %ld shots) and by RMS error "
              "(time to the RMS error 1 worker has after %ld shots); on this machine: the quickest "
              "of %d\n",
              kShots, kShots, c.repeat);
  std::printf("| scene | R | network | workers | kind | s to %ld shots | speedup | efficiency "
              "| target RMS | s to RMS | shots to RMS | speedup | efficiency | bytes/shot "
              "| master us/shot | note |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
              kShots);
  std::string startup;  // printed after the table
  std::vector<const SceneData*> all;
  for (const SceneData& s : scenes) all.push_back(&s);
  for (const SceneData& s : validate) all.push_back(&s);
  for (size_t si = 0; si < all.size(); ++si)
    for (int res : resolutions) {
      const SceneData& s = *all[si];
      const bool local_only = si >= scenes.size();
      const std::vector<glm::dvec3> ref = Reference(s, res);
      Replayer replay(s, res, ref);
      const uint64_t setup = SetupBytes(s, res);
      char line[200];
      std::snprintf(line, sizeof line, "  %s R %d: %.0f KB per worker;", s.name.c_str(), res,
                    double(setup) / 1e3);
      startup += line;
      for (const Net& net : nets)
        if (net.model.bandwidth_bps > 0 && !local_only) {
          std::snprintf(line, sizeof line, " %d workers on %s: %.3f s;", counts.back(),
                        net.name.c_str(),
                        counts.back() * 8.0 * double(setup) / net.model.bandwidth_bps);
          startup += line;
        }
      startup += "\n";
      for (const Net& net : nets)
        for (bool real : net.real ? std::vector<bool>{true, false} : std::vector<bool>{false}) {
          if (local_only && !net.real) continue;
          double target = 0;
          Point one{};
          for (int n : net.real ? c.RealCounts() : counts) {
            auto run = [&](long cap) {
              if (real) return RealRun(s, res, n, cap, c.exe, c.cores);
              SimOptions o = net.model;
              o.workers = n;
              // On this machine as the program would run (RealRun); a
              // cluster's master has its cores to itself.
              o.pool_thread = o.host_cores == 0 || UsePoolThread(-1, n, o.host_cores);
              return SimRun(s, res, o, cap);
            };
            Point p = Measure(s.name, net.name, res, n, real, net.real ? c.repeat : 1, target,
                              &replay, real ? setup : 0, run, n == 1 ? &target : nullptr);
            if (n == 1) one = p;
            p.speedup_shots = one.t_shots / p.t_shots;
            p.speedup_rms = one.t_rms / p.t_rms;
            std::printf("| %s | %d | %s | %d | %s | %s | %s | %s | %.4f%% | %s | %ld | %s | "
                        "%s | %s | %s | %s |\n",
                        s.name.c_str(), res, net.name.c_str(), n, real ? "real" : "sim",
                        Fmt(p.t_shots, "%.4f").c_str(), Fmt(p.speedup_shots).c_str(),
                        Fmt(p.Eff(p.speedup_shots), "%.3f").c_str(), 100 * target,
                        Fmt(p.t_rms, "%.4f").c_str(), p.shots_rms,
                        Fmt(p.speedup_rms).c_str(), Fmt(p.Eff(p.speedup_rms), "%.3f").c_str(),
                        Fmt(p.bytes, "%.0f").c_str(), Fmt(p.master_us, "%.1f").c_str(),
                        Note(p).c_str());
            std::fflush(stdout);
            pts.push_back(p);
          }
        }
    }
  std::printf("\nStart-up, left out above: the scene sent to the workers one after another\n%s\n",
              startup.c_str());

  const std::string path = c.out + "/speedup.csv";
  std::FILE* f = OpenCsv(path, "scene,R,network,workers,kind,seconds_500_shots,speedup_shots,"
                               "efficiency_shots,seconds_to_rms,shots_to_rms,speedup_rms,"
                               "efficiency_rms,bytes_per_shot,master_us_per_shot,note");
  for (const Point& p : pts)
    std::fprintf(f, "%s,%d,%s,%d,%s,%s,%s,%s,%s,%ld,%s,%s,%s,%s,%s\n", p.scene.c_str(), p.res,
                 p.net.c_str(), p.workers, p.real ? "real" : "sim",
                 Fmt(p.t_shots, "%.6f").c_str(), Fmt(p.speedup_shots, "%.4f").c_str(),
                 Fmt(p.Eff(p.speedup_shots), "%.4f").c_str(), Fmt(p.t_rms, "%.6f").c_str(),
                 p.shots_rms, Fmt(p.speedup_rms, "%.4f").c_str(),
                 Fmt(p.Eff(p.speedup_rms), "%.4f").c_str(), Fmt(p.bytes, "%.1f").c_str(),
                 Fmt(p.master_us, "%.2f").c_str(), Note(p).c_str());
  CloseCsv(f, path);
  for (const Net& net : nets) SpeedupGraphs(c, pts, net, counts);

  // Validation: the simulation of this machine against the real runs.
  std::printf("Validation: the simulation of this machine (%d cores shared by the master and the "
              "workers) against real runs\n"
              "| scene | R | workers | real s (%ld shots) | sim s | sim/real | real s (RMS) | "
              "sim s | sim/real | real master us/shot | sim master us/shot |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|\n",
              c.cores, kShots);
  const std::string vpath = c.out + "/validation.csv";
  f = OpenCsv(vpath, "scene,R,workers,real_s,sim_s,ratio_shots,real_rms_s,sim_rms_s,ratio_rms,"
                     "real_master_us,sim_master_us");
  double worst = 0;
  for (const Point& r : pts) {
    if (!r.real) continue;
    for (const Point& m : pts) {
      if (m.real || m.net != r.net || m.scene != r.scene || m.res != r.res ||
          m.workers != r.workers)
        continue;
      const double a = m.t_shots / r.t_shots, b = m.t_rms / r.t_rms;
      worst = std::max({worst, std::isfinite(a) ? std::abs(a - 1) : HUGE_VAL,
                        std::isfinite(b) ? std::abs(b - 1) : HUGE_VAL});
      std::printf("| %s | %d | %d | %s | %s | %s | %s | %s | %s | %.1f | %.1f |\n",
                  r.scene.c_str(), r.res, r.workers, Fmt(r.t_shots, "%.4f").c_str(),
                  Fmt(m.t_shots, "%.4f").c_str(), Fmt(a, "%.3f").c_str(),
                  Fmt(r.t_rms, "%.4f").c_str(), Fmt(m.t_rms, "%.4f").c_str(),
                  Fmt(b, "%.3f").c_str(), r.master_us, m.master_us);
      std::fprintf(f, "%s,%d,%d,%s,%s,%s,%s,%s,%s,%.2f,%.2f\n", r.scene.c_str(), r.res,
                   r.workers, Fmt(r.t_shots, "%.6f").c_str(), Fmt(m.t_shots, "%.6f").c_str(),
                   Fmt(a, "%.4f").c_str(), Fmt(r.t_rms, "%.6f").c_str(),
                   Fmt(m.t_rms, "%.6f").c_str(), Fmt(b, "%.4f").c_str(), r.master_us,
                   m.master_us);
    }
  }
  CloseCsv(f, vpath);
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "simulation within 15%% of the real runs, 1 to %d workers (worst: %.1f%%)",
                c.cores, 100 * worst);
  targets->Add(worst <= 0.15, buf);
  std::printf("\n");
  return pts;
}

// Where efficiency first falls below 0.5, per network (and scene, R).
void HalfEfficiency(const std::vector<Point>& pts, const std::vector<Net>& nets) {
  std::printf("Efficiency below 0.5 (simulation): first worker count tested\n"
              "| network | scene | R | by shots | by RMS |\n|---|---|---|---|---|\n");
  for (const Net& net : nets) {
    if (net.real) continue;
    std::map<std::pair<std::string, int>, std::pair<int, int>> first;
    for (const Point& p : pts) {
      if (p.net != net.name) continue;
      auto& f = first.try_emplace({p.scene, p.res}, 0, 0).first->second;
      if (!f.first && !(p.Eff(p.speedup_shots) >= 0.5)) f.first = p.workers;
      if (!f.second && !(p.Eff(p.speedup_rms) >= 0.5)) f.second = p.workers;
    }
    for (const auto& [k, v] : first)
      std::printf("| %s | %s | %d | %s | %s |\n", net.name.c_str(), k.first.c_str(), k.second,
                  v.first ? std::to_string(v.first).c_str() : "never",
                  v.second ? std::to_string(v.second).c_str() : "never");
  }
  std::printf("\n");
}

void SpeedupTargets(const std::vector<Point>& pts, Targets* t) {
  char buf[300];
  for (const Point& p : pts) {
    const double es = p.Eff(p.speedup_shots), er = p.Eff(p.speedup_rms);
    const std::string where = p.scene + " R " + std::to_string(p.res) + ", " + p.net;
    if (p.real && p.workers == 2) {
      std::snprintf(buf, sizeof buf, "efficiency by shots >= 0.9 with 2 real workers: %.3f (%s)",
                    es, where.c_str());
      t->Add(es >= 0.9, buf);
    }
    if (p.real || p.net == "this machine") continue;
    if (p.workers == 8) {
      std::snprintf(buf, sizeof buf, "simulated efficiency by shots >= 0.9 at 8: %.3f (%s)", es,
                    where.c_str());
      t->Add(es >= 0.9, buf);
    }
    if (p.workers == 15) {
      std::snprintf(buf, sizeof buf,
                    "simulated efficiency at 15 >= 0.85 by shots: %.3f, >= 0.75 by RMS: %s (%s)",
                    es, Fmt(er, "%.3f").c_str(), where.c_str());
      t->Add(es >= 0.85 && er >= 0.75, buf);
    }
    // Issue 17: the room at R 256 on 1 Gbit/s, 0.8 at 64 and 0.6 at 100.
    if (p.scene == "room" && p.res == 256 && p.net == "1 Gbit/s" &&
        (p.workers == 64 || p.workers == 100)) {
      const double want = p.workers == 64 ? 0.8 : 0.6;
      std::snprintf(buf, sizeof buf, "simulated efficiency by shots >= %.1f at %d: %.3f (%s)",
                    want, p.workers, es, where.c_str());
      t->Add(es >= want, buf);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Config c;
  int a = 1;
  for (; a < argc && argv[a][0] == '-'; ++a) {
    if (!std::strcmp(argv[a], "--quick")) c.quick = true;
    else if (!std::strcmp(argv[a], "--validation")) c.validation = true;
    else if (!std::strcmp(argv[a], "--repeat") && a + 1 < argc) c.repeat = std::max(1, std::atoi(argv[++a]));
    else if (!std::strcmp(argv[a], "--cores") && a + 1 < argc) c.cores = std::clamp(std::atoi(argv[++a]), 1, 256);
    else break;
  }
  if (argc - a != 2) {
    std::fprintf(stderr,
                 "usage: radiosity-parallel [--repeat N] [--quick | --validation] [--cores N] RADIOSITY OUT_DIR\n");
    return 2;
  }
  c.exe = argv[a];
  c.out = argv[a + 1];
  if (c.exe.find('/') == std::string::npos) c.exe = "./" + c.exe;
  for (const std::string& dir : {std::string("bench/results"), kCache, c.out})
    if (mkdir(dir.c_str(), 0777) != 0 && errno != EEXIST) Die(dir + ": " + std::strerror(errno));
  std::signal(SIGPIPE, SIG_IGN);  // a dead worker is an error on its connection

  const SceneData room = Load("room"), maze = Load("maze"), cornell = Load("cornell");
  Targets targets;
  const std::vector<MasterRow> master =
      c.validation ? std::vector<MasterRow>()
                   : MasterTimes(c, {room, maze, cornell},
                                 c.quick ? std::vector<int>{64, 256}
                                         : std::vector<int>{64, 128, 256, 512});
  for (const MasterRow& r : master)
    if (r.scene == "room" && r.res == 256) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "maximum possible speedup on room at R 256 > 100: %.1f",
                    r.worker / r.Master());
      targets.Add(r.worker / r.Master() > 100, buf);
    }

  // This machine: --cores cores (default 2) for the master and the
  // workers, a socketpair between them (latency: a wake-up through poll;
  // copying is the CPU's).
  // The simulated master pays this machine's wake-up when it slept (a
  // master with one or two workers sleeps between columns; a busy one
  // does not).
  // And the system calls of a master that does not sleep: the simulated
  // one reads and writes no sockets.
  const double wake = MeasureWakeup();
  const SimOptions::Io io = MeasureIo();
  std::printf("A wake-up (poll(2) woken by a socket, beyond finding the byte there; thread CPU; "
              "simulations charge it): %.1f us\n",
              1e6 * wake);
  std::printf("System calls charged per Poll, per worker read, per worker written (epoll_wait, "
              "read of 2 KB, write of 24 bytes): %.2f, %.2f, %.2f us; a worker's per column "
              "(poll, read, write of 2 KB, its CPU clock twice): %.2f us; a write more when it "
              "wakes its reader: %.2f us\n\n",
              1e6 * io.epoll_s, 1e6 * io.read_s, 1e6 * io.write_s, 1e6 * io.column_s,
              1e6 * io.wake_s);
  std::vector<Net> nets = {
      {"this machine", "local", Link(0, 20e-6, c.cores, wake, io), true},
      {"10 Gbit/s", "10gbit", Link(10e9, 20e-6, 0, wake, io), false},
      {"1 Gbit/s", "1gbit", Link(1e9, 50e-6, 0, wake, io), false},
      {"10 Mbit/s", "10mbit", Link(10e6, 200e-6, 0, wake, io), false},
  };
  if (c.validation) nets.resize(1);
  const std::vector<int> counts = c.quick ? std::vector<int>{1, 2, 8, 15, 100}
                                          : std::vector<int>{1, 2, 4, 8, 15, 32, 64, 100, 128};
  std::vector<SceneData> validate;
  if (!c.quick)
    for (const char* name : {"cornell", "blender", "cornell-holes"}) validate.push_back(Load(name));
  const std::vector<Point> pts =
      Speedups(c, c.quick ? std::vector<SceneData>{room} : std::vector<SceneData>{room, maze},
               validate, {64, 256}, nets, counts, &targets);
  if (c.validation) return 0;
  HalfEfficiency(pts, nets);
  SpeedupTargets(pts, &targets);
  std::printf("Targets (issues 4 and 17)\n");
  for (const std::string& l : targets.lines) std::printf("  %s\n", l.c_str());
  return 0;
}
