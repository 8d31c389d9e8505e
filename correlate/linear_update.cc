// update_linear(), the method of linear_update.h as a list of steps: check the input, fit with
// the signs as given (linear_fit.h), restart a misfit (linear_restarts.h), sweep the result
// (linear_sweeps.h), then weigh the evidence (reversed channels, a mode the model does not match,
// pairs the shapes do not confirm) before the warnings are put in order.
#include "jointlab/correlate/linear_update.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/correlate/linear_fit.h"
#include "jointlab/correlate/linear_odd_mode.h"
#include "jointlab/correlate/linear_problem.h"
#include "jointlab/correlate/linear_restarts.h"
#include "jointlab/correlate/linear_signs.h"
#include "jointlab/correlate/linear_sweeps.h"
#include "jointlab/correlate/linear_unconfirmed.h"

namespace jointlab::correlate {

using detail::fit_as_given;
using detail::fitted;
using detail::make_problem;
using detail::misfit_of_one_mode;
using detail::misfit_of_signs;
using detail::misfit_of_units;
using detail::PairWarning;
using detail::restart_if_misfit;
using detail::sweeps;
using detail::TrackedPoint;
using detail::unconfirmed_pairs;
using detail::undecided_units;

namespace {

void check_measured(const std::vector<Sensor>& sensors, const MeasuredModes& measured) {
  if (measured.shapes.rows() != static_cast<Eigen::Index>(sensors.size()) ||
      measured.shapes.cols() != measured.frequency_hz.size()) {
    throw InputError(fmt::format(
        "measured modes: {} shapes of {} sensors for {} frequencies, expected {} sensors",
        measured.shapes.cols(), measured.shapes.rows(), measured.frequency_hz.size(),
        sensors.size()));
  }
  // "measured mode 2", with its label when that says more ("measured mode 2 (band2)").
  auto name = [&](Eigen::Index i) {
    const std::string plain = fmt::format("measured mode {}", measured.id(i));
    if (static_cast<size_t>(i) >= measured.labels.size()) return plain;
    const std::string& l = measured.labels[static_cast<size_t>(i)];
    if (l.empty() || l == fmt::format("mode {}", measured.id(i)) || l == measured.id(i))
      return plain;
    return fmt::format("{} ({})", plain, l);
  };
  bool any_shape = false;
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) {
    if (!(measured.frequency_hz(i) > 0) || !std::isfinite(measured.frequency_hz(i))) {
      throw InputError(fmt::format("{}: frequency must be > 0", name(i)));
    }
    if (!measured.shapes.col(i).allFinite())
      throw InputError(
          fmt::format("{}: its shape is not a finite number at every sensor", name(i)));
    any_shape = any_shape || measured.shapes.col(i).squaredNorm() > 0;
  }
  if (!any_shape) return;  // frequencies only: pairs by the nearest frequency
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) {
    if (measured.shapes.col(i).squaredNorm() > 0) continue;
    throw InputError(fmt::format(
        "{} at {:.6g} Hz: its shape is zero at every sensor, so no MAC can pair it (0/0); give "
        "its shape or leave the mode out",
        name(i), measured.frequency_hz(i)));
  }
}

}  // namespace

std::string LinearUpdateOptions::error() const {
  if (!(mac_threshold > 0 && mac_threshold <= 1)) return "mac_threshold must be in (0, 1]";
  if (!(lower_factor > 0 && lower_factor < 1)) return "lower_factor must be in (0, 1)";
  if (!(upper_factor > 1) || !std::isfinite(upper_factor)) return "upper_factor must be > 1";
  if (max_iterations < 1) return "max_iterations must be >= 1";
  if (!(tolerance >= 0)) return "tolerance must be >= 0";
  if (!(flat_sensitivity > 0)) return "flat_sensitivity must be > 0";
  if (!(frequency_std > 0)) return "frequency_std must be > 0";
  if (!(sweep_decades > 0)) return "sweep_decades must be > 0";
  if (sweep_points < 2) return "sweep_points must be >= 2";
  if (!(frequency_window >= 0) || !std::isfinite(frequency_window))
    return "frequency_window must be >= 0";
  if (!(visibility >= 0 && visibility < 1)) return "visibility must be in [0, 1)";
  if (!(alias_mac > 0 && alias_mac <= 1)) return "alias_mac must be in (0, 1]";
  for (const ParameterBound& b : bounds) {
    if (!(b.lower > 0 && b.lower < b.upper) || !std::isfinite(b.upper)) {
      return fmt::format("bounds of '{}': need 0 < lower < upper", b.name);
    }
  }
  for (const ParameterHold& h : holds) {
    if (!(h.value >= 0) || !std::isfinite(h.value))
      return fmt::format("hold of '{}': the value must be a stiffness > 0", h.name);
  }
  if (rule == LinearRule::kSmallest) {
    if (!(tolerance > 0)) return "the smallest rule needs a tolerance > 0";
    if (smallest_set.empty()) return "the smallest rule needs the set to minimise";
  }
  return "";
}

