// The cluster simulation (paper §5.2 beyond the machines at hand): the real
// scheduler (RunMaster, unchanged) drives simulated workers through the
// Transport interface on a virtual clock.
//
// What is real: every column is computed by Hemicube::Column on the master's
// mesh and sent as the bytes proto::EncodeColumn makes, and the master
// decodes it, so the shooting order, overshooting and RMS error are those of
// a real run. What is modelled: time.
//  * A worker is charged the measured CPU time of its column (the hemicube
//    and the encoding, the work a worker process does per column) times its
//    speed factor, and times any slowdown active while it computes.
//  * The master is charged its own measured time: everything its thread
//    does between the return of one Poll() and the start of the next, plus
//    the decoding of the columns Poll() hands it (a Send() between Polls
//    charges what came before it). Now() includes what is used so far, so
//    the master's notion of time runs on while it works.
//    The charge is the thread's CPU time, read twice per Poll(), so that a
//    moment the master's thread was preempted is not charged; Now() in
//    between runs on the monotonic clock, which costs no system call
//    (the CPU clock's costs 1.5 us here, and the master asks the time
//    several times per shot). A master that slept in Poll for want of
//    events also pays `wakeup_s` when one wakes it, as a real one does,
//    and every turn pays the system calls a real one makes (`io`): an
//    epoll_wait, a read per worker heard, a write per worker given work.
//  * With pool_thread (the program's ThreadedPool), the master's system
//    calls and decoding are another thread's: a column that arrives is
//    read and decoded on the pool thread's own timeline (its decoding's
//    measured CPU, an epoll_wait and a read, and a wake-up when that
//    thread was idle) and reaches the master when that is done; an
//    assignment is written there too (a write) and enters the medium
//    then. The master pays for its own work, an eventfd write when it
//    hands orders to an idle pool thread, and its wake-ups. The pool
//    thread has a core of its own, unless host_cores > 0, where it counts
//    among the busy while it works and its costs are stretched by the
//    share of the moment it starts them.
//  * The master's link is one shared medium that all frames, both ways,
//    cross one after another (FIFO by the time they are sent): a frame of
//    B bytes holds it 8B / bandwidth seconds, then arrives `latency` later.
//  * A worker may have a link of its own (link_bps) in front of the
//    medium: its frames to the master cross it first, one at a time.
//  * host_cores > 0 puts the master and every worker on one machine of that
//    many cores (processor sharing: n busy on c < n cores run at c/n speed),
//    to compare with real runs on this machine; 0 gives each its own.
// Events reach the master in time order: a worker joins at startup_s (or,
// with scene_bytes, once its scene has crossed the medium, startup_s has
// passed and its ready frame is back), its columns arrive, and a crashed
// worker is reported lost `latency` after the crash (after its frames
// already on the wire); its queued work vanishes.
// With fixed costs (column_cost_s, master_cost_s >= 0) a run is fully
// deterministic; with measured ones only the times vary.
#ifndef RADIOSITY_SIM_H
#define RADIOSITY_SIM_H

#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "hemicube.h"
#include "mesh.h"
#include "protocol.h"
#include "transport.h"

