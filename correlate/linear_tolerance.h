// The rules of update_linear() that move on from the least-squares fit to the tolerance
// (internal): the paper's smallest stiffness of one set with every paired |r_i| within the
// tolerance, and each flat set lowered to the smallest value within it (bisection in ln theta).
#pragma once

#include <vector>

#include "jointlab/correlate/linear_problem.h"

namespace jointlab::correlate::detail {

/// The paper's rule: the smallest theta_k with the others fitted and every error within the
/// tolerance; `point` moves to it.
void smallest_rule(const LinearProblem& p, int k, std::vector<char> held, TrackedPoint& point,
                   LinearUpdateSummary& s);

/// The smallest stiffness within the tolerance for each flat set, the others held.
void smallest_flat(const LinearProblem& p, TrackedPoint& point, LinearUpdateSummary& s);

}  // namespace jointlab::correlate::detail
