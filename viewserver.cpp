#include "viewserver.h"

#include <httplib.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <functional>
#include <future>
#include <mutex>
#include <thread>

#include "clock.h"
#include "quiet_thread.h"

namespace {

// cpp-httplib's thread pool with the bound of ViewServer::kQueued (its own
// queue has none: a flood of connections would each hold a descriptor).
class BoundedPool : public httplib::TaskQueue {
 public:
  BoundedPool() {
    for (int i = 0; i < ViewServer::kThreads; ++i) threads_.emplace_back([this] { Work(); });
  }
  void enqueue(std::function<void()> fn) override {
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (jobs_.size() < size_t(ViewServer::kQueued)) {
        jobs_.push_back(std::move(fn));
        cv_.notify_one();
        return;
      }
    }
    fn();  // full: the accepting thread serves this one and accepts no more meanwhile
  }
  // After the server has stopped: connections still queued are closed
  // unread (the server's socket is gone), then the threads end.
  void shutdown() override {
    {
      std::lock_guard<std::mutex> lock(mu_);
      done_ = true;
    }
    cv_.notify_all();
    for (std::thread& t : threads_) t.join();
  }

 private:
  void Work() {
    for (;;) {
      std::function<void()> fn;
      {
        std::unique_lock<std::mutex> lock(mu_);
        cv_.wait(lock, [this] { return done_ || !jobs_.empty(); });
        if (jobs_.empty()) return;
        fn = std::move(jobs_.front());
        jobs_.pop_front();
      }
      fn();
    }
  }

  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> jobs_;
  std::vector<std::thread> threads_;
  bool done_ = false;
};

// cpp-httplib with the listening socket's backlog raised: the library
// listens with a backlog of 5, and 200 clients connecting at once would
// then wait for SYN retries (a second or more each). Linux takes a second
// listen() on a listening socket as a new backlog.
class Server : public httplib::Server {
 public:
  void RaiseBacklog() { ::listen(svr_sock_, ViewServer::kBacklog); }
};

bool Loopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.compare(0, 4, "127.") == 0;
}

// The host part of a Host header: "[::1]:8080" -> "::1", "a:80" -> "a".
std::string HostName(const std::string& header) {
  if (!header.empty() && header[0] == '[') return header.substr(1, header.find(']') - 1);
  return header.substr(0, header.find(':'));
}

}  // namespace

struct ViewServer::Shared {
  ViewInfo info;
  std::string host;  // as bound
  std::string page;  // ViewPage(), made once

  std::mutex mu;  // the solver's side and the servers' meet here
  std::vector<LogRow> rows;
  ViewState state;
  std::unique_ptr<ShadedMesh> mesh;  // the newest snapshot, not encoded yet
  long mesh_id = 0, mesh_shots = 0;

  // Encoding a snapshot is the serving threads' work, one at a time, under
  // a mutex of their own: the solver's mu is held only to take it.
  std::mutex encode_mu;
  std::shared_ptr<const std::string> blob;  // the newest encoded (under mu)
  long blob_id = 0, blob_shots = 0;

  Server server;
  std::thread listener;
  std::promise<void> listened;  // set when the listening thread has ended
  std::future<void> ended;      // ... and seen here

  std::shared_ptr<const std::string> Blob(long* id, long* shots);
  void Serve();
};

std::shared_ptr<const std::string> ViewServer::Shared::Blob(long* id, long* shots) {
  std::lock_guard<std::mutex> one(encode_mu);
  std::unique_ptr<ShadedMesh> m;
  long m_id = 0, m_shots = 0;
  {
    std::lock_guard<std::mutex> lock(mu);
    m = std::move(mesh);
    m_id = mesh_id;
    m_shots = mesh_shots;
  }
  if (m) {
    auto b = std::make_shared<const std::string>(ViewMeshBlob(*m, AutoExposure(*m)));
    m.reset();
    std::lock_guard<std::mutex> lock(mu);
    if (m_id > blob_id) {  // Finish() may have put a newer one there meanwhile
      blob = std::move(b);
      blob_id = m_id;
      blob_shots = m_shots;
    }
  }
  std::lock_guard<std::mutex> lock(mu);
  *id = blob_id;
  *shots = blob_shots;
  return blob;
}

