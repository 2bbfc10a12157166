#include "subdivide.h"

#include <algorithm>
#include <cmath>

#include "check.h"
#include "float_round.h"

namespace {


// Standard deviations of pixel noise a difference must pass to count
// (subdivide.h).
constexpr double kNoiseSigmas = 3.5;

// How far (relative) a leaf's luminance may move from where it was synced
// before it counts as moved (Pass): 1/16 leaves a factor bound of about
// 0.13 on an evenly lit face, under the floor threshold 0.2, and a leaf
// that gains light steadily moves about once per 6% gained (1/32 and 1/8
// evaluated about as many leaves on boxes1000, by neighbours of the moved
// and by looser bounds respectively).
constexpr double kDrift = 1.0 / 16;

// Subdivider::eligible_'s bits: a leaf; one that may be divided; one the
// lit scene's mean counts (a leaf that does not emit; its area is read
// from the mesh, not kept: 8 bytes an element).
constexpr uint8_t kLeaf = 1, kEligible = 2, kLit = 4;

double ShortestEdge(const Mesh& m, const Element& e) {
  const int n = e.IsTriangle() ? 3 : 4;
  double l = HUGE_VAL;
  for (int k = 0; k < n; ++k) l = std::min(l, glm::length(m.verts[e.v[(k + 1) % n]] - m.verts[e.v[k]]));
  return l;
}

}  // namespace

Subdivider::Subdivider(Mesh* mesh, const SubdivideOptions& opts)
    : opts_(opts), threshold_(opts.threshold), split_threshold_(opts.split_threshold) {
  CHECK(opts_.between >= 10 && opts_.floor > 0 && opts_.threshold >= opts_.floor);
  CHECK(opts_.split_floor > 0 && opts_.split_threshold >= opts_.split_floor);
  if (!(opts_.min_size > 0)) opts_.min_size = mesh->scene_diagonal / 400;
  // The radiosity is worth dividing by once every light source has shot
  // (paper §4.3: 20 to 50 shots; more lights, later), scaled to the scene.
  long emitters = 0;
  for (const Patch& p : mesh->patches) {
    const glm::dvec3& ke = mesh->Emission(mesh->faces[p.face]);
    if (ke.r + ke.g + ke.b > 0) ++emitters;
  }
  first_ = std::max(std::clamp(long(mesh->patches.size()) / 20, 20L, 50L), emitters);
  StartWave(*mesh);
}

bool Subdivider::Due(long shots) const {
  return !finished_ && shots >= first_ && (last_pass_ < 0 || shots - last_pass_ >= opts_.between);
}

// The per-element caches for elements added since (the children of
// divided elements; all of them after Restore or at a new wave), and the
// divided parents out of them.
void Subdivider::Track(const Mesh& mesh) {
  const size_t from = eligible_.size(), n = mesh.elems.size();
  eligible_.resize(n);
  synced_.resize(n, NAN);
  bound_.resize(n, 0);
  at_pass_.resize(n, -1);
  mark_.resize(n, 0);
  for (size_t e = from; e < n; ++e) {
    const Element& el = mesh.elems[e];
    const glm::dvec3& ke = mesh.Emission(mesh.FaceOf(int(e)));
    eligible_[e] = el.IsLeaf() ? kLeaf : 0;
    if (el.IsLeaf() && el.level < opts_.max_level && ShortestEdge(mesh, el) / 2 >= opts_.min_size)
      eligible_[e] |= kEligible;
    if (el.IsLeaf() && !(ke.r + ke.g + ke.b > 0)) eligible_[e] |= kLit;
    const int parent = mesh.parent[e];
    if (parent >= 0 && size_t(parent) < from) eligible_[size_t(parent)] = 0;
  }
}

// How much a factor computed at pass k of this wave may have grown with
// the radiosity as it was: each of its terms is c / (s + U) with s >= 0
// (else the factor was not bounded) and U = Lum(Kd·ambient) + 0.2·mean,
// so c / (s + U') <= c / (s + U) · max(1, U / U'), and U / U' is at most
// the largest ratio of the parts of U (all >= 0): per channel the ambient
// (Kd cancels), and the mean. +inf when a part is negative or one that
// was there is gone.
double Subdivider::PassBound(int k, const glm::dvec3& ambient, double mean) const {
  double r = 1;
  auto part = [&r](double was, double now) {
    if (was < 0 || now < 0) r = HUGE_VAL;
    else if (was > 0) r = std::max(r, now > 0 ? was / now : HUGE_VAL);
  };
  for (int c = 0; c < 3; ++c) part(pass_ambient_[size_t(k)][c], ambient[c]);
  part(pass_mean_[size_t(k)], mean);
  return r;
}

