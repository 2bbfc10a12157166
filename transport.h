// Workers as the master's scheduler sees them: one small interface, so the
// same scheduler drives workers in this process (inprocess.h), worker
// processes on this machine and over ssh (pool.h), a fake in unit tests and
// the cluster simulation (sim.h).
//
// Workers are numbered from 0 in the order they were started; numbers are
// never reused. A worker joins (it has built the mesh and can take work),
// sends columns, and may be lost at any time; a lost worker never sends
// again, so a column that arrives is always from a live assignment.
#ifndef RADIOSITY_TRANSPORT_H
#define RADIOSITY_TRANSPORT_H

#include <cstdint>
#include <string>
#include <vector>

#include "protocol.h"

struct WorkerEvent {
  enum Kind { kJoined, kColumn, kLost } kind;
  int worker;
  proto::Column column;  // kColumn
  std::string why;       // kLost: one line, no prefix
};

// What the scheduler must know of how a transport works.
struct Capabilities {
  // Columns are computed inside Poll, by the master's own thread: there is
  // no pipeline to fill (the scheduler selects a patch only when nothing
  // is owned, which is the sequential algorithm's order) and no workers
  // to report on.
  bool computes_in_poll = false;
};

class Transport {
 public:
  virtual ~Transport() = default;
  virtual int Workers() const = 0;              // started so far
  virtual int Starting() const = 0;             // started, not yet joined or lost
  virtual std::string Name(int w) const = 0;    // for messages: "worker 2 (pid 1234)"
  virtual Capabilities Caps() const { return {}; }
  virtual void Assign(int w, const proto::Assignment& a) = 0;
  virtual void Divide(const std::vector<int32_t>& elems) = 0;  // to all workers
  // Waits until there are events or `timeout` seconds have passed; appends.
  virtual void Poll(double timeout, std::vector<WorkerEvent>* events) = 0;
  // Sends what Assign and Divide queued, without reading or waiting (a
  // worker lost in sending is reported in `events`): between Polls, while
  // the master has columns to shoot. Transports that deliver at Assign
  // (in this process, simulated) have nothing to do.
  virtual void Send(std::vector<WorkerEvent>* /*events*/) {}
  // Seconds on the transport's clock (wall time; virtual in the simulation).
  virtual double Now() = 0;
  virtual uint64_t BytesSent() const { return 0; }
  virtual uint64_t BytesReceived() const { return 0; }
  // Stops every worker (Bye), waits briefly, then kills what is left.
  virtual void Shutdown() {}

  // A shot column's form factors handed back (the scheduler, once it has
  // shot them): the next column is decoded or computed into that storage,
  // as it stands (its size kept, so nothing is allocated or zeroed again
  // for a column no longer than one before), instead of a fresh list per
  // column (about 77 KB at 10^5 elements, a malloc and its zeroing a shot).
  void Recycle(std::vector<FormFactor>&& ff) {
    if (spare_.size() < kSpares) spare_.push_back(std::move(ff));
  }

 protected:
  // Storage for the next column's form factors: a recycled list, or an
  // empty one when none is left.
  std::vector<FormFactor> Spare() {
    if (spare_.empty()) return {};
    std::vector<FormFactor> ff = std::move(spare_.back());
    spare_.pop_back();
    return ff;
  }
  // Every list handed back so far, moved to the end of *into (to pass on
  // to a transport inside); both keep their capacity.
  void TakeSpares(std::vector<std::vector<FormFactor>>* into) {
    for (std::vector<FormFactor>& ff : spare_) into->push_back(std::move(ff));
    spare_.clear();
  }
  bool HasSpares() const { return !spare_.empty(); }

 private:
  // Columns decoded in one Poll before any is shot each take one; more
  // than a few are not worth the memory they hold.
  static constexpr size_t kSpares = 8;
  std::vector<std::vector<FormFactor>> spare_;
};

#endif
