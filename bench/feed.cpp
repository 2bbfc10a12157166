// radiosity-feed --worker: a worker that answers as fast as the master can
// take columns, to measure the master at a cluster's rate on a machine of
// two cores (bench/feed.sh). Started by the real master with
// `radiosity --worker-cmd build/radiosity-feed`, it speaks the real
// protocol through the real worker (RunWorker); only its columns differ:
// at the first assignment it computes one column per patch (ShotColumn,
// shooting alone, k 0) and from then on answers every assignment of that
// patch with it at once. The master's work per column (reading, decoding,
// shooting, selecting) is as in a run, since the columns are real ones of
// the scene; the answer is not (no turns, no groups), so runs with it are
// timed, never compared. It spins rather than sleeps while it waits for
// work, as a cluster's busy workers would not be woken by the master's
// sends: on this virtual machine waking a process costs the waker 5-20 us.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "../ffcodec.h"
#include "../worker.h"

int main(int argc, char** argv) {
  const bool sleep = argc == 3 && std::strcmp(argv[1], "--sleep") == 0;
  if (argc != 2 + sleep || std::strcmp(argv[1 + sleep], "--worker") != 0) {
    std::fprintf(stderr, "usage: radiosity --worker-cmd '%s [--sleep]' SCENE.obj (started as: %s [--sleep] --worker)\n",
                 argv[0], argv[0]);
    return 2;
  }
  // Coded once, as the frame's bytes: coding took the feed some 27 us a
  // column on the room (perf), more than the master's own work on it, so
  // coding each answer again made the feed, not the master, set the pace.
  std::vector<std::string> memo;
  std::vector<FormFactor> ff;
  ColumnFn column = [&memo, &ff](Hemicube* h, const Mesh& mesh, const proto::Assignment& a,
                                 bool rotate, unsigned seed, std::string* coded) {
    if (memo.empty()) {
      memo.resize(mesh.patches.size());
      for (size_t p = 0; p < memo.size(); ++p) {
        ShotColumn(h, mesh, int(p), nullptr, 0, rotate, seed, &ff);
        proto::PutFormFactors(ff, &memo[p]);
      }
    }
    // A patch divided since (shooter splits) has no column made: its own.
    if (size_t(a.patch) >= memo.size()) {
      ShotColumn(h, mesh, a.patch, a.Group(), a.k, rotate, seed, &ff);
      coded->clear();
      proto::PutFormFactors(ff, coded);
      return;
    }
    *coded = memo[size_t(a.patch)];
  };
  std::string err;
  const int status = RunWorker(0, 1, &err, column, /*spin=*/!sleep);
  if (status != 0) std::fprintf(stderr, "radiosity-feed: worker: %s\n", err.c_str());
  return status;
}
