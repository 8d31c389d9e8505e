#include "jointlab/correlate/qsma_at.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"

namespace jointlab::correlate {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;
constexpr double kTolerance = 1e-10;  // |ln s - ln s_i| at a returned point
constexpr int kMaxSteps = 200;        // static solves per requested amplitude, at most
constexpr int kNewtonSteps = 25;      // bordered Newton steps per amplitude before falling back

// A converged static solution at load level alpha.
struct State {
  double alpha = 0;
  Eigen::VectorXd r;           // joint coordinates
  Eigen::VectorXd tangent;     // dr/dalpha at the solution (continuation predictor)
  double q = 0;                // modal amplitude
  double ln_s = 0;             // ln (q omega^power)
  Eigen::VectorXd k1;          // first-harmonic stiffness at r (first-harmonic frequency only)
  bool exact_tangent = false;  // tangent factorised at r itself (not at the last iterate)
};

class Curve {
 public:
  Curve(const model::JointCondensation& m, int mode, int power, AmplitudeFrequency frequency,
        std::optional<Eigen::Index> dof)
      : m_(m), mode_(m, mode), power_(power), frequency_(frequency) {
    if (dof) dof_.emplace(m, mode, *dof);
    omega2_ = mode_.omega2;
    p_ = mode_.p;
    c_ = p_ / omega2_;
    g_ = mode_.g;
    for (int j = 0; j < m.size(); ++j)
      for (const model::Iwan& e : m.coordinates()[j].elements) kinks_.push_back({j, e.phi_max()});
  }

  // True when a coordinate is within 1e-8 of an element's phi_max, where the Iwan tangent
  // jumps: Newton may settle on either side of it, and the ring-down damping differs by side.
  // The bracketing iteration then decides, as it did before Newton was tried.
  bool near_kink(const Eigen::VectorXd& r) const {
    for (const auto& [j, phi] : kinks_)
      if (std::abs(std::abs(r(j)) - phi) <= 1e-8 * phi) return true;
    return false;
  }

  double omega2() const { return omega2_; }

  // What s is of the linear structure per unit q omega^power: 1 for q itself, |phi_r[d]| for
  // the deflection at DOF d.
  double linear_shape() const { return dof_ ? dof_->shape : 1.0; }

