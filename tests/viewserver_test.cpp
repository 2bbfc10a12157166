#include "viewserver.h"

#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "clock.h"

namespace {

ViewInfo Info() {
  ViewInfo info;
  info.scene = "box.obj";
  return info;
}

ShadedMesh Triangle(float c) {
  ShadedMesh m;
  m.own = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.colors = {glm::vec3(c), glm::vec3(c), glm::vec3(c)};
  m.polys = {{0, 1, 2, -1}};
  return m;
}

int Port(const std::string& bound) { return std::stoi(bound.substr(bound.rfind(':') + 1)); }

TEST(ViewServer, ServesThePageTheStateAndTheSnapshots) {
  ViewServer view(Info(), {{0, 0, 1, 3, 1, NAN, NAN}});
  std::string bound, err;
  ASSERT_TRUE(view.Start("127.0.0.1", 0, &bound, &err)) << err;
  EXPECT_EQ(bound.rfind("127.0.0.1:", 0), 0u) << bound;
  httplib::Client c("127.0.0.1", Port(bound));

  auto page = c.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_EQ(page->body, ViewPage());
  auto none = c.Get("/mesh.bin");
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 503);  // no snapshot yet

  EXPECT_TRUE(view.SnapshotDue());
  view.Row({0.5, 6, 1, 3, 0.5, NAN, NAN}, 2);
  view.Snapshot(6, [] { return Triangle(2); });
  EXPECT_FALSE(view.SnapshotDue());  // a second has not passed
  EXPECT_EQ(view.snapshots(), 1);

  auto state = c.Get("/state.json?rows=1");
  ASSERT_TRUE(state);
  EXPECT_EQ(state->status, 200);
  ViewState st;
  st.workers = 2;
  st.snapshot = 1;
  st.snapshot_shots = 6;
  EXPECT_EQ(state->body, ViewStateJson(Info(), st, {{0.5, 6, 1, 3, 0.5, NAN, NAN}}, 1));
  auto mesh = c.Get("/mesh.bin");
  ASSERT_TRUE(mesh);
  EXPECT_EQ(mesh->status, 200);
  EXPECT_EQ(mesh->get_header_value("X-Radiosity-Snapshot"), "1 6");
  EXPECT_EQ(mesh->body, ViewMeshBlob(Triangle(2), AutoExposure(Triangle(2))));

  view.Finish("final", 9, "converged");
  auto end = c.Get("/state.json?rows=99");
  ASSERT_TRUE(end);
  EXPECT_NE(end->body.find("\"status\":\"converged\""), std::string::npos) << end->body;
  EXPECT_NE(end->body.find("\"snapshot\":{\"id\":2,\"shots\":9},\"first\":2,\"rows\":[]"),
            std::string::npos) << end->body;
  auto last = c.Get("/mesh.bin");
  ASSERT_TRUE(last);
  EXPECT_EQ(last->body, "final");
  EXPECT_EQ(last->get_header_value("X-Radiosity-Snapshot"), "2 9");

  auto bad = c.Get("/state.json?rows=-1");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  auto missing = c.Get("/result.csv");
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 404);
  auto foreign = c.Get("/state.json", {{"Host", "rebound.example:80"}});
  ASSERT_TRUE(foreign);
  EXPECT_EQ(foreign->status, 403);
}

TEST(ViewServer, StopsWithinItsWaitWithASilentClientConnected) {
  ViewServer view(Info(), {});
  std::string bound, err;
  ASSERT_TRUE(view.Start("127.0.0.1", 0, &bound, &err)) << err;
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(uint16_t(Port(bound)));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  const double t0 = MonotonicSeconds();
  view.Stop();
  EXPECT_LT(MonotonicSeconds() - t0, ViewServer::kStopWait + 0.5);
  ::close(fd);
}

TEST(ViewServer, RefusesAnAddressInUse) {
  ViewServer a(Info(), {}), b(Info(), {});
  std::string bound, err;
  ASSERT_TRUE(a.Start("127.0.0.1", 0, &bound, &err)) << err;
  EXPECT_FALSE(b.Start("127.0.0.1", Port(bound), &bound, &err));
  EXPECT_NE(err.find("cannot listen on 127.0.0.1:"), std::string::npos) << err;
}

}  // namespace
