#include "app.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "clock.h"
#include "connect.h"
#include "errorchart.h"
#include "groups.h"
#include "hosts.h"
#include "inprocess.h"
#include "pool.h"
#include "ssh.h"
#include "worker.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;

void OnSignal(int sig) {
  if (g_stop) {  // a second signal: leave at once
    std::signal(sig, SIG_DFL);
    std::raise(sig);
  }
  g_stop = 1;
}

[[noreturn]] void Die(int status, const std::string& msg) {
  std::fprintf(stderr, "radiosity: %s\n", msg.c_str());
  std::exit(status);
}

bool MakeDirs(const std::string& path, std::string* err) {
  for (size_t i = 1; i <= path.size(); ++i) {
    if (i < path.size() && path[i] != '/') continue;
    std::string part = path.substr(0, i);
    if (mkdir(part.c_str(), 0777) != 0 && errno != EEXIST) {
      *err = part + ": " + std::strerror(errno);
      return false;
    }
  }
  struct stat st;
  if (stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    *err = path + ": not a directory";
    return false;
  }
  return true;
}

}  // namespace

ExitStatus DumpHosts(const Options& opts) {
  for (const HostSpec& h : opts.hosts) std::printf("%s\n", FormatHost(h).c_str());
  return kExitOk;
}

ExitStatus WorkerMain(const Options& opts) {
  std::string err;
  int in = 0, out = 1;
  if (!opts.connect_host.empty()) {
    in = out = ConnectBack(opts.connect_host, opts.connect_port, opts.secret, &err);
    if (in < 0) Die(kExitFailure, "worker: " + err);
  }
  const int status = RunWorker(in, out, &err);
  if (status != kExitOk) std::fprintf(stderr, "radiosity: worker: %s\n", err.c_str());
  return ExitStatus(status);
}

MasterRun::MasterRun(const Options& opts) : opts_(opts), run_(opts.run) {}

MasterRun::~MasterRun() = default;

void MasterRun::Build() {
  std::string err;
  std::vector<std::string> warnings;
  const bool loaded = LoadScene(opts_.scene_path, &scene_, &err, &warnings);
  for (const std::string& w : warnings) std::fprintf(stderr, "radiosity: warning: %s\n", w.c_str());
  if (!loaded) Die(kExitUsage, err);

  camera_ = scene_.has_camera ? scene_.camera : FrameBox(scene_.lo, scene_.hi);
  if (!opts_.camera_text.empty() && !ParseCamera(opts_.camera_text, &camera_, &err))
    Die(kExitUsage, "--camera '" + opts_.camera_text + "': " + err);

  if (!opts_.reference.empty() && !ReadReference(opts_.reference, scene_, &ref_, &err))
    Die(kExitUsage, err);

  if (!BuildMesh(scene_, opts_.mesh, &mesh_, &err)) Die(kExitUsage, opts_.scene_path + ": " + err);
  if (opts_.verbosity >= 2)
    std::fprintf(stderr, "radiosity: %zu faces, %zu patches, %zu elements (patch size %g)\n",
                 scene_.faces.size(), mesh_.patches.size(), mesh_.elems.size(), mesh_.patch_size);

  // A checkpoint to resume is checked before anything is started; one to
  // write must be writable before the run starts.
  const SolveOptions solve{run_.overshoot, run_.resolution, run_.rotate, run_.seed,
                           run_.log_every,  opts_.mesh,     opts_.subdivide, opts_.sub};
  identity_ = Identify(scene_, mesh_, solve);
  if (!opts_.resume_file.empty()) {
    if (!ReadCheckpoint(opts_.resume_file, &resume_, &err)) Die(kExitUsage, err);
    if (!CheckIdentity(resume_, identity_, &err)) Die(kExitUsage, opts_.resume_file + ": " + err);
  }
  if (!opts_.checkpoint_file.empty()) {
    const std::string tmp = opts_.checkpoint_file + ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) Die(kExitFailure, "--checkpoint: " + tmp + ": " + std::strerror(errno));
    ::close(fd);
    ::unlink(tmp.c_str());
  }

  if (!MakeDirs(opts_.out_dir, &err)) Die(kExitFailure, err);
  if (!log_.Open(opts_.out_dir + "/log.csv", &err)) Die(kExitFailure, err);
  if (!opts_.resume_file.empty()) log_.Restore(resume_.log);

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  run_.stop = &g_stop;
  solver_ = std::make_unique<Solver>(mesh_, run_.overshoot);
  // Progress: a line redrawn in place on a terminal, else a line every 2 s
  // (a log file or a batch system's output should not fill with \r).
  const bool terminal = isatty(2);
  progress_ = std::make_unique<Progress>(
      [](const std::string& text) { std::fputs(text.c_str(), stderr); }, terminal, run_.epsilon,
      terminal ? 0.25 : 2.0);
  if (solver_->Dark())  // a legal scene, but most likely a missing Ke
    std::fprintf(stderr, "radiosity: warning: %s: no face emits light (Ke); every B is 0\n",
                 opts_.scene_path.c_str());
  run_.wave_end = [this](int wave) {
    Picture({FrameName(wave)});
    if (opts_.verbosity >= 2)
      std::fprintf(stderr, "radiosity: wave %d ends: %ld elements\n", wave, mesh_.LeafCount());
  };
  if (opts_.subdivide) subdivider_ = std::make_unique<Subdivider>(&mesh_, opts_.sub);
  built_ = mesh_.LeafCount();
  StartWorkers();
  if (!opts_.resume_file.empty()) Resume();
  if (!opts_.checkpoint_file.empty()) {
    run_.checkpoint_every = opts_.checkpoint_every;
    run_.checkpoint = [this](const RunState& state) { SaveCheckpoint(state); };
  }
}