  // Puts a state whose coordinate lies within 1e-8 of an element's phi_max on the side of the
  // kink the requested amplitude (ln s = target) is on: a converged state is within 1e-10 of
  // the target in ln s, which near the kink may put r on the other side, where the Iwan tangent
  // (and with it the ring-down damping) differs. Where the kink lies is extrapolated along the
  // tangent dr/dalpha with the running slope d ln s / d ln alpha; the state is moved along the
  // tangent to 1e-12 inside the requested side (an equilibrium error of order 1e-20) and its
  // tangent and first-harmonic stiffness are left to be recomputed there.
  void to_side_of(double target, double slope, State& st) const {
    if (st.tangent.size() != st.r.size()) return;
    for (const auto& [j, phi] : kinks_) {
      const double r = st.r(j), t = st.tangent(j);
      if (std::abs(std::abs(r) - phi) > 1e-8 * phi) continue;
      const double sign = r < 0 ? -1.0 : 1.0;
      if (!(sign * t > 0)) continue;  // the coordinate does not move with the load here
      const double d_kink = (sign * phi - r) / t;  // alpha step to the kink
      // d ln s / d alpha on the state's side: d ln q = (1 + p^T diag(h') t) / (omega_r^2 q)
      // d alpha; the secant frequency adds (power / 2) (d ln alpha - d ln q), the first
      // harmonic's change is of the order of the damping and left out.
      Eigen::VectorXd h, dh;
      m_.softening(st.r, h, dh);
      const double q = (st.alpha + p_.dot(h)) / omega2_;
      const double dlnq = (1 + p_.dot(dh.cwiseProduct(st.tangent))) / (omega2_ * q);
      const double half = 0.5 * power_;
      double dlns =
          frequency_ == AmplitudeFrequency::kSecant ? (1 - half) * dlnq + half / st.alpha : dlnq;
      if (dof_) {  // d ln u_d = (z^T t + e) / u_d d alpha in place of d ln q
        const double dlny =
            dof_->sign * (dof_->z.dot(st.tangent) + dof_->e) / dof_->deflection(st.alpha, st.r);
        dlns =
            frequency_ == AmplitudeFrequency::kSecant ? dlny + half * (1 / st.alpha - dlnq) : dlny;
      }
      const double ln_s_kink = st.ln_s + (dlns > 0 ? dlns : slope / st.alpha) * d_kink;
      const bool want_below = target < ln_s_kink;
      const bool below = std::abs(r) < phi;
      if (want_below == below) continue;
      const double goal = sign * phi * (want_below ? 1 - 1e-12 : 1 + 1e-12);
      const double step = (goal - r) / t;
      st.alpha += step;
      st.r += step * st.tangent;
      st.exact_tangent = false;
      st.tangent.resize(0);
      st.k1.resize(0);
      return;
    }
  }

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
      if (dof_) {
        const double y = dof_->deflection(alpha, out.r);
        if (!(y > 0) || !std::isfinite(y)) return false;
        out.ln_s = std::log(y) + 0.5 * power_ * std::log(omega2);
        return true;
      }
      out.ln_s = std::log(out.q) + 0.5 * power_ * std::log(omega2);
      return true;
    }
    return false;
  }

  // Newton's method on the bordered system K_c r - h(r) = alpha g, ln s(r, alpha) = target in
  // (r, ln alpha), from the guess in `st`: one factorisation per step, converging
  // quadratically to rounding. On success `st` is the solution with its tangent dr/dalpha at
  // r itself and `slope` d ln s / d ln alpha there; false (st undefined) where it does not
  // converge.
  bool newton(double target, State& st, double& slope) const {
    const int nj = m_.size();
    const Eigen::MatrixXd& kc = m_.condensed_stiffness();
    const bool harmonic = frequency_ == AmplitudeFrequency::kFirstHarmonic && power_ > 0;
    const double half = 0.5 * power_;
    Eigen::VectorXd h(nj), dh(nj), kr(nj), residual(nj), grad(nj), t(nj), dk1(nj), dq(nj), dd(nj);
    Eigen::MatrixXd hessian(nj, nj);
    Eigen::Matrix<double, Eigen::Dynamic, 2> rhs(nj, 2), solved(nj, 2);  // [g, residual] solved
    Eigen::LLT<Eigen::MatrixXd> llt(nj);
    bool factorised = false;  // llt holds the Hessian of an earlier iterate
    double x = std::log(st.alpha), previous = INFINITY;
    for (int step = 0; step < kNewtonSteps; ++step) {
      const double alpha = std::exp(x);
      if (harmonic)
        m_.softening_and_harmonic(st.r, h, dh, st.k1, dk1);
      else
        m_.softening(st.r, h, dh);
      kr.noalias() = kc * st.r;
      residual = kr - h - alpha * g_;
      const double q = (alpha + p_.dot(h)) / omega2_;
      if (!(q > 0) || !std::isfinite(q)) return false;
      // c = ln s - target and its gradient: grad (in r) and dc_da (in alpha, r held).
      dq = p_.cwiseProduct(dh) / omega2_;  // dq/dr; dq/dalpha = 1/omega_r^2
      double c = 0, dc_da = 0;
      if (harmonic) {
        // omega_1^2 = omega_r^2 - D / q, D = sum_j p_j (K_T,j - k_1j) r_j (model/qsma.h).
        double big_d = 0;
        for (int j = 0; j < nj; ++j) {
          const double kt = m_.linear_stiffness(j);
          big_d += p_(j) * (kt - st.k1(j)) * st.r(j);
          dd(j) = p_(j) * (kt - st.k1(j) - dk1(j) * st.r(j));
        }
        const double omega2 = omega2_ - big_d / q;
        if (!(omega2 > 0)) return false;
        if (dof_) {  // ln s = ln u_d + half ln omega_1^2, u_d = sign (z^T r + e alpha)
          const double y = dof_->deflection(alpha, st.r);
          if (!(y > 0) || !std::isfinite(y)) return false;
          c = std::log(y) + half * std::log(omega2) - target;
          grad = (dof_->sign / y) * dof_->z + half * (-dd / q + (big_d / (q * q)) * dq) / omega2;
          dc_da = dof_->sign * dof_->e / y + half * big_d / (q * q * omega2_ * omega2);
        } else {
          c = std::log(q) + half * std::log(omega2) - target;
          grad = dq / q + half * (-dd / q + (big_d / (q * q)) * dq) / omega2;
          dc_da = 1 / (omega2_ * q) + half * big_d / (q * q * omega2_ * omega2);
        }
      } else if (dof_) {  // ln s = ln u_d + half (ln alpha - ln q)
        const double y = dof_->deflection(alpha, st.r);
        if (!(y > 0) || !std::isfinite(y)) return false;
        c = std::log(y) + half * (std::log(alpha) - std::log(q)) - target;
        grad = (dof_->sign / y) * dof_->z - (half / q) * dq;
        dc_da = dof_->sign * dof_->e / y + half / alpha - half / (omega2_ * q);
      } else {
        c = (1 - half) * std::log(q) + half * std::log(alpha) - target;
        grad = (1 - half) / q * dq;
        dc_da = (1 - half) / (omega2_ * q) + half / alpha;
      }
      const double scale = alpha * g_.lpNorm<Eigen::Infinity>() + kr.lpNorm<Eigen::Infinity>() +
                           h.lpNorm<Eigen::Infinity>();
      // Done when the force balance holds to 1e-12 of the forces (as JointCondensation::solve)
      // and ln s is on target to rounding: below 1e-14, or below 1e-10 where a step no longer
      // gains the factor 4 quadratic convergence would (the rounding floor of ln s).
      const double ac = std::abs(c);
      const bool done = residual.lpNorm<Eigen::Infinity>() <= 1e-12 * scale &&
                        (ac <= 1e-14 || (ac <= 1e-10 && ac > 0.25 * previous));
      previous = ac;
      // The tangent at r: from the last factorisation by iterative refinement where r has
      // hardly moved since (it converges like Newton's own step), else from a new one.
      if (!(done && factorised && refine(llt, dh, t))) {
        hessian = kc;
        hessian.diagonal() -= dh;
        llt.compute(hessian);
        if (llt.info() != Eigen::Success) return false;
        factorised = true;
        if (done) {
          t = llt.solve(g_);  // dr/dalpha
        } else {              // dr/dalpha and the Newton correction, in one pass
          rhs.col(0) = g_;
          rhs.col(1) = residual;
          solved = llt.solve(rhs);
          t = solved.col(0);
        }
      }
      const double dc_dx = alpha * (grad.dot(t) + dc_da);  // d ln s / d ln alpha on the path
      if (!(dc_dx > 0) || !std::isfinite(dc_dx)) return false;
      if (done) {
        st.alpha = alpha;
        st.tangent = t;
        st.exact_tangent = true;
        st.q = q;
        st.ln_s = c + target;
        if (!harmonic) st.k1.resize(0);
        slope = std::clamp(dc_dx, 1e-3, 1e6);
        return true;
      }
      const auto u = solved.col(1);  // (K_c - diag h')^{-1} residual
      double dx = (grad.dot(u) - c) / dc_dx;
      const double limit = std::log(8.0);
      dx = std::clamp(dx, -limit, limit);
      st.r += alpha * dx * t - u;
      x += dx;
      if (!st.r.allFinite() || !std::isfinite(x)) return false;
    }
    return false;
  }

  // Refines t (solved with the factorisation `llt` of an earlier iterate's Hessian) to
  // (K_c - diag dh)^{-1} g: t += llt^{-1} (g - (K_c - diag dh) t). Each pass multiplies the
  // error by rho, the relative change of the Hessian, which the first correction measures
  // (|e_0| ~ rho |t|); so after a correction d the error left is ~(|d| / |t|) |d|, below
  // 1e-16 |t| once |d| <= 1e-8 |t|. False if three passes do not get there.
  bool refine(const Eigen::LLT<Eigen::MatrixXd>& llt, const Eigen::VectorXd& dh,
              Eigen::VectorXd& t) const {
    for (int pass = 0; pass < 3; ++pass) {
      Eigen::VectorXd defect = g_ - m_.condensed_stiffness() * t;
      defect += dh.cwiseProduct(t);
      const Eigen::VectorXd correction = llt.solve(defect);
      t += correction;
      if (!t.allFinite()) return false;
      if (correction.lpNorm<Eigen::Infinity>() <= 1e-8 * t.lpNorm<Eigen::Infinity>()) return true;
    }
    return false;
  }

  model::QsmaPoint point(const State& s) const {
    const Eigen::VectorXd* k1 = s.k1.size() == m_.size() ? &s.k1 : nullptr;
    if (s.exact_tangent)
      return model::qsma_point_with_tangent(m_, mode_, s.alpha, s.r, s.tangent, k1);
    return model::qsma_point(m_, mode_, s.alpha, s.r, s.tangent, k1);
  }

 private:
  const model::JointCondensation& m_;
  model::QsmaMode mode_;
  int power_;
  AmplitudeFrequency frequency_;
  std::optional<model::QsmaDof> dof_;  // the deflection at this DOF stands for q in s
  double omega2_;
  Eigen::VectorXd p_, c_, g_;
  std::vector<std::pair<int, double>> kinks_;  // (coordinate, an element's phi_max)
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

