#include "jointlab/campaign/plot_layout.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace jointlab::campaign {

void clip_x(std::vector<double>& x, std::vector<double>& y, double lo, double hi) {
  std::vector<double> cx, cy;
  for (size_t i = 0; i < x.size(); ++i) {
    if (i > 0) {
      // Where the segment from i - 1 to i crosses an end, in the segment's order.
      std::vector<double> w;
      for (const double xe : {lo, hi})
        if ((x[i - 1] - xe) * (x[i] - xe) < 0) w.push_back((xe - x[i - 1]) / (x[i] - x[i - 1]));
      std::sort(w.begin(), w.end());
      for (const double f : w) {
        cx.push_back(x[i - 1] + f * (x[i] - x[i - 1]));
        cy.push_back(y[i - 1] + f * (y[i] - y[i - 1]));
      }
    }
    if (x[i] >= lo && x[i] <= hi) {
      cx.push_back(x[i]);
      cy.push_back(y[i]);
    }
  }
  x = std::move(cx);
  y = std::move(cy);
}

std::vector<double> log_label_values(double lo, double hi, double min_gap) {
  const std::vector<double> mantissas = hi - lo > 2.0 ? std::vector<double>{1}
                                        : hi - lo > 0.8
                                            ? std::vector<double>{1, 2, 5}
                                            : std::vector<double>{1, 2, 3, 4, 5, 6, 7, 8, 9};
  std::vector<double> out;
  if (!(hi > lo)) return out;
  double last = -std::numeric_limits<double>::infinity();
  for (int k = static_cast<int>(std::floor(lo)); k <= static_cast<int>(std::ceil(hi)); ++k) {
    for (const double m : mantissas) {
      const double v = m * std::pow(10.0, k), p = std::log10(v);
      const double at = (p - lo) / (hi - lo);
      if (p < lo || p > hi || at - last < min_gap) continue;
      out.push_back(v);
      last = at;
    }
  }
  return out;
}

}  // namespace jointlab::campaign
