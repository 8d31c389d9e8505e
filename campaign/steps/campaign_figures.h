// Step "figures" of a campaign run (method.md Figure 1): PNGs in OUT/figures/ with their
// report captions: spectrum.png (the first hit of the last group, by convention the strongest
// level, with the analysis bands; the first of an earlier group when every hit of the last
// is left out, none when every hit is), backbone_mode<k>.png (every hit faint, the binned mean and
// its confidence interval, the model's QSMA curves), mac.png and frequency_errors.png (with a
// model).
#pragma once

#include <filesystem>
#include <vector>

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/campaign_run.h"
#include "jointlab/campaign/report.h"
#include "jointlab/campaign/steps/measured_side.h"
#include "jointlab/campaign/steps/model_results.h"

namespace jointlab::campaign {

/// The figures of a run, with their captions.
struct CampaignFigures {
  ReportFigure spectrum;               ///< spectrum of one hit with the bands (none: empty)
  std::vector<ReportFigure> backbone;  ///< per mode
  std::vector<ReportFigure> model;     ///< MAC and frequency errors (with a model)
};

/// The step: draws every figure into `dir` (created); `model` is null without a model, and
/// the spectrum is not drawn from a hit in `left_out`.
CampaignFigures draw_figures(const Campaign& campaign, const MeasuredSide& measured,
                             const ModelResults* model, const std::filesystem::path& dir,
                             const std::vector<FailedHit>& left_out = {});

}  // namespace jointlab::campaign
