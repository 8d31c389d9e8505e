// The updating problem of update_linear() (internal): the sets, the measured data, the options
// and each set's bounds in x = ln theta; a point of the fit with its pairs; the least-squares
// fit over the sets not held, every pair followed by its full shape (mode_tracking.h). The
// method, the weights w_i = frequency_std / sigma_i and the Jacobian are in linear_update.h.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <ceres/types.h>
#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/mac.h"
#include "jointlab/correlate/mode_tracking.h"

namespace jointlab::correlate::detail {

/// A point of the fit whose pairs are known: ln theta, the elastic modes there, and the model
/// column each measured mode is paired with (-1: unpaired).
struct TrackedPoint {
  Eigen::VectorXd x;         ///< ln theta
  ElasticModes modes;        ///< the elastic modes at theta
  std::vector<int> columns;  ///< model column of each measured mode (-1: unpaired)
};

/// The updating problem: the sets, the data, the options and the bounds of each set.
struct LinearProblem {
  const StiffnessSets& sets;              ///< the sets updated
  const model::Model& model;              ///< the model (its mass)
  const std::vector<std::string>& names;  ///< the sets' names
  const std::vector<Sensor>& sensors;     ///< the sensors
  const MeasuredModes& measured;          ///< the measured modes
  const LinearUpdateOptions& options;     ///< the options
  Eigen::VectorXd start, lower, upper;    ///< each set's start and bounds [N/m or N m/rad]
  TrackingOptions tracking;               ///< how pairs are followed by shape
  /// Per measured mode, w_i = frequency_std / sigma_i, sigma_i its own uncertainty where wider.
  Eigen::VectorXd weight;

  /// Number of sets.
  int size() const { return sets.size(); }
  /// Where the update begins: each set's start within its bounds, or a hold's value where the
  /// options give one (InputError for a hold naming no set).
  Eigen::VectorXd begin() const;
  /// The pairing rules of the options.
  PairingRules rules() const;
  /// The point at x with its pairs made afresh by the rules; e receives the evaluation there.
  TrackedPoint fresh(const Eigen::VectorXd& x, LinearEvaluation& e) const;
  /// `from` moved to x, every pair followed by its full shape; nullopt when one is lost.
  std::optional<TrackedPoint> move(const TrackedPoint& from, const Eigen::VectorXd& x,
                                   int substeps = 1) const;
  /// Residuals and Jacobian at p with its pairs, weighted.
  LinearEvaluation evaluate(const TrackedPoint& p) const;
  /// Each pair's row of the Jacobian over its own mode's sigma (times frequency_std): the rows
  /// of the chi-square's (J^T W^2 J).
  Eigen::MatrixXd weighted_jacobian(const LinearEvaluation& e) const;
};

/// The evaluation at theta, `modes` its elastic modes, with the pairs made afresh by the rules;
/// `columns` receives the model column of each measured mode (-1: unpaired)
/// (linear_evaluation.cc).
LinearEvaluation evaluate_by_rules(const StiffnessSets& sets, const std::vector<Sensor>& sensors,
                                   const MeasuredModes& measured,
                                   const Eigen::Ref<const Eigen::VectorXd>& theta,
                                   const ElasticModes& modes, const PairingRules& rules,
                                   std::vector<int>& columns);

/// The index of `name` among the sets updated; InputError "`what`: ..." if it is not one.
int set_index(const std::vector<std::string>& names, const std::string& name,
              const std::string& what);

/// Least squares over the sets not held, from `point` (pairs known there), in the bounds;
/// `point` moves to the result, `record` (when given) receives history and iterations.
ceres::TerminationType fit(const LinearProblem& p, TrackedPoint& point,
                           const std::vector<char>& held, LinearUpdateSummary* record);

/// Each measured mode's relative frequency uncertainty: the stated frequency_std, or the mode's
/// own (MeasuredModes::frequency_std) where wider.
Eigen::VectorXd mode_sigma(const MeasuredModes& measured, double frequency_std);

/// The problem with the bounds of the options (start x factors, then the named bounds).
LinearProblem make_problem(const StiffnessSets& sets, const model::Model& model,
                           const std::vector<std::string>& names,
                           const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                           const LinearUpdateOptions& options);

/// Sensitivity of each set at `at`; flat sets are marked.
void report_sensitivity(const LinearProblem& p, const LinearEvaluation& at, LinearUpdateSummary& s);

/// The status of a fit that ended with Ceres' termination `tt`.
LinearUpdateStatus status_of(ceres::TerminationType tt);

/// Whether the update gave a result (converged, or at its iteration limit).
bool fitted(const LinearUpdateSummary& s);

/// Measured mode i's partner for a message: "model mode 3 (123.45 Hz, MAC 0.987)", or
/// "unpaired".
std::string pair_text(const LinearEvaluation& e, int i);

}  // namespace jointlab::correlate::detail
