// The other end of a connection for the tests of the process and network
// layer: frames written with the proto:: encoders, frames read whole,
// waiting for what the other side sends (a generous bound that only a
// failing test reaches), never for a fixed time.
#ifndef RADIOSITY_TESTS_PEER_H
#define RADIOSITY_TESTS_PEER_H

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "mesh.h"
#include "protocol.h"

namespace test {

// One end of a socket: blocking writes (a closed peer fails the test,
// without SIGPIPE), reads of whole frames.
class Peer {
 public:
  explicit Peer(int fd) : fd_(fd) {}
  Peer(Peer&& o) : fd_(o.fd_), in_(std::move(o.in_)) { o.fd_ = -1; }
  ~Peer() { Close(); }
  void Close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  void Send(const std::string& bytes) {
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
      ASSERT_GT(n, 0);
      done += size_t(n);
    }
  }
  void SendHello(const proto::Hello& h = proto::Hello()) {
    std::string f;
    proto::EncodeHello(h, &f);
    Send(f);
  }
  void SendReady(const Mesh& mesh) {
    std::string f;
    proto::EncodeReady({mesh.elems.size(), MeshHash(mesh)}, &f);
    Send(f);
  }
  void SendHeartbeat() {
    std::string f;
    proto::EncodeHeartbeat(&f);
    Send(f);
  }
  // The next frame's type (its payload in *payload), or false at the end
  // of the stream.
  bool Next(proto::Msg* type, std::string* payload = nullptr) {
    std::string p, err;
    for (;;) {
      const proto::FrameReader::Result r = in_.Next(type, &p, &err);
      if (r == proto::FrameReader::kBad) {
        ADD_FAILURE() << err;
        return false;
      }
      if (r == proto::FrameReader::kFrame) break;
      pollfd pfd{fd_, POLLIN, 0};
      if (::poll(&pfd, 1, 10000) != 1) {
        ADD_FAILURE() << "nothing from the pool";
        return false;
      }
      char buf[65536];
      const ssize_t n = ::read(fd_, buf, sizeof buf);
      if (n <= 0) return false;
      in_.Append(buf, size_t(n));
    }
    if (payload) *payload = p;
    return true;
  }
  // The next frame's assignments; false (the test failed) when it is not
  // a work frame or does not decode.
  bool NextWork(std::vector<proto::Assignment>* work) {
    proto::Msg type;
    std::string payload, err;
    if (!Next(&type, &payload)) return false;
    if (type != proto::Msg::kWork) {
      ADD_FAILURE() << "frame of type " << int(type) << ", not work";
      return false;
    }
    if (!proto::DecodeWork(payload, work, &err)) {
      ADD_FAILURE() << err;
      return false;
    }
    return true;
  }
  // True when nothing at all is waiting to be read.
  bool Quiet() {
    if (in_.buffered() > 0) return false;
    pollfd pfd{fd_, POLLIN, 0};
    return ::poll(&pfd, 1, 0) == 0;
  }
  int fd() const { return fd_; }

 private:
  int fd_;
  proto::FrameReader in_;
};

}  // namespace test

#endif
