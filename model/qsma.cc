#include "jointlab/model/qsma.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"

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

// An element's slip within this fraction of its phi_max counts as having reached it. The
// static solve balances forces to 1e-12 of those involved, so a slip that stops at the
// element's kink (tangent S below phi_max, 0 past it) is known there only to that order
// relative: on two stacked beams one sat at phi_max (1 - 2.5e-11) over a third of the load
// range, and whether full macroslip began at its start or somewhere along it hung on the
// last digits of the model: a rounding-level change of the model (on another machine) moved
// the pinned onset of full macroslip along that stretch, and the end of the automatic range.
constexpr double kReachedPhiMax = 1e-8;

// Why a load level cannot be part of the curve.
enum class Stop { kNone, kNoSolution, kMacroslip, kQmax };

class Problem {
 public:
  Problem(const JointCondensation& m, int column, const QsmaOptions& o, QsmaSummary* s)
      : m_(m), opt_(o), sum_(s), mode_(column - m.modes().rigid_count + 1) {
    omega2_ = m.modes().omega2(column);
    p_ = m.joint_shapes().col(column);
    c_ = p_ / omega2_;
    g_ = m.condensed_stiffness() * c_;
    phi_max_all_.resize(m.size());
    for (int j = 0; j < m.size(); ++j) phi_max_all_(j) = m.phi_max(j);
    // Coordinates that carry the mode's joint slip: at least 1 % of the largest linear
    // slip. The others (left still by symmetry, or barely moved) would reach macroslip only
    // at absurd amplitudes and do not count for full macroslip.
    loaded_ = (c_.cwiseAbs().array() >= 0.01 * c_.lpNorm<Eigen::Infinity>()).cast<double>();
  }

  // True when coordinate j carries the mode's joint slip at r: at least 1 % of the largest
  // slip both in the linear mode and at r (once the others slide, a coordinate whose slip
  // they relieve stays bounded and stops counting).
  bool carries(const Eigen::VectorXd& r, int j, double largest) const {
    return loaded_(j) > 0 && std::abs(r(j)) >= 0.01 * largest;
  }

