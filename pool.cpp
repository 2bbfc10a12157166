#include "pool.h"

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <utility>

#include <fcntl.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "exit_status.h"

namespace {

std::string DescribeStatus(int status) {
  if (WIFEXITED(status)) return DescribeExit(WEXITSTATUS(status));
  if (WIFSIGNALED(status))
    return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" +
           strsignal(WTERMSIG(status)) + ")";
  return "ended";
}

// A worker process on this machine, on one end of a socketpair; or, with
// no pid, a worker elsewhere on the other end of a TCP connection.
class LocalConn : public Conn {
 public:
  LocalConn(int fd, pid_t pid) : fd_(fd), pid_(pid) {}
  ~LocalConn() override { Close(true); }
  int fd() const override { return fd_; }
  long Read(char* buf, size_t n) override { return long(::read(fd_, buf, n)); }
  long Write(const char* buf, size_t n) override {
    return long(::send(fd_, buf, n, MSG_NOSIGNAL));  // a dead peer is an error, not SIGPIPE
  }
  void Hangup() override {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  bool Ended() override {
    int status = 0;
    if (pid_ > 0 && ::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      how_ = DescribeStatus(status);
    }
    return pid_ <= 0;
  }
  // SIGKILL also ends a worker stopped with SIGSTOP.
  std::string Reap() override {
    Hangup();
    if (!Ended()) {
      int status = 0;
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
      pid_ = -1;
    }
    return std::exchange(how_, "");
  }

 private:
  int fd_;
  pid_t pid_;
  std::string how_;  // once reaped (Ended), until Reap() says it
};

constexpr double kExitWait = 1.0;  // seconds for workers to exit at the end of their input

bool IsAgain() { return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR; }

// Hangs up on every one of `conns` and gives them together up to
// kExitWait to end: as long as the slowest takes, not the sum.
void AwaitEnd(const std::vector<Conn*>& conns) {
  for (Conn* c : conns) c->Hangup();
  const double until = MonotonicSeconds() + kExitWait;
  std::vector<pollfd> waiting;
  for (;;) {
    waiting.clear();
    for (Conn* c : conns)
      if (!c->Ended()) waiting.push_back({c->fd(), POLLIN, 0});
    const double left = until - MonotonicSeconds();
    if (waiting.empty() || left <= 0) break;
    // A closed socket's fd is -1, which poll(2) passes over: then this is
    // a sleep of 1 ms, short beside a worker's exit (with -j 2 both were
    // reaped 4 to 8 ms after the first bye); an ssh session wakes it with
    // what comes (its channel's exit status).
    ::poll(waiting.data(), nfds_t(waiting.size()), 1);
  }
}

}  // namespace

std::string Conn::Close(bool kill) {
  if (!kill) AwaitEnd({this});
  return Reap();
}

short Conn::Events(bool writing) { return short(POLLIN | (writing ? POLLOUT : 0)); }

std::string DescribeExit(int status) {
  if (status == kExitExecFailed) return "could not be started (exit status 127)";
  return "exited with status " + std::to_string(status);
}

std::string SelfExe() {
  char buf[4096];
  ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) return "";
  buf[n] = 0;
  return buf;
}

std::unique_ptr<Conn> SpawnLocal(const std::vector<std::string>& argv, pid_t* pid_out,
                                 std::string* err) {
  CHECK(!argv.empty());
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) {
    *err = std::string("socketpair: ") + std::strerror(errno);
    return nullptr;
  }
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = ::fork();
  if (pid < 0) {
    *err = std::string("fork: ") + std::strerror(errno);
    ::close(sv[0]);
    ::close(sv[1]);
    return nullptr;
  }
  if (pid == 0) {
    // Its own process group: a Ctrl-C at the terminal reaches only the
    // master, which then stops the workers in order.
    ::setpgid(0, 0);
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
    std::signal(SIGPIPE, SIG_DFL);
    if (::dup2(sv[1], 0) < 0 || ::dup2(sv[1], 1) < 0) ::_exit(kExitExecFailed);
    ::execv(args[0], args.data());
    ::_exit(kExitExecFailed);
  }
  ::close(sv[1]);
  ::fcntl(sv[0], F_SETFL, ::fcntl(sv[0], F_GETFL) | O_NONBLOCK);
  *pid_out = pid;
  return std::make_unique<LocalConn>(sv[0], pid);
}

