#include "connect.h"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/random.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

#include "check.h"
#include "clock.h"
#include "sha256.h"

namespace {

// The handshake (doc/protocol.txt, "Connect-back").
const char kMagic[4] = {'R', 'A', 'D', 'C'};
constexpr char kVersion = 1;
constexpr size_t kNonce = 32, kMac = 32;
constexpr size_t kChallenge = sizeof kMagic + 1 + kNonce;  // master -> worker
constexpr size_t kResponse = kNonce + kMac;                // worker -> master
constexpr double kHandshake = 5;  // seconds for a connection to authenticate

std::string Nonce() {
  std::string n(kNonce, '\0');
  size_t got = 0;
  while (got < n.size()) {
    const ssize_t k = ::getrandom(&n[got], n.size() - got, 0);
    CHECK(k > 0 || errno == EINTR);
    got += size_t(std::max<ssize_t>(k, 0));
  }
  return n;
}

// Each side's MAC covers both nonces and says which side it is, so that
// neither answer can be replayed as the other or in another handshake.
std::string Mac(const std::string& secret, const char* side, const std::string& master_nonce,
                const std::string& worker_nonce) {
  return HmacSha256(secret, std::string(side) + master_nonce + worker_nonce);
}

std::string AddressName(const sockaddr* a, socklen_t len) {
  char host[NI_MAXHOST], port[NI_MAXSERV];
  if (::getnameinfo(a, len, host, sizeof host, port, sizeof port, NI_NUMERICHOST | NI_NUMERICSERV))
    return "?";
  const std::string h = host;
  return (h.find(':') != std::string::npos ? "[" + h + "]" : h) + ":" + port;
}

// Column and work frames are small and answer each other: no Nagle delay.
void NoDelay(int fd) {
  int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
}

// Blocking-style I/O on a non-blocking socket, up to a deadline.
bool Wait(int fd, short events, double deadline) {
  for (;;) {
    const double left = deadline - MonotonicSeconds();
    if (left <= 0) return false;
    pollfd p{fd, events, 0};
    const int n = ::poll(&p, 1, int(left * 1000) + 1);
    if (n > 0) return true;
    if (n < 0 && errno != EINTR) return false;
  }
}

bool SendAll(int fd, const std::string& data, double deadline) {
  for (size_t done = 0; done < data.size();) {
    const ssize_t n = ::send(fd, data.data() + done, data.size() - done, MSG_NOSIGNAL);
    if (n > 0) done += size_t(n);
    else if (!((errno == EAGAIN || errno == EINTR) && Wait(fd, POLLOUT, deadline))) return false;
  }
  return true;
}

bool RecvAll(int fd, size_t want, double deadline, std::string* out) {
  char buf[256];
  while (out->size() < want) {
    const ssize_t n = ::recv(fd, buf, std::min(sizeof buf, want - out->size()), 0);
    if (n > 0) out->append(buf, size_t(n));
    else if (n == 0 || !((errno == EAGAIN || errno == EINTR) && Wait(fd, POLLIN, deadline))) return false;
  }
  return true;
}

// Accepts and authenticates on a thread of its own, several connections
// at a time, so that a slow or hostile client delays nobody.
class Listener : public WorkerSource {
 public:
  Listener(int fd, const std::string& secret, std::function<void(const std::string&, bool)> note)
      : listen_fd_(fd), secret_(secret), note_(std::move(note)) {
    CHECK(::pipe2(wake_, O_CLOEXEC | O_NONBLOCK) == 0);
    CHECK(::pipe2(stop_, O_CLOEXEC | O_NONBLOCK) == 0);
    thread_ = std::thread([this] { Run(); });
  }
  ~Listener() override {
    Stop();
    for (int fd : {wake_[0], wake_[1], stop_[0], stop_[1]}) ::close(fd);
  }
  int fd() const override { return wake_[0]; }
  void Take(WorkerPool* pool) override;
  int Expected() const override { return expected_; }
  void Stop() override;

