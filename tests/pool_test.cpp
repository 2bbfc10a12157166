// The worker pool against a peer on the other end of a socketpair: the
// test itself speaking frames (proto:: encoders), or a real RunWorker on a
// thread or in a forked child. The pool's clock is the test's, so that
// deadlines and heartbeats come when the test says: no sleeps. Reads wait
// for what the other end sends, never for a fixed time.
#include "pool.h"

#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "groups.h"
#include "protocol.h"
#include "scene.h"
#include "peer.h"
#include "test_util.h"
#include "worker.h"

namespace {

using proto::Msg;
using test::Peer;

class FakeClock : public Clock {
 public:
  double Now() override { return now; }
  double now = 100;  // not 0: the pool's epoch must be subtracted
};

class PoolTest : public ::testing::Test {
 protected:
  PoolTest()
      : mesh_(MakeMesh(Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}))),
        setup_{Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}), MeshOptions(), 16, 0, 1},
        pool_(setup_, mesh_, opts_, &clock_) {}

  // A worker whose other end is a Peer; the pool's next Poll (here) sends
  // it the hello and the scene.
  Peer Connect(const std::string& name = "w") {
    int sv[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv), 0);
    pool_.Add(SocketConn(sv[0]), name);
    std::vector<WorkerEvent> ev;
    pool_.Poll(0, &ev);
    EXPECT_TRUE(ev.empty());
    return Peer(sv[1]);
  }
  // Reads the pool's hello and scene.
  void ReadSetup(Peer* p) {
    Msg type;
    std::string payload, err;
    ASSERT_TRUE(p->Next(&type, &payload));
    ASSERT_EQ(type, Msg::kHello);
    proto::Hello h;
    ASSERT_TRUE(proto::DecodeHello(payload, &h, &err)) << err;
    EXPECT_EQ(h.build, proto::BuildId());
    ASSERT_TRUE(p->Next(&type, &payload));
    ASSERT_EQ(type, Msg::kScene);
    proto::SceneSetup s;
    ASSERT_TRUE(proto::DecodeScene(payload, &s, &err)) << err;
    EXPECT_EQ(s.resolution, 16);
  }
  // Polls (without waiting, the bytes are there already) until an event
  // comes; none within a few polls: an empty vector.
  std::vector<WorkerEvent> Events() {
    std::vector<WorkerEvent> ev;
    for (int i = 0; i < 4 && ev.empty(); ++i) pool_.Poll(0, &ev);
    return ev;
  }
  // A Peer that has joined.
  Peer Joined() {
    Peer p = Connect();
    ReadSetup(&p);
    p.SendHello();
    p.SendReady(mesh_);
    std::vector<WorkerEvent> ev = Events();
    EXPECT_EQ(ev.size(), 1u);
    if (!ev.empty()) {
      EXPECT_EQ(ev[0].kind, WorkerEvent::kJoined);
    }
    return p;
  }
  // The one event of the next polls: a loss, and why.
  std::string LostWhy() {
    std::vector<WorkerEvent> ev = Events();
    if (ev.size() != 1 || ev[0].kind != WorkerEvent::kLost) {
      ADD_FAILURE() << ev.size() << " events, not one loss";
      return "";
    }
    return ev[0].why;
  }

  FakeClock clock_;
  PoolOptions opts_;
  Mesh mesh_;
  proto::SceneSetup setup_;
  WorkerPool pool_;
};

