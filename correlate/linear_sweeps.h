// One-at-a-time sweeps of update_linear()'s result (internal): theta_k times 10^[-d, d], the
// others held, every pair followed by its full shape from the result (the paper's Figure 3).
#pragma once

#include "jointlab/correlate/linear_problem.h"

namespace jointlab::correlate::detail {

/// The sweeps of every set around `result`, into s.parameters (value, sweep_*).
void sweeps(const LinearProblem& p, const TrackedPoint& result, LinearUpdateSummary& s);

}  // namespace jointlab::correlate::detail
