#include "app.h"

#include <fcntl.h>
#include <sys/eventfd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include "clock.h"
#include "connect.h"
#include "errorchart.h"
#include "files.h"
#include "groups.h"
#include "hosts.h"
#include "inprocess.h"
#include "memory.h"
#include "pool.h"
#include "pool_thread.h"
#include "quiet_thread.h"
#include "ssh.h"
#include "surface.h"
#include "worker.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;  // the signal that stops the run
timespec g_stop_at;                      // when it came: set before g_stop

// Signals within this of the first are the same request: timeout(1)
// sends its signal to the program and then to its process group, so the
// program gets it twice microseconds apart (and left at once, exit 130,
// when the two did not merge). A person pressing Ctrl-C again is slower.
constexpr double kSameRequestS = 0.1;

// clock_gettime is async-signal-safe (POSIX.1-2008); MonotonicSeconds
// (std::chrono) is not promised to be.
double SinceStopS() {
  timespec now;
  clock_gettime(CLOCK_MONOTONIC, &now);
  return double(now.tv_sec - g_stop_at.tv_sec) + 1e-9 * double(now.tv_nsec - g_stop_at.tv_nsec);
}

void OnSignal(int sig) {
  if (g_stop) {
    if (SinceStopS() < kSameRequestS) return;
    std::signal(sig, SIG_DFL);  // a second request: leave at once
    std::raise(sig);
  }
  clock_gettime(CLOCK_MONOTONIC, &g_stop_at);
  g_stop = sig;
}

std::string StoppedBy() {
  const char* name = g_stop == SIGINT ? "SIGINT" : g_stop == SIGTERM ? "SIGTERM"
                     : g_stop == SIGHUP ? "SIGHUP" : nullptr;
  return name ? std::string("stopped on request (") + name + ")" : "stopped on request";
}

// The run's outputs not yet moved into place: removed when it dies,
// after the pictures being written into them.
Staging* g_staging = nullptr;
Writers* g_writers = nullptr;

void Say(const std::string& line) { std::fprintf(stderr, "radiosity: %s\n", Printable(line).c_str()); }

[[noreturn]] void Die(int status, const std::string& msg) {
  if (g_writers) g_writers->Wait();
  if (g_staging) g_staging->Discard();
  Say(msg);
  std::exit(status);
}

// The names of a run's outputs in its directory: what a run replaces, and
// removes when it did not write it this time (man page, FILES).
bool OutputName(const std::string& name) {
  static const char* const kNames[] = {"log.csv",    "error.svg",  "result.csv", "result.ply",
                                       "result.gltf", "result.bin", "final.png",  "final.ppm",
                                       "final.exr",   "final.hdr",  "view.html"};
  for (const char* n : kNames)
    if (name == n) return true;
  // frame-NN.png, .ppm or .exr, NN two or more digits
  const size_t dot = name.rfind('.');
  if (name.compare(0, 6, "frame-") != 0 || dot == std::string::npos || dot < 8) return false;
  const std::string ext = name.substr(dot);
  return (ext == ".png" || ext == ".ppm" || ext == ".exr") &&
         std::all_of(name.begin() + 6, name.begin() + long(dot), [](char c) { return c >= '0' && c <= '9'; });
}

