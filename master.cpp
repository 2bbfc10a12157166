#include "master.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <memory>

#include "check.h"
#include "transport.h"

namespace {
double Abs(const glm::dvec3& u) { return std::abs(u.r) + std::abs(u.g) + std::abs(u.b); }
}  // namespace

Solver::Solver(const Mesh& mesh, bool overshoot)
    : mesh_(mesh),
      overshoot_(overshoot),
      fsum_(mesh.patches.size(), 0.0),
      blind_(mesh.patches.size(), 0) {
  glm::dvec3 rho_area(0.0);
  for (size_t p = 0; p < mesh.patches.size(); ++p) {
    const MeshFace& f = mesh.faces[mesh.patches[p].face];
    const double a = mesh.patches[p].area;
    total_area_ += a;
    emitted_ += (f.emission.r + f.emission.g + f.emission.b) * a;
    rho_area += f.rho * a;
  }
  if (total_area_ > 0) {
    // Cohen et al.'s interreflection factor 1/(1−ρ̄). ρ̄ = 1 (a scene that
    // reflects everything) has no finite answer; the cap keeps the estimate
    // finite so that the run can find out and say so.
    glm::dvec3 mean = glm::min(rho_area / total_area_, glm::dvec3(1 - 1e-6));
    reflect_ = 1.0 / (1.0 - mean);
  }
  NewWave();
}

void Solver::NewWave() {
  Grow();
  for (size_t e = 0; e < b_.size(); ++e) b_[e] = mesh_.FaceOf(int(e)).emission;
  unshot_.resize(mesh_.patches.size());
  lit_.resize(mesh_.patches.size());
  for (size_t p = 0; p < unshot_.size(); ++p) {
    unshot_[p] = mesh_.faces[mesh_.patches[p].face].emission;
    lit_[p] = Abs(unshot_[p]) > 0;
  }
  times_shot_.assign(mesh_.patches.size(), 0);
  Resum();
}

// Per-element arrays for the elements Divide() has added; a divided
// element's patch is stored complemented so that Shoot tells it apart
// from a leaf without touching the Element.
void Solver::Grow() {
  const size_t from = patch_of_.size(), n = mesh_.elems.size();
  b_.resize(n);
  rho_per_area_.resize(n);
  patch_of_.resize(n);
  for (size_t e = 0; e < n; ++e) {
    const Element& el = mesh_.elems[e];
    if (e >= from) rho_per_area_[e] = mesh_.FaceOf(int(e)).rho / el.area;
    patch_of_[e] = el.IsLeaf() ? el.patch : ~el.patch;
  }
}

void Solver::Resum() {
  unshot_sum_ = glm::dvec3(0.0);
  abs_sum_ = 0;
  for (size_t p = 0; p < unshot_.size(); ++p) {
    unshot_sum_ += unshot_[p] * mesh_.patches[p].area;
    abs_sum_ += Abs(unshot_[p]) * mesh_.patches[p].area;
  }
}

glm::dvec3 Solver::Ambient() const {
  if (total_area_ == 0) return glm::dvec3(0.0);
  return reflect_ * unshot_sum_ / total_area_;
}

// A patch no light has reached yet (the floor under a box) is not
// overshot: the ambient estimate is light expected to arrive, and there
// it will not, so shooting it would only have to be taken back later.
glm::dvec3 Solver::ToShoot(int p) const {
  if (!overshoot_ || !lit_[p]) return unshot_[p];
  return unshot_[p] + mesh_.faces[mesh_.patches[p].face].rho * Ambient();
}

int Solver::Select(const std::vector<char>* taken) const {
  const glm::dvec3 amb = overshoot_ ? Ambient() : glm::dvec3(0.0);
  int best = -1;
  double best_power = 0;
  for (size_t p = 0; p < unshot_.size(); ++p) {
    if ((taken && (*taken)[p]) || blind_[p]) continue;
    const Patch& pa = mesh_.patches[p];
    glm::dvec3 x = lit_[p] ? unshot_[p] + mesh_.faces[pa.face].rho * amb : unshot_[p];
    double power = Abs(x) * pa.area;
    if (power > best_power) {
      best_power = power;
      best = int(p);
    }
  }
  return best;
}