std::unique_ptr<Conn> SocketConn(int fd) {
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
  return std::make_unique<LocalConn>(fd, -1);
}

WorkerPool::WorkerPool(const proto::SceneSetup& setup, const PoolOptions& opts, Clock* clock)
    : opts_(opts), clock_(clock), epoch_(clock->Now()) {
  epoll_ = ::epoll_create1(EPOLL_CLOEXEC);
  CHECK(epoll_ >= 0);  // only out of memory or descriptors: nothing to run on
  proto::EncodeHello(proto::Hello(), &scene_frame_);
  proto::EncodeScene(setup, &scene_frame_);
}

void WorkerPool::SetMesh(const Mesh& mesh, uint64_t hash) {
  mesh_ = &mesh;
  base_elements_ = elements_ = mesh.elems.size();
  patches_ = mesh.patches.size();
  mesh_hash_ = hash;
}

// poll(2), not the epoll set: this runs once, before Watch has put any
// worker in it, and the wake fd is not one of its sources.
void WorkerPool::SendScene(int wake_fd) {
  std::vector<pollfd> fds;
  for (;;) {
    fds.assign(1, pollfd{wake_fd, POLLIN, 0});
    for (size_t w = 0; w < workers_.size(); ++w) {
      Worker& wk = workers_[w];
      auto done = [&] { return wk.state == State::kLost || wk.scene_sent == scene_frame_.size(); };
      if (done()) continue;
      Flush(int(w), &early_);
      if (!done()) fds.push_back({wk.conn->fd(), wk.conn->Events(true), 0});
    }
    if (fds.size() == 1) return;
    if (::poll(fds.data(), fds.size(), -1) < 0 && errno != EINTR) return;
    if (fds[0].revents) return;
  }
}

WorkerPool::~WorkerPool() {
  Shutdown();
  if (epoll_ >= 0) ::close(epoll_);
}

double WorkerPool::Clk() const { return clock_->Now() - epoch_; }

double WorkerPool::Now() {
  const double joined = joined_at_.load(std::memory_order_relaxed);
  return joined < 0 ? 0 : Clk() - joined;
}

void WorkerPool::Add(std::unique_ptr<Conn> conn, const std::string& name) {
  Worker w;
  w.name = name;
  w.conn = std::move(conn);
  w.started = w.last_heard = w.last_sent = Clk();
  // A worker that joins late (or replaces a lost one) gets the hierarchy
  // as it is now: every edit so far, in order, right after the scene.
  if (!edits_.empty()) proto::EncodeDivide(edits_, &w.out);
  workers_.push_back(std::move(w));
}

// Sources are told from workers by the top bit of the event's data.
constexpr uint64_t kSourceBit = uint64_t{1} << 63;

void WorkerPool::AddSource(std::unique_ptr<WorkerSource> source) {
  epoll_event ev{};
  ev.events = EPOLLIN;
  ev.data.u64 = kSourceBit | sources_.size();
  CHECK(::epoll_ctl(epoll_, EPOLL_CTL_ADD, source->fd(), &ev) == 0);
  sources_.push_back(std::move(source));
}

void WorkerPool::Unwatch(int w) {
  const int fd = workers_[w].watched_fd;
  workers_[w].watched_fd = -1;
  workers_[w].want = 0;
  auto it = watched_.find(fd);
  if (it == watched_.end()) return;
  std::vector<int>& ws = it->second.workers;
  ws.erase(std::remove(ws.begin(), ws.end(), w), ws.end());
  if (!ws.empty()) {  // what the fd is watched for may shrink
    dirty_.push_back(fd);
    return;
  }
  if (it->second.events) ::epoll_ctl(epoll_, EPOLL_CTL_DEL, fd, nullptr);
  watched_.erase(it);
}

