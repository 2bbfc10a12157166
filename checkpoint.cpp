#include "checkpoint.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "coding.h"
#include "crypto.h"
#include "files.h"
#include "protocol.h"

namespace {

constexpr char kMagic[8] = {'R', 'A', 'D', 'C', 'K', 'P', 'T', '\n'};
constexpr size_t kHeader = 24, kSum = 32;

// Reads in the order of the format, each value 0 after a short read: the
// reader stays failed, and DecodeCheckpoint checks it once at the end.
class In {
 public:
  In(const char* p, size_t n) : r_(p, n, &err_) {}
  bool ok() const { return r_.ok(); }
  size_t left() const { return r_.left(); }
  uint64_t U64() { return Get(8); }
  uint8_t U8() { return uint8_t(Get(1)); }
  bool Bool() {
    const uint64_t v = Get(1);
    bad_flag_ |= v > 1;
    return v != 0;
  }
  bool bad_flag() const { return bad_flag_; }
  uint32_t U32() { return uint32_t(Get(4)); }
  int32_t I32() { return int32_t(uint32_t(Get(4))); }
  int64_t I64() { return int64_t(Get(8)); }
  float F32() {
    const uint32_t bits = U32();
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
  }
  double F64() {
    double d = 0;
    r_.F64(&d, "f64");
    return d;
  }
  glm::dvec3 Vec() {
    glm::dvec3 v(0);
    r_.Vec(&v, "vec");
    return v;
  }
  // An ARRAY's count: no more items than the rest could hold.
  size_t Count(size_t item_bytes) {
    uint64_t n = 0;
    r_.Count64(item_bytes, &n, "count");
    return size_t(n);
  }
  std::string Bytes(size_t n) {
    std::string s;
    r_.Bytes(n, &s, "bytes");
    return s;
  }

