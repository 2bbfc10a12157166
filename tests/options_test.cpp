#include "options.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "temp_dir.h"

namespace {

Parsed Parse(std::vector<std::string> args, Options* o, std::string* err) {
  args.insert(args.begin(), "radiosity");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return ParseOptions(int(args.size()), argv.data(), o, err);
}

// The one line a bad command line gets, or "" when it parses.
std::string Error(std::vector<std::string> args) {
  Options o;
  std::string err;
  return Parse(std::move(args), &o, &err) == Parsed::kError ? err : "";
}

Options Parses(std::vector<std::string> args) {
  Options o;
  std::string err;
  EXPECT_EQ(Parse(args, &o, &err), Parsed::kRun) << err;
  return o;
}

// A directory with a secret (mode 0600) and a hosts file in it.
class Files {
 public:
  Files() {
    secret_ = dir_.Write("secret", "0123456789abcdef0123456789abcdef\n");
    chmod(secret_.c_str(), 0600);
    hosts_ = dir_.Write("hosts", "node1 slots=2\n");
  }
  std::string Write(const std::string& name, const std::string& text) const {
    return dir_.Write(name, text);
  }
  const std::string& secret() const { return secret_; }
  const std::string& hosts() const { return hosts_; }

 private:
  TempDir dir_;
  std::string secret_, hosts_;
};

TEST(Options, Defaults) {
  const Options o = Parses({"scene.obj"});
  EXPECT_EQ(o.scene_path, "scene.obj");
  EXPECT_EQ(o.out_dir, "out");
  EXPECT_EQ(o.workers, std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)));
  EXPECT_EQ(o.run.resolution, 256);
  EXPECT_EQ(o.run.epsilon, 1e-3);
  EXPECT_EQ(o.run.max_shots, 0);
  EXPECT_EQ(o.run.max_seconds, 0);
  EXPECT_TRUE(o.run.overshoot);
  EXPECT_TRUE(o.run.rotate);
  EXPECT_EQ(o.run.seed, 1u);
  EXPECT_EQ(o.run.queue, 0);
  EXPECT_EQ(o.run.log_every, 0);
  EXPECT_EQ(o.mesh.patch_size, 0);
  EXPECT_EQ(o.mesh.elements_per_patch, 2);
  EXPECT_TRUE(o.mesh.join);
  EXPECT_TRUE(o.mesh.groups);
  EXPECT_EQ(o.mesh.group_size, 0);
  EXPECT_TRUE(o.subdivide);
  EXPECT_TRUE(o.sub.waves);
  EXPECT_EQ(o.sub.floor, 0.2);
  EXPECT_EQ(o.sub.threshold, 0.5);
  EXPECT_EQ(o.sub.max_level, 2);
  EXPECT_TRUE(o.sub.split);
  EXPECT_EQ(o.sub.split_near, 0.35);
  EXPECT_EQ(o.width, 512);
  EXPECT_EQ(o.height, 512);
  EXPECT_EQ(o.format, "png");
  EXPECT_EQ(o.verbosity, 1);
  EXPECT_EQ(o.pool.timeout_s, 10);
  EXPECT_FALSE(o.ssh.accept_new_host_keys);
  EXPECT_EQ(o.checkpoint_every, 30);
  EXPECT_TRUE(o.reference.empty() && o.converge.empty() && o.camera_text.empty());
  EXPECT_TRUE(o.checkpoint_file.empty() && o.resume_file.empty());
  EXPECT_FALSE(o.Remote());
}

