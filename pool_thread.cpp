#include "pool_thread.h"

#include <chrono>
#include <cstdint>
#include <utility>

#include <sys/eventfd.h>
#include <unistd.h>

#include "check.h"
#include "clock.h"
#include "quiet_thread.h"

namespace {

// The eventfd that wakes the pool thread for orders, as one of the pool's
// sources: the pool's own epoll_wait watches it, so that no second wait
// is needed. Take only drains it: the orders are taken by the loop.
class WakeSource : public WorkerSource {
 public:
  explicit WakeSource(int fd) : fd_(fd) {}
  int fd() const override { return fd_; }
  void Take(WorkerPool*) override {
    uint64_t n;
    while (::read(fd_, &n, sizeof n) == ssize_t(sizeof n)) {
    }
  }
  int Expected() const override { return 0; }
  void Stop() override {}

 private:
  int fd_;
};

// How long the pool thread waits in one epoll_wait with nothing to do: the
// pool caps it at half the heartbeat for its deadlines anyway.
constexpr double kSleep = 1.0;

}  // namespace

ThreadedPool::ThreadedPool(std::unique_ptr<WorkerPool> pool, const Mesh& mesh)
    : pool_(std::move(pool)), mesh_(mesh) {
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  CHECK(wake_fd_ >= 0);  // only out of descriptors or memory
  pool_->AddSource(std::make_unique<WakeSource>(wake_fd_));
  std::vector<WorkerEvent> none;
  Publish(&none);
  seen_ = said_;
  thread_ = QuietThread([this] { Loop(); });
}

ThreadedPool::~ThreadedPool() {
  Shutdown();
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

void ThreadedPool::Assign(int w, const proto::Assignment& a) { pending_.push_back({w, a, {}}); }

void ThreadedPool::Divide(const std::vector<int32_t>& elems) {
  pending_.push_back({-1, {}, elems, mesh_.elems.size(), mesh_.patches.size()});
}

void ThreadedPool::Hand() {
  if (pending_.empty() && !HasSpares()) return;
  bool wake = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    for (Order& o : pending_) orders_.push_back(std::move(o));
    TakeSpares(&storage_);
    wake = sleeping_ && !pending_.empty();
    if (wake) sleeping_ = false;  // one write wakes it
  }
  pending_.clear();
  const uint64_t one = 1;
  if (wake) CHECK(::write(wake_fd_, &one, sizeof one) == ssize_t(sizeof one));
}

void ThreadedPool::Send(std::vector<WorkerEvent>*) { Hand(); }

void ThreadedPool::Poll(double timeout, std::vector<WorkerEvent>* events) {
  Hand();
  std::unique_lock<std::mutex> lock(mu_);
  if (events_.empty() && timeout > 0 && thread_.joinable())
    heard_.wait_for(lock, std::chrono::duration<double>(timeout),
                    [this] { return !events_.empty(); });
  for (WorkerEvent& ev : events_) events->push_back(std::move(ev));
  events_.clear();
  seen_.workers = said_.workers;
  seen_.starting = said_.starting;
  seen_.sent = said_.sent;
  seen_.received = said_.received;
  while (seen_.names.size() < said_.names.size()) seen_.names.push_back(said_.names[seen_.names.size()]);
}

void ThreadedPool::Publish(std::vector<WorkerEvent>* got) {
  const int workers = pool_->Workers(), starting = pool_->Starting();
  const bool any = !got->empty();
  {
    std::lock_guard<std::mutex> lock(mu_);
    for (WorkerEvent& ev : *got) events_.push_back(std::move(ev));
    for (int w = int(said_.names.size()); w < workers; ++w) said_.names.push_back(pool_->Name(w));
    said_.workers = workers;
    said_.starting = starting;
    said_.sent = pool_->BytesSent();
    said_.received = pool_->BytesReceived();
  }
  got->clear();
  if (any) heard_.notify_one();
}

void ThreadedPool::Loop() {
  std::vector<Order> orders;
  std::vector<std::vector<FormFactor>> storage;
  std::vector<WorkerEvent> got;
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stop_) break;
      orders.swap(orders_);
      storage.swap(storage_);
    }
    for (Order& o : orders) {
      if (o.worker >= 0) pool_->Assign(o.worker, o.a);
      else pool_->DivideTo(o.elems, o.elements, o.patches);
    }
    orders.clear();
    for (std::vector<FormFactor>& ff : storage) pool_->Recycle(std::move(ff));
    storage.clear();
    // What has come, without waiting; then, with nothing to pass on and
    // no orders, a wait that an order ends (Hand).
    pool_->Poll(0, &got);
    if (got.empty()) {
      bool idle;
      {
        std::lock_guard<std::mutex> lock(mu_);
        idle = orders_.empty() && !stop_;
        sleeping_ = idle;
      }
      if (idle) {
        pool_->Poll(kSleep, &got);
        std::lock_guard<std::mutex> lock(mu_);
        sleeping_ = false;
      }
    }
    Publish(&got);
  }
  cpu_s_ = ThreadCpuSeconds();
}

void ThreadedPool::Shutdown() {
  if (thread_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      stop_ = true;
    }
    const uint64_t one = 1;
    CHECK(::write(wake_fd_, &one, sizeof one) == ssize_t(sizeof one));
    thread_.join();
  }
  pool_->Shutdown();
}

bool UsePoolThread(int setting, long local, long cores) {
  return setting >= 0 ? setting == 1 : cores >= local + 2;
}