 private:
  uint64_t Get(int bytes) {
    uint64_t v = 0;
    r_.Fixed(bytes, &v, "integer");
    return v;
  }
  std::string err_;  // unused: a failure is reported as one
  Reader r_;
  bool bad_flag_ = false;  // a u8 flag that is neither 0 nor 1
};

void PutOptions(std::string* w, const SolveOptions& o) {
  PutU8(w, o.overshoot);
  PutFixed32(w, o.resolution);
  PutU8(w, o.rotate);
  PutFixed32(w, o.seed);
  PutFixed64(w, o.log_every);
  PutFixed32(w, o.mesh.elements_per_patch);
  PutF64(w, o.mesh.patch_size);
  PutU8(w, o.mesh.groups);
  PutF64(w, o.mesh.group_size);
  PutU8(w, o.subdivide);
  PutF64(w, o.sub.threshold);
  PutF64(w, o.sub.floor);
  PutF64(w, o.sub.decay);
  PutF64(w, o.sub.min_size);
  PutFixed32(w, o.sub.max_level);
  PutU8(w, o.sub.waves);
  PutF64(w, o.sub.wave_fraction);
  PutFixed64(w, o.sub.between);
  PutF64(w, o.sub.quiet);
  PutU8(w, o.sub.split);
  PutF64(w, o.sub.split_threshold);
  PutF64(w, o.sub.split_floor);
  PutF64(w, o.sub.split_near);
}

SolveOptions GetOptions(In* r) {
  SolveOptions o;
  o.overshoot = r->Bool();
  o.resolution = r->I32();
  o.rotate = r->Bool();
  o.seed = r->U32();
  o.log_every = long(r->I64());
  o.mesh.elements_per_patch = r->I32();
  o.mesh.patch_size = r->F64();
  o.mesh.groups = r->Bool();
  o.mesh.group_size = r->F64();
  o.subdivide = r->Bool();
  o.sub.threshold = r->F64();
  o.sub.floor = r->F64();
  o.sub.decay = r->F64();
  o.sub.min_size = r->F64();
  o.sub.max_level = r->I32();
  o.sub.waves = r->Bool();
  o.sub.wave_fraction = r->F64();
  o.sub.between = long(r->I64());
  o.sub.quiet = r->F64();
  o.sub.split = r->Bool();
  o.sub.split_threshold = r->F64();
  o.sub.split_floor = r->F64();
  o.sub.split_near = r->F64();
  return o;
}

template <typename T, typename Put>
void PutArray(std::string* w, const std::vector<T>& v, Put put) {
  PutFixed64(w, v.size());
  for (const T& x : v) put(x);
}

// A value that no run writes: "" when there is none, else which. Run once
// the checksum holds (an edited file re-hashed, or a writer's bug): NaN in
// the radiosity would otherwise end as nan in result.csv.
std::string Implausible(const Checkpoint& k) {
  auto finite = [](const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
  };
  const SolverState& s = k.solver;
  if (k.elements > uint64_t(kMaxElements) || k.base_elements > k.elements ||
      k.patches > k.elements || k.edits.size() > k.elements + k.patches)
    return "element and patch counts out of range";
  if (s.b.size() != k.elements || s.unshot.size() != k.patches || s.lit.size() != k.patches ||
      s.blind.size() != k.patches || s.times_shot.size() != k.patches)
    return "solver arrays do not match the element and patch counts";
  for (const glm::dvec3& v : s.b)
    if (!finite(v)) return "a radiosity that is not a finite number";
  for (const glm::dvec3& v : s.unshot)
    if (!finite(v)) return "an unshot radiosity that is not a finite number";
  if (!s.noise.empty() && s.noise.size() != k.elements)
    return "the noise array does not match the element count";
  for (double x : s.noise)
    if (!(x >= 0) || !std::isfinite(x)) return "a noise variance that is not a finite number >= 0";
  if (!s.direct.empty() && s.direct.size() != k.elements)
    return "the direct light array does not match the element count";
  for (float x : s.direct)
    if (!(x >= 0) || !std::isfinite(x)) return "a direct light that is not a finite number >= 0";
  if (!finite(s.unshot_sum) || !std::isfinite(s.abs_sum)) return "unshot sums not finite";
  if (s.shots < 0) return "a negative shot count";
  for (size_t p = 0; p < k.patches; ++p)
    if (s.lit[p] > 1 || s.blind[p] > 1 || s.times_shot[p] < 0 || s.times_shot[p] > s.shots)
      return "patch " + std::to_string(p) + "'s flags or shot count out of range";
  const RunState& r = k.run;
  if (r.wave < 1 || r.wave_start < 0 || r.wave_start > s.shots || r.best_at < 0 ||
      r.best_at > s.shots || std::isnan(r.best) || r.best < 0 || !std::isfinite(r.seconds) ||
      r.seconds < 0 || r.columns < 0)
    return "run state out of range";
  std::vector<bool> seen(k.patches);
  for (int32_t p : r.pending) {
    if (p < 0 || uint64_t(p) >= k.patches || seen[size_t(p)])
      return "pending patch " + std::to_string(p) + " out of range or listed twice";
    seen[size_t(p)] = true;
  }
  if (k.has_subdivider) {
    const SubdividerState& d = k.subdivider;
    if (!std::isfinite(d.threshold) || d.threshold <= 0 || d.last_pass < -1 ||
        d.last_pass > s.shots || d.wave_start_leaves < 0 || d.divided_in_wave < 0 ||
        d.passes < 0 || !std::isfinite(d.seconds) || d.seconds < 0 ||
        !std::isfinite(d.split_threshold) || d.split_threshold <= 0 || d.splits < 0 ||
        !std::isfinite(d.direct_mean) || d.direct_mean < 0 || d.spread.size() > k.patches ||
        d.near.size() > k.patches ||
        std::any_of(d.spread.begin(), d.spread.end(), [](double x) { return !(x >= 0 && x < HUGE_VAL); }))
      return "subdivision state out of range";
  }
  // log.csv's rows as LogCsv writes them: numbers, commas, newlines
  if (k.log.find_first_not_of("0123456789.,-+eEinfa\n") != std::string::npos)
    return "log rows that are not numbers";
  return "";
}

}  // namespace

