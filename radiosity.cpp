// radiosity: main, options and usage. Everything else lives in the modules
// (scene, mesh, hemicube, master, transport, net, worker, results, image);
// see README.md.
#include <fcntl.h>
#include <getopt.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <unistd.h>

#include "checkpoint.h"
#include "connect.h"
#include "errorchart.h"
#include "hosts.h"
#include "image.h"
#include "inprocess.h"
#include "mesh.h"
#include "pool.h"
#include "progress.h"
#include "results.h"
#include "scene.h"
#include "scheduler.h"
#include "ssh.h"
#include "worker.h"
#include "subdivide.h"

#ifndef RADIOSITY_VERSION
#define RADIOSITY_VERSION "0.1"
#endif

namespace {

// Exit status, mirrored in man/radiosity.1 (EXIT STATUS).
enum ExitStatus {
  kExitOk = 0,       // done, or stopped on request
  kExitFailure = 1,  // run-time failure: did not converge, no worker, I/O error
  kExitUsage = 2,    // bad usage or bad input
};

// Local workers beyond the cores only share them; the cap keeps a typo
// (-j 1000000) from forking without end.
constexpr long kMaxLocalWorkers = 256;

// --converge's epsilon unless -e says otherwise: a hundred times below the
// default, so that a run to the default is measured against an answer
// about 1% of its own error away.
constexpr double kConvergeEpsilon = 1e-5;

const char kUsage[] =
    "usage: radiosity [options] SCENE.obj\n"
    "  -o, --out DIR          where results go (default: out)\n"
    "  -j, --workers N        local worker processes (default: online cores);\n"
    "                         0: the master computes form factors itself\n"
    "      --queue N          patches queued per worker (default: automatic, 3-10)\n"
    "      --timeout SEC      drop a worker silent this long (default 10)\n"
    "      --worker-cmd CMD   start local workers with CMD --worker\n"
    "  -H, --hosts FILE       also start workers on the hosts in FILE (ssh);\n"
    "                         -j then defaults to 0\n"
    "      --dump-hosts       print the hosts of -H FILE as parsed, and exit\n"
    "      --accept-new-host-keys  record unknown ssh host keys (default: refuse)\n"
    "      --listen [HOST:]PORT  take workers that connect back (--secret);\n"
    "                         -j then defaults to 0\n"
    "      --secret FILE      shared secret of --listen and --connect (mode 0600)\n"
    "  -r, --resolution R     hemicube pixels across the top face (default 256)\n"
    "  -e, --epsilon E        stop when unshot energy < E x emitted (default 1e-3)\n"
    "  -s, --shots N          stop after N shots\n"
    "  -t, --time SEC         stop after SEC seconds\n"
    "      --no-overshoot     plain progressive refinement\n"
    "      --reference CSV    log RMS error against a converged result.csv\n"
    "      --converge CSV     solve to epsilon 1e-5 (or -e) and also save result.csv\n"
    "                         as CSV, a reference for --reference\n"
    "      --patch-size L     largest patch edge (default: scene diagonal / 16)\n"
    "      --elements N       elements per patch edge (default 2)\n"
    "      --no-subdivide     keep the mesh as built (default: divide where light changes)\n"
    "      --no-waves         one wave: never restart on the finer mesh\n"
    "      --subdivide-floor F  lowest dividing-factor threshold (default 0.2)\n"
    "      --min-element L    smallest element edge made by dividing (default: diagonal / 400)\n"
    "      --max-level N      deepest division below the built elements, 0..12 (default 2)\n"
    "      --wave-fraction F  a new wave after F of the elements divided (default 0.2)\n"
    "      --no-rotate        keep the hemicube aligned (default: turned per shot)\n"
    "      --seed N           seed of the hemicube turns (default 1)\n"
    "      --log-every N      shots between log.csv rows (default: patches / 100)\n"
    "      --checkpoint FILE  save the run's state in FILE every --checkpoint-every\n"
    "                         seconds and when it stops (written to FILE.tmp, renamed)\n"
    "      --checkpoint-every SEC  seconds between checkpoints (default 30)\n"
    "      --resume FILE      go on from checkpoint FILE (same scene and options;\n"
    "                         -e, -s, -t and the output may differ)\n"
    "      --camera \"ex ey ez tx ty tz fov\"\n"
    "      --size WxH         picture size (default 512x512)\n"
    "      --format png|ppm   picture format (default png)\n"
    "  -q, --quiet            no progress, no messages but errors and warnings\n"
    "  -v, --verbose          a line per progress sample\n"
    "      --version          print the version\n"
    "  -h, --help             this help\n"
    "       radiosity --worker   speak the worker protocol on stdin/stdout\n"
    "       radiosity --worker --connect HOST:PORT --secret FILE\n"
    "                            the same with a master started with --listen\n";

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

[[noreturn]] void BadOption(const char* opt, const char* arg, const char* what) {
  Die(kExitUsage, std::string(opt) + " '" + arg + "': " + what +
                      " (try 'radiosity --help')");
}

double Number(const char* opt, const char* arg, double lo, double hi) {
  char* end = nullptr;
  errno = 0;
  double v = std::strtod(arg, &end);
  if (end == arg || *end || errno || !std::isfinite(v)) BadOption(opt, arg, "not a number");
  if (v < lo || v > hi) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "must be from %g to %g", lo, hi);
    BadOption(opt, arg, buf);
  }
  return v;
}