// Whether PATH names NAME in directory DIR, by the directories' identity.
bool InDir(const std::string& path, const std::string& dir, std::string* name) {
  struct stat a, b;
  *name = path.substr(path.rfind('/') + 1);
  return ::stat(DirName(path).c_str(), &a) == 0 && ::stat(dir.c_str(), &b) == 0 &&
         a.st_dev == b.st_dev && a.st_ino == b.st_ino;
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

std::string Printable(const std::string& text) {
  std::string out;
  for (unsigned char c : text) {
    if (c >= 0x20 && c != 0x7f) {
      out += char(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    }
  }
  return out;
}

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
  if (status != kExitOk) Say("worker: " + err);
  return ExitStatus(status);
}

MasterRun::MasterRun(const Options& opts) : opts_(opts), run_(opts.run) {}

MasterRun::~MasterRun() {
  writers_.Wait();
  g_writers = nullptr;
  g_staging = nullptr;
}

void MasterRun::Build() {
  MapLargeArrays();
  std::string err;
  std::vector<std::string> warnings;
  // A closed stderr (piped into head, a gone terminal) is no reason to
  // lose the run: writes to it fail, the run goes on.
  std::signal(SIGPIPE, SIG_IGN);
  const double t0 = MonotonicSeconds();
  const bool loaded = LoadScene(opts_.scene_path, &scene_, &err, &warnings);
  for (const std::string& w : warnings) Say("warning: " + w);
  if (!loaded) Die(kExitUsage, err);
  // What the run reads, that nothing it writes may replace.
  auto input = [&](const std::string& what, const std::string& path) {
    if (!path.empty() && !AddInput(what, path, &inputs_, &err)) Die(kExitUsage, err);
  };
  for (const std::string& f : scene_.files)
    input(f == scene_.path ? "the scene" : "an MTL file of the scene", f);
  input("the --secret file", opts_.secret_file);
  input("the hosts file", opts_.hosts_file);

  camera_ = scene_.has_camera ? scene_.camera : FrameBox(scene_.lo, scene_.hi);
  if (!opts_.camera_text.empty() && !ParseCamera(opts_.camera_text, &camera_, &err))
    Die(kExitUsage, "--camera '" + opts_.camera_text + "': " + err);

  if (!opts_.reference.empty() && !ReadReference(opts_.reference, scene_, &ref_, &err))
    Die(kExitUsage, err);
  input("the --reference file", opts_.reference);

  double t1 = MonotonicSeconds();
  // Refused here rather than killed by the kernel later (and before any
  // worker is started); and subdivision stops (with its warning) where
  // the memory would run out.
  const double usable = UsableMemory();
  {
    // Joined once for the estimate and the mesh, and let go as they are
    // meshed: not beside the group search (FormGroups) at its end, where
    // they were 40 bytes an element of the master's peak with -j 1.
    std::vector<Surface> surfaces = BuildSurfaces(scene_, opts_.mesh.join);
    if (!FitsInMemory(EstimateMesh(scene_, surfaces, opts_.mesh).elements, kMasterBytesPerElement,
                      usable, &err))
      Die(kExitUsage, opts_.scene_path + ": " + err);
    sub_limit_ = std::min(opts_.sub.max_elements, long(usable / kMasterBytesPerElement));
    const double started = MonotonicSeconds();
    StartWorkers();  // its time is the scene frame's, said there
    t1 += MonotonicSeconds() - started;
    MeshScene(std::move(surfaces));
  }
  const double t2 = MonotonicSeconds();
  if (opts_.verbosity >= 2)
    std::fprintf(stderr,
                 "radiosity: %zu faces, %zu surfaces, %zu patches, %zu elements (patch size %g); "
                 "loaded in %.2f s, meshed in %.2f s\n",
                 scene_.faces.size(), mesh_.faces.size(), mesh_.patches.size(), mesh_.elems.size(),
                 mesh_.patch_size, t1 - t0, t2 - t1);

  // A checkpoint to resume is checked, and one to write must be writable,
  // before the run starts (the workers are meshing already: refused here,
  // the master exits and they see the connection end).
  const SolveOptions solve{run_.overshoot, run_.resolution, run_.rotate, run_.seed,
                           run_.log_every,  opts_.mesh,     opts_.subdivide, opts_.sub};
  identity_ = Identify(scene_, mesh_, solve);
  // The checkpoint may replace the one resumed from: that is how a run
  // goes on from its own checkpoints.
  std::vector<Input> ck_inputs = inputs_;
  if (!opts_.resume_file.empty()) {
    if (!ReadCheckpoint(opts_.resume_file, &resume_, &err)) Die(kExitUsage, err);
    if (!CheckIdentity(resume_, identity_, &err)) Die(kExitUsage, opts_.resume_file + ": " + err);
    input("the --resume checkpoint", opts_.resume_file);
  }
  CheckOutputs(ck_inputs);

  if (!staging_.Open(opts_.out_dir, &err)) Die(kExitFailure, err);
  g_staging = &staging_;
  g_writers = &writers_;
  if (!log_.Open(staging_.Path("log.csv"), &err)) Die(kExitFailure, err);
  if (!opts_.resume_file.empty()) log_.Restore(resume_.log);
  if (!opts_.view.empty()) {
    view_ = std::make_unique<ViewServer>(ViewOf(), log_.rows());
    std::string bound;
    if (!view_->Start(opts_.view_host, opts_.view_port, &bound, &err))
      Die(kExitFailure, "--view " + opts_.view + ": " + err);
    // Said even with -q, as --listen's address is: with port 0 it is news.
    std::fprintf(stderr, "radiosity: view on http://%s/\n", bound.c_str());
  }

  // A closed terminal or ssh session (SIGHUP) stops the run as Ctrl-C does.
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, OnSignal);
  run_.stop = &g_stop;
  // The scene frame was made from the scene's vertices, which are freed
  // before the solver and subdivision's adjacency are made (with them
  // beside, that was the master's peak).
  built_ = mesh_.LeafCount();
  JoinWorkers();
  DropVertices(&scene_);  // hashed, sent and meshed: 120 bytes a face freed
  ReturnFreeMemory();     // and given back to the system (glibc would keep them)
  solver_ = std::make_unique<Solver>(mesh_, run_.overshoot);
  // Progress: a line redrawn in place on a terminal, else a line every 2 s
  // (a log file or a batch system's output should not fill with \r).
  const bool terminal = isatty(2);
  progress_ = std::make_unique<Progress>(
      [](const std::string& text) { std::fputs(text.c_str(), stderr); }, terminal, run_.epsilon,
      terminal ? 0.25 : 2.0);
  if (solver_->Dark())  // a legal scene, but most likely a missing Ke
    Say("warning: " + opts_.scene_path + ": no face emits light (Ke); every B is 0");
  run_.wave_end = [this](int wave) {
    if (opts_.Alone() || view_) {
      const auto shaded = Picture(solver_->radiosity(), {FrameName(wave)}).first;
      // The view shows the wave's end, and nothing of the next wave until
      // it is as far (a new wave starts again from the lights): the
      // picture never goes back to a less converged one. A copy: the
      // picture's thread draws from this one meanwhile.
      if (view_) {
        view_->Snapshot(solver_->shots(), [&] { return *shaded; });
        view_floor_ = last_unshot_;
      }
    } else {
      // Workers wait for nothing the picture needs: at 5x10^5 elements
      // shading and exposure took 0.2-0.25 s a wave on the master's
      // thread, every worker idle.
      PictureLater(solver_->radiosity(), {FrameName(wave)});
    }
    if (opts_.verbosity >= 2)
      std::fprintf(stderr, "radiosity: wave %d ends: %ld elements\n", wave, mesh_.LeafCount());
    // With -j 0 no worker waits for the picture, and drawing it beside
    // the next wave's first columns raised -j 0's dividing peak (memory.h)
    // by 16 bytes an element.
    if (opts_.Alone()) Drawn();
  };
  // A wave's picture is drawn while the next wave shoots (on a 200,000-face
  // scene it takes seconds, which the workers spent waiting), and is done
  // before a division pass changes the points it reads; its encoding, not
  // (the PNG of a small scene's picture takes longer than its drawing).
  run_.mesh_changes = [this] { Drawn(); };
  if (opts_.subdivide) {
    SubdivideOptions sub = opts_.sub;
    sub.max_elements = sub_limit_;
    subdivider_ = std::make_unique<Subdivider>(&mesh_, sub);
  }
  if (!opts_.resume_file.empty()) Resume();
  if (!opts_.checkpoint_file.empty()) {
    run_.checkpoint_every = opts_.checkpoint_every;
    run_.checkpoint = [this](const RunState& state) { SaveCheckpoint(state); };
  }
}