namespace {

// The scene as protocol 1 to 3 sent it (doc/protocol.txt before version
// 4): bounding box, materials, then every face with its own vertices,
// normal and area. SceneHash is defined on these bytes, so they stay.
void PutSceneV1(const Scene& scene, std::string* out) {
  proto::PutBoxAndMaterials(scene, out);
  PutVarint(out, scene.faces.size());
  for (const Face& f : scene.faces) {
    PutVarint(out, uint32_t(f.material));
    PutVarint(out, uint32_t(f.index));
    PutVarint(out, f.verts.size());
    PutVec(out, f.normal);
    PutF64(out, f.area);
    for (const auto& v : f.verts) PutVec(out, v);
  }
}

}  // namespace

std::string SceneHash(const Scene& scene) {
  // Format 1 defines it as the SHA-256 of protocol 1's scene frame for the
  // default options: only the scene varies (the options are compared on
  // their own, CompareOptions), and the frame's later fields do not enter.
  std::string frame;
  const size_t start = proto::BeginFrame(proto::Msg::kScene, &frame);
  PutU8(&frame, 1);        // rotate
  PutVarint(&frame, 256);  // resolution
  PutFixed32(&frame, 1);   // seed
  PutVarint(&frame, 2);    // elements per patch
  PutF64(&frame, 0);       // patch size
  PutSceneV1(scene, &frame);
  proto::EndFrame(start, &frame);
  return Sha256Of(frame);
}

std::vector<int32_t> DivideHistory(const Mesh& mesh) {
  std::vector<int32_t> edits;
  for (size_t e = 0; e < mesh.elems.size(); ++e)
    if (!mesh.elems[e].IsLeaf()) edits.push_back(int32_t(e));
  std::sort(edits.begin(), edits.end(), [&](int32_t a, int32_t b) {
    return mesh.elems[a].first_child < mesh.elems[b].first_child;
  });
  // Then the splits in their order: they commute with divisions (mesh.h).
  for (int32_t p : mesh.splits) edits.push_back(~p);
  return edits;
}

bool ReplayDivisions(Mesh* mesh, const std::vector<int32_t>& edits, std::string* err) {
  for (size_t i = 0; i < edits.size(); ++i) {
    const int32_t e = edits[i];
    if (e < 0) {
      if (SplitPieces(*mesh, ~e) < 2) {
        *err = "edit " + std::to_string(i + 1) + " of " + std::to_string(edits.size()) +
               " splits patch " + std::to_string(~e) + ", which cannot be split";
        return false;
      }
      SplitPatch(mesh, ~e);
      continue;
    }
    if (size_t(e) >= mesh->elems.size() || !mesh->elems[e].IsLeaf()) {
      *err = "division " + std::to_string(i + 1) + " of " + std::to_string(edits.size()) +
             " names element " + std::to_string(e) + ", which is not a leaf of the mesh";
      return false;
    }
    Divide(mesh, e);
  }
  return true;
}

RunIdentity Identify(const Scene& scene, const Mesh& built, const SolveOptions& options) {
  RunIdentity id;
  id.scene_hash = SceneHash(scene);
  id.base_hash = MeshHash(built);
  id.base_elements = built.elems.size();
  id.options = options;
  return id;
}

Checkpoint Capture(const RunIdentity& id, const Mesh& mesh, const Solver& solver,
                   const Subdivider* sub, const RunState& run, const std::string& log) {
  Checkpoint c;
  c.scene_hash = id.scene_hash;
  c.base_hash = id.base_hash;
  c.base_elements = id.base_elements;
  c.mesh_hash = MeshHash(mesh);
  c.elements = mesh.elems.size();
  c.patches = mesh.patches.size();
  c.options = id.options;
  c.edits = DivideHistory(mesh);
  c.solver = solver.State();
  c.has_subdivider = sub != nullptr;
  if (sub) c.subdivider = sub->State();
  c.run = run;
  c.log = log;
  return c;
}

bool CheckIdentity(const Checkpoint& c, const RunIdentity& id, std::string* err) {
  if (c.scene_hash != id.scene_hash) {
    *err = "a checkpoint of another scene (its faces or materials differ)";
    return false;
  }
  const std::string differ = CompareOptions(c.options, id.options);
  if (!differ.empty()) {
    *err = "made with other options: " + differ + "; resume with the options of that run";
    return false;
  }
  if (c.base_hash != id.base_hash || c.base_elements != id.base_elements) {
    *err = "made by a build or with a --no-join that meshes this scene differently (" +
           std::to_string(c.base_elements) + " elements, this one " +
           std::to_string(id.base_elements) + ")";
    return false;
  }
  if (c.has_subdivider != id.options.subdivide) {
    *err = "corrupt: subdivision state does not match its options";
    return false;
  }
  return true;
}

