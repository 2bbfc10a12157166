// Progressive refinement radiosity's mathematics: choosing shooters,
// shooting with ambient overshooting, handing a divided element's
// radiosity to its children, starting a wave again.
//
// Numbers: radiosity, unshot radiosity, areas and the ambient sums are
// double. Overshooting subtracts nearly equal quantities (unshot minus what
// was shot in advance) and ρ → 1 scenes amplify any error by 1/(1−ρ), so
// float's 7 digits would show in the answer; form factors arrive as float.
#ifndef RADIOSITY_SOLVER_H
#define RADIOSITY_SOLVER_H

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "elemb.h"
#include "hemicube.h"
#include "memory.h"
#include "mesh.h"
#include "shooters.h"

// Everything a Solver holds that is not derived from the mesh: what a
// checkpoint keeps (checkpoint.h) to go on later exactly where it stood.
struct SolverState {
  std::vector<glm::dvec3> b;          // per element (divided ones too)
  std::vector<glm::dvec3> unshot;     // per patch
  std::vector<uint8_t> lit, blind;    // per patch
  std::vector<int32_t> times_shot;    // per patch
  std::vector<double> noise;          // per element, when tracked (TrackNoise)
  std::vector<float> direct;          // per element, when tracked (TrackDirect)
  glm::dvec3 unshot_sum{0.0};         // the running sums as they are, drift
  double abs_sum = 0;                 // included, so that a resumed run
  long shots = 0;                     // makes the same choices bit for bit
};

class Solver {
 public:
  // overshoot: ambient overshooting (Feda & Purgathofer 1992).
  Solver(const Mesh& mesh, bool overshoot);

  // The shooter with the largest power still to shoot (|unshot + overshoot
  // estimate| × area, channels summed; a group's summed over its members;
  // ties to the lowest id) among those not taken, or -1 when there is
  // nothing left to shoot. Shooters are patch ids: a patch alone, or a
  // group's first member for the group (groups.h); other members are
  // never returned, taken or released. Exactly the
  // choice of SelectByScan, found in a ShooterQueue (shooters.h): the
  // overshooting estimate, shared by all patches, is bounded by how far it
  // moved since the queue's bounds were set (Bound, Select).
  int Select();
  // Take(p): p is handed to a worker and not selected until Release(p)
  // (after its shot, or when its worker is lost).
  void Take(int p) { queue_.Take(p); }
  void Release(int p) { queue_.Release(p); }
  bool Taken(int p) const { return queue_.Taken(p); }
  // What Select() ranks shooter p by: its power to shoot now.
  double PowerToShoot(int p) const {
    return ShooterPower(p, overshoot_ ? Ambient() : glm::dvec3(0.0));
  }
  // Select() by looking at every shooter not marked in `taken` (may be
  // null): the reference the queue is tested against.
  int SelectByScan(const std::vector<char>* taken = nullptr) const;

  // Shoots shooter p (a patch, or a group by its first member) along its
  // column. The overshooting estimate is taken here, from the ambient
  // term as it is now (paper §4.2), not when p was selected. The column
  // may predate divisions (a worker computed it before it heard of them):
  // what an element since divided receives goes to every leaf under it
  // alike.
  void Shoot(int p, const std::vector<FormFactor>& column);

  // From now on Shoot also sums, per element, the variance its luminance
  // B has from the hemicube's pixels at resolution R (noise(); what the
  // dividing factor discounts, subdivide.h): the light a shot brings to an
  // element is counted in whole pixels, so it is off by a few pixels'
  // delta form factors, more the fewer pixels the element covers. Costs
  // 8 bytes an element and a little per form factor in Shoot; a run that
  // divides nothing does not call it. Keeps a restored noise().
  void TrackNoise(int resolution);
  // Per element: the variance of its luminance B from the hemicube's
  // pixels (TrackNoise), a divided element's children have their
  // parent's; empty when not tracked.
  const std::vector<double>& noise() const { return noise_; }

  // From now on Shoot also sums, per element, the luminance its first
  // light brings: ρ·Ke·F·A_s/A_e of each emitting shooter's first shot in
  // the wave (direct(); what shooter division measures, split.cpp). It
  // depends on the mesh and the emitters' columns only, not on the order
  // other shots come in, so every run of the scene (any -j) measures the
  // same. Float: it only decides splits against a threshold, and 4
  // bytes an element is what it costs. Keeps a restored direct().
  void TrackDirect();
  // Per element: that direct luminance (a divided element's children
  // have their parent's); empty when not tracked.
  const std::vector<float>& direct() const { return direct_; }
  // Every emitting shooter has shot in this wave: direct() is complete.
  bool DirectDone() const { return dark_emitters_ == 0; }

