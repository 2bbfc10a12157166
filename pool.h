// The local pool: worker processes behind byte streams (Conn), started
// here (SpawnLocal), connected back or over ssh (a WorkerSource), driven by
// one epoll(7) loop that speaks the protocol of doc/protocol.txt with
// heartbeats both ways and deadlines.
#ifndef RADIOSITY_POOL_H
#define RADIOSITY_POOL_H

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <sys/epoll.h>
#include <sys/types.h>
#include <unordered_map>
#include <vector>

#include "clock.h"
#include "mesh.h"
#include "protocol.h"
#include "transport.h"

// A byte stream to one worker process: a socket or pipe pair, or an ssh
// channel. Non-blocking: Read/Write return -1 with errno EAGAIN when they
// would block, 0 from Read at end of stream.
class Conn {
 public:
  virtual ~Conn() = default;
  virtual int fd() const = 0;  // to poll; several Conns may share one (ssh)
  // The poll(2) events to wait for, asked before every poll: POLLIN, and
  // POLLOUT when `writing` (bytes wait to be written). An ssh channel may
  // push its session's pending output here and ask for POLLOUT on its own
  // account, or not at all while its window is shut.
  virtual short Events(bool writing);
  // True when Read would return at once although the fd may not be
  // readable: bytes or the end of the stream are buffered in this process
  // (an ssh channel whose packets came in while a sibling channel read).
  virtual bool Buffered() { return false; }
  virtual long Read(char* buf, size_t n) = 0;
  virtual long Write(const char* buf, size_t n) = 0;
  // Ends the stream and the process behind it, unless `kill` giving it
  // 1 s to exit at the end of its input first; returns how it ended
  // ("exited with status 3", "killed by signal 9"), or "" if unknown.
  std::string Close(bool kill);
  // Close's steps, so that many can end at once: the end of the stream
  // (a worker exits at the end of its input); whether the process behind
  // it has ended, without waiting (true when there is none); and the end,
  // killing it if it has not, with how it ended.
  virtual void Hangup() = 0;
  virtual bool Ended() = 0;
  virtual std::string Reap() = 0;
};

// How a worker process ended with this exit status, as Close() says it.
std::string DescribeExit(int status);

// Starts `argv` (this binary with --worker, or a --worker-cmd) with a
// socketpair on its stdin and stdout.
std::unique_ptr<Conn> SpawnLocal(const std::vector<std::string>& argv, pid_t* pid,
                                 std::string* err);

// A worker on the other end of a connected socket, started by someone
// else (connect-back): closing it only closes the socket.
std::unique_ptr<Conn> SocketConn(int fd);

// Path of the running executable (to start local workers from).
std::string SelfExe();

struct PoolOptions {
  double heartbeat_s = 1.0;  // send a heartbeat after this much silence
  double timeout_s = 10.0;   // drop a worker silent, or given work and no column, this long
  double hello_s = 30.0;     // deadline for the worker's hello (then: heartbeats)
};

class WorkerPool;

// Brings workers to a pool while it runs: hosts being set up over ssh,
// workers connecting back. Its work happens on threads of its own or in
// Take(), never blocking the pool's poll loop for long.
class WorkerSource {
 public:
  virtual ~WorkerSource() = default;
  virtual int fd() const = 0;  // readable when Take() has something to do
  // Adds what has arrived to the pool (WorkerPool::Add).
  virtual void Take(WorkerPool* pool) = 0;
  // Workers that may still come and are worth waiting for before the
  // master concludes that it has none (hosts still being set up).
  virtual int Expected() const = 0;
  // No more workers: stop the threads, close the sockets.
  virtual void Stop() = 0;
  // A worker of the pool (of any source) has joined.
  virtual void Joined() {}
};

// Workers behind Conns, driven by epoll(7) with non-blocking I/O: the
// protocol of doc/protocol.txt, heartbeats both ways and deadlines.
class WorkerPool : public Transport {
 public:
  // Deadlines and heartbeats go by `clock` (tests drive it). `setup` is
  // encoded at once and not kept: the pool holds the scene frame only.
  // Its heartbeat_s is the workers' (normally opts.heartbeat_s). The mesh
  // comes later (SetMesh): workers are started, and sent the scene
  // (SendScene), while the master meshes it too.
  WorkerPool(const proto::SceneSetup& setup, const PoolOptions& opts,
             Clock* clock = MonotonicClock());
  WorkerPool(const proto::SceneSetup& setup, const Mesh& mesh, const PoolOptions& opts,
             Clock* clock = MonotonicClock())
      : WorkerPool(setup, opts, clock) {
    SetMesh(mesh, MeshHash(mesh));
  }
  ~WorkerPool() override;
  // The scene frame is larger than the protocol allows (a scene of some
  // millions of faces): workers cannot take it.
  bool SceneTooLarge() const { return scene_frame_.size() > proto::kMaxFrame; }
  // Bytes every worker is sent before its first work: hello and scene.
  size_t SetupBytes() const { return scene_frame_.size(); }
  // The mesh as BuildMesh made it from the scene, and its MeshHash (the
  // caller's, computed once for the run's identity too): the workers'
  // readies are checked against them. Before the first Poll.
  void SetMesh(const Mesh& mesh, uint64_t hash);
  // Writes the hello and scene frame to the workers added so far, waiting
  // for them to take it, until each has it or is lost, or `wake_fd` is
  // readable (the master is done meshing). Reads nothing: what they say
  // waits for Poll, after SetMesh; workers lost here, the first Poll
  // reports.
  void SendScene(int wake_fd);
  // Takes a new worker; the hello and the scene are sent at once.
  void Add(std::unique_ptr<Conn> conn, const std::string& name);
  // Polls `source` along with the workers from now on.
  void AddSource(std::unique_ptr<WorkerSource> source);