void WorkerPool::Watch(std::vector<WorkerEvent>* events) {
  for (size_t w = 0; w < workers_.size(); ++w) {
    Worker& wk = workers_[w];
    if (wk.state == State::kLost) continue;
    const int fd = wk.conn->fd();
    if (wk.watched_fd != fd) {
      Unwatch(int(w));
      watched_[fd].workers.push_back(int(w));
      wk.watched_fd = fd;
    }
    // Always for input: epoll, as poll(2), reports the end of the stream
    // and errors with it. EPOLLIN, EPOLLOUT are POLLIN, POLLOUT.
    const uint32_t want =
        EPOLLIN | uint16_t(wk.conn->Events(wk.Writing(scene_frame_.size())));
    if (want != wk.want) {
      wk.want = want;
      dirty_.push_back(fd);
    }
  }
  unwatchable_.clear();
  for (int fd : dirty_) {
    auto it = watched_.find(fd);
    if (it == watched_.end()) continue;
    Watched& wd = it->second;
    uint32_t want = 0;
    for (int w : wd.workers) want |= workers_[w].want;
    if (want == wd.events) continue;
    epoll_event ev{};
    ev.events = want;
    ev.data.u64 = uint64_t(uint32_t(fd));
    if (::epoll_ctl(epoll_, wd.events ? EPOLL_CTL_MOD : EPOLL_CTL_ADD, fd, &ev) != 0) {
      unwatchable_.push_back({fd, errno});
      continue;
    }
    wd.events = want;
  }
  dirty_.clear();
  // A connection that cannot be watched (its fd closed under it) would
  // never be heard again.
  for (auto [fd, err] : unwatchable_) {
    auto it = watched_.find(fd);
    if (it == watched_.end()) continue;
    const std::vector<int> ws = it->second.workers;
    for (int w : ws) Lose(w, std::string("cannot watch its connection: ") + std::strerror(err), events);
  }
}

int WorkerPool::Starting() const {
  int n = 0;
  for (const Worker& w : workers_) n += w.state == State::kHello || w.state == State::kReady;
  for (const auto& s : sources_) n += s->Expected();
  return n;
}

void WorkerPool::Assign(int w, const proto::Assignment& a) {
  Worker& wk = workers_[w];
  // Lost before the master heard of it (later in the same batch of
  // events, or on the pool's own thread, ThreadedPool): dropped, since
  // the loss, once heard, gives every patch it owned, this one too, to
  // the others.
  if (wk.state == State::kLost) return;
  CHECK(wk.state == State::kJoined);
  if (wk.owed++ == 0) wk.progress = Clk();
  proto::EncodeWork({a}, &wk.out);
}

void WorkerPool::Divide(const std::vector<int32_t>& elems) {
  DivideTo(elems, mesh_->elems.size(), mesh_->patches.size());
}

void WorkerPool::DivideTo(const std::vector<int32_t>& elems, size_t elements, size_t patches) {
  elements_ = elements;
  patches_ = patches;
  edits_.insert(edits_.end(), elems.begin(), elems.end());
  for (Worker& w : workers_)
    if (w.state != State::kLost) proto::EncodeDivide(elems, &w.out);
}

void WorkerPool::Lose(int w, const std::string& why, std::vector<WorkerEvent>* events,
                      bool ended) {
  Worker& wk = workers_[w];
  if (wk.state == State::kLost) return;
  wk.state = State::kLost;
  Unwatch(w);
  std::string how = wk.conn->Close(!ended);
  events->push_back({WorkerEvent::kLost, w, {}, how.empty() ? why : why + ", " + how});
  wk.out.clear();
  wk.out_pos = 0;
}

void WorkerPool::Flush(int w, std::vector<WorkerEvent>* events) {
  Worker& wk = workers_[w];
  while (wk.state != State::kLost && wk.Writing(scene_frame_.size())) {
    const bool scene = wk.scene_sent < scene_frame_.size();
    long n = scene ? wk.conn->Write(scene_frame_.data() + wk.scene_sent,
                                    scene_frame_.size() - wk.scene_sent)
                   : wk.conn->Write(wk.out.data() + wk.out_pos, wk.out.size() - wk.out_pos);
    if (n < 0 && IsAgain()) break;
    if (n <= 0) {
      Lose(w, std::string("cannot send: ") + std::strerror(errno), events);
      return;
    }
    (scene ? wk.scene_sent : wk.out_pos) += size_t(n);
    sent_ += uint64_t(n);
    wk.last_sent = Clk();
  }
  if (wk.out_pos == wk.out.size()) {
    wk.out.clear();
    wk.out_pos = 0;
  }
}