// The dividing factor of leaf e (subdivide.h), and in *bound the largest
// it can be with every luminance within its synced value's tolerance
// (synced_, kDrift) and this scale's shared part; +inf where PassBound
// does not hold (a term's s < 0, or no positive scale).
double Subdivider::Factor(const Mesh& mesh, const ElemB& b,
                          const std::vector<double>& noise, const glm::dvec3& ambient,
                          double mean, int e, double* bound) {
  std::vector<int>& nb = nb_;
  const Element& el = mesh.elems[size_t(e)];
  LeafNeighbours(mesh, e, &nb);
  const double unsure = Lum(mesh.Rho(mesh.FaceOf(e)) * ambient) + 0.2 * mean;
  const glm::dvec3 c = mesh.Centroid(e);
  const double size = std::sqrt(mesh.elem_area[size_t(e)]), be = Lum(b[size_t(e)]);
  const double se = synced_[size_t(e)], te = kDrift * std::abs(se);
  double factor = 0, most = 0;
  for (int m : nb) {
    const double dist = glm::length(mesh.Centroid(m) - c);
    const double bm = Lum(b[size_t(m)]);
    const double scale = std::max(be, bm) + unsure;
    if (!(dist > 0)) continue;
    const double sm = synced_[size_t(m)], tm = kDrift * std::abs(sm);
    // The least max(B_e, B_n) and the largest difference within tolerance.
    const double low = std::max(se - te, sm - tm), wide = std::abs(se - sm) + te + tm;
    // (B itself out of tolerance: a luminance a float cannot keep.)
    if (!(low >= 0) || !(low + unsure > 0) || !(std::abs(be - se) <= te) || !(std::abs(bm - sm) <= tm))
      most = HUGE_VAL;
    if (!(scale > 0)) continue;
    const double finer = 1 + 0.5 * std::max(0, mesh.elems[size_t(m)].level - el.level);
    // A difference the hemicube's pixels could have made is no light's.
    const double gate = noise.empty() ? -1 : kNoiseSigmas * std::sqrt(noise[size_t(e)] + noise[size_t(m)]);
    const double diff = std::abs(be - bm);
    const double light = diff > gate ? diff : 0;
    factor = std::max(factor, light / dist * size / scale * finer);
    // The gate only rises (V adds up): one the widest difference cannot
    // pass now, it never will.
    if (wide > gate && most < HUGE_VAL) most = std::max(most, wide / dist * size / (low + unsure) * finer);
  }
  *bound = most;
  return factor;
}

