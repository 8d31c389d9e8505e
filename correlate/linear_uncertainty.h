// Standard deviations of the fitted sets at the result of update_linear() (internal): the
// covariance (J^T W^2 J)^-1 frequency_std^2 over the fitted sets, scaled by the reduced
// chi-square where the frequencies scatter beyond their stated uncertainty and widened for
// Student's t over nu = pairs - fitted degrees of freedom (linear_update.h has the method).
#pragma once

#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <Eigen/Core>

#include "jointlab/correlate/linear_problem.h"

namespace jointlab::correlate::detail {

/// The stated frequency uncertainty sf for the report, with each measured mode whose own sigma is
/// wider (id(i) names mode i): "0.1 %, test mode 2's 0.427 %".
template <class Id>
std::string stated_noise(double sf, const Eigen::VectorXd& sigma, const Id& id) {
  std::vector<std::string> wider;
  for (Eigen::Index i = 0; i < sigma.size(); ++i)
    if (sigma(i) > sf * (1 + 1e-9))
      wider.push_back(fmt::format("test mode {}'s {:.3g} %", id(i), 100 * sigma(i)));
  if (wider.empty()) return fmt::format("{:.3g} %", 100 * sf);
  return fmt::format("{:.3g} %, {}", 100 * sf, fmt::join(wider, ", "));
}

/// What the standard deviations of a scatter-set scale are, for the report, or why none is
/// stated.
std::string scatter_widening(const LinearUpdateSummary& s);

/// The variance the standard deviations rest on: frequency_std^2, times the reduced chi-square
/// and Student's widening squared where they rest on the frequencies' scatter.
double sigma_variance(const LinearProblem& p, const LinearUpdateSummary& s);

/// The chi-square rise, in units of sigma_variance(), that marks 3 standard deviations along a
/// profile: 9 where the stated noise sets the scale; where the scale is the scatter's, the square
/// of Student's t's one-sided 0.99865 point over the degrees of freedom divided by its widening
/// (18.2 over 5), in the share the widening takes.
double three_sigma_rise(const LinearUpdateSummary& s);

/// Standard deviations of the fitted sets at the result `at` (the least-squares fit `ls` sets
/// the chi-square), the sets acting together named, the degrees of freedom counted.
void report_uncertainty(const LinearProblem& p, const Eigen::VectorXd& theta,
                        const LinearEvaluation& at, const LinearEvaluation& ls,
                        const std::vector<char>& held, LinearUpdateSummary& s);

}  // namespace jointlab::correlate::detail
