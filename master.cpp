#include "master.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "check.h"

Solver::Solver(const Mesh& mesh, bool overshoot)
    : mesh_(mesh),
      overshoot_(overshoot),
      b_(mesh.elems.size()),
      unshot_(mesh.patches.size()),
      times_shot_(mesh.patches.size(), 0) {
  for (size_t e = 0; e < mesh.elems.size(); ++e) b_[e] = mesh.FaceOf(int(e)).emission;
  glm::dvec3 rho_area(0.0);
  for (size_t p = 0; p < mesh.patches.size(); ++p) {
    const MeshFace& f = mesh.faces[mesh.patches[p].face];
    const double a = mesh.patches[p].area;
    unshot_[p] = f.emission;
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
    const Element& e = mesh_.elems[ff.elem];
    const Patch& q = mesh_.patches[e.patch];
    // Power arriving at e and reflected: ρ_e · x · F · A_shooter.
    const glm::dvec3 reflected = mesh_.faces[q.face].rho * x * (double(ff.f) * shooter.area);
    b_[ff.elem] += reflected / e.area;
    unshot_[e.patch] += reflected / q.area;
    unshot_sum_ += reflected;
  }
  ++times_shot_[p];
  // The running sum drifts by rounding; a full sum every sweep bounds it.
  if (++shots_ % long(unshot_.size()) == 0) Resum();
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

RunResult RunSequential(const Mesh& mesh, const RunOptions& opts, Solver* solver,
                        const std::function<void(const Sample&)>& sample) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  Hemicube hemicube(opts.resolution);
  const long npatch = long(mesh.patches.size());
  const long log_every = opts.log_every > 0 ? opts.log_every : std::max(1L, npatch / 100);
  // Not converging: the unshot fraction has not fallen by 1% for this many
  // shots (20 sweeps over the patches). Progress that slow (ρ → 1 without
  // overshooting) or none at all (ρ = 1) would not finish in useful time.
  const long stall = std::max(1000L, 20 * npatch);
  double best = HUGE_VAL;
  long best_at = 0;
  RunResult r;
  std::vector<FormFactor> column;
  auto emit = [&](double unshot) {
    if (sample) sample({elapsed(), solver->shots(), 1, long(mesh.elems.size()), unshot});
  };
  double unshot = solver->UnshotFraction();
  emit(unshot);
  for (;;) {
    const long shots = solver->shots();
    if (solver->Dark()) { r.status = RunStatus::kConverged; r.why = "the scene emits no light"; break; }
    if (unshot < opts.epsilon) { r.status = RunStatus::kConverged; break; }
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
    hemicube.Column(mesh, p, angle, &column, &r.columns);
    auto t2 = Clock::now();
    solver->Shoot(p, column);
    unshot = solver->UnshotFraction();
    auto t3 = Clock::now();
    r.select_s += std::chrono::duration<double>(t1 - t0).count();
    r.shoot_s += std::chrono::duration<double>(t3 - t2).count();
    if (solver->shots() % log_every == 0) emit(unshot);
  }
  if (solver->shots() % log_every != 0) emit(unshot);  // the last state, once
  r.shots = solver->shots();
  r.seconds = elapsed();
  r.unshot = unshot;
  return r;
}