// Nothing the run writes may replace one of its inputs or anything but a
// regular file: checked before the run starts (and again as each output
// is moved into place, Staging::Commit).
void MasterRun::CheckOutputs(const std::vector<Input>& ck_inputs) {
  std::string err, name;
  auto check = [&](const std::string& opt, const std::string& path, const std::vector<Input>& in) {
    const std::string why = Unwritable(path, in);
    if (!why.empty()) Die(kExitUsage, opt + path + ": " + why + "; refusing to overwrite it");
  };
  if (!MakeDirs(opts_.out_dir, &err)) Die(kExitFailure, err);
  for (const char* n : {"log.csv", "error.svg", "result.csv", "result.ply", "result.gltf",
                        "result.bin", "final.hdr", "view.html"})
    check("", opts_.out_dir + "/" + n, inputs_);
  check("", opts_.out_dir + "/final." + opts_.format, inputs_);
  if (!opts_.converge.empty()) check("--converge ", opts_.converge, inputs_);
  const std::string& ck = opts_.checkpoint_file;
  if (ck.empty()) return;
  check("--checkpoint ", ck, ck_inputs);
  if (InDir(ck, opts_.out_dir, &name) && OutputName(name))
    Die(kExitUsage, "--checkpoint " + ck + ": is an output of this run (" + name +
                        " in -o " + opts_.out_dir + "); choose another name");
  // Writable: a file can be made beside it (the checkpoint's temporary).
  std::string probe = ck + ".XXXXXX";
  const int fd = ::mkostemp(&probe[0], O_CLOEXEC);
  if (fd < 0)
    Die(kExitFailure, "--checkpoint " + ck + ": cannot create a file in " + DirName(ck) + ": " +
                          std::strerror(errno));
  ::close(fd);
  ::unlink(probe.c_str());
}

