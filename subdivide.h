// The subdivision policy (paper §4.3) and the bookkeeping of waves (§4.4):
// which leaf elements to divide in one pass, when a pass is due and when a
// wave is over. It reads the mesh and the solver's radiosity and divides
// nothing itself: the run loop applies Divide() to what a pass returns, in
// that order, and so can ship the same edits to workers.
//
// Dividing factor of a leaf e, the largest over its neighbours n across
// shared edges (same face):
//
//   |B_e - B_n| / dist(e, n) * size(e) / scale  *  (1 + (level_n - level_e) / 2)
//
// where |B_e - B_n| > 3.5 sqrt(V_e + V_n), else 0; luminance (channels
// averaged); size(e) = sqrt(area); the last term only for finer
// neighbours. scale = max(B_e, B_n) + Kd·ambient + 0.2 × the mean
// B of the lit scene: relative contrast where it is bright, absolute where
// it is dark, and never above what the light still unshot (the ambient
// term) may change.
//
// V is the variance of an element's B from the hemicube's pixels
// (Solver::TrackNoise): division is by light, not by what the hemicube at
// this resolution cannot resolve. A shot gives an element g = x·ρ·F·A_s/A_e
// for a form factor F summed over the n pixels whose centres fall in its
// projection, n = F / δF with δF the delta form factor of a pixel in its
// direction. Turned per shot, the hemicube counts those pixels with an
// error: an element under 4/9 pixel is hit whole or missed (Bernoulli,
// Var(n) = n(1 - n) <= n); a larger one gains or loses the pixels its
// outline crosses, about its perimeter 4 sqrt(n), each in with a chance
// uniform in 0..1 (variance 1/6 each): Var(n) = (2/3) sqrt(n). So the shot
// adds g² · min(1/n, (2/3) n^-3/2) to V. Measured over 64 turns of the
// Cornell box's light at R 64 and 256: the spread of F is 0.5 to 1 times
// the model's for n = 0.3 .. 40 (it errs toward dividing less: straight
// outlines lose and gain fewer pixels than random ones) and 1.7 times at
// n = 150, where it is 3% of F, far under any threshold.
// Shots are turned independently and add their variances; a divided
// element's children keep their parent's V (their B is its). The error
// of a difference between neighbours is sqrt(V_e + V_n), and 3.5 of those
// is what noise exceeds for under 1/2000 of the pairs (two-sided normal
// tail; a count's error is bounded, lighter-tailed than that): with about
// four neighbours each, under the 0.2% of the leaves that makes a pass
// quiet. A difference beyond it is light, and counts in full: a gate, not
// a discount, so that an edge resolved at R 128 and at R 256 is divided
// alike at both (a discount of 3.5 sigma left the Cornell box with holes
// at 3045 elements at R 128, 4401 at R 256; the gate 4509 and 4737). So a
// uniformly lit face is not divided at any resolution, and a coarser
// hemicube divides only the gradients it resolves: at R 64 an element
// 1/16 of its distance across, under the shooter, covers 4 pixels, ±25%
// in one shot, and even a full shadow edge there is at the limit.
//
// Shooter division (SplitPass, split.cpp) is led alike, at the same
// passes: a patch is split into patches, one a piece (SplitPatch), when
//
//  * its light is uneven: it shoots from its centre light that really
//    leaves from its bright part (a table top round the contact shadow of
//    what stands on it). Measured on the light it received first
//    (Solver::direct(): each emitter's first shot of the wave, which
//    depends on the mesh only and not on the order in which columns come
//    back, so that every -j splits alike), once every emitter has shot:
//
//      (max_i D_i - min_i D_i) / (max_i D_i + 0.2 × mean D of the lit scene)
//
//    over its pieces' (SplitPieces: its top elements, or its one top
//    element's children) area-weighted mean direct luminance D_i
//    exceeds the split threshold, lowered by `decay` every pass from then
//    on down to split_floor (measured once a wave even when no division
//    pass is due any more, SplitDue: a later wave's first light tells
//    apart the children of elements divided before it); or
//  * its receivers are close: a top element of another face, in front of
//    it and facing it, has its centroid nearer than split_near × the
//    patch's width (√area) to the patch's centre, where the hemicube at
//    the centre misjudges how it sees the patch (geometry: at the first
//    pass, and for the pieces of a split at the pass after).
//
// Splits of children follow element divisions, which the order of shots
// moves a little. Emitters are never split (their light is their own, not
// received), nor members of shooter groups (groups.h).
#ifndef RADIOSITY_SUBDIVIDE_H
#define RADIOSITY_SUBDIVIDE_H

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "elemb.h"
#include "mesh.h"

