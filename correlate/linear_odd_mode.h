// One measured mode the model does not match (internal to update_linear()): where a fit leaves
// scatter far beyond the noise, each paired mode left out in turn and the rest fitted again;
// where it leaves scatter beyond the noise, the same where one mode pulls a set further than
// the standard deviations of the fits with and without it allow.
#pragma once

#include <string>
#include <vector>

#include "jointlab/correlate/linear_update.h"

namespace jointlab::correlate::detail {

/// Why a fit's misfit is one measured mode that the model does not match, or "".
std::string misfit_of_one_mode(const model::Model& model, const std::vector<std::string>& names,
                               const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                               const LinearUpdateOptions& options, const LinearUpdateSummary& s);

}  // namespace jointlab::correlate::detail
