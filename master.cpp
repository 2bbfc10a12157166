#include "master.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "check.h"

Solver::Solver(const Mesh& mesh, bool overshoot)
    : mesh_(mesh), overshoot_(overshoot) {
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
  b_.resize(mesh_.elems.size());
  for (size_t e = 0; e < b_.size(); ++e) b_[e] = mesh_.FaceOf(int(e)).emission;
  unshot_.resize(mesh_.patches.size());
  for (size_t p = 0; p < unshot_.size(); ++p) unshot_[p] = mesh_.faces[mesh_.patches[p].face].emission;
  times_shot_.assign(mesh_.patches.size(), 0);
  Resum();
}

void Solver::Resum() {
  unshot_sum_ = glm::dvec3(0.0);
  for (size_t p = 0; p < unshot_.size(); ++p) unshot_sum_ += unshot_[p] * mesh_.patches[p].area;
}

glm::dvec3 Solver::Ambient() const {
  if (total_area_ == 0) return glm::dvec3(0.0);
  return reflect_ * unshot_sum_ / total_area_;
}

glm::dvec3 Solver::ToShoot(int p) const {
  if (!overshoot_) return unshot_[p];
  return unshot_[p] + mesh_.faces[mesh_.patches[p].face].rho * Ambient();
}

int Solver::Select(const std::vector<char>* taken) const {
  const glm::dvec3 amb = overshoot_ ? Ambient() : glm::dvec3(0.0);
  int best = -1;
  double best_power = 0;
  for (size_t p = 0; p < unshot_.size(); ++p) {
    if (taken && (*taken)[p]) continue;
    const Patch& pa = mesh_.patches[p];
    glm::dvec3 x = unshot_[p] + mesh_.faces[pa.face].rho * amb;
    double power = (std::abs(x.r) + std::abs(x.g) + std::abs(x.b)) * pa.area;
    if (power > best_power) {
      best_power = power;
      best = int(p);
    }
  }
  return best;
}

void Solver::Shoot(int p, const std::vector<FormFactor>& column) {
  const Patch& shooter = mesh_.patches[p];
  const glm::dvec3 x = ToShoot(p);
  unshot_[p] -= x;
  unshot_sum_ -= x * shooter.area;
  for (const FormFactor& ff : column) {
    CHECK(ff.elem >= 0 && size_t(ff.elem) < b_.size());
    const Element& e = mesh_.elems[ff.elem];
    const Patch& q = mesh_.patches[e.patch];
    // Power arriving at e and reflected: ρ_e · x · F · A_shooter.
    const glm::dvec3 reflected = mesh_.faces[q.face].rho * x * (double(ff.f) * shooter.area);
    if (e.IsLeaf()) {
      b_[ff.elem] += reflected / e.area;
    } else {  // divided since the column was computed: Σ leaf areas = e.area
      mesh_.LeavesUnder(ff.elem, &leaves_);
      for (int l : leaves_) b_[l] += reflected / e.area;
    }
    unshot_[e.patch] += reflected / q.area;
    unshot_sum_ += reflected;
  }
  ++times_shot_[p];
  // The running sum drifts by rounding; a full sum every sweep bounds it.
  if (++shots_ % long(unshot_.size()) == 0) Resum();
}

