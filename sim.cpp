#include "sim.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <string>

#include <poll.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "clock.h"

SimTransport::SimTransport(const Mesh& mesh, const SimOptions& opts)
    : mesh_(mesh), opts_(opts), hemicube_(opts.resolution), workers_(opts.workers),
      mark_(ThreadCpuSeconds()), wall_mark_(MonotonicSeconds()) {
  CHECK(opts_.workers >= 1 && opts_.host_cores >= 0 && opts_.latency_s >= 0);
  std::string frame;
  proto::EncodeHello(proto::Hello(), &frame);
  proto::EncodeReady({mesh.elems.size(), 0}, &frame);
  ready_bytes_ = frame.size();
  for (size_t w = 0; w < workers_.size(); ++w) {
    if (w < opts_.speed_factor.size()) workers_[w].factor = opts_.speed_factor[w];
    CHECK(workers_[w].factor > 0);
    if (opts_.scene_bytes > 0) {
      sent_ += opts_.scene_bytes;
      Schedule(0, {Event::kSend, int(w), opts_.scene_bytes, Event::kScene});
    } else {
      Schedule(opts_.startup_s, {Event::kJoin, int(w)});
    }
  }
  for (const SimOptions::Slowdown& s : opts_.slowdowns) {
    CHECK(s.factor > 0 && s.from <= s.to && s.worker < opts_.workers);
    Schedule(s.from, {Event::kRate, s.worker});
    if (std::isfinite(s.to)) Schedule(s.to, {Event::kRate, s.worker});
  }
  for (double bps : opts_.link_bps) CHECK(std::isfinite(bps));
  for (const SimOptions::Fluctuation& f : opts_.bandwidth_changes)
    CHECK(f.from <= f.to && f.factor >= 0 && (f.factor > 0 || std::isfinite(f.to)));
  for (const SimOptions::Crash& c : opts_.crashes) {
    CHECK(c.worker >= 0 && c.worker < opts_.workers);
    Schedule(c.at, {Event::kCrash, c.worker});
  }
}

int SimTransport::Starting() const {
  int n = 0;
  for (const Worker& w : workers_) n += !w.joined && !w.lost;
  return n;
}

double SimTransport::Now() {
  if (opts_.master_cost_s >= 0) return now_;
  return now_ + MonotonicSeconds() - wall_mark_;
}

void SimTransport::Schedule(double t, Event ev) {
  events_.emplace(std::make_pair(t, seq_++), std::move(ev));
}

// The frame goes out at the master's present moment, which runs ahead of
// now_ by the CPU it has used since Poll; it enters the medium when the
// clock gets there, in order with the workers' frames.
void SimTransport::Assign(int w, const proto::Assignment& a) {
  std::string frame;
  proto::EncodeWork({a}, &frame);
  sent_ += frame.size();
  Event ev{Event::kSend, w, frame.size(), Event::kWork};
  ev.a = a;
  const double t = Now();
  Worker& wk = workers_[size_t(w)];
  // The first work on its way to an idle worker wakes it.
  const double wake = !wk.busy && wk.todo.empty() && wk.sent == 0 ? opts_.io.wake_s : 0;
  ++wk.sent;
  if (opts_.pool_thread) {
    // Handed over (an eventfd write when the pool thread sleeps), then
    // written by it.
    if (!handed_ && pool_free_ <= t) io_owed_ += opts_.io.write_s;
    handed_ = true;
    Schedule(PoolWork(t, opts_.io.write_s + wake), ev);
    return;
  }
  Schedule(t, ev);
  io_owed_ += wake;
  unsent_ += wk.given != turn_;
  wk.given = turn_;
}

double SimTransport::PoolWork(double at, double cpu) {
  if (at > pool_free_) cpu += opts_.wakeup_s;  // it slept in epoll_wait
  pool_s_ += cpu;
  if (opts_.host_cores > 0) {
    int busy = 2;  // the master and this thread
    for (const Worker& w : workers_) busy += w.busy;
    if (busy > opts_.host_cores) cpu *= double(busy) / opts_.host_cores;
  }
  pool_free_ = std::max(at, pool_free_) + cpu;
  return pool_free_;
}