void Solver::Shoot(int p, const std::vector<FormFactor>& column) {
  const Patch& shooter = mesh_.patches[p];
  // A patch that sees no element sends its light out of the scene: its
  // unshot radiosity is spent, and it is never chosen again (nothing can
  // send it light either, by reciprocity).
  if (column.empty()) blind_[p] = 1;
  const glm::dvec3 x = column.empty() ? unshot_[p] : ToShoot(p);
  abs_sum_ -= Abs(unshot_[p]) * shooter.area;
  unshot_[p] -= x;
  abs_sum_ += Abs(unshot_[p]) * shooter.area;
  unshot_sum_ -= x * shooter.area;
  // Power arriving at element e and reflected: ρ_e · x · F · A_shooter.
  // Per element only B changes, by that over A_e; a patch's unshot
  // radiosity gains the same summed over its elements, and since they
  // share one ρ it is enough to sum F per patch here (the master's
  // per-shot cost bounds the speedup, paper graph 2).
  const glm::dvec3 xa = x * shooter.area;
  // Ids increase along a column: the last is the largest.
  CHECK(column.empty() || size_t(column.back().elem) < patch_of_.size());
  for (const FormFactor& ff : column) {
    const int32_t e = ff.elem;
    int32_t q = patch_of_[e];
    if (q >= 0) {
      b_[e] += xa * (double(ff.f) * rho_per_area_[e]);
    } else {  // divided since the column was computed: each leaf gains alike
      q = ~q;
      mesh_.LeavesUnder(e, &leaves_);
      const glm::dvec3 gain = xa * (double(ff.f) * rho_per_area_[e]);
      for (int l : leaves_) b_[l] += gain;
    }
    if (fsum_[q] == 0) touched_.push_back(q);
    fsum_[q] += double(ff.f);
  }
  for (int32_t q : touched_) {
    const Patch& pq = mesh_.patches[q];
    const glm::dvec3 reflected = mesh_.faces[pq.face].rho * xa * fsum_[q];
    fsum_[q] = 0;
    lit_[q] |= Abs(reflected) > 0;
    if (blind_[q]) continue;  // a hemicube speck: it could not pass it on
    abs_sum_ -= Abs(unshot_[q]) * pq.area;
    unshot_[q] += reflected / pq.area;
    abs_sum_ += Abs(unshot_[q]) * pq.area;
    unshot_sum_ += reflected;
  }
  touched_.clear();
  ++times_shot_[p];
  // The running sums drift by rounding; a full sum every sweep bounds it.
  if (++shots_ % long(unshot_.size()) == 0) Resum();
}

