// The pool on a thread of its own against peers on socketpairs (the test
// speaking frames, or a real RunWorker on a thread): what the master's
// thread orders reaches the workers in order, what they send comes back
// through Poll, waiting for it rather than for a fixed time, and signals
// stay with the master's thread.
#include "pool_thread.h"

#include <pthread.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "groups.h"
#include "peer.h"
#include "protocol.h"
#include "test_util.h"
#include "worker.h"

namespace {

using proto::Msg;
using test::Peer;

class ThreadedPoolTest : public ::testing::Test {
 protected:
  ThreadedPoolTest()
      : mesh_(MakeMesh(Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}))),
        setup_{Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}), MeshOptions(), 16, 0, 1} {}

  // n workers whose other ends are peers, then the pool on its thread.
  std::vector<Peer> Start(int n) {
    auto pool = std::make_unique<WorkerPool>(setup_, mesh_, PoolOptions());
    std::vector<Peer> peers;
    for (int i = 0; i < n; ++i) {
      int sv[2];
      EXPECT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv), 0);
      pool->Add(SocketConn(sv[0]), "worker " + std::to_string(i));
      peers.emplace_back(sv[1]);
    }
    pool_ = std::make_unique<ThreadedPool>(std::move(pool), mesh_);
    return peers;
  }
  // Reads the hello and scene, answers hello and ready.
  void Join(Peer* p) {
    Msg type;
    ASSERT_TRUE(p->Next(&type));
    ASSERT_EQ(type, Msg::kHello);
    ASSERT_TRUE(p->Next(&type));
    ASSERT_EQ(type, Msg::kScene);
    p->SendHello();
    p->SendReady(mesh_);
  }
  // The next events, waiting for them (a bound only a failing test reaches).
  std::vector<WorkerEvent> Next(size_t want = 1) {
    std::vector<WorkerEvent> ev;
    const double until = MonotonicSeconds() + 10;
    while (ev.size() < want && MonotonicSeconds() < until) pool_->Poll(10, &ev);
    EXPECT_EQ(ev.size(), want);
    return ev;
  }
  void SendColumn(Peer* p, int patch, std::vector<FormFactor> ff) {
    proto::Column c;
    c.patch = patch;
    c.ff = std::move(ff);
    std::string frame;
    proto::EncodeColumn(c, &frame);
    p->Send(frame);
  }

  Mesh mesh_;
  proto::SceneSetup setup_;
  std::unique_ptr<ThreadedPool> pool_;
};

TEST_F(ThreadedPoolTest, OrdersGoOutInOrderAndColumnsComeBack) {
  std::vector<Peer> peers = Start(2);
  EXPECT_EQ(pool_->Workers(), 2);
  EXPECT_EQ(pool_->Starting(), 2);
  EXPECT_EQ(pool_->Name(1), "worker 1");
  for (Peer& p : peers) Join(&p);
  std::vector<WorkerEvent> ev = Next(2);
  ASSERT_EQ(ev.size(), 2u);
  for (const WorkerEvent& e : ev) EXPECT_EQ(e.kind, WorkerEvent::kJoined);
  EXPECT_EQ(pool_->Starting(), 0);  // as the pool said it with the joins

  // Work, a division, more work: worker 1 reads them in that order.
  pool_->Assign(1, {3, 0});
  pool_->Divide({5});
  pool_->Assign(1, {4, 1});
  pool_->Send(&ev);
  Msg type;
  std::string payload, err;
  std::vector<proto::Assignment> work;
  std::vector<int32_t> divided;
  ASSERT_TRUE(peers[1].NextWork(&work));
  ASSERT_EQ(work.size(), 1u);
  EXPECT_EQ(work[0].patch, 3);
  ASSERT_TRUE(peers[1].Next(&type, &payload));
  ASSERT_EQ(type, Msg::kDivide);
  ASSERT_TRUE(proto::DecodeDivide(payload, &divided, &err)) << err;
  EXPECT_EQ(divided, std::vector<int32_t>{5});
  ASSERT_TRUE(peers[1].NextWork(&work));
  EXPECT_EQ(work[0].patch, 4);
  EXPECT_EQ(work[0].k, 1);
  ASSERT_TRUE(peers[0].Next(&type));  // the division reaches every worker
  EXPECT_EQ(type, Msg::kDivide);

  SendColumn(&peers[1], 3, {{1, 0.25f}, {4, 0.5f}});
  ev = Next();
  ASSERT_EQ(ev[0].kind, WorkerEvent::kColumn);
  EXPECT_EQ(ev[0].worker, 1);
  EXPECT_EQ(ev[0].column.patch, 3);
  ASSERT_EQ(ev[0].column.ff.size(), 2u);
  EXPECT_EQ(ev[0].column.ff[1].elem, 4);
  EXPECT_GT(pool_->BytesReceived(), 0u);
  EXPECT_GT(pool_->BytesSent(), 0u);
}

