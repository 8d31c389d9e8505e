// The median of a sample.
#pragma once

#include <algorithm>
#include <cassert>
#include <vector>

namespace jointlab {

/// The median of `x` (not empty): its middle value, or the mean of the middle two.
inline double median(std::vector<double> x) {
  assert(!x.empty());
  std::sort(x.begin(), x.end());
  const size_t n = x.size();
  return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

}  // namespace jointlab
