// The rules that move on from the least-squares fit to the tolerance (linear_tolerance.h).
#include "jointlab/correlate/linear_tolerance.h"

#include <cmath>
#include <optional>

#include <fmt/format.h>

namespace jointlab::correlate::detail {
namespace {

// Within the tolerance: every pair of `at` kept, every paired error at most the tolerance.
auto within_tolerance(const LinearProblem& p, const LinearEvaluation& at) {
  return [&p, pairs = at.pairing.pairs.size()](const LinearEvaluation& e) {
    return e.pairing.pairs.size() == pairs && e.max_error() <= p.options.tolerance;
  };
}

}  // namespace

// The paper's rule: the smallest theta_k with the others fitted and every error within the
// tolerance; `point` moves to it.
void smallest_rule(const LinearProblem& p, int k, std::vector<char> held, TrackedPoint& point,
                   LinearUpdateSummary& s) {
  const auto within = within_tolerance(p, p.evaluate(point));
  if (!within(p.evaluate(point))) {
    s.tolerance_met = false;
    s.warnings.push_back(
        fmt::format("the tolerance {:.3g} % cannot be met: the least-squares fit leaves a largest "
                    "frequency error of {:.3g} %; kept the least-squares result",
                    100 * p.options.tolerance, 100 * p.evaluate(point).max_error()));
    return;
  }
  held[static_cast<size_t>(k)] = 1;
  // feasible(v): fit the others at theta_k = v from the last feasible point.
  TrackedPoint best = point;
  auto feasible = [&](double v) {
    Eigen::VectorXd x = best.x;
    x(k) = v;
    std::optional<TrackedPoint> trial = p.move(best, x);
    if (!trial) return false;
    fit(p, *trial, held, nullptr);
    const LinearEvaluation e = p.evaluate(*trial);
    if (!within(e)) return false;
    best = std::move(*trial);
    s.history.push_back(e.cost());
    s.theta_history.push_back(best.x.array().exp());
    return true;
  };
  double hi = point.x(k), lo = std::log(p.lower(k));
  if (feasible(lo)) {
    s.warnings.push_back(fmt::format(
        "{}: every value down to its lower bound {:.6g} keeps the errors within {:.3g} %: the "
        "frequencies do not bound it from below, and the result is that bound",
        p.names[k], p.lower(k), 100 * p.options.tolerance));
  } else {
    // ln theta to 1e-3: theta_m within 0.1 % of the smallest feasible value.
    for (int it = 0; it < 60 && hi - lo > 1e-3; ++it) {
      const double mid = 0.5 * (lo + hi);
      (feasible(mid) ? hi : lo) = mid;
    }
  }
  point = best;
  s.parameters[k].smallest_within_tolerance = std::exp(point.x(k));
}

// The smallest stiffness within the tolerance for each flat set, the others held; a set that
// meets it down to its lower bound stays where it is.
void smallest_flat(const LinearProblem& p, TrackedPoint& point, LinearUpdateSummary& s) {
  const auto within = within_tolerance(p, p.evaluate(point));
  for (int k = 0; k < p.size(); ++k) {
    if (!s.parameters[k].flat || s.parameters[k].held_by_user) continue;
    auto at = [&](double lx) -> std::optional<TrackedPoint> {
      Eigen::VectorXd x = point.x;
      x(k) = lx;
      std::optional<TrackedPoint> q = p.move(point, x);
      if (!q || !within(p.evaluate(*q))) return std::nullopt;
      return q;
    };
    if (!within(p.evaluate(point))) continue;
    double hi = point.x(k), lo = std::log(p.lower(k));
    if (at(lo)) {
      s.warnings.push_back(fmt::format(
          "{}: every value down to its lower bound {:.6g} keeps the errors within {:.3g} %: "
          "held at {:.6g}",
          p.names[k], p.lower(k), 100 * p.options.tolerance, std::exp(point.x(k))));
      continue;
    }
    for (int it = 0; it < 40 && hi - lo > 1e-4; ++it) {
      const double mid = 0.5 * (lo + hi);
      (at(mid) ? hi : lo) = mid;
    }
    if (std::optional<TrackedPoint> q = at(hi)) point = std::move(*q);
    s.parameters[k].smallest_within_tolerance = std::exp(point.x(k));
  }
}

}  // namespace jointlab::correlate::detail