 private:
  struct Arrival {
    int fd = -1;          // authenticated, or -1
    std::string peer;
    std::string refusal;  // why it was refused; empty with fd -1: nobody came in time
  };
  struct Pending {
    int fd;
    std::string peer, nonce, in;
    double deadline;
  };
  void Run();
  void Push(Arrival a) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      done_.push_back(std::move(a));
    }
    const char byte = 1;
    if (::write(wake_[1], &byte, 1) < 0) {}  // a full pipe wakes the pool all the same
  }
  void Accept(std::vector<Pending>* pending);
  enum Outcome { kWaiting, kRefused, kJoined };
  // Reads what pending connection p sent and settles it when it is all in.
  Outcome Answer(Pending* p);

  int listen_fd_;
  std::string secret_;
  std::function<void(const std::string&, bool)> note_;
  int wake_[2], stop_[2];
  std::thread thread_;
  std::mutex mu_;
  std::vector<Arrival> done_;  // guarded by mu_
  int expected_ = 1;           // waiting for the first worker (the pool's thread only)
  bool stopped_ = false;
};

void Listener::Accept(std::vector<Pending>* pending) {
  sockaddr_storage addr;
  socklen_t len = sizeof addr;
  const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len,
                           SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0) return;
  Pending p{fd, AddressName(reinterpret_cast<sockaddr*>(&addr), len), Nonce(), "",
            MonotonicSeconds() + kHandshake};
  NoDelay(fd);
  const std::string challenge = std::string(kMagic, sizeof kMagic) + kVersion + p.nonce;
  // A fresh socket's buffer takes these few bytes at once.
  if (::send(fd, challenge.data(), challenge.size(), MSG_NOSIGNAL) != ssize_t(challenge.size())) {
    ::close(fd);
    return;
  }
  pending->push_back(std::move(p));
}

Listener::Outcome Listener::Answer(Pending* p) {
  char buf[kResponse];
  const ssize_t n = ::recv(p->fd, buf, kResponse - p->in.size(), 0);
  if (n < 0 && (errno == EAGAIN || errno == EINTR)) return kWaiting;
  if (n <= 0) {
    Push({-1, p->peer, "closed the connection before authenticating"});
    ::close(p->fd);
    return kRefused;
  }
  p->in.append(buf, size_t(n));
  if (p->in.size() < kResponse) return kWaiting;
  const std::string worker_nonce = p->in.substr(0, kNonce);
  if (!SameBytes(p->in.substr(kNonce), Mac(secret_, "radiosity worker", p->nonce, worker_nonce))) {
    Push({-1, p->peer, "does not know the secret"});
    ::close(p->fd);
    return kRefused;
  }
  if (!SendAll(p->fd, Mac(secret_, "radiosity master", p->nonce, worker_nonce),
               MonotonicSeconds() + kHandshake)) {
    Push({-1, p->peer, "closed the connection while authenticating"});
    ::close(p->fd);
    return kRefused;
  }
  Push({p->fd, p->peer, ""});
  return kJoined;
}

void Listener::Run() {
  const double give_up = MonotonicSeconds() + kConnectWait;
  bool anyone = false;
  std::vector<Pending> pending;
  for (;;) {
    std::vector<pollfd> fds{{stop_[0], POLLIN, 0}, {listen_fd_, POLLIN, 0}};
    for (const Pending& p : pending) fds.push_back({p.fd, POLLIN, 0});
    ::poll(fds.data(), fds.size(), 200);
    if (fds[0].revents) break;
    if (fds[1].revents) Accept(&pending);
    const double now = MonotonicSeconds();
    // fds[2 + i] belongs to pending[i] as it was before this round's accept.
    for (size_t i = fds.size() - 2; i-- > 0;) {
      Pending& p = pending[i];
      bool keep = true;
      if (fds[2 + i].revents) {
        const Outcome o = Answer(&p);
        keep = o == kWaiting;
        anyone |= o == kJoined;
      } else if (now > p.deadline) {
        Push({-1, p.peer, "did not authenticate within " + std::to_string(int(kHandshake)) + " s"});
        ::close(p.fd);
        keep = false;
      }
      if (!keep) pending.erase(pending.begin() + long(i));
    }
    if (!anyone && now > give_up) {
      anyone = true;  // said once
      Push({});
    }
  }
  for (const Pending& p : pending) ::close(p.fd);
}

