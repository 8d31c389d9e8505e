// Steps "model" and "evaluate model" of a campaign run (method.md Figure 1, model side):
// the reduced model is built from the campaign's description into OUT/model/ (unless up to
// date) or taken from its model file; evaluating a model gives its linear frequencies, its
// mode shapes at the sensors (for the MAC) and the QSMA curve of each campaign mode's model
// mode, converted to the measured amplitude at the reference channel: displacement
// x = |phi_r[d]| q, velocity omega x, acceleration omega^2 x, omega = 2 pi f(q) along the curve,
// written to OUT/qsma/mode<k>.<tag>.csv.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/campaign_run.h"
#include "jointlab/campaign/figures.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/model/model_file.h"

namespace jointlab::campaign {

/// The step "model": builds the description's model into OUT/model/ when it is missing or
/// stale and returns the model file to use (empty: the campaign has no model).
std::filesystem::path prepare_model(const Campaign& campaign, const std::filesystem::path& out,
                                    const RunOptions& options, RunSummary& summary);

/// A campaign's model with its channels resolved to model DOFs.
struct CampaignModelData {
  std::filesystem::path file;              ///< the model file
  model::Model model;                      ///< the model read from it
  std::vector<Eigen::Index> dofs;          ///< per channel: its DOF
  std::vector<correlate::Sensor> sensors;  ///< per channel: name, DOF and sign
};

/// Reads the model file and resolves every channel's DOF; InputError naming the channel.
CampaignModelData read_campaign_model(const Campaign& campaign, const std::filesystem::path& file);

/// A model's side of the comparison.
struct ModelSide {
  std::vector<double> frequency_hz;     ///< per campaign mode (0: no model mode)
  Eigen::MatrixXd sensor_shapes;        ///< sensors x first elastic modes
  std::vector<double> shape_hz;         ///< frequency of each column [Hz]
  std::vector<ModelCurve> curves;       ///< per campaign mode (empty: no model mode)
  std::vector<std::string> qsma_notes;  ///< QSMA's message per evaluated mode
};

/// The step "evaluate model": linear modes, shapes at the sensors and QSMA curves of `m`
/// (legend `label`), each curve written to `qsma_dir`/mode<k>.`tag`.csv.
ModelSide evaluate_model(const Campaign& campaign, const model::Model& m,
                         const std::vector<Eigen::Index>& dofs, const std::string& label,
                         const std::filesystem::path& qsma_dir, const std::string& tag);

}  // namespace jointlab::campaign
