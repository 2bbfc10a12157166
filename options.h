// The command line: every option, its checks against the others, and the
// usage text. ParseOptions does all that main needs before it loads the
// scene, so that a bad command line stops before anything is started.
#ifndef RADIOSITY_OPTIONS_H
#define RADIOSITY_OPTIONS_H

#include <string>
#include <vector>

#include "hosts.h"
#include "mesh.h"
#include "pool.h"
#include "scheduler.h"
#include "ssh.h"
#include "subdivide.h"

// The text of --help (stdout) and of a command line without one scene
// (stderr).
extern const char kUsage[];

struct Options {
  std::string scene_path;
  std::string out_dir = "out";
  std::string reference, converge;  // --reference CSV, --converge CSV
  std::string camera_text;          // --camera, parsed against the scene
  std::string format = "png";
  int width = 512, height = 512;
  int verbosity = 1;  // 0 -q, 1 the progress line, 2 -v
  RunOptions run;     // stop, wave_end and the checkpoint hooks are the run's
  MeshOptions mesh;
  bool subdivide = true;
  SubdivideOptions sub;

  long workers = 0;  // -j: online cores, 0 with -H or --listen
  std::string worker_cmd;
  // --pool-thread / --no-pool-thread: the workers' I/O on a thread of its
  // own or on the master's; unset (-1): when a core is free for it
  // (UsePoolThread, pool_thread.h).
  int pool_thread = -1;
  std::string hosts_file;
  std::vector<HostSpec> hosts;  // -H FILE, read
  PoolOptions pool;
  SshOptions ssh;
  // --listen [HOST:]PORT and --connect HOST:PORT, as given and parsed.
  std::string listen, listen_host;
  int listen_port = 0;
  std::string connect, connect_host;
  int connect_port = 0;
  std::string secret_file, secret;  // --secret FILE and its contents
  // --view [HOST:]PORT as given, and parsed (HOST 127.0.0.1 unless given):
  // the live view in a browser.
  std::string view, view_host;
  int view_port = 0;
  // Workers from -H or --listen, beside or instead of the -j local ones.
  bool Remote() const { return !hosts.empty() || !listen.empty(); }
  // -j 0 and no remote workers: the master computes every column itself.
  bool Alone() const { return workers == 0 && !Remote(); }

  std::string checkpoint_file, resume_file;
  double checkpoint_every = 30;
};

// What main is to do.
enum class Parsed {
  kRun,        // solve opts->scene_path
  kHelp,       // print kUsage on stdout
  kVersion,    // print the version
  kDumpHosts,  // print opts->hosts
  kWorker,     // speak the worker protocol (on opts->connect_host if set)
  kNoScene,    // no scene: print kUsage on stderr
  kError,      // bad usage or input: *err is the line to print
};

// Parses argv (permuting it, as getopt_long does) into *opts. Reads the
// --secret and -H files, whose errors are usage errors too.
Parsed ParseOptions(int argc, char** argv, Options* opts, std::string* err);

#endif