// Started before the master meshes the scene, and sent its frame while
// it does (MeshScene): each worker meshes the scene as the master does,
// at the same time. At 10^6 elements the master took 0.56 s to mesh and
// each worker 0.5 s after it.
void MasterRun::StartWorkers() {
  if (opts_.Alone()) return;
  std::string err;
  // The scene is lent to the pool's encoder, not copied (hundreds of MB
  // at 10^6 faces), and comes back for the results.
  proto::SceneSetup setup{std::move(scene_), opts_.mesh, run_.resolution, run_.rotate, run_.seed,
                          opts_.pool.heartbeat_s};
  const double t0 = MonotonicSeconds();
  auto pool = std::make_unique<WorkerPool>(setup, opts_.pool);  // the mesh comes at JoinWorkers
  scene_ = std::move(setup.scene);
  if (opts_.verbosity >= 2)
    std::fprintf(stderr, "radiosity: scene frame of %zu bytes (%.1f a face), encoded in %.2f s\n",
                 pool->SetupBytes(), double(pool->SetupBytes()) / double(std::max<size_t>(1, scene_.faces.size())),
                 MonotonicSeconds() - t0);
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
      Say(name + ": " + err);
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
    // Said even with -q: with port 0 the workers need it.
    std::fprintf(stderr, "radiosity: listening for workers on %s\n", bound.c_str());
    pool->AddSource(std::move(listener));
  }
  local_workers_ = long(local.size());
  starting_ = std::move(pool);
}

// The mesh on a thread of its own while this one writes the scene frame
// to the workers started (WorkerPool::SendScene), which takes as long as
// they take to read it: a 9 MB frame at 10^6 faces. Their hellos and
// readies wait for the pool's first Poll, which checks them against
// this mesh (JoinWorkers).
void MasterRun::MeshScene(std::vector<Surface> surfaces) {
  std::string err;
  bool ok = false;
  auto mesh = [&] { ok = BuildMesh(scene_, std::move(surfaces), opts_.mesh, &mesh_, &err); };
  if (!starting_) {
    mesh();
  } else {
    const int done = ::eventfd(0, EFD_CLOEXEC);
    CHECK(done >= 0);  // only out of descriptors or memory
    std::thread mesher = QuietThread([&] {
      mesh();
      const uint64_t one = 1;
      CHECK(::write(done, &one, sizeof one) == ssize_t(sizeof one));
    });
    starting_->SendScene(done);
    mesher.join();
    ::close(done);
  }
  if (!ok) Die(kExitUsage, opts_.scene_path + ": " + err);
}