bool ApplyCheckpoint(const Checkpoint& c, Mesh* mesh, Solver* solver, Subdivider* sub,
                     std::string* err) {
  if (!ReplayDivisions(mesh, c.edits, err)) return false;
  if (MeshHash(*mesh) != c.mesh_hash || mesh->elems.size() != c.elements ||
      mesh->patches.size() != c.patches) {
    *err = "its " + std::to_string(c.edits.size()) +
           " divisions do not give the mesh it was made with";
    return false;
  }
  if (!solver->Restore(c.solver, err)) return false;
  if (sub) sub->Restore(c.subdivider);
  return true;
}

std::string EncodeCheckpoint(const Checkpoint& c) {
  std::string w(kMagic, 8);
  PutFixed32(&w, kCheckpointVersion);
  PutFixed32(&w, 0);
  PutFixed64(&w, 0);  // payload length, filled in below
  w += c.scene_hash;
  PutFixed64(&w, c.base_hash);
  PutFixed64(&w, c.base_elements);
  PutFixed64(&w, c.mesh_hash);
  PutFixed64(&w, c.elements);
  PutFixed64(&w, c.patches);
  PutOptions(&w, c.options);
  PutArray(&w, c.edits, [&](int32_t e) { PutFixed32(&w, e); });
  const SolverState& s = c.solver;
  PutFixed64(&w, s.shots);
  PutVec(&w, s.unshot_sum);
  PutF64(&w, s.abs_sum);
  PutArray(&w, s.b, [&](const glm::dvec3& v) { PutVec(&w, v); });
  PutArray(&w, s.unshot, [&](const glm::dvec3& v) { PutVec(&w, v); });
  PutArray(&w, s.lit, [&](uint8_t x) { PutU8(&w, x); });
  PutArray(&w, s.blind, [&](uint8_t x) { PutU8(&w, x); });
  PutArray(&w, s.times_shot, [&](int32_t x) { PutFixed32(&w, x); });
  PutArray(&w, s.noise, [&](double x) { PutF64(&w, x); });
  PutArray(&w, s.direct, [&](float x) { PutF32(&w, x); });
  PutU8(&w, c.has_subdivider);
  if (c.has_subdivider) {
    const SubdividerState& d = c.subdivider;
    PutF64(&w, d.threshold);
    PutFixed64(&w, d.last_pass);
    PutFixed64(&w, d.wave_start_leaves);
    PutFixed64(&w, d.divided_in_wave);
    PutU8(&w, d.finished);
    PutU8(&w, d.quiet);
    PutFixed64(&w, d.passes);
    PutF64(&w, d.seconds);
    PutF64(&w, d.split_threshold);
    PutFixed64(&w, d.splits);
    PutU8(&w, d.measured);
    PutF64(&w, d.direct_mean);
    PutArray(&w, d.spread, [&](double x) { PutF64(&w, x); });
    PutArray(&w, d.near, [&](uint8_t x) { PutU8(&w, x); });
  }
  const RunState& r = c.run;
  PutFixed32(&w, r.wave);
  PutFixed64(&w, r.wave_start);
  PutF64(&w, r.best);
  PutFixed64(&w, r.best_at);
  PutF64(&w, r.seconds);
  PutFixed64(&w, r.columns);
  PutArray(&w, r.pending, [&](int32_t p) { PutFixed32(&w, p); });
  PutFixed64(&w, c.log.size());
  w += c.log;
  EncodeFixed64(&w[16], w.size() - kHeader);
  w += Sha256Of(w);
  return w;
}