proto::Column SimTransport::Decode(const Event& ev) {
  reader_.Append(ev.frame.data(), ev.frame.size());
  proto::Msg type;
  std::string_view payload;
  std::string err;
  CHECK(reader_.Next(&type, &payload, &err) == proto::FrameReader::kFrame);
  proto::Column c;
  c.ff = Spare();
  CHECK(type == proto::Msg::kColumn && proto::DecodeColumn(payload, &c, &err));
  return c;
}

void SimTransport::Divide(const std::vector<int32_t>& elems) {
  std::string frame;
  proto::EncodeDivide(elems, &frame);
  const double t = Now();
  for (size_t w = 0; w < workers_.size(); ++w) {
    if (workers_[w].lost) continue;
    sent_ += frame.size();
    Schedule(t, {Event::kSend, int(w), frame.size(), Event::kEdit});
  }
}

double SimTransport::Transmit(size_t bytes) {
  double end = std::max(now_, medium_free_);
  if (opts_.bandwidth_bps > 0) {
    double bits = 8.0 * double(bytes);
    for (;;) {  // through the bandwidth's changes, piece by piece
      double bw = opts_.bandwidth_bps, next = HUGE_VAL;
      for (const SimOptions::Fluctuation& f : opts_.bandwidth_changes) {
        if (f.from <= end && end < f.to) {
          bw *= f.factor;
          next = std::min(next, f.to);
        } else if (f.from > end) {
          next = std::min(next, f.from);
        }
      }
      if (bw > 0 && bits <= bw * (next - end)) {
        end += bits / bw;
        break;
      }
      bits -= bw * (next - end);
      end = next;
    }
  }
  medium_free_ = end;
  return end + opts_.latency_s;
}

double SimTransport::Speed(int w) const {
  double s = 1 / workers_[w].factor;
  for (const SimOptions::Slowdown& d : opts_.slowdowns)
    if ((d.worker == w || d.worker < 0) && d.from <= now_ && now_ < d.to) s /= d.factor;
  return s;
}

// A worker takes its next assignment: the column is computed now, for
// real, and what that cost is the work the worker has to get through.
void SimTransport::Start(int w, double extra) {
  Worker& wk = workers_[w];
  if (wk.crashed || wk.busy || wk.todo.empty()) return;
  const proto::Assignment a = wk.todo.front().first;
  scratch_.patch = a.patch;
  scratch_.k = a.k;
  scratch_.wait_s = now_ - wk.todo.front().second;
  wk.todo.pop_front();
  const bool fixed = opts_.column_cost_s >= 0;
  const double t0 = ThreadCpuSeconds();
  ShotColumn(&hemicube_, mesh_, a.patch, a.Group(), a.k, opts_.rotate, opts_.seed, &scratch_.ff);
  scratch_.compute_s = (fixed ? opts_.column_cost_s : ThreadCpuSeconds() - t0) * wk.factor;
  wk.frame.clear();
  proto::EncodeColumn(scratch_, &wk.frame);
  wk.left = (fixed ? opts_.column_cost_s : ThreadCpuSeconds() - t0) + extra;
  wk.busy = true;
}

void SimTransport::Upload(int w, Event ev) {
  Worker& wk = workers_[w];
  const double bps = size_t(w) < opts_.link_bps.size() ? opts_.link_bps[size_t(w)] : 0;
  if (bps <= 0) {
    wk.last_arrival = Transmit(ev.bytes);
    Schedule(wk.last_arrival, std::move(ev));
    return;
  }
  wk.link_free = std::max(now_, wk.link_free) + 8.0 * double(ev.bytes) / bps;
  Event up{Event::kUp, w, ev.bytes};
  up.then = ev.kind;
  up.frame = std::move(ev.frame);
  Schedule(wk.link_free, std::move(up));
}