void MasterRun::StartWorkers() {
  // The master itself: alone with -j 0, and when every worker is lost.
  run_.fallback = [this] {
    return std::make_unique<InProcessTransport>(mesh_, run_.resolution, run_.rotate, run_.seed);
  };
  if (opts_.workers == 0 && !opts_.Remote()) {
    transport_ = run_.fallback();
    return;
  }
  std::string err;
  std::signal(SIGPIPE, SIG_IGN);  // a dead worker is an error on its connection
  proto::SceneSetup setup{scene_, opts_.mesh, run_.resolution, run_.rotate, run_.seed};
  auto pool = std::make_unique<WorkerPool>(std::move(setup), mesh_, opts_.pool);
  if (pool->SceneTooLarge())
    Die(kExitUsage, opts_.scene_path + ": too large to send to workers (protocol limit " +
                        std::to_string(proto::kMaxFrame >> 20) + " MiB); use -j 0");
  auto command = [&](const std::string& user_cmd) {
    return user_cmd.empty() ? std::vector<std::string>{SelfExe(), "--worker"}
                            : std::vector<std::string>{"/bin/sh", "-c", "exec " + user_cmd + " --worker"};
  };
  // -j workers, then the hosts file's localhost lines: forked here.
  std::vector<std::vector<std::string>> local(size_t(opts_.workers), command(opts_.worker_cmd));
  std::vector<HostSpec> ssh_hosts;
  for (const HostSpec& h : opts_.hosts) {
    if (!h.Local()) ssh_hosts.push_back(h);
    else local.insert(local.end(), size_t(h.slots), command(h.cmd.empty() ? opts_.worker_cmd : h.cmd));
  }
  for (size_t i = 0; i < local.size(); ++i) {
    pid_t pid = 0;
    std::unique_ptr<Conn> conn = SpawnLocal(local[i], &pid, &err);
    const std::string name = "local worker " + std::to_string(i + 1);
    if (conn)
      pool->Add(std::move(conn), name + " (pid " + std::to_string(pid) + ")");
    else
      std::fprintf(stderr, "radiosity: %s: %s\n", name.c_str(), err.c_str());
  }
  auto note = [this](const std::string& line, bool warning) { Note(line, warning); };
  if (!ssh_hosts.empty()) {
    SshOptions ssh = opts_.ssh;
    ssh.timeout_s = opts_.pool.timeout_s;
    pool->AddSource(StartSshHosts(ssh_hosts, ssh, note));
  }
  if (!opts_.listen.empty()) {
    std::string bound;
    std::unique_ptr<WorkerSource> listener =
        Listen(opts_.listen_host, opts_.listen_port, opts_.secret, note, &bound, &err);
    if (!listener) Die(kExitFailure, "--listen " + opts_.listen + ": " + err);
    if (opts_.verbosity >= 1)
      std::fprintf(stderr, "radiosity: listening for workers on %s\n", bound.c_str());
    pool->AddSource(std::move(listener));
  }
  transport_ = std::move(pool);
}

