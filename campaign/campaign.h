// A test campaign file (TOML; docs/campaign-file.md): the hammer tests of one structure,
// grouped by force level, the channels and the model DOFs they see, the modes and their
// bands, the model, and the summaries and updates to run.
//
// Paths in the file are relative to the file's own directory. Frequencies in Hz; every
// other quantity SI. A campaign is only read and checked here; run_campaign()
// (campaign_run.h) does the work.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "jointlab/campaign/scatter.h"
#include "jointlab/core/units.h"
#include "jointlab/signal/band_analytic.h"

namespace jointlab::campaign {

/// Hits at one force level.
struct CampaignGroup {
  std::string name;                          ///< short name ("low"), used in file names
  std::string level;                         ///< free text for reports ("4 N")
  std::vector<std::filesystem::path> files;  ///< test files (absolute)
};

/// A measured channel and the model DOF it sees (it reads sign * u[dof]).
struct CampaignChannel {
  std::string name;  ///< channel name in the test files
  std::string dof;   ///< model DOF: "node:component" label or 0-based index
  double sign = 1;   ///< +1 or -1
};

/// A mode to analyse.
struct CampaignMode {
  std::string name;       ///< "mode 1"
  signal::Band band;      ///< band-pass around the mode [Hz]
  int model_mode = 0;     ///< elastic mode of the model it corresponds to (1-based); 0: none
  std::string reference;  ///< channel whose backbones are summarised
  /// Stepped-sine files of this mode (absolute; data/stepped_sine.h), the response measured at
  /// the reference channel: their backbones are fitted with the hammer hits'.
  std::vector<std::filesystem::path> stepped_sine;
  /// Backbone tables of this mode (absolute; data/backbone_table.h, one curve each, from any
  /// source), the amplitude of the campaign's `amplitude` quantity at the reference channel:
  /// fitted with the hammer hits' backbones (ring-down backbones).
  std::vector<std::filesystem::path> backbones;
};

/// Where the model comes from: a model file, or a riveted-beam description to build.
struct CampaignModel {
  std::filesystem::path file;         ///< model.toml (absolute), or empty
  std::filesystem::path description;  ///< build-model description (absolute), or empty
  int fixed_interface_modes = -1;     ///< override of the description's reduction; -1: keep
};

/// Absolute bounds of one named set [N/m], 0 < lower < upper.
struct SetBounds {
  std::string set;   ///< the set's name
  double lower = 0;  ///< smallest stiffness allowed
  double upper = 0;  ///< largest stiffness allowed
};

/// One setting of an update table as written: a number, a text, or bounds of named sets.
struct CampaignSetting {
  std::variant<double, std::string, std::vector<SetBounds>, bool> value;  ///< the value
  long line = 0;  ///< its line in the campaign file (0: not read from a file)
  CampaignSetting() = default;
  /// A number (implicit, so a setting can be assigned a number).
  CampaignSetting(double v, long at = 0) : value(v), line(at) {}  // NOLINT(google-explicit-*)
  /// A text.
  CampaignSetting(std::string v, long at) : value(std::move(v)), line(at) {}
  /// Bounds of named sets.
  CampaignSetting(std::vector<SetBounds> v, long at) : value(std::move(v)), line(at) {}
  /// A flag (true or false).
  static CampaignSetting flag(bool v, long at) {
    CampaignSetting s;
    s.value = v;
    s.line = at;
    return s;
  }
};

/// One update step and its settings (passed on to the updating library).
struct CampaignUpdate {
  bool enabled = false;            ///< run this step
  std::vector<std::string> sets;   ///< named element sets to update ("spring.kz", "iwan.rivet")
  std::vector<std::string> modes;  ///< campaign modes (by name) it fits; empty: every mode
  std::map<std::string, CampaignSetting> settings;  ///< every other key of the table
  /// True if this step fits the campaign mode named `mode` (listed, or no list given).
  bool fits(const std::string& mode) const;
};

/// A whole campaign.
struct Campaign {
  std::filesystem::path file;                ///< the campaign file (absolute)
  std::string name;                          ///< title for reports
  std::optional<Quantity> quantity;          ///< what unit-less channels measure, if given
  Quantity amplitude = Quantity::kVelocity;  ///< amplitude quantity of the backbones
  std::filesystem::path truth;               ///< optional known parameters (absolute), or empty
  std::vector<CampaignGroup> groups;         ///< at least one
  std::vector<CampaignChannel> channels;     ///< at least one
  std::vector<CampaignMode> modes;           ///< at least one
  CampaignModel model;                       ///< may be empty (no model side)
  ScatterOptions scatter;                    ///< [scatter]
  int qsma_points = 60;                      ///< [qsma] points
  CampaignUpdate linear_update;              ///< [update.linear]
  CampaignUpdate iwan_update;                ///< [update.iwan]

  /// Number of hits over every group.
  int hit_count() const;
  /// The channel named `name`, or nullptr.
  const CampaignChannel* channel(const std::string& name) const;
};

/// Reads and checks a campaign file; InputError naming the file, line and field.
Campaign read_campaign(const std::filesystem::path& path);

/// Parses campaign text as if read from `path` (relative paths resolve against its folder).
Campaign parse_campaign(const std::string& text, const std::filesystem::path& path);

}  // namespace jointlab::campaign
