#include "jointlab/model/qsma.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::model {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

// A converged static solution at load level alpha, with its continuation tangent.
struct State {
  double alpha = 0;
  Eigen::VectorXd r;        // joint coordinates
  Eigen::VectorXd tangent;  // dr/dalpha (empty if unknown)
  double q = 0;             // modal amplitude
};

// Why a load level cannot be part of the curve.
enum class Stop { kNone, kNoSolution, kMacroslip, kQmax };

class Problem {
 public:
  Problem(const JointCondensation& m, int column, const QsmaOptions& o, QsmaSummary* s)
      : m_(m), opt_(o), sum_(s) {
    omega2_ = m.modes().omega2(column);
    p_ = m.joint_shapes().col(column);
    c_ = p_ / omega2_;
    g_ = m.condensed_stiffness() * c_;
    // Coordinates the mode's linear motion moves; the others (by symmetry, say) never
    // reach macroslip and do not count for full macroslip.
    loaded_ = (c_.cwiseAbs().array() > 1e-6 * c_.lpNorm<Eigen::Infinity>()).cast<double>();
  }

  // Every loaded coordinate past its phi_max.
  bool full_macroslip(const Eigen::VectorXd& r) const {
    for (int j = 0; j < m_.size(); ++j) {
      if (loaded_(j) > 0 && std::abs(r(j)) < m_.phi_max(j)) return false;
    }
    return true;
  }

  const Eigen::VectorXd& c() const { return c_; }
  double omega2() const { return omega2_; }

  State zero() const { return {0.0, Eigen::VectorXd::Zero(m_.size()), c_, 0.0}; }

  // Solves at alpha, continuing from `from`; false if no equilibrium is found.
  bool solve(double alpha, const State& from, State& out) {
    out.alpha = alpha;
    const double runaway = 1e6 * (alpha * c_.lpNorm<Eigen::Infinity>() + m_.smallest_phi_max() +
                                  from.r.lpNorm<Eigen::Infinity>());
    for (int attempt = 0; attempt < 2; ++attempt) {
      if (attempt == 0 && from.tangent.size() == m_.size()) {
        out.r = from.r + (alpha - from.alpha) * from.tangent;  // Euler predictor
      } else if (attempt == 0 || from.alpha == 0) {
        out.r = alpha * c_;
      } else {
        out.r = from.r * (alpha / from.alpha);
      }
      const StaticSolve s =
          m_.solve(g_, alpha, out.r, runaway, opt_.max_newton_iterations, &out.tangent);
      ++sum_->solves;
      sum_->newton_iterations += s.iterations;
      if (s.converged) {
        out.q = (alpha + p_.dot(m_.softening(out.r))) / omega2_;
        return out.q > 0 && std::isfinite(out.q);
      }
    }
    return false;
  }

  // With q_max the curve continues past full macroslip (the elements carry F_S, the rest
  // of the structure the load increase) until q_max or the limit load; without it, full
  // macroslip ends the automatic range.
  Stop classify(bool ok, const State& s) const {
    if (!ok) return Stop::kNoSolution;
    if (opt_.q_max > 0) return s.q >= opt_.q_max ? Stop::kQmax : Stop::kNone;
    if (full_macroslip(s.r)) return Stop::kMacroslip;
    return Stop::kNone;
  }

  QsmaPoint point(const State& s) const {
    QsmaPoint pt;
    pt.force_amplitude = s.alpha;
    pt.modal_amplitude = s.q;
    pt.frequency_hz = std::sqrt(s.alpha / s.q) / kTwoPi;
    pt.damping_ratio = m_.dissipation(s.r) / (kTwoPi * s.alpha * s.q);
    pt.max_slip = s.r.cwiseAbs().maxCoeff();
    return pt;
  }

  // |zeta / zeta_0 - 1| at a solution: zeta_0 is the damping of the linear joint motion
  // at the same modal amplitude (the microslip power law).
  double microslip_deviation(const State& s) const {
    const double d0 = m_.dissipation(omega2_ * s.q * c_);
    const double zeta0 = d0 / (kTwoPi * omega2_ * s.q * s.q);
    const double zeta = m_.dissipation(s.r) / (kTwoPi * s.alpha * s.q);
    return std::abs(zeta / zeta0 - 1);
  }