TEST(Options, EveryValueOption) {
  const Options o = Parses({"-o", "res", "-j", "3", "--queue", "7", "--timeout", "2.5",
                         "--worker-cmd", "valgrind radiosity", "-r", "64", "-e", "1e-4", "-s",
                         "500", "-t", "12.5", "--no-overshoot", "--reference", "ref.csv",
                         "--patch-size", "0.25", "--elements", "3", "--no-join", "--no-groups",
                         "--group-size", "0.125", "--subdivide-floor", "0.3", "--min-element", "0.01",
                         "--max-level", "5", "--wave-fraction", "0.5", "--no-rotate", "--seed",
                         "42", "--log-every", "9", "--checkpoint", "ck", "--checkpoint-every",
                         "0.5", "--resume", "old", "--camera", "0 1 2 3 4 5 60", "--size",
                         "640x480", "--format", "ppm", "--accept-new-host-keys", "-q", "s.obj"});
  EXPECT_EQ(o.scene_path, "s.obj");
  EXPECT_EQ(o.out_dir, "res");
  EXPECT_EQ(o.workers, 3);
  EXPECT_EQ(o.run.queue, 7);
  EXPECT_EQ(o.pool.timeout_s, 2.5);
  EXPECT_EQ(o.worker_cmd, "valgrind radiosity");
  EXPECT_EQ(o.run.resolution, 64);
  EXPECT_EQ(o.run.epsilon, 1e-4);
  EXPECT_EQ(o.run.max_shots, 500);
  EXPECT_EQ(o.run.max_seconds, 12.5);
  EXPECT_FALSE(o.run.overshoot);
  EXPECT_EQ(o.reference, "ref.csv");
  EXPECT_EQ(o.mesh.patch_size, 0.25);
  EXPECT_EQ(o.mesh.elements_per_patch, 3);
  // (--no-subdivide and --no-waves contradict the limits: on their own)
  EXPECT_FALSE(Parses({"--no-subdivide", "s.obj"}).subdivide);
  EXPECT_FALSE(Parses({"--no-waves", "s.obj"}).sub.waves);
  EXPECT_FALSE(o.mesh.join);
  EXPECT_FALSE(o.mesh.groups);
  EXPECT_EQ(o.mesh.group_size, 0.125);
  EXPECT_EQ(o.sub.floor, 0.3);
  EXPECT_EQ(o.sub.min_size, 0.01);
  EXPECT_EQ(o.sub.max_level, 5);
  EXPECT_EQ(o.sub.wave_fraction, 0.5);
  EXPECT_FALSE(o.run.rotate);
  EXPECT_EQ(o.run.seed, 42u);
  EXPECT_EQ(o.run.log_every, 9);
  EXPECT_EQ(o.checkpoint_file, "ck");
  EXPECT_EQ(o.checkpoint_every, 0.5);
  EXPECT_EQ(o.resume_file, "old");
  EXPECT_EQ(o.camera_text, "0 1 2 3 4 5 60");
  EXPECT_EQ(o.width, 640);
  EXPECT_EQ(o.height, 480);
  EXPECT_EQ(o.format, "ppm");
  EXPECT_TRUE(o.ssh.accept_new_host_keys);
  EXPECT_EQ(o.verbosity, 0);
}

TEST(Options, LongFormsOfShortOptions) {
  const Options o = Parses({"--out", "d", "--workers", "0", "--resolution", "32", "--epsilon",
                         "0.01", "--shots", "5", "--time", "1", "--verbose", "s.obj"});
  EXPECT_EQ(o.out_dir, "d");
  EXPECT_EQ(o.workers, 0);
  EXPECT_EQ(o.run.resolution, 32);
  EXPECT_EQ(o.run.epsilon, 0.01);
  EXPECT_EQ(o.run.max_shots, 5);
  EXPECT_EQ(o.run.max_seconds, 1);
  EXPECT_EQ(o.verbosity, 2);
  // -q and -v together are refused (ContradictionsAreRefused); the scene
  // may come first.
  EXPECT_EQ(Parses({"s.obj", "-q"}).verbosity, 0);
  EXPECT_EQ(Parses({"s.obj", "-j", "0"}).scene_path, "s.obj");
}

TEST(Options, PoolThreadIsAutomaticUnlessSaid) {
  EXPECT_EQ(Parses({"s.obj"}).pool_thread, -1);
  EXPECT_EQ(Parses({"--pool-thread", "s.obj"}).pool_thread, 1);
  EXPECT_EQ(Parses({"--no-pool-thread", "s.obj"}).pool_thread, 0);
}