void SimTransport::Finish(int w) {
  Worker& wk = workers_[w];
  wk.busy = false;
  Event ev{Event::kColumn, w, wk.frame.size()};
  ev.frame = std::move(wk.frame);
  Upload(w, std::move(ev));
  Start(w, opts_.io.column_s + (ReaderAsleep() ? opts_.io.wake_s : 0));
}

bool SimTransport::ReaderAsleep() const {
  return opts_.pool_thread ? pool_free_ <= now_ : asleep_;
}

void SimTransport::Process(Event& ev) {
  if (ev.kind == Event::kRate) return;  // splits the time step: Advance recomputes speeds
  if (ev.kind == Event::kSend) {
    const double at = Transmit(ev.bytes);
    Event arrival{ev.then, ev.worker};
    arrival.a = ev.a;
    Schedule(at, arrival);
    return;
  }
  Worker& wk = workers_[ev.worker];
  if (wk.crashed && ev.kind != Event::kColumn && ev.kind != Event::kDecoded &&
      ev.kind != Event::kLost)
    return;  // into the void
  switch (ev.kind) {
    case Event::kUp: {  // (what a crashed worker's link held is lost with it)
      wk.last_arrival = Transmit(ev.bytes);
      Event arrival{ev.then, ev.worker, ev.bytes};
      arrival.frame = std::move(ev.frame);
      Schedule(wk.last_arrival, std::move(arrival));
      return;
    }
    case Event::kWork: {
      --wk.sent;
      const bool idle = !wk.busy && wk.todo.empty();  // asleep in poll: woken
      wk.todo.emplace_back(ev.a, now_);
      Start(ev.worker, idle ? opts_.wakeup_s : 0);
      return;
    }
    case Event::kScene:
      Schedule(now_ + opts_.startup_s, {Event::kReady, ev.worker});
      return;
    case Event::kReady:
      Upload(ev.worker, {Event::kJoin, ev.worker, ready_bytes_});
      return;
    case Event::kCrash:
      wk.crashed = true;
      wk.busy = false;
      wk.todo.clear();
      // Noticed like a closed connection: after what it had already sent.
      Schedule(std::max(now_ + opts_.latency_s, wk.last_arrival), {Event::kLost, ev.worker});
      return;
    case Event::kColumn:
      if (opts_.pool_thread) {
        // Its CPU is the pool thread's, not the master's (this runs
        // between the master's charges).
        const bool fixed = opts_.master_cost_s >= 0;
        const double c0 = fixed ? 0 : ThreadCpuSeconds();
        Event d{Event::kDecoded, ev.worker, ev.bytes};
        d.column = Decode(ev);
        const double cpu = fixed ? 0 : ThreadCpuSeconds() - c0;
        Schedule(PoolWork(now_, cpu + opts_.io.epoll_s + opts_.io.read_s), std::move(d));
        return;
      }
      inbox_.push_back(std::move(ev));
      return;
    case Event::kLost:
      // After its columns that the pool thread is still decoding (then:
      // deferred once already, behind all of them).
      if (opts_.pool_thread && pool_free_ > now_ && ev.then != Event::kLost) {
        ev.then = Event::kLost;
        Schedule(pool_free_, std::move(ev));
        return;
      }
      inbox_.push_back(std::move(ev));
      return;
    case Event::kJoin:
    case Event::kDecoded:
      inbox_.push_back(std::move(ev));
      return;
    default:  // kEdit: the workers share the master's mesh
      return;
  }
}

