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

#include "hemicube.h"
#include "mesh.h"

// Everything a Solver holds that is not derived from the mesh: what a
// checkpoint keeps (checkpoint.h) to go on later exactly where it stood.
struct SolverState {
  std::vector<glm::dvec3> b;          // per element (divided ones too)
  std::vector<glm::dvec3> unshot;     // per patch
  std::vector<uint8_t> lit, blind;    // per patch
  std::vector<int32_t> times_shot;    // per patch
  glm::dvec3 unshot_sum{0.0};         // the running sums as they are, drift
  double abs_sum = 0;                 // included, so that a resumed run
  long shots = 0;                     // makes the same choices bit for bit
};

class Solver {
 public:
  // overshoot: ambient overshooting (Feda & Purgathofer 1992).
  Solver(const Mesh& mesh, bool overshoot);

  // The shooter with the largest power still to shoot (|unshot + overshoot
  // estimate| × area, channels summed; a group's summed over its members)
  // among those not marked in `taken` (may be null), or -1 when there is
  // nothing left to shoot. Shooters are patch ids: a patch alone, or a
  // group's first member for the group (groups.h); other members are
  // never returned, and nothing of them need be marked in `taken`.
  int Select(const std::vector<char>* taken = nullptr) const;

  // Shoots shooter p (a patch, or a group by its first member) along its
  // column. The overshooting estimate is taken
  // here, from the ambient term as it is now (paper §4.2), not when p was
  // selected. The column may predate divisions (a worker computed it
  // before it heard of them): what an element since divided receives goes
  // to every leaf under it alike.
  void Shoot(int p, const std::vector<FormFactor>& column);

  // Divide() was applied to the mesh for these elements (in this order):
  // their children get the parent's radiosity shaped by its gradient
  // (paper §4.4), fitted to the neighbours and limited to their range,
  // keeping Σ B·area. Unshot radiosity is per patch and stays.
  void Divided(const std::vector<int32_t>& elems);
  // A new wave (paper §4.4): all computed radiosity is thrown away and the
  // solution starts again from the emitters, on the mesh as it is now.
  void NewWave();

  // Σ|unshot|·area / Σ emitted·area, channels summed; 0 for a dark scene.
  double UnshotFraction() const;
  // Σ B·area over all elements / Σ emitted·area: grows without bound when
  // a closed scene reflects everything.
  double PowerRatio() const;
  bool Dark() const { return emitted_ == 0; }
  long shots() const { return shots_; }
  int TimesShot(int p) const { return times_shot_[p]; }
  const std::vector<glm::dvec3>& radiosity() const { return b_; }  // per element
  const std::vector<glm::dvec3>& unshot() const { return unshot_; } // per patch
  glm::dvec3 Ambient() const;  // the overshooting estimate before ρ

  SolverState State() const;
  // Takes a State() of a solver of this mesh (divided alike since): false
  // with *err when the sizes do not match the mesh.
  bool Restore(const SolverState& s, std::string* err);

 private:
  glm::dvec3 ToShoot(int p) const;
  double Power(int p, const glm::dvec3& amb) const;  // one patch's, for Select
  void Resum();
  void Grow();

  const Mesh& mesh_;
  bool overshoot_;
  std::vector<int> leaves_;         // scratch for Shoot
  std::vector<glm::dvec3> b_;       // per element
  std::vector<glm::dvec3> rho_per_area_;  // per element: ρ / A, for Shoot
  std::vector<int32_t> patch_of_;   // per element, compact for Shoot
  std::vector<glm::dvec3> unshot_;  // per patch
  std::vector<double> fsum_;        // per patch: Σ F within one Shoot
  std::vector<int32_t> touched_;    // patches with fsum_ != 0
  std::vector<uint8_t> lit_;        // per patch: emits, or light reached it
  std::vector<uint8_t> blind_;      // per patch: its column was empty
  std::vector<int> times_shot_;
  glm::dvec3 unshot_sum_{0.0};      // Σ unshot·area, kept incrementally
  double abs_sum_ = 0;              // Σ |unshot|·area (channels summed), too
  glm::dvec3 reflect_{1.0};         // 1/(1−ρ̄): ambient interreflection factor
  double total_area_ = 0, emitted_ = 0;
  long shots_ = 0;
};

#endif
