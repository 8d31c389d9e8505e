#include "jointlab/signal/extend.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <tuple>
#include <utility>

#include <Eigen/Dense>

namespace jointlab::signal {

namespace {

// Forward continuation of y by `count` samples. Where it grows past max_growth
// times the RMS it was fitted on (an unstable or over-damped model run
// backwards) it is cut: the faithful part before that point is kept, its last
// half faded out by a half cosine, and zeros follow. Returns the samples and the
// number of them that are an unfaded continuation.
// Only the last fit_length samples of y are used (and copied): a record may be far longer.
std::pair<Eigen::VectorXd, Eigen::Index> continue_forward(
    const Eigen::Ref<const Eigen::VectorXd>& whole, Eigen::Index count, int order,
    Eigen::Index fit_length, double max_growth, Eigen::Index lag) {
  const Eigen::Index len = std::min(fit_length, whole.size());
  const auto y = whole.tail(len);
  const Eigen::Index n = len;
  const Eigen::Index span = order * lag;  // history one prediction needs
  if (count <= 0 || len < span + 4 * order) {
    return {Eigen::VectorXd::Zero(std::max<Eigen::Index>(count, 0)), 0};
  }
  const Eigen::Index first = n - len;
  // Neighbouring rows carry nearly the same equation in an oversampled record:
  // keep every row_step-th row, at least 8 per unknown.
  const Eigen::Index row_step = std::max<Eigen::Index>(1, (len - span) / (8 * order));
  const Eigen::Index rows = (len - span - 1) / row_step + 1;
  Eigen::MatrixXd A(rows, order);
  Eigen::VectorXd b(rows);
  for (Eigen::Index r = 0; r < rows; ++r) {
    const Eigen::Index k = first + span + r * row_step;
    for (int j = 1; j <= order; ++j) A(r, j - 1) = y(k - j * lag);
    b(r) = y(k);
  }
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
  // Continued up to the first sample past the limit (a sinusoid of RMS r peaks at r sqrt 2):
  // what follows it is dropped. Work on y followed by the continuation, so every lagged
  // sample is at hand.
  const double ref = std::sqrt(y.tail(len).squaredNorm() / static_cast<double>(len));
  const double limit = max_growth * ref * std::sqrt(2.0);
  Eigen::VectorXd full(n + count);
  full.head(n) = y;
  Eigen::Index keep = 0;
  for (; keep < count; ++keep) {
    const Eigen::Index k = n + keep;
    double v = 0;
    for (int j = 1; j <= order; ++j) v += c(j - 1) * full(k - j * lag);
    if (!(std::isfinite(v) && std::abs(v) <= limit)) break;
    full(k) = v;
  }
  Eigen::VectorXd out = Eigen::VectorXd::Zero(count);
  out.head(keep) = full.segment(n, keep);
  if (keep == count) return {out, count};
  const Eigen::Index faithful = keep / 2;
  for (Eigen::Index k = faithful; k < keep; ++k) {
    const double x = static_cast<double>(k - faithful) / static_cast<double>(keep - faithful);
    out(k) *= 0.5 * (1.0 + std::cos(std::numbers::pi * x));
  }
  return {out, faithful};
}

}  // namespace

Continuation continue_record(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Index before,
                             Eigen::Index after, int order, Eigen::Index fit_length,
                             double max_growth, Eigen::Index lag) {
  assert(order >= 1 && before >= 0 && after >= 0 && lag >= 1);
  Continuation c;
  std::tie(c.after, c.after_valid) = continue_forward(x, after, order, fit_length, max_growth, lag);
  // Backward continuation is forward continuation of the time-reversed record (of the samples
  // it is fitted on).
  const Eigen::VectorXd reversed = x.head(std::min(fit_length, x.size())).reverse();
  auto [head, before_valid] =
      continue_forward(reversed, before, order, fit_length, max_growth, lag);
  c.before = head.reverse();
  c.before_valid = before_valid;
  return c;
}

Extension extend_record(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Index before,
                        Eigen::Index after, int order, Eigen::Index fit_length, double max_growth,
                        Eigen::Index lag) {
  const Eigen::Index n = x.size();
  const Continuation c = continue_record(x, before, after, order, fit_length, max_growth, lag);
  Extension e;
  e.before = before;
  e.after = after;
  e.samples.resize(before + n + after);
  e.samples.head(before) = c.before;
  e.samples.segment(before, n) = x;
  e.samples.tail(after) = c.after;
  e.before_valid = c.before_valid;
  e.after_valid = c.after_valid;
  return e;
}

}  // namespace jointlab::signal