void SimTransport::Advance(double* master_cpu, double until, bool stop_on_arrival) {
  std::vector<double> done(workers_.size());
  for (;;) {
    if (master_cpu ? *master_cpu <= 0 : now_ >= until) return;
    if (stop_on_arrival && !inbox_.empty()) return;
    // Speeds are constant until the next event, completion or the end.
    int busy = (master_cpu != nullptr) + (opts_.pool_thread && pool_free_ > now_);
    for (const Worker& w : workers_) busy += w.busy;
    const double share =
        opts_.host_cores > 0 && busy > opts_.host_cores ? double(opts_.host_cores) / busy : 1.0;
    double t = master_cpu ? HUGE_VAL : until;
    if (!events_.empty()) t = std::min(t, events_.begin()->first.first);
    const double master_done = master_cpu ? now_ + *master_cpu / share : HUGE_VAL;
    t = std::min(t, master_done);
    for (size_t w = 0; w < workers_.size(); ++w) {
      if (!workers_[w].busy) continue;
      done[w] = now_ + workers_[w].left / (share * Speed(int(w)));
      t = std::min(t, done[w]);
    }
    // Whoever ends at t ends exactly there (no rounding leftovers).
    for (size_t w = 0; w < workers_.size(); ++w) {
      Worker& wk = workers_[w];
      if (!wk.busy) continue;
      wk.left = done[w] <= t ? 0 : wk.left - (t - now_) * share * Speed(int(w));
    }
    if (master_cpu) *master_cpu = master_done <= t ? 0 : *master_cpu - (t - now_) * share;
    now_ = t;
    for (size_t w = 0; w < workers_.size(); ++w)
      if (workers_[w].busy && workers_[w].left == 0) Finish(int(w));
    while (!events_.empty() && events_.begin()->first.first <= now_) {
      Event ev = std::move(events_.begin()->second);
      events_.erase(events_.begin());
      Process(ev);
    }
  }
}

// The master has worked since the last Poll or Send: the world moves on
// meanwhile.
void SimTransport::Charge() {
  double cpu = opts_.master_cost_s >= 0 ? opts_.master_cost_s : ThreadCpuSeconds() - mark_;
  cpu += io_owed_ + opts_.io.write_s * unsent_;
  io_owed_ = 0;
  unsent_ = 0;
  handed_ = false;
  ++turn_;
  master_s_ += cpu;
  Advance(&cpu, 0, false);
}

// A turn of the master that does not read: charged as one; what arrived
// waits in the inbox for the next Poll.
void SimTransport::Send(std::vector<WorkerEvent>*) {
  Charge();
  mark_ = ThreadCpuSeconds();
  wall_mark_ = MonotonicSeconds();
}

void SimTransport::Poll(double timeout, std::vector<WorkerEvent>* events) {
  Charge();
  if (inbox_.empty()) {
    const double slept_from = now_;
    asleep_ = true;
    Advance(nullptr, now_ + timeout, true);
    asleep_ = false;
    if (opts_.wakeup_s > 0 && now_ > slept_from && !inbox_.empty()) {
      double wake = opts_.wakeup_s;
      master_s_ += wake;
      Advance(&wake, 0, false);
    }
  }
  // Charged at the next turn: this epoll_wait, and a read per worker heard
  // (the pool thread's, with one).
  if (!opts_.pool_thread) {
    io_owed_ += opts_.io.epoll_s;
    for (const Event& ev : inbox_) {
      Worker& wk = workers_[size_t(ev.worker)];
      if (wk.heard != turn_) io_owed_ += opts_.io.read_s;
      wk.heard = turn_;
    }
  }
  // From here on it is the master's work again: decoding what arrived.
  mark_ = ThreadCpuSeconds();
  wall_mark_ = MonotonicSeconds();
  for (Event& ev : inbox_) {
    Worker& wk = workers_[ev.worker];
    switch (ev.kind) {
      case Event::kJoin:
        received_ += ev.bytes;
        wk.joined = true;
        events->push_back({WorkerEvent::kJoined, ev.worker, {}, ""});
        break;
      case Event::kLost:
        wk.lost = true;
        events->push_back({WorkerEvent::kLost, ev.worker, {}, "crashed (simulated)"});
        break;
      case Event::kColumn:
      case Event::kDecoded: {
        received_ += ev.bytes;
        ++wk.columns;
        WorkerEvent out{WorkerEvent::kColumn, ev.worker, {}, ""};
        out.column = ev.kind == Event::kDecoded ? std::move(ev.column) : Decode(ev);
        events->push_back(std::move(out));
        break;
      }
      default:
        CHECK(false);
    }
  }
  inbox_.clear();
}

