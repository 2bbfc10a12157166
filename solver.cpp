#include "solver.h"

#include <algorithm>
#include <cmath>

#include "check.h"
#include "groups.h"

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

double Solver::Power(int p, const glm::dvec3& amb) const {
  const Patch& pa = mesh_.patches[p];
  glm::dvec3 x = lit_[p] ? unshot_[p] + mesh_.faces[pa.face].rho * amb : unshot_[p];
  return Abs(x) * pa.area;
}

int Solver::Select(const std::vector<char>* taken) const {
  const glm::dvec3 amb = overshoot_ ? Ambient() : glm::dvec3(0.0);
  int best = -1;
  double best_power = 0;
  for (size_t p = 0; p < unshot_.size(); ++p) {
    if ((taken && (*taken)[p]) || blind_[p]) continue;
    double power;
    if (const PatchGroup* g = GroupOf(mesh_, int(p))) {
      if (g->members[0] != int(p)) continue;  // its group's shooter shoots for it
      power = 0;
      for (int m : g->members) power += Power(m, amb);
    } else {
      power = Power(int(p), amb);
    }
    if (power > best_power) {
      best_power = power;
      best = int(p);
    }
  }
  return best;
}

void Solver::Shoot(int p, const std::vector<FormFactor>& column) {
  // A group (groups.h) shoots Σ x·A of its members from one column, and
  // each member gives up exactly its own x: what leaves is what is shot.
  const PatchGroup* group = GroupOf(mesh_, p);
  const int single[1] = {p};
  const int* members = group ? group->members.data() : single;
  const size_t count = group ? group->members.size() : 1;
  glm::dvec3 xa(0.0);  // Σ x·A of what shoots
  for (size_t i = 0; i < count; ++i) {
    const int m = members[i];
    const double area = mesh_.patches[m].area;
    // A shooter that sees no element sends its light out of the scene:
    // its unshot radiosity is spent, and it is never chosen again (nothing
    // can send it light either, by reciprocity).
    if (column.empty()) blind_[m] = 1;
    const glm::dvec3 x = column.empty() ? unshot_[m] : ToShoot(m);
    abs_sum_ -= Abs(unshot_[m]) * area;
    unshot_[m] -= x;
    abs_sum_ += Abs(unshot_[m]) * area;
    unshot_sum_ -= x * area;
    xa += x * area;
  }
  // Power arriving at element e and reflected: ρ_e · x · F · A_shooter.
  // Per element only B changes, by that over A_e; a patch's unshot
  // radiosity gains the same summed over its elements, and since they
  // share one ρ it is enough to sum F per patch here (the master's
  // per-shot cost bounds the speedup, paper graph 2).
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
