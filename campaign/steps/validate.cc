#include "jointlab/campaign/steps/validate.h"

#include <fmt/format.h>

#include "jointlab/campaign/steps/iwan_step.h"
#include "jointlab/campaign/steps/known_parameters.h"
#include "jointlab/campaign/steps/linear_step.h"
#include "jointlab/core/error.h"
#include "jointlab/correlate/linear_update.h"

namespace jointlab::campaign {

void validate_settings(const Campaign& c) {
  // The truth file and the stepped-sine files are read now, not after the hits: a defect
  // in one of them once stopped a run only after its minutes of processing.
  read_truth(c.truth, truth_set(c));
  for (size_t k = 0; k < c.modes.size(); ++k) {
    if (!c.modes[k].stepped_sine.empty()) stepped_sine_backbones(c, k, 0);
  }
  if (c.linear_update.enabled) linear_update_options(c);
  if (c.iwan_update.enabled) {
    correlate::IwanUpdateOptions io;
    IwanTargetOptions to;
    iwan_update_options(c, io, to);
  }
}

CampaignModelData validate_model(const Campaign& c, const std::filesystem::path& file) {
  CampaignModelData d = read_campaign_model(c, file);
  for (const CampaignMode& m : c.modes) {
    if (m.model_mode > d.model.size())
      throw InputError(where(c.file.string(), 0,
                             fmt::format("mode '{}': model_mode {} but the model {} has {} DOFs",
                                         m.name, m.model_mode, file.string(), d.model.size())));
  }
  const auto sets_error = [&](const char* table, const std::string& why) {
    return InputError(where(c.file.string(), 0, fmt::format("{}.sets: {}", table, why)));
  };
  if (c.linear_update.enabled && !c.linear_update.sets.empty()) {
    try {
      correlate::StiffnessSets(d.model, c.linear_update.sets);
    } catch (const InputError& e) {
      throw sets_error("update.linear", e.what());
    }
  }
  if (c.iwan_update.enabled) {
    const std::string set = iwan_set(c, d.model);
    bool found = false;
    for (const model::Joint& j : d.model.joints)
      found = found || (j.iwan && (j.element == set || j.element == "iwan." + set));
    if (!found)
      throw sets_error("update.iwan",
                       fmt::format("'{}' is not an Iwan set of {}", set, file.string()));
  }
  return d;
}

}  // namespace jointlab::campaign
