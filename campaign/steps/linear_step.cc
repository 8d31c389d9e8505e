#include "jointlab/campaign/steps/linear_step.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/core/error.h"

namespace jointlab::campaign {

correlate::LinearUpdateOptions linear_update_options(const Campaign& c) {
  correlate::LinearUpdateOptions lo;
  for (const auto& [key, value] : c.linear_update.settings) {
    if (key == "mac_threshold")
      lo.mac_threshold = value;
    else if (key == "lower_factor")
      lo.lower_factor = value;
    else if (key == "upper_factor")
      lo.upper_factor = value;
    else if (key == "max_iterations")
      lo.max_iterations = static_cast<int>(value);
    else if (key == "tolerance")
      lo.tolerance = value;
    else if (key == "flat_sensitivity")
      lo.flat_sensitivity = value;
    else if (key == "frequency_std")
      lo.frequency_std = value;
    else
      throw InputError(
          where(c.file.string(), 0, fmt::format("update.linear: unknown setting '{}'", key)));
  }
  if (const std::string e = lo.error(); !e.empty())
    throw InputError(where(c.file.string(), 0, "update.linear: " + e));
  return lo;
}

LinearStep linear_update_step(const Campaign& c, const CampaignModelData& m,
                              const correlate::MeasuredModes& measured,
                              const std::function<void(const std::string&)>& progress) {
  LinearStep step;
  if (!c.linear_update.enabled) return step;
  if (c.linear_update.sets.empty()) {
    step.note = "update.linear: no 'sets' given; linear updating skipped";
    return step;
  }
  const correlate::LinearUpdateOptions lo = linear_update_options(c);
  if (progress)
    progress("update: linear updating of " +
             fmt::format("{}", fmt::join(c.linear_update.sets, ", ")));
  // The measured modes it fits: those named in 'modes' (default every mode).
  correlate::MeasuredModes fitted;
  std::vector<Eigen::Index> keep;
  for (size_t k = 0; k < c.modes.size(); ++k)
    if (c.linear_update.fits(c.modes[k].name) &&
        measured.frequency_hz(static_cast<Eigen::Index>(k)) > 0)
      keep.push_back(static_cast<Eigen::Index>(k));
  if (keep.empty()) {
    step.note =
        "update.linear: no fitted mode has a measured linear frequency; linear updating skipped";
    return step;
  }
  fitted.frequency_hz = measured.frequency_hz(keep);
  fitted.shapes = measured.shapes(Eigen::all, keep);
  for (Eigen::Index k : keep) fitted.labels.push_back(measured.labels[k]);
  const Eigen::VectorXd theta =
      correlate::update_linear(m.model, c.linear_update.sets, m.sensors, fitted, lo, &step.summary);
  step.updated = correlate::StiffnessSets(m.model, c.linear_update.sets).apply(theta);
  step.ran = true;
  if (progress) progress("update: " + step.summary.report());
  return step;
}

}  // namespace jointlab::campaign
