// Step "Iwan update" of a campaign run (method.md Figure 1): [update.iwan] identifies one Iwan
// set's F_S, K_T, chi and beta from the kept hits' backbones (iwan_targets.h) of the modes
// that name their model mode, starting from the linearly updated model. Below phi_max the
// backbones depend on K_T, chi and R only, so the first fit holds beta at its starting value
// (unless the campaign holds it); only when that fit puts the top of the data past phi_max
// is beta freed for a second fit, and the better of the two is kept. The search box is
// update-iwan's default (correlate::default_iwan_bounds), so that both commands give the same
// parameters for the same backbones and settings.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/iwan_fit.h"
#include "jointlab/campaign/iwan_targets.h"
#include "jointlab/campaign/steps/linear_step.h"
#include "jointlab/campaign/steps/measured_side.h"
#include "jointlab/campaign/steps/model_side.h"
#include "jointlab/correlate/iwan_update.h"

namespace jointlab::campaign {

/// The updating options and target settings of [update.iwan]'s settings; InputError naming
/// the campaign file for an unknown setting or a value out of range.
void iwan_update_options(const Campaign& campaign, correlate::IwanUpdateOptions& options,
                         IwanTargetOptions& targets);

/// The Iwan set [update.iwan] updates: the one named in 'sets', else the model's first Iwan
/// set; InputError when the model has none.
std::string iwan_set(const Campaign& campaign, const model::Model& model);

/// The campaign's modes as the Iwan update sees them: each mode's backbones at its reference
/// channel, its scatter summary and measured linear frequency; then, for each mode that lists
/// stepped-sine files, one more entry of the same model mode with their backbones.
std::vector<ModeBackbones> campaign_backbones(const Campaign& campaign,
                                              const MeasuredSide& measured);

/// The stepped-sine backbones of campaign mode k (one curve per file, of kind stepped sine, the
/// amplitude in the campaign's quantity), measured at sensor index `sensor`; InputError naming
/// the campaign file when no level of its files gives a point.
ModeBackbones stepped_sine_backbones(const Campaign& campaign, size_t k, int sensor);

/// One mode's backbone cost at the start and at the result.
struct ModeCost {
  std::string mode;    ///< the campaign mode
  bool fitted = true;  ///< the update fitted it
  double start = 0;    ///< cost at the starting parameters
  double updated = 0;  ///< cost at the result
};

/// What the Iwan update did.
struct IwanStep {
  bool ran = false;      ///< the update ran
  std::string note;      ///< why it was skipped ("" when it ran or was off)
  bool refused = false;  ///< the data cannot be fitted (note says why)
  /// Not run: the linear update's result cannot carry it (note says why; iwan_stop_reason)
  bool stopped = false;
  std::string set;                       ///< the updated set
  correlate::IwanUpdateSummary summary;  ///< its outcome (the better fit)
  bool beta_held = false;                ///< beta held: microslip data, or by the campaign
  int curves = 0;                        ///< backbones fitted
  std::vector<ModeCost> mode_costs;      ///< per mode with a target, fitted or not
  double cost_known = 0;                 ///< cost at the known parameters (0: none given)
  model::Model updated;                  ///< the updated model (when it ran)
  /// What the report says beside the fit's own report: each fitted mode whose joint dissipation
  /// other Iwan sets carry (campaign::set_share_warnings), then each mode's backbone tables read
  /// without an amplitude unit (ModeBackbones::amplitude_note, as "note: ...").
  std::vector<std::string> warnings;
};

/// The step: runs [update.iwan] from `base` (the linearly updated model, else the campaign's)
/// against the measured side; skipped when off or without targets. `linear_updated`: `base` is
/// the linear update's result (IwanUpdateOptions::linear_part_updated: the report states the
/// linear part's effect without sending to update-linear).
IwanStep iwan_update_step(const Campaign& campaign, const model::Model& base,
                          const std::vector<correlate::Sensor>& sensors,
                          const MeasuredSide& measured,
                          const std::function<void(const std::string&)>& progress,
                          bool linear_updated = false, const std::function<void()>& interrupt = {});

/// [update.iwan] accept_unconfirmed_pairs: run the Iwan update from a linear update whose pairs
/// the shapes do not confirm at its result (default false); InputError naming the campaign file
/// for a value that is not true or false.
bool accepts_unconfirmed_pairs(const Campaign& campaign);

/// Why the Iwan update must not start from the linear update's result, or "": pairs the shapes
/// do not confirm at that result (LinearUpdateStatus::kPairsUnconfirmed: the model's modes may
/// be cross-paired) unless [update.iwan] accept_unconfirmed_pairs = true, a fitted [[mode]]
/// whose model_mode differs from the model mode its shape is paired with (a confirmed MAC), or
/// the Iwan set `set` acting together with another set (only their combination determined: the
/// split the Iwan joint would start from is arbitrary). Names the campaign-file keys that
/// change it.
std::string iwan_stop_reason(const Campaign& campaign, const LinearStep& linear,
                             const std::string& set);

/// The step after the linear update: iwan_update_step() from the linearly updated model (the
/// campaign's where the linear update did not run), or, where iwan_stop_reason() gives a
/// reason, not run (IwanStep::stopped, the reason in its note).
IwanStep iwan_update_after(const Campaign& campaign, const CampaignModelData& model,
                           const LinearStep& linear, const MeasuredSide& measured,
                           const std::function<void(const std::string&)>& progress,
                           const std::function<void()>& interrupt = {});

}  // namespace jointlab::campaign
