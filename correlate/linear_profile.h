// Fitted sets the frequencies bound from one side only, and standard deviations the chi-square
// does not bear out (internal to update_linear()): each set's chi-square profile walked each way
// from the result, the other fitted sets fitted again at each value, to where it rises by 9.
#pragma once

#include <optional>
#include <vector>

#include "jointlab/correlate/linear_problem.h"

namespace jointlab::correlate::detail {

/// Each fitted set with a standard deviation: one_sided where a bound comes before the rise of
/// 9, else a third of the farther distance where wider than the local slope's.
void report_one_sided(const LinearProblem& p, const TrackedPoint& point, const LinearEvaluation& at,
                      const std::vector<char>& held, LinearUpdateSummary& s);

/// How far below the result `point` set k may go: where its chi-square profile (the sets not
/// `held` fitted again, in units of the variance the summary's sigmas rest on) rises by 9, three
/// standard deviations; none where it does not within the set's range or its pairs are lost.
std::optional<double> lower_limit(const LinearProblem& p, const TrackedPoint& point,
                                  const std::vector<char>& held, int k,
                                  const LinearUpdateSummary& s);

/// Each pair of fitted sets acting together (s.collinear) whose stated combination
/// theta_a + weight theta_b does not hold along the valley of equal fit: set a walked each way
/// from the least-squares `point` to where the chi-square (the other sets not `held` fitted
/// again) rises by 9 or the bound, the combination's value is withdrawn (0, no standard
/// deviation) and the warning says why, where it changes there by more than half its standard
/// deviation from its value at `point`; `theta` is the result's stiffnesses (the rule's).
void check_combinations(const LinearProblem& p, const TrackedPoint& point,
                        const LinearEvaluation& at, const std::vector<char>& held,
                        const Eigen::VectorXd& theta, LinearUpdateSummary& s);

}  // namespace jointlab::correlate::detail
