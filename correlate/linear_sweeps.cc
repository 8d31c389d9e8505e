// One-at-a-time sweeps around the result (linear_sweeps.h).
#include "jointlab/correlate/linear_sweeps.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "jointlab/core/parallel.h"

namespace jointlab::correlate::detail {
namespace {

double rms_of(const LinearEvaluation& e) {
  if (e.pairing.pairs.empty()) return 0;
  return std::sqrt(e.residuals.squaredNorm() / static_cast<double>(e.pairing.pairs.size()));
}

}  // namespace

// One-at-a-time sweeps around the result, every pair followed by its full shape from the result
// on a grid eight times finer than the sweep's.
void sweeps(const LinearProblem& p, const TrackedPoint& result, LinearUpdateSummary& s) {
  const LinearUpdateOptions& o = p.options;
  const int m = static_cast<int>(p.measured.frequency_hz.size());
  const int n = o.sweep_points;
  std::vector<double> d(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) d[i] = -o.sweep_decades + 2.0 * o.sweep_decades * i / (n - 1);
  // The start point is the sweep point nearest the result (factor 1).
  int mid = 0;
  for (int i = 1; i < n; ++i)
    if (std::abs(d[i]) < std::abs(d[mid])) mid = i;
  for (int k = 0; k < p.size(); ++k) {
    ParameterReport& r = s.parameters[k];
    r.value = std::exp(result.x(k));
    r.sweep_factor.assign(static_cast<size_t>(n), 0.0);
    r.sweep_rms.assign(static_cast<size_t>(n), std::nullopt);
    r.sweep_errors.assign(static_cast<size_t>(n), std::vector<std::optional<double>>(m));
    for (int i = 0; i < n; ++i) r.sweep_factor[i] = std::pow(10.0, d[i]);
  }
  // Outward from the result in each direction, reached along the sweep's own line. Each set's
  // two walks are independent of every other (pure eigen-solves; each writes its own points),
  // so they run side by side: the sweeps were 71 % of an update of the example beam's four sets
  // (256 eigen-solves of its 353 DOFs), and the numbers do not depend on the order.
  const auto walk = [&](int k, int from, int to, int step) {
    ParameterReport& r = s.parameters[k];
    std::optional<TrackedPoint> at = result;
    double last = 0;  // decades from the result
    for (int i = from; i != to + step; i += step) {
      if (!at) break;
      Eigen::VectorXd x = result.x;
      x(k) += d[i] * std::log(10.0);
      const int substeps = std::max(
          1,
          static_cast<int>(std::ceil(8 * std::abs(d[i] - last) * (n - 1) / (2 * o.sweep_decades))));
      at = p.move(*at, x, substeps);
      last = d[i];
      if (!at) break;
      const LinearEvaluation e = p.evaluate(*at);
      for (const ModePair& q : e.pairing.pairs)
        r.sweep_errors[i][static_cast<size_t>(q.measured)] = e.residuals(q.measured);
      if (!e.pairing.pairs.empty()) r.sweep_rms[i] = rms_of(e);
    }
  };
  parallel_for(
      2 * static_cast<size_t>(p.size()), 0, [] { return 0; },
      [&](size_t job, int) {
        const int k = static_cast<int>(job / 2);
        if (job % 2 == 0)
          walk(k, mid, n - 1, 1);
        else if (mid > 0)
          walk(k, mid - 1, 0, -1);
      });
}

}  // namespace jointlab::correlate::detail
