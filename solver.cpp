#include "solver.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <type_traits>

#include <unistd.h>

#include "check.h"
#include "groups.h"

namespace {
double Abs(const glm::dvec3& u) { return std::abs(u.r) + std::abs(u.g) + std::abs(u.b); }

// The delta form factor, at most, of a hemicube pixel seen cos_a off the
// shooter's normal, for one whose top-centre pixel has pixel_ff (the
// noise model and its derivation: subdivide.h). A pixel seen that way has
// pixel_ff · cos_a · cos³γ, γ its angle from the axis of the hemicube face
// it is on; cos γ is the direction's largest component in the hemicube's
// frame, at most max(cos_a, sin_a) however the hemicube is turned: so the
// pixels an element covers are not underestimated, nor its noise. Unknown
// direction (cos_a <= 0, where a patch centre is behind the shooter and
// an element of it is not): pixel_ff.
double PixelFormFactor(double pixel_ff, double cos_a) {
  if (!(cos_a > 0)) return pixel_ff;
  const double m = std::max(cos_a, std::sqrt(std::max(0.0, 1 - cos_a * cos_a)));
  return pixel_ff * cos_a * m * m * m;
}

// The variance that a shot's gain g (luminance) adds to an element's B
// when it took g as form factor f, n = f / df pixels of delta form factor
// df: Var(pixel count) / count² is 1/n for an element smaller than 4/9
// pixel (hit or missed whole), (2/3) n^-3/2 for the pixels along its
// outline. In 1/n = df / f: one division (and the square root) where
// n = f / df took two, which held each element of a dividing run's shot
// on the divider (boxes3800, radiosity-master --divide: shooting 243-246
// us a shot, then 227-228).
inline double ShotNoise(double g, double f, double df) {
  const double r = df / f;  // 1/n
  return g * g * (r > 9.0 / 4 ? r : (2.0 / 3) * r * std::sqrt(r));
}

// This core's second-level cache (1 MiB when the system does not say).
size_t SecondLevelCacheBytes() {
  static const size_t bytes = [] {
    const long b = sysconf(_SC_LEVEL2_CACHE_SIZE);
    return b > 0 ? size_t(b) : size_t(1) << 20;
  }();
  return bytes;
}

}  // namespace

