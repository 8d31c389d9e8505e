#include "jointlab/campaign/steps/linear_step.h"

#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/campaign/steps/update_settings.h"
#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/core/units.h"
#include "jointlab/correlate/measured_data.h"

namespace jointlab::campaign {

correlate::LinearUpdateOptions linear_update_options(const Campaign& c) {
  const UpdateSettings in(c, "update.linear");
  correlate::LinearUpdateOptions lo;
  for (const auto& [key, s] : c.linear_update.settings) {
    if (key == "mac_threshold") {
      lo.mac_threshold = in.number(key, s);
    } else if (key == "lower_factor") {
      lo.lower_factor = in.number(key, s);
    } else if (key == "upper_factor") {
      lo.upper_factor = in.number(key, s);
    } else if (key == "max_iterations") {
      lo.max_iterations = in.whole(key, s, 1, 100000);
    } else if (key == "tolerance") {
      lo.tolerance = in.number(key, s);
    } else if (key == "flat_sensitivity") {
      lo.flat_sensitivity = in.number(key, s);
    } else if (key == "frequency_std") {
      lo.frequency_std = in.number(key, s);
    } else if (key == "frequency_window") {
      lo.frequency_window = in.number(key, s);
      if (!(lo.frequency_window >= 0)) in.fail(key, s, "must be >= 0 (0: no window)");
    } else if (key == "trust_signs") {
      lo.trust_signs = in.flag(key, s);
    } else if (key == "alias_mac") {
      lo.alias_mac = in.number(key, s);
      if (!(lo.alias_mac > 0 && lo.alias_mac <= 1)) in.fail(key, s, "must be in (0, 1]");
    } else if (key == "rule") {
      const std::string& r = in.text(key, s);
      if (r == "least-squares") {
        lo.rule = correlate::LinearRule::kLeastSquares;
      } else if (r == "smallest") {
        lo.rule = correlate::LinearRule::kSmallest;
      } else {
        in.fail(key, s,
                fmt::format("must be \"least-squares\" or \"smallest\", not \"{}\"", printable(r)));
      }
    } else if (key == "smallest_set") {
      lo.smallest_set = in.text(key, s);
      if (std::find(c.linear_update.sets.begin(), c.linear_update.sets.end(), lo.smallest_set) ==
          c.linear_update.sets.end()) {
        in.fail(key, s, fmt::format("'{}' is not one of update.linear.sets", lo.smallest_set));
      }
    } else if (key == "bounds") {
      for (const SetBounds& b : in.bounds(key, s)) {
        if (std::find(c.linear_update.sets.begin(), c.linear_update.sets.end(), b.set) ==
            c.linear_update.sets.end()) {
          in.fail(key, s, fmt::format("'{}' is not one of update.linear.sets", b.set));
        }
        lo.bounds.push_back({b.set, b.lower, b.upper});
      }
    } else {
      in.unknown(key, s,
                 "rule, smallest_set, tolerance, bounds, lower_factor, upper_factor, "
                 "frequency_window, mac_threshold, alias_mac, max_iterations, "
                 "flat_sensitivity, frequency_std, trust_signs");
    }
  }
  if (lo.rule == correlate::LinearRule::kSmallest && lo.smallest_set.empty() &&
      c.linear_update.sets.size() == 1) {
    lo.smallest_set = c.linear_update.sets.front();  // one set: the one minimised
  }
  if (const std::string e = lo.error(); !e.empty())
    throw InputError(where(c.file.string(), 0, "update.linear: " + e));
  return lo;
}

namespace {

// Each kept hit's linear frequency of mode k, at the lowest amplitude its backbone read (the
// hit cache keeps no stated uncertainty of it: 0).
std::vector<correlate::LinearReading> hit_readings(const Campaign& c, const MeasuredSide& side,
                                                   size_t k) {
  std::vector<correlate::LinearReading> out;
  if (k >= side.curves.size()) return out;
  const std::vector<correlate::Curve>& curves = side.curves[k];
  for (size_t h = 0; h < curves.size(); ++h) {
    const correlate::Curve& cv = curves[h];
    const bool flagged = k < side.scatter.size() && h < side.scatter[k].hits.size() &&
                         side.scatter[k].hits[h].outlier;
    if (!cv.has_linear || !(cv.linear_frequency_hz > 0) || (flagged && c.scatter.exclude_outliers))
      continue;
    out.push_back({cv.id, cv.linear_frequency_hz, 0,
                   cv.amplitude.size() > 0 ? cv.amplitude.minCoeff() : 0.0});
  }
  return out;
}

}  // namespace

LinearStep linear_update_step(const Campaign& c, const CampaignModelData& m,
                              const correlate::MeasuredModes& measured,
                              const std::function<void(const std::string&)>& progress,
                              const MeasuredSide* side, const std::function<void()>& interrupt) {
  LinearStep step;
  if (!c.linear_update.enabled) return step;
  if (c.linear_update.sets.empty()) {
    step.note = "update.linear: no 'sets' given; linear updating skipped";
    return step;
  }
  correlate::LinearUpdateOptions lo = linear_update_options(c);
  lo.interrupt = interrupt;
  if (progress)
    progress("update: linear updating of " +
             fmt::format("{}", fmt::join(c.linear_update.sets, ", ")));
  // The measured modes it fits: those named in 'modes' (default every mode).
  correlate::MeasuredModes fitted;
  std::vector<Eigen::Index> keep;
  // A mode without a measured shape (no hit measured it at a sensor) cannot be paired by MAC:
  // left out while other modes have shapes.
  const bool any_shape = measured.shapes.squaredNorm() > 0;
  for (size_t k = 0; k < c.modes.size(); ++k) {
    const auto col = static_cast<Eigen::Index>(k);
    if (c.linear_update.fits(c.modes[k].name) && measured.frequency_hz(col) > 0 &&
        (!any_shape || measured.shapes.col(col).squaredNorm() > 0))
      keep.push_back(col);
  }
  if (keep.empty()) {
    step.note =
        "update.linear: no fitted mode has a measured linear frequency; linear updating skipped";
    return step;
  }
  fitted = measured.columns(keep);  // each keeps its id: its place in the [[mode]] list
  for (Eigen::Index k : keep) step.campaign_modes.push_back(static_cast<int>(k));
  if (side) {
    fitted.frequency_std = Eigen::VectorXd::Zero(fitted.frequency_hz.size());
    for (size_t i = 0; i < keep.size(); ++i) {
      const auto k = static_cast<size_t>(keep[i]);
      const std::vector<correlate::LinearReading> readings = hit_readings(c, *side, k);
      if (readings.empty()) continue;
      const correlate::LinearSpread spread = correlate::linear_spread(
          c.modes[k].name, readings, lo.frequency_std, si_unit(c.amplitude));
      const auto col = static_cast<Eigen::Index>(i);
      if (spread.note.empty()) continue;  // within the update's uncertainty: the mean, as given
      fitted.frequency_hz(col) = spread.frequency_hz;
      fitted.frequency_std(col) = spread.relative_std;
      if (spread.falls_with_level) {
        step.lowest_level_hz.resize(c.modes.size(), 0.0);
        step.lowest_level_hz[k] = spread.frequency_hz;
      }
      fitted.warnings.push_back(spread.note);
    }
  }
  const Eigen::VectorXd theta =
      correlate::update_linear(m.model, c.linear_update.sets, m.sensors, fitted, lo, &step.summary);
  // A refused update (as update-linear refuses it) leaves the model as given: its stiffness
  // must not reach the Iwan update and the model-side results as if identified.
  std::string why = correlate::linear_refusal(step.summary, lo, "");
  // An optimiser that failed leaves no result either: its stiffness is wherever it stopped.
  if (why.empty() && step.summary.status == correlate::LinearUpdateStatus::kFailed)
    why = "the optimiser failed (numerically) before a result";
  if (!why.empty()) {
    step.refused = true;
    step.note = "update.linear: " + why + "; the model's linear part is left as given";
    return step;
  }
  step.updated = correlate::StiffnessSets(m.model, c.linear_update.sets).apply(theta);
  step.ran = true;
  const bool at_limit = step.summary.status == correlate::LinearUpdateStatus::kIterationLimit ||
                        (step.summary.status == correlate::LinearUpdateStatus::kPairsUnconfirmed &&
                         !step.summary.fit_converged);
  if (at_limit) {
    step.note = fmt::format(
        "update.linear: reached its iteration limit (update.linear max_iterations = {}) before "
        "converging; the next steps start from where it stopped",
        lo.max_iterations);
  }
  if (progress) progress("update: " + step.summary.report());
  return step;
}

}  // namespace jointlab::campaign