long Integer(const char* opt, const char* arg, long lo, long hi) {
  char* end = nullptr;
  errno = 0;
  long v = std::strtol(arg, &end, 10);
  if (end == arg || *end || errno) BadOption(opt, arg, "not an integer");
  if (v < lo || v > hi) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "must be from %ld to %ld", lo, hi);
    BadOption(opt, arg, buf);
  }
  return v;
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

int main(int argc, char** argv) {
  enum {
    kNoOvershoot = 256, kReference, kPatchSize, kElements, kNoRotate, kSeed,
    kLogEvery, kCamera, kSize, kFormat, kVersion, kQueue, kTimeout, kWorker, kWorkerCmd,
    kNoSubdivide, kNoWaves, kFloor, kMinElement, kMaxLevel, kWaveFraction,
    kDumpHosts, kAcceptNewHostKeys, kListen, kSecret, kConnect, kConverge,
    kCheckpoint, kCheckpointEvery, kResume,
  };
  static const option kLong[] = {
      {"out", required_argument, nullptr, 'o'},
      {"workers", required_argument, nullptr, 'j'},
      {"queue", required_argument, nullptr, kQueue},
      {"timeout", required_argument, nullptr, kTimeout},
      {"worker", no_argument, nullptr, kWorker},
      {"worker-cmd", required_argument, nullptr, kWorkerCmd},
      {"hosts", required_argument, nullptr, 'H'},
      {"dump-hosts", no_argument, nullptr, kDumpHosts},
      {"accept-new-host-keys", no_argument, nullptr, kAcceptNewHostKeys},
      {"listen", required_argument, nullptr, kListen},
      {"secret", required_argument, nullptr, kSecret},
      {"connect", required_argument, nullptr, kConnect},
      {"resolution", required_argument, nullptr, 'r'},
      {"epsilon", required_argument, nullptr, 'e'},
      {"shots", required_argument, nullptr, 's'},
      {"time", required_argument, nullptr, 't'},
      {"no-overshoot", no_argument, nullptr, kNoOvershoot},
      {"reference", required_argument, nullptr, kReference},
      {"converge", required_argument, nullptr, kConverge},
      {"patch-size", required_argument, nullptr, kPatchSize},
      {"elements", required_argument, nullptr, kElements},
      {"no-subdivide", no_argument, nullptr, kNoSubdivide},
      {"no-waves", no_argument, nullptr, kNoWaves},
      {"subdivide-floor", required_argument, nullptr, kFloor},
      {"min-element", required_argument, nullptr, kMinElement},
      {"max-level", required_argument, nullptr, kMaxLevel},
      {"wave-fraction", required_argument, nullptr, kWaveFraction},
      {"no-rotate", no_argument, nullptr, kNoRotate},
      {"seed", required_argument, nullptr, kSeed},
      {"log-every", required_argument, nullptr, kLogEvery},
      {"checkpoint", required_argument, nullptr, kCheckpoint},
      {"checkpoint-every", required_argument, nullptr, kCheckpointEvery},
      {"resume", required_argument, nullptr, kResume},
      {"camera", required_argument, nullptr, kCamera},
      {"size", required_argument, nullptr, kSize},
      {"format", required_argument, nullptr, kFormat},
      {"quiet", no_argument, nullptr, 'q'},
      {"verbose", no_argument, nullptr, 'v'},
      {"version", no_argument, nullptr, kVersion},
      {"help", no_argument, nullptr, 'h'},
      {nullptr, 0, nullptr, 0},
  };
  std::string out_dir = "out", reference, converge, camera_text, format = "png";
  bool epsilon_given = false;
  RunOptions run;
  MeshOptions mesh_opts;
  SubdivideOptions sub_opts;
  bool subdivide = true;
  int width = 512, height = 512, verbosity = 1;
  long workers = std::max(1L, sysconf(_SC_NPROCESSORS_ONLN));
  bool worker_mode = false, workers_given = false, dump_hosts = false;
  std::string worker_cmd, hosts_file, listen, secret_file, connect;
  std::string checkpoint_file, resume_file;
  double checkpoint_every = 30;
  PoolOptions pool_opts;
  SshOptions ssh_opts;
  opterr = 0;
  int c;
  while ((c = getopt_long(argc, argv, ":o:j:H:r:e:s:t:qvh", kLong, nullptr)) != -1) {
    switch (c) {
      case 'o': out_dir = optarg; break;
      case 'j':
        workers = Integer("--workers", optarg, 0, kMaxLocalWorkers);
        workers_given = true;
        break;
      case kQueue: run.queue = int(Integer("--queue", optarg, 1, 64)); break;
      case kTimeout: pool_opts.timeout_s = Number("--timeout", optarg, 0.5, 86400); break;
      case kWorker: worker_mode = true; break;
      case kWorkerCmd: worker_cmd = optarg; break;
      case 'H': hosts_file = optarg; break;
      case kDumpHosts: dump_hosts = true; break;
      case kAcceptNewHostKeys: ssh_opts.accept_new_host_keys = true; break;
      case kListen: listen = optarg; break;
      case kSecret: secret_file = optarg; break;
      case kConnect: connect = optarg; break;
      case 'r': {
        run.resolution = int(Integer("--resolution", optarg, 8, Hemicube::kMaxResolution));
        if (run.resolution % 2) BadOption("--resolution", optarg, "must be even");
        break;
      }
      case 'e':
        run.epsilon = Number("--epsilon", optarg, 1e-15, 1);
        epsilon_given = true;
        break;
      case 's': run.max_shots = Integer("--shots", optarg, 1, 1L << 50); break;
      case 't': run.max_seconds = Number("--time", optarg, 1e-3, 1e9); break;
      case kNoOvershoot: run.overshoot = false; break;
      case kReference: reference = optarg; break;
      case kConverge: converge = optarg; break;
      case kPatchSize: mesh_opts.patch_size = Number("--patch-size", optarg, 1e-300, 1e300); break;
      case kElements: mesh_opts.elements_per_patch = int(Integer("--elements", optarg, 1, 64)); break;
      case kNoSubdivide: subdivide = false; break;
      case kNoWaves: sub_opts.waves = false; break;
      case kFloor: sub_opts.floor = Number("--subdivide-floor", optarg, 1e-3, 100); break;
      case kMinElement: sub_opts.min_size = Number("--min-element", optarg, 1e-300, 1e300); break;
      case kMaxLevel: sub_opts.max_level = int(Integer("--max-level", optarg, 0, 12)); break;
      case kWaveFraction: sub_opts.wave_fraction = Number("--wave-fraction", optarg, 0.01, 1); break;
      case kNoRotate: run.rotate = false; break;
      case kSeed: run.seed = unsigned(Integer("--seed", optarg, 0, 0xFFFFFFFFL)); break;
      case kLogEvery: run.log_every = Integer("--log-every", optarg, 1, 1L << 50); break;
      case kCheckpoint: checkpoint_file = optarg; break;
      case kCheckpointEvery:
        checkpoint_every = Number("--checkpoint-every", optarg, 0.001, 1e9);
        break;
      case kResume: resume_file = optarg; break;
      case kCamera: camera_text = optarg; break;
      case kSize: {
        // strtol, not sscanf("%d"): a number past int is then refused, not
        // undefined.
        char* x = nullptr;
        char* end = nullptr;
        errno = 0;
        const long w = std::strtol(optarg, &x, 10);
        if (x == optarg || *x != 'x' || !std::isdigit((unsigned char)x[1]))
          BadOption("--size", optarg, "expected WIDTHxHEIGHT");
        const long h = std::strtol(x + 1, &end, 10);
        if (*end || errno == ERANGE) BadOption("--size", optarg, "expected WIDTHxHEIGHT");
        if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide)
          BadOption("--size", optarg,
                    ("width and height must be from 1 to " + std::to_string(kMaxImageSide)).c_str());
        if (w * h > kMaxImagePixels)
          BadOption("--size", optarg,
                    ("at most " + std::to_string(kMaxImagePixels) + " pixels (8192x8192)").c_str());
        width = int(w);
        height = int(h);
        break;
      }
      case kFormat:
        format = optarg;
        if (format != "png" && format != "ppm") BadOption("--format", optarg, "must be png or ppm");
        break;
      case 'q': verbosity = 0; break;
      case 'v': verbosity = 2; break;
      case kVersion: std::printf("radiosity %s\n", RADIOSITY_VERSION); return kExitOk;
      case 'h': std::fputs(kUsage, stdout); return kExitOk;
      case ':': Die(kExitUsage, std::string("option ") + argv[optind - 1] + " needs a value (try 'radiosity --help')");
      default: Die(kExitUsage, std::string("unknown option ") + argv[optind - 1] + " (try 'radiosity --help')");
    }
  }
  // Connect-back: the secret is read before anything else, so that a
  // file others can read stops the run before it starts.
  std::string secret, err;
  if (!listen.empty() || !connect.empty()) {
    if (secret_file.empty())
      Die(kExitUsage, std::string(listen.empty() ? "--connect" : "--listen") +
                          " needs --secret FILE (the same file for the master and the workers)");
    if (!ReadSecret(secret_file, &secret, &err)) Die(kExitUsage, err);
  } else if (!secret_file.empty()) {
    Die(kExitUsage, "--secret goes with --listen or --worker --connect");
  }
  if (!connect.empty() && !worker_mode)
    Die(kExitUsage, "--connect is for workers: radiosity --worker --connect HOST:PORT --secret FILE");
  if (worker_mode) {
    if (optind != argc) Die(kExitUsage, "--worker takes no scene: the master sends it");
    int in = 0, out = 1;
    if (!connect.empty()) {
      std::string host;
      int port = 0;
      if (!ParseEndpoint(connect, true, &host, &port, &err))
        BadOption("--connect", connect.c_str(), err.c_str());
      in = out = ConnectBack(host, port, secret, &err);
      if (in < 0) Die(kExitFailure, "worker: " + err);
    }
    const int status = RunWorker(in, out, &err);
    if (status != 0) std::fprintf(stderr, "radiosity: worker: %s\n", err.c_str());
    return status;
  }
  std::vector<HostSpec> hosts;
  if (!hosts_file.empty() && !ReadHosts(hosts_file, &hosts, &err)) Die(kExitUsage, err);
  if (dump_hosts) {
    if (hosts_file.empty()) Die(kExitUsage, "--dump-hosts needs -H FILE");
    for (const HostSpec& h : hosts) std::printf("%s\n", FormatHost(h).c_str());
    return kExitOk;
  }
  std::string listen_host;
  int listen_port = 0;
  if (!listen.empty() && !ParseEndpoint(listen, false, &listen_host, &listen_port, &err))
    BadOption("--listen", listen.c_str(), err.c_str());
  // Remote workers take the place of local ones unless -j says otherwise.
  const bool remote = !hosts.empty() || !listen.empty();
  if (remote && !workers_given) workers = 0;
  if (optind != argc - 1) {
    std::fputs(kUsage, stderr);
    return kExitUsage;
  }
  const std::string scene_path = argv[optind];
  if (!converge.empty() && !epsilon_given) run.epsilon = kConvergeEpsilon;

  std::vector<std::string> warnings;
  Scene scene;
  bool loaded = LoadScene(scene_path, &scene, &err, &warnings);
  for (const std::string& w : warnings) std::fprintf(stderr, "radiosity: warning: %s\n", w.c_str());
  if (!loaded) Die(kExitUsage, err);

  Camera camera = scene.has_camera ? scene.camera : FrameBox(scene.lo, scene.hi);
  if (!camera_text.empty() && !ParseCamera(camera_text, &camera, &err))
    Die(kExitUsage, "--camera '" + camera_text + "': " + err);

  std::vector<glm::dvec3> ref;
  if (!reference.empty() && !ReadReference(reference, scene, &ref, &err)) Die(kExitUsage, err);

  Mesh mesh;
  if (!BuildMesh(scene, mesh_opts, &mesh, &err)) Die(kExitUsage, scene_path + ": " + err);
  if (verbosity >= 2)
    std::fprintf(stderr, "radiosity: %zu faces, %zu patches, %zu elements (patch size %g)\n",
                 scene.faces.size(), mesh.patches.size(), mesh.elems.size(), mesh.patch_size);

  // A checkpoint to resume is checked before anything is started; one to
  // write must be writable before the run starts.
  sub_opts.threshold = std::max(sub_opts.threshold, sub_opts.floor);
  const SolveOptions solve{run.overshoot, run.resolution, run.rotate, run.seed,
                           run.log_every,  mesh_opts,      subdivide,  sub_opts};
  const RunIdentity identity = Identify(scene, mesh, solve);
  Checkpoint resume;
  if (!resume_file.empty()) {
    if (!ReadCheckpoint(resume_file, &resume, &err)) Die(kExitUsage, err);
    if (!CheckIdentity(resume, identity, &err)) Die(kExitUsage, resume_file + ": " + err);
  }
  if (!checkpoint_file.empty()) {
    const std::string tmp = checkpoint_file + ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) Die(kExitFailure, "--checkpoint: " + tmp + ": " + std::strerror(errno));
    ::close(fd);
    ::unlink(tmp.c_str());
  }

  if (!MakeDirs(out_dir, &err)) Die(kExitFailure, err);
  LogCsv log;
  if (!log.Open(out_dir + "/log.csv", &err)) Die(kExitFailure, err);
  if (!resume_file.empty()) log.Restore(resume.log);

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  run.stop = &g_stop;
  Solver solver(mesh, run.overshoot);
  // Progress: a line redrawn in place on a terminal, else a line every 2 s
  // (a log file or a batch system's output should not fill with \r).
  const bool terminal = isatty(2);
  Progress progress([](const std::string& text) { std::fputs(text.c_str(), stderr); }, terminal,
                    run.epsilon, terminal ? 0.25 : 2.0);
  auto sample = [&](const Sample& s) {
    double rms = 0, rel = 0;
    if (!ref.empty()) RmsError(scene, FaceRadiosity(mesh, solver.radiosity()), ref, &rms, &rel);
    log.Row(s, ref.empty() ? nullptr : &rms, ref.empty() ? nullptr : &rel);
    if (verbosity == 1) progress.Update(s, ref.empty() ? nullptr : &rms, ref.empty() ? nullptr : &rel);
    if (verbosity >= 2) {
      std::fprintf(stderr, "radiosity: %8.2f s %7ld shots  unshot %.3e", s.seconds, s.shots, s.unshot);
      if (!ref.empty()) std::fprintf(stderr, "  rms %.3e (%.3f%%)", rms, 100 * rel);
      std::fputc('\n', stderr);
    }
  };
  if (solver.Dark())  // a legal scene, but most likely a missing Ke
    std::fprintf(stderr, "radiosity: warning: %s: no face emits light (Ke); every B is 0\n",
                 scene_path.c_str());
  // A picture of the solution as it stands: the end of a wave, the final one.
  // The last wave's frame and final.png are the same picture: shaded and
  // rendered once (on a 200,000-face scene each costs seconds).
  auto picture = [&](const std::vector<std::string>& paths) {
    ShadedMesh shaded = Shade(mesh, solver.radiosity());
    Image img;
    Render(shaded, camera, width, height, &img);
    const float exposure = AutoExposure(shaded);
    for (const std::string& path : paths)
      if (!WriteImage(img, exposure, path, format, &err)) Die(kExitFailure, err);
    return std::make_pair(std::move(shaded), exposure);
  };
  auto frame_name = [&](int wave) {
    char name[32];
    std::snprintf(name, sizeof name, "/frame-%02d.", wave);
    return out_dir + name + format;
  };
  auto frame = [&](int wave) {
    picture({frame_name(wave)});
    if (verbosity >= 2)
      std::fprintf(stderr, "radiosity: wave %d ends: %ld elements\n", wave, mesh.LeafCount());
  };
  run.wave_end = frame;
  std::unique_ptr<Subdivider> subdivider;
  if (subdivide) subdivider = std::make_unique<Subdivider>(&mesh, sub_opts);
  const long built = mesh.LeafCount();
  // Workers joining, lost or skipped: above the progress line; -q keeps
  // only the warnings.
  auto note = [&](const std::string& line, bool warning) {
    if (verbosity == 1) progress.Note(line);
    else if (warning || verbosity >= 2) std::fprintf(stderr, "radiosity: %s\n", line.c_str());
  };
  run.fallback = [&] {
    return std::make_unique<InProcessTransport>(mesh, run.resolution, run.rotate, run.seed);
  };
  std::unique_ptr<Transport> transport;
  if (workers == 0 && !remote) {
    transport = std::make_unique<InProcessTransport>(mesh, run.resolution, run.rotate, run.seed);
  } else {
    std::signal(SIGPIPE, SIG_IGN);  // a dead worker is an error on its connection
    proto::SceneSetup setup{scene, mesh_opts, run.resolution, run.rotate, run.seed};
    auto pool = std::make_unique<WorkerPool>(setup, mesh, pool_opts);
    if (pool->SceneTooLarge())
      Die(kExitUsage, scene_path + ": too large to send to workers (protocol limit " +
                          std::to_string(proto::kMaxFrame >> 20) + " MiB); use -j 0");
    auto command = [&](const std::string& user_cmd) {
      return user_cmd.empty() ? std::vector<std::string>{SelfExe(), "--worker"}
                              : std::vector<std::string>{"/bin/sh", "-c", "exec " + user_cmd + " --worker"};
    };
    // -j workers, then the hosts file's localhost lines: forked here.
    std::vector<std::vector<std::string>> local(size_t(workers), command(worker_cmd));
    std::vector<HostSpec> ssh_hosts;
    for (const HostSpec& h : hosts) {
      if (!h.Local()) ssh_hosts.push_back(h);
      else local.insert(local.end(), size_t(h.slots), command(h.cmd.empty() ? worker_cmd : h.cmd));
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
    if (!ssh_hosts.empty()) {
      ssh_opts.timeout_s = pool_opts.timeout_s;
      pool->AddSource(StartSshHosts(ssh_hosts, ssh_opts, note));
    }
    if (!listen.empty()) {
      std::string bound;
      std::unique_ptr<WorkerSource> listener =
          Listen(listen_host, listen_port, secret, note, &bound, &err);
      if (!listener) Die(kExitFailure, "--listen " + listen + ": " + err);
      if (verbosity >= 1)
        std::fprintf(stderr, "radiosity: listening for workers on %s\n", bound.c_str());
      pool->AddSource(std::move(listener));
    }
    transport = std::move(pool);
  }
  if (!resume_file.empty()) {
    // Workers got the mesh as built; the divisions follow the scene.
    if (!ApplyCheckpoint(resume, &mesh, &solver, subdivider.get(), &err))
      Die(kExitUsage, resume_file + ": " + err);
    transport->Divide(resume.edits);
    run.resume = &resume.run;
    if (verbosity >= 2)
      std::fprintf(stderr, "radiosity: resumed from %s: %ld shots, wave %d, %ld elements\n",
                   resume_file.c_str(), solver.shots(), resume.run.wave, mesh.LeafCount());
  }
  if (!checkpoint_file.empty()) {
    run.checkpoint_every = checkpoint_every;
    run.checkpoint = [&](const RunState& state) {
      const auto t0 = std::chrono::steady_clock::now();
      size_t bytes = 0;
      const Checkpoint c = Capture(identity, mesh, solver, subdivider.get(), state, log.text());
      if (!WriteCheckpoint(checkpoint_file, c, &bytes, &err))
        std::fprintf(stderr, "radiosity: warning: checkpoint not written: %s\n", err.c_str());
      else if (verbosity >= 2)
        std::fprintf(stderr, "radiosity: checkpoint %s: %zu bytes at %ld shots in %.1f ms\n",
                     checkpoint_file.c_str(), bytes, solver.shots(),
                     std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    };
  }
  RunResult result =
      RunMaster(&mesh, run, &solver, subdivider.get(), transport.get(), sample, note);
  transport->Shutdown();
  progress.Finish();
  if (verbosity >= 2)
    std::fprintf(stderr,
                 "radiosity: master: %.3f s distributing, %.3f s receiving, %.3f s shooting, "
                 "%.3f s waiting; "
                 "workers: %d joined, %d lost, %ld columns in %.3f s, %ld stale; "
                 "%.0f bytes/shot sent, %.0f received\n",
                 result.distribute_s, result.receive_s, result.shoot_s, result.wait_s,
                 result.joined, result.lost,
                 result.columns, result.worker_s, result.stale,
                 double(result.bytes_sent) / std::max(1L, result.shots),
                 double(result.bytes_received) / std::max(1L, result.shots));
  if (!log.Close(&err)) Die(kExitFailure, err);
  // Drawn even when the run failed: how it went is what one wants to see.
  const std::string scene_name = scene_path.substr(scene_path.rfind('/') + 1);
  if (!WriteErrorChart(out_dir + "/error.svg", scene_name + ": error against run time",
                       log.rows(), &err))
    Die(kExitFailure, err);
  if (result.status == RunStatus::kNoWorkers)
    Die(kExitFailure, result.why + "; no results written");
  if (result.status == RunStatus::kNotConverged)
    Die(kExitFailure, "did not converge after " + std::to_string(result.shots) + " shots: " +
                          result.why + "; no results written");

  std::vector<glm::dvec3> face_b = FaceRadiosity(mesh, solver.radiosity());
  if (!WriteResultCsv(out_dir + "/result.csv", scene, face_b, &err)) Die(kExitFailure, err);
  const auto shaded = picture({frame_name(result.waves), out_dir + "/final." + format});
  if (verbosity >= 2)
    std::fprintf(stderr, "radiosity: wave %d ends: %ld elements\n", result.waves, mesh.LeafCount());
  if (!WritePly(shaded.first, shaded.second, out_dir + "/result.ply", &err) ||
      !WriteGltf(shaded.first, shaded.second, out_dir + "/result.gltf", out_dir + "/result.bin",
                 &err))
    Die(kExitFailure, err);
  if (!converge.empty()) {
    // A reference must be converged: one cut short by -s, -t or a signal
    // would pass its own error on to every run measured against it.
    if (result.status != RunStatus::kConverged)
      Die(kExitFailure, "--converge " + converge + ": not written, the run did not converge (" +
                            (result.why.empty() ? std::string("stopped on request") : result.why) +
                            ")");
    if (!WriteResultCsv(converge, scene, face_b, &err)) Die(kExitFailure, err);
    if (verbosity >= 1)
      std::fprintf(stderr, "radiosity: reference (epsilon %g) in %s: use --reference %s\n",
                   run.epsilon, converge.c_str(), converge.c_str());
  }

  if (subdivider && subdivider->capped())
    std::fprintf(stderr, "radiosity: warning: subdivision stopped at %ld elements: the next "
                         "pass would pass the limit of %d\n", long(mesh.elems.size()), kMaxElements);
  if (result.status == RunStatus::kLimit)  // said even with -q: these are not converged numbers
    std::fprintf(stderr,
                 "radiosity: warning: did not converge: %s with unshot energy %.3g of "
                 "emitted (epsilon %g)\n",
                 result.why.c_str(), result.unshot, run.epsilon);
  if (verbosity >= 1) {
    const char* how = result.status == RunStatus::kConverged ? "converged"
                      : result.status == RunStatus::kStopped ? "stopped on request"
                                                             : result.why.c_str();
    std::fprintf(stderr,
                 "radiosity: %s: %ld shots in %.2f s, unshot %.3g of emitted; "
                 "%zu patches, %ld elements (%ld built; %d waves, %ld division passes "
                 "in %.3f s); results in %s/\n",
                 how, result.shots, result.seconds, result.unshot, mesh.patches.size(),
                 mesh.LeafCount(), built, result.waves, result.passes, result.subdivide_s,
                 out_dir.c_str());
  }
  return kExitOk;
}