TEST(Options, HelpAndVersion) {
  Options o;
  std::string err;
  EXPECT_EQ(Parse({"-h"}, &o, &err), Parsed::kHelp);
  EXPECT_EQ(Parse({"--help", "x.obj"}, &o, &err), Parsed::kHelp);
  EXPECT_EQ(Parse({"--version"}, &o, &err), Parsed::kVersion);
  // Taken in order: a bad option before --help is the error.
  EXPECT_EQ(Parse({"--bogus", "--help"}, &o, &err), Parsed::kError);
  EXPECT_EQ(Parse({"--help", "--bogus"}, &o, &err), Parsed::kHelp);
  EXPECT_EQ(std::string(kUsage).rfind("usage: radiosity [options] SCENE.obj\n", 0), 0u);
}

TEST(Options, NoSceneOrTwo) {
  Options o;
  std::string err;
  EXPECT_EQ(Parse({}, &o, &err), Parsed::kNoScene);
  EXPECT_EQ(Parse({"-j", "0"}, &o, &err), Parsed::kNoScene);
  EXPECT_EQ(Parse({"a.obj", "b.obj"}, &o, &err), Parsed::kError);  // one line, not the usage
  EXPECT_EQ(err, "one scene at a time, got 2: a.obj b.obj (try 'radiosity --help')");
}

TEST(Options, UnknownOptionsAndMissingValues) {
  EXPECT_EQ(Error({"--bogus", "s.obj"}), "unknown option --bogus (try 'radiosity --help')");
  EXPECT_EQ(Error({"-x", "s.obj"}), "unknown option -x (try 'radiosity --help')");
  EXPECT_EQ(Error({"s.obj", "--out"}), "option --out needs a value (try 'radiosity --help')");
  EXPECT_EQ(Error({"s.obj", "-o"}), "option -o needs a value (try 'radiosity --help')");
  EXPECT_EQ(Error({"s.obj", "--size"}), "option --size needs a value (try 'radiosity --help')");
}