void Solver::Divided(const std::vector<int32_t>& elems) {
  Grow();
  for (int32_t p : elems)
    for (int k = 0; k < kChildren; ++k) b_[mesh_.elems[p].first_child + k] = b_[p];
  // Fitted to the values as they are now (elements divided in this pass
  // hold their parent's), so the order of `elems` does not matter.
  std::vector<glm::dvec3> shaped(kChildren * elems.size());
  std::vector<int> nb, around;
  for (size_t i = 0; i < elems.size(); ++i) {
    const int p = elems[i];
    const Element& pe = mesh_.elems[p];
    const glm::dvec3 bp = b_[p];
    // The parent's neighbours: its children's, less their siblings.
    around.clear();
    for (int k = 0; k < kChildren; ++k) {
      LeafNeighbours(mesh_, pe.first_child + k, &nb);
      for (int n : nb)
        if (mesh_.elems[n].parent != p && std::find(around.begin(), around.end(), n) == around.end())
          around.push_back(n);
    }
    // Coordinates in the face's plane, about the children's area centroid.
    const glm::dvec3 nrm = mesh_.FaceOf(p).normal;
    glm::dvec3 t1 = mesh_.verts[pe.v[1]] - mesh_.verts[pe.v[0]];
    t1 = glm::normalize(t1 - nrm * glm::dot(t1, nrm));
    const glm::dvec3 t2 = glm::cross(nrm, t1);
    glm::dvec3 cc[kChildren], mean(0.0);
    double area = 0;
    for (int k = 0; k < kChildren; ++k) {
      const int c = pe.first_child + k;
      cc[k] = mesh_.Centroid(c);
      mean += mesh_.elems[c].area * cc[k];
      area += mesh_.elems[c].area;
    }
    mean /= area;
    // Least-squares gradient through the parent's value at `mean`, per
    // channel; a little damping where the neighbours span one direction.
    double m11 = 0, m12 = 0, m22 = 0;
    glm::dvec3 r1(0.0), r2(0.0), lo = bp, hi = bp;
    for (int n : around) {
      const glm::dvec3 d = mesh_.Centroid(n) - mean;
      const double dx = glm::dot(d, t1), dy = glm::dot(d, t2);
      m11 += dx * dx;
      m12 += dx * dy;
      m22 += dy * dy;
      r1 += dx * (b_[n] - bp);
      r2 += dy * (b_[n] - bp);
      lo = glm::min(lo, b_[n]);
      hi = glm::max(hi, b_[n]);
    }
    const double damp = 1e-3 * (m11 + m22);
    m11 += damp;
    m22 += damp;
    const double det = m11 * m22 - m12 * m12;
    glm::dvec3 gx(0.0), gy(0.0);
    if (det > 0) {
      gx = (m22 * r1 - m12 * r2) / det;
      gy = (m11 * r2 - m12 * r1) / det;
    }
    // Limited so that no child leaves the neighbours' range: the same
    // factor for all children keeps Σ B·area, as Σ area·(c − mean) = 0.
    glm::dvec3 dev[kChildren], scale(1.0);
    for (int k = 0; k < kChildren; ++k) {
      const glm::dvec3 d = cc[k] - mean;
      dev[k] = gx * glm::dot(d, t1) + gy * glm::dot(d, t2);
      for (int ch = 0; ch < 3; ++ch) {
        if (dev[k][ch] > 0) scale[ch] = std::min(scale[ch], (hi[ch] - bp[ch]) / dev[k][ch]);
        if (dev[k][ch] < 0) scale[ch] = std::min(scale[ch], (lo[ch] - bp[ch]) / dev[k][ch]);
      }
    }
    for (int k = 0; k < kChildren; ++k) shaped[kChildren * i + k] = bp + scale * dev[k];
  }
  for (size_t i = 0; i < elems.size(); ++i)
    for (int k = 0; k < kChildren; ++k)
      b_[mesh_.elems[elems[i]].first_child + k] = shaped[kChildren * i + k];
}

SolverState Solver::State() const {
  SolverState s;
  s.b = b_;
  s.unshot = unshot_;
  s.lit = lit_;
  s.blind = blind_;
  s.times_shot.assign(times_shot_.begin(), times_shot_.end());
  s.unshot_sum = unshot_sum_;
  s.abs_sum = abs_sum_;
  s.shots = shots_;
  return s;
}

