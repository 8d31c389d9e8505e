// Step "figures" of a campaign run (method.md Figure 1): PNGs in OUT/figures/ with their
// report captions: spectrum.png (the first hit of the last group, by convention the strongest
// level, with the analysis bands), backbone_mode<k>.png (every hit faint, the binned mean and
// its confidence interval, the model's QSMA curves), mac.png and frequency_errors.png (with a
// model).
#pragma once

#include <filesystem>
#include <vector>

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/report.h"
#include "jointlab/campaign/steps/measured_side.h"
#include "jointlab/campaign/steps/model_results.h"

namespace jointlab::campaign {

/// The figures of a run, with their captions.
struct CampaignFigures {
  ReportFigure spectrum;               ///< spectrum of one hit with the bands
  std::vector<ReportFigure> backbone;  ///< per mode
  std::vector<ReportFigure> model;     ///< MAC and frequency errors (with a model)
};

/// The step: draws every figure into `dir` (created); `model` is null without a model.
CampaignFigures draw_figures(const Campaign& campaign, const MeasuredSide& measured,
                             const ModelResults* model, const std::filesystem::path& dir);

}  // namespace jointlab::campaign
