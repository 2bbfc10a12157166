#include "subdivide.h"

#include <algorithm>
#include <cmath>

#include "check.h"

namespace {

double Lum(const glm::dvec3& x) { return (x.r + x.g + x.b) / 3; }

double LongestEdge(const Mesh& m, const Element& e) {
  const int n = e.IsTriangle() ? 3 : 4;
  double l = 0;
  for (int k = 0; k < n; ++k) l = std::max(l, glm::length(m.verts[e.v[(k + 1) % n]] - m.verts[e.v[k]]));
  return l;
}

}  // namespace

Subdivider::Subdivider(Mesh* mesh, const SubdivideOptions& opts)
    : opts_(opts), threshold_(opts.threshold) {
  CHECK(opts_.between >= 10 && opts_.floor > 0 && opts_.threshold >= opts_.floor);
  if (!(opts_.min_size > 0)) opts_.min_size = mesh->scene_diagonal / 400;
  ConnectEdges(mesh);
  // The radiosity is worth dividing by once every light source has shot
  // (paper §4.3: 20 to 50 shots; more lights, later), scaled to the scene.
  long emitters = 0;
  for (const Patch& p : mesh->patches) {
    const glm::dvec3& ke = mesh->faces[p.face].emission;
    if (ke.r + ke.g + ke.b > 0) ++emitters;
  }
  first_ = std::max(std::clamp(long(mesh->patches.size()) / 20, 20L, 50L), emitters);
  StartWave(*mesh);
}

bool Subdivider::Due(long shots) const {
  return !finished_ && shots >= first_ && (last_pass_ < 0 || shots - last_pass_ >= opts_.between);
}

std::vector<int32_t> Subdivider::Pass(const Mesh& mesh, const std::vector<glm::dvec3>& b,
                                      const glm::dvec3& ambient, long shots) {
  last_pass_ = shots;
  ++passes_;
  const size_t n = mesh.elems.size();
  CHECK(b.size() == n);
  double sum = 0, area = 0;  // the lit scene's mean: the absolute part of the scale
  for (size_t e = 0; e < n; ++e) {
    const Element& el = mesh.elems[e];
    const glm::dvec3& ke = mesh.FaceOf(int(e)).emission;
    if (!el.IsLeaf() || ke.r + ke.g + ke.b > 0) continue;
    sum += Lum(b[e]) * el.area;
    area += el.area;
  }
  const double mean = area > 0 ? sum / area : 0;

  std::vector<char> chosen(n, 0);
  std::vector<int32_t> out;
  std::vector<int> nb;
  for (size_t e = 0; e < n; ++e) {
    const Element& el = mesh.elems[e];
    if (!el.IsLeaf() || el.level >= opts_.max_level) continue;
    if (LongestEdge(mesh, el) / 2 < opts_.min_size) continue;
    LeafNeighbours(mesh, int(e), &nb);
    const double unsure = Lum(mesh.FaceOf(int(e)).rho * ambient) + 0.2 * mean;
    const glm::dvec3 c = mesh.Centroid(int(e));
    const double size = std::sqrt(el.area), be = Lum(b[e]);
    double factor = 0;
    for (int m : nb) {
      const double dist = glm::length(mesh.Centroid(m) - c);
      const double bm = Lum(b[m]);
      const double scale = std::max(be, bm) + unsure;
      if (!(dist > 0) || !(scale > 0)) continue;
      const double finer = 1 + 0.5 * std::max(0, mesh.elems[m].level - el.level);
      factor = std::max(factor, std::abs(be - bm) / dist * size / scale * finer);
    }
    if (factor > threshold_) {
      chosen[e] = 1;
      out.push_back(int32_t(e));
    }
  }
  // Graded: a coarser neighbour of a leaf being divided is divided too, or
  // levels two apart would meet (a T-vertex on a T-vertex).
  for (size_t i = 0; i < out.size(); ++i) {
    LeafNeighbours(mesh, out[i], &nb);
    for (int m : nb)
      if (!chosen[m] && mesh.elems[m].level < mesh.elems[out[i]].level) {
        chosen[m] = 1;
        out.push_back(m);
      }
  }
  std::sort(out.begin(), out.end(), [&](int32_t a, int32_t c) {
    const int la = mesh.elems[a].level, lc = mesh.elems[c].level;
    return la != lc ? la < lc : a < c;
  });
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
  wave_start_leaves_ = mesh.LeafCount();
  divided_in_wave_ = 0;
  last_pass_ = -1;
  quiet_ = false;
}

SubdividerState Subdivider::State() const {
  SubdividerState s;
  s.threshold = threshold_;
  s.last_pass = last_pass_;
  s.wave_start_leaves = wave_start_leaves_;
  s.divided_in_wave = divided_in_wave_;
  s.finished = finished_;
  s.quiet = quiet_;
  s.passes = passes_;
  s.seconds = seconds_;
  return s;
}

void Subdivider::Restore(const SubdividerState& s) {
  threshold_ = s.threshold;
  last_pass_ = s.last_pass;
  wave_start_leaves_ = s.wave_start_leaves;
  divided_in_wave_ = s.divided_in_wave;
  finished_ = s.finished;
  quiet_ = s.quiet;
  passes_ = s.passes;
  seconds_ = s.seconds;
}
