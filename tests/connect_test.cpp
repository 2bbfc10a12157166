// The connect-back handshake (doc/protocol.txt, "Connect-back") over
// socket pairs, both sides and each way a peer can fail, with the one-line
// reason the master logs or the worker says; and ReadSecret's checks of
// the secret file.
#include "connect.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "crypto.h"
#include "temp_dir.h"

namespace {

const std::string kSecret = "correct horse battery staple";

// A connected pair: master() non-blocking as Listen's sockets are,
// worker() blocking as the test's own end.
class Pair {
 public:
  Pair() {
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fd_) != 0) std::abort();
    ::fcntl(fd_[0], F_SETFL, ::fcntl(fd_[0], F_GETFL) | O_NONBLOCK);
  }
  ~Pair() {
    CloseMaster();
    CloseWorker();
  }
  int master() const { return fd_[0]; }
  int worker() const { return fd_[1]; }
  void CloseMaster() { Close(&fd_[0]); }
  void CloseWorker() { Close(&fd_[1]); }
  void Send(const std::string& bytes) {
    ASSERT_EQ(::write(worker(), bytes.data(), bytes.size()), ssize_t(bytes.size()));
  }
  std::string Recv(size_t n) {  // exactly n bytes from the master
    std::string out;
    char buf[256];
    while (out.size() < n) {
      const ssize_t k = ::read(worker(), buf, std::min(sizeof buf, n - out.size()));
      if (k <= 0) break;
      out.append(buf, size_t(k));
    }
    return out;
  }

 private:
  static void Close(int* fd) {
    if (*fd >= 0) ::close(*fd);
    *fd = -1;
  }
  int fd_[2];
};

// Feeds the master what the worker sends until it settles. The poll's
// limit only keeps a broken test from hanging; nothing waits for it.
MasterHandshake::Outcome Settle(MasterHandshake* m, std::string* why) {
  for (;;) {
    pollfd p{m->fd(), POLLIN, 0};
    if (::poll(&p, 1, 10000) != 1) return MasterHandshake::kWaiting;
    const MasterHandshake::Outcome o = m->Read(why);
    if (o != MasterHandshake::kWaiting) return o;
  }
}

// A worker's response to `challenge` as doc/protocol.txt spells it.
std::string Response(const std::string& secret, const std::string& challenge,
                     const std::string& worker_nonce) {
  return worker_nonce + HmacSha256(secret, "radiosity worker" + challenge.substr(5) + worker_nonce);
}

// The master's side of one handshake, its challenge sent; the test plays
// the worker on pair_.worker().
class MasterSide : public ::testing::Test {
 protected:
  MasterSide() : master_(pair_.master(), kSecret, 100) {}
  void SetUp() override { ASSERT_TRUE(master_.Start()); }
  // Why the master refused the worker; "joined" or "waiting" if it did not.
  std::string Refusal() {
    std::string why;
    switch (Settle(&master_, &why)) {
      case MasterHandshake::kJoined: return "joined";
      case MasterHandshake::kWaiting: return "waiting";
      case MasterHandshake::kRefused: break;
    }
    return why;
  }
  Pair pair_;
  MasterHandshake master_;
};

TEST_F(MasterSide, RightSecretJoins) {
  bool proved = false;
  std::string err;
  std::thread worker([&] { proved = ProveToMaster(pair_.worker(), kSecret, "master", &err); });
  EXPECT_EQ(Refusal(), "joined");
  worker.join();
  EXPECT_TRUE(proved) << err;
}

TEST_F(MasterSide, WireBytesAreTheDocumentedOnes) {
  const std::string challenge = pair_.Recv(37);
  ASSERT_EQ(challenge.size(), 37u);
  EXPECT_EQ(challenge.substr(0, 5), std::string("RADC\x01", 5));
  const std::string nw(32, 'w');
  pair_.Send(Response(kSecret, challenge, nw));
  ASSERT_EQ(Refusal(), "joined");
  EXPECT_EQ(Hex(pair_.Recv(32)),
            Hex(HmacSha256(kSecret, "radiosity master" + challenge.substr(5) + nw)));
}

