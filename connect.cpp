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
#include <atomic>
#include <cerrno>
#include <cstring>
#include <thread>
#include <vector>

#include "check.h"
#include "clock.h"
#include "crypto.h"
#include "files.h"
#include "source.h"

namespace {

// The handshake (doc/protocol.txt, "Connect-back").
const char kMagic[4] = {'R', 'A', 'D', 'C'};
constexpr char kVersion = 1;
constexpr size_t kNonce = 32, kMac = 32;
constexpr size_t kChallenge = sizeof kMagic + 1 + kNonce;  // master -> worker
constexpr size_t kResponse = kNonce + kMac;                // worker -> master
constexpr double kHandshake = 5;  // seconds for a connection to authenticate
// Connections authenticating at once: more wait in the kernel's backlog,
// so that anyone who can reach the port cannot use up the descriptors.
constexpr size_t kMaxPending = 32;
// After accept() fails for want of descriptors: this long before the next.
constexpr double kBackOff = 1;
// Refusals said one a line; past this many, only that more were refused.
constexpr int kRefusalsSaid = 10;

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
// at a time, so that a slow or hostile client delays nobody. It waits for
// one worker: the first to join the pool (not merely to authenticate: it
// may be another build, or close at once), or kConnectWait without any,
// settles it.
class Listener : public ThreadedSource {
 public:
  Listener(int fd, const std::string& secret, Note note)
      : ThreadedSource(std::move(note), 1), listen_fd_(fd), secret_(secret) {
    CHECK(::pipe2(stop_, O_CLOEXEC | O_NONBLOCK) == 0);
    thread_ = std::thread([this] { Run(); });
  }
  ~Listener() override {
    Stop();
    for (int fd : stop_) ::close(fd);
  }
  void Stop() override;
  void Joined() override { joined_ = true; }
  int Expected() const override { return joined_ ? 0 : ThreadedSource::Expected(); }

 private:
  struct Pending {
    MasterHandshake handshake;
    std::string peer;
  };
  void Run();
  void Accept(std::vector<Pending>* pending);
  void Refuse(const Pending& p, const std::string& why) {
    ::close(p.handshake.fd());
    if (++refused_ > kRefusalsSaid) return;
    Delivery d;
    d.notes.emplace_back("connect-back from " + p.peer + " refused: " + why +
                             (refused_ == kRefusalsSaid ? " (further refusals not shown)" : ""),
                         true);
    Deliver(std::move(d));
  }

  int listen_fd_;
  std::string secret_;
  int stop_[2];
  std::thread thread_;
  bool stopped_ = false;
  int refused_ = 0;
  double backoff_until_ = 0;  // accept() ran out of descriptors: not before this
  bool said_backoff_ = false;
  std::atomic<bool> joined_{false};  // set on the pool's thread, read on this one
};

void Listener::Accept(std::vector<Pending>* pending) {
  sockaddr_storage addr;
  socklen_t len = sizeof addr;
  const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len,
                           SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0) {
    // The connection stays in the backlog and the socket readable: without
    // a pause this would spin.
    if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
      backoff_until_ = MonotonicSeconds() + kBackOff;
      if (!said_backoff_) {
        said_backoff_ = true;
        Delivery d;
        d.notes.emplace_back(std::string("connect-back: cannot accept (") + std::strerror(errno) +
                                 "); trying again every " + std::to_string(int(kBackOff)) + " s",
                             true);
        Deliver(std::move(d));
      }
    }
    return;
  }
  NoDelay(fd);
  Pending p{MasterHandshake(fd, secret_, MonotonicSeconds() + kHandshake),
            AddressName(reinterpret_cast<sockaddr*>(&addr), len)};
  if (!p.handshake.Start()) {
    ::close(fd);
    return;
  }
  pending->push_back(std::move(p));
}

void Listener::Run() {
  const double give_up = MonotonicSeconds() + kConnectWait;
  bool settled = false;
  std::vector<Pending> pending;
  for (;;) {
    // The listening socket is left out while the handshakes are full or
    // descriptors ran out (poll ignores a negative fd).
    const bool accepting = pending.size() < kMaxPending && MonotonicSeconds() >= backoff_until_;
    std::vector<pollfd> fds{{stop_[0], POLLIN, 0}, {accepting ? listen_fd_ : -1, POLLIN, 0}};
    for (const Pending& p : pending) fds.push_back({p.handshake.fd(), POLLIN, 0});
    ::poll(fds.data(), fds.size(), 200);
    if (fds[0].revents) break;
    if (fds[1].revents) Accept(&pending);
    const double now = MonotonicSeconds();
    // fds[2 + i] belongs to pending[i] as it was before this round's accept.
    for (size_t i = fds.size() - 2; i-- > 0;) {
      Pending& p = pending[i];
      std::string why;
      MasterHandshake::Outcome o = MasterHandshake::kWaiting;
      if (fds[2 + i].revents) o = p.handshake.Read(&why);
      else if (p.handshake.Late(now, &why)) o = MasterHandshake::kRefused;
      if (o == MasterHandshake::kRefused) {
        Refuse(p, why);
      } else if (o == MasterHandshake::kJoined) {
        Delivery d;
        d.workers.emplace_back(SocketConn(p.handshake.fd()), "worker at " + p.peer);
        Deliver(std::move(d));
      }
      if (o != MasterHandshake::kWaiting) pending.erase(pending.begin() + long(i));
    }
    if (!settled && !joined_ && now > give_up) {
      settled = true;  // said once
      Delivery d;
      d.notes.emplace_back("no worker connected within " + std::to_string(int(kConnectWait)) + " s",
                           true);
      d.settled = 1;
      Deliver(std::move(d));
    }
  }
  for (const Pending& p : pending) ::close(p.handshake.fd());
}