bool WorkerPool::Handle(int w, proto::Msg type, std::string_view payload,
                        std::vector<WorkerEvent>* events, std::string* why) {
  using proto::Msg;
  Worker& wk = workers_[w];
  std::string err;
  if (type == Msg::kError) {
    std::string text;
    *why = proto::DecodeError(payload, &text, &err) ? "says: " + text : "garbled error: " + err;
    return false;
  }
  // Heartbeats come from the worker's hello on: while it receives the
  // scene and builds its mesh, and while it computes.
  if (type == Msg::kHeartbeat && (wk.state == State::kReady || wk.state == State::kJoined)) {
    if (payload.empty()) return true;
    *why = "garbled heartbeat";
    return false;
  }
  switch (wk.state) {
    case State::kHello: {
      proto::Hello h;
      if (type != Msg::kHello) break;
      if (!proto::DecodeHello(payload, &h, &err)) { *why = "garbled hello: " + err; return false; }
      if (h.magic != proto::kMagic || h.version != proto::kVersion) {
        *why = "speaks protocol version " + std::to_string(h.version) + ", this master speaks " +
               std::to_string(proto::kVersion) + " (build '" + h.build + "')";
        return false;
      }
      if (h.build != proto::BuildId()) {
        *why = "is another build ('" + h.build + "', this is '" + proto::BuildId() + "')";
        return false;
      }
      wk.state = State::kReady;
      return true;
    }
    case State::kReady: {
      proto::Ready r;
      if (type != Msg::kReady) break;
      if (!proto::DecodeReady(payload, &r, &err)) { *why = "garbled ready: " + err; return false; }
      if (r.elements != base_elements_ || r.mesh_hash != mesh_hash_) {
        *why = "built a different mesh (" + std::to_string(r.elements) + " elements, this has " +
               std::to_string(base_elements_) + ")";
        return false;
      }
      wk.state = State::kJoined;
      if (joined_at_ < 0) joined_at_ = Clk();
      events->push_back({WorkerEvent::kJoined, w, {}, ""});
      for (const auto& s : sources_) s->Joined();
      return true;
    }
    case State::kJoined: {
      if (type != Msg::kColumn) break;
      WorkerEvent ev{WorkerEvent::kColumn, w, {}, ""};
      ev.column.ff = Spare();
      if (!proto::DecodeColumn(payload, &ev.column, &err)) { *why = "garbled column: " + err; return false; }
      // The decoder cannot know the mesh: ids from the wire index the
      // master's arrays, so they are checked here (ids increase: the last
      // is the largest).
      const proto::Column& c = ev.column;
      if (c.patch < 0 || size_t(c.patch) >= patches_ ||
          (!c.ff.empty() && size_t(c.ff.back().elem) >= elements_)) {
        *why = "sent a column out of the mesh's range";
        return false;
      }
      wk.owed = std::max(0L, wk.owed - 1);
      wk.progress = Clk();
      events->push_back(std::move(ev));
      return true;
    }
    case State::kLost:
      return false;
  }
  *why = std::string("sent an unexpected ") + proto::MsgName(type) + " frame";
  return false;
}

void WorkerPool::Receive(int w, std::vector<WorkerEvent>* events) {
  Worker& wk = workers_[w];
  char buf[65536];
  for (;;) {
    long n = wk.conn->Read(buf, sizeof buf);
    if (n < 0 && IsAgain()) break;
    if (n < 0) { Lose(w, std::string("cannot read: ") + std::strerror(errno), events, true); return; }
    if (n == 0) { Lose(w, "closed the connection", events, true); return; }
    received_ += uint64_t(n);
    wk.last_heard = Clk();
    wk.in.Append(buf, size_t(n));
    proto::Msg type;
    std::string_view payload;  // in wk.in's buffer: no copy of each column
    std::string err;
    for (;;) {
      proto::FrameReader::Result r = wk.in.Next(&type, &payload, &err);
      if (r == proto::FrameReader::kNeedMore) break;
      std::string why;
      if (r == proto::FrameReader::kBad) why = "sent a bad frame: " + err;
      if (r == proto::FrameReader::kBad || !Handle(w, type, payload, events, &why)) {
        Lose(w, why, events);
        return;
      }
    }
    if (size_t(n) < sizeof buf) break;  // drained: spare the EAGAIN read
  }
}

void WorkerPool::Send(std::vector<WorkerEvent>* events) {
  for (size_t w = 0; w < workers_.size(); ++w)
    if (workers_[w].state != State::kLost && workers_[w].Writing(scene_frame_.size()))
      Flush(int(w), events);
}