Eigen::VectorXd update_linear(const model::Model& model, const std::vector<std::string>& names,
                              const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                              const LinearUpdateOptions& options, LinearUpdateSummary* summary) {
  if (const std::string e = options.error(); !e.empty()) throw InputError("update-linear: " + e);
  check_measured(sensors, measured);
  // Files of a mode that disagree widen that mode's frequency uncertainty (mode_sigma): its
  // residual weighs less, and only the sets it fixes widen.
  if (measured.frequency_std.size() > 0 &&
      (measured.frequency_std.size() != measured.frequency_hz.size() ||
       !(measured.frequency_std.array() >= 0).all() || !measured.frequency_std.allFinite()))
    throw InputError("measured modes: frequency_std must be finite and >= 0, one per mode");
  LinearUpdateSummary local;
  LinearUpdateSummary& s = summary ? *summary : local;
  // A table of frequencies alone in rad/s under frequency_hz is named before any fit, by the
  // rule undecided_units() applies after one: the example beam's six bending modes so, four
  // sets, were refused as undecided pairs after 9 min of CPU, the unit named only then.
  LinearEvaluation at_start;
  if (std::string why =
          detail::units_before_fit(model, names, sensors, measured, options, at_start);
      !why.empty()) {
    s = LinearUpdateSummary{};
    s.status = LinearUpdateStatus::kShapesRefused;
    s.shape_problem =
        why +
        "; decided before any fit, as a table of frequencies alone (if they are in Hz, give "
        "each mode's entry at one sensor: it then pairs by frequency alone as before, and is "
        "not judged so)";
    s.start = at_start;
    s.final = std::move(at_start);
    s.initial_cost = s.final_cost = s.start.cost();
    return StiffnessSets(model, names).initial();
  }
  std::vector<PairWarning> weak_pairs;
  std::optional<TrackedPoint> end;
  Eigen::VectorXd theta =
      fit_as_given(model, names, sensors, measured, options, false, s, &weak_pairs, nullptr, &end);
  restart_if_misfit(model, names, sensors, measured, options, s, theta, end, &weak_pairs);
  if (end) {
    // The one-at-a-time sweeps of the result kept (the winner's where a restart won).
    const StiffnessSets sets(model, names);
    sweeps(make_problem(sets, model, names, sensors, measured, options), *end, s);
  }
  if (std::string why = misfit_of_units(model, names, sensors, measured, options, s);
      !why.empty()) {
    s.status = LinearUpdateStatus::kShapesRefused;
    s.shape_problem = std::move(why);
  } else if (std::string why = misfit_of_signs(model, names, sensors, measured, options, s);
             !why.empty()) {
    s.status = LinearUpdateStatus::kShapesRefused;
    s.shape_problem = std::move(why);
  } else if (std::string one = misfit_of_one_mode(model, names, sensors, measured, options, s);
             !one.empty()) {
    s.status = LinearUpdateStatus::kShapesRefused;
    s.shape_problem = std::move(one);
  }
  // Undecided pairs of frequencies in rad/s: no refit can confirm the unit where the same
  // table in Hz is as undecidable (frequencies alone, four sets on the example beam).
  if (s.status == LinearUpdateStatus::kAmbiguous) {
    s.units = undecided_units(measured, options, s);
  } else if (std::string why = undecided_units(measured, options, s); !why.empty()) {
    // A fit beyond the noise whose refit divided by 2 pi (misfit_of_units) found no better
    // minimum from the start: the two chains' six modes in rad/s, three sets, "converged" with
    // 3 of 6 paired (reduced chi-square 453), the unit never named.
    s.warnings.push_back(why + " (the fit above took them as Hz)");
  }
  if (fitted(s)) {
    if (std::string why = unconfirmed_pairs(measured, options, s); !why.empty()) {
      s.fit_converged = s.status == LinearUpdateStatus::kConverged;
      s.status = LinearUpdateStatus::kPairsUnconfirmed;
      s.unconfirmed = std::move(why);
    }
  }
  // A weak pair is warned of once: not again where the unconfirmed line names its mode.
  std::vector<std::string> weak;
  for (PairWarning& w : weak_pairs) {
    if (std::find(s.unconfirmed_modes.begin(), s.unconfirmed_modes.end(), w.measured) ==
        s.unconfirmed_modes.end())
      weak.push_back(std::move(w.text));
  }
  s.warnings.insert(s.warnings.begin(), weak.begin(), weak.end());
  s.warnings.insert(s.warnings.begin(), measured.warnings.begin(), measured.warnings.end());
  return theta;
}

}  // namespace jointlab::correlate