// The run's transport, now that the mesh is built: the pool the workers
// were started in, or the master itself.
void MasterRun::JoinWorkers() {
  // The master itself: alone with -j 0, and when every worker is lost.
  run_.fallback = [this] {
    return std::make_unique<InProcessTransport>(mesh_, run_.resolution, run_.rotate, run_.seed);
  };
  if (!starting_) {
    transport_ = run_.fallback();
    return;
  }
  starting_->SetMesh(mesh_, identity_.base_hash);  // MeshHash of the mesh as built
  if (!UsePoolThread(opts_.pool_thread, local_workers_, sysconf(_SC_NPROCESSORS_ONLN))) {
    transport_ = std::move(starting_);
    return;
  }
  auto threaded = std::make_unique<ThreadedPool>(std::move(starting_), mesh_);
  pool_thread_ = threaded.get();
  transport_ = std::move(threaded);
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
                 Printable(opts_.resume_file).c_str(), solver_->shots(), resume_.run.wave, mesh_.LeafCount());
}

void MasterRun::SaveCheckpoint(const RunState& state) {
  const double t0 = MonotonicSeconds();
  size_t bytes = 0;
  std::string err;
  const Checkpoint c =
      Capture(identity_, mesh_, *solver_, subdivider_.get(), state, log_.text());
  if (!WriteCheckpoint(opts_.checkpoint_file, c, &bytes, &err))
    Say("warning: checkpoint not written: " + err);
  else if (opts_.verbosity >= 2)
    std::fprintf(stderr, "radiosity: checkpoint %s: %zu bytes at %ld shots in %.1f ms\n",
                 Printable(opts_.checkpoint_file).c_str(), bytes, solver_->shots(),
                 (MonotonicSeconds() - t0) * 1e3);
}

ViewInfo MasterRun::ViewOf() const {
  const std::string& path = opts_.scene_path;
  return {path.substr(path.rfind('/') + 1), camera_, opts_.width, opts_.height, run_.epsilon};
}

void MasterRun::OnSample(const Sample& s) {
  double rms = 0, rel = 0;
  const bool with_ref = !ref_.empty();
  if (with_ref) RmsError(scene_, FaceRadiosity(mesh_, solver_->radiosity()), ref_, &rms, &rel);
  log_.Row(s, with_ref ? &rms : nullptr, with_ref ? &rel : nullptr);
  workers_ = s.workers;
  last_unshot_ = s.unshot;
  if (view_) {
    view_->Row({s.seconds, s.shots, s.wave, s.elements, s.unshot, with_ref ? rms : NAN,
                with_ref ? rel : NAN},
               s.workers);
    if (s.unshot <= view_floor_ && view_->SnapshotDue()) {
      view_->Snapshot(s.shots, [this] { return Shade(mesh_, solver_->radiosity()); });
      view_floor_ = HUGE_VAL;
    }
  }
  if (opts_.verbosity == 1) {
    std::lock_guard<std::mutex> lock(progress_mu_);
    progress_->Update(s, with_ref ? &rms : nullptr, with_ref ? &rel : nullptr);
  }
  if (opts_.verbosity >= 2) {
    std::fprintf(stderr, "radiosity: %8.2f s %7ld shots  unshot %.3e", s.seconds, s.shots, s.unshot);
    if (with_ref) std::fprintf(stderr, "  rms %.3e (%.3f%%)", rms, 100 * rel);
    std::fputc('\n', stderr);
  }
}

// Workers joining, lost or skipped: above the progress line; -q keeps only
// the warnings.
void MasterRun::Note(const std::string& line, bool warning) {
  std::lock_guard<std::mutex> lock(progress_mu_);
  if (opts_.verbosity == 1) progress_->Note(Printable(line));
  else if (warning || opts_.verbosity >= 2) Say(line);
}

std::string MasterRun::FrameName(int wave) const {
  char name[32];
  std::snprintf(name, sizeof name, "frame-%02d.", wave);
  return staging_.Path(name + opts_.format);
}