void Solver::Divided(const std::vector<int32_t>& elems) {
  b_.resize(mesh_.elems.size());
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

double Solver::UnshotFraction() const {
  if (emitted_ == 0) return 0;
  double s = 0;
  for (size_t p = 0; p < unshot_.size(); ++p) {
    const glm::dvec3& u = unshot_[p];
    s += (std::abs(u.r) + std::abs(u.g) + std::abs(u.b)) * mesh_.patches[p].area;
  }
  return s / emitted_;
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
  const auto t0 = std::chrono::steady_clock::now();
  *edits = subdivider->Pass(*mesh, solver->radiosity(), solver->Ambient(), shots_in_wave);
  for (int32_t e : *edits) Divide(mesh, e);
  solver->Divided(*edits);
  subdivider->CountTime(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return subdivider->WaveOver();
}

RunResult RunSequential(Mesh* mesh, const RunOptions& opts, Solver* solver,
                        Subdivider* subdivider,
                        const std::function<void(const Sample&)>& sample) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  Hemicube hemicube(opts.resolution);
  const long npatch = long(mesh->patches.size());
  const long log_every = opts.log_every > 0 ? opts.log_every : std::max(1L, npatch / 100);
  // Not converging: the unshot fraction has not fallen by 1% for this many
  // shots (20 sweeps over the patches). Progress that slow (ρ → 1 without
  // overshooting) or none at all (ρ = 1) would not finish in useful time.
  // Counted per wave: a new wave starts again from all the emitted light.
  const long stall = std::max(1000L, 20 * npatch);
  double best = HUGE_VAL;
  long best_at = 0;
  int wave = 1;
  long wave_start = 0;  // shots before this wave
  RunResult r;
  std::vector<FormFactor> column;
  std::vector<int32_t> edits;
  auto emit = [&](double unshot) {
    if (sample) sample({elapsed(), solver->shots(), wave, mesh->LeafCount(), unshot});
  };
  double unshot = solver->UnshotFraction();
  auto next_wave = [&] {
    if (opts.wave_end) opts.wave_end(wave);
    solver->NewWave();
    subdivider->StartWave(*mesh);
    ++wave;
    wave_start = best_at = solver->shots();
    best = HUGE_VAL;
    unshot = solver->UnshotFraction();
    emit(unshot);
  };
  emit(unshot);
  for (;;) {
    const long shots = solver->shots();
    if (solver->Dark()) { r.status = RunStatus::kConverged; r.why = "the scene emits no light"; break; }
    if (unshot < opts.epsilon) {
      if (subdivider && subdivider->WaveOver(true)) {
        next_wave();
        continue;
      }
      r.status = RunStatus::kConverged;
      break;
    }
    if (opts.stop && *opts.stop) { r.status = RunStatus::kStopped; break; }
    if (opts.max_shots > 0 && shots >= opts.max_shots) {
      r.status = RunStatus::kLimit;
      r.why = "shot limit reached";
      break;
    }
    if (opts.max_seconds > 0 && elapsed() >= opts.max_seconds) {
      r.status = RunStatus::kLimit;
      r.why = "time limit reached";
      break;
    }
    if (!std::isfinite(unshot) || unshot > 1e12) {
      r.status = RunStatus::kNotConverged;
      r.why = "unshot energy grows without bound (does the scene reflect all light?)";
      break;
    }
    if (unshot < best * 0.99) {
      best = unshot;
      best_at = shots;
    } else if (shots - best_at > stall) {
      r.status = RunStatus::kNotConverged;
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "unshot energy still %.3g of emitted and not falling for %ld shots "
                    "(reflectance too close to 1?)",
                    unshot, stall);
      r.why = buf;
      break;
    }
    auto t0 = Clock::now();
    const int p = solver->Select();
    auto t1 = Clock::now();
    if (p < 0) { r.status = RunStatus::kConverged; break; }
    const double angle = opts.rotate ? ShotAngle(opts.seed, p, solver->TimesShot(p)) : 0.0;
    hemicube.Column(*mesh, p, angle, &column, &r.columns);
    auto t2 = Clock::now();
    solver->Shoot(p, column);
    unshot = solver->UnshotFraction();
    auto t3 = Clock::now();
    r.select_s += std::chrono::duration<double>(t1 - t0).count();
    r.shoot_s += std::chrono::duration<double>(t3 - t2).count();
    if (solver->shots() % log_every == 0) emit(unshot);
    if (subdivider && Refine(mesh, solver, subdivider, solver->shots() - wave_start, &edits))
      next_wave();
  }
  if (solver->shots() % log_every != 0) emit(unshot);  // the last state, once
  r.shots = solver->shots();
  r.seconds = elapsed();
  r.unshot = unshot;
  r.waves = wave;
  if (subdivider) {
    r.subdivide_s = subdivider->seconds();
    r.passes = subdivider->passes();
  }
  return r;
}
