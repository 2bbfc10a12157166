#include "options.h"

#include <getopt.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "connect.h"
#include "hemicube.h"
#include "image.h"

namespace {

// Local workers beyond the cores only share them; the cap keeps a typo
// (-j 1000000) from forking without end.
constexpr long kMaxLocalWorkers = 256;

// --converge's epsilon unless -e says otherwise: a hundred times below the
// default, so that a run to the default is measured against an answer
// about 1% of its own error away.
constexpr double kConvergeEpsilon = 1e-5;

bool BadOption(const char* opt, const char* arg, const std::string& what, std::string* err) {
  *err = std::string(opt) + " '" + arg + "': " + what + " (try 'radiosity --help')";
  return false;
}

bool Number(const char* opt, const char* arg, double lo, double hi, double* out,
            std::string* err) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(arg, &end);
  if (end == arg || *end || errno || !std::isfinite(v))
    return BadOption(opt, arg, "not a number", err);
  if (v < lo || v > hi) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "must be from %g to %g", lo, hi);
    return BadOption(opt, arg, buf, err);
  }
  *out = v;
  return true;
}

template <class T>
bool Integer(const char* opt, const char* arg, long lo, long hi, T* out, std::string* err) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(arg, &end, 10);
  if (end == arg || *end || errno) return BadOption(opt, arg, "not an integer", err);
  if (v < lo || v > hi) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "must be from %ld to %ld", lo, hi);
    return BadOption(opt, arg, buf, err);
  }
  *out = T(v);
  return true;
}

bool Size(const char* arg, int* width, int* height, std::string* err) {
  // strtol, not sscanf("%d"): a number past int is then refused, not
  // undefined.
  char* x = nullptr;
  char* end = nullptr;
  errno = 0;
  const long w = std::strtol(arg, &x, 10);
  if (x == arg || *x != 'x' || !std::isdigit((unsigned char)x[1]))
    return BadOption("--size", arg, "expected WIDTHxHEIGHT", err);
  const long h = std::strtol(x + 1, &end, 10);
  if (*end || errno == ERANGE) return BadOption("--size", arg, "expected WIDTHxHEIGHT", err);
  if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide)
    return BadOption("--size", arg,
                     "width and height must be from 1 to " + std::to_string(kMaxImageSide), err);
  if (w * h > kMaxImagePixels)
    return BadOption("--size", arg,
                     "at most " + std::to_string(kMaxImagePixels) + " pixels (8192x8192)", err);
  *width = int(w);
  *height = int(h);
  return true;
}

}  // namespace