// The Euler predictor from `at` towards ln s = target: ln alpha moved by the running slope (at
// most a factor 8), r along the tangent.
State predict(const State& at, double target, double slope) {
  const double limit = std::log(8.0);
  const double dx = std::clamp((target - at.ln_s) / slope, -limit, limit);
  State next;
  next.alpha = at.alpha * std::exp(dx);
  if (at.tangent.size() == at.r.size())
    next.r = at.r + (next.alpha - at.alpha) * at.tangent;
  else
    next.r = at.r * (next.alpha / at.alpha);
  return next;
}

}  // namespace

std::vector<QsmaAtPoint> qsma_at(const model::JointCondensation& model, int mode, int power,
                                 const std::vector<double>& amplitudes,
                                 AmplitudeFrequency frequency, QsmaAtSolver solver,
                                 std::optional<Eigen::Index> dof) {
  assert(power >= 0 && power <= 2);
  assert(std::is_sorted(amplitudes.begin(), amplitudes.end()));
  if (mode < 1 || mode > model.elastic_count()) {
    throw InputError(fmt::format("mode {} does not exist: the model has {}", mode,
                                 counted(model.elastic_count(), "elastic mode")));
  }
  std::vector<QsmaAtPoint> out;
  if (amplitudes.empty()) return out;
  assert(amplitudes.front() > 0);
  const Curve curve(model, mode, power, frequency, dof);
  if (!(curve.linear_shape() > 0)) {
    throw InputError(fmt::format(
        "mode {} leaves DOF {} still: its amplitude there says nothing of the mode", mode, *dof));
  }
  // Start at the load of the linear structure: s = alpha shape omega^(power - 2), the shape
  // |phi_r[d]| (1 for q).
  State at;
  double alpha0 = amplitudes.front() * std::pow(curve.omega2(), 1 - 0.5 * power);
  if (dof) alpha0 /= curve.linear_shape();
  if (!curve.solve(alpha0, nullptr, at)) return {};
  double slope = 1;  // d ln s / d ln alpha of the linear structure
  bool reached = true;
  for (double s : amplitudes) {
    // Past the last reachable amplitude every larger one is unreachable too.
    if (reached) {
      const double target = std::log(s);
      State next = predict(at, target, slope);
      double next_slope = slope;
      if (solver == QsmaAtSolver::kNewton && curve.newton(target, next, next_slope) &&
          !curve.near_kink(next.r)) {
        at = std::move(next);
        slope = next_slope;
      } else if (!find(curve, target, at, slope, &reached)) {
        return {};
      }
    }
    if (reached && curve.near_kink(at.r)) {
      State sided = at;
      curve.to_side_of(std::log(s), slope, sided);
      out.push_back({curve.point(sided), reached});
      continue;
    }
    out.push_back({curve.point(at), reached});
  }
  return out;
}

}  // namespace jointlab::correlate
