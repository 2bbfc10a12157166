// libFuzzer target: the protocol decoder (protocol.h) as a master or worker
// meets it: bytes from the peer cut into reads of any size, split into
// frames by FrameReader, each frame decoded by its message's decoder
// (Hello, Scene, Ready, Work, Column, Divide, Error; Heartbeat and Bye are
// empty). What decodes must encode again and decode to the same message.
//
// Input: byte 0 chooses the mode. Even: a stream; byte 1 seeds the read
// sizes. Odd: one payload for the decoder of message type 1 + (byte 0 >> 1)
// % 9, the rest of the input, without a frame header (so the decoders
// see payloads the frame limits would otherwise keep small).
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "protocol.h"

namespace {

using namespace proto;

void Require(bool ok) {
  if (!ok) std::abort();
}

void Decode(Msg type, const std::string& payload, bool framed) {
  std::string err, again;
  switch (type) {
    case Msg::kHello: {
      Hello m;
      if (!DecodeHello(payload, &m, &err)) return;
      if (m.magic != kMagic || m.version != kVersion) return;  // read leniently
      EncodeHello(m, &again);
      Require(again.substr(kHeaderSize) == payload);
      return;
    }
    case Msg::kScene: {
      SceneSetup m;
      if (!DecodeScene(payload, &m, &err)) return;
      EncodeScene(m, &again);
      SceneSetup m2;
      Require(DecodeScene(again.substr(kHeaderSize), &m2, &err));
      Require(again.substr(kHeaderSize) == payload);
      // A worker builds its mesh from what it was sent (small scenes only:
      // a face spanning the bounding box makes 16 x 16 patches).
      if (m.scene.faces.size() <= 16 && m.mesh.elements_per_patch <= 4 &&
          (m.mesh.patch_size == 0 || m.mesh.patch_size > 1e-3 * glm::length(m.scene.hi - m.scene.lo))) {
        Mesh mesh;
        BuildMesh(m.scene, m.mesh, &mesh, &err);
      }
      return;
    }
    case Msg::kReady: {
      Ready m;
      if (!DecodeReady(payload, &m, &err)) return;
      EncodeReady(m, &again);
      Require(again.substr(kHeaderSize) == payload);
      return;
    }
    case Msg::kWork: {
      std::vector<Assignment> m;
      if (!DecodeWork(payload, &m, &err)) return;
      EncodeWork(m, &again);
      Require(again.substr(kHeaderSize) == payload);
      return;
    }
    case Msg::kColumn: {
      Column m;
      if (!DecodeColumn(payload, &m, &err)) return;
      for (size_t i = 0; i < m.ff.size(); ++i)
        Require(m.ff[i].f > 0 && (i == 0 || m.ff[i].elem > m.ff[i - 1].elem));
      EncodeColumn(m, &again);
      Column m2;
      Require(DecodeColumn(again.substr(kHeaderSize), &m2, &err));
      Require(m2.patch == m.patch && m2.k == m.k && m2.ff.size() == m.ff.size());
      for (size_t i = 0; i < m.ff.size(); ++i) Require(m2.ff[i].elem == m.ff[i].elem);
      return;
    }
    case Msg::kDivide: {
      std::vector<int32_t> m;
      if (!DecodeDivide(payload, &m, &err)) return;
      EncodeDivide(m, &again);
      Require(again.substr(kHeaderSize) == payload);
      return;
    }
    case Msg::kError: {
      std::string text;
      if (!DecodeError(payload, &text, &err)) return;
      EncodeError(text, &again);
      Require(again.substr(kHeaderSize) == payload);
      return;
    }
    case Msg::kHeartbeat:
    case Msg::kBye:
      if (framed) Require(payload.empty());  // FrameReader's limit for these is 0
      return;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  if (data[0] & 1) {
    const std::string payload(reinterpret_cast<const char*>(data + 1), size - 1);
    Decode(Msg(1 + (data[0] >> 1) % 9), payload, false);
    return 0;
  }
  FrameReader reader;
  uint32_t rng = data[1] * 2654435761u + 1;
  size_t pos = 2;
  Msg type;
  std::string payload, err;
  while (pos < size) {
    rng = rng * 1664525u + 1013904223u;
    const size_t n = std::min(size - pos, size_t(1 + (rng >> 24) % 64));
    reader.Append(reinterpret_cast<const char*>(data + pos), n);
    pos += n;
    for (;;) {
      const FrameReader::Result r = reader.Next(&type, &payload, &err);
      if (r == FrameReader::kNeedMore) break;
      if (r == FrameReader::kBad) {
        Require(!err.empty());
        return 0;
      }
      Decode(type, payload, true);
    }
  }
  return 0;
}