  // Every coordinate carrying the mode's joint slip is past its phi_max.
  bool full_macroslip(const Eigen::VectorXd& r) const {
    const double largest = r.lpNorm<Eigen::Infinity>();
    for (int j = 0; j < m_.size(); ++j) {
      if (carries(r, j, largest) && std::abs(r(j)) < (1 - kReachedPhiMax) * m_.phi_max(j)) {
        return false;
      }
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

  QsmaPoint point(const State& s) const { return qsma_point(m_, mode_, s.alpha, s.r, s.tangent); }

  // |zeta / zeta_0 - 1| at a solution: zeta_0 is the damping of the linear joint motion
  // at the same modal amplitude (the microslip power law).
  double microslip_deviation(const State& s) const {
    const double d0 = m_.dissipation(omega2_ * s.q * c_);
    const double zeta0 = d0 / (kTwoPi * omega2_ * s.q * s.q);
    const double zeta = m_.dissipation(s.r) / (kTwoPi * s.alpha * s.q);
    return std::abs(zeta / zeta0 - 1);
  }

  // ln of the smallest |r_j| / phi_max_j over the loaded coordinates: >= 0 exactly in full
  // macroslip (`reached`: >= 0 from (1 - kReachedPhiMax) phi_max on).
  double macroslip_margin(const State& s, bool reached = true) const {
    double m = INFINITY;
    const double largest = s.r.lpNorm<Eigen::Infinity>();
    for (int j = 0; j < m_.size(); ++j) {
      if (carries(s.r, j, largest)) m = std::min(m, std::abs(s.r(j)) / m_.phi_max(j));
    }
    return std::log(reached ? m / (1 - kReachedPhiMax) : m);
  }

  // ln of the largest |r_j| / phi_max_j: >= 0 once the first element is in macroslip.
  double onset_margin(const State& s) const {
    return std::log((s.r.cwiseAbs().array() / phi_max_all_.array()).maxCoeff());
  }

  // The first element's onset of macroslip between a (before it) and b (past it).
  State find_onset(const State& a, const State& b) {
    return find_root([&](const State& s) { return onset_margin(s); }, a, b);
  }

  // Finds the state with q = target between a (q <= target) and b (q >= target).
  State find_q(double target, const State& a, const State& b) {
    return find_root([&](const State& s) { return std::log(s.q / target); }, a, b);
  }

  // The onset of full macroslip between a (not in it) and b (in it): the kink where the last
  // loaded slip passes its phi_max, or nothing where the slips reach (1 - kReachedPhiMax)
  // phi_max but do not pass it within 1e-6 of that load. Such a slip approaches phi_max
  // without a kink (the element's load nears F_S while other paths take the increase), and
  // where it would reach it hangs on the last digits: on the stacked beams in
  // iwan_set_model_test.cc, 1e-15 of the model moved that load by 2.5e-5 to 2e-4.
  std::optional<State> find_macroslip(const State& a, const State& b) {
    const State reached = find_root([&](const State& s) { return macroslip_margin(s); }, a, b);
    const auto exact = [&](const State& s) { return macroslip_margin(s, false); };
    if (exact(reached) >= 0) return reached;
    const double alpha = reached.alpha * (1 + 1e-6);
    State probe = b;
    if (alpha < b.alpha && !solve(alpha, reached, probe)) return std::nullopt;
    if (exact(probe) >= 0) return find_root(exact, reached, probe);
    return std::nullopt;
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
  int mode_;
  double omega2_;
  Eigen::VectorXd p_, c_, g_, loaded_, phi_max_all_;
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

// n load levels from lo to end (both included): log-spaced, or, below a limit load,
// log-spaced to 0.9 end and then clustered 10 %, ..., 0.1 % under it.
std::vector<double> grid_to_end(double lo, double end, int n, bool cluster) {
  if (!cluster || n < 6 || lo >= 0.8 * end) return log_grid(lo, end, n, true);
  const int m = std::clamp(n / 4, 3, 8);
  std::vector<double> alphas = log_grid(lo, 0.9 * end, n - m, false);
  for (int i = 0; i < m - 1; ++i) {
    alphas.push_back(end * (1 - 0.1 * std::pow(0.01, static_cast<double>(i) / (m - 2))));
  }
  alphas.push_back(end);
  return alphas;
}

// The linear curve of a mode that moves no Iwan joint (only with q_max).
std::vector<QsmaPoint> linear_curve(double omega2, int mode, const QsmaOptions& options,
                                    QsmaSummary* summary) {
  std::vector<QsmaPoint> curve;
  summary->termination = QsmaTermination::kJointsNotLoaded;
  if (options.q_max <= 0) {
    summary->message = fmt::format(
        "mode {} does not move any Iwan joint: its QSMA curve is linear (give q_max)", mode);
    return curve;
  }
  const double lo = options.q_min > 0 ? options.q_min : options.q_max / 1e3;
  const double hz = std::sqrt(omega2) / kTwoPi;
  for (double q : log_grid(lo, options.q_max, options.points, true)) {
    curve.push_back({omega2 * q, q, hz, 0.0, 0.0, hz, 0.0, 0.0});
  }
  summary->end_force = curve.back().force_amplitude;
  summary->end_modal_amplitude = curve.back().modal_amplitude;
  summary->message = fmt::format("mode {} does not move any Iwan joint: linear curve", mode);
  return curve;
}

// Step 1: a start well inside microslip (damping within microslip_deviation / 5 ... of its
// power law), moved down to q_min when that lies lower. alpha = 0 when no load is carried.
State find_start(Problem& problem, const JointCondensation& model, const QsmaOptions& options) {
  constexpr double kStartSlip = 0.1;  // largest |r_j| / phi_max_j of the automatic start
  const State zero = problem.zero();
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
    // A joint far softer than the structure (K_T / k0 = 2e-4) keeps its damping on the power
    // law up to macroslip (dev <= K_T / k0 there): the deviation alone would raise the start
    // without bound. Past kStartSlip of an element's phi_max is no longer "well inside".
    const double slip = std::exp(problem.onset_margin(s));
    if (slip > kStartSlip) {
      alpha *= 0.5 * kStartSlip / slip;
      continue;
    }
    const double dev = problem.microslip_deviation(s);
    if (dev <= target) {
      if (!have_best || s.alpha > best.alpha) best = s;
      have_best = true;
      if (dev >= 0.2 * target || slip >= 0.2 * kStartSlip) break;
    }
    // dev grows as alpha^(chi+1): aim at half the allowed deviation, and no further than
    // kStartSlip (the slip grows at most as fast as alpha below it).
    const double factor =
        dev > 0 ? std::pow(0.5 * target / dev, 1 / model.smallest_chi_plus_one()) : 10.0;
    alpha *= std::clamp(std::min(factor, 0.5 * kStartSlip / slip), 1e-8, 1e8);
  }
  if (!have_best && !problem.solve(alpha, zero, best)) best = zero;  // no microslip start
  if (options.q_min > 0) {
    // Down to q_min: q is nearly linear in alpha here, so each step lands at or just below
    // half of q_min (a fixed factor of 4 once needed more than 200 steps from a high start).
    for (int it = 0; it < 200 && best.alpha > 0 && best.q > options.q_min; ++it) {
      State s;
      const double factor = std::min(0.25, 0.5 * options.q_min / best.q);
      if (!problem.solve(best.alpha * factor, zero, s)) break;
      best = s;
    }
  }
  return best;
}

// Step 2's outcome: every converged level, the last one, and the doubling step that
// crosses full macroslip (with q_max the curve may run past it).
struct March {
  std::vector<State> levels;
  State end;
  bool crossed = false;
  State before_macroslip, after_macroslip;
};

constexpr int kMaxDoublings = 2100;

// Step 2: march up by doubling until the curve must stop, then bracket the end.
March march_to_end(Problem& problem, const QsmaOptions& options, const State& start, int mode,
                   QsmaSummary* summary) {
  March m;
  m.levels.push_back(start);
  State hi;
  Stop reason = Stop::kNone;
  // Doubling spans the whole double range in 2100 steps (each a few microseconds): a q_max
  // of 1e100 is reached, not cut off silently after 2^200 of the start.
  for (int it = 0; it < kMaxDoublings; ++it) {
    State next;
    const double alpha = 2 * m.levels.back().alpha;
    const bool ok = std::isfinite(alpha) && problem.solve(alpha, m.levels.back(), next);
    if (ok && !m.crossed && problem.macroslip_margin(next) >= 0 &&
        problem.macroslip_margin(m.levels.back()) < 0) {
      m.crossed = true;
      m.before_macroslip = m.levels.back();
      m.after_macroslip = next;
    }
    reason = problem.classify(ok, next);
    if (reason != Stop::kNone) {
      hi = next;
      break;
    }
    m.levels.push_back(next);
  }
  m.end = m.levels.back();
  if (reason == Stop::kNone) {
    summary->termination = QsmaTermination::kFullMacroslip;
    summary->message = fmt::format(
        "mode {}: not every Iwan element reached macroslip within 2^{} of the starting load", mode,
        kMaxDoublings);
    return m;
  }
  // Bisection in ln alpha: a finite bracket closes to limit_tolerance in well under 200
  // halvings; the bound keeps an overflowing one from running on.
  for (int it = 0; it < 200 && hi.alpha / m.end.alpha - 1 > options.limit_tolerance; ++it) {
    State mid;
    const double alpha = std::sqrt(m.end.alpha) * std::sqrt(hi.alpha);
    if (!std::isfinite(alpha)) break;
    const bool ok = problem.solve(alpha, m.end, mid);
    const Stop why = problem.classify(ok, mid);
    if (why == Stop::kNone) {
      m.end = mid;
      m.levels.push_back(mid);
    } else {
      hi = mid;
      reason = why;
    }
  }
  if (reason == Stop::kNoSolution) {
    summary->termination = QsmaTermination::kLimitLoad;
  } else if (reason == Stop::kQmax) {
    m.end = problem.find_q(options.q_max, m.end, hi);
    summary->termination = QsmaTermination::kReachedQmax;
  } else {
    m.end = hi;
    summary->termination = QsmaTermination::kFullMacroslip;
  }
  std::sort(m.levels.begin(), m.levels.end(),
            [](const State& x, const State& y) { return x.alpha < y.alpha; });
  return m;
}

// The converged level bracketing a root of an increasing f along the march: the states
// just before (f < 0) and at or past (f >= 0) it; false when f changes sign nowhere.
template <class F>
bool bracket(const March& m, F f, State* below, State* above) {
  std::vector<const State*> all;
  for (const State& s : m.levels) all.push_back(&s);
  all.push_back(&m.end);
  for (size_t i = 1; i < all.size(); ++i) {
    if (f(*all[i - 1]) < 0 && f(*all[i]) >= 0) {
      *below = *all[i - 1];
      *above = *all[i];
      return true;
    }
  }
  return false;
}

// Step 3: the first point, the automatic start or q = q_min; false (with the summary
// saying why) when q_min lies past the end of the curve.
bool find_first(Problem& problem, const QsmaOptions& options, const March& m, const State& start,
                int mode, QsmaSummary* summary, State* first) {
  *first = start;
  if (options.q_min <= 0 || start.q >= options.q_min) return true;
  if (m.end.q < options.q_min) {
    summary->termination = QsmaTermination::kEmptyRange;
    summary->message = fmt::format(
        "mode {}: q_min = {:.6g} lies beyond the end of the curve (q = {:.6g} at force "
        "amplitude {:.6g})",
        mode, options.q_min, m.end.q, m.end.alpha);
    return false;
  }
  State a, b;
  const auto f = [&](const State& s) { return std::log(s.q / options.q_min); };
  *first = bracket(m, f, &a, &b) ? problem.find_q(options.q_min, a, b) : m.end;
  return true;
}

// Step 4: the load levels of the output and the states pinned on some of them (the
// first, the last, and the onset of full macroslip on a curve continued past it).
struct Grid {
  std::vector<double> alphas;
  std::vector<std::pair<size_t, State>> pinned;
};

// Without q_max the points sit densely through the transition: 30 % log-spaced from the
// start to the first element's onset of macroslip, the rest from there to the end
// (clustered below a limit load). With q_max, log-spaced, and the grid point nearest the
// onset of full macroslip moves onto it, so that interpolating the curve never straddles
// its kink (the tangent of the last elements to slip drops from S to 0); slips that only
// approach phi_max have no kink there, and the grid stays as it is.
Grid output_grid(Problem& problem, const QsmaOptions& options, const March& m, const State& first,
                 QsmaTermination termination) {
  Grid g;
  const int n = options.points;
  const bool cluster = termination == QsmaTermination::kLimitLoad;
  State onset, a, b;
  const auto margin = [&](const State& s) { return problem.onset_margin(s); };
  const bool split = options.q_max <= 0 && n >= 6 && margin(first) < 0 &&
                     bracket(m, margin, &a, &b) &&
                     (onset = problem.find_onset(a, b)).alpha < 0.99 * m.end.alpha;
  if (split) {
    const int micro = std::max(2, static_cast<int>(std::lround(0.3 * n)));
    g.alphas = log_grid(first.alpha, onset.alpha, micro, false);
    const std::vector<double> rest = grid_to_end(onset.alpha, m.end.alpha, n - micro, cluster);
    g.alphas.insert(g.alphas.end(), rest.begin(), rest.end());
    g.pinned.emplace_back(static_cast<size_t>(micro), onset);
  } else {
    g.alphas = grid_to_end(first.alpha, m.end.alpha, n, cluster);
  }
  g.pinned.emplace_back(0, first);
  g.pinned.emplace_back(g.alphas.size() - 1, m.end);
  // The doubling step that crossed full macroslip, or else two converged levels that straddle
  // it: a doubling step across it can fail to converge (past the kink the structure's
  // tangent is nearly singular) where the bisection's levels that follow converge.
  State before = m.before_macroslip, after = m.after_macroslip;
  const auto crossed = [&] {
    return m.crossed ||
           bracket(
               m, [&](const State& s) { return problem.macroslip_margin(s); }, &before, &after);
  };
  const std::optional<State> kink = options.q_max > 0 && g.alphas.size() > 2 && crossed()
                                        ? problem.find_macroslip(before, after)
                                        : std::nullopt;
  if (kink) {
    const State& full = *kink;
    const double x = std::log(full.alpha);
    size_t best = 1;
    for (size_t i = 2; i + 1 < g.alphas.size(); ++i) {
      if (std::abs(std::log(g.alphas[i]) - x) < std::abs(std::log(g.alphas[best]) - x)) best = i;
    }
    if (g.alphas[best - 1] < full.alpha && full.alpha < g.alphas[best + 1]) {
      g.alphas[best] = full.alpha;
      g.pinned.emplace_back(best, full);
    }
  }
  return g;
}

// Step 5: solve at every grid level, continuing from the previous one, and evaluate it.
// A grid level far above the previous one (a range of many decades on few points) is solved
// from the highest converged march level below it instead, at most a doubling away. A level
// that still fails, or a point with a non-finite column, ends the curve there and the summary
// says so (qsma() then reports the shortfall).
std::vector<QsmaPoint> evaluate_grid(Problem& problem, const Grid& g, const March& m, int mode,
                                     QsmaSummary* summary) {
  std::vector<QsmaPoint> curve;
  State cur;
  for (size_t i = 0; i < g.alphas.size(); ++i) {
    State s;
    const auto pin =
        std::find_if(g.pinned.begin(), g.pinned.end(), [&](const auto& p) { return p.first == i; });
    bool ok = true;
    if (pin != g.pinned.end()) {
      s = pin->second;
    } else if (!problem.solve(g.alphas[i], cur, s)) {
      const State* from = nullptr;
      for (const State& level : m.levels) {
        if (level.alpha <= g.alphas[i] && (!from || level.alpha > from->alpha)) from = &level;
      }
      ok = from && problem.solve(g.alphas[i], *from, s);
    }
    const QsmaPoint pt = ok ? problem.point(s) : QsmaPoint{};
    // Never a non-finite number in a curve: end it before.
    if (!ok || !std::isfinite(pt.frequency_hz) || !std::isfinite(pt.damping_ratio) ||
        !std::isfinite(pt.ringdown_frequency_hz) || !std::isfinite(pt.ringdown_damping_ratio) ||
        !std::isfinite(pt.harmonic_damping_ratio) || !std::isfinite(pt.max_slip) ||
        !(pt.modal_amplitude > 0)) {
      summary->message = fmt::format(
          "mode {}: {} at force amplitude {:.6g} (point {} of {}); the curve cannot go on", mode,
          ok ? "a column is not a finite number" : "no static solution found", g.alphas[i], i + 1,
          g.alphas.size());
      summary->incomplete = true;
      break;
    }
    curve.push_back(pt);
    cur = s;
  }
  return curve;
}

// Step 6: the summary's end point and message.
void finish_summary(const std::vector<QsmaPoint>& curve, int mode, const QsmaOptions& options,
                    QsmaSummary* summary) {
  summary->end_force = curve.back().force_amplitude;
  summary->end_modal_amplitude = curve.back().modal_amplitude;
  if (!summary->message.empty()) return;
  switch (summary->termination) {
    case QsmaTermination::kLimitLoad:
      summary->message = fmt::format(
          "mode {}: no static solution past force amplitude {:.6g} (modal amplitude {:.6g}): "
          "the joints slide freely; the curve stops there",
          mode, summary->end_force, summary->end_modal_amplitude);
      break;
    case QsmaTermination::kFullMacroslip:
      summary->message = fmt::format(
          "mode {}: every Iwan element carrying the mode's joint slip is in macroslip from "
          "force amplitude {:.6g}",
          mode, summary->end_force);
      break;
    default:
      summary->message = fmt::format("mode {}: reached q_max = {:.6g}", mode, options.q_max);
  }
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

QsmaMode::QsmaMode(const JointCondensation& model, int mode) {
  const int column = model.modes().rigid_count + mode - 1;
  omega2 = model.modes().omega2(column);
  p = model.joint_shapes().col(column);
  g = model.condensed_stiffness() * (p / omega2);
}

QsmaDof::QsmaDof(const JointCondensation& model, int mode, Eigen::Index dof) {
  const Eigen::MatrixXd& psi = model.constraint_modes();
  if (psi.rows() == 0)
    throw InputError(
        "QSMA: this condensation carries no constraint modes to read a DOF's deflection");
  if (dof < 0 || dof >= psi.rows())
    throw InputError(fmt::format("QSMA: DOF {} does not exist: the model has {}", dof, psi.rows()));
  const QsmaMode m(model, mode);
  const double phi = model.modes().shapes(dof, model.modes().rigid_count + mode - 1);
  z = psi.row(dof).transpose();
  e = (phi - z.dot(m.p)) / m.omega2;
  sign = phi < 0 ? -1.0 : 1.0;
  shape = std::abs(phi);
}

QsmaPoint qsma_point(const JointCondensation& m, int mode, double alpha, const Eigen::VectorXd& r,
                     const Eigen::VectorXd& solver_tangent) {
  return qsma_point(m, QsmaMode(m, mode), alpha, r, solver_tangent);
}

QsmaPoint qsma_point(const JointCondensation& m, const QsmaMode& mode, double alpha,
                     const Eigen::VectorXd& r, const Eigen::VectorXd& solver_tangent,
                     const Eigen::VectorXd* first_harmonic) {
  Eigen::VectorXd t = m.tangent(mode.g, r);
  if (t.size() == 0) t = solver_tangent;  // singular exactly at a limit point: the solver's own
  if (t.size() == 0) t = r / alpha;
  return qsma_point_with_tangent(m, mode, alpha, r, t, first_harmonic);
}

QsmaPoint qsma_point_with_tangent(const JointCondensation& m, const QsmaMode& mode, double alpha,
                                  const Eigen::VectorXd& r, const Eigen::VectorXd& t,
                                  const Eigen::VectorXd* first_harmonic) {
  const double omega2 = mode.omega2;
  const Eigen::VectorXd& p = mode.p;
  Eigen::VectorXd h, dh;
  m.softening(r, h, dh);
  const double q = (alpha + p.dot(h)) / omega2;
  QsmaPoint pt;
  pt.force_amplitude = alpha;
  pt.modal_amplitude = q;
  pt.frequency_hz = std::sqrt(alpha / q) / kTwoPi;
  const double d = m.dissipation(r);
  pt.damping_ratio = d / (kTwoPi * alpha * q);
  pt.max_slip = r.cwiseAbs().maxCoeff();
  // First-harmonic modal stiffness (qsma.h): omega_1^2 = omega_r^2 - p^T diag(K_T - k_1) r / q.
  const Eigen::VectorXd k1 = first_harmonic ? *first_harmonic : m.first_harmonic_stiffness(r);
  double w1 = omega2;
  for (int j = 0; j < m.size(); ++j) w1 -= p(j) * (m.linear_stiffness(j) - k1(j)) * r(j) / q;
  w1 = std::max(w1, 0.0);
  pt.ringdown_frequency_hz = std::sqrt(w1) / kTwoPi;
  pt.harmonic_damping_ratio = d / (kTwoPi * w1 * q * q);
  // dE/dq along the curve (qsma.h): alpha + sum_j (dr_j/dq) (h_j - r_j h'_j), with
  // dr/dalpha = (K_c - diag h')^{-1} g and dq/dalpha = (1 + p^T diag(h') dr/dalpha) / omega_r^2.
  const double dq = (1 + p.dot(dh.cwiseProduct(t))) / omega2;
  const double dE = alpha + t.dot(h - r.cwiseProduct(dh)) / dq;
  pt.ringdown_damping_ratio = d / (kTwoPi * q * dE);
  // The structure's own damping Z adds to each (method.md section 2 point 4): a viscous modal
  // damping dissipates 2 pi Z q dE/dq per cycle, so to first order every ratio gains Z.
  const double z = m.linear_damping();
  pt.damping_ratio += z;
  pt.ringdown_damping_ratio += z;
  pt.harmonic_damping_ratio += z;
  return pt;
}

std::vector<QsmaPoint> qsma(const JointCondensation& model, int mode, const QsmaOptions& options,
                            QsmaSummary* summary) {
  if (!summary) throw std::invalid_argument("qsma: summary must not be null");
  if (const std::string e = options.error(); !e.empty()) {
    throw InputError(fmt::format("qsma: {}", e));
  }
  *summary = QsmaSummary{};
  if (mode < 1 || mode > model.elastic_count()) {
    throw InputError(
        fmt::format("mode {} does not exist: the model has {} "
                    "(numbered from 1)",
                    mode, counted(model.elastic_count(), "elastic mode")));
  }
  const int column = model.modes().rigid_count + mode - 1;
  Problem problem(model, column, options, summary);
  const double shape_scale = model.joint_shapes().cwiseAbs().maxCoeff();
  if (problem.c().lpNorm<Eigen::Infinity>() * problem.omega2() <= 1e-9 * shape_scale) {
    return linear_curve(problem.omega2(), mode, options, summary);
  }
  // K_T,j C_jj is the share of coordinate j's linear flexibility its Iwan elements give
  // (K_T C_jj = 1: nothing else holds it). Below 1e-12 everywhere the structure holds the
  // joints so stiffly that their slip is rounding noise of its deflection.
  double share = 0;
  for (int j = 0; j < model.size(); ++j) {
    share = std::max(share, model.linear_stiffness(j) * model.flexibility()(j, j));
  }
  if (!(share > 1e-12)) {
    throw InputError(fmt::format(
        "qsma: mode {}: the structure holds the Iwan joints {:.3g} times more stiffly than "
        "they hold themselves: their slip is below rounding (check the stiffness units)",
        mode, 1 / share));
  }
  const State start = find_start(problem, model, options);
  if (start.alpha <= 0) {
    summary->termination = QsmaTermination::kLimitLoad;
    summary->message = fmt::format("mode {}: no static solution even at the smallest load", mode);
    return {};
  }
  const March march = march_to_end(problem, options, start, mode, summary);
  State first;
  if (!find_first(problem, options, march, start, mode, summary, &first)) return {};
  const Grid grid = output_grid(problem, options, march, first, summary->termination);
  std::vector<QsmaPoint> curve = evaluate_grid(problem, grid, march, mode, summary);
  // Amplitude strictly increases along a curve: equal or falling neighbours mean the range
  // collapsed (a start that could not be moved to q_min once gave 11 identical rows).
  for (size_t i = 1; i < curve.size() && !summary->incomplete; ++i) {
    if (!(curve[i].modal_amplitude > curve[i - 1].modal_amplitude)) {
      summary->message = fmt::format(
          "mode {}: points {} and {} have modal amplitudes {:.17g} and {:.17g}, not increasing; "
          "the curve cannot be resolved there",
          mode, i, i + 1, curve[i - 1].modal_amplitude, curve[i].modal_amplitude);
      summary->incomplete = true;
    }
  }
  if (summary->incomplete || curve.empty()) {
    summary->incomplete = true;
    if (summary->message.empty()) summary->message = fmt::format("mode {}: no point", mode);
    return {};
  }
  finish_summary(curve, mode, options, summary);
  return curve;
}

}  // namespace jointlab::model
