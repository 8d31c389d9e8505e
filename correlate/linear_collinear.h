// Fitted sets acting together in update_linear() (internal): sets whose sensitivity columns
// nearly repeat one another (a singular value of J with unit columns below sqrt(1e-3)), of which
// the frequencies determine only a combination; (J^T J)^+ without those directions.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/linear_problem.h"

namespace jointlab::correlate::detail {

/// The sensitivities of the fitted sets, J (columns d r / d ln theta of each), taken apart: the
/// directions of ln theta the frequencies barely see and the sets each one moves (a share of at
/// least a tenth of its largest), merged into groups acting together, and (J^T J)^+ without
/// those directions (right for the combinations and for the sets outside the groups, where
/// (J^T J)^-1 is rounding noise: +/- 1.11e+08 % for an Iwan element beside a spring on one
/// degree of freedom).
struct SensitivityDirections {
  Eigen::MatrixXd inverse;               ///< (J^T J)^+, near-null directions dropped
  std::vector<std::vector<int>> groups;  ///< columns of J acting together, each ascending
  std::vector<int> unseen;               ///< near-null directions in each group
  int rank = 0;                          ///< combinations determined: columns - near-null
};

/// The directions of J (columns: sensitivities of the fitted sets, none zero).
SensitivityDirections sensitivity_directions(const Eigen::MatrixXd& j);

/// The groups of `d` recorded in s.collinear, each set marked with the others, one warning per
/// group; `cov` the covariance of ln theta over the fitted sets (empty: none stated).
void report_collinear(const std::vector<int>& fitted, const Eigen::VectorXd& theta,
                      const Eigen::MatrixXd& j, const SensitivityDirections& d,
                      const Eigen::MatrixXd& cov, LinearUpdateSummary& s);

/// Sets the flat rule held at their start where the fit had driven them, acting together with
/// fitted sets, named as fitted ones acting together are.
void report_collinear_with_held_flat(const LinearProblem& p, const Eigen::VectorXd& theta,
                                     const LinearEvaluation& at, const std::vector<char>& held,
                                     const std::vector<int>& fitted, const Eigen::MatrixXd& cov,
                                     LinearUpdateSummary& s);

}  // namespace jointlab::correlate::detail