Solver::Solver(const Mesh& mesh, bool overshoot)
    : mesh_(mesh), overshoot_(overshoot) {
  PatchArrays();
  glm::dvec3 rho_area(0.0);
  for (size_t p = 0; p < mesh.patches.size(); ++p) {
    const MeshFace& f = mesh.faces[mesh.patches[p].face];
    const glm::dvec3& ke = mesh.Emission(f);
    const double a = mesh.patch_area[p];
    total_area_ += a;
    emitted_ += (ke.r + ke.g + ke.b) * a;
    rho_area += mesh.Rho(f) * a;
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

// The per-patch arrays that follow from the mesh, for its patches as they
// are (split ones included).
void Solver::PatchArrays() {
  const size_t n = mesh_.patches.size();
  patch_.resize(n);
  weight_.resize(n);
  for (size_t p = 0; p < n; ++p) {
    const MeshFace& face = mesh_.faces[mesh_.patches[p].face];
    const glm::dvec3& rho = mesh_.Rho(face);
    patch_[p].material = face.material;
    patch_[p].group = mesh_.group_of.empty() ? -1 : mesh_.group_of[p];
    patch_[p].SetArea(mesh_.patch_area[p]);
    patch_[p].fsum = 0;
    weight_[p] = patch_[p].area * std::max({rho.r, rho.g, rho.b});
  }
  // A group's drift moves Σ of its members' powers: its key (members[0])
  // carries their weights summed, the other members none (never chosen).
  for (const PatchGroup& g : mesh_.groups)
    for (size_t i = 1; i < g.members.size(); ++i) {
      weight_[size_t(g.members[0])] += weight_[size_t(g.members[i])];
      weight_[size_t(g.members[i])] = 0;
    }
  group_dirty_.assign(mesh_.groups.size(), 0);
}

void Solver::EndWave() {
  FreeStorage(&noise_);
  FreeStorage(&direct_);
}

void Solver::NewWave() {
  Grow();
  for (size_t e = 0; e < elem_.size(); ++e) elem_[e].b = mesh_.Emission(mesh_.FaceOf(int(e)));
  if (pixel_ff_ > 0) noise_.assign(elem_.size(), 0.0);
  if (track_direct_) direct_.assign(elem_.size(), 0.0f);
  patch_.resize(mesh_.patches.size());
  for (size_t p = 0; p < patch_.size(); ++p) {
    patch_[p].unshot = mesh_.Emission(mesh_.faces[mesh_.patches[p].face]);
    patch_[p].lit = Abs(patch_[p].unshot) > 0;
  }
  times_shot_.assign(mesh_.patches.size(), 0);
  CountDarkEmitters();
  Resum();
  Rebase();
}

// The emitting shooters (a group's members summed) that can still shoot
// and have not in this wave: DirectDone() once none is left.
void Solver::CountDarkEmitters() {
  dark_emitters_ = 0;
  for (size_t p = 0; p < patch_.size(); ++p) {
    if (patch_[p].blind || times_shot_[p] > 0 || !IsShooter(mesh_, int(p))) continue;
    const int32_t shooter = int32_t(p);
    double ke = 0;
    for (int32_t m : ShootsAs(mesh_, shooter)) ke += Abs(mesh_.Emission(mesh_.faces[mesh_.patches[size_t(m)].face]));
    if (ke > 0) ++dark_emitters_;
  }
}

// Per-element arrays for the elements Divide() has added; a divided
// element's patch is stored complemented so that Shoot tells it apart
// from a leaf without touching the Element.
void Solver::Grow() {
  const size_t from = patch_of_.size(), n = mesh_.elems.size();
  elem_.resize(n);
  patch_of_.resize(n);
  changed_bits_.resize((n + 63) / 64, 0);
  if (pixel_ff_ > 0) noise_.resize(n, 0.0);
  if (track_direct_) direct_.resize(n, 0.0f);
  // Only added elements and their parents (divided since): O(divisions).
  for (size_t e = from; e < n; ++e) {
    const Element& el = mesh_.elems[e];
    patch_of_[e] = el.IsLeaf() ? el.patch : ~el.patch;
    elem_[e].inv_area = 1.0 / mesh_.elem_area[e];
    const int parent = mesh_.parent[e];
    if (parent >= 0 && size_t(parent) < from) patch_of_[size_t(parent)] = ~el.patch;
  }
  HugeArrays();
}

// What Shoot reads at a column's elements, scattered over arrays of 10^5
// entries and more, in 2 MB pages (memory.h); elem_, patch_of_ and
// patch_ are allocated so, these are handed out as std::vector.
void Solver::HugeArrays() {
  PreferHugePages(noise_.data(), noise_.size() * sizeof(double));
  PreferHugePages(direct_.data(), direct_.size() * sizeof(float));
}

void Solver::TrackNoise(int resolution) {
  // The top face spans 2 × 2 at unit height: a pixel (2/R)² there, at its
  // centre, has delta form factor (2/R)² / π.
  pixel_ff_ = 4 / (M_PI * double(resolution) * resolution);
  noise_.resize(elem_.size(), 0.0);
  HugeArrays();
}

void Solver::TrackDirect() {
  track_direct_ = true;
  direct_.resize(elem_.size(), 0.0f);
  HugeArrays();
}

void Solver::Resum() {
  unshot_sum_ = glm::dvec3(0.0);
  abs_sum_ = 0;
  for (size_t p = 0; p < patch_.size(); ++p) {
    unshot_sum_ += patch_[p].unshot * mesh_.patch_area[p];
    abs_sum_ += Abs(patch_[p].unshot) * mesh_.patch_area[p];
  }
}

std::vector<glm::dvec3> Solver::unshot() const {
  std::vector<glm::dvec3> u(patch_.size());
  for (size_t p = 0; p < u.size(); ++p) u[p] = patch_[p].unshot;
  return u;
}

glm::dvec3 Solver::Ambient() const {
  if (total_area_ == 0) return glm::dvec3(0.0);
  return reflect_ * unshot_sum_ / total_area_;
}

// A patch no light has reached yet (the floor under a box) is not
// overshot: the ambient estimate is light expected to arrive, and there
// it will not, so shooting it would only have to be taken back later.
glm::dvec3 Solver::ToShoot(int p) const {
  if (!overshoot_ || !patch_[p].lit) return patch_[p].unshot;
  return patch_[p].unshot + Rho(p) * Ambient();
}

double Solver::Power(int p, const glm::dvec3& ambient) const {
  const glm::dvec3 x = patch_[p].lit ? patch_[p].unshot + Rho(p) * ambient : patch_[p].unshot;
  return Abs(x) * patch_[p].area;
}

// A lone patch's Power, a group's summed over its members (groups.h).
double Solver::ShooterPower(int p, const glm::dvec3& ambient) const {
  const PatchGroup* g = GroupOf(mesh_, p);
  if (!g) return Power(p, ambient);
  double power = 0;
  for (int m : g->members) power += Power(m, ambient);
  return power;
}

int Solver::SelectByScan(const std::vector<char>* taken) const {
  const glm::dvec3 amb = overshoot_ ? Ambient() : glm::dvec3(0.0);
  int best = -1;
  double best_power = 0;
  for (size_t p = 0; p < patch_.size(); ++p) {
    if ((taken && (*taken)[p]) || patch_[p].blind || !IsShooter(mesh_, int(p))) continue;
    const double power = ShooterPower(int(p), amb);
    if (power > best_power) {
      best_power = power;
      best = int(p);
    }
  }
  return best;
}

// An upper bound of Power(p, a) for a = base_ (exact without
// overshooting or light), plus 1e-9 of the magnitudes summed: far above
// the rounding of either side (1e-16), so that the bound holds for the
// computed powers too. For any other a, Power(p, a) moves from its value
// at base_ by at most Σ_c area·ρ_c·|a_c − base_c| <= weight · Σ_c |Δa_c|
// (weight = area · max ρ): the drift Select adds to every bound, times
// each patch's weight.
inline double Solver::PatchBound(int p) const {  // inline: Shoot's touched loop calls it
  if (!overshoot_ || !patch_[p].lit) return Abs(patch_[p].unshot) * patch_[p].area;
  const glm::dvec3 shared = Rho(p) * base_;
  return (Abs(patch_[p].unshot + shared) + 1e-9 * (Abs(patch_[p].unshot) + Abs(shared))) * patch_[p].area;
}

// Per shooter: a group's bound is its members' summed in the order
// ShooterPower sums their powers (floating-point addition is monotone, so
// it bounds that sum), under its weight summed likewise (the constructor);
// -inf for the other members and the blind. A group's members go blind
// together (Shoot).
double Solver::Bound(int p) const {
  if (patch_[p].blind || !IsShooter(mesh_, p)) return -HUGE_VAL;
  const PatchGroup* g = GroupOf(mesh_, p);
  if (!g) return PatchBound(p);
  double bound = 0;
  for (int m : g->members) bound += PatchBound(m);
  return bound;
}

// The bounds again at the overshooting estimate as it is now: O(patches),
// when the drift since the last made Select look at too many patches.
void Solver::Rebase() {
  base_ = overshoot_ ? Ambient() : glm::dvec3(0.0);
  std::vector<double> bounds(patch_.size());
  for (size_t p = 0; p < bounds.size(); ++p) bounds[p] = Bound(int(p));
  queue_.Build(bounds, weight_);
}

int Solver::Select() {
  CHECK(!splits_pending_);
  const glm::dvec3 amb = overshoot_ ? Ambient() : glm::dvec3(0.0);
  const glm::dvec3 d = glm::abs(amb - base_);
  double drift = (d.r + d.g + d.b) * (1 + 1e-9);
  if (!std::isfinite(drift)) {  // a run about to stop as diverging: no bound holds
    std::vector<char> taken(patch_.size());
    for (size_t p = 0; p < taken.size(); ++p) taken[p] = queue_.Taken(int(p));
    return SelectByScan(&taken);
  }
  // Re-based once the patches visited since the last cost as much as
  // doing it (with drift 0 only ties are visited: nothing to gain).
  if (drift > 0 && queue_.Visited() > long(patch_.size()) / 2 + 64) {
    Rebase();
    drift = 0;
  }
  return queue_.Best(drift, [&](int p) { return ShooterPower(p, amb); });
}

void Solver::Shoot(int p, const std::vector<FormFactor>& column) {
  CHECK(!splits_pending_);
  // A group (groups.h) shoots Σ x·A of its members from one column, and
  // each member gives up exactly its own x: what leaves is what is shot.
  const PatchGroup* group = GroupOf(mesh_, p);
  const int32_t shooter = p;
  glm::dvec3 xa(0.0);  // Σ x·A of what shoots
  glm::dvec3 ka(0.0);  // Σ Ke·A of it, at its first shot in the wave (TrackDirect)
  for (const int32_t m : ShootsAs(mesh_, shooter)) {
    if (times_shot_[p] == 0) ka += mesh_.Emission(mesh_.faces[mesh_.patches[m].face]) * patch_[m].area;
    // A shooter that sees no element sends its light out of the scene:
    // its unshot radiosity is spent, and it is never chosen again (nothing
    // can send it light either, by reciprocity).
    if (column.empty()) patch_[m].blind = 1;
    const glm::dvec3 x = column.empty() ? patch_[m].unshot : ToShoot(m);
    abs_sum_ -= Abs(patch_[m].unshot) * patch_[m].area;
    patch_[m].unshot -= x;
    abs_sum_ += Abs(patch_[m].unshot) * patch_[m].area;
    unshot_sum_ -= x * patch_[m].area;
    xa += x * patch_[m].area;
  }
  // Power arriving at element e and reflected: ρ_e · x · F · A_shooter.
  // Per element only B changes, by that over A_e; a patch's unshot
  // radiosity gains the same summed over its elements, and since they
  // share one ρ it is enough to sum F per patch here (the master's
  // per-shot cost bounds the speedup, paper graph 2).
  // Ids increase along a column: the last is the largest.
  CHECK(column.empty() || size_t(column.back().elem) < patch_of_.size());
  // At 10^5 elements and more the arrays are far larger than the caches
  // and a column's elements are sparse in them: each element would wait
  // for memory (~100 ns). Fetched kAhead elements early, it does not
  // (32: at a few ns an element, 16 ahead was less time than memory takes
  // on a loaded machine; 48 measured no better). Arrays that fit in this
  // core's second-level cache are not fetched early: there the fetches
  // cost only their instructions (radiosity-master, R 256, L2 of 1 MiB:
  // on the room, 190 KB, shooting took 11.0 and 10.4 us a shot with them,
  // 8.9 and 9.0 without; at 640 KB the same or 10% less without (two
  // runs); at 1.45 MB 7% less with them).
  constexpr size_t kAhead = 32;
  const bool ahead = elem_.size() * (sizeof(ElemShot) + sizeof(int32_t)) +
                         patch_.size() * sizeof(PatchShot) > SecondLevelCacheBytes();
  const FormFactor* col = column.data();
  const size_t n = column.size();
  const bool noisy = pixel_ff_ > 0;
  if (Abs(ka) > 0) --dark_emitters_;  // its first shot (blind or not)
  const bool direct = track_direct_ && Abs(ka) > 0;
  // Where the hemicube looked from (Hemicube::Column), for the noise: each
  // element's direction is taken as its patch centre's.
  const glm::dvec3 from = group ? group->center : mesh_.patch_center[size_t(p)];
  const glm::dvec3 axis = group ? group->normal : mesh_.faces[mesh_.patches[p].face].normal;
  // A receiving patch's pixel delta form factor, once per run of its
  // elements in the column (they are mostly neighbours in id), and again
  // where it comes back after others: kept per patch in an array, its
  // line was one more to wait for per patch at 10^5 patches.
  int32_t pixel_q = -1;
  double pixel_df = 0;
  auto pixel = [&](int32_t q) {
    if (q != pixel_q) {
      const glm::dvec3 d = mesh_.patch_center[size_t(q)] - from;
      const double len = glm::length(d);
      pixel_df = PixelFormFactor(pixel_ff_, len > 0 ? glm::dot(d, axis) / len : 0.0);
      pixel_q = q;
    }
    return pixel_df;
  };
  // Each patch reached is listed at its first form factor (its fsum still
  // 0) without a branch: written always, counted only then (whether an
  // element is its patch's first is data, a branch mispredicted often).
  // Room for every patch and, should a sum stay 0, every form factor.
  if (touched_.size() < patch_.size() + n) touched_.resize(patch_.size() + n);
  int32_t* const touched = touched_.data();
  if (stale_.size() < n) stale_.resize(n);
  uint32_t* const stale_at = stale_.data();
  // The arrays as local pointers: as members they were loaded again at
  // every element (a store through one of them might, for all the compiler
  // knows, have changed another).
  ElemShot* const elem = elem_.data();
  PatchShot* const patch = patch_.data();
  const int32_t* const patch_of = patch_of_.data();
  const Mesh::Material* const mats = mesh_.materials.data();
  // The loop over the column, once without what only subdivision needs
  // (noise, first light, the changed list: off unless the run divides) and
  // once with it, so that the common loop tests none of it per element.
  // The same operations on B and Σ F in the same order either way.
  auto elements = [&](auto extras, auto fetch_ahead) {
    constexpr bool kExtras = decltype(extras)::value;
    constexpr bool kAheadOn = decltype(fetch_ahead)::value;
    size_t reached = 0, stale = 0;
    // Its patch's record (ρ, Σ F: one line) is fetched kAhead early too,
    // from its patch id fetched 2 kAhead early.
    for (size_t i = 0; i < n; ++i) {
      if (kAheadOn && i + 2 * kAhead < n)
        __builtin_prefetch(&patch_of[size_t(col[i + 2 * kAhead].elem)]);
      if (kAheadOn && i + kAhead < n) {
        const int32_t a = col[i + kAhead].elem;
        __builtin_prefetch(&elem[size_t(a)], 1);
        const int32_t qa = patch_of[size_t(a)];
        if (qa >= 0) __builtin_prefetch(&patch[size_t(qa)], 1);
        if (kExtras) {
          // And what only a dividing run reads: the noise and the patch's
          // centre (for its pixels' form factor); the changed bits stay in
          // the caches.
          if (noisy) __builtin_prefetch(&noise_[size_t(a)], 1);
          if (noisy && qa >= 0) __builtin_prefetch(&mesh_.patch_center[size_t(qa)]);
        }
      }
      const int32_t e = col[i].elem;
      const int32_t q = patch_of[e];
      // Divided since the column was computed: after the loop, so that
      // the loop calls nothing (a call made it keep its values on the
      // stack, and load them again at every element).
      if (q < 0) {
        stale_at[stale++] = uint32_t(i);
        continue;
      }
      const double f = double(col[i].f);
      // ρ/A from the patch's ρ and the element's 1/A here rather than a
      // copy per element (24 bytes an element). 1/A is the solver's copy
      // beside B (elem_), not Mesh::elem_area, another cache line each.
      const glm::dvec3 w = (f * elem[size_t(e)].inv_area) * mats[patch[size_t(q)].material].rho;
      const glm::dvec3 gain = xa * w;
      elem[e].b += gain;
      if (kExtras) {
        if (direct) direct_[e] += float(Lum(ka * w));
        if (noisy) noise_[e] += ShotNoise(Lum(gain), f, pixel(q));
        if (track_) Changed(e);
      }
      touched[reached] = q;
      reached += patch[q].fsum == 0;
      patch[q].fsum += f;
    }
    for (size_t k = 0; k < stale; ++k) {  // each leaf gains alike
      const size_t i = stale_at[k];
      const int32_t e = col[i].elem;
      const int32_t q = ~patch_of[e];
      const double f = double(col[i].f);
      mesh_.LeavesUnder(e, &leaves_);
      const glm::dvec3 w = (f * elem[size_t(e)].inv_area) * mats[patch[size_t(q)].material].rho;
      const glm::dvec3 gain = xa * w;
      const double var = noisy ? ShotNoise(Lum(gain), f, pixel(q)) : 0;
      const float first = direct ? float(Lum(ka * w)) : 0.0f;
      bool one_patch = true;
      for (int l : leaves_) {
        elem[l].b += gain;
        if (direct) direct_[l] += first;
        if (noisy) noise_[l] += var;
        if (track_) Changed(l);
        one_patch &= patch_of[size_t(l)] == q;
      }
      if (one_patch) {
        touched[reached] = q;
        reached += patch[q].fsum == 0;
        patch[q].fsum += f;
        continue;
      }
      for (int l : leaves_) {  // and split since: each piece reflects its leaves' share
        const int32_t r = patch_of[size_t(l)];
        touched[reached] = r;
        reached += patch[r].fsum == 0;
        patch[r].fsum += f * (mesh_.elem_area[size_t(l)] / mesh_.elem_area[size_t(e)]);
      }
    }
    return reached;
  };
  auto with = [&](auto extras) {
    return ahead ? elements(extras, std::true_type()) : elements(extras, std::false_type());
  };
  const size_t reached = noisy || direct || track_ ? with(std::true_type()) : with(std::false_type());
  queue_.Expect(reached + 1);
  // The running sums in locals: as members, every patch's byte stores
  // (the lit flag) and the queue's calls made them a load and a store each, a
  // chain of store-to-load waits through the loop. The same operations
  // in the same order: the same bits.
  double abs_sum = abs_sum_;
  glm::dvec3 unshot_sum = unshot_sum_;
  for (size_t i = 0; i < reached; ++i) {
    if (ahead && i + kAhead < reached) {
      const size_t a = size_t(touched[i + kAhead]);
      __builtin_prefetch(&patch_[a], 1);
      queue_.Prefetch(int(a));
    }
    const int32_t q = touched[i];
    const glm::dvec3 reflected = mats[patch_[q].material].rho * xa * patch_[q].fsum;
    patch_[q].fsum = 0;
    patch_[q].lit |= Abs(reflected) > 0;
    if (patch_[q].blind) continue;  // a hemicube speck: it could not pass it on
    abs_sum -= Abs(patch_[q].unshot) * patch_[q].area;
    patch_[q].unshot += reflected * patch_[q].inv_area;
    abs_sum += Abs(patch_[q].unshot) * patch_[q].area;
    unshot_sum += reflected;
    // Light reaching a group's member moves its group's key, once a shot.
    const int32_t g = patch_[q].group;
    if (g < 0) {  // a shooter alone and not blind: its bound is its own
      queue_.Set(q, PatchBound(q));
    } else if (!group_dirty_[size_t(g)]) {
      group_dirty_[size_t(g)] = 1;
      dirty_groups_.push_back(g);
    }
  }
  abs_sum_ = abs_sum;
  unshot_sum_ = unshot_sum;
  for (int32_t g : dirty_groups_) {
    group_dirty_[size_t(g)] = 0;
    const int key = mesh_.groups[size_t(g)].members[0];
    queue_.Set(key, Bound(key));
  }
  dirty_groups_.clear();
  queue_.Set(p, Bound(p));
  ++times_shot_[p];
  // The running sums drift by rounding; a full sum every sweep bounds it.
  if (++shots_ % long(patch_.size()) == 0) Resum();
}

void Solver::TakeChanged(std::vector<int32_t>* out) {
  track_ = true;
  out->swap(changed_);
  changed_.clear();
  for (int32_t e : *out) changed_bits_[size_t(e) / 64] = 0;
}

void Solver::Divided(const std::vector<int32_t>& elems) {
  Grow();
  for (int32_t p : elems)
    for (int k = 0; k < kChildren; ++k) {
      elem_[mesh_.elems[p].first_child + k].b = elem_[p].b;
      // What they have is the parent's, and so is its error.
      if (pixel_ff_ > 0) noise_[mesh_.elems[p].first_child + k] = noise_[p];
      if (track_direct_) direct_[mesh_.elems[p].first_child + k] = direct_[p];
      if (track_) Changed(mesh_.elems[p].first_child + k);
    }
  // Fitted to the values as they are now (elements divided in this pass
  // hold their parent's), so the order of `elems` does not matter.
  std::vector<glm::dvec3> shaped(kChildren * elems.size());
  std::vector<int> nb, around;
  for (size_t i = 0; i < elems.size(); ++i) {
    const int p = elems[i];
    const Element& pe = mesh_.elems[p];
    const glm::dvec3 bp = elem_[p].b;
    // The parent's neighbours: its children's, less their siblings.
    around.clear();
    for (int k = 0; k < kChildren; ++k) {
      LeafNeighbours(mesh_, pe.first_child + k, &nb);
      for (int n : nb)
        if (mesh_.parent[size_t(n)] != p && std::find(around.begin(), around.end(), n) == around.end())
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
      mean += mesh_.elem_area[size_t(c)] * cc[k];
      area += mesh_.elem_area[size_t(c)];
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
      r1 += dx * (elem_[n].b - bp);
      r2 += dy * (elem_[n].b - bp);
      lo = glm::min(lo, elem_[n].b);
      hi = glm::max(hi, elem_[n].b);
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
      elem_[mesh_.elems[elems[i]].first_child + k].b = shaped[kChildren * i + k];
}

void Solver::Split(int p) {
  const size_t from = patch_.size(), n = mesh_.patches.size();
  const double whole = patch_[size_t(p)].area;
  const glm::dvec3 power = patch_[size_t(p)].unshot * whole;
  const PatchShot piece = patch_[size_t(p)];  // what every piece inherits: ρ, the flags
  std::vector<int> pieces{p};
  for (size_t q = from; q < n; ++q) pieces.push_back(int(q));
  const MeshFace& face = mesh_.faces[size_t(mesh_.patches[size_t(p)].face)];
  const glm::dvec3 &kd = mesh_.Rho(face), &ke = mesh_.Emission(face);
  // The room the mesh has for a pass's pieces (ReserveSplits), taken at
  // once rather than doubled split by split.
  if (mesh_.patches.capacity() > patch_.capacity()) {
    const size_t room = mesh_.patches.capacity();
    patch_.reserve(room), weight_.reserve(room);
    times_shot_.reserve(room);
  }
  patch_.resize(n);
  for (size_t q = from; q < n; ++q) {
    patch_[q].material = piece.material;
    patch_[q].group = -1;  // a grouped patch is never split (split.cpp)
    patch_[q].lit = piece.lit;
    patch_[q].blind = piece.blind;
  }
  weight_.resize(n);
  times_shot_.resize(n, 0);
  // What each piece's leaves received, per channel, and the pieces' own
  // elements, divided ones complemented as Grow() keeps them.
  std::vector<glm::dvec3> got(pieces.size(), glm::dvec3(0.0));
  glm::dvec3 total(0.0);
  for (size_t i = 0; i < pieces.size(); ++i) {
    const int q = pieces[i];
    patch_[size_t(q)].SetArea(mesh_.patch_area[size_t(q)]);
    weight_[size_t(q)] = patch_[size_t(q)].area * std::max({kd.r, kd.g, kd.b});
    const IdSpan tops = mesh_.Tops(q);
    std::vector<int> stack(tops.begin(), tops.end());
    while (!stack.empty()) {
      const int e = stack.back();
      stack.pop_back();
      const Element& el = mesh_.elems[size_t(e)];
      if (!el.IsLeaf()) {
        patch_of_[size_t(e)] = ~q;
        for (int k = 0; k < kChildren; ++k) stack.push_back(el.first_child + k);
        continue;
      }
      patch_of_[size_t(e)] = q;
      got[i] += glm::max(elem_[size_t(e)].b - ke, glm::dvec3(0.0)) * mesh_.elem_area[size_t(e)];
    }
    total += got[i];
  }
  // Shares per channel; the last piece takes what the others left, so
  // that the shares' powers sum to p's as closely as doubles allow.
  glm::dvec3 left = power;
  for (size_t i = 0; i < pieces.size(); ++i) {
    const int q = pieces[i];
    glm::dvec3 share;
    for (int c = 0; c < 3; ++c)
      share[c] = total[c] > 0 ? got[i][c] / total[c] : patch_[size_t(q)].area / whole;
    glm::dvec3 part = i + 1 < pieces.size() ? power * share : left;
    left -= part;
    patch_[size_t(q)].unshot = part / patch_[size_t(q)].area;
  }
  splits_pending_ = true;
}

void Solver::SplitsDone() {
  Resum();
  Rebase();
  splits_pending_ = false;
}

std::vector<glm::dvec3> Solver::TakeRadiosity() {
  FreeStorage(&patch_of_), FreeStorage(&patch_), FreeStorage(&touched_);
  FreeStorage(&changed_bits_), FreeStorage(&noise_), FreeStorage(&direct_);
  FreeStorage(&changed_), FreeStorage(&times_shot_);
  FreeStorage(&weight_), FreeStorage(&group_dirty_), FreeStorage(&dirty_groups_), FreeStorage(&leaves_);
  queue_ = ShooterQueue();
  std::vector<glm::dvec3> b = radiosity();
  FreeStorage(&elem_);
  return b;
}

SolverState Solver::State() const {
  SolverState s;
  s.b = radiosity();
  s.unshot = unshot();
  s.lit.resize(patch_.size());
  s.blind.resize(patch_.size());
  for (size_t p = 0; p < patch_.size(); ++p) {
    s.lit[p] = patch_[p].lit;
    s.blind[p] = patch_[p].blind;
  }
  s.times_shot.assign(times_shot_.begin(), times_shot_.end());
  s.noise = noise_;
  s.direct = direct_;
  s.unshot_sum = unshot_sum_;
  s.abs_sum = abs_sum_;
  s.shots = shots_;
  return s;
}

bool Solver::Restore(const SolverState& s, std::string* err) {
  const size_t np = mesh_.patches.size();
  if (s.b.size() != mesh_.elems.size() || s.unshot.size() != np || s.lit.size() != np ||
      s.blind.size() != np || s.times_shot.size() != np ||
      (!s.noise.empty() && s.noise.size() != mesh_.elems.size()) ||
      (!s.direct.empty() && s.direct.size() != mesh_.elems.size())) {
    *err = "solver state of " + std::to_string(s.b.size()) + " elements and " +
           std::to_string(s.unshot.size()) + " patches, the mesh has " +
           std::to_string(mesh_.elems.size()) + " and " + std::to_string(np);
    return false;
  }
  // The mesh was divided and split since the constructor: every element's
  // patch again, the patches' arrays for their count.
  patch_of_.clear();
  Grow();
  PatchArrays();
  for (size_t e = 0; e < elem_.size(); ++e) elem_[e].b = s.b[e];
  for (size_t p = 0; p < np; ++p) {
    patch_[p].unshot = s.unshot[p];
    patch_[p].lit = s.lit[p];
    patch_[p].blind = s.blind[p];
  }
  times_shot_.assign(s.times_shot.begin(), s.times_shot.end());
  noise_ = s.noise;
  direct_ = s.direct;
  if (track_direct_) direct_.resize(elem_.size(), 0.0f);
  unshot_sum_ = s.unshot_sum;
  abs_sum_ = s.abs_sum;
  shots_ = s.shots;
  CountDarkEmitters();
  Rebase();
  return true;
}

double Solver::UnshotFraction() const {
  if (emitted_ == 0) return 0;
  return std::max(0.0, abs_sum_) / emitted_;
}

double Solver::PowerRatio() const {
  if (emitted_ == 0) return 0;
  double s = 0;
  for (size_t e = 0; e < elem_.size(); ++e) {
    const glm::dvec3& b = elem_[e].b;
    if (mesh_.elems[e].IsLeaf()) s += (b.r + b.g + b.b) * mesh_.elem_area[e];
  }
  return s / emitted_;
}

void Solver::ShotLines(const std::vector<FormFactor>& column, std::vector<const char*>* written,
                       std::vector<const char*>* read) const {
  std::vector<const void*> w, r;
  for (const FormFactor& ff : column) {
    const size_t e = size_t(ff.elem);
    w.push_back(&elem_[e]);
    r.push_back(&patch_of_[e]);
    // From the mesh, so that listing them reads none of the lines (a
    // divided element counts its patch only, not its leaves').
    const int32_t q = mesh_.elems[e].patch;
    w.push_back(&patch_[size_t(q)]);
    queue_.Touches(q, &w, &r);
  }
  auto lines = [](const std::vector<const void*>& at, std::vector<const char*>* out) {
    out->clear();
    for (const void* a : at)
      out->push_back(reinterpret_cast<const char*>(reinterpret_cast<uintptr_t>(a) & ~uintptr_t(63)));
    std::sort(out->begin(), out->end());
    out->erase(std::unique(out->begin(), out->end()), out->end());
  };
  lines(w, written);
  std::vector<const char*> all;
  lines(r, &all);
  read->clear();
  std::set_difference(all.begin(), all.end(), written->begin(), written->end(), std::back_inserter(*read));
}