TEST_F(MasterSide, WrongSecretRefusedOnBothSides) {
  bool proved = true;
  std::string err;
  std::thread worker(
      [&] { proved = ProveToMaster(pair_.worker(), "some other secret entirely", "M:7", &err); });
  EXPECT_EQ(Refusal(), "does not know the secret");
  pair_.CloseMaster();  // as the listener does
  worker.join();
  EXPECT_FALSE(proved);
  EXPECT_EQ(err, "the master at M:7 refused this worker (not the same secret?)");
}

TEST_F(MasterSide, SilentPeerRefusedAtTheDeadline) {
  std::string why;
  EXPECT_EQ(master_.Read(&why), MasterHandshake::kWaiting);
  EXPECT_FALSE(master_.Late(100, &why));
  pair_.Send(std::string(63, 'x'));  // one byte short
  EXPECT_EQ(master_.Read(&why), MasterHandshake::kWaiting);
  ASSERT_TRUE(master_.Late(100.5, &why));
  EXPECT_EQ(why, "did not authenticate within 5 s");
}

TEST_F(MasterSide, PeerThatClosesEarlyRefused) {
  pair_.Send(std::string(10, 'x'));
  pair_.CloseWorker();
  EXPECT_EQ(Refusal(), "closed the connection before authenticating");
}

TEST_F(MasterSide, PeerThatLeavesBeforeTheAnswerRefused) {
  pair_.Send(Response(kSecret, pair_.Recv(37), std::string(32, 'w')));
  pair_.CloseWorker();
  EXPECT_EQ(Refusal(), "closed the connection while authenticating");
}

TEST_F(MasterSide, GarbageRefused) {
  pair_.Send("GET / HTTP/1.1\r\nHost: cluster\r\n\r\n" + std::string(31, '\n'));
  EXPECT_EQ(Refusal(), "does not know the secret");
}

TEST_F(MasterSide, ReplayedResponseRefused) {
  // A response recorded from a handshake that succeeded...
  std::string recorded;
  {
    Pair earlier;
    MasterHandshake m(earlier.master(), kSecret, 100);
    ASSERT_TRUE(m.Start());
    recorded = Response(kSecret, earlier.Recv(37), std::string(32, 'w'));
    earlier.Send(recorded);
    std::string why;
    ASSERT_EQ(Settle(&m, &why), MasterHandshake::kJoined) << why;
  }
  // ...does not pass this one: its master's nonce is fresh.
  pair_.Send(recorded);
  EXPECT_EQ(Refusal(), "does not know the secret");
}

TEST_F(MasterSide, MasterMacDoesNotServeAsTheWorkers) {
  const std::string challenge = pair_.Recv(37);
  const std::string nw(32, 'w');
  pair_.Send(nw + HmacSha256(kSecret, "radiosity master" + challenge.substr(5) + nw));
  EXPECT_EQ(Refusal(), "does not know the secret");
}

// The worker's side against masters that are not ours. Each "master" has
// written all it will before the worker starts, so no thread is needed.
class WorkerSide : public ::testing::Test {
 protected:
  WorkerSide() { ::fcntl(pair_.master(), F_SETFL, ::fcntl(pair_.master(), F_GETFL) & ~O_NONBLOCK); }
  void MasterSends(const std::string& bytes) {
    ASSERT_EQ(::write(pair_.master(), bytes.data(), bytes.size()), ssize_t(bytes.size()));
  }
  std::string Prove() {
    std::string err;
    EXPECT_FALSE(ProveToMaster(pair_.worker(), kSecret, "node1:7000", &err));
    return err;
  }
  Pair pair_;
};

const char kNotAMaster[] = "node1:7000 is not a radiosity master listening for workers (of this version)";