// A picture of the solution as it stands: the end of a wave, the final one.
// The last wave's frame and final.png are the same picture: shaded and
// rendered once (on a 200,000-face scene each costs seconds). HDR_PATH:
// also the linear picture there, as Radiance RGBE.
std::pair<std::shared_ptr<const ShadedMesh>, float> MasterRun::Picture(
    const ElemB& b, const std::vector<std::string>& paths, const std::string& hdr_path) {
  PicturesDone();  // one picture's pixels at a time (up to 18 bytes a pixel, image.h)
  auto shaded = std::make_shared<const ShadedMesh>(Shade(mesh_, b));
  // Here, not on the thread: its arrays (about 12 bytes a vertex) gone
  // before the next wave's solver arrays come, at the master's peak
  // (memory.h), and before the picture's pixels.
  const float exposure = AutoExposure(*shaded);
  StartDrawing([shaded, exposure]() mutable { return std::make_pair(std::move(shaded), exposure); },
               paths, hdr_path);
  return {std::move(shaded), exposure};
}

void MasterRun::PictureLater(const ElemB& b, const std::vector<std::string>& paths) {
  // One picture's pixels at a time (about 18 bytes a pixel, image.h), or
  // two when both take no more than 64 MiB: the maze's waves end about
  // as often as a 512 x 512 PNG takes to encode (30 ms), and the master
  // waited for the last one's encoding with every worker idle.
  const double bytes = 18.0 * double(opts_.width) * double(opts_.height);
  const std::string err = writers_.WaitOlder(2 * bytes <= 64.0 * (1 << 20) ? 1 : 0);
  if (!err.empty()) Die(kExitFailure, err);
  // The last one drawn, though: only the newest may read the mesh (Drawn).
  Drawn();
  auto copy = std::make_shared<std::vector<glm::dvec3>>(b);
  StartDrawing(
      [this, copy] {
        // Only reads the mesh, which the master's thread leaves as it is
        // until Drawn() (RunOptions::mesh_changes, the run's end).
        auto shaded = std::make_shared<const ShadedMesh>(Shade(mesh_, *copy));
        copy->clear();
        copy->shrink_to_fit();
        const float exposure = AutoExposure(*shaded);
        return std::make_pair(std::move(shaded), exposure);
      },
      paths, "");
}

void MasterRun::StartDrawing(Shading shade, const std::vector<std::string>& paths,
                             const std::string& hdr_path) {
  // Drawn once, the files encoded in turn on one thread (their buffers one
  // at a time), while the run, or the rest of the outputs, go on.
  auto drawn = std::make_shared<std::promise<void>>();
  drawn_ = drawn->get_future().share();
  writers_.Start([shade = std::move(shade), drawn, camera = camera_, width = opts_.width,
                  height = opts_.height, paths, hdr_path,
                  format = opts_.format](std::string* e) mutable {
    auto picture = shade();
    Image img;
    Render(*picture.first, camera, width, height, &img);
    picture.first.reset();  // not read again (nor its lent points)
    drawn->set_value();
    return WriteImage(img, picture.second, paths, format, e) &&
           (hdr_path.empty() || WriteRadianceHdr(img, hdr_path, e));
  });
}

void MasterRun::Drawn() {
  if (drawn_.valid()) drawn_.wait();
}

void MasterRun::PicturesDone() {
  const std::string err = writers_.Wait();
  if (!err.empty()) Die(kExitFailure, err);
}