std::vector<int32_t> Subdivider::Pass(const Mesh& mesh, const ElemB& b,
                                      const std::vector<double>& noise,
                                      const glm::dvec3& ambient, long shots,
                                      const std::vector<int32_t>& changed) {
  last_pass_ = shots;
  ++passes_;
  const size_t n = mesh.elems.size();
  CHECK(b.size() == n && (noise.empty() || noise.size() == n));
  Track(mesh);
  // The leaves whose luminance left its synced value's tolerance (new
  // ones: NaN), synced again: found from the changed list when it is short,
  // else in the scan of every leaf that sums the lit scene's mean (a scan
  // in order is cheaper than a long list in the order shots touched them).
  const int pass = int(pass_mean_.size());
  const bool scan = !opts_.incremental || pass == 0 || 8 * changed.size() > n;
  std::vector<int32_t> moved;
  auto sync = [&](size_t e) {
    const double l = Lum(b[e]), s = synced_[e];
    if (std::abs(l - s) <= kDrift * std::abs(s)) return;
    synced_[e] = float(l);
    moved.push_back(int32_t(e));
  };
  if (!scan)
    for (int32_t e : changed)
      if (size_t(e) < n && eligible_[size_t(e)] & kLeaf) sync(size_t(e));  // not divided since
  double sum = 0, area = 0;  // the lit scene's mean: the absolute part of the scale
  for (size_t e = 0; e < n; ++e) {
    if (scan && eligible_[e] & kLeaf) sync(e);
    if (!(eligible_[e] & kLit)) continue;
    const double a = mesh.elem_area[e];
    sum += Lum(b[e]) * a;
    area += a;
  }
  const double mean = area > 0 ? sum / area : 0;

  // The leaves to evaluate, marked: every one at a wave's first pass (or
  // without `incremental`); else those moved, their neighbours, the new,
  // and those whose bound reaches the threshold. Evaluated in id order.
  std::vector<int32_t> todo;
  std::vector<int> nb;
  auto want = [&](int32_t e) {
    if (eligible_[size_t(e)] & kEligible && !mark_[size_t(e)]) {
      mark_[size_t(e)] = 1;
      todo.push_back(e);
    }
  };
  // Moved leaves and their neighbours take two neighbour searches each:
  // when a quarter of the leaves moved, evaluating all is cheaper.
  if (!opts_.incremental || pass == 0 || 4 * long(moved.size()) > mesh.LeafCount()) {
    for (size_t e = 0; e < n; ++e) want(int32_t(e));
  } else {
    for (int32_t e : moved) {
      want(e);
      LeafNeighbours(mesh, e, &nb);
      for (int m : nb) want(m);
    }
    std::vector<double> grow(static_cast<size_t>(pass));
    for (int k = 0; k < pass; ++k) grow[size_t(k)] = PassBound(k, ambient, mean) * (1 + 1e-9);
    for (size_t e = 0; e < n; ++e) {
      if (!(eligible_[e] & kEligible) || mark_[e]) continue;
      const int k = at_pass_[e];
      if (k < 0 || !(double(bound_[e]) * grow[size_t(k)] <= threshold_)) want(int32_t(e));
    }
    std::sort(todo.begin(), todo.end());
  }
  pass_ambient_.push_back(ambient);
  pass_mean_.push_back(mean);
  evaluated_ = long(todo.size());

  std::vector<int32_t> out;
  for (int32_t e : todo) {
    double bound;
    const double factor = Factor(mesh, b, noise, ambient, mean, e, &bound);
    bound_[size_t(e)] = FloatUp(bound);
    at_pass_[size_t(e)] = pass;
    if (factor > threshold_) out.push_back(e);
    else mark_[size_t(e)] = 0;  // marks left: the chosen, for grading
  }
  // Graded: a coarser neighbour of a leaf being divided is divided too, or
  // levels two apart would meet (a T-vertex on a T-vertex).
  for (size_t i = 0; i < out.size(); ++i) {
    LeafNeighbours(mesh, out[i], &nb);
    for (int m : nb)
      if (!mark_[size_t(m)] && mesh.elems[m].level < mesh.elems[out[i]].level) {
        mark_[size_t(m)] = 1;
        out.push_back(m);
      }
  }
  std::sort(out.begin(), out.end(), [&](int32_t a, int32_t c) {
    const int la = mesh.elems[a].level, lc = mesh.elems[c].level;
    return la != lc ? la < lc : a < c;
  });
  for (int32_t e : out) mark_[size_t(e)] = 0;
  // A pass that finds only a few (the radiosity still settling, hemicube
  // noise) is quiet: at the floor, subdivision is finished, and the few are
  // not worth a wave of their own.
  quiet_ = double(out.size()) < opts_.quiet * double(wave_start_leaves_);
  if (quiet_ && threshold_ <= opts_.floor) {
    finished_ = true;
    out.clear();
  }
  // The element cap (memory, and ids that fit the protocol's int32): the
  // whole pass or nothing, so grading is never left half done.
  if (long(n) + kChildren * long(out.size()) > opts_.max_elements) {
    finished_ = capped_ = true;
    out.clear();
  }
  divided_in_wave_ += long(out.size());
  threshold_ = std::max(opts_.floor, threshold_ * opts_.decay);
  return out;
}

bool Subdivider::WaveOver(bool converged) const {
  return opts_.waves && divided_in_wave_ > 0 &&
         (converged || quiet_ || double(divided_in_wave_) >= opts_.wave_fraction * wave_start_leaves_);
}

void Subdivider::StartWave(const Mesh& mesh) {
  // The radiosity starts again: the wave's first pass evaluates every leaf.
  pass_ambient_.clear();
  pass_mean_.clear();
  measured_ = false;
  wave_start_leaves_ = mesh.LeafCount();
  divided_in_wave_ = 0;
  last_pass_ = -1;
  quiet_ = false;
}

SubdividerState Subdivider::State() const {
  SubdividerState s;
  s.threshold = threshold_;
  s.split_threshold = split_threshold_;
  s.splits = splits_;
  s.last_pass = last_pass_;
  s.wave_start_leaves = wave_start_leaves_;
  s.divided_in_wave = divided_in_wave_;
  s.finished = finished_;
  s.quiet = quiet_;
  s.passes = passes_;
  s.seconds = seconds_;
  s.measured = measured_;
  s.direct_mean = direct_mean_;
  s.spread = spread_;
  s.near = near_;
  return s;
}

void Subdivider::Restore(const SubdividerState& s) {
  // The mesh was divided since: every cache again, every leaf evaluated.
  eligible_.clear();
  synced_.clear();
  pass_ambient_.clear();
  pass_mean_.clear();
  measured_ = s.measured;
  direct_mean_ = s.direct_mean;
  spread_ = s.spread;
  near_ = s.near;
  threshold_ = s.threshold;
  split_threshold_ = s.split_threshold;
  splits_ = s.splits;
  last_pass_ = s.last_pass;
  wave_start_leaves_ = s.wave_start_leaves;
  divided_in_wave_ = s.divided_in_wave;
  finished_ = s.finished;
  quiet_ = s.quiet;
  passes_ = s.passes;
  seconds_ = s.seconds;
}
