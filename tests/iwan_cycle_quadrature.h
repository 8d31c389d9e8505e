// The first-harmonic stiffness and turning-point energy of an Iwan element's steady cycle by
// brute force, independent of model/iwan_cycle.h: the exact Masing force history of
// model/iwan_hysteresis.h along u = A cos(theta), integrated over one period.
#pragma once

#include <cmath>
#include <numbers>

#include "jointlab/model/iwan.h"
#include "jointlab/model/iwan_hysteresis.h"

namespace jointlab::testing {

/// (1 / (pi A)) int_0^{2 pi} F(A cos t) cos t dt over the second (steady) cycle, by the
/// trapezoid rule on 2^16 intervals: the force is periodic with kinks only (at the reversal
/// points, which are nodes, and where the branch passes phi_max), so the error is O(h^2),
/// about 1e-9 relative.
inline double first_harmonic_by_quadrature(const model::Iwan& iwan, double amplitude) {
  model::IwanHysteresis h(iwan);
  h.update(amplitude);  // virgin loading to the first turning point
  const int n = 1 << 16;
  double sum = 0;
  for (int i = 1; i <= n; ++i) {
    const double t = 2 * std::numbers::pi * i / n;
    sum += h.update(amplitude * std::cos(t)) * std::cos(t);
  }
  return sum * (2 * std::numbers::pi / n) / (std::numbers::pi * amplitude);
}

}  // namespace jointlab::testing
