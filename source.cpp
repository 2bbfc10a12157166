#include "source.h"

#include <fcntl.h>
#include <unistd.h>

#include "check.h"

ThreadedSource::ThreadedSource(Note note, int expected)
    : note_(std::move(note)), expected_(expected) {
  CHECK(::pipe2(wake_, O_CLOEXEC | O_NONBLOCK) == 0);
}

ThreadedSource::~ThreadedSource() {
  ::close(wake_[0]);
  ::close(wake_[1]);
}

void ThreadedSource::Deliver(Delivery d) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    done_.push_back(std::move(d));
  }
  const char byte = 1;
  if (::write(wake_[1], &byte, 1) < 0) {}  // a full pipe wakes the pool all the same
}

void ThreadedSource::Take(WorkerPool* pool) {
  char buf[256];
  while (::read(wake_[0], buf, sizeof buf) > 0) {}
  std::vector<Delivery> done;
  {
    std::lock_guard<std::mutex> lock(mu_);
    done.swap(done_);
  }
  for (Delivery& d : done) {
    expected_ -= d.settled;
    for (const auto& n : d.notes) note_(n.first, n.second);
    for (auto& w : d.workers) pool->Add(std::move(w.first), w.second);
  }
}

void ThreadedSource::Drop() {
  std::lock_guard<std::mutex> lock(mu_);
  done_.clear();
  expected_ = 0;
}