  // ln of the smallest |r_j| / phi_max_j over the loaded coordinates: >= 0 exactly in
  // full macroslip.
  double macroslip_margin(const State& s) const {
    double m = INFINITY;
    for (int j = 0; j < m_.size(); ++j) {
      if (loaded_(j) > 0) m = std::min(m, std::abs(s.r(j)) / m_.phi_max(j));
    }
    return std::log(m);
  }

  // Finds the state with q = target between a (q <= target) and b (q >= target).
  State find_q(double target, const State& a, const State& b) {
    return find_root([&](const State& s) { return std::log(s.q / target); }, a, b);
  }

  // The onset of full macroslip between a (not in it) and b (in it).
  State find_macroslip(const State& a, const State& b) {
    return find_root([&](const State& s) { return macroslip_margin(s); }, a, b);
  }

  // Root of an increasing function f of the state between a (f <= 0) and b (f >= 0):
  // Illinois false position on ln alpha, to |f| <= 1e-13.
  template <class F>
  State find_root(F f, State a, State b) {
    double fa = f(a), fb = f(b);
    int side = 0;
    for (int it = 0; it < 100; ++it) {
      if (std::abs(fa) <= 1e-13) return a;
      if (std::abs(fb) <= 1e-13) return b;
      const double xa = std::log(a.alpha), xb = std::log(b.alpha);
      if (xb - xa <= 1e-15) break;
      double x = xa - fa * (xb - xa) / (fb - fa);
      if (!(x > xa && x < xb)) x = 0.5 * (xa + xb);
      State t;
      if (!solve(std::exp(x), a, t)) {  // cannot happen inside a converged bracket
        b = a;
        fb = fa;
        break;
      }
      const double ft = f(t);
      if (ft < 0) {
        a = t;
        fa = ft;
        if (side == -1) fb /= 2;
        side = -1;
      } else {
        b = t;
        fb = ft;
        if (side == 1) fa /= 2;
        side = 1;
      }
    }
    return std::abs(fa) < std::abs(fb) ? a : b;
  }

 private:
  const JointCondensation& m_;
  QsmaOptions opt_;
  QsmaSummary* sum_;
  double omega2_;
  Eigen::VectorXd p_, c_, g_, loaded_;
};

std::vector<double> log_grid(double lo, double hi, int n, bool include_hi) {
  std::vector<double> out;
  const int intervals = include_hi ? n - 1 : n;
  for (int i = 0; i < n; ++i) {
    out.push_back(i == 0 ? lo : lo * std::pow(hi / lo, static_cast<double>(i) / intervals));
  }
  if (include_hi && n > 1) out.back() = hi;
  return out;
}

}  // namespace

std::string QsmaOptions::error() const {
  if (points < 2) return fmt::format("points = {} must be >= 2", points);
  if (!(q_min >= 0) || !(q_max >= 0) || !std::isfinite(q_min) || !std::isfinite(q_max)) {
    return "q_min and q_max must be finite and >= 0 (0: automatic)";
  }
  if (q_min > 0 && q_max > 0 && q_min >= q_max) {
    return fmt::format("q_min = {} must be below q_max = {}", q_min, q_max);
  }
  if (!(microslip_deviation > 0 && microslip_deviation < 1)) {
    return "microslip_deviation must be in (0, 1)";
  }
  if (!(limit_tolerance > 0 && limit_tolerance <= 1e-2)) {
    return "limit_tolerance must be in (0, 0.01]";
  }
  if (max_newton_iterations < 1) return "max_newton_iterations must be >= 1";
  return "";
}

std::string QsmaSummary::report() const {
  const char* why = "";
  switch (termination) {
    case QsmaTermination::kReachedQmax:
      why = "reached the requested q_max";
      break;
    case QsmaTermination::kFullMacroslip:
      why = "full macroslip (every Iwan element slides)";
      break;
    case QsmaTermination::kLimitLoad:
      why = "limit load (no static solution beyond)";
      break;
    case QsmaTermination::kJointsNotLoaded:
      why = "the mode does not move the joints";
      break;
    case QsmaTermination::kEmptyRange:
      why = "empty range";
      break;
  }
  return fmt::format(
      "QSMA ended: {}. Last point: force amplitude {:.6g}, modal amplitude {:.6g}. "
      "{} static solves, {} Newton iterations. {}",
      why, end_force, end_modal_amplitude, solves, newton_iterations, message);
}

