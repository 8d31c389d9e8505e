#include "jointlab/modal/clipping.h"

#include <algorithm>

namespace jointlab::modal {

Clipping find_clipping(const Eigen::Ref<const Eigen::VectorXd>& x) {
  Clipping c;
  if (x.size() == 0) return c;
  c.high = x.maxCoeff();
  c.low = x.minCoeff();
  // Most channels reach their extremes once: one branch-free counting pass settles them, and
  // only a side reached at kMinClippedSamples or more has its runs counted.
  Eigen::Index at_high = 0, at_low = 0;
  const double* v = x.data();
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    at_high += v[k] == c.high;
    at_low += v[k] == c.low;
  }
  const auto side = [&](double value, Eigen::Index count, bool& pinned) {
    if (count < kMinClippedSamples) return;
    // Only flat runs count: a sine's peak samples, however often they repeat its largest
    // value, stand alone (or in twos, a peak midway between two samples).
    Eigen::Index runs = 0, last = -1, length = 0;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      if (v[k] != value) continue;
      length = last == k - 1 ? length + 1 : 1;
      if (length == kMinClippedRunSamples) ++runs;
      last = k;
    }
    if (runs < kMinClippedRuns) return;
    pinned = true;
    c.samples += count;
    c.last = std::max(c.last, last);
  };
  side(c.high, at_high, c.high_pinned);
  if (c.low != c.high) side(c.low, at_low, c.low_pinned);
  return c;
}

}  // namespace jointlab::modal
