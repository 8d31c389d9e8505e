// A small simulated test campaign for tests of `jointlab run` and its steps: the two-chain
// model with an Iwan joint (correlate/two_chain.h) struck at the end of chain A at a few force
// levels, recorded at two DOFs of chain A; one campaign mode (chain A's first mode). The
// campaign's model starts with K_T 20 % below and chi 0.2 above the truth that made the hits.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "jointlab/correlate/two_chain.h"
#include "jointlab/model/model_file.h"

namespace jointlab::testing {

/// What make_small_campaign() wrote.
struct SmallCampaign {
  std::filesystem::path dir;                ///< the folder holding everything
  std::filesystem::path campaign;           ///< campaign.toml
  std::filesystem::path model;              ///< the campaign's (starting) model file
  std::filesystem::path sensors;            ///< sensors file (channel,dof,sign) for the commands
  std::vector<std::filesystem::path> hits;  ///< the test files, campaign order
  correlate::TwoChainParameters truth;      ///< the parameters the hits were simulated with
  correlate::TwoChainParameters start;      ///< the campaign model's parameters
  int model_mode = 0;                       ///< chain A's first mode among the elastic modes
  double frequency_hz = 0;                  ///< its linear frequency in the truth [Hz]
  std::vector<double> band;                 ///< the campaign's band [Hz]
};

/// Writes the campaign into `dir` (created); `extra` is appended to campaign.toml (update
/// tables and settings). Hits: one per force in `forces` [N], 2 s at 1 kHz.
SmallCampaign make_small_campaign(const std::filesystem::path& dir, const std::string& extra,
                                  const std::vector<double>& forces = {10, 20, 40});

}  // namespace jointlab::testing
