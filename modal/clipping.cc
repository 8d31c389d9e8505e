#include "jointlab/modal/clipping.h"

#include <algorithm>

namespace jointlab::modal {

Clipping find_clipping(const Eigen::Ref<const Eigen::VectorXd>& x) {
  Clipping c;
  if (x.size() == 0) return c;
  const auto side = [&](double value, bool& pinned) {
    Eigen::Index count = 0, runs = 0, last = -1;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      if (x(k) != value) continue;
      ++count;
      if (last != k - 1) ++runs;
      last = k;
    }
    if (count < kMinClippedSamples || runs < kMinClippedRuns) return;
    pinned = true;
    c.samples += count;
    c.last = std::max(c.last, last);
  };
  c.high = x.maxCoeff();
  c.low = x.minCoeff();
  side(c.high, c.high_pinned);
  if (c.low != c.high) side(c.low, c.low_pinned);
  return c;
}

}  // namespace jointlab::modal