void MasterRun::Resume() {
  std::string err;
  // Workers got the mesh as built; the divisions follow the scene.
  if (!ApplyCheckpoint(resume_, &mesh_, solver_.get(), subdivider_.get(), &err))
    Die(kExitUsage, opts_.resume_file + ": " + err);
  transport_->Divide(resume_.edits);
  run_.resume = &resume_.run;
  if (opts_.verbosity >= 2)
    std::fprintf(stderr, "radiosity: resumed from %s: %ld shots, wave %d, %ld elements\n",
                 opts_.resume_file.c_str(), solver_->shots(), resume_.run.wave, mesh_.LeafCount());
}

void MasterRun::SaveCheckpoint(const RunState& state) {
  const double t0 = MonotonicSeconds();
  size_t bytes = 0;
  std::string err;
  const Checkpoint c =
      Capture(identity_, mesh_, *solver_, subdivider_.get(), state, log_.text());
  if (!WriteCheckpoint(opts_.checkpoint_file, c, &bytes, &err))
    std::fprintf(stderr, "radiosity: warning: checkpoint not written: %s\n", err.c_str());
  else if (opts_.verbosity >= 2)
    std::fprintf(stderr, "radiosity: checkpoint %s: %zu bytes at %ld shots in %.1f ms\n",
                 opts_.checkpoint_file.c_str(), bytes, solver_->shots(),
                 (MonotonicSeconds() - t0) * 1e3);
}

void MasterRun::OnSample(const Sample& s) {
  double rms = 0, rel = 0;
  const bool with_ref = !ref_.empty();
  if (with_ref) RmsError(scene_, FaceRadiosity(mesh_, solver_->radiosity()), ref_, &rms, &rel);
  log_.Row(s, with_ref ? &rms : nullptr, with_ref ? &rel : nullptr);
  if (opts_.verbosity == 1) progress_->Update(s, with_ref ? &rms : nullptr, with_ref ? &rel : nullptr);
  if (opts_.verbosity >= 2) {
    std::fprintf(stderr, "radiosity: %8.2f s %7ld shots  unshot %.3e", s.seconds, s.shots, s.unshot);
    if (with_ref) std::fprintf(stderr, "  rms %.3e (%.3f%%)", rms, 100 * rel);
    std::fputc('\n', stderr);
  }
}

// Workers joining, lost or skipped: above the progress line; -q keeps only
// the warnings.
void MasterRun::Note(const std::string& line, bool warning) {
  if (opts_.verbosity == 1) progress_->Note(line);
  else if (warning || opts_.verbosity >= 2) std::fprintf(stderr, "radiosity: %s\n", line.c_str());
}

std::string MasterRun::FrameName(int wave) const {
  char name[32];
  std::snprintf(name, sizeof name, "/frame-%02d.", wave);
  return opts_.out_dir + name + opts_.format;
}

// A picture of the solution as it stands: the end of a wave, the final one.
// The last wave's frame and final.png are the same picture: shaded and
// rendered once (on a 200,000-face scene each costs seconds).
std::pair<ShadedMesh, float> MasterRun::Picture(const std::vector<std::string>& paths) {
  std::string err;
  ShadedMesh shaded = Shade(mesh_, solver_->radiosity());
  Image img;
  Render(shaded, camera_, opts_.width, opts_.height, &img);
  const float exposure = AutoExposure(shaded);
  for (const std::string& path : paths)
    if (!WriteImage(img, exposure, path, opts_.format, &err)) Die(kExitFailure, err);
  return std::make_pair(std::move(shaded), exposure);
}

