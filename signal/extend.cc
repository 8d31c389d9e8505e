#include "jointlab/signal/extend.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <Eigen/Dense>

namespace jointlab::signal {

namespace {

// Forward continuation of y by `count` samples; zeros if unstable.
Eigen::VectorXd continue_forward(const Eigen::VectorXd& y, Eigen::Index count, int order,
                                 Eigen::Index fit_length, double max_growth, Eigen::Index lag) {
  const Eigen::Index n = y.size();
  const Eigen::Index len = std::min(fit_length, n);
  const Eigen::Index span = order * lag;  // history one prediction needs
  if (count <= 0 || len < span + 4 * order) {
    return Eigen::VectorXd::Zero(std::max<Eigen::Index>(count, 0));
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
  // Work on y followed by the continuation, so every lagged sample is at hand.
  Eigen::VectorXd full(n + count);
  full.head(n) = y;
  for (Eigen::Index k = n; k < n + count; ++k) {
    double v = 0;
    for (int j = 1; j <= order; ++j) v += c(j - 1) * full(k - j * lag);
    full(k) = v;
  }
  const Eigen::VectorXd out = full.tail(count);
  const double ref = std::sqrt(y.tail(len).squaredNorm() / static_cast<double>(len));
  const double got = std::sqrt(out.squaredNorm() / static_cast<double>(count));
  if (!std::isfinite(got) || got > max_growth * ref) return Eigen::VectorXd::Zero(count);
  return out;
}

}  // namespace

Extension extend_record(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Index before,
                        Eigen::Index after, int order, Eigen::Index fit_length, double max_growth,
                        Eigen::Index lag) {
  assert(order >= 1 && before >= 0 && after >= 0 && lag >= 1);
  const Eigen::Index n = x.size();
  Extension e;
  e.before = before;
  e.after = after;
  e.samples.resize(before + n + after);
  e.samples.segment(before, n) = x;
  e.samples.tail(after) = continue_forward(x, after, order, fit_length, max_growth, lag);
  // Backward continuation is forward continuation of the time-reversed record.
  const Eigen::VectorXd reversed = x.reverse();
  e.samples.head(before) =
      continue_forward(reversed, before, order, fit_length, max_growth, lag).reverse();
  return e;
}

}  // namespace jointlab::signal
