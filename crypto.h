// SHA-256 and HMAC-SHA256 from OpenSSL's libcrypto: the checksum that keys
// uploaded binaries on remote hosts and seals checkpoints, and the MAC of
// the connect-back handshake. libcrypto is libssh's own crypto, so it is on
// every machine that builds radiosity; as mosh's src/crypto chooses
// OpenSSL's implementation, a vetted primitive beats a hand-written one on
// an authentication path.
#ifndef RADIOSITY_CRYPTO_H
#define RADIOSITY_CRYPTO_H

#include <string>

std::string Sha256Of(const std::string& data);  // 32 raw bytes
std::string HmacSha256(const std::string& key, const std::string& msg);  // 32 raw bytes
std::string Hex(const std::string& bytes);  // lower case

// Compares in constant time (CRYPTO_memcmp), so that the time taken does
// not tell an attacker how much of a MAC was right.
bool SameBytes(const std::string& a, const std::string& b);

#endif