bool Has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST_F(PoolTest, JoinsAfterHelloAndReadyThenTradesWorkForColumns) {
  Peer p = Connect("worker 0");
  EXPECT_EQ(pool_.Starting(), 1);
  ReadSetup(&p);
  p.SendHello();
  EXPECT_TRUE(Events().empty());  // a hello alone is not a join
  p.SendReady(mesh_);
  std::vector<WorkerEvent> ev = Events();
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, WorkerEvent::kJoined);
  EXPECT_EQ(ev[0].worker, 0);
  EXPECT_EQ(pool_.Starting(), 0);
  EXPECT_EQ(pool_.Name(0), "worker 0");

  pool_.Assign(0, {3, 2});
  ev.clear();
  pool_.Poll(0, &ev);  // writes the work frame
  std::vector<proto::Assignment> work;
  ASSERT_TRUE(p.NextWork(&work));
  ASSERT_EQ(work.size(), 1u);
  EXPECT_EQ(work[0].patch, 3);
  EXPECT_EQ(work[0].k, 2);

  proto::Column c;
  c.patch = 3;
  c.k = 2;
  c.ff = {{1, 0.25f}, {4, 0.5f}};
  std::string frame;
  proto::EncodeColumn(c, &frame);
  p.Send(frame);
  ev = Events();
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, WorkerEvent::kColumn);
  EXPECT_EQ(ev[0].column.patch, 3);
  EXPECT_EQ(ev[0].column.k, 2);
  ASSERT_EQ(ev[0].column.ff.size(), 2u);
  EXPECT_EQ(ev[0].column.ff[1].elem, 4);
  EXPECT_GT(pool_.BytesReceived(), frame.size());
  EXPECT_GT(pool_.BytesSent(), 0u);
}

// Many workers on one epoll set: each one's column is heard, and a
// worker lost leaves it so that a newcomer on the same fd number (the
// lowest free one: the lost worker's) is heard in its place.
TEST_F(PoolTest, AHundredWorkersAreHeardAndALostOnesFdServesANewcomer) {
  std::vector<Peer> peers;
  for (int i = 0; i < 100; ++i) peers.push_back(Joined());
  const int patches = int(mesh_.patches.size());
  std::vector<WorkerEvent> ev;  // what the polls bring, from the first
  auto trade = [&](int w, Peer* p) {
    pool_.Assign(w, {w % patches, 0});
    pool_.Poll(0, &ev);  // writes the work frame
    Msg type;
    std::string payload;
    ASSERT_TRUE(p->Next(&type, &payload));
    ASSERT_EQ(type, Msg::kWork);
    proto::Column c;
    c.patch = w % patches;
    c.ff = {{1, 0.25f}};
    std::string frame;
    proto::EncodeColumn(c, &frame);
    p->Send(frame);
  };
  for (int w = 0; w < 100; ++w) trade(w, &peers[size_t(w)]);
  std::vector<int> heard(100, 0);
  for (int i = 0; i < 100 && ev.size() < 100; ++i) pool_.Poll(0, &ev);
  ASSERT_EQ(ev.size(), 100u);
  for (const WorkerEvent& e : ev) {
    ASSERT_EQ(e.kind, WorkerEvent::kColumn);
    ++heard[size_t(e.worker)];
  }
  EXPECT_EQ(std::count(heard.begin(), heard.end(), 1), 100);

  peers[50].Close();
  EXPECT_TRUE(Has(LostWhy(), "closed the connection"));
  Peer late = Joined();
  ev.clear();
  trade(100, &late);
  for (int i = 0; i < 4 && ev.empty(); ++i) pool_.Poll(0, &ev);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, WorkerEvent::kColumn);
  EXPECT_EQ(ev[0].worker, 100);
}

// The master may assign to a worker the pool lost before the master
// heard of it: while it handles an earlier event of the same Poll, or
// with the pool on a thread of its own (ThreadedPool). The assignment is
// dropped (the loss gives back all the worker owned) and the pool goes on.
TEST_F(PoolTest, AnAssignmentToAWorkerLostBeforeTheMasterHeardIsDropped) {
  Peer gone = Joined(), alive = Joined();
  gone.Close();
  EXPECT_TRUE(Has(LostWhy(), "closed the connection"));
  pool_.Assign(0, {2, 0});
  pool_.Assign(1, {3, 0});
  std::vector<WorkerEvent> ev;
  pool_.Poll(0, &ev);
  EXPECT_TRUE(ev.empty());
  std::vector<proto::Assignment> work;
  ASSERT_TRUE(alive.NextWork(&work));
  ASSERT_EQ(work.size(), 1u);
  EXPECT_EQ(work[0].patch, 3);
}