struct SimOptions {
  int workers = 1;
  // Per worker (missing entries: 1): its CPU time per column is the
  // measured one times this, so 2 is a worker half as fast.
  std::vector<double> speed_factor;
  // A worker (or every worker: -1) slowed by `factor` during [from, to).
  struct Slowdown {
    int worker;
    double from, to, factor;
  };
  std::vector<Slowdown> slowdowns;
  double latency_s = 100e-6;  // per frame, after it has left the medium
  double bandwidth_bps = 1e9; // bits/s; <= 0: unlimited
  // The link's bandwidth times `factor` during [from, to).
  struct Fluctuation {
    double from, to, factor;
  };
  std::vector<Fluctuation> bandwidth_changes;
  // Per worker (missing entries, or <= 0: none): bits/s of its own link,
  // which its frames to the master cross, one after another, before the
  // shared medium: a rate limiter on its output (pv -L in tests/throttle.sh).
  std::vector<double> link_bps;
  struct Crash {
    int worker;
    double at;
  };
  std::vector<Crash> crashes;
  double startup_s = 0;       // process start and mesh build
  // > 0: the master first sends each worker this many bytes (hello and
  // scene), at t = 0 in worker order, and each answers with a hello and a
  // ready frame; 0: no start-up traffic, every worker joins at startup_s.
  size_t scene_bytes = 0;
  int host_cores = 0;         // > 0: everyone shares one machine of this many cores
  // >= 0: charge this instead of the measurements (tests): seconds per
  // column, and seconds of master work per turn of its loop (each Poll()
  // and Send() cycle).
  double column_cost_s = -1;
  double master_cost_s = -1;
  // CPU seconds the master pays when, having nothing to do, it slept in
  // Poll and an arrival woke it (the kernel's wake-up path, which a real
  // run pays and the simulated master, never sleeping, does not):
  // MeasureWakeup() on this machine, or 0.
  double wakeup_s = 0;
  // CPU seconds of the system calls that a real master makes and the
  // simulated one does not (MeasureIo() on this machine, or 0): an
  // epoll_wait per Poll, a read per worker heard in it (all its frames in
  // one read), a write per worker given work since the last Poll or Send.
  // And those of a real worker, which a simulated one, computing in this
  // process, does not make: column_s per column (a write of its frame, a
  // poll finding nothing new, its CPU clock read twice), and wake_s more
  // for a write whose reader sleeps in epoll_wait or poll (the kernel
  // wakes it on the writer's time: an interrupt to another core, dear in
  // a virtual machine). A worker pays it for a column that finds the
  // master (or its pool thread) asleep, the master for work sent to an
  // idle worker; an idle worker woken by work pays wakeup_s, as the
  // master does.
  struct Io {
    double epoll_s = 0, read_s = 0, write_s = 0;
    double column_s = 0, wake_s = 0;
  } io;
  // The master's I/O on a thread of its own, as the program does it
  // (pool_thread.h); false: on the master's, as before it.
  bool pool_thread = true;
  // The columns' parameters, as RunOptions has them.
  int resolution = 256;
  bool rotate = true;
  unsigned seed = 1;
};

// This machine's CPU cost of one wake-up: a thread blocked in poll(2) on
// a socket, woken by another process's write every 300 us, less the same
// poll(2) and read(2) finding the byte there already, in thread CPU
// seconds per wake-up (the least of 3 rounds of 200).
double MeasureWakeup();

// This machine's CPU cost of the system calls a real run makes and the
// simulation does not (SimOptions::Io): epoll_wait finding a socket ready,
// a read of a 2 KB frame (a column's size on the shipped scenes), a write
// of an assignment, on a socketpair; a worker's per column; and what a
// write costs more when it wakes another process sleeping in epoll_wait.
// Thread CPU seconds each, the least of 3 rounds.
SimOptions::Io MeasureIo();

class SimTransport : public Transport {
 public:
  SimTransport(const Mesh& mesh, const SimOptions& opts);
  int Workers() const override { return opts_.workers; }
  int Starting() const override;
  std::string Name(int w) const override { return "simulated worker " + std::to_string(w); }
  void Assign(int w, const proto::Assignment& a) override;
  void Divide(const std::vector<int32_t>& elems) override;
  void Poll(double timeout, std::vector<WorkerEvent>* events) override;
  void Send(std::vector<WorkerEvent>* events) override;
  double Now() override;
  uint64_t BytesSent() const override { return sent_; }
  uint64_t BytesReceived() const override { return received_; }

  long Columns(int w) const { return workers_[w].columns; }  // delivered to the master
  double MasterSeconds() const { return master_s_; }  // charged to the master so far
  double PoolSeconds() const { return pool_s_; }  // charged to the pool thread so far