void ViewServer::Shared::Serve() {
  httplib::Server& s = server;
  s.set_keep_alive_timeout(kIdleTimeout);
  s.set_keep_alive_max_count(kKeepAliveRequests);
  s.set_read_timeout(kReadTimeout);
  s.set_write_timeout(kWriteTimeout);
  s.set_payload_max_length(kMaxPayload);
  s.new_task_queue = [] { return new BoundedPool; };
  // SO_REUSEADDR only: the library's default adds SO_REUSEPORT, with which
  // a second run on the same port would share it with the first, each
  // browser request going to either.
  s.set_socket_options([](int sock) {
    const int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  // A page elsewhere may make the browser ask a name that resolves to this
  // machine (DNS rebinding); a loopback server answers its own names only
  // (and a request with no Host, which no browser sends).
  if (Loopback(host))
    s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
      const std::string name = HostName(req.get_header_value("Host"));
      if (name.empty() || Loopback(name) || name == host) return httplib::Server::HandlerResponse::Unhandled;
      res.status = 403;
      res.set_content("403 not this server's name\n", "text/plain");
      return httplib::Server::HandlerResponse::Handled;
    });
  s.set_error_handler([](const httplib::Request&, httplib::Response& res) {
    res.set_content(std::to_string(res.status) + "\n", "text/plain");
  });
  s.set_default_headers({{"Cache-Control", "no-store"}, {"X-Content-Type-Options", "nosniff"}});
  s.Get("/", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(page, "text/html; charset=utf-8");
  });
  s.Get("/state.json", [this](const httplib::Request& req, httplib::Response& res) {
    // ?rows=K: only the rows from K on (the page has the others).
    size_t first = 0;
    if (req.has_param("rows")) {
      const std::string v = req.get_param_value("rows");
      char* end = nullptr;
      const unsigned long long k = std::strtoull(v.c_str(), &end, 10);
      if (v.empty() || *end || v[0] == '-') {
        res.status = 400;
        res.set_content("400 rows must be a row number\n", "text/plain");
        return;
      }
      first = size_t(std::min<unsigned long long>(k, SIZE_MAX));
    }
    ViewState st;
    std::vector<LogRow> tail;
    {
      std::lock_guard<std::mutex> lock(mu);
      st = state;
      first = std::min(first, rows.size());
      tail.assign(rows.begin() + long(first), rows.end());
    }
    // The rows copied out, the JSON made without the lock.
    res.set_content(ViewStateJson(info, st, tail, first), "application/json");
  });
  s.Get("/mesh.bin", [this](const httplib::Request&, httplib::Response& res) {
    long id = 0, shots = 0;
    const std::shared_ptr<const std::string> b = Blob(&id, &shots);
    if (!b) {
      res.status = 503;
      res.set_content("503 no snapshot yet\n", "text/plain");
      return;
    }
    res.set_header("X-Radiosity-Snapshot", std::to_string(id) + " " + std::to_string(shots));
    res.set_content(*b, "application/octet-stream");
  });
}

ViewServer::ViewServer(const ViewInfo& info, std::vector<LogRow> rows) : shared_(new Shared) {
  shared_->info = info;
  shared_->page = ViewPage();
  shared_->rows = std::move(rows);
}

ViewServer::~ViewServer() {
  Stop();
  delete shared_;
}

