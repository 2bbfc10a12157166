// The wire protocol between master and workers: framing and message
// codecs (the bytes coded by coding.h, the form factors by ffcodec.h).
// doc/protocol.txt describes every byte; this file is its code.
//
// A frame is an 8-byte header (u32 length of the payload, u8 type, three
// zero bytes) followed by the payload; all integers little-endian. A frame
// longer than kMaxFrame, of an unknown type or with a payload that does not
// decode exactly (too short, bytes left over, out-of-range values) is an
// error of that connection: the decoders return false with a message and
// the caller closes the connection, never the program.
#ifndef RADIOSITY_PROTOCOL_H
#define RADIOSITY_PROTOCOL_H

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hemicube.h"
#include "mesh.h"
#include "scene.h"
#include "version.h"

namespace proto {

constexpr uint32_t kMagic = 0x57444152;  // "RADW" on the wire
constexpr size_t kHeaderSize = 8;
constexpr uint32_t kMaxFrame = 256u << 20;  // the scene frame is the largest

enum class Msg : uint8_t {
  kHello = 1,      // both ways, first frame
  kScene = 2,      // master -> worker, once
  kReady = 3,      // worker -> master: mesh built
  kWork = 4,       // master -> worker: patches to compute
  kColumn = 5,     // worker -> master: one form-factor column
  kDivide = 6,     // master -> worker: hierarchy edits (divisions, splits)
  kHeartbeat = 7,  // both ways, when nothing else was sent for a while
  kError = 8,      // both ways: a one-line reason, then the sender closes
  kBye = 9,        // master -> worker: exit now
};
const char* MsgName(Msg m);

struct Hello {
  uint32_t magic = kMagic;
  uint16_t version = kVersion;
  std::string build = BuildId();  // both ends must agree
};

// What a worker needs to build the master's mesh bit for bit and to
// compute columns like the master would. Not the shooter groups: those
// come with the work (Assignment), and a decoded setup has
// mesh.groups false.
struct SceneSetup {
  Scene scene;          // faces (verts, material, index), materials (kd,
                        // ke), lo, hi; names are not sent. Each face's
                        // normal and area must be FacePlane's (LoadScene
                        // gives them so): the worker computes them again.
  MeshOptions mesh;
  int32_t resolution = 256;
  uint8_t rotate = 1;
  uint32_t seed = 1;
  // The worker sends a heartbeat after this much silence (the master's
  // PoolOptions::heartbeat_s), in (0, kMaxHeartbeat] seconds.
  double heartbeat_s = 1.0;
};
constexpr double kMaxHeartbeat = 3600;

struct Ready {
  uint64_t elements = 0;  // elements in the worker's mesh
  uint64_t mesh_hash = 0; // MeshHash() of it: must equal the master's
};

struct Assignment {
  int32_t patch;
  int32_t k;  // this is the patch's k-th shot: the hemicube angle
  // The shooter group patch is the first member of (groups.h), or no
  // members when it shoots alone: the master forms the groups and sends
  // each with its shooter's work, so that a worker need not (their search
  // was its memory peak). Only members (members[0] == patch, increasing,
  // 2..kMaxGroup), center and normal travel; area is not sent.
  PatchGroup group = {};
  // The group, or null when patch shoots alone: what ShotColumn takes.
  const PatchGroup* Group() const { return group.members.empty() ? nullptr : &group; }
};

struct Column {
  int32_t patch = 0;
  int32_t k = 0;
  double compute_s = 0;  // worker CPU seconds for this column
  double wait_s = 0;     // seconds it waited in the worker before that:
                         // the master subtracts both from the round trip
  std::vector<FormFactor> ff;  // increasing elem, f > 0
};

// A frame by hand: BeginFrame appends a header of length 0 and returns
// where it starts, EndFrame fills in the length of what followed.
size_t BeginFrame(Msg type, std::string* out);
void EndFrame(size_t start, std::string* out);

// Appends a whole frame (header and payload) to *out.
void EncodeHello(const Hello& m, std::string* out);
void EncodeScene(const SceneSetup& m, std::string* out);
// The scene frame's bounding box and materials, laid out alike since
// version 1; checkpoints hash them (SceneHash) with version 1's faces.
void PutBoxAndMaterials(const Scene& scene, std::string* out);
void EncodeReady(const Ready& m, std::string* out);
void EncodeWork(const std::vector<Assignment>& m, std::string* out);
// The column's form factors as ffcodec.h codes them.
void EncodeColumn(const Column& m, std::string* out);
// The same frame from form factors coded already (PutFormFactors' bytes,
// in place of m.ff): a worker that sends one column many times
// (bench/feed.cpp) codes it once.
void EncodeColumn(const Column& m, std::string_view coded_ff, std::string* out);
// Edits in the order made: e >= 0 divides element e, ~p splits patch p.
void EncodeDivide(const std::vector<int32_t>& elems, std::string* out);
void EncodeHeartbeat(std::string* out);
void EncodeError(const std::string& text, std::string* out);
void EncodeBye(std::string* out);

// Payload decoders: the payload of one frame of the matching type. False
// with *err (one line, no prefix) when it does not decode exactly.
bool DecodeHello(std::string_view payload, Hello* m, std::string* err);
bool DecodeScene(std::string_view payload, SceneSetup* m, std::string* err);
bool DecodeReady(std::string_view payload, Ready* m, std::string* err);
bool DecodeWork(std::string_view payload, std::vector<Assignment>* m, std::string* err);
// DecodeColumn writes into *m as it reads, reusing m->ff's storage (the
// master's hot path); on false *m is partly written.
bool DecodeColumn(std::string_view payload, Column* m, std::string* err);
bool DecodeDivide(std::string_view payload, std::vector<int32_t>* m, std::string* err);
bool DecodeError(std::string_view payload, std::string* text, std::string* err);

// Splits a byte stream into frames. Feed it what read() returned; Next()
// hands out whole frames in order.
class FrameReader {
 public:
  void Append(const char* data, size_t n);
  enum Result { kFrame, kNeedMore, kBad };
  // kFrame: *type and *payload set. kBad: *err says why; the stream is
  // then unusable (no resynchronisation: the connection must be closed).
  Result Next(Msg* type, std::string* payload, std::string* err);
  // The same, the payload handed out as a view of the reader's buffer
  // (valid until the next Append or Next): the master's columns are
  // decoded from there without a copy of each (a column of 10^4 form
  // factors is 20 to 30 KB).
  Result Next(Msg* type, std::string_view* payload, std::string* err);
  size_t buffered() const { return buf_.size() - pos_; }
  // Bytes the reader's buffer holds, read or not (given back once a large
  // frame has been copied out).
  size_t held() const { return buf_.capacity(); }

 private:
  void Compact();
  std::string buf_;
  size_t pos_ = 0;
  bool bad_ = false;
};

}  // namespace proto

#endif
