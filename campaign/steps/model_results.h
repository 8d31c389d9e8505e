// What a campaign run found on the model side: the model, its evaluation before updating,
// the two updates and the evaluation of the updated model. The figures and the report read it.
#pragma once

#include "jointlab/campaign/steps/iwan_step.h"
#include "jointlab/campaign/steps/linear_step.h"
#include "jointlab/campaign/steps/model_side.h"

namespace jointlab::campaign {

/// The model side of a run.
struct ModelResults {
  CampaignModelData data;     ///< the model and the channels' DOFs
  ModelSide start;            ///< the model as given
  LinearStep linear;          ///< the linear update
  IwanStep iwan;              ///< the Iwan update
  bool have_updated = false;  ///< either update ran
  model::Model updated;       ///< the model after both updates (when have_updated)
  ModelSide after;            ///< the updated model (when have_updated)
};

}  // namespace jointlab::campaign