std::vector<QsmaPoint> qsma(const JointCondensation& model, int mode, const QsmaOptions& options,
                            QsmaSummary* summary) {
  assert(options.error().empty());
  assert(summary);
  *summary = QsmaSummary{};
  if (mode < 1 || mode > model.elastic_count()) {
    throw InputError(
        fmt::format("mode {} does not exist: the model has {} elastic modes "
                    "(numbered from 1)",
                    mode, model.elastic_count()));
  }
  const int column = model.modes().rigid_count + mode - 1;
  Problem problem(model, column, options, summary);
  const double omega2 = problem.omega2();
  std::vector<QsmaPoint> curve;

  // A mode that does not move any joint has a linear curve.
  const double shape_scale = model.joint_shapes().cwiseAbs().maxCoeff();
  if (problem.c().lpNorm<Eigen::Infinity>() * omega2 <= 1e-9 * shape_scale) {
    summary->termination = QsmaTermination::kJointsNotLoaded;
    if (options.q_max > 0) {
      const double lo = options.q_min > 0 ? options.q_min : options.q_max / 1e3;
      for (double q : log_grid(lo, options.q_max, options.points, true)) {
        curve.push_back({omega2 * q, q, std::sqrt(omega2) / kTwoPi, 0.0, 0.0});
      }
      summary->end_force = curve.back().force_amplitude;
      summary->end_modal_amplitude = curve.back().modal_amplitude;
      summary->message = fmt::format("mode {} does not move any Iwan joint: linear curve", mode);
    } else {
      summary->message = fmt::format(
          "mode {} does not move any Iwan joint: its QSMA curve is linear (give q_max)", mode);
    }
    return curve;
  }

  // 1. Start: well inside microslip (or below q_min).
  const State zero = problem.zero();
  State start;
  {
    double alpha = 1e-3 * model.smallest_phi_max() / problem.c().lpNorm<Eigen::Infinity>();
    const double target = options.microslip_deviation;
    State best;
    bool have_best = false;
    for (int it = 0; it < 40; ++it) {
      State s;
      if (!problem.solve(alpha, zero, s)) {
        alpha /= 10;
        continue;
      }
      const double dev = problem.microslip_deviation(s);
      if (dev <= target) {
        if (!have_best || s.alpha > best.alpha) best = s;
        have_best = true;
        if (dev >= 0.2 * target) break;
      }
      // dev grows as alpha^(chi+1): aim at half the allowed deviation.
      const double factor =
          dev > 0 ? std::pow(0.5 * target / dev, 1 / model.smallest_chi_plus_one()) : 10.0;
      alpha *= std::clamp(factor, 1e-8, 1e8);
    }
    if (!have_best) {
      if (!problem.solve(alpha, zero, best)) best = zero;  // no microslip start found
    }
    start = best;
    if (options.q_min > 0) {
      for (int it = 0; it < 200 && start.q > options.q_min; ++it) {
        State s;
        if (problem.solve(start.alpha / 4, zero, s)) start = s;
      }
    }
  }
  if (start.alpha <= 0) {
    summary->termination = QsmaTermination::kLimitLoad;
    summary->message = fmt::format("mode {}: no static solution even at the smallest load", mode);
    return curve;
  }

  // 2. March up by doubling until the curve must stop, then bracket the end.
  // With q_max the march may cross full macroslip: remember the doubling step that does.
  std::vector<State> marched{start};
  State hi, before_macroslip, after_macroslip;
  bool crossed = false;
  Stop reason = Stop::kNone;
  for (int it = 0; it < 200; ++it) {
    State next;
    const bool ok = problem.solve(2 * marched.back().alpha, marched.back(), next);
    if (ok && !crossed && problem.macroslip_margin(next) >= 0 &&
        problem.macroslip_margin(marched.back()) < 0) {
      crossed = true;
      before_macroslip = marched.back();
      after_macroslip = next;
    }
    reason = problem.classify(ok, next);
    if (reason != Stop::kNone) {
      hi = next;
      break;
    }
    marched.push_back(next);
  }
  State end = marched.back();
  if (reason == Stop::kNone) {
    summary->termination = QsmaTermination::kFullMacroslip;
    summary->message = fmt::format(
        "mode {}: not every Iwan element reached macroslip within 2^200 of the starting load",
        mode);
  } else {
    while (hi.alpha / end.alpha - 1 > options.limit_tolerance) {
      State mid;
      const bool ok = problem.solve(std::sqrt(end.alpha * hi.alpha), end, mid);
      const Stop why = problem.classify(ok, mid);
      if (why == Stop::kNone) {
        end = mid;
        marched.push_back(mid);
      } else {
        hi = mid;
        reason = why;
      }
    }
    if (reason == Stop::kNoSolution) {
      summary->termination = QsmaTermination::kLimitLoad;
    } else if (reason == Stop::kQmax) {
      end = problem.find_q(options.q_max, end, hi);
      summary->termination = QsmaTermination::kReachedQmax;
    } else {
      end = hi;
      summary->termination = QsmaTermination::kFullMacroslip;
    }
  }

  // 3. The first point: the automatic start or q = q_min.
  State first = start;
  if (options.q_min > 0 && start.q < options.q_min) {
    if (end.q < options.q_min) {
      summary->termination = QsmaTermination::kEmptyRange;
      summary->message = fmt::format(
          "mode {}: q_min = {:.6g} lies beyond the end of the curve (q = {:.6g} at force "
          "amplitude {:.6g})",
          mode, options.q_min, end.q, end.alpha);
      return curve;
    }
    std::sort(marched.begin(), marched.end(),
              [](const State& x, const State& y) { return x.alpha < y.alpha; });
    size_t i = 0;
    while (i < marched.size() && marched[i].q < options.q_min) ++i;
    first = i < marched.size() ? problem.find_q(options.q_min, marched[i - 1], marched[i])
                               : problem.find_q(options.q_min, marched.back(), end);
  }

  // 4. The output grid: log-spaced in alpha, clustered below a limit load.
  std::vector<double> alphas;
  const int n = options.points;
  const bool cluster = summary->termination == QsmaTermination::kLimitLoad && n >= 6 &&
                       first.alpha < 0.8 * end.alpha;
  if (cluster) {
    const int m = std::clamp(n / 4, 3, 8);
    alphas = log_grid(first.alpha, 0.9 * end.alpha, n - m, false);
    for (int i = 0; i < m - 1; ++i) {
      const double delta = 0.1 * std::pow(0.01, static_cast<double>(i) / (m - 2));
      alphas.push_back(end.alpha * (1 - delta));
    }
    alphas.push_back(end.alpha);
  } else {
    alphas = log_grid(first.alpha, end.alpha, n, true);
  }
  // A curve continued past full macroslip has a kink there (the tangent of the last
  // elements to slip drops from S to 0): the interior grid point nearest to its onset
  // moves onto it, so that interpolating the curve never straddles the kink.
  State onset;
  size_t onset_index = 0;
  if (crossed && options.q_max > 0 && alphas.size() > 2) {
    onset = problem.find_macroslip(before_macroslip, after_macroslip);
    const double x = std::log(onset.alpha);
    size_t best = 1;
    for (size_t i = 2; i + 1 < alphas.size(); ++i) {
      if (std::abs(std::log(alphas[i]) - x) < std::abs(std::log(alphas[best]) - x)) best = i;
    }
    if (alphas[best - 1] < onset.alpha && onset.alpha < alphas[best + 1]) {
      alphas[best] = onset.alpha;
      onset_index = best;
    }
  }
  State cur = first;
  curve.push_back(problem.point(first));
  for (size_t i = 1; i < alphas.size(); ++i) {
    State s;
    if (i + 1 == alphas.size()) {
      s = end;
    } else if (onset_index == i) {
      s = onset;
    } else if (!problem.solve(alphas[i], cur, s)) {
      break;  // cannot happen below a converged end level; keep the curve consistent
    }
    curve.push_back(problem.point(s));
    cur = s;
  }
  summary->end_force = curve.back().force_amplitude;
  summary->end_modal_amplitude = curve.back().modal_amplitude;
  if (summary->message.empty()) {
    switch (summary->termination) {
      case QsmaTermination::kLimitLoad:
        summary->message = fmt::format(
            "mode {}: no static solution past force amplitude {:.6g} (modal amplitude {:.6g}): "
            "the joints slide freely; the curve stops there",
            mode, summary->end_force, summary->end_modal_amplitude);
        break;
      case QsmaTermination::kFullMacroslip:
        summary->message =
            fmt::format("mode {}: every Iwan element is in macroslip from force amplitude {:.6g}",
                        mode, summary->end_force);
        break;
      default:
        summary->message = fmt::format("mode {}: reached q_max = {:.6g}", mode, options.q_max);
    }
  }
  return curve;
}

}  // namespace jointlab::model