void MasterRun::Run() {
  result_ = RunMaster(&mesh_, run_, solver_.get(), subdivider_.get(), transport_.get(),
                      [this](const Sample& s) { OnSample(s); },
                      [this](const std::string& line, bool warning) { Note(line, warning); });
  transport_->Shutdown();
  const double pool_cpu = pool_thread_ ? pool_thread_->CpuSeconds() : 0;
  transport_.reset();  // with -j 0 the hemicube's buffers, freed before the pictures
  pool_thread_ = nullptr;
  Drawn();  // the last wave's picture may still be reading the mesh
  ReleaseEdges(&mesh_);  // and subdivision's edge maps: nothing is divided after the run
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
  if (opts_.verbosity >= 2 && pool_cpu > 0)
    std::fprintf(stderr, "radiosity: pool thread: %.3f s CPU (reading, decoding, writing)\n", pool_cpu);
  if (opts_.verbosity >= 2)
    for (const RunResult::Worker& w : r.workers)
      std::fprintf(stderr,
                   "radiosity: %s: %ld columns, %ld deferred, %ld taken back; queue %d..%d sent, %d at the "
                   "end, high watermark up to %d, %d more before passes; %.2f ms a column, %.2f ms on "
                   "the wire, one every %.2f ms\n",
                   Printable(w.name).c_str(), w.columns, w.deferred, w.reclaimed, w.depth_min, w.depth_max,
                   w.depth, w.high_max, w.reserve_max, 1e3 * w.column_s, 1e3 * w.wire_s, 1e3 * w.interval_s);
  if (opts_.verbosity >= 2 && r.joined > 0)
    std::fprintf(stderr,
                 "radiosity: workers idle %.3f s: %.3f s in pictures, %.3f s in division "
                 "passes, %.3f s with nothing to select, %.3f s otherwise, %.3f s at the end; "
                 "%.3f s on stale columns\n",
                 r.idle.Sum(), r.idle.picture, r.idle.pass, r.idle.dry, r.idle.other, r.idle.end,
                 r.stale_s);
}