void Listener::Take(WorkerPool* pool) {
  char buf[256];
  while (::read(wake_[0], buf, sizeof buf) > 0) {}
  std::vector<Arrival> done;
  {
    std::lock_guard<std::mutex> lock(mu_);
    done.swap(done_);
  }
  for (Arrival& a : done) {
    if (a.fd >= 0) {
      expected_ = 0;
      pool->Add(SocketConn(a.fd), "worker at " + a.peer);
    } else if (a.peer.empty()) {
      expected_ = 0;
      note_("no worker connected within " + std::to_string(int(kConnectWait)) + " s", true);
    } else {
      note_("connect-back from " + a.peer + " refused: " + a.refusal, true);
    }
  }
}

void Listener::Stop() {
  if (stopped_) return;
  stopped_ = true;
  const char byte = 1;
  if (::write(stop_[1], &byte, 1) < 0) {}  // cannot be full: written once
  thread_.join();
  ::close(listen_fd_);
  std::lock_guard<std::mutex> lock(mu_);
  for (const Arrival& a : done_)
    if (a.fd >= 0) ::close(a.fd);
  done_.clear();
  expected_ = 0;
}

}  // namespace

bool ReadSecret(const std::string& file, std::string* secret, std::string* err) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st;
  if (fd < 0 || ::fstat(fd, &st) != 0) {
    *err = file + ": " + std::strerror(errno);
    if (fd >= 0) ::close(fd);
    return false;
  }
  std::string text;
  char buf[4096];
  ssize_t n = 0;
  while (S_ISREG(st.st_mode) && text.size() < (1 << 16) && (n = ::read(fd, buf, sizeof buf)) > 0)
    text.append(buf, size_t(n));
  ::close(fd);
  char mode[8];
  std::snprintf(mode, sizeof mode, "%04o", unsigned(st.st_mode & 07777));
  if (!S_ISREG(st.st_mode)) {
    *err = file + ": not a regular file";
  } else if (st.st_mode & 077) {
    *err = file + ": the secret may be read or changed by others (mode " + mode +
           "); make it private with: chmod 600 " + file;
  } else if (n < 0) {
    *err = file + ": " + std::strerror(errno);
  } else {
    text.erase(text.find_last_not_of(" \t\r\n") + 1);
    if (text.size() >= 16) {
      *secret = text;
      return true;
    }
    *err = file + ": a secret of " + std::to_string(text.size()) +
           " bytes is too short (at least 16; e.g. head -c 32 /dev/urandom | base64 >" + file + ")";
  }
  return false;
}

bool ParseEndpoint(const std::string& text, bool need_host, std::string* host, int* port,
                   std::string* err) {
  std::string p = text;
  host->clear();
  if (!text.empty() && text[0] == '[') {
    const size_t close = text.find("]:");
    if (close == std::string::npos) { *err = "expected [ADDRESS]:PORT"; return false; }
    *host = text.substr(1, close - 1);
    p = text.substr(close + 2);
  } else if (std::count(text.begin(), text.end(), ':') > 1) {
    *err = "write an IPv6 address in brackets: [ADDRESS]:PORT";
    return false;
  } else if (text.find(':') != std::string::npos) {
    *host = text.substr(0, text.find(':'));
    p = text.substr(text.find(':') + 1);
    if (host->empty()) { *err = "empty host before ':'"; return false; }
  }
  if (need_host && host->empty()) { *err = "expected HOST:PORT"; return false; }
  char* end = nullptr;
  const long v = std::strtol(p.c_str(), &end, 10);
  if (p.empty() || *end || p[0] == '-' || p[0] == '+' || v > 65535 || (need_host && v == 0)) {
    *err = "bad port '" + p + "' (must be " + (need_host ? "1" : "0") + " to 65535)";
    return false;
  }
  *port = int(v);
  return true;
}