TEST_F(PoolTest, HelloDeadline) {
  Peer p = Connect();
  ReadSetup(&p);
  clock_.now += opts_.hello_s + 0.5;
  EXPECT_EQ(LostWhy(), "did not start within 30 s");
  EXPECT_EQ(pool_.Starting(), 0);
  Msg type;
  EXPECT_FALSE(p.Next(&type));  // the pool closed its end
}

// After its hello a worker may take minutes to receive and mesh a large
// scene, as long as it heartbeats; silent, it is dropped as when joined.
TEST_F(PoolTest, SetupTakesAsLongAsTheWorkerHeartbeats) {
  Peer p = Connect();
  ReadSetup(&p);
  p.SendHello();
  EXPECT_TRUE(Events().empty());
  for (int i = 0; i < 20; ++i) {  // 20 timeouts' worth of building
    clock_.now += opts_.timeout_s - 1;
    p.SendHeartbeat();
    EXPECT_TRUE(Events().empty()) << i;
  }
  EXPECT_EQ(pool_.Starting(), 1);
  p.SendReady(mesh_);
  std::vector<WorkerEvent> ev = Events();
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, WorkerEvent::kJoined);

  Peer q = Connect("silent");
  ReadSetup(&q);
  q.SendHello();
  EXPECT_TRUE(Events().empty());
  clock_.now += opts_.timeout_s + 0.5;
  p.SendHeartbeat();  // the first stays
  EXPECT_EQ(LostWhy(), "silent for 10.5 s");
  EXPECT_EQ(pool_.Starting(), 0);
}

TEST_F(PoolTest, HeartbeatsAfterSilenceAndTimeoutWithout) {
  Peer p = Joined();
  EXPECT_TRUE(p.Quiet());
  clock_.now += opts_.heartbeat_s / 2;
  EXPECT_TRUE(Events().empty());
  EXPECT_TRUE(p.Quiet());  // not silent long enough
  clock_.now += opts_.heartbeat_s;
  EXPECT_TRUE(Events().empty());
  Msg type;
  ASSERT_TRUE(p.Next(&type));
  EXPECT_EQ(type, Msg::kHeartbeat);

  // The worker's heartbeats keep it alive past the timeout.
  for (int i = 0; i < 3; ++i) {
    clock_.now += 0.6 * opts_.timeout_s;
    p.SendHeartbeat();
    EXPECT_TRUE(Events().empty()) << i;
    while (!p.Quiet()) ASSERT_TRUE(p.Next(&type));  // the pool's own heartbeats
  }
  // Without them it is dropped.
  clock_.now += opts_.timeout_s + 0.5;
  EXPECT_EQ(LostWhy(), "silent for 10.5 s");
}

// A master busy for longer than the timeout (a division pass over a
// million elements) judges silence by what is waiting when it comes back:
// the heartbeats sent meanwhile count, the worker stays.
TEST_F(PoolTest, HeartbeatsThatArrivedWhileTheMasterWasBusyCount) {
  Peer p = Joined();
  p.SendHeartbeat();  // sent during the busy spell, read only after it
  clock_.now += 2 * opts_.timeout_s;
  EXPECT_TRUE(Events().empty());
  clock_.now += opts_.timeout_s + 0.5;  // then really silent
  EXPECT_EQ(LostWhy(), "silent for 10.5 s");
}

