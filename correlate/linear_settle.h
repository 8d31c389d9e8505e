// Pairs decided by the data in update_linear() (internal): least squares with the pairs
// followed by shape, the pairs made afresh by the rules at the result, each candidate pairing
// fitted, and the lowest cost kept where it is lower by at least 9 in chi-square units
// (2 (c_other - c_best) / sigma_f^2); otherwise the shapes decide where they can
// (shapes_decide), and the pairs cannot be decided where they cannot.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/SparseCore>

#include "jointlab/correlate/linear_problem.h"

namespace jointlab::correlate::detail {

/// At most this many candidate pairings are fitted from the start: each is a whole fit
/// (seconds on a thousand-DOF model), and more guesses than this say the sensors do not see
/// the modes apart.
constexpr size_t kMaxPairings = 16;

/// A warning about one measured mode's pair: a mode followed by its shape to a model mode whose
/// MAC at the result is below the threshold. update_linear() keeps it unless the line on the
/// pairs the shapes do not confirm (LinearUpdateSummary::unconfirmed) already names that mode.
struct PairWarning {
  int measured = -1;  ///< the measured mode's row
  std::string text;   ///< the warning
};

/// The outcome of settle().
struct Settled {
  TrackedPoint point;                   ///< the result
  LinearUpdateSummary record;           ///< history, iterations, warnings
  std::vector<PairWarning> weak_pairs;  ///< pairs followed below the MAC threshold at the result
  LinearUpdateStatus status = LinearUpdateStatus::kFailed;  ///< the fit's
  double cost = 0;                                          ///< at the result
  int rounds = 0;                                           ///< fits run
  std::string ambiguity;  ///< non-empty: the pairs cannot be decided
  /// With an ambiguity: the results that pair some mode otherwise and fit as well as `point`.
  std::vector<TrackedPoint> rivals;
  LinearEvaluation fresh_end;  ///< the pairs made afresh by the rules at the result
};

/// The pairings to try where the rules pair `at` (made afresh at `point`) by a guess: every
/// combination of one candidate for each of the first `ties` ties; else `point`.
std::vector<TrackedPoint> candidate_pairings(const TrackedPoint& point, const LinearEvaluation& at,
                                             size_t ties);

/// Whether the shapes decide for result `a` over result `b` where the frequencies cannot: each
/// measured mode the two pair otherwise has, at three sensors or more, a MAC of at least the
/// threshold with its partner at `a` and below it, by 0.3 or more, at `b`.
bool shapes_prefer(const LinearProblem& p, const TrackedPoint& a, const TrackedPoint& b);

/// Which of `points` (results whose costs the frequencies cannot tell apart) the shapes prefer
/// over every other that pairs some measured mode otherwise (shapes_prefer()), or none.
std::optional<size_t> shapes_decide(const LinearProblem& p,
                                    const std::vector<const TrackedPoint*>& points);

/// The warning where the shapes decided for result `a` over `b`: each mode they pair otherwise,
/// with its MAC at each, and both costs.
std::string shapes_decided(const LinearProblem& p, const TrackedPoint& a, double cost_a,
                           const TrackedPoint& b, double cost_b);

/// Why the update stops where results `a` and `b` (costs `cost_a`, `cost_b`) pair some measured
/// mode otherwise and the data cannot tell them apart (`why`, in brackets): each such mode with
/// its partner at each, the sets that differ, the costs, and what to do.
std::string differing_pairs(const LinearProblem& p, const TrackedPoint& a, double cost_a,
                            const TrackedPoint& b, double cost_b, const std::string& why);

/// Whether a fit of reduced chi-square `worse` over `dof_worse` degrees of freedom is told from
/// one of `better` over `dof_better` without the stated noise: their ratio, which no noise scale
/// enters, reaches Fisher's F's 3-sigma point (variance_ratio_limit()).
bool ratio_decides(double worse, int dof_worse, double better, int dof_better);

/// Why ratio_decides() did not, from the better fit's "left ...": "left 0.339 over 2, 39.4 times
/// less, and without the stated noise only a ratio beyond 740 (Fisher's F's 3-sigma point over 2
/// and 2 degrees of freedom) tells the two apart; if the noise is larger than stated, give it
/// (--frequency-std)".
std::string ratio_undecided(double worse, int dof_worse, double better, int dof_better);

/// Least squares with pairs followed by shape from `point`, the pairs at its result decided by
/// the data.
Settled settle(const LinearProblem& p, TrackedPoint point, const std::vector<char>& held);

/// Why the update stops because a fitted set only pairs the sensors cannot confirm see, or "";
/// where the result stands, *warning says which pairs changed.
std::string unconfirmed_sets(const LinearProblem& p, const Eigen::SparseMatrix<double>& mass,
                             const TrackedPoint& start, const TrackedPoint& end,
                             const MeasuredModes& measured, const LinearUpdateOptions& options,
                             const std::vector<char>& held, const std::vector<std::string>& names,
                             std::string* warning);

}  // namespace jointlab::correlate::detail