TEST(Options, BadNumbers) {
  EXPECT_EQ(Error({"-j", "two", "s.obj"}),
            "--workers 'two': not an integer (try 'radiosity --help')");
  EXPECT_EQ(Error({"-j", "257", "s.obj"}),
            "--workers '257': must be from 0 to 256 (try 'radiosity --help')");
  EXPECT_EQ(Error({"-j", "-1", "s.obj"}),
            "--workers '-1': must be from 0 to 256 (try 'radiosity --help')");
  EXPECT_EQ(Error({"-j", "3.5", "s.obj"}),
            "--workers '3.5': not an integer (try 'radiosity --help')");
  EXPECT_EQ(Error({"-j", "", "s.obj"}), "--workers '': not an integer (try 'radiosity --help')");
  EXPECT_EQ(Error({"-j", "99999999999999999999", "s.obj"}),
            "--workers '99999999999999999999': not an integer (try 'radiosity --help')");
  EXPECT_EQ(Error({"-e", "abc", "s.obj"}),
            "--epsilon 'abc': not a number (try 'radiosity --help')");
  EXPECT_EQ(Error({"-e", "2", "s.obj"}),
            "--epsilon '2': must be from 1e-15 to 1 (try 'radiosity --help')");
  EXPECT_EQ(Error({"-e", "nan", "s.obj"}), "--epsilon 'nan': not a number (try 'radiosity --help')");
  EXPECT_EQ(Error({"-e", "inf", "s.obj"}), "--epsilon 'inf': not a number (try 'radiosity --help')");
  EXPECT_EQ(Error({"-e", "1e-3x", "s.obj"}),
            "--epsilon '1e-3x': not a number (try 'radiosity --help')");
  EXPECT_EQ(Error({"-e", "1e999", "s.obj"}),
            "--epsilon '1e999': not a number (try 'radiosity --help')");
  EXPECT_EQ(Error({"-r", "7", "s.obj"}),
            "--resolution '7': must be from 8 to 4096 (try 'radiosity --help')");
  EXPECT_EQ(Error({"-r", "33", "s.obj"}),
            "--resolution '33': must be even (try 'radiosity --help')");
  EXPECT_EQ(Error({"--timeout", "0.1", "s.obj"}),
            "--timeout '0.1': must be from 0.5 to 86400 (try 'radiosity --help')");
  EXPECT_EQ(Error({"--max-level", "13", "s.obj"}),
            "--max-level '13': must be from 0 to 12 (try 'radiosity --help')");
  EXPECT_EQ(Error({"--seed", "4294967296", "s.obj"}),
            "--seed '4294967296': must be from 0 to 4294967295 (try 'radiosity --help')");
  EXPECT_EQ(Parses({"--seed", "4294967295", "s.obj"}).run.seed, 4294967295u);
  // Every numeric option has its range; the ends are in it.
  struct Range { const char* opt; const char* low; const char* high; const char* below; const char* above; };
  const Range ranges[] = {
      {"--queue", "1", "64", "0", "65"},
      {"--timeout", "0.5", "86400", "0.4", "86401"},
      {"-r", "8", "4096", "6", "4098"},
      {"-e", "1e-15", "1", "1e-16", "1.1"},
      {"-s", "1", "1125899906842624", "0", "1125899906842625"},
      {"-t", "0.001", "1e9", "0.0009", "2e9"},
      {"--patch-size", "1e-300", "1e300", "0", "1e301"},
      {"--elements", "1", "64", "0", "65"},
      {"--group-size", "1e-300", "1e300", "0", "1e301"},
      {"--subdivide-floor", "0.001", "100", "0.0009", "101"},
      {"--min-element", "1e-300", "1e300", "0", "1e301"},
      {"--max-level", "0", "12", "-1", "13"},
      {"--wave-fraction", "0.01", "1", "0.009", "1.5"},
      {"--seed", "0", "4294967295", "-1", "4294967296"},
      {"--log-every", "1", "1125899906842624", "0", "1125899906842625"},
      {"--checkpoint-every", "0.001", "1e9", "0", "1e10"},
      {"-j", "0", "256", "-1", "257"},
  };
  for (const Range& r : ranges) {
    EXPECT_EQ(Error({r.opt, r.low, "s.obj"}), "") << r.opt;
    EXPECT_EQ(Error({r.opt, r.high, "s.obj"}), "") << r.opt;
    EXPECT_NE(Error({r.opt, r.below, "s.obj"}).find("must be from"), std::string::npos) << r.opt;
    EXPECT_NE(Error({r.opt, r.above, "s.obj"}).find("must be from"), std::string::npos) << r.opt;
    EXPECT_NE(Error({r.opt, "x", "s.obj"}).find("not a"), std::string::npos) << r.opt;
  }
}

TEST(Options, Format) {
  EXPECT_EQ(Parses({"--format", "png", "s.obj"}).format, "png");
  EXPECT_EQ(Parses({"--format", "exr", "s.obj"}).format, "exr");
  EXPECT_EQ(Error({"--format", "jpg", "s.obj"}),
            "--format 'jpg': must be png, ppm or exr (try 'radiosity --help')");
  EXPECT_EQ(Error({"--format", "PNG", "s.obj"}),
            "--format 'PNG': must be png, ppm or exr (try 'radiosity --help')");
  EXPECT_NE(Error({"--format", "hdr", "s.obj"}), "");  // final.hdr is always written
}

