#include "jointlab/core/rank_correlation.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <numeric>

namespace jointlab {

std::vector<double> ranks(const std::vector<double>& v) {
  std::vector<size_t> order(v.size());
  for (size_t i = 0; i < v.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return v[a] < v[b]; });
  std::vector<double> r(v.size());
  for (size_t k = 0; k < order.size(); ++k) r[order[k]] = static_cast<double>(k);
  return r;
}

double rank_correlation(const std::vector<double>& a, const std::vector<double>& b) {
  assert(a.size() == b.size() && a.size() >= 2);
  const std::vector<double> r1 = ranks(a), r2 = ranks(b);
  const double mean = 0.5 * static_cast<double>(a.size() - 1);
  double s11 = 0, s22 = 0, s12 = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    s11 += (r1[i] - mean) * (r1[i] - mean);
    s22 += (r2[i] - mean) * (r2[i] - mean);
    s12 += (r1[i] - mean) * (r2[i] - mean);
  }
  return s12 / std::sqrt(s11 * s22);
}

double rank_trend(const std::vector<double>& x) {
  assert(x.size() >= 2);
  const size_t n = x.size();
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return x[a] < x[b]; });
  double d2 = 0;
  for (size_t r = 0; r < n; ++r) {
    const double d = static_cast<double>(r) - static_cast<double>(order[r]);
    d2 += d * d;
  }
  const double m = static_cast<double>(n);
  return 1 - 6 * d2 / (m * (m * m - 1));
}

}  // namespace jointlab
