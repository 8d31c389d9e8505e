// The 4-parameter Iwan element under an arbitrary displacement history, evaluated for
// implicit time integration: trial moves from a committed state with their exact force,
// tangent, work and dissipation.
//
// Slider picture (iwan.h): unit-stiffness Jenkins sliders with slip displacement phi and
// density R phi^chi on (0, phi_max), plus S delta(phi - phi_max). A slider's elastic
// stretch s(phi) obeys |s| <= phi; the force is F = int rho(phi) s(phi) dphi. A move by
// d > 0 maps s to min(s + d, phi) (d < 0: the mirror image). The state s(phi) is exact:
// piecewise linear with slopes +-1 between Masing reversal points and a constant tail
// (the representation of iwan_hysteresis.h, which this reproduces to rounding). Per move,
// with root phi* the first phi where the slider reaches its slip limit (phi - s = d) and
// e(phi) = s + d - phi >= 0 the slip of each slider below it:
//   F_new   = F + K_T d - int_0^phi* rho e dphi                       [N]
//   dF/du   = K_T - int_0^phi* rho dphi = K_T - R phi*^(chi+1)/(chi+1)  (0 in macroslip)
//   W       = int F du = F d + K_T d^2/2 - int_0^phi* rho e^2/2 dphi   [J]
//   D       = int_0^phi* rho phi e dphi >= 0 (slip force phi times slip) [J]
// and the stored energy E = int rho s^2/2 changes by W - D. Only the segments below phi*
// are visited, so a move costs O(1) amortised even with a long memory (a ring-down adds
// one breakpoint per half cycle). Units: u in m, F in N, energies in J.
#pragma once

#include <vector>

#include "jointlab/model/iwan.h"

namespace jointlab::model {

/// Force, tangent and energies of one move from the committed state of an IwanHistory.
struct IwanMove {
  double force = 0;        ///< F at the new displacement [N]
  double tangent = 0;      ///< dF/du at the new displacement along the move [N/m]
  double work = 0;         ///< int F du over the move [J]
  double dissipation = 0;  ///< energy the sliders dissipate over the move, >= 0 [J]
};

/// An Iwan element with exact memory and incremental energy bookkeeping.
class IwanHistory {
 public:
  /// A virgin element (no slider stretched) at u = 0.
  explicit IwanHistory(const Iwan& iwan);

  /// The move from the committed displacement to u, without changing the state. For
  /// u equal to the committed displacement the tangent is K_T (every slider sticks).
  IwanMove trial(double u) const;
  /// Moves the element to u and returns that move (the same numbers as trial(u)).
  IwanMove commit(double u);

  /// The element.
  const Iwan& element() const { return iwan_; }
  /// Committed displacement [m].
  double displacement() const { return u_; }
  /// Committed force [N].
  double force() const { return force_; }
  /// Energy stored in the stretched sliders, accumulated move by move [J].
  double stored_energy() const { return stored_; }
  /// Energy dissipated since the virgin state [J].
  double dissipated_energy() const { return dissipated_; }
  /// Stored energy integrated afresh over the slider state (a check of stored_energy) [J].
  double stored_energy_from_state() const;
  /// Force integrated afresh over the slider state (a check of force) [N].
  double force_from_state() const;
  /// Number of breakpoints of the slider state.
  int memory() const { return static_cast<int>(phi_.size()); }

 private:
  struct Walk;  // the result of locating the root of a move
  Walk walk(double u) const;

  Iwan iwan_;
  double c1_ = 0;      // chi + 1
  double pm_pow_ = 0;  // phi_max^(chi+1)
  double u_ = 0, force_ = 0, stored_ = 0, dissipated_ = 0;
  // Breakpoints of s(phi) other than phi = 0, largest first (the small end, where moves
  // act, is at the back); q = s - u is invariant under the moves that keep a breakpoint;
  // pw = phi^(chi+1).
  std::vector<double> phi_, q_, pw_;
};

}  // namespace jointlab::model