bool Solver::Restore(const SolverState& s, std::string* err) {
  const size_t np = mesh_.patches.size();
  if (s.b.size() != mesh_.elems.size() || s.unshot.size() != np || s.lit.size() != np ||
      s.blind.size() != np || s.times_shot.size() != np) {
    *err = "solver state of " + std::to_string(s.b.size()) + " elements and " +
           std::to_string(s.unshot.size()) + " patches, the mesh has " +
           std::to_string(mesh_.elems.size()) + " and " + std::to_string(np);
    return false;
  }
  Grow();  // the mesh was divided since the constructor
  b_ = s.b;
  unshot_ = s.unshot;
  lit_ = s.lit;
  blind_ = s.blind;
  times_shot_.assign(s.times_shot.begin(), s.times_shot.end());
  unshot_sum_ = s.unshot_sum;
  abs_sum_ = s.abs_sum;
  shots_ = s.shots;
  return true;
}

double Solver::UnshotFraction() const {
  if (emitted_ == 0) return 0;
  return std::max(0.0, abs_sum_) / emitted_;
}

double Solver::PowerRatio() const {
  if (emitted_ == 0) return 0;
  double s = 0;
  for (size_t e = 0; e < b_.size(); ++e)
    if (mesh_.elems[e].IsLeaf()) s += (b_[e].r + b_[e].g + b_[e].b) * mesh_.elems[e].area;
  return s / emitted_;
}

double ShotAngle(unsigned seed, int patch, int k) {
  // splitmix64 of (seed, patch, k)
  uint64_t z = (uint64_t(seed) << 40) ^ (uint64_t(uint32_t(patch)) << 16) ^ uint64_t(k);
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return double(z >> 11) * 0x1.0p-53 * 2 * M_PI;
}

bool Refine(Mesh* mesh, Solver* solver, Subdivider* subdivider, long shots_in_wave,
            std::vector<int32_t>* edits) {
  edits->clear();
  if (!subdivider->Due(shots_in_wave)) return false;
  const double t0 = ThreadCpuSeconds();
  *edits = subdivider->Pass(*mesh, solver->radiosity(), solver->Ambient(), shots_in_wave);
  for (int32_t e : *edits) Divide(mesh, e);
  solver->Divided(*edits);
  subdivider->CountTime(ThreadCpuSeconds() - t0);
  return subdivider->WaveOver();
}

namespace {

// A worker as the scheduler keeps it (paper §4.1): the patches sent and
// not yet answered, and the queue prepared for it. A patch in either is
// owned by this worker and no other.
struct Slot {
  bool alive = false;
  struct Sent {
    proto::Assignment a;
    double at;
  };
  std::deque<Sent> sent;
  std::deque<int> prepared;
  int depth = 2;          // sent and unanswered, at most
  int high = 3, low = 2;  // watermarks on Queued()
  long columns = 0;
  int waiting = 0;        // its columns received and not yet shot
  size_t Owned() const { return sent.size() + prepared.size(); }
  // What the watermarks count: its columns waiting to be shot too, so
  // that a master slower than its workers stops feeding them. Otherwise
  // columns pile up, shot in arrival order (ever lower priority), and the
  // master, decoding more than it shoots, falls further behind: 15
  // simulated workers on the room at R 64 once received 1175 columns for
  // 500 shots at 108 us a shot instead of 30.
  size_t Queued() const { return Owned() + size_t(waiting); }
};

class Scheduler {
 public:
  Scheduler(Mesh* mesh, const RunOptions& opts, Solver* solver, Subdivider* sub, Transport* t,
            const std::function<void(const Sample&)>& sample,
            const std::function<void(const std::string&, bool)>& note)
      : mesh_(*mesh), mutable_mesh_(mesh), opts_(opts), solver_(solver), sub_(sub), t_(t),
        first_(t), sample_(sample), note_(note), taken_(mesh->patches.size(), 0) {
    if (const RunState* r = opts.resume) {
      wave_ = r->wave;
      wave_start_ = r->wave_start;
      best_ = r->best;
      best_at_ = r->best_at;
      before_ = r->seconds;
      r_.columns = r->columns;
      pending_.assign(r->pending.begin(), r->pending.end());
    }
  }
  RunResult Run();

