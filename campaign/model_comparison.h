// What `jointlab compare` shows (the paper's Figures 5-7): the measured backbones of one mode
// (campaign/iwan_inputs.h: a `process` folder with its sensors, or backbone tables) and the QSMA
// backbone of each model over their amplitude range, compared like with like
// (correlate::model_backbone: the ring-down or stepped-sine columns, the sensor's amplitude the
// QSMA deflection at its DOF). The command draws it (backbone_comparison.h); the Python module
// returns it.
#pragma once

#include <string>
#include <vector>

#include "jointlab/campaign/backbone_comparison.h"
#include "jointlab/campaign/iwan_inputs.h"

namespace jointlab::campaign {

/// The measured curves and the models' curves of one comparison.
struct ModelComparison {
  BackboneComparison figure;  ///< title, axis label, measured curves, one curve per model
  std::vector<bool> clipped;  ///< per model: its curve stops short of the measured range
  /// Per clipped model, why (for the command's stderr and the Python warning).
  std::vector<std::string> notes;
  std::string slip_screen;  ///< several process modes: the slip screen's lines (iwan_inputs.h)
};

/// The models (files sharing their DOFs) against the measured side `measured` (its `modes` the
/// one mode compared, R or R:BAND), `points` points per model curve, each labelled by
/// `labels` (one per model, or none: the file names); InputError prefixed by "compare".
ModelComparison compare_models(const std::vector<std::string>& models,
                               const std::vector<std::string>& labels, IwanInputArgs measured,
                               int points);

}  // namespace jointlab::campaign