void MasterRun::Run() {
  result_ = RunMaster(&mesh_, run_, solver_.get(), subdivider_.get(), transport_.get(),
                      [this](const Sample& s) { OnSample(s); },
                      [this](const std::string& line, bool warning) { Note(line, warning); });
  transport_->Shutdown();
  progress_->Finish();
  const RunResult& r = result_;
  if (opts_.verbosity >= 2)
    std::fprintf(stderr,
                 "radiosity: master: %.3f s distributing, %.3f s receiving, %.3f s shooting, "
                 "%.3f s waiting; "
                 "workers: %d joined, %d lost, %ld columns in %.3f s, %ld stale; "
                 "%.0f bytes/shot sent, %.0f received\n",
                 r.distribute_s, r.receive_s, r.shoot_s, r.wait_s, r.joined, r.lost, r.columns,
                 r.worker_s, r.stale, double(r.bytes_sent) / std::max(1L, r.shots),
                 double(r.bytes_received) / std::max(1L, r.shots));
}

void MasterRun::WriteOutputs() {
  std::string err;
  const RunResult& r = result_;
  const std::string& out = opts_.out_dir;
  if (!log_.Close(&err)) Die(kExitFailure, err);
  // Drawn even when the run failed: how it went is what one wants to see.
  const std::string& scene_path = opts_.scene_path;
  const std::string scene_name = scene_path.substr(scene_path.rfind('/') + 1);
  if (!WriteErrorChart(out + "/error.svg", scene_name + ": error against run time", log_.rows(),
                       &err))
    Die(kExitFailure, err);
  if (r.status == RunStatus::kNoWorkers) Die(kExitFailure, r.why + "; no results written");
  if (r.status == RunStatus::kNotConverged)
    Die(kExitFailure, "did not converge after " + std::to_string(r.shots) + " shots: " + r.why +
                          "; no results written");

  const std::vector<glm::dvec3> face_b = FaceRadiosity(mesh_, solver_->radiosity());
  if (!WriteResultCsv(out + "/result.csv", scene_, face_b, &err)) Die(kExitFailure, err);
  const auto shaded = Picture({FrameName(r.waves), out + "/final." + opts_.format});
  if (opts_.verbosity >= 2)
    std::fprintf(stderr, "radiosity: wave %d ends: %ld elements\n", r.waves, mesh_.LeafCount());
  if (!WritePly(shaded.first, shaded.second, out + "/result.ply", &err) ||
      !WriteGltf(shaded.first, shaded.second, out + "/result.gltf", out + "/result.bin", &err))
    Die(kExitFailure, err);
  if (!opts_.converge.empty()) {
    // A reference must be converged: one cut short by -s, -t or a signal
    // would pass its own error on to every run measured against it.
    if (r.status != RunStatus::kConverged)
      Die(kExitFailure, "--converge " + opts_.converge + ": not written, the run did not converge (" +
                            (r.why.empty() ? std::string("stopped on request") : r.why) + ")");
    if (!WriteResultCsv(opts_.converge, scene_, face_b, &err)) Die(kExitFailure, err);
    if (opts_.verbosity >= 1)
      std::fprintf(stderr, "radiosity: reference (epsilon %g) in %s: use --reference %s\n",
                   run_.epsilon, opts_.converge.c_str(), opts_.converge.c_str());
  }

  if (subdivider_ && subdivider_->capped())
    std::fprintf(stderr, "radiosity: warning: subdivision stopped at %ld elements: the next "
                         "pass would pass the limit of %d\n", long(mesh_.elems.size()), kMaxElements);
  if (r.status == RunStatus::kLimit)  // said even with -q: these are not converged numbers
    std::fprintf(stderr,
                 "radiosity: warning: did not converge: %s with unshot energy %.3g of "
                 "emitted (epsilon %g)\n",
                 r.why.c_str(), r.unshot, run_.epsilon);
  if (opts_.verbosity >= 1) {
    const char* how = r.status == RunStatus::kConverged ? "converged"
                      : r.status == RunStatus::kStopped ? "stopped on request"
                                                        : r.why.c_str();
    std::fprintf(stderr,
                 "radiosity: %s: %ld shots in %.2f s, unshot %.3g of emitted; "
                 "%zu patches, %ld elements (%ld built; %d waves, %ld division passes "
                 "in %.3f s; %zu shooters, %zu of them groups); results in %s/\n",
                 how, r.shots, r.seconds, r.unshot, mesh_.patches.size(), mesh_.LeafCount(),
                 built_, r.waves, r.passes, r.subdivide_s, Shooters(mesh_), mesh_.groups.size(),
                 out.c_str());
  }
}