// Heartbeats alone do not keep a worker that was given work: with no
// column for --timeout it is dropped (its patches then go to the others,
// as for any lost worker); one that answers, or has nothing to do, stays.
TEST_F(PoolTest, AWorkerGivenWorkThatSendsNoColumnIsDropped) {
  Peer p = Joined();
  Msg type;
  // Idle: heartbeats are enough.
  for (int i = 0; i < 3; ++i) {
    clock_.now += 0.6 * opts_.timeout_s;
    p.SendHeartbeat();
    EXPECT_TRUE(Events().empty()) << i;
    while (!p.Quiet()) ASSERT_TRUE(p.Next(&type));
  }
  pool_.Assign(0, {1, 0});
  pool_.Assign(0, {2, 0});
  // A column within the timeout is progress, though one patch is still owed.
  clock_.now += 0.6 * opts_.timeout_s;
  proto::Column c;
  c.patch = 1;
  c.ff = {{0, 0.5f}};
  std::string frame;
  proto::EncodeColumn(c, &frame);
  p.Send(frame);
  std::vector<WorkerEvent> ev = Events();
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, WorkerEvent::kColumn);
  for (int i = 0; i < 3; ++i) {  // then only heartbeats
    clock_.now += 0.4 * opts_.timeout_s;
    p.SendHeartbeat();
    while (!p.Quiet()) ASSERT_TRUE(p.Next(&type));
    if (i < 2) {
      EXPECT_TRUE(Events().empty()) << i;
    }
  }
  EXPECT_EQ(LostWhy(), "no column in 12.0 s though given work (heartbeats only)");
}

// The run's clock starts when the first worker joins: a run that waits
// for its workers (connect-back, ssh) does not spend its -t on waiting.
TEST_F(PoolTest, TheRunClockStartsAtTheFirstJoin) {
  EXPECT_EQ(pool_.Now(), 0);
  clock_.now += 25;  // waiting for a worker
  EXPECT_EQ(pool_.Now(), 0);
  Peer p = Joined();
  EXPECT_EQ(pool_.Now(), 0);
  clock_.now += 1.5;
  EXPECT_EQ(pool_.Now(), 1.5);
}

TEST_F(PoolTest, GarbageIsABadFrame) {
  Peer p = Connect();
  ReadSetup(&p);
  p.Send("this is not a frame at all");
  EXPECT_TRUE(Has(LostWhy(), "sent a bad frame: ")) << "garbage";
}

TEST_F(PoolTest, ATruncatedFrameWaitsThenTheCloseLosesTheWorker) {
  Peer p = Connect();
  ReadSetup(&p);
  std::string f;
  proto::EncodeHello(proto::Hello(), &f);
  p.Send(f.substr(0, f.size() / 2));
  EXPECT_TRUE(Events().empty());  // the rest may still come
  p.Close();
  EXPECT_EQ(LostWhy(), "closed the connection");
}

TEST_F(PoolTest, AGarbledPayloadIsNamed) {
  Peer p = Connect();
  ReadSetup(&p);
  std::string f;
  proto::EncodeHello(proto::Hello(), &f);
  f.resize(f.size() - 1);
  f[0] = char(f[0] - 1);  // the header's length, little-endian, one byte less
  p.Send(f);
  EXPECT_TRUE(Has(LostWhy(), "garbled hello: ")) << "truncated payload";
}

TEST_F(PoolTest, WrongProtocolVersion) {
  Peer p = Connect();
  ReadSetup(&p);
  proto::Hello h;
  h.version = proto::kVersion + 1;
  p.SendHello(h);
  const std::string why = LostWhy();
  EXPECT_TRUE(Has(why, "speaks protocol version " + std::to_string(proto::kVersion + 1) +
                           ", this master speaks " + std::to_string(proto::kVersion)))
      << why;
}

TEST_F(PoolTest, AnotherBuild) {
  Peer p = Connect();
  ReadSetup(&p);
  proto::Hello h;
  h.build = "radiosity 0.0 (elsewhere)";
  p.SendHello(h);
  const std::string why = LostWhy();
  EXPECT_TRUE(Has(why, "is another build ('radiosity 0.0 (elsewhere)'")) << why;
}

TEST_F(PoolTest, AnotherMesh) {
  Peer p = Connect();
  ReadSetup(&p);
  p.SendHello();
  std::string f;
  proto::EncodeReady({mesh_.elems.size(), MeshHash(mesh_) ^ 1}, &f);
  p.Send(f);
  const std::string why = LostWhy();
  EXPECT_TRUE(Has(why, "built a different mesh (" + std::to_string(mesh_.elems.size()) +
                           " elements")) << why;
}

