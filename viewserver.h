// The live view's HTTP server (--view): cpp-httplib on threads of its own
// serves the page (view.h), state.json and mesh.bin from what the solver
// thread publishes. The solver thread never waits for a request: it hands
// its rows and mesh snapshots over under a mutex it only tries to take
// (what it cannot hand over now goes with the next sample), and a mesh
// is encoded by the thread that serves it, not by the solver.
#ifndef RADIOSITY_VIEWSERVER_H
#define RADIOSITY_VIEWSERVER_H

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "image.h"
#include "results.h"
#include "view.h"

class ViewServer {
 public:
  // Limits (man page, --view). A connection is served by one of kThreads
  // threads; at most kQueued more wait for one; past that the accepting
  // thread serves the next itself, so that it accepts none until that one
  // is done and the rest wait in the kernel's backlog: the process holds at
  // most kThreads + kQueued + 1 connections whatever the clients do.
  static constexpr int kThreads = 8;
  static constexpr int kQueued = 64;
  static constexpr int kBacklog = 128;
  // Seconds: to send a request or a first byte (a silent client), between
  // bytes of a request (a slow one), and for each write of a response.
  static constexpr int kIdleTimeout = 2;
  static constexpr int kReadTimeout = 2;
  static constexpr int kWriteTimeout = 5;
  // One request per connection: an idle kept-alive connection (a
  // browser's, between its polls) would hold a thread, and the end of the
  // run would wait for it; a new loopback connection per poll costs
  // nothing.
  static constexpr int kKeepAliveRequests = 1;
  static constexpr size_t kMaxPayload = 1024;  // a request body: none is needed
  // A mesh snapshot at most every kInterval seconds, and no sooner than
  // kCostFactor times the last one's cost after it: at most 1/kCostFactor
  // of the solver's time goes into snapshots on a scene of any size.
  static constexpr double kInterval = 1.0;
  static constexpr double kCostFactor = 50;
  // How long the end of the run waits for a connection still being served.
  static constexpr double kStopWait = 1.0;

  // `rows`: log.csv's rows so far (those of a resumed run).
  ViewServer(const ViewInfo& info, std::vector<LogRow> rows);
  ~ViewServer();  // Stop()
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  // Binds HOST:PORT (PORT 0: a free one) and starts serving; *bound gets
  // the address ("127.0.0.1:8080"). False with *err.
  bool Start(const std::string& host, int port, std::string* bound, std::string* err);
  // Stops serving; waits kStopWait at most for connections still being
  // served (a client stalled inside a request may hold a thread up to its
  // timeouts, and a run never waits for that: the thread is left to end
  // with the process).
  void Stop();

  // The solver's thread. A row of log.csv and the workers alive.
  void Row(const LogRow& row, int workers);
  // Whether a mesh snapshot is wanted now (kInterval, kCostFactor).
  bool SnapshotDue() const;
  // A snapshot of the mesh as `shade` makes it, at `shots`; timed, with
  // its hand-over, as what it costs the solver.
  void Snapshot(long shots, const std::function<ShadedMesh()>& shade);
  // The run has ended: the final mesh, encoded (ViewMeshBlob), and how it
  // ended. Served until Stop().
  void Finish(std::string mesh_blob, long shots, const std::string& status);
  // What the snapshots cost the solver: how many, seconds in all, the
  // most one took.
  long snapshots() const { return snapshots_; }
  double snapshot_seconds() const { return snapshot_s_; }
  double max_snapshot_seconds() const { return max_snapshot_s_; }

 private:
  struct Shared;
  void Hand();  // pending rows and snapshot to shared_, if its mutex is free

  // Shared with the server's threads; left behind (never freed) when Stop
  // gives up on a thread, which may still use it.
  Shared* shared_;
  // The solver's side: what it could not hand over yet, and the costs.
  std::vector<LogRow> rows_;
  int workers_ = 0;
  std::unique_ptr<ShadedMesh> mesh_;
  long mesh_shots_ = 0;
  double last_snapshot_ = -1e300, last_cost_ = 0;
  long snapshots_ = 0;
  double snapshot_s_ = 0, max_snapshot_s_ = 0;
};

#endif