// Storage handed back on the master's thread is what the pool thread
// decodes the next column into.
TEST_F(ThreadedPoolTest, HandedBackStorageIsDecodedInto) {
  std::vector<Peer> peers = Start(1);
  Join(&peers[0]);
  Next();
  std::vector<WorkerEvent> ev;
  pool_->Assign(0, {2, 0});
  pool_->Send(&ev);
  SendColumn(&peers[0], 2, {{1, 0.5f}});
  ev = Next();
  std::vector<FormFactor> ff = std::move(ev[0].column.ff);
  ff.reserve(5000);
  const FormFactor* storage = ff.data();
  pool_->Recycle(std::move(ff));
  pool_->Assign(0, {2, 1});
  ev.clear();
  pool_->Send(&ev);
  Msg type;
  ASSERT_TRUE(peers[0].Next(&type));
  ASSERT_TRUE(peers[0].Next(&type));  // both assignments: the storage went with the second
  SendColumn(&peers[0], 2, {{3, 0.5f}});
  ev = Next();
  EXPECT_EQ(ev[0].column.ff.data(), storage);
  EXPECT_GE(ev[0].column.ff.capacity(), 5000u);
}

TEST_F(ThreadedPoolTest, AWorkerThatClosesIsLost) {
  std::vector<Peer> peers = Start(1);
  Join(&peers[0]);
  Next();
  peers[0].Close();
  std::vector<WorkerEvent> ev = Next();
  ASSERT_EQ(ev[0].kind, WorkerEvent::kLost);
  EXPECT_NE(ev[0].why.find("closed the connection"), std::string::npos) << ev[0].why;
}

// The master may assign to a worker the pool thread has lost before the
// loss reaches it (tests/ssh.sh's kill -9 of a remote worker aborted the
// master so, on WorkerPool::Assign's CHECK that the worker had joined,
// in 1 run of 11 here): the order is dropped, the pool goes on.
TEST_F(ThreadedPoolTest, AnAssignmentToAWorkerLostMeanwhileIsDropped) {
  std::vector<Peer> peers = Start(2);
  for (Peer& p : peers) Join(&p);
  Next(2);
  peers[0].Close();
  std::vector<WorkerEvent> ev = Next();
  ASSERT_EQ(ev[0].kind, WorkerEvent::kLost);
  ASSERT_EQ(ev[0].worker, 0);
  pool_->Assign(0, {2, 0});  // as a master that has not yet polled would
  pool_->Assign(1, {3, 0});
  ev.clear();
  pool_->Send(&ev);
  std::vector<proto::Assignment> work;
  ASSERT_TRUE(peers[1].NextWork(&work));
  ASSERT_EQ(work.size(), 1u);
  EXPECT_EQ(work[0].patch, 3);
}

// Columns' ids are checked against the mesh as this thread divided it,
// the counts going with the Divide (the pool thread never reads the mesh
// this thread changes): an id of a child is refused before, taken after.
TEST_F(ThreadedPoolTest, ColumnsAreCheckedAgainstTheMeshOfTheLastDivide) {
  std::vector<Peer> peers = Start(2);
  for (Peer& p : peers) Join(&p);
  Next(2);
  const int32_t child = int32_t(mesh_.elems.size());  // Divide's first child
  SendColumn(&peers[0], 1, {{child, 0.5f}});
  std::vector<WorkerEvent> ev = Next();
  ASSERT_EQ(ev[0].kind, WorkerEvent::kLost);
  EXPECT_EQ(ev[0].worker, 0);
  EXPECT_NE(ev[0].why.find("out of the mesh's range"), std::string::npos) << ev[0].why;
  Divide(&mesh_, 0);
  ASSERT_GT(mesh_.elems.size(), size_t(child));
  pool_->Divide({0});
  pool_->Send(&ev);
  Msg type;
  ASSERT_TRUE(peers[1].Next(&type));  // the pool thread has taken the Divide
  EXPECT_EQ(type, Msg::kDivide);
  SendColumn(&peers[1], 1, {{child, 0.5f}});
  ev = Next();
  EXPECT_EQ(ev[0].kind, WorkerEvent::kColumn) << ev[0].why;
}

