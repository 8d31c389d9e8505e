// Fitted sets the frequencies bound from one side only, and standard deviations the chi-square
// does not bear out (internal to update_linear()): each set's chi-square profile walked each way
// from the result, the other fitted sets fitted again at each value, to where it rises by 9.
#pragma once

#include <vector>

#include "jointlab/correlate/linear_problem.h"

namespace jointlab::correlate::detail {

/// Each fitted set with a standard deviation: one_sided where a bound comes before the rise of
/// 9, else a third of the farther distance where wider than the local slope's.
void report_one_sided(const LinearProblem& p, const TrackedPoint& point, const LinearEvaluation& at,
                      const std::vector<char>& held, LinearUpdateSummary& s);

}  // namespace jointlab::correlate::detail
