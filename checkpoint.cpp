#include "checkpoint.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <fcntl.h>
#include <unistd.h>

#include "crypto.h"
#include "net.h"

namespace {

constexpr char kMagic[8] = {'R', 'A', 'D', 'C', 'K', 'P', 'T', '\n'};
constexpr size_t kHeader = 24, kSum = 32;

class Writer {
 public:
  void LE(uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) s.push_back(char(v >> (8 * i)));
  }
  void U8(uint8_t v) { LE(v, 1); }
  void U32(uint32_t v) { LE(v, 4); }
  void I32(int32_t v) { LE(uint32_t(v), 4); }
  void I64(int64_t v) { LE(uint64_t(v), 8); }
  void F64(double d) {
    uint64_t b;
    std::memcpy(&b, &d, 8);
    LE(b, 8);
  }
  void Vec(const glm::dvec3& v) { F64(v.x), F64(v.y), F64(v.z); }
  std::string s;
};

// Reads what Writer wrote. A short read fails once and stays failed, so
// that a decoder can read on and check ok() at the end.
class Reader {
 public:
  Reader(const char* p, size_t n) : p_(reinterpret_cast<const uint8_t*>(p)), n_(n) {}
  bool ok() const { return ok_; }
  size_t left() const { return n_ - pos_; }
  uint64_t LE(int bytes) {
    if (!ok_ || left() < size_t(bytes)) {
      ok_ = false;
      return 0;
    }
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= uint64_t(p_[pos_ + i]) << (8 * i);
    pos_ += size_t(bytes);
    return v;
  }
  uint8_t U8() { return uint8_t(LE(1)); }
  bool Bool() { return LE(1) != 0; }
  uint32_t U32() { return uint32_t(LE(4)); }
  int32_t I32() { return int32_t(uint32_t(LE(4))); }
  int64_t I64() { return int64_t(LE(8)); }
  double F64() {
    uint64_t b = LE(8);
    double d;
    std::memcpy(&d, &b, 8);
    return d;
  }
  glm::dvec3 Vec() {
    glm::dvec3 v;
    v.x = F64(), v.y = F64(), v.z = F64();
    return v;
  }
  // An array count: no more items than the rest could hold, so that a bad
  // count never allocates much.
  size_t Count(size_t item_bytes) {
    const uint64_t n = LE(8);
    if (!ok_ || n > left() / item_bytes) {
      ok_ = false;
      return 0;
    }
    return size_t(n);
  }
  std::string Bytes(size_t n) {
    if (!ok_ || left() < n) {
      ok_ = false;
      return "";
    }
    std::string s(reinterpret_cast<const char*>(p_ + pos_), n);
    pos_ += n;
    return s;
  }

 private:
  const uint8_t* p_;
  size_t n_, pos_ = 0;
  bool ok_ = true;
};

void PutOptions(Writer* w, const SolveOptions& o) {
  w->U8(o.overshoot);
  w->I32(o.resolution);
  w->U8(o.rotate);
  w->U32(o.seed);
  w->I64(o.log_every);
  w->I32(o.mesh.elements_per_patch);
  w->F64(o.mesh.patch_size);
  w->U8(o.subdivide);
  w->F64(o.sub.threshold);
  w->F64(o.sub.floor);
  w->F64(o.sub.decay);
  w->F64(o.sub.min_size);
  w->I32(o.sub.max_level);
  w->U8(o.sub.waves);
  w->F64(o.sub.wave_fraction);
  w->I64(o.sub.between);
  w->F64(o.sub.quiet);
}

SolveOptions GetOptions(Reader* r) {
  SolveOptions o;
  o.overshoot = r->Bool();
  o.resolution = r->I32();
  o.rotate = r->Bool();
  o.seed = r->U32();
  o.log_every = long(r->I64());
  o.mesh.elements_per_patch = r->I32();
  o.mesh.patch_size = r->F64();
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
  return o;
}

template <typename T, typename Put>
void PutArray(Writer* w, const std::vector<T>& v, Put put) {
  w->LE(v.size(), 8);
  for (const T& x : v) put(x);
}

}  // namespace

std::string SceneHash(const Scene& scene) {
  // The frame of a setup whose options are the defaults: only the scene
  // varies (the options are compared on their own, CompareOptions).
  proto::SceneSetup setup;
  setup.scene = scene;
  std::string frame;
  proto::EncodeScene(setup, &frame);
  return Sha256Of(frame);
}

std::vector<int32_t> DivideHistory(const Mesh& mesh) {
  std::vector<int32_t> edits;
  for (size_t e = 0; e < mesh.elems.size(); ++e)
    if (!mesh.elems[e].IsLeaf()) edits.push_back(int32_t(e));
  std::sort(edits.begin(), edits.end(), [&](int32_t a, int32_t b) {
    return mesh.elems[a].first_child < mesh.elems[b].first_child;
  });
  return edits;
}

