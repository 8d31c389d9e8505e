// One steady symmetric Masing cycle u(t) = A cos(theta) of a 4-parameter Iwan element:
// its first-harmonic (describing-function) stiffness and the energy it stores at the
// turning point, the two quantities a ring-down or a stepped-sine test sees (method.md,
// "What a ring-down would show").
//
// Per unit-stiffness Jenkins slider with slip displacement phi (iwan.h: density R phi^chi on
// (0, phi_max) plus S delta(phi - phi_max)) at amplitude A:
//   A <= phi: stiffness 1, no loss, stored energy A^2 / 2;
//   A >  phi: in-phase first-harmonic stiffness g(phi / A) = (t - sin(2 t) / 2) / pi with
//             cos t = 1 - 2 phi / A, stored energy phi^2 / 2 (it sits at its slip force),
//             dissipation 4 phi (A - phi) per cycle.
// Integrated over the density, with b = min(1, phi_max / A):
//   k_1(A) = R A^(chi+1) J(b) + [A < phi_max] (R (phi_max^(chi+1) - A^(chi+1)) / (chi+1) + S)
//            + [A >= phi_max] S g(phi_max / A),      J(b) = int_0^b s^chi g(s) ds,
//   E(A)   = K_T A^2 / 2 - R A^(chi+3) / ((chi+1)(chi+3))       (A < phi_max),
//   E(A)   = R phi_max^(chi+3) / (2 (chi+3)) + S phi_max^2 / 2  (A >= phi_max),
// with slope dk_1/dA = R A^chi ((chi+1) J(1) - 1) (A < phi_max) and, past phi_max,
//   R (chi+1) A^chi J(b) - (b / A) (R A^(chi+1) b^chi g(b) + S g'(b)),  g'(s) = 4 sin(t) / pi;
// so dE/dA = A F'(A) (F' the virgin tangent of iwan.h: the stiffness of the sliders not
// slipping). J(1) depends on chi alone and is computed once; J(b < 1) (macroslip) by the
// same quadrature: substituting s = sin^2(t/2), t = T u^3 makes the integrand a smooth
// power u^(6 chi + 14) near 0, and Gauss-Legendre on u (24 nodes up to chi 3, up to 384 at
// chi kIwanCycleChiMax) integrates it to rounding.
// Units: A in m, k_1 in N/m, E in J.
#pragma once

#include "jointlab/model/iwan.h"

namespace jointlab::model {

/// The largest chi whose slip integral the quadrature is verified for (to 6e-11 against 2500
/// nodes); JointCondensation refuses elements above it.
inline constexpr double kIwanCycleChiMax = 2000;

/// The steady-cycle properties of one Iwan element (J(1) precomputed).
class IwanCycle {
 public:
  /// Precomputes the microslip integral of `iwan` (chi <= kIwanCycleChiMax).
  explicit IwanCycle(const Iwan& iwan);

  /// In-phase first-harmonic stiffness of the cycle of amplitude |A| [N/m]; K_T at A = 0.
  /// When slope is given it receives dk_1/dA at A [N/m^2] (odd in A; 0 at A = 0, where it is
  /// singular for chi < 0).
  double first_harmonic_stiffness(double amplitude, double* slope = nullptr) const;
  /// The microslip integral J(1) = int_0^1 s^chi g(s) ds (above): below phi_max,
  /// k_1(A) = R A^(chi+1) (J(1) - 1 / (chi+1)) + R phi_max^(chi+1) / (chi+1) + S.
  double microslip_integral() const { return j1_; }
  /// Energy stored at the turning point of the cycle of amplitude |A| [J].
  double turning_point_energy(double amplitude) const;

 private:
  Iwan iwan_;
  double j1_ = 0;       // J(1)
  double pm_chi1_ = 0;  // phi_max^(chi+1)
};

}  // namespace jointlab::model