TEST_F(WorkerSide, SomethingElseListening) {
  MasterSends("SSH-2.0-OpenSSH_9.2p1 Debian-2+deb12u3\r\n");
  EXPECT_EQ(Prove(), kNotAMaster);
}

TEST_F(WorkerSide, OtherVersionOfTheExchange) {
  MasterSends(std::string("RADC\x02", 5) + std::string(32, 'n'));
  EXPECT_EQ(Prove(), kNotAMaster);
}

TEST_F(WorkerSide, ClosedBeforeTheChallenge) {
  MasterSends("RADC");
  pair_.CloseMaster();
  EXPECT_EQ(Prove(), kNotAMaster);
}

TEST_F(WorkerSide, MasterThatClosesAfterTheChallenge) {
  MasterSends(std::string("RADC\x01", 5) + std::string(32, 'n'));
  ::shutdown(pair_.master(), SHUT_WR);
  EXPECT_EQ(Prove(), "the master at node1:7000 refused this worker (not the same secret?)");
}

TEST_F(WorkerSide, MasterWithoutTheSecret) {
  MasterSends(std::string("RADC\x01", 5) + std::string(32, 'n') + std::string(32, 'm'));
  EXPECT_EQ(Prove(), "the master at node1:7000 does not know the secret: not ours");
}

class SecretFile : public ::testing::Test {
 protected:
  // Writes `content` with exactly `mode`, whatever the umask.
  std::string Write(const std::string& content, mode_t mode) {
    const std::string path = dir_.path() + "/secret";
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    EXPECT_GE(fd, 0);
    EXPECT_EQ(::write(fd, content.data(), content.size()), ssize_t(content.size()));
    EXPECT_EQ(::fchmod(fd, mode), 0);
    ::close(fd);
    return path;
  }
  TempDir dir_;
};

TEST_F(SecretFile, PrivateFileRead) {
  std::string secret, err;
  ASSERT_TRUE(ReadSecret(Write("0123456789abcdef  \t\r\n\n", 0600), &secret, &err)) << err;
  EXPECT_EQ(secret, "0123456789abcdef");  // trailing white space dropped
  ASSERT_TRUE(ReadSecret(Write(" leading space kept ", 0400), &secret, &err)) << err;
  EXPECT_EQ(secret, " leading space kept");
}

TEST_F(SecretFile, OthersMayReadOrWrite) {
  for (mode_t mode : {0644, 0604, 0620, 0660, 0666}) {
    const std::string path = Write("0123456789abcdef0123", mode);
    std::string secret, err;
    EXPECT_FALSE(ReadSecret(path, &secret, &err));
    char octal[8];
    std::snprintf(octal, sizeof octal, "%04o", unsigned(mode));
    EXPECT_EQ(err, path + ": the secret may be read or changed by others (mode " + octal +
                       "); make it private with: chmod 600 " + path);
    EXPECT_TRUE(secret.empty());
  }
}

TEST_F(SecretFile, TooShort) {
  const std::string path = Write("fifteen bytes!!\n", 0600);
  std::string secret, err;
  EXPECT_FALSE(ReadSecret(path, &secret, &err));
  EXPECT_EQ(err, path + ": a secret of 15 bytes is too short (at least 16; e.g. head -c 32 "
                        "/dev/urandom | base64 >" + path + ")");
  EXPECT_FALSE(ReadSecret(Write("", 0600), &secret, &err));
  EXPECT_NE(err.find("a secret of 0 bytes is too short"), std::string::npos) << err;
}

TEST_F(SecretFile, NotAFile) {
  std::string secret, err;
  EXPECT_FALSE(ReadSecret(dir_.path(), &secret, &err));
  EXPECT_EQ(err, dir_.path() + ": not a regular file");
  EXPECT_FALSE(ReadSecret(dir_.path() + "/missing", &secret, &err));
  EXPECT_EQ(err, dir_.path() + "/missing: No such file or directory");
}

}  // namespace
