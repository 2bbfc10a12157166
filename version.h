// This program's identity: its version (--version), the version of the
// master/worker protocol (doc/protocol.txt) and the build id that master
// and workers compare in their hellos.
#ifndef RADIOSITY_VERSION_H
#define RADIOSITY_VERSION_H

#include <cstdint>
#include <string>

// A packager may set it at build time (-DRADIOSITY_VERSION='"1.0"').
#ifndef RADIOSITY_VERSION
#define RADIOSITY_VERSION "0.1"
#endif
constexpr char kRadiosityVersion[] = RADIOSITY_VERSION;

namespace proto {

// Bumped whenever a frame's layout or meaning changes.
constexpr uint16_t kVersion = 7;

// This build's identity, sent in Hello: version, protocol and the
// compiler, so that master and workers build identical meshes. At most
// kMaxBuild printable ASCII bytes.
constexpr size_t kMaxBuild = 256;
std::string BuildId();

}  // namespace proto

#endif
