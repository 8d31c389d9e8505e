#include "jointlab/correlate/qsma_at.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::correlate {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;
constexpr double kTolerance = 1e-10;  // |ln s - ln s_i| at a returned point
constexpr int kMaxSteps = 200;        // static solves per requested amplitude, at most

// A converged static solution at load level alpha.
struct State {
  double alpha = 0;
  Eigen::VectorXd r;        // joint coordinates
  Eigen::VectorXd tangent;  // dr/dalpha at the solution (continuation predictor)
  double q = 0;             // modal amplitude
  double ln_s = 0;          // ln (q omega^power)
  Eigen::VectorXd k1;       // first-harmonic stiffness at r (first-harmonic frequency only)
};

class Curve {
 public:
  Curve(const model::JointCondensation& m, int mode, int power, AmplitudeFrequency frequency)
      : m_(m), mode_(m, mode), power_(power), frequency_(frequency) {
    omega2_ = mode_.omega2;
    p_ = mode_.p;
    c_ = p_ / omega2_;
    g_ = mode_.g;
  }

  double omega2() const { return omega2_; }

  // Solves at alpha continuing from `from` (alpha 0: the unloaded structure).
  bool solve(double alpha, const State* from, State& out) const {
    out.alpha = alpha;
    const double from_norm = from ? from->r.lpNorm<Eigen::Infinity>() : 0.0;
    const double runaway =
        1e6 * (alpha * c_.lpNorm<Eigen::Infinity>() + m_.smallest_phi_max() + from_norm);
    for (int attempt = 0; attempt < 2; ++attempt) {
      if (attempt == 0 && from && from->tangent.size() == m_.size()) {
        out.r = from->r + (alpha - from->alpha) * from->tangent;  // Euler predictor
      } else if (attempt == 0 || !from) {
        out.r = alpha * c_;  // the linear solution
      } else {
        out.r = from->r * (alpha / from->alpha);
      }
      const model::StaticSolve s = m_.solve(g_, alpha, out.r, runaway, 60, &out.tangent);
      if (!s.converged) continue;
      out.q = (alpha + p_.dot(m_.softening(out.r))) / omega2_;
      if (!(out.q > 0) || !std::isfinite(out.q)) return false;
      double omega2 = alpha / out.q;  // secant
      if (frequency_ == AmplitudeFrequency::kFirstHarmonic && power_ > 0) {
        // omega_1^2 = omega_r^2 - p^T diag(K_T - k_1) r / q (model/qsma.h)
        out.k1 = m_.first_harmonic_stiffness(out.r);
        omega2 = omega2_;
        for (int j = 0; j < m_.size(); ++j)
          omega2 -= p_(j) * (m_.linear_stiffness(j) - out.k1(j)) * out.r(j) / out.q;
        if (!(omega2 > 0)) return false;
      }
      out.ln_s = std::log(out.q) + 0.5 * power_ * std::log(omega2);
      return true;
    }
    return false;
  }

  model::QsmaPoint point(const State& s) const {
    return model::qsma_point(m_, mode_, s.alpha, s.r, s.tangent,
                             s.k1.size() == m_.size() ? &s.k1 : nullptr);
  }

 private:
  const model::JointCondensation& m_;
  model::QsmaMode mode_;
  int power_;
  AmplitudeFrequency frequency_;
  double omega2_;
  Eigen::VectorXd p_, c_, g_;
};