 private:
  double Elapsed() { return before_ + t_->Now() - base_; }
  void Note(const std::string& line, bool warning) {
    if (note_) note_(line, warning);
  }
  void Sizes(Slot* s, int workers) const;
  void Handle(WorkerEvent& ev);
  void Distribute();
  void Release(Slot* s);
  bool Stop(double unshot);
  void Subdivide();
  void NextWave();
  int NextPatch();
  RunState State();
  void Checkpoint() {
    if (opts_.checkpoint) opts_.checkpoint(State());
    last_checkpoint_ = t_->Now();
  }
  void Emit(double unshot) {
    if (!sample_) return;
    int alive = 0;
    if (!t_->InProcess())
      for (const Slot& s : slots_) alive += s.alive;
    sample_({Elapsed(), solver_->shots(), wave_, mesh_.LeafCount(), unshot, alive});
  }

  const Mesh& mesh_;
  Mesh* mutable_mesh_;  // changed only by Subdivide()
  const RunOptions& opts_;
  Solver* solver_;
  Subdivider* sub_;     // null: no subdivision, one wave
  Transport* t_;
  Transport* first_;    // the transport given (t_ may become the fallback)
  std::unique_ptr<InProcessTransport> fallback_;
  const std::function<void(const Sample&)>& sample_;
  const std::function<void(const std::string&, bool)>& note_;
  std::vector<char> taken_;           // owned by a worker, or its column waits
  std::vector<Slot> slots_;
  struct Ready {
    proto::Column column;
    int from;  // the slot it came from (-1: that slot is gone)
  };
  std::deque<Ready> ready_;  // columns received, to be shot in order
  double base_ = 0, before_ = 0;      // clock: Elapsed() survives a fallback
  double best_ = HUGE_VAL;            // stall detection, per wave
  long best_at_ = 0;
  int wave_ = 1;
  long wave_start_ = 0;               // shots before this wave
  std::vector<int32_t> edits_;
  std::deque<int> pending_;           // RunState::pending of a resumed run
  double last_checkpoint_ = 0;        // on t_'s clock
  RunResult r_;
};

// The next patch to hand out: first those a resumed run's checkpoint had
// selected and not shot, then the one with the most power to shoot.
int Scheduler::NextPatch() {
  while (!pending_.empty()) {
    const int p = pending_.front();
    pending_.pop_front();
    if (p >= 0 && size_t(p) < taken_.size() && !taken_[p]) return p;
  }
  return solver_->Select(&taken_);
}

RunState Scheduler::State() {
  RunState s;
  s.wave = wave_;
  s.wave_start = wave_start_;
  s.best = best_;
  s.best_at = best_at_;
  s.seconds = Elapsed();
  s.columns = r_.columns;
  // Columns waiting are shot first; then the workers' patches, sent before
  // prepared, taken in turns as their columns would come back.
  for (const Ready& r : ready_) s.pending.push_back(r.column.patch);
  for (size_t i = 0;; ++i) {
    bool any = false;
    for (const Slot& w : slots_) {
      if (!w.alive || i >= w.Owned()) continue;
      any = true;
      s.pending.push_back(i < w.sent.size() ? w.sent[i].a.patch : w.prepared[i - w.sent.size()]);
    }
    if (!any) break;
  }
  for (int p : pending_) s.pending.push_back(p);
  return s;
}

// Queue sizes (paper §4.1: "3-10 patches according to network size").
// depth covers the measured round trip: while one column travels back and
// the next assignment travels out, the worker computes the ones it holds.
// high adds enough prepared patches to refill that pipeline twice, more
// with many workers (the master then takes longer to come round to each).
void Scheduler::Sizes(Slot* s, int workers) const {
  if (t_->InProcess()) {  // select right before computing: sequential order
    s->depth = s->high = s->low = 1;
    return;
  }
  if (opts_.queue > 0) {
    s->high = opts_.queue;
    s->depth = std::min(s->depth, s->high);
  } else {
    s->high = std::clamp(2 * s->depth + workers / 32, 3, 10);
  }
  s->low = std::max(1, (s->high + 1) / 2);
}

void Scheduler::Release(Slot* s) {
  for (const Slot::Sent& x : s->sent) taken_[x.a.patch] = 0;
  for (int p : s->prepared) taken_[p] = 0;
  s->sent.clear();
  s->prepared.clear();
}

void Scheduler::Handle(WorkerEvent& ev) {
  if (ev.worker >= int(slots_.size())) slots_.resize(ev.worker + 1);
  Slot& s = slots_[ev.worker];
  switch (ev.kind) {
    case WorkerEvent::kJoined:
      s.alive = true;
      ++r_.joined;
      Sizes(&s, t_->Workers());
      if (!t_->InProcess()) Note(t_->Name(ev.worker) + ": joined", false);
      return;
    case WorkerEvent::kLost: {
      if (!s.alive) {  // never joined: nothing of it to give back
        Note(t_->Name(ev.worker) + ": " + ev.why, true);
        return;
      }
      s.alive = false;
      ++r_.lost;
      const size_t n = s.Owned();
      Release(&s);
      Note(t_->Name(ev.worker) + ": lost (" + ev.why + "); its " + std::to_string(n) +
           " patches go to the others", true);
      return;
    }
    case WorkerEvent::kColumn: {
      const proto::Column& c = ev.column;
      auto it = std::find_if(s.sent.begin(), s.sent.end(), [&](const Slot::Sent& x) {
        return x.a.patch == c.patch && x.a.k == c.k;
      });
      // Only an outstanding assignment is shot: never the same patch twice.
      if (!s.alive || it == s.sent.end()) {
        ++r_.stale;
        return;
      }
      const double net = t_->Now() - it->at - c.compute_s - c.wait_s;
      if (!t_->InProcess() && c.compute_s > 0 && s.columns > 0) {
        const int need = 1 + int(std::ceil(std::max(0.0, net) / c.compute_s));
        s.depth = std::clamp(need, 2, 10);
        Sizes(&s, t_->Workers());
      }
      ++s.columns;
      ++s.waiting;
      s.sent.erase(it);
      r_.worker_s += c.compute_s;
      ready_.push_back({std::move(ev.column), ev.worker});
      return;
    }
  }
}

// Cyclic fill (paper §4.1): when any queue is under its low mark, go round
// the workers not yet at their high mark, one patch each per turn, always
// the patch with the most power to shoot, so that the first lights of a
// run go to different workers. Then send what each pipeline has room for.
void Scheduler::Distribute() {
  const double t0 = WallNow();
  bool low = false;
  for (const Slot& s : slots_) low |= s.alive && s.Queued() < size_t(s.low);
  for (bool more = low; more;) {
    more = false;
    for (Slot& s : slots_) {
      if (!s.alive || s.Queued() >= size_t(s.high)) continue;
      const int p = NextPatch();
      if (p < 0) break;  // nothing left with power to shoot: send what is prepared
      taken_[p] = 1;
      s.prepared.push_back(p);
      more = true;
    }
  }
  for (size_t w = 0; w < slots_.size(); ++w) {
    Slot& s = slots_[w];
    while (s.alive && !s.prepared.empty() && s.sent.size() < size_t(s.depth)) {
      const int p = s.prepared.front();
      s.prepared.pop_front();
      const proto::Assignment a{p, solver_->TimesShot(p)};
      s.sent.push_back({a, t_->Now()});
      t_->Assign(int(w), a);
    }
  }
  r_.distribute_s += WallNow() - t0;
}

bool Scheduler::Stop(double unshot) {
  const long shots = solver_->shots();
  if (solver_->Dark()) {
    r_.status = RunStatus::kConverged;
    r_.why = "the scene emits no light";
  } else if (unshot < opts_.epsilon) {
    r_.status = RunStatus::kConverged;
  } else if (opts_.stop && *opts_.stop) {
    r_.status = RunStatus::kStopped;
  } else if (opts_.max_shots > 0 && shots >= opts_.max_shots) {
    r_.status = RunStatus::kLimit;
    r_.why = "shot limit reached";
  } else if (opts_.max_seconds > 0 && Elapsed() >= opts_.max_seconds) {
    r_.status = RunStatus::kLimit;
    r_.why = "time limit reached";
  } else if (!std::isfinite(unshot) || unshot > 1e12) {
    r_.status = RunStatus::kNotConverged;
    r_.why = "unshot energy grows without bound (does the scene reflect all light?)";
  } else {
    // Not converging: the unshot fraction has not fallen by 1% for this
    // many shots (20 sweeps over the patches). Progress that slow (ρ → 1
    // without overshooting) or none at all (ρ = 1) would not finish in
    // useful time.
    const long stall = std::max(1000L, 20 * long(mesh_.patches.size()));
    if (unshot < best_ * 0.99) {
      best_ = unshot;
      best_at_ = shots;
      return false;
    }
    if (shots - best_at_ <= stall) return false;
    r_.status = RunStatus::kNotConverged;
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "unshot energy still %.3g of emitted and not falling for %ld shots "
                  "(reflectance too close to 1?)",
                  unshot, stall);
    r_.why = buf;
  }
  return true;
}