double MeasureWakeup() {
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) return 0;
  constexpr int kRounds = 3, kWakes = 200;
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(sv[0]);
    for (int i = 0; i < kRounds * kWakes; ++i) {
      const double until = MonotonicSeconds() + 300e-6;
      while (MonotonicSeconds() < until) {
      }
      if (::write(sv[1], "x", 1) != 1) ::_exit(1);
    }
    ::_exit(0);
  }
  ::close(sv[1]);
  // poll(2) and a read of a byte, kWakes times on fd: CPU seconds each.
  auto each = [](int fd) {
    const double c0 = ThreadCpuSeconds();
    for (int i = 0; i < kWakes; ++i) {
      pollfd p{fd, POLLIN, 0};
      char b;
      if (::poll(&p, 1, 1000) != 1 || ::read(fd, &b, 1) != 1) return HUGE_VAL;
    }
    return (ThreadCpuSeconds() - c0) / kWakes;
  };
  double woken = HUGE_VAL, ready = HUGE_VAL;
  for (int r = 0; r < kRounds && pid > 0; ++r) woken = std::min(woken, each(sv[0]));
  ::close(sv[0]);
  if (pid > 0) ::waitpid(pid, nullptr, 0);
  // The same calls with the bytes there already: what MeasureIo charges.
  const std::string bytes(kWakes, 'x');
  for (int r = 0; r < kRounds && std::isfinite(woken); ++r) {
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) break;
    if (::write(sv[1], bytes.data(), bytes.size()) == ssize_t(bytes.size()))
      ready = std::min(ready, each(sv[0]));
    ::close(sv[0]);
    ::close(sv[1]);
  }
  return std::isfinite(woken) && std::isfinite(ready) ? std::max(0.0, woken - ready) : 0;
}

namespace {

// What writing `frame` costs more when its reader, another process, sleeps
// in epoll_wait than when it does not (thread CPU seconds, the least of 3
// rounds; 0 if it cannot be measured): 300 us between writes lets it fall
// asleep each time, back to back it has no time to.
double WakingWrite(const std::string& frame) {
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) return 0;
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(sv[1]);
    const int ep = ::epoll_create1(EPOLL_CLOEXEC);
    epoll_event ev{};
    ev.events = EPOLLIN;
    if (ep < 0 || ::epoll_ctl(ep, EPOLL_CTL_ADD, sv[0], &ev) != 0) ::_exit(1);
    char buf[65536];
    for (;;) {
      epoll_event got;
      if (::epoll_wait(ep, &got, 1, -1) < 0 && errno != EINTR) ::_exit(1);
      if (::read(sv[0], buf, sizeof buf) <= 0) ::_exit(0);
    }
  }
  ::close(sv[0]);
  constexpr int kRounds = 3, kWrites = 100;
  double woken = HUGE_VAL, awake = HUGE_VAL;
  bool ok = pid > 0;
  for (int r = 0; r < kRounds && ok; ++r) {
    double cpu = 0;
    for (int i = 0; i < kWrites && ok; ++i) {
      const double until = MonotonicSeconds() + 300e-6;
      while (MonotonicSeconds() < until) {
      }
      const double c0 = ThreadCpuSeconds();
      ok &= ::write(sv[1], frame.data(), frame.size()) == ssize_t(frame.size());
      cpu += ThreadCpuSeconds() - c0;
    }
    woken = std::min(woken, cpu / kWrites);
    cpu = 0;  // timed alike, so that the clock's own cost cancels
    for (int i = 0; i < kWrites && ok; ++i) {
      const double c0 = ThreadCpuSeconds();
      ok &= ::write(sv[1], frame.data(), frame.size()) == ssize_t(frame.size());
      cpu += ThreadCpuSeconds() - c0;
    }
    awake = std::min(awake, cpu / kWrites);
  }
  ::close(sv[1]);
  if (pid > 0) ::waitpid(pid, nullptr, 0);
  return ok ? std::max(0.0, woken - awake) : 0;
}

}  // namespace