std::unique_ptr<WorkerSource> Listen(const std::string& host, int port, const std::string& secret,
                                     std::function<void(const std::string&, bool)> note,
                                     std::string* bound, std::string* err) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  addrinfo* res = nullptr;
  const int rc = ::getaddrinfo(host.empty() ? nullptr : host.c_str(), std::to_string(port).c_str(),
                               &hints, &res);
  if (rc != 0) {
    *err = host + ": " + gai_strerror(rc);
    return nullptr;
  }
  int fd = -1;
  for (addrinfo* a = res; a && fd < 0; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) continue;
    int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (::bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, 64) != 0) {
      *err = std::string(std::strerror(errno));
      ::close(fd);
      fd = -1;
    }
  }
  ::freeaddrinfo(res);
  if (fd < 0) return nullptr;
  sockaddr_storage addr;
  socklen_t len = sizeof addr;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  *bound = AddressName(reinterpret_cast<sockaddr*>(&addr), len);
  return std::make_unique<Listener>(fd, secret, std::move(note));
}

int ConnectBack(const std::string& host, int port, const std::string& secret, std::string* err) {
  const double give_up = MonotonicSeconds() + kConnectWait;
  const std::string where = host + ":" + std::to_string(port);
  int fd = -1;
  // The master may not be listening yet: srun and mpirun start everyone
  // at once.
  while (fd < 0) {
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* res = nullptr;
    const int rc = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &res);
    if (rc != 0) {
      *err = host + ": " + gai_strerror(rc);
      return -1;
    }
    for (addrinfo* a = res; a && fd < 0; a = a->ai_next) {
      fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
      if (fd < 0) continue;
      int so_error = 0;
      socklen_t len = sizeof so_error;
      const bool ok =
          (::connect(fd, a->ai_addr, a->ai_addrlen) == 0 ||
           (errno == EINPROGRESS && Wait(fd, POLLOUT, std::min(give_up, MonotonicSeconds() + 5)) &&
            ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &so_error, &len) == 0 && so_error == 0));
      if (!ok) {
        *err = "cannot connect to " + where + ": " +
               std::strerror(so_error ? so_error : errno ? errno : ETIMEDOUT);
        ::close(fd);
        fd = -1;
      }
    }
    ::freeaddrinfo(res);
    if (fd >= 0) break;
    if (MonotonicSeconds() + 0.5 > give_up) return -1;
    ::usleep(500000);
  }
  NoDelay(fd);
  const double deadline = MonotonicSeconds() + 2 * kHandshake;
  std::string challenge, answer;
  if (!RecvAll(fd, kChallenge, deadline, &challenge) ||
      challenge.compare(0, sizeof kMagic, kMagic, sizeof kMagic) != 0 ||
      challenge[sizeof kMagic] != kVersion) {
    *err = where + " is not a radiosity master listening for workers (of this version)";
    ::close(fd);
    return -1;
  }
  const std::string master_nonce = challenge.substr(sizeof kMagic + 1), nonce = Nonce();
  if (!SendAll(fd, nonce + Mac(secret, "radiosity worker", master_nonce, nonce), deadline) ||
      !RecvAll(fd, kMac, deadline, &answer)) {
    *err = "the master at " + where + " refused this worker (not the same secret?)";
    ::close(fd);
    return -1;
  }
  if (!SameBytes(answer, Mac(secret, "radiosity master", master_nonce, nonce))) {
    *err = "the master at " + where + " does not know the secret: not ours";
    ::close(fd);
    return -1;
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);  // the worker loop polls itself
  return fd;
}