void Listener::Stop() {
  if (stopped_) return;
  stopped_ = true;
  const char byte = 1;
  if (::write(stop_[1], &byte, 1) < 0) {}  // cannot be full: written once
  thread_.join();
  ::close(listen_fd_);
  Drop();
}

}  // namespace

MasterHandshake::MasterHandshake(int fd, const std::string& secret, double deadline)
    : fd_(fd), secret_(secret), nonce_(Nonce()), deadline_(deadline) {}

bool MasterHandshake::Start() {
  const std::string challenge = std::string(kMagic, sizeof kMagic) + kVersion + nonce_;
  // A fresh socket's buffer takes these few bytes at once.
  return ::send(fd_, challenge.data(), challenge.size(), MSG_NOSIGNAL) == ssize_t(challenge.size());
}

MasterHandshake::Outcome MasterHandshake::Read(std::string* refusal) {
  char buf[kResponse];
  const ssize_t n = ::recv(fd_, buf, kResponse - in_.size(), 0);
  if (n < 0 && (errno == EAGAIN || errno == EINTR)) return kWaiting;
  if (n <= 0) {
    *refusal = "closed the connection before authenticating";
    return kRefused;
  }
  in_.append(buf, size_t(n));
  if (in_.size() < kResponse) return kWaiting;
  const std::string worker_nonce = in_.substr(0, kNonce);
  if (!SameBytes(in_.substr(kNonce), Mac(secret_, "radiosity worker", nonce_, worker_nonce))) {
    *refusal = "does not know the secret";
    return kRefused;
  }
  if (!SendAll(fd_, Mac(secret_, "radiosity master", nonce_, worker_nonce), MonotonicSeconds() + kHandshake)) {
    *refusal = "closed the connection while authenticating";
    return kRefused;
  }
  return kJoined;
}

bool MasterHandshake::Late(double now, std::string* refusal) const {
  if (now <= deadline_) return false;
  *refusal = "did not authenticate within " + std::to_string(int(kHandshake)) + " s";
  return true;
}

bool ProveToMaster(int fd, const std::string& secret, const std::string& where, std::string* err) {
  const double deadline = MonotonicSeconds() + 2 * kHandshake;
  std::string challenge, answer;
  if (!RecvAll(fd, kChallenge, deadline, &challenge) ||
      challenge.compare(0, sizeof kMagic, kMagic, sizeof kMagic) != 0 ||
      challenge[sizeof kMagic] != kVersion) {
    *err = where + " is not a radiosity master listening for workers (of this version)";
    return false;
  }
  const std::string master_nonce = challenge.substr(sizeof kMagic + 1), nonce = Nonce();
  if (!SendAll(fd, nonce + Mac(secret, "radiosity worker", master_nonce, nonce), deadline) ||
      !RecvAll(fd, kMac, deadline, &answer)) {
    *err = "the master at " + where + " refused this worker (not the same secret?)";
    return false;
  }
  if (!SameBytes(answer, Mac(secret, "radiosity master", master_nonce, nonce))) {
    *err = "the master at " + where + " does not know the secret: not ours";
    return false;
  }
  return true;
}

bool ReadSecret(const std::string& file, std::string* secret, std::string* err) {
  // O_NONBLOCK: a FIFO without a writer must not block the open; fstat
  // refuses it below.
  const int fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  struct stat st;
  if (fd < 0 || ::fstat(fd, &st) != 0) {
    *err = file + ": " + std::strerror(errno);
    if (fd >= 0) ::close(fd);
    return false;
  }
  std::string text;
  char buf[4096];
  ssize_t n = 0;
  const bool readable = S_ISREG(st.st_mode) && uint64_t(st.st_size) <= kMaxSecretBytes;
  while (readable && text.size() <= kMaxSecretBytes && (n = ::read(fd, buf, sizeof buf)) > 0)
    text.append(buf, size_t(n));
  ::close(fd);
  char mode[8];
  std::snprintf(mode, sizeof mode, "%04o", unsigned(st.st_mode & 07777));
  if (!S_ISREG(st.st_mode)) {
    *err = file + ": not a regular file";
  } else if (st.st_mode & 077) {
    *err = file + ": the secret may be read or changed by others (mode " + mode +
           "); make it private with: chmod 600 " + file;
  } else if (st.st_mode & 0100) {
    *err = file + ": the secret must be mode 0600 or 0400, not " + mode + ": chmod 600 " + file;
  } else if (n < 0) {
    *err = file + ": " + std::strerror(errno);
  } else if (!readable || text.size() > kMaxSecretBytes) {
    *err = file + ": more than the limit of " + std::to_string(kMaxSecretBytes >> 10) +
           " KiB for a secret";
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
  if (!ProveToMaster(fd, secret, where, err)) {
    ::close(fd);
    return -1;
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);  // the worker loop polls itself
  return fd;
}