struct SubdivideOptions {
  double threshold = 0.5;  // the dividing factor a leaf must exceed, at first
  double floor = 0.2;      // ... lowered by `decay` every pass down to this
  double decay = 0.7;
  double min_size = 0;     // no child's edge shorter; 0: scene diagonal / 400
  int max_level = 2;       // deepest level below the elements BuildMesh made
  bool waves = true;       // restart on the finer mesh after wave_fraction
  double wave_fraction = 0.2;  // of the wave's starting elements divided
  long between = 10;       // shots between passes (at least 10)
  double quiet = 0.002;    // a pass dividing under this fraction of the leaves is quiet
  bool split = true;            // shooter division (SplitPass); --no-split: false
  double split_threshold = 0.9; // the spread a patch must exceed, at first
  double split_floor = 0.8;     // ... lowered by `decay` every pass down to this
  double split_near = 0.35;     // receivers nearer than this × its width split it; 0: never
  // Elements (mesh.elems, divided ones included) a pass may not go past:
  // a pass that would is dropped and subdivision ends (capped()).
  long max_elements = kMaxElements;
  // Evaluate only the leaves whose factor may have passed the threshold
  // (Pass); false: every leaf, every pass (the reference the tests hold
  // the incremental passes to).
  bool incremental = true;
};

// A Subdivider's state between passes (checkpoint.h).
struct SubdividerState {
  double threshold = 0, split_threshold = 0;
  long last_pass = -1, wave_start_leaves = 0, divided_in_wave = 0;
  bool finished = false, quiet = false;
  long passes = 0;
  double seconds = 0;
  long splits = 0;
  // Shooter division's measurements, so that a resumed run splits as the
  // run it continues (each is a function of when it was taken: the
  // pieces made since are measured at the next pass).
  bool measured = false;
  double direct_mean = 0;
  std::vector<double> spread;  // per patch
  std::vector<uint8_t> near;   // per patch
};

class Subdivider {
 public:
  Subdivider(Mesh* mesh, const SubdivideOptions& opts);

  // Whether a pass is due after `shots` shots of the current wave: not
  // before every light source has shot once and 20 to 50 shots (patches /
  // 20), then every `between` shots, until finished().
  bool Due(long shots) const;

  // One pass: the leaves whose dividing factor exceeds the threshold, and
  // the coarser neighbours they force (neighbouring levels stay within
  // one), coarser first. b: radiosity per element; noise: the variance of
  // its luminance from the hemicube's pixels (Solver::noise(); empty:
  // none discounted); ambient: the solver's
  // overshooting estimate (before Kd); changed: the elements whose b
  // changed since the last pass (Solver::TakeChanged; the noise changes
  // where b does). Lowers the
  // threshold.
  //
  // The divisions are those of evaluating every leaf, but a pass evaluates
  // (neighbour search, factor) only the leaves whose factor may have
  // passed the threshold. Each leaf keeps its luminance as of when it was
  // last synced, s, and counts as moved only when its B has left
  // s ± kDrift·|s| (new leaves always): a pass evaluates the moved
  // leaves, their neighbours, new leaves, and those whose bound could
  // have grown past the threshold since. The bound is the largest factor
  // any B within those tolerances gives (noise gate included: V only
  // grows), so it holds until a neighbour moves; with the same
  // tolerances, the factor changes only through the scale's shared part
  // Kd·ambient + 0.2·mean, by at most the ratio of the old shared terms
  // to the new (PassBound). A scan of three numbers per leaf (12 bytes:
  // s and the bound as floats, the pass) finds those; the mean of the lit
  // scene is still summed over every leaf (its area read from the mesh,
  // in order: the same sum). A moved leaf costs two neighbour searches (itself, its
  // neighbours): when over a quarter moved, the pass evaluates every leaf
  // instead. Needs the mesh's edges connected (ConnectEdges) for the
  // neighbour search.
  std::vector<int32_t> Pass(const Mesh& mesh, const ElemB& b,
                            const std::vector<double>& noise, const glm::dvec3& ambient,
                            long shots, const std::vector<int32_t>& changed);
  // The patches to split after the pass just made (call it after Pass and
  // after the divisions are applied and shared, Solver::Divided), in
  // increasing id (above). direct: Solver::direct(); direct_done:
  // Solver::DirectDone(), before which only closeness splits. The spreads
  // are measured once a wave, when direct_done (divisions since give
  // children their parent's direct light: the pieces' means stay), so a
  // resumed run, which measures them at its first pass, splits alike.
  // Lowers the split threshold once the spreads are measured. Empty
  // without opts.split. times_shot: Solver::times_shot(), this wave's
  // shots per patch. A split counts toward ending the wave (WaveOver) only
  // where the patch has already shot in it: one that has not shot loses
  // nothing (its unshot power is shared out exactly and shot from the
  // pieces), so it needs no new wave; one that has shot shot from its
  // centre, which only a new wave redoes.
  std::vector<int32_t> SplitPass(const Mesh& mesh, const std::vector<float>& direct,
                                 bool direct_done, const std::vector<int>& times_shot);
  // SplitPass's closeness search of the patches not yet searched, ahead
  // of it: the first pass searches every patch (0.4 s at 10^6 elements,
  // the workers idle), and its answer depends on the mesh alone. May run
  // on another thread while the mesh does not change and nothing else is
  // called on this subdivider but Due, SplitDue, WaveOver and StartWave,
  // which read and write none of what it does.
  void Prepare(const Mesh& mesh) { FindNear(mesh, near_.size()); }
  long splits() const { return splits_; }
  bool splitting() const { return opts_.split; }
  // A wave's first light is complete and not yet measured: SplitPass is
  // due even where no division pass is (Due), as after the last one.
  bool SplitDue(bool direct_done) const { return opts_.split && direct_done && !measured_; }