bool ViewServer::Start(const std::string& host, int port, std::string* bound, std::string* err) {
  Shared& sh = *shared_;
  sh.host = host;
  sh.Serve();
  errno = 0;
  const int got = port == 0 ? sh.server.bind_to_any_port(host) : sh.server.bind_to_port(host, port) ? port : -1;
  if (got < 0) {
    *err = "cannot listen on " + host + ":" + std::to_string(port) +
           (errno ? std::string(": ") + std::strerror(errno) : std::string());
    return false;
  }
  sh.server.RaiseBacklog();
  // The server's threads take no signals: SIGINT and the rest stop the
  // run through the main thread's handler, as without --view.
  sh.ended = sh.listened.get_future();
  sh.listener = QuietThread([&sh] {
    sh.server.listen_after_bind();
    sh.listened.set_value();
  });
  // stop() is a no-op until the server runs: wait for that (or its end).
  while (!sh.server.is_running() &&
         sh.ended.wait_for(std::chrono::milliseconds(1)) != std::future_status::ready) {
  }
  const bool v6 = host.find(':') != std::string::npos;
  *bound = (v6 ? "[" + host + "]" : host) + ":" + std::to_string(got);
  return true;
}

void ViewServer::Stop() {
  if (!shared_ || !shared_->listener.joinable()) return;
  shared_->server.stop();
  if (shared_->ended.wait_for(std::chrono::duration<double>(kStopWait)) ==
      std::future_status::ready) {
    shared_->listener.join();
    return;
  }
  shared_->listener.detach();
  // Left to the threads still using it, and still reachable: not a leak.
  // The list itself is never destroyed: a static vector is freed at exit
  // before the leak checker looks, which then found Shared unreachable
  // once its threads had ended (the sanitizer build, now and then).
  static std::vector<Shared*>* const abandoned = new std::vector<Shared*>;
  abandoned->push_back(shared_);
  shared_ = nullptr;
}

void ViewServer::Row(const LogRow& row, int workers) {
  rows_.push_back(row);
  workers_ = workers;
  Hand();
}

bool ViewServer::SnapshotDue() const {
  return MonotonicSeconds() - last_snapshot_ >= std::max(kInterval, kCostFactor * last_cost_);
}

void ViewServer::Snapshot(long shots, const std::function<ShadedMesh()>& shade) {
  const double t0 = MonotonicSeconds();
  mesh_ = std::make_unique<ShadedMesh>(shade());
  mesh_->Keep();  // the solver divides on while the server encodes this
  mesh_shots_ = shots;
  Hand();
  const double t1 = MonotonicSeconds();
  last_snapshot_ = t1;
  last_cost_ = t1 - t0;
  ++snapshots_;
  snapshot_s_ += last_cost_;
  max_snapshot_s_ = std::max(max_snapshot_s_, last_cost_);
}

void ViewServer::Hand() {
  if (!shared_ || !shared_->mu.try_lock()) return;  // the next sample brings it
  Shared& sh = *shared_;
  sh.rows.insert(sh.rows.end(), rows_.begin(), rows_.end());
  rows_.clear();
  sh.state.workers = workers_;
  if (mesh_) {
    sh.mesh = std::move(mesh_);
    sh.mesh_shots = mesh_shots_;
    sh.state.snapshot = ++sh.mesh_id;
    sh.state.snapshot_shots = mesh_shots_;
  }
  sh.mu.unlock();
}

void ViewServer::Finish(std::string mesh_blob, long shots, const std::string& status) {
  if (!shared_) return;
  Shared& sh = *shared_;
  std::lock_guard<std::mutex> lock(sh.mu);
  sh.rows.insert(sh.rows.end(), rows_.begin(), rows_.end());
  rows_.clear();
  mesh_.reset();
  sh.mesh.reset();
  sh.blob = std::make_shared<const std::string>(std::move(mesh_blob));
  sh.blob_id = sh.mesh_id = sh.state.snapshot = sh.mesh_id + 1;
  sh.blob_shots = sh.mesh_shots = sh.state.snapshot_shots = shots;
  sh.state.workers = workers_;
  sh.state.status = status;
}