  int Workers() const override { return int(workers_.size()); }
  int Starting() const override;
  std::string Name(int w) const override { return workers_[w].name; }
  void Assign(int w, const proto::Assignment& a) override;
  void Divide(const std::vector<int32_t>& elems) override;
  // Divide, with the mesh's element and patch counts after it, which the
  // columns' ids are checked against from then on: Divide reads them
  // from the mesh; a pool on a thread of its own (ThreadedPool) is given
  // them, read on the thread that divides the mesh.
  void DivideTo(const std::vector<int32_t>& elems, size_t elements, size_t patches);
  void Poll(double timeout, std::vector<WorkerEvent>* events) override;
  void Send(std::vector<WorkerEvent>* events) override;
  // The run's clock: 0 until the first worker joins, so that waiting for
  // workers (connect-back, ssh set-up, start-up) does not count against
  // -t; the deadlines go by the pool's own clock. Another thread may ask
  // while this one polls (ThreadedPool), when the clock is thread-safe.
  double Now() override;
  uint64_t BytesSent() const override { return sent_; }
  uint64_t BytesReceived() const override { return received_; }
  void Shutdown() override;

 private:
  enum class State { kHello, kReady, kJoined, kLost };
  struct Worker {
    std::string name;
    std::unique_ptr<Conn> conn;
    State state = State::kHello;
    proto::FrameReader in;
    // The hello and scene frame are sent from scene_frame_ itself (a copy
    // per worker was the scene's size times the workers on the master),
    // then what is queued in `out`.
    size_t scene_sent = 0;  // bytes of scene_frame_ written
    std::string out;        // encoded frames not yet written
    size_t out_pos = 0;
    bool Writing(size_t scene) const { return scene_sent < scene || out_pos < out.size(); }
    double last_heard = 0, last_sent = 0, started = 0;
    // Patches given and not answered with a column, and when the last
    // column came (or the first of them was given): heartbeats say a
    // worker lives, columns that it works.
    long owed = 0;
    double progress = 0;
    int watched_fd = -1;  // the fd it is watched under (Watch)
    uint32_t want = 0;    // and its part of what that fd is watched for
  };
  // ended: the worker closed its end (so it is exiting: wait for its
  // status); otherwise it is killed.
  void Lose(int w, const std::string& why, std::vector<WorkerEvent>* events,
            bool ended = false);
  void Flush(int w, std::vector<WorkerEvent>* events);
  void Receive(int w, std::vector<WorkerEvent>* events);
  bool Handle(int w, proto::Msg type, std::string_view payload,
              std::vector<WorkerEvent>* events, std::string* why);
  void Queue(int w, double now);
  double Clk() const;  // seconds since the pool was made
  // Registers what each fd is to be watched for (the union of its
  // workers' Events()), changing the epoll set only where a worker's
  // changed; loses the workers of an fd that cannot be watched.
  void Watch(std::vector<WorkerEvent>* events);
  void Unwatch(int w);  // before the worker's Conn is closed

  const Mesh* mesh_ = nullptr;  // SetMesh's
  std::string scene_frame_;  // encoded once, sent to every worker
  uint64_t base_elements_ = 0, mesh_hash_ = 0;  // of the mesh as BuildMesh made it
  size_t elements_ = 0, patches_ = 0;           // of the mesh now (DivideTo)
  std::vector<WorkerEvent> early_;              // SendScene's losses, for Poll
  std::vector<int32_t> edits_;          // every Divide so far, in order
  PoolOptions opts_;
  Clock* clock_;
  std::vector<Worker> workers_;
  std::vector<std::unique_ptr<WorkerSource>> sources_;
  // epoll rather than poll(2): poll costs 8 us for 100 idle sockets here
  // (0.2 us for epoll_wait), and a master feeding a cluster polls often.
  // An fd may carry several workers (the channels of one ssh session).
  struct Watched {
    std::vector<int> workers;
    uint32_t events = 0;  // registered (0: not yet added)
  };
  int epoll_ = -1;
  std::unordered_map<int, Watched> watched_;  // by fd
  std::vector<epoll_event> fired_;            // epoll_wait's
  std::vector<int> buffered_;                 // workers with bytes read for them
  std::vector<std::pair<int, int>> unwatchable_;  // fd, errno (Watch)
  std::vector<int> dirty_;  // fds whose workers' events changed (Watch)
  std::vector<int> hear_;   // the workers of an fd that fired (Poll)
  uint64_t sent_ = 0, received_ = 0;
  double epoch_;
  std::atomic<double> joined_at_{-1};  // Clk() when the first worker joined (Now)
};

#endif