TEST_F(PoolTest, AColumnBeforeJoiningIsUnexpected) {
  Peer p = Connect();
  ReadSetup(&p);
  p.SendHello();
  proto::Column c;
  std::string f;
  proto::EncodeColumn(c, &f);
  p.Send(f);
  EXPECT_EQ(LostWhy(), "sent an unexpected column frame");
}

TEST_F(PoolTest, AColumnOutOfTheMeshIsRefused) {
  Peer p = Joined();
  proto::Column c;
  c.patch = int32_t(mesh_.patches.size());
  std::string f;
  proto::EncodeColumn(c, &f);
  p.Send(f);
  EXPECT_EQ(LostWhy(), "sent a column out of the mesh's range");
}

TEST_F(PoolTest, AWorkersErrorIsPassedOn) {
  Peer p = Connect();
  ReadSetup(&p);
  std::string f;
  proto::EncodeError("cannot build the mesh", &f);
  p.Send(f);
  EXPECT_EQ(LostWhy(), "says: cannot build the mesh");
}

TEST_F(PoolTest, AWorkerThatClosesMidColumnIsLost) {
  Peer p = Joined();
  pool_.Assign(0, {0, 0});
  std::vector<WorkerEvent> ev;
  pool_.Poll(0, &ev);
  Msg type;
  ASSERT_TRUE(p.Next(&type));
  ASSERT_EQ(type, Msg::kWork);
  p.Close();  // as a worker that crashed while computing it
  EXPECT_EQ(LostWhy(), "closed the connection");
  // A lost worker gets nothing more, and Divide passes it by.
  pool_.Divide({0});
  EXPECT_TRUE(Events().empty());
}

TEST_F(PoolTest, LateJoinersGetEveryDivisionSoFar) {
  pool_.Divide({0});
  pool_.Divide({1, 2});
  Peer p = Connect();
  ReadSetup(&p);
  Msg type;
  std::string payload, err;
  ASSERT_TRUE(p.Next(&type, &payload));
  ASSERT_EQ(type, Msg::kDivide);
  std::vector<int32_t> elems;
  ASSERT_TRUE(proto::DecodeDivide(payload, &elems, &err)) << err;
  EXPECT_EQ(elems, (std::vector<int32_t>{0, 1, 2}));
}

TEST_F(PoolTest, ShutdownSaysBye) {
  Peer p = Joined();
  pool_.Shutdown();
  Msg type;
  ASSERT_TRUE(p.Next(&type));
  EXPECT_EQ(type, Msg::kBye);
  EXPECT_FALSE(p.Next(&type));
}

// A worker's connection that logs Close's steps and whose process ends
// at the `ends_at`-th look after its hangup (0: never, until killed).
class LoggedConn : public Conn {
 public:
  LoggedConn(int fd, std::string name, int ends_at, std::vector<std::string>* log)
      : inner_(SocketConn(fd)), name_(std::move(name)), ends_at_(ends_at), log_(log) {}
  int fd() const override { return inner_->fd(); }
  long Read(char* buf, size_t n) override { return inner_->Read(buf, n); }
  long Write(const char* buf, size_t n) override { return inner_->Write(buf, n); }
  void Hangup() override {
    log_->push_back("hangup " + name_);
    hung_up_ = true;
    inner_->Hangup();
  }
  bool Ended() override { return hung_up_ && ends_at_ > 0 && ++looks_ >= ends_at_; }
  std::string Reap() override {
    log_->push_back("reap " + name_ + (Ended() ? "" : ", killed"));
    return inner_->Reap();
  }

 private:
  std::unique_ptr<Conn> inner_;
  std::string name_;
  int ends_at_, looks_ = 0;
  bool hung_up_ = false;
  std::vector<std::string>* log_;
};

class ShutdownTest : public PoolTest {
 protected:
  ~ShutdownTest() override {
    for (int fd : peers_) ::close(fd);
  }
  // A LoggedConn to the pool, its other end left unread.
  void Add(const std::string& name, int ends_at) {
    int sv[2];
    ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv), 0);
    pool_.Add(std::make_unique<LoggedConn>(sv[0], name, ends_at, &log_), name);
    peers_.push_back(sv[1]);
  }
  std::vector<std::string> log_;
  std::vector<int> peers_;
};

