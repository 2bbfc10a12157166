#include "worker.h"

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>

#include <poll.h>
#include <unistd.h>

#include "clock.h"
#include "exit_status.h"
#include "hemicube.h"
#include "memory.h"
#include "mesh.h"
#include "surface.h"
#include "protocol.h"

namespace {

// Frames to the master, from the main thread and the heartbeat thread.
class Sender {
 public:
  explicit Sender(int fd) : fd_(fd), last_(MonotonicSeconds()) {}
  bool Send(const std::string& frame) {
    std::lock_guard<std::mutex> lock(mu_);
    size_t done = 0;
    while (done < frame.size()) {
      ssize_t n = ::write(fd_, frame.data() + done, frame.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      done += size_t(n);
    }
    last_ = MonotonicSeconds();
    return true;
  }
  double last() {
    std::lock_guard<std::mutex> lock(mu_);
    return last_;
  }

 private:
  std::mutex mu_;
  int fd_;
  double last_;
};

// Sends a heartbeat whenever nothing else went out for `period` seconds
// (the master's, from the scene setup), so the master can tell a long
// column from a dead worker.
class Heartbeat {
 public:
  Heartbeat(Sender* out, double period)
      : out_(out), period_(period), thread_([this] { Loop(); }) {}
  ~Heartbeat() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }

 private:
  void Loop() {
    std::unique_lock<std::mutex> lock(mu_);
    const auto poll = std::chrono::duration<double>(period_ / 4);
    while (!cv_.wait_for(lock, poll, [this] { return stop_; })) {
      if (MonotonicSeconds() - out_->last() < period_) continue;
      std::string frame;
      proto::EncodeHeartbeat(&frame);
      if (!out_->Send(frame)) return;
    }
  }
  Sender* out_;
  const double period_;
  std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false;
  std::thread thread_;
};

class Worker {
 public:
  Worker(int in_fd, int out_fd, ColumnFn column, bool spin)
      : in_fd_(in_fd), out_(out_fd), column_(std::move(column)), spin_(spin) {}
  int Run(std::string* err);

 private:
  enum Got { kFrame, kTimeout, kEnd, kBad };
  // Waits up to `timeout` s for one frame.
  Got Read(double timeout, proto::Msg* type, std::string* payload, std::string* err);
  int Fail(const std::string& what, std::string* err) {
    *err = what;
    std::string frame;
    proto::EncodeError(what, &frame);
    out_.Send(frame);
    return kExitFailure;
  }
  // Handles one frame after setup; returns false when the worker is done
  // (*status set).
  bool Handle(proto::Msg type, const std::string& payload, int* status, std::string* err);

