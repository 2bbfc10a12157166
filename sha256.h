// SHA-256 (FIPS 180-4) and HMAC-SHA256 (RFC 2104), self-contained: the
// checksum that keys uploaded binaries on remote hosts, and the MAC of the
// connect-back handshake. Not for bulk data: a few MB per run at most.
#ifndef RADIOSITY_SHA256_H
#define RADIOSITY_SHA256_H

#include <cstdint>
#include <string>

class Sha256 {
 public:
  Sha256();
  void Update(const void* data, size_t n);
  std::string Digest();  // 32 raw bytes; the object is spent after this

 private:
  void Block(const uint8_t* p);
  uint32_t h_[8];
  uint8_t buf_[64];
  size_t used_ = 0;
  uint64_t bytes_ = 0;
};

std::string Sha256Of(const std::string& data);  // 32 raw bytes
std::string HmacSha256(const std::string& key, const std::string& msg);  // 32 raw bytes
std::string Hex(const std::string& bytes);  // lower case

// Compares without an early exit, so that the time taken does not tell an
// attacker how much of a MAC was right.
bool SameBytes(const std::string& a, const std::string& b);

#endif
