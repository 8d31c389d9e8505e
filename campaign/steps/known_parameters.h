// Known parameters of a simulated campaign (the campaign's `truth` file: [iwan] Kt Fs chi
// beta, [scatter] Kt Fs planted relative scatter) and the report's comparison of the updated
// parameters with them: per quantity the updated and the known value, the difference, the
// tolerance (twice the planted one-sigma scatter where scatter was planted, else twice the
// update's own one-sigma uncertainty from the scatter between hits) and whether the update
// recovers it. Parameters the data cannot identify are said to be so.
#pragma once

#include <filesystem>
#include <string>

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/report.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/model/iwan.h"
#include "jointlab/model/model_file.h"

namespace jointlab::campaign {

/// Known parameters of a simulated campaign.
struct Truth {
  bool present = false;        ///< a truth file was given
  model::IwanParameters iwan;  ///< the Iwan set's parameters
  double scatter_kt = 0;       ///< planted relative hit-to-hit scatter of K_T
  double scatter_fs = 0;       ///< planted relative hit-to-hit scatter of F_S
};

/// Reads a truth file (empty path: none); InputError naming the file and field. Its [iwan] holds
/// the fitted set's known values, or one table per set ([iwan.bolt], [iwan.rivet]): then the
/// table of `set` ("iwan.<name>" or "<name>", [update.iwan] sets), which must be named.
Truth read_truth(const std::filesystem::path& path, const std::string& set = "");

/// The set whose known values a campaign's truth file gives: [update.iwan] sets' one, or "".
std::string truth_set(const Campaign& campaign);

/// The parameters and element name of the model's Iwan set `want` ("iwan.<name>" or "<name>";
/// "" the first Iwan joint's set); false when the model has no such joint.
bool first_iwan(const model::Model& m, model::IwanParameters& p, std::string& set,
                const std::string& want = "");

/// What the report compares with the known parameters.
struct KnownComparison {
  Truth truth;                        ///< the known parameters
  model::IwanParameters updated;      ///< the updated model's Iwan set
  bool kt_updated = false;            ///< K_T changed by the linear or the Iwan update
  bool iwan_ran = false;              ///< the Iwan update ran
  bool beta_held = false;             ///< beta held (microslip data, or by the campaign)
  int curves = 0;                     ///< backbones the Iwan update fitted
  correlate::IwanUpdateSummary iwan;  ///< the Iwan update's outcome
  double cost_known = 0;              ///< the Iwan update's cost at the known parameters
  /// The updated K_T's relative one-sigma uncertainty from the update that set it (the Iwan
  /// update where it fitted K_T, else the linear update); 0: none stated.
  double kt_std = 0;
};

/// Adds the "Updated versus known" table and its paragraph to `section`.
void compare_with_known(const KnownComparison& k, const std::string& truth_name,
                        ReportSection& section);

}  // namespace jointlab::campaign
