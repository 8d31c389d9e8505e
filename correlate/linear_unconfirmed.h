// Pairs at the result of update_linear() that the shapes do not confirm (internal): a MAC with
// the partner below the threshold, or pairs crosswise to the frequency order at two sensors
// where the fit leaves a misfit.
#pragma once

#include <string>

#include "jointlab/correlate/linear_update.h"

namespace jointlab::correlate::detail {

/// The line for the report naming the unconfirmed pairs, why, and what to do ("" when every
/// pair is confirmed); their rows in s.unconfirmed_modes.
std::string unconfirmed_pairs(const MeasuredModes& measured, const LinearUpdateOptions& options,
                              LinearUpdateSummary& s);

}  // namespace jointlab::correlate::detail