bool DecodeCheckpoint(const std::string& bytes, Checkpoint* c, std::string* err) {
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 8) != 0) {
    *err = "not a radiosity checkpoint (no RADCKPT magic)";
    return false;
  }
  In h(bytes.data(), bytes.size());
  h.Bytes(8);
  const uint32_t version = h.U32(), reserved = h.U32();
  const uint64_t n = h.U64();
  if (!h.ok()) {
    *err = "truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the header";
    return false;
  }
  if (version != kCheckpointVersion || reserved != 0) {
    *err = "checkpoint format version " + std::to_string(version) + ", this radiosity reads " +
           std::to_string(kCheckpointVersion);
    return false;
  }
  if (n > bytes.size() || bytes.size() - kHeader - std::min(n, bytes.size() - kHeader) < kSum ||
      bytes.size() != kHeader + n + kSum) {
    const std::string want = n > UINT64_MAX - kHeader - kSum ? "more" : std::to_string(kHeader + n + kSum);
    *err = (bytes.size() < kHeader + n + kSum || n > bytes.size() ? "truncated: "
                                                                  : "bytes after the end: ") +
           std::to_string(bytes.size()) + " bytes, the header says " + want;
    return false;
  }
  if (Sha256Of(bytes.substr(0, kHeader + n)) != bytes.substr(kHeader + n)) {
    *err = "corrupt: the SHA-256 checksum does not match";
    return false;
  }
  In r(bytes.data() + kHeader, size_t(n));
  Checkpoint k;
  k.scene_hash = r.Bytes(32);
  k.base_hash = r.U64();
  k.base_elements = r.U64();
  k.mesh_hash = r.U64();
  k.elements = r.U64();
  k.patches = r.U64();
  k.options = GetOptions(&r);
  k.edits.resize(r.Count(4));
  for (int32_t& e : k.edits) e = r.I32();
  SolverState& s = k.solver;
  s.shots = long(r.I64());
  s.unshot_sum = r.Vec();
  s.abs_sum = r.F64();
  s.b.resize(r.Count(24));
  for (glm::dvec3& v : s.b) v = r.Vec();
  s.unshot.resize(r.Count(24));
  for (glm::dvec3& v : s.unshot) v = r.Vec();
  s.lit.resize(r.Count(1));
  for (uint8_t& x : s.lit) x = r.U8();
  s.blind.resize(r.Count(1));
  for (uint8_t& x : s.blind) x = r.U8();
  s.times_shot.resize(r.Count(4));
  for (int32_t& x : s.times_shot) x = r.I32();
  s.noise.resize(r.Count(8));
  for (double& x : s.noise) x = r.F64();
  s.direct.resize(r.Count(4));
  for (float& x : s.direct) x = r.F32();
  k.has_subdivider = r.Bool();
  if (k.has_subdivider) {
    SubdividerState& d = k.subdivider;
    d.threshold = r.F64();
    d.last_pass = long(r.I64());
    d.wave_start_leaves = long(r.I64());
    d.divided_in_wave = long(r.I64());
    d.finished = r.Bool();
    d.quiet = r.Bool();
    d.passes = long(r.I64());
    d.seconds = r.F64();
    d.split_threshold = r.F64();
    d.splits = long(r.I64());
    d.measured = r.Bool();
    d.direct_mean = r.F64();
    d.spread.resize(r.Count(8));
    for (double& x : d.spread) x = r.F64();
    d.near.resize(r.Count(1));
    for (uint8_t& x : d.near) x = r.Bool();
  }
  RunState& run = k.run;
  run.wave = r.I32();
  run.wave_start = long(r.I64());
  run.best = r.F64();
  run.best_at = long(r.I64());
  run.seconds = r.F64();
  run.columns = long(r.I64());
  run.pending.resize(r.Count(4));
  for (int32_t& p : run.pending) p = r.I32();
  k.log = r.Bytes(r.Count(1));
  // The checksum held, so this is a writer's bug or a forgery: say so.
  if (!r.ok() || r.left() != 0) {
    *err = "corrupt: the payload does not decode (" + std::to_string(r.left()) + " bytes left)";
    return false;
  }
  const std::string implausible = r.bad_flag() ? "a flag that is neither 0 nor 1" : Implausible(k);
  if (!implausible.empty()) {
    *err = "corrupt: " + implausible + " (the checksum holds: an edited file?)";
    return false;
  }
  *c = std::move(k);
  return true;
}

bool WriteCheckpoint(const std::string& path, const Checkpoint& c, size_t* bytes,
                     std::string* err) {
  // Synced before the rename: after a crash the name holds the old
  // checkpoint or the whole new one.
  const std::string data = EncodeCheckpoint(c);
  if (!WriteFileAtomic(path, data, err, true)) return false;
  *bytes = data.size();
  return true;
}