TEST(Options, SizeForms) {
  Options o = Parses({"--size", "1x1", "s.obj"});
  EXPECT_EQ(o.width, 1);
  EXPECT_EQ(o.height, 1);
  o = Parses({"--size", "16384x4096", "s.obj"});
  EXPECT_EQ(o.width, 16384);
  EXPECT_EQ(o.height, 4096);
  o = Parses({"--size", "8192x8192", "s.obj"});
  EXPECT_EQ(o.width, 8192);
  const std::string form = " (try 'radiosity --help')";
  for (const char* bad : {"640", "640x", "x480", "640X480", "640x480x2", "640x480 ", "640*480",
                          "640x+480", "640x-480", "axb", "", "640x99999999999999999999"})
    EXPECT_EQ(Error({"--size", bad, "s.obj"}),
              "--size '" + std::string(bad) + "': expected WIDTHxHEIGHT" + form) << bad;
  for (const char* big : {"0x10", "10x0", "-5x10", "16385x1", "1x16385"})
    EXPECT_EQ(Error({"--size", big, "s.obj"}),
              "--size '" + std::string(big) + "': width and height must be from 1 to 16384" + form)
        << big;
  EXPECT_EQ(Error({"--size", "8193x8192", "s.obj"}),
            "--size '8193x8192': at most 67108864 pixels (8192x8192)" + form);
  EXPECT_EQ(Error({"--size", "16384x16384", "s.obj"}),
            "--size '16384x16384': at most 67108864 pixels (8192x8192)" + form);
}

TEST(Options, ConvergeLowersEpsilonUnlessGiven) {
  const Options o = Parses({"--converge", "ref.csv", "s.obj"});
  EXPECT_EQ(o.converge, "ref.csv");
  EXPECT_EQ(o.run.epsilon, 1e-5);
  EXPECT_EQ(Parses({"--converge", "ref.csv", "-e", "1e-4", "s.obj"}).run.epsilon, 1e-4);
  EXPECT_EQ(Parses({"-e", "1e-3", "--converge", "ref.csv", "s.obj"}).run.epsilon, 1e-3);
}

TEST(Options, ThresholdNeverBelowFloor) {
  EXPECT_EQ(Parses({"--subdivide-floor", "0.7", "s.obj"}).sub.threshold, 0.7);
  EXPECT_EQ(Parses({"--subdivide-floor", "0.01", "s.obj"}).sub.threshold, 0.5);
}

TEST(Options, RemoteWorkersDefaultToNoLocalOnes) {
  Files f;
  Options o = Parses({"-H", f.hosts(), "s.obj"});
  EXPECT_EQ(o.workers, 0);
  ASSERT_EQ(o.hosts.size(), 1u);
  EXPECT_EQ(o.hosts[0].slots, 2);
  EXPECT_TRUE(o.Remote());
  EXPECT_EQ(Parses({"-H", f.hosts(), "-j", "2", "s.obj"}).workers, 2);
  EXPECT_EQ(Parses({"-j", "2", "--hosts", f.hosts(), "s.obj"}).workers, 2);

  o = Parses({"--listen", "127.0.0.1:0", "--secret", f.secret(), "s.obj"});
  EXPECT_EQ(o.workers, 0);
  EXPECT_EQ(o.listen_host, "127.0.0.1");
  EXPECT_EQ(o.listen_port, 0);
  EXPECT_EQ(o.secret, "0123456789abcdef0123456789abcdef");
  EXPECT_TRUE(o.Remote());
  EXPECT_EQ(Parses({"--listen", "7000", "--secret", f.secret(), "-j", "1", "s.obj"}).workers, 1);
  EXPECT_EQ(Parses({"--listen", "7000", "--secret", f.secret(), "s.obj"}).listen_port, 7000);
}

TEST(Options, ConnectBackNeedsASecret) {
  Files f;
  EXPECT_EQ(Error({"--listen", "7000", "s.obj"}),
            "--listen needs --secret FILE (the same file for the master and the workers)");
  EXPECT_EQ(Error({"--worker", "--connect", "h:1"}),
            "--connect needs --secret FILE (the same file for the master and the workers)");
  EXPECT_EQ(Error({"--secret", f.secret(), "s.obj"}),
            "--secret goes with --listen or --worker --connect");
  EXPECT_EQ(Error({"--connect", "h:1", "--secret", f.secret(), "s.obj"}),
            "--connect is for workers: radiosity --worker --connect HOST:PORT --secret FILE");
  const std::string open = f.Write("open", "0123456789abcdef0123456789abcdef\n");
  chmod(open.c_str(), 0644);
  EXPECT_NE(Error({"--listen", "7000", "--secret", open, "s.obj"})
                .find(": the secret may be read or changed by others (mode 0644)"),
            std::string::npos);
  // The secret is read before the scene is asked for.
  Options o;
  std::string err;
  EXPECT_EQ(Parse({"--listen", "7000", "--secret", open}, &o, &err), Parsed::kError);
}

