// Step "summarise scatter" of a campaign run (method.md Figure 1, test side): per mode, the
// backbones of every hit at the mode's reference channel, their scatter summary (scatter.h,
// written to OUT/scatter/mode<k>.{bins.csv,hits.csv,json}), and the measured linear modes the
// model is compared with: per mode the mean linear frequency over the kept hits and the mean
// operating shape, each hit's shape normalised by the modulus at the reference channel.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/scatter.h"
#include "jointlab/campaign/steps/hits.h"
#include "jointlab/correlate/linear_update.h"

namespace jointlab::campaign {

/// What one hit kept of one mode at the mode's reference channel.
struct HitSpan {
  std::string hit;     ///< the hit's id (file stem)
  std::string group;   ///< its group
  bool ok = false;     ///< a backbone was kept
  double start_s = 0;  ///< first kept point [s]
  double end_s = 0;    ///< last kept point [s]
  double decades = 0;  ///< decades of amplitude kept
  std::string reason;  ///< why nothing was kept (when not ok)
};

/// The test side of a campaign after its hits are summarised.
struct MeasuredSide {
  std::vector<int> reference;                    ///< per mode: its reference channel index
  std::vector<std::vector<Curve>> curves;        ///< per mode: each hit's backbone there
  std::vector<std::vector<PointStd>> point_std;  ///< per mode: each curve's own uncertainty
  std::vector<ScatterSummary> scatter;           ///< per mode
  std::vector<std::vector<HitSpan>> spans;       ///< per mode: every hit, campaign order
  std::vector<bool> flagged;                     ///< per hit: flagged in any mode
  int flagged_hits = 0;                          ///< hits flagged in any mode
  correlate::MeasuredModes modes;                ///< linear frequencies and shapes per mode
  std::vector<std::string> reference_hint;       ///< per mode: reference_hint()'s
};

/// For mode `k` whose reference channel gave no backbone in any hit while other channels did:
/// "channel acc_9003_z gives one in 9 of 9 hits: give reference = "acc_9003_z" in [[mode]]"
/// (the channel with the most, then others with their counts); "" otherwise.
std::string reference_hint(const Campaign& campaign, const std::vector<HitData>& hits, size_t k);

/// The step: summarises every mode, writes the summaries into `dir` (created) and says one
/// line per mode through `progress` (may be empty).
MeasuredSide summarise_measured(const Campaign& campaign, const std::vector<HitData>& hits,
                                const std::filesystem::path& dir,
                                const std::function<void(const std::string&)>& progress);

}  // namespace jointlab::campaign
