// The worker pool on a thread of its own (issue 17): reading, decoding and
// writing frames, heartbeats and deadlines go on there while the master's
// thread selects and shoots. A master fed as a cluster feeds it spent about
// 7 of its 18 us a shot on the room receiving (epoll_wait, read, decoding
// the column) and 1.6 writing the assignment: that caps the speedup, and a
// master machine has a second core for it.
//
// The two threads trade through queues under one mutex, in order: orders
// (Assign, Divide, form-factor storage handed back) one way, events
// (joined, column decoded, lost) the other, with the pool's counts and
// names as they stood after them. The pool thread sleeps in the pool's
// epoll_wait; an order wakes it through an eventfd in that epoll set only
// when it sleeps (a busy pool thread finds it at its next turn). It blocks
// every signal: they go to the master's thread, as before.
//
// What this layer does not know: the protocol, the workers, deadlines (the
// pool's). After the constructor only the pool thread touches the pool,
// until Shutdown joins it; the mesh, only this thread.
#ifndef RADIOSITY_POOL_THREAD_H
#define RADIOSITY_POOL_THREAD_H

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "pool.h"

class ThreadedPool : public Transport {
 public:
  // Starts the thread: workers and sources already added are its. `mesh`
  // is the pool's, read here only (its counts at each Divide: the pool
  // thread must not read a mesh this thread divides).
  ThreadedPool(std::unique_ptr<WorkerPool> pool, const Mesh& mesh);
  ~ThreadedPool() override;

  // As the pool said them with the last events Poll returned.
  int Workers() const override { return seen_.workers; }
  int Starting() const override { return seen_.starting; }
  std::string Name(int w) const override { return seen_.names[size_t(w)]; }
  void Assign(int w, const proto::Assignment& a) override;
  void Divide(const std::vector<int32_t>& elems) override;
  // Hands the orders over; the pool thread writes them.
  void Send(std::vector<WorkerEvent>* events) override;
  // Hands the orders over and takes the events that have come, waiting up
  // to `timeout` for one when none has.
  void Poll(double timeout, std::vector<WorkerEvent>* events) override;
  double Now() override { return pool_->Now(); }
  uint64_t BytesSent() const override { return seen_.sent; }
  uint64_t BytesReceived() const override { return seen_.received; }
  // Stops the thread, then the pool (from this thread).
  void Shutdown() override;
  // The pool thread's CPU seconds, once Shutdown has stopped it.
  double CpuSeconds() const { return cpu_s_; }

 private:
  struct Order {
    int worker;  // -1: a Divide
    proto::Assignment a;
    std::vector<int32_t> elems;
    size_t elements = 0, patches = 0;  // the mesh's after the Divide
  };
  // What the pool said, copied with its events.
  struct Said {
    int workers = 0, starting = 0;
    std::vector<std::string> names;
    uint64_t sent = 0, received = 0;
  };
  void Hand();   // this thread's orders and storage to the pool thread
  void Loop();   // the pool thread
  void Publish(std::vector<WorkerEvent>* got);  // on the pool thread

  std::unique_ptr<WorkerPool> pool_;
  const Mesh& mesh_;
  int wake_fd_ = -1;  // eventfd, in the pool's epoll set (a WorkerSource)
  std::vector<Order> pending_;  // this thread's, not yet handed over
  Said seen_;                   // this thread's copy

  std::mutex mu_;  // guards what follows
  std::condition_variable heard_;  // events_ is no longer empty
  std::vector<Order> orders_;
  std::vector<std::vector<FormFactor>> storage_;
  std::vector<WorkerEvent> events_;
  Said said_;
  bool sleeping_ = false;  // the pool thread waits in epoll_wait
  bool stop_ = false;
  double cpu_s_ = 0;  // written by the thread as it ends, read after join
  std::thread thread_;
};

// Whether the pool gets a thread of its own: `setting` 1 yes, 0 no; -1
// (the default) when the machine has a core for it beside the master's
// thread and its `local` worker processes. With every core computing
// columns a second master thread only takes CPU from them, and wakes
// twice more a column (the pool thread, then the master's): -j 2 on this
// project's two cores reached 0.92-0.96 of ideal with it against
// 0.93-1.00 without, lower in 4 of 5 pairs (bench/defaults.sh, room twice,
// blender, maze, side by side).
bool UsePoolThread(int setting, long local, long cores);

#endif