  // The elements whose radiosity changed since the last call (each once;
  // those Divided() made included), into *out: what a division pass needs
  // to look at again (Subdivider::Pass). Kept only from the first call on,
  // so that a run without subdivision does not pay for it in Shoot (a
  // wave's first pass evaluates every leaf and needs no list).
  void TakeChanged(std::vector<int32_t>* out);

  // Divide() was applied to the mesh for these elements (in this order):
  // their children get the parent's radiosity shaped by its gradient
  // (paper §4.4), fitted to the neighbours and limited to their range,
  // keeping Σ B·area. Unshot radiosity is per patch and stays.
  void Divided(const std::vector<int32_t>& elems);
  // SplitPatch(p) was just applied to the mesh (the pieces are p and the
  // patches appended since): p's unshot power Σ unshot·A is shared among
  // the pieces by what their leaves received (Σ (B − Ke)·A per channel;
  // by area where nothing was received), so no power is made or lost
  // (to rounding); the pieces inherit p's flags and start their own shot
  // counts. Emitters are never split (Subdivider::SplitPass), so what a
  // piece holds is received light. The splits of one pass end with one
  // SplitsDone() before the next Select or Shoot.
  void Split(int p);
  // The running sums summed again and the shooter queue rebuilt, once for
  // all the splits since the last call: each costs O(patches), and a pass
  // at 10^5 patches and more splits thousands of them. The same state as
  // doing both after every split (a full sum and a build depend only on
  // the patches as they are).
  void SplitsDone();
  // A new wave (paper §4.4): all computed radiosity is thrown away and the
  // solution starts again from the emitters, on the mesh as it is now.
  void NewWave();
  // The end of a wave, before its picture: the per-element tracks that
  // NewWave() starts again from 0 (the noise and the direct light, 12
  // bytes an element) freed now, so that they do not stand beside the
  // picture (the master's peak in a run that divides). Until NewWave(),
  // noise() and direct() are empty.
  void EndWave();

  // Σ|unshot|·area / Σ emitted·area, channels summed; 0 for a dark scene.
  double UnshotFraction() const;
  // Σ B·area over all elements / Σ emitted·area: grows without bound when
  // a closed scene reflects everything.
  double PowerRatio() const;
  // The 64-byte cache lines that Shoot(p, column) touches for the
  // column's elements and the patches they reach (their records here and
  // their leaves in the shooter queue), as laid out now: their first
  // bytes, each line once, in increasing address order, those it writes
  // into *written and those it only reads into *read. At 10^5 elements
  // and more they are scattered over arrays larger than the caches, and a
  // shot waits on each (bench/master.cpp's memory floor). A column's ids
  // are as Shoot takes them (increasing).
  void ShotLines(const std::vector<FormFactor>& column, std::vector<const char*>* written,
                 std::vector<const char*>* read) const;
  bool Dark() const { return emitted_ == 0; }
  long shots() const { return shots_; }
  int TimesShot(int p) const { return times_shot_[p]; }
  const std::vector<int>& times_shot() const { return times_shot_; } // per patch, this wave
  ElemB radiosity() const {  // per element
    return ElemB(reinterpret_cast<const glm::dvec3*>(elem_.data()), elem_.size(), sizeof(ElemShot));
  }
  // B as a plain array, for a caller done with the solver: the solver's
  // other arrays are freed first and the element records after the copy,
  // so that the copy stands beside those alone (the master's peak at the
  // end of a run). The solver is empty afterwards.
  std::vector<glm::dvec3> TakeRadiosity();
  std::vector<glm::dvec3> unshot() const;  // per patch, a copy (State, tests)
  glm::dvec3 Ambient() const;  // the overshooting estimate before ρ

  SolverState State() const;
  // Takes a State() of a solver of this mesh (divided alike since): false
  // with *err when the sizes do not match the mesh.
  bool Restore(const SolverState& s, std::string* err);