TEST(Options, BadEndpoints) {
  Files f;
  EXPECT_EQ(Error({"--listen", "nope:port", "--secret", f.secret(), "s.obj"}).rfind(
                "--listen 'nope:port': ", 0),
            0u);
  EXPECT_EQ(Error({"--worker", "--connect", "7000", "--secret", f.secret()}).rfind(
                "--connect '7000': ", 0),
            0u);
}

TEST(Options, ViewIsOnLoopbackUnlessAHostIsNamed) {
  Options o = Parses({"s.obj"});
  EXPECT_EQ(o.view, "");
  o = Parses({"--view", "8080", "s.obj"});
  EXPECT_EQ(o.view_host, "127.0.0.1");
  EXPECT_EQ(o.view_port, 8080);
  o = Parses({"--view", "0.0.0.0:0", "s.obj"});
  EXPECT_EQ(o.view_host, "0.0.0.0");
  EXPECT_EQ(o.view_port, 0);
  EXPECT_EQ(Parses({"--view", "[::1]:9000", "s.obj"}).view_host, "::1");
  EXPECT_EQ(Error({"--view", "70000", "s.obj"}),
            "--view '70000': bad port '70000' (must be 0 to 65535) (try 'radiosity --help')");
  EXPECT_EQ(Error({"--view", "", "s.obj"}),
            "--view '': needs a name, not an empty string (try 'radiosity --help')");
  EXPECT_EQ(Error({"--view", ":80", "s.obj"}),
            "--view ':80': empty host before ':' (try 'radiosity --help')");
}

TEST(Options, Worker) {
  Files f;
  Options o;
  std::string err;
  EXPECT_EQ(Parse({"--worker"}, &o, &err), Parsed::kWorker);
  EXPECT_TRUE(o.connect_host.empty());
  EXPECT_EQ(Error({"--worker", "s.obj"}), "--worker takes no scene: the master sends it");
  Options c;
  EXPECT_EQ(Parse({"--worker", "--connect", "example.org:4000", "--secret", f.secret()}, &c, &err),
            Parsed::kWorker)
      << err;
  EXPECT_EQ(c.connect_host, "example.org");
  EXPECT_EQ(c.connect_port, 4000);
  EXPECT_EQ(c.secret, "0123456789abcdef0123456789abcdef");
}

TEST(Options, DumpHosts) {
  Files f;
  Options o;
  std::string err;
  EXPECT_EQ(Parse({"--dump-hosts", "-H", f.hosts()}, &o, &err), Parsed::kDumpHosts);
  EXPECT_EQ(o.hosts.size(), 1u);
  EXPECT_EQ(Error({"--dump-hosts"}), "--dump-hosts needs -H FILE");
  EXPECT_EQ(Error({"--dump-hosts", "-H", "/nonexistent/hosts"}).rfind("/nonexistent/hosts", 0),
            0u);
  const std::string bad = f.Write("bad", "node1 slots=zero\n");
  EXPECT_NE(Error({"-H", bad, "s.obj"}).find(bad + ":1"), std::string::npos);
}

}  // namespace