void WorkerPool::Poll(double timeout, std::vector<WorkerEvent>* events) {
  CHECK(mesh_ != nullptr);
  const size_t before = events->size();
  for (WorkerEvent& ev : early_) events->push_back(std::move(ev));
  early_.clear();
  double now = Clk();
  for (size_t w = 0; w < workers_.size(); ++w) {
    Worker& wk = workers_[w];
    if (wk.state == State::kLost) continue;
    if (wk.state == State::kHello && now - wk.started > opts_.hello_s) {
      Lose(int(w), "did not start within " + std::to_string(int(opts_.hello_s)) + " s", events);
    } else if (wk.state == State::kJoined && wk.out.empty() &&
               now - wk.last_sent > opts_.heartbeat_s) {
      proto::EncodeHeartbeat(&wk.out);
    }
    Flush(int(w), events);
  }
  // Events() may read the socket (ssh), Buffered() does not: all of the
  // first before any of the second, so that nothing read for one worker
  // (a sibling channel of one ssh session) is left unseen while
  // epoll_wait sleeps.
  Watch(events);
  buffered_.clear();
  for (size_t w = 0; w < workers_.size(); ++w)
    if (workers_[w].state != State::kLost && workers_[w].conn->Buffered())
      buffered_.push_back(int(w));
  if (events->size() > before || !buffered_.empty()) timeout = 0;
  // Wake for heartbeats and deadlines even when nothing arrives.
  const double wait = std::min(timeout, opts_.heartbeat_s / 2);
  fired_.resize(std::max<size_t>(16, watched_.size() + sources_.size()));
  int n = ::epoll_wait(epoll_, fired_.data(), int(fired_.size()),
                       int(std::max(0.0, wait) * 1000));
  for (int w : buffered_) Receive(w, events);
  for (int i = 0; i < n; ++i) {
    const uint64_t tag = fired_[size_t(i)].data.u64;
    const uint32_t got = fired_[size_t(i)].events;
    if (tag & kSourceBit) {
      sources_[size_t(tag & ~kSourceBit)]->Take(this);
      continue;
    }
    auto it = watched_.find(int(tag));
    if (it == watched_.end()) continue;  // its last worker was lost meanwhile
    // A copy: a worker lost here leaves the list.
    hear_.assign(it->second.workers.begin(), it->second.workers.end());
    for (int w : hear_) {
      if (got & EPOLLOUT) Flush(w, events);
      if (workers_[w].state != State::kLost && (got & (EPOLLIN | EPOLLHUP | EPOLLERR)))
        Receive(w, events);
    }
  }
  // Silence and progress are judged after reading, so that a heartbeat or
  // a column that came while the master was busy elsewhere (a picture, a
  // division pass over a million elements) counts.
  now = Clk();
  for (size_t w = 0; w < workers_.size(); ++w) {
    const Worker& wk = workers_[w];
    // After its hello a worker may take as long as the scene takes to
    // arrive and mesh, as long as it says that it lives.
    if ((wk.state == State::kReady || wk.state == State::kJoined) &&
        now - wk.last_heard > opts_.timeout_s) {
      char buf[80];
      std::snprintf(buf, sizeof buf, "silent for %.1f s", now - wk.last_heard);
      Lose(int(w), buf, events);
    } else if (wk.state == State::kJoined && wk.owed > 0 && now - wk.progress > opts_.timeout_s) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "no column in %.1f s though given work (heartbeats only)",
                    now - wk.progress);
      Lose(int(w), buf, events);
    }
  }
}

void WorkerPool::Shutdown() {
  for (const auto& s : sources_) s->Stop();
  std::vector<WorkerEvent> ignored;
  std::vector<Conn*> ending;
  for (size_t w = 0; w < workers_.size(); ++w) {
    Worker& wk = workers_[w];
    if (wk.state == State::kLost) continue;
    proto::EncodeBye(&wk.out);
    Flush(int(w), &ignored);
    wk.state = State::kLost;
    Unwatch(int(w));
    ending.push_back(wk.conn.get());
  }
  // Every worker told first, then all waited for together: one after
  // another, each worker's exit (20 to 35 ms with -j 2) added to the end
  // of the run.
  AwaitEnd(ending);
  for (Conn* c : ending) c->Reap();  // killing those that did not end
}
