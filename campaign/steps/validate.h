// Checking a whole campaign before any hit is processed, so that a typo in an update table, a
// bad DOF or a model that does not fit the campaign is reported at once, not after minutes of
// processing: the update tables' settings, then (once the model file is known) the model
// itself, every channel's DOF, every mode's model_mode against the model's size and the
// update tables' element sets. Each failure is an InputError naming the campaign file and
// field.
#pragma once

#include <filesystem>

#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/steps/model_side.h"

namespace jointlab::campaign {

/// Checks what needs no model, before any hit is processed: the truth file, the stepped-sine
/// files and the settings of [update.linear] and [update.iwan].
void validate_settings(const Campaign& campaign);

/// Reads the model file and checks the campaign against it; returns the model with the
/// channels' DOFs.
CampaignModelData validate_model(const Campaign& campaign, const std::filesystem::path& file);

}  // namespace jointlab::campaign
