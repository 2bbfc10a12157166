// Connect-back: workers started by a cluster's own launcher (Slurm srun,
// mpirun, a batch script) instead of over ssh. The master listens
// (radiosity --listen [HOST:]PORT --secret FILE); each worker connects
// (radiosity --worker --connect HOST:PORT --secret FILE) and both prove
// that they know the secret by challenge and response (HMAC-SHA256 of
// fresh nonces from both sides: doc/protocol.txt, "Connect-back"), so the
// secret never crosses the wire. The stream itself is not encrypted: use
// it on the cluster's own network. Then the worker protocol runs as over
// a pipe.
#ifndef RADIOSITY_CONNECT_H
#define RADIOSITY_CONNECT_H

#include <functional>
#include <memory>
#include <string>

#include "pool.h"

// How long the master waits for the first worker to connect, and a
// worker for the master to listen.
constexpr double kConnectWait = 60;

// Reads the shared secret from FILE: a regular file that only its owner
// may read or write (mode 0600 or 0400), of at least 16 bytes (trailing
// white space dropped).
bool ReadSecret(const std::string& file, std::string* secret, std::string* err);

// Splits [HOST:]PORT ("7000", "node1:7000", "[::1]:7000"). HOST may be
// left out only when !need_host; PORT is 0..65535 (0: any free port, for
// --listen).
bool ParseEndpoint(const std::string& text, bool need_host, std::string* host, int* port,
                   std::string* err);

// Listens on host:port (host empty: every interface). Workers that prove
// they know the secret join the pool; any other connection is refused and
// said as a warning through `note`. *bound gets the address listened on
// ("0.0.0.0:7000").
std::unique_ptr<WorkerSource> Listen(const std::string& host, int port, const std::string& secret,
                                     std::function<void(const std::string&, bool warning)> note,
                                     std::string* bound, std::string* err);

// The worker's side: connects to host:port (retrying while the master is
// not there yet, up to kConnectWait), authenticates, and returns the
// socket to speak the worker protocol on; -1 with *err.
int ConnectBack(const std::string& host, int port, const std::string& secret, std::string* err);

// The handshake itself (doc/protocol.txt, "Connect-back"), one connection
// at a time: what Listen and ConnectBack run over their sockets, and what
// the tests run over socket pairs.

// The master's side, over a non-blocking socket that stays the caller's:
// Start() sends the challenge; Read(), whenever the socket is readable,
// takes what the worker sent, and answers once all of it is in and right.
class MasterHandshake {
 public:
  enum Outcome { kWaiting, kRefused, kJoined };
  // The worker has until `deadline` (on Listen's steady clock) to answer.
  MasterHandshake(int fd, const std::string& secret, double deadline);
  bool Start();  // false: the peer is gone already
  // *refusal gets why, in a few words ("does not know the secret").
  Outcome Read(std::string* refusal);
  // Whether `now` is past the deadline (the answer is not all in yet).
  bool Late(double now, std::string* refusal) const;
  int fd() const { return fd_; }

 private:
  int fd_;
  std::string secret_, nonce_, in_;
  double deadline_;
};

// The worker's side, over a connected socket: takes the challenge, proves
// that it knows the secret and checks that the master does too. *err
// names the master as `where`.
bool ProveToMaster(int fd, const std::string& secret, const std::string& where, std::string* err);

#endif
