// Helpers for the tests of the binary formats (protocol, ffcodec,
// checkpoint): raw writers made from the documents (doc/protocol.txt, not
// from coding.h), so that tests can write any bytes; bytes as hex; the
// payload of one frame.
#ifndef RADIOSITY_TESTS_WIRE_UTIL_H
#define RADIOSITY_TESTS_WIRE_UTIL_H

#include <cstdio>
#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include "protocol.h"

inline void WLE(std::string* s, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) s->push_back(char((v >> (8 * i)) & 0xff));
}
inline void WVar(std::string* s, uint64_t v) {
  do {
    uint8_t b = v & 0x7f;
    v >>= 7;
    s->push_back(char(v ? b | 0x80 : b));
  } while (v);
}
inline void WF64(std::string* s, double d) {
  uint64_t b;
  std::memcpy(&b, &d, 8);
  WLE(s, b, 8);
}
inline void WVec(std::string* s, const glm::dvec3& v) {
  WF64(s, v.x);
  WF64(s, v.y);
  WF64(s, v.z);
}
inline std::string Header(uint32_t len, uint8_t type, uint8_t r0 = 0, uint8_t r1 = 0, uint8_t r2 = 0) {
  std::string h;
  WLE(&h, len, 4);
  h += char(type);
  h += char(r0);
  h += char(r1);
  h += char(r2);
  return h;
}


inline uint64_t Bits(double d) {
  uint64_t b;
  std::memcpy(&b, &d, 8);
  return b;
}
inline uint32_t Bits(float f) {
  uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}
inline std::string Hex(const std::string& s) {
  std::string h;
  char buf[4];
  for (char c : s) {
    std::snprintf(buf, sizeof buf, "%02x", unsigned(uint8_t(c)));
    h += buf;
  }
  return h;
}

// The one frame in `frame`: its type must be `type`; returns the payload.
inline std::string PayloadOf(const std::string& frame, proto::Msg type) {
  proto::FrameReader r;
  r.Append(frame.data(), frame.size());
  proto::Msg t = proto::Msg(0);
  std::string p, err;
  EXPECT_EQ(r.Next(&t, &p, &err), proto::FrameReader::kFrame) << err;
  EXPECT_EQ(t, type);
  EXPECT_EQ(r.buffered(), 0u);
  EXPECT_EQ(frame.size(), proto::kHeaderSize + p.size());
  return p;
}

#endif