bool ReplayDivisions(Mesh* mesh, const std::vector<int32_t>& edits, std::string* err) {
  for (size_t i = 0; i < edits.size(); ++i) {
    const int32_t e = edits[i];
    if (e < 0 || size_t(e) >= mesh->elems.size() || !mesh->elems[e].IsLeaf()) {
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
  id.base_hash = proto::MeshHash(built);
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
  c.mesh_hash = proto::MeshHash(mesh);
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
    *err = "made by a build that meshes this scene differently (" +
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
  if (proto::MeshHash(*mesh) != c.mesh_hash || mesh->elems.size() != c.elements ||
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
  Writer w;
  w.s.append(kMagic, 8);
  w.U32(kCheckpointVersion);
  w.U32(0);
  w.LE(0, 8);  // payload length, filled in below
  w.s += c.scene_hash;
  w.LE(c.base_hash, 8);
  w.LE(c.base_elements, 8);
  w.LE(c.mesh_hash, 8);
  w.LE(c.elements, 8);
  w.LE(c.patches, 8);
  PutOptions(&w, c.options);
  PutArray(&w, c.edits, [&](int32_t e) { w.I32(e); });
  const SolverState& s = c.solver;
  w.I64(s.shots);
  w.Vec(s.unshot_sum);
  w.F64(s.abs_sum);
  PutArray(&w, s.b, [&](const glm::dvec3& v) { w.Vec(v); });
  PutArray(&w, s.unshot, [&](const glm::dvec3& v) { w.Vec(v); });
  PutArray(&w, s.lit, [&](uint8_t x) { w.U8(x); });
  PutArray(&w, s.blind, [&](uint8_t x) { w.U8(x); });
  PutArray(&w, s.times_shot, [&](int32_t x) { w.I32(x); });
  w.U8(c.has_subdivider);
  if (c.has_subdivider) {
    const SubdividerState& d = c.subdivider;
    w.F64(d.threshold);
    w.I64(d.last_pass);
    w.I64(d.wave_start_leaves);
    w.I64(d.divided_in_wave);
    w.U8(d.finished);
    w.U8(d.quiet);
    w.I64(d.passes);
    w.F64(d.seconds);
  }
  const RunState& r = c.run;
  w.I32(r.wave);
  w.I64(r.wave_start);
  w.F64(r.best);
  w.I64(r.best_at);
  w.F64(r.seconds);
  w.I64(r.columns);
  PutArray(&w, r.pending, [&](int32_t p) { w.I32(p); });
  w.LE(c.log.size(), 8);
  w.s += c.log;
  const uint64_t n = w.s.size() - kHeader;
  for (int i = 0; i < 8; ++i) w.s[16 + i] = char(n >> (8 * i));
  w.s += Sha256Of(w.s);
  return w.s;
}

bool DecodeCheckpoint(const std::string& bytes, Checkpoint* c, std::string* err) {
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 8) != 0) {
    *err = "not a radiosity checkpoint (no RADCKPT magic)";
    return false;
  }
  Reader h(bytes.data(), bytes.size());
  h.Bytes(8);
  const uint32_t version = h.U32(), reserved = h.U32();
  const uint64_t n = h.LE(8);
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
  Reader r(bytes.data() + kHeader, size_t(n));
  Checkpoint k;
  k.scene_hash = r.Bytes(32);
  k.base_hash = r.LE(8);
  k.base_elements = r.LE(8);
  k.mesh_hash = r.LE(8);
  k.elements = r.LE(8);
  k.patches = r.LE(8);
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
  *c = std::move(k);
  return true;
}

bool WriteCheckpoint(const std::string& path, const Checkpoint& c, size_t* bytes,
                     std::string* err) {
  const std::string data = EncodeCheckpoint(c), tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    *err = tmp + ": " + std::strerror(errno);
    return false;
  }
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      *err = tmp + ": " + std::strerror(n < 0 ? errno : EIO);
      ::close(fd);
      ::unlink(tmp.c_str());
      return false;
    }
    done += size_t(n);
  }
  // Synced before the rename: after a crash the name holds the old
  // checkpoint or the whole new one.
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    *err = tmp + ": " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return false;
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    *err = path + ": " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return false;
  }
  *bytes = data.size();
  return true;
}

bool ReadCheckpoint(const std::string& path, Checkpoint* c, std::string* err) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    *err = path + ": " + std::strerror(errno);
    return false;
  }
  std::string bytes;
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) bytes.append(buf, n);
  const bool failed = std::ferror(f);
  std::fclose(f);
  if (failed) {
    *err = path + ": cannot read: " + std::strerror(errno);
    return false;
  }
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
  if (a.sub.threshold != b.sub.threshold || a.sub.decay != b.sub.decay ||
      a.sub.between != b.sub.between || a.sub.quiet != b.sub.quiet)
    return "made by a build with other subdivision settings";
  return "";
}
