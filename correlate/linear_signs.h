// Channels read reversed, for update_linear() (internal): the start's check of the measured
// shapes against the model (shape_checks.h), and a fit's misfit that the best reversal removes.
#pragma once

#include <string>
#include <vector>

#include "jointlab/correlate/linear_update.h"

namespace jointlab::correlate::detail {

/// What is wrong with the measured shapes against the model at the start (shape_checks.h), or "".
std::string shape_problem(const LinearEvaluation& start, const std::vector<Sensor>& sensors,
                          const MeasuredModes& measured, const LinearUpdateOptions& options);

/// Why a fit's misfit is one or two channels read reversed, or "".
std::string misfit_of_signs(const model::Model& model, const std::vector<std::string>& names,
                            const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                            const LinearUpdateOptions& options, const LinearUpdateSummary& s);

/// Why a fit's misfit is frequencies in rad/s read as Hz, or "": where a fit leaves scatter
/// beyond the noise (reduced_chi2_limit) and, divided by 2 pi, every measured mode has a partner
/// candidate at the start (within the frequency window, MAC >= 0.9 where it has entries at three
/// sensors or more), the update is fitted again so; when that pairs as many modes and leaves
/// scatter within the noise, or a hundredth of the given, the frequencies are named.
std::string misfit_of_units(const model::Model& model, const std::vector<std::string>& names,
                            const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                            const LinearUpdateOptions& options, const LinearUpdateSummary& s);

/// Why the pairs an update could not decide (kAmbiguous), or a fit that leaves scatter beyond the
/// noise, look like frequencies in rad/s read as Hz, or "": divided by 2 pi, each measured mode
/// has a visible model mode of its own at the start within the frequency window (0.5 at most;
/// MAC >= 0.9 where it has entries at three sensors or more), and read as Hz the table's lowest
/// mode lies above one visible model mode or more by more than the window. No refit: a
/// frequency-only table can be as undecidable in Hz.
std::string undecided_units(const MeasuredModes& measured, const LinearUpdateOptions& options,
                            const LinearUpdateSummary& s);

/// The rule of undecided_units() against the model at the start `start`, whatever a fit gave,
/// with the frequency window at most `max_window`.
std::string angular_units(const MeasuredModes& measured, const LinearUpdateOptions& options,
                          const LinearEvaluation& start, double max_window = 0.5);

/// Why a table of frequencies alone (every shape entry empty) looks like rad/s read as Hz before
/// any fit, or "": angular_units() at the start (the sets at their start, or a hold's value),
/// which `start` receives (nothing where the table has shapes), for three modes or more and
/// within a window of 25 %. A fit of such a table can run for minutes before its pairs are found
/// undecided (the example beam's six bending modes and four sets: 9 min of CPU); without a fit
/// the rule is a guess, which two modes (their ratio alone) or a pairing looser than 25 % made
/// of true Hz tables of higher modes (the example beam's bending modes 4 and 6: within 17 %;
/// 3 and 5: 41 %). Those are judged after the fit, by its misfit.
std::string units_before_fit(const model::Model& model, const std::vector<std::string>& names,
                             const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                             const LinearUpdateOptions& options, LinearEvaluation& start);

}  // namespace jointlab::correlate::detail
