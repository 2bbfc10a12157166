// RunWorker on a thread with the test as its master over a socketpair:
// what it says and how it ends when the master speaks well or badly.
#include "worker.h"

#include <sys/socket.h>
#include <unistd.h>

#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "ffcodec.h"
#include "groups.h"
#include "hemicube.h"
#include "protocol.h"
#include "peer.h"
#include "test_util.h"

namespace {

using proto::Msg;
using test::Peer;

class WorkerTest : public ::testing::Test {
 protected:
  WorkerTest() : setup_{Box(1.0, {glm::dvec3(0.5)}, {glm::dvec3(1.0)}), MeshOptions(), 16, 0, 1} {
    int sv[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv), 0);
    fd_ = sv[1];
    master_ = std::make_unique<Peer>(sv[0]);
    thread_ = std::thread([this] { status_ = RunWorker(fd_, fd_, &err_); });
  }
  ~WorkerTest() override {
    master_->Close();  // end of stream: a worker still running exits
    End();
  }
  // Waits for the worker to return.
  void End() {
    if (thread_.joinable()) thread_.join();
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  Msg Next(std::string* payload = nullptr) {
    Msg type = Msg::kBye;
    EXPECT_TRUE(master_->Next(&type, payload));
    return type;
  }
  // The worker's hello, the master's hello and scene, the worker's ready.
  void Handshake() {
    ASSERT_EQ(Next(), Msg::kHello);
    std::string f;
    proto::EncodeHello(proto::Hello(), &f);
    proto::EncodeScene(setup_, &f);
    master_->Send(f);
    std::string payload, err;
    Msg type = Next(&payload);
    while (type == Msg::kHeartbeat) type = Next(&payload);  // while it builds the mesh
    ASSERT_EQ(type, Msg::kReady);
    proto::Ready r;
    ASSERT_TRUE(proto::DecodeReady(payload, &r, &err)) << err;
    const Mesh m = MakeMesh(setup_.scene);
    EXPECT_EQ(r.elements, m.elems.size());
    EXPECT_EQ(r.mesh_hash, MeshHash(m));
  }
  // The next column the worker sent: assignment a's, as ShotColumn draws
  // it on m (ids exact, form factors within the wire's rounding).
  void ExpectColumn(Hemicube* h, const Mesh& m, const proto::Assignment& a) {
    std::string payload, err;
    Msg type = Next(&payload);
    while (type == Msg::kHeartbeat) type = Next(&payload);
    ASSERT_EQ(type, Msg::kColumn);
    proto::Column c;
    ASSERT_TRUE(proto::DecodeColumn(payload, &c, &err)) << err;
    EXPECT_EQ(c.patch, a.patch);
    EXPECT_EQ(c.k, a.k);
    std::vector<FormFactor> want;
    ShotColumn(h, m, a.patch, a.Group(), a.k, false, 1, &want);
    ASSERT_EQ(c.ff.size(), want.size());
    for (size_t i = 0; i < want.size(); ++i) {
      EXPECT_EQ(c.ff[i].elem, want[i].elem) << i;
      EXPECT_NEAR(c.ff[i].f, want[i].f, proto::kFormFactorError * want[i].f) << i;
    }
  }
  // The error frame the worker sent, and its return.
  std::string Error() {
    std::string payload, text, err;
    Msg type = Next(&payload);
    while (type == Msg::kHeartbeat) type = Next(&payload);
    EXPECT_EQ(type, Msg::kError);
    EXPECT_TRUE(proto::DecodeError(payload, &text, &err)) << err;
    End();
    EXPECT_EQ(status_, 1);
    EXPECT_EQ(err_, text);
    return text;
  }

  proto::SceneSetup setup_;
  std::unique_ptr<Peer> master_;
  int fd_ = -1;
  int status_ = -1;
  std::string err_;
  std::thread thread_;
};

TEST_F(WorkerTest, ComputesColumnsInOrderAndLeavesOnBye) {
  Handshake();
  std::string f;
  proto::EncodeWork({{1, 0}, {4, 3}}, &f);
  master_->Send(f);
  const Mesh m = MakeMesh(setup_.scene);
  Hemicube h(16);
  ExpectColumn(&h, m, {1, 0});
  ExpectColumn(&h, m, {4, 3});
  f.clear();
  proto::EncodeBye(&f);
  master_->Send(f);
  End();
  EXPECT_EQ(status_, 0) << err_;
}

// Division edits between columns (which free the worker's hemicube cache):
// the next column is drawn on the divided mesh, its children included.
TEST_F(WorkerTest, AColumnAfterDivisionsSeesTheDividedMesh) {
  Handshake();
  Mesh m = MakeMesh(setup_.scene);
  Hemicube h(16);
  std::string f;
  proto::EncodeWork({{1, 0}}, &f);
  master_->Send(f);
  ExpectColumn(&h, m, {1, 0});
  // Every top element of the last face divided: its children receive
  // from patch 1 (of another face).
  ASSERT_NE(m.patches[1].face, int(m.faces.size()) - 1);
  std::vector<int32_t> divided;
  for (int p : m.FacePatches(m.faces.back()))
    for (int e : m.Tops(p)) divided.push_back(e);
  const int32_t before = int32_t(m.elems.size());
  for (int32_t e : divided) Divide(&m, e);
  f.clear();
  proto::EncodeDivide(divided, &f);
  proto::EncodeWork({{1, 1}}, &f);
  master_->Send(f);
  ExpectColumn(&h, m, {1, 1});
  std::vector<FormFactor> want;
  ShotColumn(&h, m, 1, GroupOf(m, 1), 1, false, 1, &want);
  EXPECT_GE(want.back().elem, before);  // a child's, which ExpectColumn compared
}

// A large scene takes long to arrive and to mesh: the worker says that it
// lives meanwhile (doc/protocol.txt, the conversation).
TEST_F(WorkerTest, HeartbeatsWhileTheSceneArrives) {
  ASSERT_EQ(Next(), Msg::kHello);
  std::string hello, scene;
  proto::EncodeHello(proto::Hello(), &hello);
  proto::EncodeScene(setup_, &scene);
  master_->Send(hello + scene.substr(0, scene.size() / 2));
  EXPECT_EQ(Next(), Msg::kHeartbeat);  // within 0.25 s of silence
  master_->Send(scene.substr(scene.size() / 2));
  Msg type = Next();
  while (type == Msg::kHeartbeat) type = Next();
  EXPECT_EQ(type, Msg::kReady);
  master_->Close();
  End();
  EXPECT_EQ(status_, 0) << err_;
}

TEST_F(WorkerTest, EndOfStreamBeforeTheSceneIsAQuietExit) {
  ASSERT_EQ(Next(), Msg::kHello);
  master_->Close();
  End();
  EXPECT_EQ(status_, 0) << err_;
}

TEST_F(WorkerTest, RefusesAnotherProtocolVersion) {
  ASSERT_EQ(Next(), Msg::kHello);
  proto::Hello h;
  h.version = proto::kVersion + 1;
  h.build = "elsewhere";
  std::string f;
  proto::EncodeHello(h, &f);
  master_->Send(f);
  EXPECT_EQ(Error(), "this worker is '" + proto::BuildId() + "', the master 'elsewhere'");
}

TEST_F(WorkerTest, GarbageFromTheMasterIsAnError) {
  ASSERT_EQ(Next(), Msg::kHello);
  master_->Send("garbage, not a frame");
  EXPECT_FALSE(Error().empty());
}

TEST_F(WorkerTest, WorkOutOfTheMeshIsAnError) {
  Handshake();
  std::string f;
  proto::EncodeWork({{1 << 20, 0}}, &f);
  master_->Send(f);
  EXPECT_EQ(Error(), "patch 1048576 out of range");
}

TEST_F(WorkerTest, AGroupMemberOutOfTheMeshIsAnError) {
  Handshake();
  proto::Assignment a{1, 0};
  a.group.members = {1, 2, 1 << 20};
  a.group.center = glm::dvec3(0.5);
  a.group.normal = glm::dvec3(0, 1, 0);
  std::string f;
  proto::EncodeWork({a}, &f);
  master_->Send(f);
  EXPECT_EQ(Error(), "patch 1's group: member 1048576 out of range");
}

TEST_F(WorkerTest, ADivisionOfNoLeafIsAnError) {
  Handshake();
  std::string f;
  proto::EncodeDivide({0, 0}, &f);  // the second time 0 is divided already
  master_->Send(f);
  EXPECT_EQ(Error(), "cannot divide element 0");
}

TEST_F(WorkerTest, TheMastersErrorEndsIt) {
  Handshake();
  std::string f;
  proto::EncodeError("stop", &f);
  master_->Send(f);
  End();
  EXPECT_EQ(status_, 1);
  EXPECT_EQ(err_, "master says: stop");
}

}  // namespace