  int in_fd_;
  Sender out_;
  ColumnFn column_;
  bool spin_;
  proto::FrameReader in_;
  Mesh mesh_;
  // Made once the scene is in (its resolution comes with it); a member so
  // that division edits can free its copy of the mesh (Handle).
  std::unique_ptr<Hemicube> hemicube_;
  struct Todo {
    proto::Assignment a;
    double received;  // for Column::wait_s
  };
  std::deque<Todo> todo_;
  // The master sends heartbeats when idle; this much silence means it is
  // gone without closing the stream (a host that vanished).
  static constexpr double kMasterTimeout = 60.0;
  // The heartbeat period from the master's hello to the ready
  // (doc/protocol.txt): below the master's least --timeout, 0.5 s.
  static constexpr double kSetupHeartbeat = 0.25;
};

Worker::Got Worker::Read(double timeout, proto::Msg* type, std::string* payload,
                         std::string* err) {
  // `timeout` is of silence: a large scene may take longer to arrive.
  double until = MonotonicSeconds() + timeout;
  for (;;) {
    switch (in_.Next(type, payload, err)) {
      case proto::FrameReader::kFrame: return kFrame;
      case proto::FrameReader::kBad: return kBad;
      case proto::FrameReader::kNeedMore: break;
    }
    const double left = until - MonotonicSeconds();
    pollfd p{in_fd_, POLLIN, 0};
    int n = ::poll(&p, 1, left <= 0 ? 0 : int(left * 1000) + 1);
    if (n < 0 && errno != EINTR) { *err = std::string("poll: ") + std::strerror(errno); return kBad; }
    if (n == 0 && left <= 0) return kTimeout;
    if (n <= 0) continue;
    char buf[65536];
    ssize_t got = ::read(in_fd_, buf, sizeof buf);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return kEnd;
    in_.Append(buf, size_t(got));
    until = MonotonicSeconds() + timeout;
  }
}

bool Worker::Handle(proto::Msg type, const std::string& payload, int* status,
                    std::string* err) {
  std::string why;
  switch (type) {
    case proto::Msg::kWork: {
      std::vector<proto::Assignment> work;
      if (!proto::DecodeWork(payload, &work, &why)) break;
      for (const proto::Assignment& a : work) {
        if (a.patch < 0 || size_t(a.patch) >= mesh_.patches.size() || a.k < 0) {
          why = "patch " + std::to_string(a.patch) + " out of range";
          break;
        }
        // The decoder saw the members increasing from a.patch; the last
        // is the largest.
        if (a.Group() && size_t(a.group.members.back()) >= mesh_.patches.size()) {
          why = "patch " + std::to_string(a.patch) + "'s group: member " +
                std::to_string(a.group.members.back()) + " out of range";
          break;
        }
        todo_.push_back({a, MonotonicSeconds()});
      }
      if (!why.empty()) break;
      return true;
    }
    case proto::Msg::kDivide: {
      std::vector<int32_t> elems;
      if (!proto::DecodeDivide(payload, &elems, &why)) break;
      // The mesh changes, so the next column rebuilds the hemicube's copy
      // of it anyway: freed now, it does not stand beside the adjacency
      // the first division makes and the children (the worker's peak in
      // a dividing run).
      if (hemicube_) hemicube_->ReleaseCache();
      for (int32_t e : elems) {
        // Divide() and SplitPatch() CHECK these; from the wire they are
        // input, not invariants. ~p: split patch p.
        if (e < 0) {
          if (SplitPieces(mesh_, ~e) < 2) {
            why = "cannot split patch " + std::to_string(~e);
            break;
          }
          SplitPatch(&mesh_, ~e);
          continue;
        }
        if (size_t(e) >= mesh_.elems.size() || !mesh_.elems[e].IsLeaf()) {
          why = "cannot divide element " + std::to_string(e);
          break;
        }
        Divide(&mesh_, e);
      }
      if (!why.empty()) break;
      return true;
    }
    case proto::Msg::kHeartbeat: return true;
    case proto::Msg::kBye: *status = kExitOk; return false;
    case proto::Msg::kError: {
      std::string text;
      *err = proto::DecodeError(payload, &text, &why) ? "master says: " + text : why;
      *status = kExitFailure;
      return false;
    }
    default: why = std::string("unexpected ") + proto::MsgName(type) + " frame"; break;
  }
  *status = Fail(why, err);
  return false;
}

int Worker::Run(std::string* err) {
  std::string frame, coded;
  proto::EncodeHello(proto::Hello(), &frame);
  if (!out_.Send(frame)) { *err = "cannot write to the master"; return kExitFailure; }
  proto::Msg type;
  std::string payload, why;
  // Setup: the master's hello, then the scene.
  Got got = Read(kMasterTimeout, &type, &payload, &why);
  if (got == kEnd) return kExitOk;
  if (got != kFrame) return Fail(got == kTimeout ? "no hello from the master" : why, err);
  proto::Hello hello;
  if (type != proto::Msg::kHello || !proto::DecodeHello(payload, &hello, &why))
    return Fail("expected a hello: " + why, err);
  if (hello.magic != proto::kMagic || hello.version != proto::kVersion ||
      hello.build != proto::BuildId())
    return Fail("this worker is '" + proto::BuildId() + "', the master '" + hello.build + "'", err);
  // Receiving and meshing a scene of 10^6 faces takes seconds to minutes:
  // heartbeats say meanwhile that this worker lives (the scene's own period
  // is not known before it is in).
  auto setup_heartbeat = std::make_unique<Heartbeat>(&out_, kSetupHeartbeat);
  got = Read(kMasterTimeout, &type, &payload, &why);
  if (got == kEnd) return kExitOk;
  if (got != kFrame) return Fail(got == kTimeout ? "no scene from the master" : why, err);
  proto::SceneSetup setup;
  if (type != proto::Msg::kScene || !proto::DecodeScene(payload, &setup, &why))
    return Fail("expected a scene: " + why, err);
  // Decoded: the frame (25-50 bytes an element) is let go before the mesh
  // is built beside the scene, the worker's peak.
  std::string().swap(payload);
  {
    // Joined once for the estimate and the mesh, and freed surface by
    // surface as BuildMesh cuts them (their polygons and faces, about 27
    // bytes an element, stood beside the whole mesh: the worker's peak).
    std::vector<Surface> surfaces = BuildSurfaces(setup.scene, setup.mesh.join);
    if (!FitsInMemory(EstimateMesh(setup.scene, surfaces, setup.mesh).elements,
                      kWorkerBytesPerElement, UsableMemory(), &why) ||
        !BuildMesh(setup.scene, std::move(surfaces), setup.mesh, &mesh_, &why, [&setup] {
          // The faces with their vertices (some 65 bytes an element, in as
          // many blocks as faces) go back to the system before the elements
          // are made: from here BuildMesh reads only the materials.
          FreeStorage(&setup.scene.faces);
          ReturnFreeMemory();
        }))
      return Fail(why, err);
  }
  // Only the mesh is needed from here on: the scene (100-200 bytes a face)
  // is let go rather than kept for the whole run.
  setup.scene = Scene();
  // Hashed while it has its areas and centres (without them MeshHash
  // computes them again).
  const proto::Ready ready{mesh_.elems.size(), MeshHash(mesh_)};
  // Nor what only the master reads: the areas and parents, the patch
  // centres (a column computes its shooter's: Mesh::Center), the links
  // back to the scene's faces and the group index (all -1: the decoded
  // setup has groups off, so the mesh has none; the master sends each
  // group with its shooter's work, and forming them here was the
  // worker's memory peak).
  mesh_.KeepColumnsOnly();
  // Its hundreds of thousands of small blocks freed go back to the system
  // (glibc keeps them otherwise), before the hemicube's arrays come.
  ReturnFreeMemory();
  frame.clear();
  proto::EncodeReady(ready, &frame);
  setup_heartbeat.reset();
  if (!out_.Send(frame)) return kExitOk;

  hemicube_ = std::make_unique<Hemicube>(setup.resolution);
  Heartbeat heartbeat(&out_, setup.heartbeat_s);
  // The columns' copy of the mesh made now, not at the first column: at
  // 10^6 elements the master, making its shooter groups, the run's
  // identity and the solver's arrays, sends the first work 0.5 s after
  // this worker is ready, and making the copy took 0.3 s of the first
  // column after that.
  hemicube_->Prepare(mesh_);
  double heard = MonotonicSeconds();
  for (;;) {
    // Take in everything that has arrived; wait only when idle.
    for (;;) {
      const double wait = todo_.empty() && !spin_ ? 1.0 : 0.0;
      got = Read(wait, &type, &payload, &why);
      if (got == kEnd) return kExitOk;
      if (got == kBad) return Fail(why, err);
      if (got == kTimeout) {
        if (!todo_.empty()) break;
        if (MonotonicSeconds() - heard > kMasterTimeout) { *err = "the master is silent"; return kExitFailure; }
        continue;
      }
      heard = MonotonicSeconds();
      int status = kExitOk;
      if (!Handle(type, payload, &status, err)) return status;
    }
    const proto::Assignment a = todo_.front().a;
    proto::Column col;
    col.patch = a.patch;
    col.k = a.k;
    col.wait_s = MonotonicSeconds() - todo_.front().received;
    todo_.pop_front();
    const double t0 = ThreadCpuSeconds();
    frame.clear();
    if (column_) {
      column_(hemicube_.get(), mesh_, a, setup.rotate, setup.seed, &coded);
      col.compute_s = ThreadCpuSeconds() - t0;
      proto::EncodeColumn(col, coded, &frame);
    } else {
      ShotColumn(hemicube_.get(), mesh_, a.patch, a.Group(), a.k, setup.rotate, setup.seed,
                 &col.ff);
      col.compute_s = ThreadCpuSeconds() - t0;
      proto::EncodeColumn(col, &frame);
    }
    if (!out_.Send(frame)) return kExitOk;  // the master has gone: nothing to report to
  }
}

}  // namespace

int RunWorker(int in_fd, int out_fd, std::string* err, ColumnFn column, bool spin) {
  MapLargeArrays();
  Worker w(in_fd, out_fd, std::move(column), spin);
  return w.Run(err);
}