  // Leaves whose factor the last pass computed.
  long evaluated() const { return evaluated_; }

  // True when the current wave should end, once it divided anything:
  // wave_fraction of its starting elements divided, or a pass found little
  // more to divide (`quiet`), or the wave `converged`. So
  // waves stay short and the last one solves the final mesh from scratch,
  // with no radiosity in the answer shared out by gradient. Always false
  // without waves.
  bool WaveOver(bool converged = false) const;
  // A new wave starts on `mesh` as it is now.
  void StartWave(const Mesh& mesh);

  // A pass at the floor threshold found little to divide (under `quiet` of
  // the leaves; it then divides nothing): no more passes.
  bool finished() const { return finished_; }
  // Subdivision ended because a pass would have passed max_elements.
  bool capped() const { return capped_; }
  long passes() const { return passes_; }
  // Time spent dividing (policy, Divide, Solver::Divided), as the run
  // loop measured it.
  void CountTime(double seconds) { seconds_ += seconds; }
  double seconds() const { return seconds_; }

  SubdividerState State() const;
  void Restore(const SubdividerState& s);

  // FindNear (split.cpp) streams every top element past the patches it
  // searches when they are fewer than 1/kStreamBelow of them, else grids
  // them: a pass after the first searches the pieces of the last splits,
  // tens or hundreds at 10^6 elements, where gridding every top element
  // took 60-110 ms a pass.
  static constexpr size_t kStreamBelow = 64;
  // A patch FindNear looks for close receivers of: its centre, normal,
  // radius, face and id.
  struct Searcher {
    glm::dvec3 c0, normal;
    double r;
    int32_t face, patch;
  };

 private:
  double Factor(const Mesh& mesh, const ElemB& b,
                const std::vector<double>& noise, const glm::dvec3& ambient, double mean, int e,
                double* bound);
  void Track(const Mesh& mesh);
  double PassBound(int pass, const glm::dvec3& ambient, double mean) const;
  void FindNear(const Mesh& mesh, size_t from);
  void Radii(const Mesh& mesh);
  void StreamNear(const Mesh& mesh, const std::vector<Searcher>& searchers);
  void GridNear(const Mesh& mesh, const std::vector<Searcher>& searchers, size_t count);
  void Spread(const Mesh& mesh, const std::vector<float>& direct, size_t from);

  SubdivideOptions opts_;
  // Per element, grown as the mesh is: is it a leaf, may it be divided (a
  // leaf above max_level, long enough), does the lit mean count it;
  // its luminance when last synced (NaN: never); the bound on its factor
  // as last computed, rounded up, and the pass of this wave that did (-1:
  // none; bound +inf: to be computed every pass, no bound holds).
  std::vector<uint8_t> eligible_;
  std::vector<float> synced_;
  std::vector<float> bound_;
  std::vector<int32_t> at_pass_;
  std::vector<uint8_t> mark_;            // Pass's scratch, all 0 between passes
  std::vector<int> nb_;                  // Factor's scratch
  std::vector<glm::dvec3> pass_ambient_;  // per pass of this wave: its shared terms
  std::vector<double> pass_mean_;
  long evaluated_ = 0;
  double threshold_;
  double split_threshold_;
  // Per patch, for SplitPass: its top elements' brightest and darkest
  // mean direct luminance over the scale (0: not split by light), when
  // measured_ in this wave; whether its receivers are close (near_,
  // found at the first pass; empty: not yet).
  std::vector<double> spread_;
  bool measured_ = false;
  double direct_mean_ = 0;         // the lit scene's mean D when measured
  std::vector<uint8_t> near_;
  // StreamNear's per patch: how far its top elements lie from its centre
  // at most (Radii).
  std::vector<float> radius_;
  std::vector<int> tops_, leaves_; // SplitPass's scratch
  long splits_ = 0;
  long first_ = 0;
  long last_pass_ = -1;       // shot of the last pass in this wave
  long wave_start_leaves_ = 0;
  long divided_in_wave_ = 0;
  bool finished_ = false;
  bool capped_ = false;
  bool quiet_ = false;        // the last pass divided under `quiet` of the leaves
  long passes_ = 0;
  double seconds_ = 0;
};

#endif
