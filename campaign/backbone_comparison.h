// Model backbones over measured ones, the paper's Figures 5-7: `jointlab compare` and the
// backbones.png of `jointlab update-iwan` draw with this one function.
//
// The measured backbones (one curve per hit or table) are drawn faint with their binned mean
// (campaign/scatter.h, default settings), each model curve over the measured amplitude range
// (correlate::model_backbone), frequency above and damping (log) below (plot_backbones). The
// CSV beside the figure holds what is drawn of the models: model,amplitude,frequency_hz,
// damping_ratio, one row per point, in the order given.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "jointlab/campaign/figures.h"
#include "jointlab/correlate/iwan_update.h"

namespace jointlab::campaign {

/// What one comparison figure shows.
struct BackboneComparison {
  std::string title;                                  ///< top line ("mode 1")
  std::string amplitude_label;                        ///< x axis ("modal amplitude q [m kg^1/2]")
  std::vector<correlate::MeasuredBackbone> measured;  ///< the measured curves
  std::vector<ModelCurve> models;                     ///< labelled model curves
};

/// The x-axis label of a measured amplitude: modal, or the quantity named by `quantity`.
std::string amplitude_axis_label(bool modal, correlate::AmplitudeQuantity quantity);

/// The figure of the comparison: the measured curves as hits, none of them flagged (they are
/// the curves the fit used, its scatter screen already applied), their mean over all of them.
BackboneFigure comparison_figure(const BackboneComparison& comparison);

/// Draws the comparison into `figure` (.png, .svg or .pdf) and, when `csv` is not empty, writes
/// the model curves there; InputError when a file cannot be written.
void plot_backbone_comparison(const BackboneComparison& comparison,
                              const std::filesystem::path& figure,
                              const std::filesystem::path& csv);

}  // namespace jointlab::campaign