// At the end of a run every worker is told before any is waited for, so
// that the run ends when the slowest has exited, not after the sum.
TEST_F(ShutdownTest, EveryWorkerIsToldBeforeAnyIsWaitedFor) {
  Add("a", 3);
  Add("b", 1);
  pool_.Shutdown();
  EXPECT_EQ(log_, (std::vector<std::string>{"hangup a", "hangup b", "reap a", "reap b"}));
}

// One that does not exit is given the second the others are, then killed
// (real time: the pool waits for processes, not on its clock).
TEST_F(ShutdownTest, AWorkerThatDoesNotExitIsKilledAfterASecond) {
  Add("stuck", 0);
  Add("quick", 2);
  const double t0 = MonotonicSeconds();
  pool_.Shutdown();
  const double waited = MonotonicSeconds() - t0;
  EXPECT_EQ(log_, (std::vector<std::string>{"hangup stuck", "hangup quick",
                                            "reap stuck, killed", "reap quick"}));
  EXPECT_GE(waited, 1.0);
  EXPECT_LT(waited, 1.9);
}

// A real worker on a thread: it joins, computes the column the master
// would and leaves on bye with status 0.
TEST_F(PoolTest, ARealWorkerComputesTheColumn) {
  int sv[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv), 0);
  int status = -1;
  std::string err;
  std::thread worker([&] { status = RunWorker(sv[1], sv[1], &err); });
  pool_.Add(SocketConn(sv[0]), "thread");
  std::vector<WorkerEvent> ev;
  while (ev.empty()) pool_.Poll(10, &ev);  // returns when the worker writes
  ASSERT_EQ(ev[0].kind, WorkerEvent::kJoined) << ev[0].why;
  pool_.Assign(0, {2, 1});
  ev.clear();
  while (ev.empty()) pool_.Poll(10, &ev);
  ASSERT_EQ(ev[0].kind, WorkerEvent::kColumn) << ev[0].why;
  EXPECT_EQ(ev[0].column.patch, 2);
  EXPECT_EQ(ev[0].column.k, 1);
  Hemicube h(16);
  std::vector<FormFactor> want;
  ShotColumn(&h, mesh_, 2, GroupOf(mesh_, 2), 1, false, 1, &want);
  ASSERT_EQ(ev[0].column.ff.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) EXPECT_EQ(ev[0].column.ff[i].elem, want[i].elem);
  pool_.Shutdown();
  worker.join();
  ::close(sv[1]);
  EXPECT_EQ(status, 0) << err;
}

// Workers are started and sent the scene before the master has meshed it
// (MasterRun::MeshScene): the pool is made without the mesh, SendScene
// writes the frame, and the ready is checked against the mesh given
// later. The sockets' buffers are made small, so that the room's frame
// does not fit in them at once.
class SendSceneTest : public ::testing::Test {
 protected:
  SendSceneTest() {
    setup_.scene = ShippedScene("room");
    mesh_ = MakeMesh(setup_.scene);
    setup_.resolution = 16;
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv_), 0);
    const int small = 4096;
    ::setsockopt(sv_[0], SOL_SOCKET, SO_SNDBUF, &small, sizeof small);
    ::setsockopt(sv_[1], SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    wake_ = ::eventfd(0, EFD_CLOEXEC);
    EXPECT_GE(wake_, 0);
  }
  ~SendSceneTest() override { ::close(wake_); }
  void Wake() {
    const uint64_t one = 1;
    ASSERT_EQ(::write(wake_, &one, sizeof one), ssize_t(sizeof one));
  }

  FakeClock clock_;
  proto::SceneSetup setup_;
  Mesh mesh_;
  int sv_[2];
  int wake_ = -1;
};