void MasterRun::WriteOutputs() {
  std::string err;
  const RunResult& r = result_;
  const std::string& out = opts_.out_dir;
  if (!log_.Close(&err)) Die(kExitFailure, err);
  // Drawn even when the run failed: how it went is what one wants to see.
  const std::string& scene_path = opts_.scene_path;
  const std::string scene_name = scene_path.substr(scene_path.rfind('/') + 1);
  if (!WriteErrorChart(staging_.Path("error.svg"), scene_name + ": error against run time",
                       log_.rows(), &err))
    Die(kExitFailure, err);
  // Every output of the run moved into place at once, and the rest of an
  // earlier run's removed: the directory holds one run's files.
  auto commit = [&] {
    err = writers_.Wait();
    if (!err.empty() || !staging_.Commit(inputs_, OutputName, &err)) Die(kExitFailure, err);
  };
  if (r.status == RunStatus::kNoWorkers) {
    commit();
    Die(kExitFailure, r.why + "; no results written");
  }
  if (r.status == RunStatus::kNotConverged) {
    commit();
    Die(kExitFailure, "did not converge after " + std::to_string(r.shots) + " shots: " + r.why +
                          "; no results written");
  }

  // The last wave's picture drawn before the end's arrays come.
  Drawn();
  // Nothing is shot or divided after the run: of the solver the outputs
  // read only B (copied out once the solver's other arrays are gone), and
  // of subdivision whether it was capped; the rest (some 60 and 14 bytes
  // an element) is freed before the pictures, the peak of the master's end.
  const std::vector<glm::dvec3> b = solver_->TakeRadiosity();
  const bool capped = subdivider_ && subdivider_->capped();
  solver_.reset();
  subdivider_.reset();
  auto face_b = std::make_shared<const std::vector<glm::dvec3>>(FaceRadiosity(mesh_, b));
  const auto picture = Picture(b, {FrameName(r.waves), staging_.Path("final." + opts_.format)},
                               staging_.Path("final.hdr"));
  const std::shared_ptr<const ShadedMesh> shaded = picture.first;
  const float exposure = picture.second;
  if (opts_.verbosity >= 2)
    std::fprintf(stderr, "radiosity: wave %d ends: %ld elements\n", r.waves, mesh_.LeafCount());
  // The files side by side on the writers' threads, beside the picture's
  // drawing and encoding: one after another on the master's thread they
  // took 0.5 s of boxes20000's end (536,760 elements). Each reads only
  // what is made here, and the scene, which nothing changes now; all are
  // waited for, and a failure reported, at the commit.
  writers_.Start([this, face_b, path = staging_.Path("result.csv")](std::string* e) {
    return WriteResultCsv(path, scene_, *face_b, e);
  });
  writers_.Start([shaded, exposure, path = staging_.Path("result.ply")](std::string* e) {
    return WritePly(*shaded, exposure, path, e);
  });
  writers_.Start([shaded, exposure, gltf = staging_.Path("result.gltf"),
                  bin = staging_.Path("result.bin")](std::string* e) {
    return WriteGltf(*shaded, exposure, gltf, bin, e);
  });
  const std::string how = r.status == RunStatus::kConverged ? "converged"
                          : r.status == RunStatus::kStopped ? StoppedBy()
                                                            : r.why;
  {
    // view.html: the browser view with the final state and mesh in it.
    ViewState final_state;
    final_state.status = how;
    final_state.workers = workers_;
    final_state.snapshot = 1;
    final_state.snapshot_shots = r.shots;
    // Written as it is encoded: at 10^6 elements the page is some 100 MB.
    writers_.Start([shaded, exposure, state = ViewStateJson(ViewOf(), final_state, log_.rows(), 0),
                    path = staging_.Path("view.html")](std::string* e) {
      return WriteFileAtomic(path,
                             [&](const FileSink& put) {
                               return WriteOfflineViewPage(
                                   state,
                                   [&](const FileSink& blob) {
                                     return ViewMeshBlob(*shaded, exposure, blob);
                                   },
                                   put);
                             },
                             e);
    });
    if (view_) view_->Finish(ViewMeshBlob(*shaded, exposure), r.shots, how);
  }
  if (!opts_.converge.empty()) {
    // A reference must be converged: one cut short by -s, -t or a signal
    // would pass its own error on to every run measured against it.
    if (r.status != RunStatus::kConverged) {
      commit();
      Die(kExitFailure, "--converge " + opts_.converge + ": not written, the run did not converge (" +
                            (r.why.empty() ? std::string("stopped on request") : r.why) + ")");
    }
    if (!WriteResultCsv(opts_.converge, scene_, *face_b, &err)) Die(kExitFailure, err);
    if (opts_.verbosity >= 1)
      std::fprintf(stderr, "radiosity: reference (epsilon %g) in %s: use --reference %s\n",
                   run_.epsilon, Printable(opts_.converge).c_str(), Printable(opts_.converge).c_str());
  }
  commit();

  if (capped)
    std::fprintf(stderr, "radiosity: warning: subdivision stopped at %ld elements: the next "
                         "pass would pass the limit of %ld\n", long(mesh_.elems.size()), sub_limit_);
  if (r.status == RunStatus::kLimit)  // said even with -q: these are not converged numbers
    std::fprintf(stderr,
                 "radiosity: warning: did not converge: %s with unshot energy %.3g of "
                 "emitted (epsilon %g)\n",
                 r.why.c_str(), r.unshot, run_.epsilon);
  if (opts_.verbosity >= 1) {
    std::fprintf(stderr,
                 "radiosity: %s: %ld shots in %.2f s, unshot %.3g of emitted; "
                 "%zu patches, %ld elements (%ld built; %d waves, %ld division passes "
                 "in %.3f s; %zu shooters, %zu of them groups); results in %s/\n",
                 how.c_str(), r.shots, r.seconds, r.unshot, mesh_.patches.size(), mesh_.LeafCount(),
                 built_, r.waves, r.passes, r.subdivide_s, Shooters(mesh_), mesh_.groups.size(),
                 Printable(out).c_str());
  }
  if (view_ && opts_.verbosity >= 2)
    std::fprintf(stderr,
                 "radiosity: view: %ld mesh snapshots, %.2f ms each (at most %.2f), %.3f s in all, "
                 "%.2f%% of the run\n",
                 view_->snapshots(), 1e3 * view_->snapshot_seconds() / std::max(1L, view_->snapshots()),
                 1e3 * view_->max_snapshot_seconds(), view_->snapshot_seconds(),
                 100 * view_->snapshot_seconds() / std::max(1e-9, r.seconds));
}