// A division pass (paper §4.3) when one is due, only while every worker's
// queue holds at least its low mark and no column waits to be shot, so
// that the workers stay busy while the master divides. The edits go to
// every worker in the order they were made.
void Scheduler::Subdivide() {
  if (!sub_ || !ready_.empty()) return;
  for (const Slot& s : slots_)
    if (s.alive && !t_->InProcess() && s.Queued() < size_t(s.low)) return;
  const double t0 = WallNow();
  const bool over = Refine(mutable_mesh_, solver_, sub_, solver_->shots() - wave_start_, &edits_);
  if (!edits_.empty()) t_->Divide(edits_);
  r_.subdivide_s += WallNow() - t0;
  if (over) NextWave();
}

// The end of a wave (paper §4.4): a picture of it, then the radiosity is
// thrown away and shooting starts again from the emitters on the finer
// mesh. Columns in flight are still shot: they are columns of the same
// geometry.
void Scheduler::NextWave() {
  if (opts_.wave_end) opts_.wave_end(wave_);
  solver_->NewWave();
  sub_->StartWave(mesh_);
  ++wave_;
  wave_start_ = best_at_ = solver_->shots();
  best_ = HUGE_VAL;
  Emit(solver_->UnshotFraction());
}

RunResult Scheduler::Run() {
  // The master's parts are timed with the monotonic clock: the thread's
  // CPU clock is a system call (8 us on a loaded virtual machine), dearer
  // than the work it would time, so it is read once per turn of the loop.
  // The wall time of a turn that was not CPU time was spent blocked, in
  // Poll waiting for workers (or preempted): counted as waiting, up to the
  // wall time of the Poll; the rest of the Poll is receiving.
  auto since = [](double t0) { return WallNow() - t0; };
  double turn_wall = WallNow(), turn_cpu = ThreadCpuSeconds(), poll_s = 0;
  auto account = [&] {
    const double wall = WallNow(), cpu = ThreadCpuSeconds();
    const double blocked = std::clamp((wall - turn_wall) - (cpu - turn_cpu), 0.0, poll_s);
    r_.wait_s += blocked;
    r_.receive_s += poll_s - blocked;
    turn_wall = wall;
    turn_cpu = cpu;
    poll_s = 0;
  };
  base_ = t_->Now();
  const long log_every =
      opts_.log_every > 0 ? opts_.log_every : std::max(1L, long(mesh_.patches.size()) / 100);
  double unshot = solver_->UnshotFraction();
  if (!opts_.resume) Emit(unshot);
  last_checkpoint_ = t_->Now();
  std::vector<WorkerEvent> events;
  for (;;) {
    if (unshot < opts_.epsilon && sub_ && sub_->WaveOver(true)) {
      NextWave();
      unshot = solver_->UnshotFraction();
    }
    account();
    if (Stop(unshot)) break;
    // Wait for workers only when there is nothing to shoot.
    double t0 = WallNow();
    events.clear();
    t_->Poll(ready_.empty() ? 0.25 : 0.0, &events);
    poll_s = since(t0);
    for (WorkerEvent& ev : events) Handle(ev);
    bool alive = false;
    for (const Slot& s : slots_) alive |= s.alive;
    if (!alive && t_->Starting() == 0 && ready_.empty()) {
      if (r_.joined == 0) {
        r_.status = RunStatus::kNoWorkers;
        r_.why = "no worker could be started";
        break;
      }
      Note("no workers left: the master computes the form factors itself", true);
      r_.fell_back = true;
      before_ = Elapsed();
      fallback_ = std::make_unique<InProcessTransport>(mesh_, opts_.resolution, opts_.rotate,
                                                       opts_.seed);
      t_ = fallback_.get();
      base_ = last_checkpoint_ = t_->Now();
      slots_.clear();
      for (Ready& r : ready_) r.from = -1;
      continue;
    }
    // Sending work comes before shooting, so that workers never starve.
    Distribute();
    if (ready_.empty()) {
      bool owned = false;
      for (const Slot& s : slots_) owned |= s.Owned() > 0;
      if (!owned && alive) {  // nothing left with power to shoot
        r_.status = RunStatus::kConverged;
        break;
      }
      continue;
    }
    t0 = WallNow();
    const proto::Column c = std::move(ready_.front().column);
    Slot* from = ready_.front().from >= 0 ? &slots_[size_t(ready_.front().from)] : nullptr;
    ready_.pop_front();
    if (from) --from->waiting;
    solver_->Shoot(c.patch, c.ff);
    taken_[c.patch] = 0;
    ++r_.columns;
    unshot = solver_->UnshotFraction();
    r_.shoot_s += since(t0);
    // The shot made room in its worker's queue: refill it before Poll
    // blocks, as the arrival of the column no longer did.
    if (from && from->alive && from->Queued() < size_t(from->low)) Distribute();
    if (solver_->shots() % log_every == 0) Emit(unshot);
    Subdivide();
    unshot = solver_->UnshotFraction();
    if (opts_.checkpoint_every > 0 && t_->Now() - last_checkpoint_ >= opts_.checkpoint_every)
      Checkpoint();
  }
  Checkpoint();  // before the last sample, which a resumed run then writes
  if (solver_->shots() % log_every != 0) Emit(unshot);  // the last state, once
  r_.shots = solver_->shots();
  r_.seconds = Elapsed();
  r_.unshot = unshot;
  r_.bytes_sent = first_->BytesSent();
  r_.bytes_received = first_->BytesReceived();
  r_.waves = wave_;
  if (sub_) r_.passes = sub_->passes();
  return r_;
}

}  // namespace

RunResult RunMaster(Mesh* mesh, const RunOptions& opts, Solver* solver, Subdivider* subdivider,
                    Transport* transport, const std::function<void(const Sample&)>& sample,
                    const std::function<void(const std::string&, bool)>& note) {
  Scheduler s(mesh, opts, solver, subdivider, transport, sample, note);
  return s.Run();
}

RunResult RunSequential(Mesh* mesh, const RunOptions& opts, Solver* solver,
                        Subdivider* subdivider,
                        const std::function<void(const Sample&)>& sample) {
  InProcessTransport t(*mesh, opts.resolution, opts.rotate, opts.seed);
  return RunMaster(mesh, opts, solver, subdivider, &t, sample, nullptr);
}
