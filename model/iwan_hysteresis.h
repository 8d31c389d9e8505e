// The force of a 4-parameter Iwan element under an arbitrary displacement history, exact.
//
// Each unit-stiffness Jenkins slider with slip displacement phi carries s(phi) = u - x(phi),
// |s| <= phi; the element force is F = int_0^phi_max R phi^chi s(phi) dphi + S s(phi_max)
// (see iwan.h). A displacement increment d > 0 maps s to min(s + d, phi), d < 0 to
// max(s + d, -phi). Starting from s = 0 the state stays continuous and piecewise linear in
// phi with slopes alternating between +1 and -1 and a constant tail: its breakpoints are
// half the ranges between Masing reversal points, and loops that close merge their
// segments (the wipe-out rule). The force is integrated in closed form over the segments,
// so the Masing rules (reversal branch F_r -/+ 2 F((u_r - u)/2), return to the virgin
// curve, nested loops) hold exactly, with no discretisation of the slider continuum.
// Units: u in m, F in N.
#pragma once

#include <vector>

#include "jointlab/model/iwan.h"

namespace jointlab::model {

/// An Iwan element with memory: feed displacements in time order, read forces.
class IwanHysteresis {
 public:
  /// A virgin element (no slider displaced) at u = 0.
  explicit IwanHysteresis(const Iwan& iwan);

  /// Moves the element to displacement u [m] and returns the force [N].
  double update(double u);
  /// The current force [N].
  double force() const { return force_; }
  /// The current displacement [m].
  double displacement() const { return u_; }
  /// Number of breakpoints of the slider state (grows with nested, unclosed loops).
  int memory() const { return static_cast<int>(phi_.size()); }

 private:
  void move_up(double d);  // s -> min(s + d, phi), d > 0
  double integrate() const;

  Iwan iwan_;
  double u_ = 0;
  double force_ = 0;
  // Breakpoints of s(phi): phi_[0] = 0 < phi_[1] < ...; s linear between, constant after.
  std::vector<double> phi_{0.0};
  std::vector<double> s_{0.0};
};

}  // namespace jointlab::model
