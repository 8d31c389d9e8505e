#include "jointlab/model/iwan_hysteresis.h"

#include <cassert>
#include <cmath>

namespace jointlab::model {

IwanHysteresis::IwanHysteresis(const Iwan& iwan) : iwan_(iwan) {}

double IwanHysteresis::update(double u) {
  const double d = u - u_;
  if (d > 0) {
    move_up(d);
  } else if (d < 0) {
    // The mirror image: s -> -s turns max(s + d, -phi) into min(s' - d, phi).
    for (double& s : s_) s = -s;
    move_up(-d);
    for (double& s : s_) s = -s;
  }
  u_ = u;
  force_ = integrate();
  return force_;
}

void IwanHysteresis::move_up(double d) {
  assert(d > 0);
  // g(phi) = phi - s(phi) - d is nondecreasing (s has slopes -1, 0, +1) and g(0) = -d < 0:
  // the new state is phi up to the root phi* of g, and s + d beyond it.
  const size_t n = phi_.size();
  size_t k = 1;
  while (k < n && phi_[k] - s_[k] - d < 0) ++k;
  double root;
  if (k == n) {
    root = s_.back() + d;  // on the constant tail, g = phi - s_n - d
  } else {
    const double g0 = phi_[k - 1] - s_[k - 1] - d, g1 = phi_[k] - s_[k] - d;
    root = phi_[k - 1] + (phi_[k] - phi_[k - 1]) * (-g0 / (g1 - g0));
  }
  std::vector<double> phi{0.0, root};
  std::vector<double> s{0.0, root};
  for (size_t j = k; j < n; ++j) {
    if (phi_[j] <= root) continue;
    phi.push_back(phi_[j]);
    s.push_back(s_[j] + d);
  }
  // Merge collinear segments (closed loops) and drop a last breakpoint that only starts
  // a flat tail. Slopes are exactly +-1 or 0 in exact arithmetic.
  auto slope = [&](size_t a, size_t b) { return (s[b] - s[a]) / (phi[b] - phi[a]); };
  phi_.assign(1, 0.0);
  s_.assign(1, 0.0);
  for (size_t j = 1; j < phi.size(); ++j) {
    if (j + 1 < phi.size() && std::abs(slope(j - 1, j) - slope(j, j + 1)) < 1e-9) {
      // j is interior to a straight run: keep only the run's ends (phi[j-1] stays valid
      // because the previous kept point is on the same line).
      continue;
    }
    phi_.push_back(phi[j]);
    s_.push_back(s[j]);
  }
  while (phi_.size() > 1) {
    const size_t m = phi_.size() - 1;
    if (std::abs((s_[m] - s_[m - 1]) / (phi_[m] - phi_[m - 1])) < 1e-9) {
      phi_.pop_back();
      s_.pop_back();
    } else {
      break;
    }
  }
}

double IwanHysteresis::integrate() const {
  // int_a^b R phi^chi (s0 + m (phi - a)) dphi over each segment inside (0, phi_max).
  const double chi = iwan_.chi(), R = iwan_.R(), pm = iwan_.phi_max();
  double f = 0;
  double s_at_pm = s_.back();
  for (size_t j = 0; j < phi_.size(); ++j) {
    const double a = phi_[j];
    if (a >= pm) {
      break;
    }
    const bool last = j + 1 == phi_.size();
    const double m = last ? 0.0 : (s_[j + 1] - s_[j]) / (phi_[j + 1] - a);
    const double b = last ? pm : std::min(phi_[j + 1], pm);
    const double c0 = s_[j] - m * a;  // s = c0 + m phi on the segment
    f += R * (c0 * (std::pow(b, chi + 1) - std::pow(a, chi + 1)) / (chi + 1) +
              m * (std::pow(b, chi + 2) - std::pow(a, chi + 2)) / (chi + 2));
    if (b == pm) s_at_pm = c0 + m * pm;
  }
  return f + iwan_.S() * s_at_pm;
}

}  // namespace jointlab::model
