// Step "report" of a campaign run (method.md Figure 1): the report's sections, in order:
// the hits left out and the modes without a backbone (when there are any), data processed,
// settings, one scatter summary per mode, the model (linear frequencies, joint parameters, the
// updates and, for a simulated campaign, the comparison with the known parameters) and notes.
// report.h writes it as HTML and Markdown.
#pragma once

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/campaign_run.h"
#include "jointlab/campaign/report.h"
#include "jointlab/campaign/steps/campaign_figures.h"
#include "jointlab/campaign/steps/measured_side.h"
#include "jointlab/campaign/steps/model_results.h"

namespace jointlab::campaign {

/// The step: the report of a run; `model` is null without a model.
Report campaign_report(const Campaign& campaign, const RunSummary& summary,
                       const MeasuredSide& measured, const ModelResults* model,
                       const CampaignFigures& figures);

}  // namespace jointlab::campaign