const char kUsage[] =
    "usage: radiosity [options] SCENE.obj\n"
    "  -o, --out DIR          where results go (default: out)\n"
    "  -j, --workers N        local worker processes (default: online cores);\n"
    "                         0: the master computes form factors itself\n"
    "      --queue N          patches queued per worker (default: automatic, 3-64)\n"
    "      --timeout SEC      drop a worker silent, or given work and sending no\n"
    "                         column, this long (default 10)\n"
    "      --worker-cmd CMD   start local workers with CMD --worker\n"
    "      --pool-thread      talk to the workers on a thread of its own (default:\n"
    "                         when the local workers leave a core free for it)\n"
    "      --no-pool-thread   talk to them on the master's thread\n"
    "  -H, --hosts FILE       also start workers on the hosts in FILE (ssh);\n"
    "                         -j then defaults to 0\n"
    "      --dump-hosts       print the hosts of -H FILE as parsed, and exit\n"
    "      --accept-new-host-keys  record unknown ssh host keys (default: refuse)\n"
    "      --listen [HOST:]PORT  take workers that connect back (--secret);\n"
    "                         -j then defaults to 0\n"
    "      --secret FILE      shared secret of --listen and --connect (mode 0600 or 0400)\n"
    "      --view [HOST:]PORT  serve a live view of the run to a browser on\n"
    "                         http://HOST:PORT/ (HOST: 127.0.0.1 unless given)\n"
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
    "      --no-join          cut every face on its own (default: join coplanar faces\n"
    "                         of one material into surfaces)\n"
    "      --no-groups        every patch shoots alone (default: small patches\n"
    "                         near one another that face alike shoot as a group)\n"
    "      --group-size L     widest shooter group (default: 4 patch sizes; also\n"
    "                         no wider than the distance to what it lights)\n"
    "      --no-subdivide     keep the mesh as built (default: divide where light changes)\n"
    "      --no-waves         one wave: never restart on the finer mesh\n"
    "      --subdivide-floor F  lowest dividing-factor threshold (default 0.2)\n"
    "      --min-element L    smallest element edge made by dividing (default: diagonal / 400)\n"
    "      --max-level N      deepest division below the built elements, 0..12 (default 2)\n"
    "      --wave-fraction F  a new wave after F of the elements divided (default 0.2)\n"
    "      --split            split shooter patches lit unevenly or with receivers\n"
    "                         close (the default)\n"
    "      --no-split         keep the shooter patches as built\n"
    "      --split-floor F    lowest shooter-division threshold (default 0.8)\n"
    "      --split-near K     split a patch with receivers nearer than K times its\n"
    "                         width, 0: never (default 0.35)\n"
    "      --no-rotate        keep the hemicube aligned (default: turned per shot)\n"
    "      --seed N           seed of the hemicube turns (default 1)\n"
    "      --log-every N      shots between log.csv rows (default: patches / 100)\n"
    "      --checkpoint FILE  save the run's state in FILE every --checkpoint-every\n"
    "                         seconds and when it stops (written beside it, renamed)\n"
    "      --checkpoint-every SEC  seconds between checkpoints (default 30)\n"
    "      --resume FILE      go on from checkpoint FILE (same scene and options;\n"
    "                         -e, -s, -t and the output may differ)\n"
    "      --camera \"ex ey ez tx ty tz fov\"\n"
    "      --size WxH         picture size (default 512x512)\n"
    "      --format png|ppm|exr  picture format (default png; exr: linear radiosity,\n"
    "                         32-bit float, unexposed; final.hdr is always written)\n"
    "  -q, --quiet            no progress, no messages but errors and warnings\n"
    "  -v, --verbose          a line per progress sample\n"
    "      --version          print the version\n"
    "  -h, --help             this help\n"
    "       radiosity --worker   speak the worker protocol on stdin/stdout\n"
    "       radiosity --worker --connect HOST:PORT --secret FILE\n"
    "                            the same with a master started with --listen\n";

