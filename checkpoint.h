// Checkpoints (--checkpoint FILE, --resume FILE): the state of a run,
// written atomically (FILE.tmp, fsync, rename) so that a run killed at any
// moment leaves the previous checkpoint or the new one, never half of one.
// A resumed run loads the scene from its command line as usual, checks it
// against the checkpoint, replays the divisions, restores the rest and goes
// on; with -j 0 it then makes the same shots as the run it continues, bit
// for bit.
//
// File format, version 4; integers little-endian, f64 IEEE 754 bits:
//
//   offset  size  field
//   0       8     magic "RADCKPT\n"
//   8       4     u32 version (4)
//   12      4     u32 reserved, 0
//   16      8     u64 N: payload length
//   24      N     payload
//   24+N    32    SHA-256 of bytes [0, 24+N)
//
// Payload, in this order (u8/u32/i32/i64/u64/f64 fixed width; vec = 3 f64;
// ARRAY<T> = u64 count, then count T):
//
//   scene     32 bytes SHA-256 of the scene as protocol 1 sent it to
//             workers (faces, materials, bounding box: SceneHash), u64 MeshHash and u64
//             element count of the mesh as built, u64 MeshHash, u64
//             element count and u64 patch count of the mesh as saved
//   options   what shapes the answer (SolveOptions, in field order): u8
//             overshoot, i32 resolution, u8 rotate, u32 seed, i64
//             log_every, i32 elements per patch, f64 patch size, u8
//             groups, f64 group size, u8 subdivide, f64 threshold, f64 floor, f64 decay, f64
//             min_size, i32 max_level, u8 waves, f64 wave_fraction,
//             i64 between, f64 quiet, u8 split, f64 split_threshold,
//             f64 split_floor, f64 split_near
//   edits     ARRAY<i32>: the elements divided, in the order Divide() ran,
//             then ~p for each patch p split, in the order SplitPatch() ran
//   solver    i64 shots, vec unshot_sum, f64 abs_sum, ARRAY<vec> B per
//             element, ARRAY<vec> unshot per patch, ARRAY<u8> lit,
//             ARRAY<u8> blind, ARRAY<i32> times shot, ARRAY<f64> noise
//             per element (empty when the run does not divide), ARRAY<f32>
//             direct light per element (empty when it does not split)
//   subdiv    u8 present; if 1: f64 threshold, i64 last_pass, i64
//             wave_start_leaves, i64 divided_in_wave, u8 finished, u8
//             quiet, i64 passes, f64 seconds, f64 split_threshold, i64
//             splits, u8 measured, f64 direct_mean, ARRAY<f64> spread
//             per patch, ARRAY<u8> near per patch (shooter division's
//             measurements; format 5)
//   run       i32 wave, i64 wave_start, f64 best, i64 best_at, f64
//             seconds, i64 columns, ARRAY<i32> pending patches
//   log       ARRAY<u8>: log.csv's rows so far, without the header
//
// The stop rules (-e, -s, -t) and everything about output and workers come
// from the resuming command line; the options above must be given alike.
#ifndef RADIOSITY_CHECKPOINT_H
#define RADIOSITY_CHECKPOINT_H

#include <cstdint>
#include <string>
#include <vector>

#include "scheduler.h"
#include "solver.h"
#include "mesh.h"
#include "scene.h"
#include "subdivide.h"

constexpr uint32_t kCheckpointVersion = 5;

// The options that shape the answer: a checkpoint is resumed only with
// the same ones.
struct SolveOptions {
  bool overshoot = true;
  int32_t resolution = 256;
  bool rotate = true;
  uint32_t seed = 1;
  long log_every = 0;
  MeshOptions mesh;
  bool subdivide = true;
  SubdivideOptions sub;
};

struct Checkpoint {
  std::string scene_hash;  // SceneHash(): 32 bytes
  uint64_t base_hash = 0, base_elements = 0;  // MeshHash of the mesh as built
  uint64_t mesh_hash = 0, elements = 0, patches = 0;  // and as saved
  SolveOptions options;
  std::vector<int32_t> edits;
  SolverState solver;
  bool has_subdivider = false;
  SubdividerState subdivider;
  RunState run;
  std::string log;  // log.csv rows (LogCsv::text())
};

// SHA-256 of what identifies a scene's answer: its faces (vertices,
// normals, areas, materials, indices), its materials and bounding box, as
// the scene frame of protocol version 1 encodes them with the default
// options (fixed with this format, whatever the protocol becomes).
std::string SceneHash(const Scene& scene);

// The elements of `mesh` that Divide() divided, in the order it ran (a
// child block's position in Mesh::elems gives it away), then ~p for the
// patches split (Mesh::splits): replayed on the mesh as built they give
// this mesh again (divisions and splits commute, mesh.h).
std::vector<int32_t> DivideHistory(const Mesh& mesh);

// Divide() for each edit e >= 0, SplitPatch(~e) for each e < 0, each
// checked first (a leaf, a patch that can be split); false with *err at
// the first that is not.
bool ReplayDivisions(Mesh* mesh, const std::vector<int32_t>& edits, std::string* err);

// What a checkpoint is checked against: the scene, the mesh as BuildMesh
// made it, the options.
struct RunIdentity {
  std::string scene_hash;
  uint64_t base_hash = 0, base_elements = 0;
  SolveOptions options;
};
RunIdentity Identify(const Scene& scene, const Mesh& built, const SolveOptions& options);

// The run as it stands (sub may be null: no subdivision).
Checkpoint Capture(const RunIdentity& id, const Mesh& mesh, const Solver& solver,
                   const Subdivider* sub, const RunState& run, const std::string& log);

// Whether `c` continues a run of this scene, mesh and options: false with
// *err (one line, no file name) when it does not.
bool CheckIdentity(const Checkpoint& c, const RunIdentity& id, std::string* err);

// Replays the divisions on the mesh as built (checking that the result is
// the mesh saved) and restores the solver and the subdivider (null when
// not dividing). The run's state is c.run (RunOptions::resume).
bool ApplyCheckpoint(const Checkpoint& c, Mesh* mesh, Solver* solver, Subdivider* sub,
                     std::string* err);

// The whole file, checksum included.
std::string EncodeCheckpoint(const Checkpoint& c);
// False with *err (no file name) when `bytes` is not a checkpoint, is
// of another version, is truncated or fails its checksum.
bool DecodeCheckpoint(const std::string& bytes, Checkpoint* c, std::string* err);

// Writes PATH.tmp, syncs it and renames it to PATH. *bytes: the size.
bool WriteCheckpoint(const std::string& path, const Checkpoint& c, size_t* bytes,
                     std::string* err);
// False with *err = "PATH: what" (cannot read it, or DecodeCheckpoint's).
bool ReadCheckpoint(const std::string& path, Checkpoint* c, std::string* err);

// "" when `a` (the checkpoint's) and `b` (this run's) agree, else the
// first difference as "--resolution 128 (this run: 256)".
std::string CompareOptions(const SolveOptions& a, const SolveOptions& b);

#endif