// The state with ln s = target, starting from a solved state `at`; slope is the running
// estimate of d ln s / d ln alpha (updated). False if no bracket is found. *reached is false
// when the target lies past the largest load with a static solution (then the returned
// state is the highest reachable one).
bool find(const Curve& curve, double target, State& at, double& slope, bool* reached) {
  *reached = true;
  State lo, hi;
  bool have_lo = false, have_hi = false;  // hi: ln s >= target (solved)
  double x_fail = INFINITY;               // smallest ln alpha known to have no solution
  if (at.ln_s <= target) {
    lo = at;
    have_lo = true;
  } else {
    hi = at;
    have_hi = true;
  }
  State cur = at;
  int steps = 0;
  // 1. Bracket: secant steps with the running slope, at most a factor 8 in alpha each.
  while (!(have_lo && have_hi) && std::abs(cur.ln_s - target) > kTolerance) {
    if (++steps > kMaxSteps) return false;
    const double x0 = std::log(cur.alpha);
    double dx = std::clamp((target - cur.ln_s) / slope, -std::log(8.0), std::log(8.0));
    if (x0 + dx >= x_fail) dx = 0.5 * (x_fail - x0);
    if (have_lo && x_fail < INFINITY && x_fail - std::log(lo.alpha) <= 1e-13) {
      *reached = false;  // the target lies past the last load with a static solution
      at = lo;
      return true;
    }
    State next;
    if (!curve.solve(std::exp(x0 + dx), &cur, next)) {
      if (dx < 0) return false;  // no solution below a solved load: the model is broken
      x_fail = x0 + dx;
      continue;
    }
    const double m = (next.ln_s - cur.ln_s) / dx;
    if (m > 1e-3 && std::isfinite(m)) slope = std::min(m, 1e6);
    if (next.ln_s <= target) {
      lo = next;
      have_lo = true;
    } else {
      hi = next;
      have_hi = true;
    }
    cur = next;
  }
  if (std::abs(cur.ln_s - target) <= kTolerance) {
    at = cur;
    return true;
  }
  // 2. Illinois false position on ln alpha inside [lo, hi].
  double fa = lo.ln_s - target, fb = hi.ln_s - target;
  int side = 0;
  while (true) {
    if (++steps > kMaxSteps) return false;
    const double xa = std::log(lo.alpha), xb = std::log(hi.alpha);
    if (xb - xa <= 1e-14) break;
    double x = xa - fa * (xb - xa) / (fb - fa);
    if (!(x > xa && x < xb)) x = 0.5 * (xa + xb);
    State t;
    if (!curve.solve(std::exp(x), &lo, t)) return false;  // inside a solved bracket
    const double ft = t.ln_s - target;
    if (std::abs(ft) <= kTolerance) {
      lo = t;
      fa = ft;
      break;
    }
    if (ft < 0) {
      lo = t;
      fa = ft;
      if (side == -1) fb /= 2;
      side = -1;
    } else {
      hi = t;
      fb = ft;
      if (side == 1) fa /= 2;
      side = 1;
    }
  }
  at = std::abs(fa) <= std::abs(fb) ? lo : hi;
  const double xs = std::log(hi.alpha) - std::log(lo.alpha);
  if (xs > 0 && hi.ln_s > lo.ln_s) slope = std::clamp((hi.ln_s - lo.ln_s) / xs, 1e-3, 1e6);
  return true;
}

}  // namespace

std::vector<QsmaAtPoint> qsma_at(const model::JointCondensation& model, int mode, int power,
                                 const std::vector<double>& amplitudes,
                                 AmplitudeFrequency frequency) {
  assert(power >= 0 && power <= 2);
  assert(std::is_sorted(amplitudes.begin(), amplitudes.end()));
  if (mode < 1 || mode > model.elastic_count()) {
    throw InputError(fmt::format("mode {} does not exist: the model has {} elastic modes", mode,
                                 model.elastic_count()));
  }
  std::vector<QsmaAtPoint> out;
  if (amplitudes.empty()) return out;
  assert(amplitudes.front() > 0);
  const Curve curve(model, mode, power, frequency);
  // Start at the load of the linear structure: s = alpha omega^(power - 2).
  State at;
  const double alpha0 = amplitudes.front() * std::pow(curve.omega2(), 1 - 0.5 * power);
  if (!curve.solve(alpha0, nullptr, at)) return {};
  double slope = 1;  // d ln s / d ln alpha of the linear structure
  bool reached = true;
  for (double s : amplitudes) {
    // Past the last reachable amplitude every larger one is unreachable too.
    if (reached && !find(curve, std::log(s), at, slope, &reached)) return {};
    out.push_back({curve.point(at), reached});
  }
  return out;
}

}  // namespace jointlab::correlate
