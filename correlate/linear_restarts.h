// Restarts of a linear update whose fit leaves scatter beyond the noise (internal to
// update_linear()): fitted again from each set's start times and divided by 10, one set at a
// time, the lowest cost kept where its reduced chi-square is lower too; one that pairs some mode
// otherwise only where the ratio of the two reduced chi-squares reaches Fisher's F's 3-sigma point
// (or the shapes decide): else the pairs cannot be decided.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/linear_problem.h"
#include "jointlab/correlate/linear_settle.h"

namespace jointlab::correlate::detail {

/// Where s leaves scatter beyond the noise, the restarts tried and the winner kept (s, theta,
/// end and weak_pairs follow it; s.restarts says what was tried); kAmbiguous (end reset) where a
/// better one pairs otherwise and the data cannot tell the two apart without the stated noise.
void restart_if_misfit(const model::Model& model, const std::vector<std::string>& names,
                       const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                       const LinearUpdateOptions& options, LinearUpdateSummary& s,
                       Eigen::VectorXd& theta, std::optional<TrackedPoint>& end,
                       std::vector<PairWarning>* weak_pairs);

}  // namespace jointlab::correlate::detail