Parsed ParseOptions(int argc, char** argv, Options* opts, std::string* err) {
  enum {
    kNoOvershoot = 256, kReference, kPatchSize, kElements, kNoRotate, kSeed,
    kLogEvery, kCamera, kSize, kFormat, kVersion, kQueue, kTimeout, kWorker, kWorkerCmd,
    kPoolThread, kNoPoolThread,
    kNoJoin, kNoSubdivide, kNoWaves, kFloor, kMinElement, kMaxLevel, kWaveFraction,
    kDumpHosts, kAcceptNewHostKeys, kListen, kSecret, kConnect, kConverge,
    kCheckpoint, kCheckpointEvery, kResume, kNoGroups, kGroupSize, kView, kSplit, kSplitFloor,
    kNoSplit, kSplitNear,
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
      {"view", required_argument, nullptr, kView},
      {"resolution", required_argument, nullptr, 'r'},
      {"epsilon", required_argument, nullptr, 'e'},
      {"shots", required_argument, nullptr, 's'},
      {"time", required_argument, nullptr, 't'},
      {"no-overshoot", no_argument, nullptr, kNoOvershoot},
      {"reference", required_argument, nullptr, kReference},
      {"converge", required_argument, nullptr, kConverge},
      {"patch-size", required_argument, nullptr, kPatchSize},
      {"elements", required_argument, nullptr, kElements},
      {"no-join", no_argument, nullptr, kNoJoin},
      {"no-groups", no_argument, nullptr, kNoGroups},
      {"group-size", required_argument, nullptr, kGroupSize},
      {"no-subdivide", no_argument, nullptr, kNoSubdivide},
      {"pool-thread", no_argument, nullptr, kPoolThread},
      {"no-pool-thread", no_argument, nullptr, kNoPoolThread},
      {"no-waves", no_argument, nullptr, kNoWaves},
      {"subdivide-floor", required_argument, nullptr, kFloor},
      {"split", no_argument, nullptr, kSplit},
      {"split-floor", required_argument, nullptr, kSplitFloor},
      {"no-split", no_argument, nullptr, kNoSplit},
      {"split-near", required_argument, nullptr, kSplitNear},
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
  Options& o = *opts;
  o.workers = std::max(1L, sysconf(_SC_NPROCESSORS_ONLN));
  bool epsilon_given = false, worker_mode = false, workers_given = false, dump_hosts = false;
  // Given on the command line: options that contradict others.
  bool quiet = false, verbose = false, no_subdivide = false, no_waves = false;
  bool pool_thread_on = false, pool_thread_off = false;
  bool wave_fraction = false;
  std::string subdivide_limit;  // the last of --subdivide-floor, --min-element, --max-level, --split-*
  std::string split_given;      // the last of --split-floor, --split-near
  bool no_split = false, split = false;  // as given: shooter division is on by default
  std::string& secret_file = o.secret_file;
  opterr = 0;
  optind = 0;  // glibc: start afresh, so that a second call parses its own argv
  int c;
  while ((c = getopt_long(argc, argv, ":o:j:H:r:e:s:t:qvh", kLong, nullptr)) != -1) {
    bool ok = true;
    // A name given empty would be ignored or misread: say so.
    if (optarg && !*optarg && (c == 'o' || c == 'H' || c == kWorkerCmd || c == kListen ||
                               c == kSecret || c == kConnect || c == kReference ||
                               c == kConverge || c == kCheckpoint || c == kResume || c == kCamera ||
                               c == kView)) {
      const option* o = kLong;
      while (o->name && o->val != c) ++o;
      BadOption(("--" + std::string(o->name)).c_str(), "", "needs a name, not an empty string", err);
      return Parsed::kError;
    }
    switch (c) {
      case 'o': o.out_dir = optarg; break;
      case 'j':
        ok = Integer("--workers", optarg, 0, kMaxLocalWorkers, &o.workers, err);
        workers_given = true;
        break;
      case kQueue: ok = Integer("--queue", optarg, 1, 64, &o.run.queue, err); break;
      case kTimeout: ok = Number("--timeout", optarg, 0.5, 86400, &o.pool.timeout_s, err); break;
      case kWorker: worker_mode = true; break;
      case kWorkerCmd: o.worker_cmd = optarg; break;
      case kPoolThread: o.pool_thread = 1; pool_thread_on = true; break;
      case kNoPoolThread: o.pool_thread = 0; pool_thread_off = true; break;
      case 'H': o.hosts_file = optarg; break;
      case kDumpHosts: dump_hosts = true; break;
      case kAcceptNewHostKeys: o.ssh.accept_new_host_keys = true; break;
      case kListen: o.listen = optarg; break;
      case kSecret: secret_file = optarg; break;
      case kConnect: o.connect = optarg; break;
      case kView: o.view = optarg; break;
      case 'r':
        ok = Integer("--resolution", optarg, 8, Hemicube::kMaxResolution, &o.run.resolution, err);
        if (ok && o.run.resolution % 2) ok = BadOption("--resolution", optarg, "must be even", err);
        break;
      case 'e':
        ok = Number("--epsilon", optarg, 1e-15, 1, &o.run.epsilon, err);
        epsilon_given = true;
        break;
      case 's': ok = Integer("--shots", optarg, 1, 1L << 50, &o.run.max_shots, err); break;
      case 't': ok = Number("--time", optarg, 1e-3, 1e9, &o.run.max_seconds, err); break;
      case kNoOvershoot: o.run.overshoot = false; break;
      case kReference: o.reference = optarg; break;
      case kConverge: o.converge = optarg; break;
      case kPatchSize:
        ok = Number("--patch-size", optarg, 1e-300, 1e300, &o.mesh.patch_size, err);
        break;
      case kElements:
        ok = Integer("--elements", optarg, 1, 64, &o.mesh.elements_per_patch, err);
        break;
      case kNoJoin: o.mesh.join = false; break;
      case kNoGroups: o.mesh.groups = false; break;
      case kGroupSize:
        ok = Number("--group-size", optarg, 1e-300, 1e300, &o.mesh.group_size, err);
        break;
      case kNoSubdivide: o.subdivide = false; no_subdivide = true; break;
      case kNoWaves: o.sub.waves = false; no_waves = true; break;
      case kFloor:
        ok = Number("--subdivide-floor", optarg, 1e-3, 100, &o.sub.floor, err);
        subdivide_limit = "--subdivide-floor";
        break;
      case kSplit: split = true; break;
      case kNoSplit: no_split = true; break;
      case kSplitNear:
        ok = Number("--split-near", optarg, 0, 100, &o.sub.split_near, err);
        subdivide_limit = split_given = "--split-near";
        break;
      case kSplitFloor:
        ok = Number("--split-floor", optarg, 1e-3, 100, &o.sub.split_floor, err);
        subdivide_limit = split_given = "--split-floor";
        break;
      case kMinElement:
        ok = Number("--min-element", optarg, 1e-300, 1e300, &o.sub.min_size, err);
        subdivide_limit = "--min-element";
        break;
      case kMaxLevel:
        ok = Integer("--max-level", optarg, 0, 12, &o.sub.max_level, err);
        subdivide_limit = "--max-level";
        break;
      case kWaveFraction:
        ok = Number("--wave-fraction", optarg, 0.01, 1, &o.sub.wave_fraction, err);
        wave_fraction = true;
        break;
      case kNoRotate: o.run.rotate = false; break;
      case kSeed: ok = Integer("--seed", optarg, 0, 0xFFFFFFFFL, &o.run.seed, err); break;
      case kLogEvery: ok = Integer("--log-every", optarg, 1, 1L << 50, &o.run.log_every, err); break;
      case kCheckpoint: o.checkpoint_file = optarg; break;
      case kCheckpointEvery:
        ok = Number("--checkpoint-every", optarg, 0.001, 1e9, &o.checkpoint_every, err);
        break;
      case kResume: o.resume_file = optarg; break;
      case kCamera: o.camera_text = optarg; break;
      case kSize: ok = Size(optarg, &o.width, &o.height, err); break;
      case kFormat:
        o.format = optarg;
        if (o.format != "png" && o.format != "ppm" && o.format != "exr")
          ok = BadOption("--format", optarg, "must be png, ppm or exr", err);
        break;
      case 'q': o.verbosity = 0; quiet = true; break;
      case 'v': o.verbosity = 2; verbose = true; break;
      case kVersion: return Parsed::kVersion;
      case 'h': return Parsed::kHelp;
      case ':':
        *err = std::string("option ") + argv[optind - 1] + " needs a value (try 'radiosity --help')";
        return Parsed::kError;
      default:
        *err = std::string("unknown option ") + argv[optind - 1] + " (try 'radiosity --help')";
        return Parsed::kError;
    }
    if (!ok) return Parsed::kError;
  }
  // Options that contradict each other: one of them would be ignored.
  std::string clash;
  if (quiet && verbose) clash = "-q and -v contradict each other";
  else if (pool_thread_on && pool_thread_off)
    clash = "--pool-thread and --no-pool-thread contradict each other";
  else if (no_subdivide && !subdivide_limit.empty())
    clash = subdivide_limit + " limits dividing, and --no-subdivide divides nothing";
  else if (no_subdivide && split)
    clash = "--split divides shooters, and --no-subdivide divides nothing";
  else if (no_split && (split || !split_given.empty()))
    clash = (split_given.empty() ? std::string("--split") : split_given) +
            " splits shooters, and --no-split splits none";
  else if (wave_fraction && (no_subdivide || no_waves))
    clash = "--wave-fraction starts waves, and " +
            std::string(no_subdivide ? "--no-subdivide" : "--no-waves") + " has none";
  if (no_split) o.sub.split = false;
  if (!clash.empty()) {
    *err = clash + " (try 'radiosity --help')";
    return Parsed::kError;
  }
  // Connect-back: the secret is read before anything else, so that a
  // file others can read stops the run before it starts.
  if (!o.listen.empty() || !o.connect.empty()) {
    if (secret_file.empty()) {
      *err = std::string(o.listen.empty() ? "--connect" : "--listen") +
             " needs --secret FILE (the same file for the master and the workers)";
      return Parsed::kError;
    }
    if (!ReadSecret(secret_file, &o.secret, err)) return Parsed::kError;
  } else if (!secret_file.empty()) {
    *err = "--secret goes with --listen or --worker --connect";
    return Parsed::kError;
  }
  if (!o.connect.empty() && !worker_mode) {
    *err = "--connect is for workers: radiosity --worker --connect HOST:PORT --secret FILE";
    return Parsed::kError;
  }
  if (worker_mode) {
    if (optind != argc) {
      *err = "--worker takes no scene: the master sends it";
      return Parsed::kError;
    }
    std::string why;
    if (!o.connect.empty() &&
        !ParseEndpoint(o.connect, true, &o.connect_host, &o.connect_port, &why)) {
      BadOption("--connect", o.connect.c_str(), why, err);
      return Parsed::kError;
    }
    return Parsed::kWorker;
  }
  if (!o.hosts_file.empty() && !ReadHosts(o.hosts_file, &o.hosts, err)) return Parsed::kError;
  if (dump_hosts) {
    if (o.hosts_file.empty()) {
      *err = "--dump-hosts needs -H FILE";
      return Parsed::kError;
    }
    return Parsed::kDumpHosts;
  }
  std::string why;
  if (!o.listen.empty() &&
      !ParseEndpoint(o.listen, false, &o.listen_host, &o.listen_port, &why)) {
    BadOption("--listen", o.listen.c_str(), why, err);
    return Parsed::kError;
  }
  // The view is for this machine's browser unless a host is named.
  if (!o.view.empty()) {
    if (!ParseEndpoint(o.view, false, &o.view_host, &o.view_port, &why)) {
      BadOption("--view", o.view.c_str(), why, err);
      return Parsed::kError;
    }
    if (o.view_host.empty()) o.view_host = "127.0.0.1";
  }
  // Remote workers take the place of local ones unless -j says otherwise.
  if (o.Remote() && !workers_given) o.workers = 0;
  if (optind < argc - 1) {
    *err = "one scene at a time, got " + std::to_string(argc - optind) + ": " + argv[optind] +
           " " + argv[optind + 1] + (argc - optind > 2 ? " ..." : "") + " (try 'radiosity --help')";
    return Parsed::kError;
  }
  if (optind != argc - 1) return Parsed::kNoScene;
  // Local workers: -j and the hosts file's localhost lines, within -j's cap.
  long local = o.workers;
  for (const HostSpec& h : o.hosts) local += h.Local() ? h.slots : 0;
  if (local > kMaxLocalWorkers) {
    *err = "-j " + std::to_string(o.workers) + " and the localhost slots of " + o.hosts_file +
           " make " + std::to_string(local) + " local workers, more than " +
           std::to_string(kMaxLocalWorkers);
    return Parsed::kError;
  }
  o.scene_path = argv[optind];
  if (!o.converge.empty() && !epsilon_given) o.run.epsilon = kConvergeEpsilon;
  // Dividing never asks less than its floor.
  o.sub.threshold = std::max(o.sub.threshold, o.sub.floor);
  o.sub.split_threshold = std::max(o.sub.split_threshold, o.sub.split_floor);
  return Parsed::kRun;
}
