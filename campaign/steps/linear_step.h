// Step "linear update" of a campaign run (method.md Figure 1): [update.linear] tunes the named
// stiffness sets so the model's linear frequencies match the measured mean linear
// frequencies of the modes it fits (correlate/linear_update.h, MAC pairing at every step).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/steps/measured_side.h"
#include "jointlab/campaign/steps/model_side.h"
#include "jointlab/correlate/linear_update.h"

namespace jointlab::campaign {

/// The updating options of [update.linear]'s settings; InputError naming the campaign file
/// for an unknown setting or a value out of range.
correlate::LinearUpdateOptions linear_update_options(const Campaign& campaign);

/// What the linear update did.
struct LinearStep {
  bool ran = false;  ///< the update ran
  /// Why it was skipped or refused, or that it ran into its iteration limit ("" otherwise)
  std::string note;
  /// It ran and gave no result: refused as update-linear refuses, or the optimiser failed
  bool refused = false;
  correlate::LinearUpdateSummary summary;  ///< its outcome
  model::Model updated;                    ///< the updated model (when it ran)
  /// Per measured mode of the update (its index in the summary), the campaign's [[mode]] index.
  std::vector<int> campaign_modes;
  /// Per [[mode]], where its hits' linear frequencies fall with the level, the lowest-level
  /// hits' value the update fitted instead of their mean [Hz] (0: the mean, or not fitted).
  std::vector<double> lowest_level_hz;
};

/// The step: runs [update.linear] on the model against `measured` (every campaign mode, in
/// order; modes without a measured linear frequency, 0, are left out); skipped when off,
/// without sets or without a mode to fit. With `side` (the hits behind `measured`), each fitted
/// mode's frequency and uncertainty are correlate::linear_spread()'s over its kept hits' linear
/// frequencies, each at the lowest amplitude its backbone read: hits that disagree beyond the
/// update's frequency_std widen that mode's uncertainty (its residual's own sigma), and where
/// they fall with the level the lowest-level hits' value is fitted, with a warning that the
/// joint still slips there.
LinearStep linear_update_step(const Campaign& campaign, const CampaignModelData& model,
                              const correlate::MeasuredModes& measured,
                              const std::function<void(const std::string&)>& progress,
                              const MeasuredSide* side = nullptr,
                              const std::function<void()>& interrupt = {});

}  // namespace jointlab::campaign