TEST_F(SendSceneTest, ARealWorkerIsSentTheSceneThenJoinsOnceTheMeshIsGiven) {
  WorkerPool pool(setup_, PoolOptions(), &clock_);
  int status = -1;
  std::string err;
  std::thread worker([&] { status = RunWorker(sv_[1], sv_[1], &err); });
  pool.Add(SocketConn(sv_[0]), "thread");
  pool.SendScene(wake_);  // never woken: it returns once the worker has it all
  // (more than the buffers hold: AWakeEndsItAndPollSendsTheRest)
  EXPECT_EQ(pool.BytesSent(), pool.SetupBytes());
  pool.SetMesh(mesh_, MeshHash(mesh_));
  std::vector<WorkerEvent> ev;
  while (ev.empty()) pool.Poll(10, &ev);  // the worker's ready, checked now
  ASSERT_EQ(ev[0].kind, WorkerEvent::kJoined) << ev[0].why;
  pool.Shutdown();
  worker.join();
  ::close(sv_[1]);
  EXPECT_EQ(status, 0) << err;
}

TEST_F(SendSceneTest, AWakeEndsItAndPollSendsTheRest) {
  WorkerPool pool(setup_, PoolOptions(), &clock_);
  pool.Add(SocketConn(sv_[0]), "w");
  Wake();  // the master is done meshing; the peer has read nothing
  pool.SendScene(wake_);
  ASSERT_LT(pool.BytesSent(), pool.SetupBytes());
  pool.SetMesh(mesh_, MeshHash(mesh_));
  size_t got = 0;
  std::thread reader([&] {
    char buf[4096];
    while (got < pool.SetupBytes()) {
      const ssize_t n = ::read(sv_[1], buf, sizeof buf);
      if (n <= 0) break;
      got += size_t(n);
    }
  });
  std::vector<WorkerEvent> ev;
  while (pool.BytesSent() < pool.SetupBytes()) pool.Poll(10, &ev);
  reader.join();
  EXPECT_EQ(got, pool.SetupBytes());
  EXPECT_TRUE(ev.empty());
  ::close(sv_[1]);
}

TEST_F(SendSceneTest, AWorkerLostMeanwhileIsReportedByTheFirstPoll) {
  WorkerPool pool(setup_, PoolOptions(), &clock_);
  pool.Add(SocketConn(sv_[0]), "w");
  ::close(sv_[1]);
  pool.SendScene(wake_);  // the write fails: lost, nothing to wait for
  pool.SetMesh(mesh_, MeshHash(mesh_));
  std::vector<WorkerEvent> ev;
  pool.Poll(0, &ev);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].kind, WorkerEvent::kLost);
  EXPECT_TRUE(Has(ev[0].why, "cannot send")) << ev[0].why;
}

// A real worker in a child process, killed with an assignment outstanding:
// the pool reports it lost, whatever the child was doing.
TEST_F(PoolTest, AKilledWorkerProcessIsLost) {
  int sv[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::close(sv[0]);
    std::string err;
    ::_exit(RunWorker(sv[1], sv[1], &err));
  }
  ::close(sv[1]);
  pool_.Add(SocketConn(sv[0]), "child");
  std::vector<WorkerEvent> ev;
  while (ev.empty()) pool_.Poll(10, &ev);
  ASSERT_EQ(ev[0].kind, WorkerEvent::kJoined) << ev[0].why;
  pool_.Assign(0, {0, 0});
  ev.clear();
  pool_.Poll(0, &ev);  // the work goes out
  ASSERT_EQ(::kill(pid, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status));
  // Its column may have come back before the kill; then the loss.
  for (int i = 0; i < 100 && (ev.empty() || ev.back().kind != WorkerEvent::kLost); ++i)
    pool_.Poll(10, &ev);
  ASSERT_FALSE(ev.empty());
  EXPECT_EQ(ev.back().kind, WorkerEvent::kLost);
  // Killed with the work frame unread, its end resets the connection.
  const std::string why = ev.back().why;
  EXPECT_TRUE(why == "closed the connection" || Has(why, "cannot read: ")) << why;
}

}  // namespace