 private:
  struct Event {
    enum Kind {
      kSend,    // a frame of the master's enters the medium
      kWork,    // an assignment reaches its worker
      kEdit,    // a hierarchy edit reaches its worker (it shares the mesh)
      kScene,   // the scene reaches its worker: it starts up
      kReady,   // a worker has built its mesh and says so
      kJoin,    // the master learns that a worker has joined
      kColumn,  // a column frame reaches the master
      kCrash,   // a worker dies
      kLost,    // the master learns of it
      kRate,    // a slowdown begins or ends: speeds change
      kUp,      // a worker's frame has crossed its own link: onto the medium
      kDecoded, // the pool thread has read and decoded a column: to the master
    } kind;
    int worker;
    size_t bytes = 0;     // of the frame, for the medium and the counts
    Kind then = kSend;    // kSend: what its arrival is (kWork, kEdit, kScene)
    proto::Assignment a{};  // kSend, kWork
    std::string frame{};    // kColumn
    proto::Column column{}; // kDecoded
  };
  struct Worker {
    bool joined = false, lost = false;  // as the master was told
    bool crashed = false;
    std::deque<std::pair<proto::Assignment, double>> todo;  // arrived, and when
    bool busy = false;
    double left = 0;          // CPU seconds at full speed still to do on the column
    std::string frame;        // that column, encoded
    double factor = 1;
    double last_arrival = 0;  // of its frames at the master
    double link_free = 0;     // when its own link is next idle
    long columns = 0;
    long given = -1;          // the last turn (turn_) it was given work in
    int sent = 0;             // assignments on their way to it
    long heard = -1;          // the last turn whose Poll read it
  };

  void Schedule(double t, Event ev);
  // Puts `bytes` on the medium at now_; returns when they arrive.
  double Transmit(size_t bytes);
  // A frame of worker w's to the master, `ev` on its arrival: across its
  // own link first, if it has one.
  void Upload(int w, Event ev);
  double Speed(int w) const;  // column CPU seconds per second, alone on a core
  void Charge();  // the master's work since the last Poll or Send, and its writes
  // Runs the world forward: while the master works `*master_cpu` seconds
  // (master_cpu non-null), else until `until` or, with stop_on_arrival,
  // the first frame at the master.
  void Advance(double* master_cpu, double until, bool stop_on_arrival);
  void Process(Event& ev);
  // The pool thread does `cpu` seconds of work from `at` on (after waking,
  // if it was idle); returns when it is done.
  double PoolWork(double at, double cpu);
  // A column's frame decoded as the master would, into a recycled list.
  proto::Column Decode(const Event& ev);
  // Worker w starts its next column, if it has one, after `extra` CPU
  // seconds of system calls.
  void Start(int w, double extra = 0);
  void Finish(int w);
  // Whether the reader of a column sent now (the master or its pool
  // thread) sleeps in epoll_wait.
  bool ReaderAsleep() const;

  const Mesh& mesh_;
  SimOptions opts_;
  // One for all workers: a column does not depend on whose hemicube made
  // it, and one stays warm in the cache as a worker process's would, where
  // a hundred taking turns would be charged cache misses no worker has.
  Hemicube hemicube_;
  proto::Column scratch_;
  long turn_ = 0;            // the master's turns charged (Poll and Send)
  int unsent_ = 0;           // workers given work in this turn
  double io_owed_ = 0;       // system calls' CPU seconds not yet charged
  std::vector<Worker> workers_;
  std::map<std::pair<double, long>, Event> events_;  // by time, then order made
  long seq_ = 0;
  std::deque<Event> inbox_;  // reached the master, not yet polled
  double now_ = 0;
  double medium_free_ = 0;  // when the link is next idle
  double mark_;             // the thread's CPU time at the last charge
  double wall_mark_;        // the monotonic clock then
  proto::FrameReader reader_;
  size_t ready_bytes_;       // a worker's hello and ready frames
  uint64_t sent_ = 0, received_ = 0;
  double master_s_ = 0;
  double pool_free_ = 0;  // when the pool thread is next idle (pool_thread)
  double pool_s_ = 0;
  bool handed_ = false;   // orders handed to the pool thread this turn
  bool asleep_ = false;   // the master waits in Poll for an arrival
};

#endif