SimOptions::Io MeasureIo() {
  SimOptions::Io io;
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) return io;
  const int ep = ::epoll_create1(EPOLL_CLOEXEC);
  epoll_event ev{};
  ev.events = EPOLLIN;
  if (ep < 0 || ::epoll_ctl(ep, EPOLL_CTL_ADD, sv[0], &ev) != 0) {
    if (ep >= 0) ::close(ep);
    ::close(sv[0]);
    ::close(sv[1]);
    return io;
  }
  constexpr int kRounds = 3, kCalls = 40;
  const std::string frame(2048, 'c'), work(24, 'w');
  std::string buf(frame.size(), '\0');
  io.epoll_s = io.read_s = io.write_s = io.column_s = HUGE_VAL;
  bool ok = true;
  // Reads what was written to sv[1] and not yet read, untimed.
  auto drain = [&](size_t left) {
    while (ok && left > 0) {
      const ssize_t n = ::read(sv[0], &buf[0], std::min(left, buf.size()));
      ok &= n > 0;
      left -= size_t(std::max<ssize_t>(n, 0));
    }
  };
  for (int r = 0; r < kRounds && ok; ++r) {
    double c0 = ThreadCpuSeconds();
    for (int i = 0; i < kCalls; ++i) ok &= ::write(sv[1], work.data(), work.size()) == ssize_t(work.size());
    io.write_s = std::min(io.write_s, (ThreadCpuSeconds() - c0) / kCalls);
    c0 = ThreadCpuSeconds();
    epoll_event got[16];
    for (int i = 0; i < kCalls; ++i) ok &= ::epoll_wait(ep, got, 16, 0) == 1;
    io.epoll_s = std::min(io.epoll_s, (ThreadCpuSeconds() - c0) / kCalls);
    drain(work.size() * kCalls);
    for (int i = 0; i < kCalls; ++i) ok &= ::write(sv[1], frame.data(), frame.size()) == ssize_t(frame.size());
    c0 = ThreadCpuSeconds();
    for (int i = 0; i < kCalls; ++i) ok &= ::read(sv[0], &buf[0], buf.size()) == ssize_t(buf.size());
    io.read_s = std::min(io.read_s, (ThreadCpuSeconds() - c0) / kCalls);
    // A worker's turn: the poll after its column finding nothing, an
    // assignment read, its column written, its CPU clock read twice.
    for (int i = 0; i < kCalls; ++i) ok &= ::write(sv[0], work.data(), work.size()) == ssize_t(work.size());
    c0 = ThreadCpuSeconds();
    for (int i = 0; i < kCalls; ++i) {
      pollfd p{sv[1], POLLIN, 0};
      ok &= ::poll(&p, 1, 0) == 1 && ::read(sv[1], &buf[0], work.size()) == ssize_t(work.size());
      ok &= ::write(sv[1], frame.data(), frame.size()) == ssize_t(frame.size());
      ok &= ThreadCpuSeconds() >= 0 && ThreadCpuSeconds() >= 0;
    }
    io.column_s = std::min(io.column_s, (ThreadCpuSeconds() - c0) / kCalls);
    drain(frame.size() * kCalls);
  }
  ::close(ep);
  ::close(sv[0]);
  ::close(sv[1]);
  if (!ok) return SimOptions::Io();
  io.wake_s = WakingWrite(frame);
  return io;
}