// A real worker on a thread: its column is the one the master would
// compute, and bye ends it with status 0.
TEST_F(ThreadedPoolTest, ARealWorkerComputesTheColumn) {
  int sv[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv), 0);
  int status = -1;
  std::string err;
  std::thread worker([&] { status = RunWorker(sv[1], sv[1], &err); });
  auto pool = std::make_unique<WorkerPool>(setup_, mesh_, PoolOptions());
  pool->Add(SocketConn(sv[0]), "thread");
  pool_ = std::make_unique<ThreadedPool>(std::move(pool), mesh_);
  std::vector<WorkerEvent> ev = Next();
  ASSERT_EQ(ev[0].kind, WorkerEvent::kJoined) << ev[0].why;
  pool_->Assign(0, {2, 1});
  ev = Next();
  ASSERT_EQ(ev[0].kind, WorkerEvent::kColumn) << ev[0].why;
  Hemicube h(16);
  std::vector<FormFactor> want;
  ShotColumn(&h, mesh_, 2, GroupOf(mesh_, 2), 1, false, 1, &want);
  ASSERT_EQ(ev[0].column.ff.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) EXPECT_EQ(ev[0].column.ff[i].elem, want[i].elem);
  pool_->Shutdown();
  worker.join();
  ::close(sv[1]);
  EXPECT_EQ(status, 0) << err;
}

std::atomic<int> handled{0};
std::atomic<bool> on_master{false};
pthread_t master_thread;
void Note(int) {
  on_master = pthread_equal(pthread_self(), master_thread) != 0;
  ++handled;
}

// A signal to the process is handled by the master's thread (the one that
// checks the stop flag), never by the pool thread, which blocks them all.
// The master's thread blocks it for a while: a pool thread that took
// signals would be given it then, and would have run the handler by the
// time it has woken to write an assignment.
TEST_F(ThreadedPoolTest, SignalsGoToTheMastersThread) {
  std::vector<Peer> peers = Start(1);
  Join(&peers[0]);
  Next();
  master_thread = pthread_self();
  struct sigaction sa {}, old {};
  sa.sa_handler = Note;
  sigemptyset(&sa.sa_mask);
  ASSERT_EQ(::sigaction(SIGUSR1, &sa, &old), 0);
  sigset_t usr1, was;
  sigemptyset(&usr1);
  sigaddset(&usr1, SIGUSR1);
  ASSERT_EQ(::pthread_sigmask(SIG_BLOCK, &usr1, &was), 0);
  ASSERT_EQ(::kill(::getpid(), SIGUSR1), 0);
  std::vector<WorkerEvent> ev;
  pool_->Assign(0, {1, 0});
  pool_->Send(&ev);
  Msg type;
  ASSERT_TRUE(peers[0].Next(&type));
  EXPECT_EQ(type, Msg::kWork);
  EXPECT_EQ(handled, 0) << "the pool thread took the signal";
  sigset_t pending;
  ASSERT_EQ(::sigpending(&pending), 0);
  EXPECT_TRUE(sigismember(&pending, SIGUSR1));
  ASSERT_EQ(::pthread_sigmask(SIG_SETMASK, &was, nullptr), 0);  // delivered here, now
  EXPECT_EQ(handled, 1);
  EXPECT_TRUE(on_master);
  ::sigaction(SIGUSR1, &old, nullptr);
}

TEST(UsePoolThread, WhenACoreIsFreeForItUnlessSaid) {
  EXPECT_TRUE(UsePoolThread(-1, 0, 2));   // remote workers only
  EXPECT_FALSE(UsePoolThread(-1, 1, 2));  // -j 1 on two cores
  EXPECT_FALSE(UsePoolThread(-1, 2, 2));
  EXPECT_TRUE(UsePoolThread(-1, 2, 4));
  EXPECT_FALSE(UsePoolThread(-1, 0, 1));
  EXPECT_TRUE(UsePoolThread(1, 2, 2));
  EXPECT_FALSE(UsePoolThread(0, 0, 64));
}

}  // namespace