 private:
  const glm::dvec3& Rho(int p) const { return mesh_.materials[size_t(patch_[size_t(p)].material)].rho; }
  glm::dvec3 ToShoot(int p) const;
  double Power(int p, const glm::dvec3& ambient) const;  // one patch's
  double ShooterPower(int p, const glm::dvec3& ambient) const;
  double PatchBound(int p) const;
  double Bound(int p) const;  // per shooter, for queue_
  void Rebase();
  void Changed(int32_t e) {
    uint64_t& word = changed_bits_[size_t(e) / 64];
    const uint64_t bit = uint64_t{1} << (e % 64);
    if (!(word & bit)) {
      word |= bit;
      changed_.push_back(e);
    }
  }
  void Resum();
  void CountDarkEmitters();
  void Grow();
  void PatchArrays();
  void HugeArrays();

  const Mesh& mesh_;
  bool overshoot_;
  std::vector<int> leaves_;         // scratch for Shoot
  // Per element, its B and its Element's 1/area together: at 10^5
  // elements and more a column's elements are sparse in arrays larger
  // than the caches, and B and the area in two arrays were two lines to
  // wait for (radiosity() hands B out as a view of these). Shoot
  // multiplies by 1/A (double, so within 2 ulp of dividing by A): two
  // divisions an element (divpd + divsd) held the loop at the divider's
  // pace, about 10 cycles; shooting the room at R 256 took 11.2 and
  // 11.1 us a shot, 10.0 and 10.4 with the product (radiosity-master,
  // quiet pairs), and result.csv of the shipped scenes stays the same to
  // its 9 digits.
  struct ElemShot {
    glm::dvec3 b{0.0};
    double inv_area = 0;
  };
  static_assert(sizeof(ElemShot) == 32, "two a cache line, none across two");
  std::vector<ElemShot, HugePageAllocator<ElemShot>> elem_;
  std::vector<int32_t, HugePageAllocator<int32_t>> patch_of_;  // per element; ~patch when divided
  // Per patch, what Shoot reads and writes of each patch a column reaches,
  // in one cache line: at 10^5 patches and more the patches a shot
  // reaches are scattered over arrays larger than the caches, and each
  // array was a line to wait for. ρ by its material (Rho(p): the
  // materials are few and stay in the caches), so that the flags and the
  // group fit beside the rest.
  struct alignas(64) PatchShot {
    glm::dvec3 unshot{0.0};
    double area = 0;
    double inv_area = 0;    // 1 / area (see ElemShot::inv_area)
    double fsum = 0;        // Σ F within one Shoot
    int32_t material = 0;   // its face's, in mesh_.materials
    int32_t group = -1;     // mesh_.group_of's (-1: none)
    uint8_t lit = 0;        // emits, or light reached it
    uint8_t blind = 0;      // its column was empty
    void SetArea(double a) {  // area and 1/area never apart
      area = a;
      inv_area = 1.0 / a;
    }
  };
  static_assert(sizeof(PatchShot) == 64, "one cache line");
  std::vector<PatchShot, HugePageAllocator<PatchShot>> patch_;
  std::vector<int32_t> touched_;    // Shoot's scratch: the patches it reached
  std::vector<uint32_t> stale_;     // Shoot's scratch: where its column has divided elements
  // Per element, a bit: in changed_. Bits, not bytes, so that Shoot's
  // scattered tests hit 66 KB at 529,260 elements, not 529 KB.
  std::vector<uint64_t> changed_bits_;
  std::vector<double> noise_;       // per element when tracked: variance of Lum(B)
  double pixel_ff_ = 0;             // a top-centre pixel's delta form factor; 0: no noise
  std::vector<float> direct_;       // per element when tracked: first light's luminance
  bool track_direct_ = false;
  long dark_emitters_ = 0;          // emitting shooters not yet shot in this wave
  std::vector<int32_t> changed_;    // elements whose B changed, for TakeChanged
  bool track_ = false;              // since TakeChanged was first called
  std::vector<int> times_shot_;
  glm::dvec3 unshot_sum_{0.0};      // Σ unshot·area, kept incrementally
  double abs_sum_ = 0;              // Σ |unshot|·area (channels summed), too
  ShooterQueue queue_;              // by patch id: Bound(p) of shooters, taken
  glm::dvec3 base_{0.0};            // the overshooting estimate the bounds assume
  std::vector<double> weight_;      // per shooter: Σ area · max ρ, how far drift moves it
  std::vector<uint8_t> group_dirty_;  // per group: in dirty_groups_
  std::vector<int32_t> dirty_groups_; // groups a shot's light reached, for Shoot
  glm::dvec3 reflect_{1.0};         // 1/(1−ρ̄): ambient interreflection factor
  double total_area_ = 0, emitted_ = 0;
  long shots_ = 0;
  bool splits_pending_ = false;     // Split() called, SplitsDone() not yet
};

#endif