bool ReadCheckpoint(const std::string& path, Checkpoint* c, std::string* err) {
  std::string bytes;
  if (!ReadInput(path, kMaxCheckpointBytes, &bytes, err)) return false;
  if (!DecodeCheckpoint(bytes, c, err)) {
    *err = path + ": " + *err;
    return false;
  }
  return true;
}

std::string CompareOptions(const SolveOptions& a, const SolveOptions& b) {
  auto num = [](double x) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    return std::string(buf);
  };
  auto differ = [](const std::string& opt, const std::string& x, const std::string& y) {
    return opt + " " + x + " (this run: " + y + ")";
  };
  // An option without a value: given in one run, not in the other.
  auto flag = [](const std::string& opt, bool given_a, bool given_b) {
    return opt + (given_a ? " given" : " not given") + " (this run: " +
           (given_b ? "given" : "not given") + ")";
  };
  if (a.overshoot != b.overshoot) return flag("--no-overshoot", !a.overshoot, !b.overshoot);
  if (a.resolution != b.resolution)
    return differ("--resolution", std::to_string(a.resolution), std::to_string(b.resolution));
  if (a.rotate != b.rotate) return flag("--no-rotate", !a.rotate, !b.rotate);
  if (a.seed != b.seed) return differ("--seed", std::to_string(a.seed), std::to_string(b.seed));
  if (a.log_every != b.log_every)
    return differ("--log-every", a.log_every ? std::to_string(a.log_every) : "default",
                  b.log_every ? std::to_string(b.log_every) : "default");
  if (a.mesh.elements_per_patch != b.mesh.elements_per_patch)
    return differ("--elements", std::to_string(a.mesh.elements_per_patch),
                  std::to_string(b.mesh.elements_per_patch));
  if (a.mesh.patch_size != b.mesh.patch_size)
    return differ("--patch-size", a.mesh.patch_size ? num(a.mesh.patch_size) : "default",
                  b.mesh.patch_size ? num(b.mesh.patch_size) : "default");
  if (a.mesh.groups != b.mesh.groups) return flag("--no-groups", !a.mesh.groups, !b.mesh.groups);
  if (a.mesh.groups && a.mesh.group_size != b.mesh.group_size)
    return differ("--group-size", a.mesh.group_size ? num(a.mesh.group_size) : "default",
                  b.mesh.group_size ? num(b.mesh.group_size) : "default");
  if (a.subdivide != b.subdivide) return flag("--no-subdivide", !a.subdivide, !b.subdivide);
  if (!a.subdivide) return "";
  if (a.sub.floor != b.sub.floor) return differ("--subdivide-floor", num(a.sub.floor), num(b.sub.floor));
  if (a.sub.min_size != b.sub.min_size)
    return differ("--min-element", a.sub.min_size ? num(a.sub.min_size) : "default",
                  b.sub.min_size ? num(b.sub.min_size) : "default");
  if (a.sub.max_level != b.sub.max_level)
    return differ("--max-level", std::to_string(a.sub.max_level), std::to_string(b.sub.max_level));
  if (a.sub.waves != b.sub.waves) return flag("--no-waves", !a.sub.waves, !b.sub.waves);
  if (a.sub.wave_fraction != b.sub.wave_fraction)
    return differ("--wave-fraction", num(a.sub.wave_fraction), num(b.sub.wave_fraction));
  if (a.sub.split != b.sub.split) return flag("--split", a.sub.split, b.sub.split);
  if (a.sub.split && a.sub.split_floor != b.sub.split_floor)
    return differ("--split-floor", num(a.sub.split_floor), num(b.sub.split_floor));
  if (a.sub.split && a.sub.split_near != b.sub.split_near)
    return differ("--split-near", num(a.sub.split_near), num(b.sub.split_near));
  if (a.sub.split_threshold != b.sub.split_threshold || a.sub.threshold != b.sub.threshold ||
      a.sub.decay != b.sub.decay ||
      a.sub.between != b.sub.between || a.sub.quiet != b.sub.quiet)
    return "made by a build with other subdivision settings";
  return "";
}
