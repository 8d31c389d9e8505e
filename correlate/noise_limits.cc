#include "jointlab/correlate/noise_limits.h"

#include <cassert>
#include <cmath>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>

namespace jointlab::correlate {

double reduced_chi2_limit(int degrees_of_freedom) {
  assert(degrees_of_freedom > 0);
  const boost::math::chi_squared chi2(degrees_of_freedom);
  return boost::math::quantile(chi2, 0.99865) / degrees_of_freedom;
}

double variance_ratio_limit(int degrees_of_freedom_a, int degrees_of_freedom_b) {
  assert(degrees_of_freedom_a > 0 && degrees_of_freedom_b > 0);
  const boost::math::fisher_f f(degrees_of_freedom_a, degrees_of_freedom_b);
  return boost::math::quantile(f, 0.99865);
}

std::optional<double> student_t_variance(double degrees_of_freedom) {
  if (!(degrees_of_freedom > 2) || !std::isfinite(degrees_of_freedom)) return std::nullopt;
  return degrees_of_freedom / (degrees_of_freedom - 2);
}

}  // namespace jointlab::correlate
