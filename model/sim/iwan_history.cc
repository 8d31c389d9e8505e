#include "jointlab/model/sim/iwan_history.h"

#include <cassert>
#include <cmath>
#include <utility>

namespace jointlab::model {
namespace {

// int_a^b phi^chi {1, phi, phi^2} dphi from pa = a^(chi+1), pb = b^(chi+1), c1 = chi + 1.
struct Moments {
  double i0, i1, i2;
  Moments(double a, double pa, double b, double pb, double c1)
      : i0((pb - pa) / c1),
        i1((b * pb - a * pa) / (c1 + 1)),
        i2((b * b * pb - a * a * pa) / (c1 + 2)) {}
};

}  // namespace

struct IwanHistory::Walk {
  IwanMove move;
  double sign = 1;      // direction of the move
  double root = 0;      // phi*: sliders below it slip
  double root_pow = 0;  // root^(chi+1)
  size_t keep = 0;      // breakpoints kept (from the front)
};

IwanHistory::IwanHistory(const Iwan& iwan)
    : iwan_(iwan), c1_(iwan.chi() + 1), pm_pow_(std::pow(iwan.phi_max(), iwan.chi() + 1)) {
  assert(
      iwan_parameter_error({iwan.slip_force(), iwan.stiffness(), iwan.chi(), iwan.beta()}).empty());
}

IwanHistory::Walk IwanHistory::walk(double u) const {
  Walk w;
  const double d = u - u_;
  w.keep = phi_.size();
  if (d == 0) {
    w.move = {force_, iwan_.stiffness(), 0.0, 0.0};
    return w;
  }
  // Work in the mirrored frame t = sign * s, where the move is by D = |d| > 0.
  const double sg = d > 0 ? 1.0 : -1.0, D = std::abs(d);
  const double Kt = iwan_.stiffness(), R = iwan_.R(), S = iwan_.S(), pm = iwan_.phi_max();
  double slip = 0, diss = 0, wsq = 0;  // int rho {e, phi e, e^2/2} over (0, min(phi*, pm))
  double e_pm = 0;                     // slip of the sliders at phi_max
  bool have_pm = false;
  // Adds the segment [a, b] on which the slip e runs linearly from ea to eb.
  auto add = [&](double a, double pa, double ea, double b, double pb, double eb) {
    if (a >= pm) {
      if (!have_pm) e_pm = ea, have_pm = true;
      return;
    }
    if (b > pm) {
      eb = ea + (eb - ea) * (pm - a) / (b - a);
      b = pm, pb = pm_pow_;
      e_pm = eb, have_pm = true;
    }
    if (!(b > a)) return;
    const double k = (eb - ea) / (b - a), al = ea - k * a;  // e = al + k phi
    const Moments m(a, pa, b, pb, c1_);
    slip += R * (al * m.i0 + k * m.i1);
    diss += R * (al * m.i1 + k * m.i2);
    wsq += 0.5 * R * (al * al * m.i0 + 2 * al * k * m.i1 + k * k * m.i2);
  };
  // g(phi) = phi - t(phi) - D is nondecreasing with g(0) = -D: walk up to its root.
  double a = 0, ta = 0, pa = 0;
  size_t k = phi_.size();
  for (;;) {
    const double ga = a - ta - D;  // <= 0
    if (k == 0) {                  // the constant tail t = ta
      w.root = ta + D;
      w.root_pow = std::pow(w.root, c1_);
      add(a, pa, -ga, w.root, w.root_pow, 0.0);
      break;
    }
    const double b = phi_[k - 1], tb = sg * (q_[k - 1] + u_), pb = pw_[k - 1];
    const double gb = b - tb - D;
    if (gb > 0) {
      w.root = std::min(b, a + (b - a) * (-ga / (gb - ga)));
      w.root_pow = std::pow(w.root, c1_);
      add(a, pa, -ga, w.root, w.root_pow, 0.0);
      break;
    }
    add(a, pa, -ga, b, pb, -gb);
    a = b, ta = tb, pa = pb;
    --k;
  }
  w.keep = k;
  w.sign = sg;
  const double f0 = sg * force_;  // committed force in the mirrored frame
  IwanMove& mv = w.move;
  if (w.root >= pm) {  // macroslip: every slider, the delta included, at its slip limit
    mv.force = sg * iwan_.slip_force();
    mv.tangent = 0;
    mv.work = f0 * D + 0.5 * Kt * D * D - wsq - 0.5 * S * e_pm * e_pm;
    mv.dissipation = diss + S * pm * e_pm;
  } else {
    mv.force = sg * (f0 + Kt * D - slip);
    mv.tangent = Kt - R * w.root_pow / c1_;
    mv.work = f0 * D + 0.5 * Kt * D * D - wsq;
    mv.dissipation = diss;
  }
  return w;
}

IwanMove IwanHistory::trial(double u) const { return walk(u).move; }

IwanMove IwanHistory::commit(double u) {
  const Walk w = walk(u);
  if (u == u_) return w.move;
  phi_.resize(w.keep);
  q_.resize(w.keep);
  pw_.resize(w.keep);
  // Below the root every slider is at its limit, s = sign * phi; beyond it the state is
  // shifted by the move, which leaves q = s - u unchanged.
  phi_.push_back(w.root);
  q_.push_back(w.sign * w.root - u);
  pw_.push_back(w.root_pow);
  u_ = u;
  force_ = w.move.force;
  stored_ += w.move.work - w.move.dissipation;
  dissipated_ += w.move.dissipation;
  return w.move;
}

namespace {

// int rho(phi) term(s) dphi over (0, phi_max) for the state s = q + u at breakpoints phi
// (pw = phi^(chi+1)); term(al, k, moments) integrates the term for s = al + k phi.
// Returns the integral and s(phi_max) for the delta.
template <typename Fn>
std::pair<double, double> integrate_state(const Iwan& iwan, double c1, double pm_pow,
                                          const std::vector<double>& phi,
                                          const std::vector<double>& q,
                                          const std::vector<double>& pw, double u, Fn term) {
  const double R = iwan.R(), pm = iwan.phi_max();
  double total = 0, a = 0, sa = 0, pa = 0, s_pm = 0;
  bool have_pm = false;
  auto add = [&](double a, double pa, double sa, double b, double pb, double sb) {
    if (a >= pm) {
      if (!have_pm) s_pm = sa, have_pm = true;
      return;
    }
    if (b > pm) {
      sb = sa + (sb - sa) * (pm - a) / (b - a);
      b = pm, pb = pm_pow;
      s_pm = sb, have_pm = true;
    }
    if (!(b > a)) return;
    const double k = (sb - sa) / (b - a), al = sa - k * a;
    total += R * term(al, k, Moments(a, pa, b, pb, c1));
  };
  for (size_t k = phi.size(); k > 0; --k) {
    const double b = phi[k - 1], sb = q[k - 1] + u;
    add(a, pa, sa, b, pw[k - 1], sb);
    a = b, sa = sb, pa = pw[k - 1];
  }
  if (a < pm) add(a, pa, sa, pm, pm_pow, sa);
  if (!have_pm) s_pm = sa;
  return {total, s_pm};
}

}  // namespace

double IwanHistory::force_from_state() const {
  const auto [body, s_pm] =
      integrate_state(iwan_, c1_, pm_pow_, phi_, q_, pw_, u_,
                      [](double al, double k, const Moments& m) { return al * m.i0 + k * m.i1; });
  return body + iwan_.S() * s_pm;
}

double IwanHistory::stored_energy_from_state() const {
  const auto [body, s_pm] = integrate_state(
      iwan_, c1_, pm_pow_, phi_, q_, pw_, u_, [](double al, double k, const Moments& m) {
        return 0.5 * (al * al * m.i0 + 2 * al * k * m.i1 + k * k * m.i2);
      });
  return body + 0.5 * iwan_.S() * s_pm * s_pm;
}

}  // namespace jointlab::model
