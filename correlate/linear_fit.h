// One linear update from a start, the sensors' signs as given (internal to update_linear()):
// the start's pairs by the rules, least squares from each candidate pairing with the pairs
// decided by the data (linear_settle.h), flat sets held and the rest fitted again, the rule's
// step to the tolerance, then the result's sensitivities, uncertainty and warnings.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/linear_problem.h"
#include "jointlab/correlate/linear_settle.h"

namespace jointlab::correlate::detail {

/// update_linear() with the sensors' signs as given (after the start's shape checks); the
/// one-at-a-time sweeps only where `with_sweeps`. Warnings on pairs followed below the MAC
/// threshold go to `weak_pairs` (when given); the fit starts from `from` where given; `end`
/// receives the result's point where the fit reaches one.
Eigen::VectorXd fit_as_given(const model::Model& model, const std::vector<std::string>& names,
                             const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                             const LinearUpdateOptions& options, bool with_sweeps,
                             LinearUpdateSummary& s, std::vector<PairWarning>* weak_pairs = nullptr,
                             const Eigen::VectorXd* from = nullptr,
                             std::optional<TrackedPoint>* end = nullptr);

}  // namespace jointlab::correlate::detail
