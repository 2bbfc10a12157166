// The part of a WorkerSource that is the same for every source whose work
// runs on threads of its own (the connect-back listener, the ssh
// launcher): those threads Deliver what they finish; Take(), on the pool's
// thread, says its notes and hands its workers to the pool, in order.
#ifndef RADIOSITY_SOURCE_H
#define RADIOSITY_SOURCE_H

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "pool.h"

class ThreadedSource : public WorkerSource {
 public:
  using Note = std::function<void(const std::string&, bool warning)>;
  // The source waits for `expected` workers until Deliveries settle them.
  ThreadedSource(Note note, int expected);
  ~ThreadedSource() override;  // a derived class has Stop()ped its threads
  int fd() const override { return wake_[0]; }
  void Take(WorkerPool* pool) final;
  int Expected() const override { return expected_; }

 protected:
  // What a thread has finished.
  struct Delivery {
    std::vector<std::pair<std::string, bool>> notes;  // said first: text, warning
    std::vector<std::pair<std::unique_ptr<Conn>, std::string>> workers;  // with their names
    int settled = 0;  // Expected() falls by this many once taken
  };
  void Deliver(Delivery d);  // any thread
  // For Stop(), once the threads have ended: no more workers, and those
  // not taken yet are stopped.
  void Drop();

 private:
  Note note_;
  int wake_[2];
  int expected_;  // the pool's thread only
  std::mutex mu_;
  std::vector<Delivery> done_;  // guarded by mu_
};

#endif
