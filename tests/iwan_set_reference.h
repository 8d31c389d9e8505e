// Test-only references for the shared set-up of Iwan updating (model/iwan_set_model.h): the
// model with a set changed, built as the objective does, and the QSMA curves of two
// condensations at the same modal amplitudes.
#pragma once

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/qsma.h"

namespace jointlab::testing {

/// The model with every element of `set` at p (stiffness K_T, Iwan element of p).
inline model::Model with_set(model::Model m, const std::string& set,
                             const model::IwanParameters& p) {
  for (model::Joint& j : m.joints) {
    if (j.element != set) continue;
    j.stiffness = p.Kt;
    j.iwan = model::Iwan(p);
  }
  return m;
}

/// qsma() of `mode` of `fast` (into *cf) and of `reference` (into *cs) at the same modal
/// amplitudes: `points` of the reference's default range, up to its last point but one (at its
/// end, the limit load or full macroslip, the curve is flat in alpha and its q there hangs on
/// the last digits of the model). A fatal failure when that range has fewer than 3 points:
/// call it inside ASSERT_NO_FATAL_FAILURE.
inline void qsma_on_one_range(const model::JointCondensation& fast,
                              const model::JointCondensation& reference, int mode, int points,
                              std::vector<model::QsmaPoint>* cf,
                              std::vector<model::QsmaPoint>* cs) {
  model::QsmaOptions options;
  model::QsmaSummary summary;
  options.points = points;
  const std::vector<model::QsmaPoint> range = model::qsma(reference, mode, options, &summary);
  ASSERT_GE(range.size(), 3u);
  options.q_min = range.front().modal_amplitude;
  options.q_max = range[range.size() - 2].modal_amplitude;
  *cf = model::qsma(fast, mode, options, &summary);
  *cs = model::qsma(reference, mode, options, &summary);
}

}  // namespace jointlab::testing