// Careless command lines (issue 18, item 11): an empty name, a secret
// anyone may execute, options that cancel each other, more local workers
// than -j allows, each refused with one line.
TEST(Options, EmptyNamesAreRefused) {
  Files f;
  EXPECT_EQ(Error({"-o", "", "s.obj"}),
            "--out '': needs a name, not an empty string (try 'radiosity --help')");
  EXPECT_EQ(Error({"--camera", "", "s.obj"}),
            "--camera '': needs a name, not an empty string (try 'radiosity --help')");
  EXPECT_EQ(Error({"--checkpoint=", "s.obj"}),
            "--checkpoint '': needs a name, not an empty string (try 'radiosity --help')");
  EXPECT_EQ(Error({"--listen", "", "--secret", f.secret(), "s.obj"}),
            "--listen '': needs a name, not an empty string (try 'radiosity --help')");
  for (const char* opt : {"--resume", "--reference", "--converge", "--secret", "--hosts",
                          "--worker-cmd"})
    EXPECT_NE(Error({opt, "", "s.obj"}), "") << opt;
}

TEST(Options, ContradictionsAreRefused) {
  EXPECT_EQ(Error({"-q", "-v", "s.obj"}), "-q and -v contradict each other (try 'radiosity --help')");
  EXPECT_EQ(Error({"--pool-thread", "--no-pool-thread", "s.obj"}),
            "--pool-thread and --no-pool-thread contradict each other (try 'radiosity --help')");
  EXPECT_EQ(Error({"--no-subdivide", "--max-level", "3", "s.obj"}),
            "--max-level limits dividing, and --no-subdivide divides nothing (try 'radiosity --help')");
  EXPECT_EQ(Error({"--min-element", "0.1", "--no-subdivide", "s.obj"}),
            "--min-element limits dividing, and --no-subdivide divides nothing (try 'radiosity --help')");
  EXPECT_EQ(Error({"--no-waves", "--wave-fraction", "0.5", "s.obj"}),
            "--wave-fraction starts waves, and --no-waves has none (try 'radiosity --help')");
  EXPECT_EQ(Error({"--split", "--no-split", "s.obj"}),
            "--split splits shooters, and --no-split splits none (try 'radiosity --help')");
  EXPECT_EQ(Error({"--no-split", "--split-near", "0.5", "s.obj"}),
            "--split-near splits shooters, and --no-split splits none (try 'radiosity --help')");
  EXPECT_EQ(Error({"--split", "--no-subdivide", "s.obj"}),
            "--split divides shooters, and --no-subdivide divides nothing (try 'radiosity --help')");
  EXPECT_FALSE(Parses({"--no-split", "s.obj"}).sub.split);
  EXPECT_TRUE(Parses({"--split", "s.obj"}).sub.split);  // the default, said
  Parses({"--no-subdivide", "--no-waves", "s.obj"});  // the same said twice
}

TEST(Options, ASecretOnlyItsOwnerMayReadOrWrite) {
  Files f;
  const std::string exec = f.Write("exec", "0123456789abcdef0123456789abcdef\n");
  chmod(exec.c_str(), 0700);
  EXPECT_EQ(Error({"--listen", "7000", "--secret", exec, "s.obj"}),
            exec + ": the secret must be mode 0600 or 0400, not 0700: chmod 600 " + exec);
}

TEST(Options, LocalWorkersStayWithinTheCap) {
  Files f;
  std::string many;
  for (int i = 0; i < 2; ++i) many += "localhost slots=200\n";
  const std::string hosts = f.Write("many", many);
  EXPECT_EQ(Error({"-H", hosts, "s.obj"}),
            "-j 0 and the localhost slots of " + hosts + " make 400 local workers, more than 256");
  EXPECT_EQ(Error({"-j", "100", "-H", f.Write("one", "localhost slots=200\n"), "s.obj"}),
            "-j 100 and the localhost slots of " + f.Write("one", "localhost slots=200\n") +
                " make 300 local workers, more than 256");
  std::string all;
  for (int i = 0; i < 17; ++i) all += "node" + std::to_string(i) + " slots=256\n";
  EXPECT_EQ(Error({"-H", f.Write("all", all), "s.obj"}),
            f.Write("all", all) + ":17: more than 4096 slots in all");
}
