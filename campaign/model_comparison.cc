#include "jointlab/campaign/model_comparison.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/model_file.h"

namespace jointlab::campaign {

ModelComparison compare_models(const std::vector<std::string>& models,
                               const std::vector<std::string>& labels, IwanInputArgs measured,
                               int points) {
  if (models.empty()) throw InputError("compare: give at least one model file");
  if (!labels.empty() && labels.size() != models.size()) {
    throw InputError(fmt::format("compare: {} --label for {} models: give one per model or none",
                                 labels.size(), models.size()));
  }
  if (measured.modes.size() != 1) throw InputError("compare: give one --mode");
  // The measured side against the first model (every model shares its DOFs).
  measured.model = models.front();
  const model::Model first = model::read_model(measured.model);
  const IwanInputs in = read_iwan_inputs(first, measured, "compare");
  const correlate::IwanTarget& target = in.targets.front();
  double lo = INFINITY, hi = 0;
  for (const correlate::MeasuredBackbone& c : target.curves) {
    lo = std::min(lo, c.amplitude.minCoeff());
    hi = std::max(hi, c.amplitude.maxCoeff());
  }
  const correlate::MeasuredBackbone& ref = target.curves.front();
  ModelComparison out;
  out.slip_screen = in.slip_screen;
  out.notes = in.curve_notes;
  BackboneComparison& c = out.figure;
  c.title = fmt::format("mode {}: measured and {} model{}", target.mode, models.size(),
                        models.size() == 1 ? "" : "s");
  c.amplitude_label = amplitude_axis_label(in.modal, in.amplitude);
  c.measured = target.curves;
  for (size_t i = 0; i < models.size(); ++i) {
    const model::Model m = i == 0 ? first : model::read_model(models[i]);
    if (m.size() != first.size()) {
      throw InputError(fmt::format("{}: {} DOFs where {} has {}: the models must share their DOFs",
                                   models[i], m.size(), models.front(), first.size()));
    }
    if (m.iwan_count() == 0) {
      throw InputError(where(models[i], 0, "the model has no Iwan joint; QSMA needs one"));
    }
    model::ModesOptions mo;
    mo.elastic_count = target.mode;
    const model::JointCondensation jc(m, mo);
    if (target.mode > jc.elastic_count()) {
      throw InputError(fmt::format("--mode {}: {} has {}", target.mode, models[i],
                                   counted(jc.elastic_count(), "elastic mode")));
    }
    const int col = jc.modes().rigid_count + target.mode - 1;
    const double phi =
        in.modal ? 1.0 : std::abs(jc.modes().shapes(in.sensors[ref.sensor].dof, col));
    const int power = in.modal ? 0 : correlate::amplitude_power(in.amplitude);
    std::string label = labels.empty() ? models[i] : labels[i];
    correlate::ModelBackbone b;
    if (phi > 0) {
      // The deflection at the sensor's DOF, as update-iwan fits it (not phi q).
      const std::optional<Eigen::Index> dof =
          in.modal ? std::nullopt : std::optional<Eigen::Index>(in.sensors[ref.sensor].dof);
      b = correlate::model_backbone(jc, target.mode, dof, power, ref.kind,
                                    correlate::IwanComparison::kMatched, lo, hi, points);
    } else {
      b.clipped = true;
    }
    out.clipped.push_back(b.clipped);
    if (b.clipped) {
      const double reached = b.amplitude.size() > 0 ? b.amplitude.maxCoeff() : 0.0;
      label += " (clipped)";
      out.notes.push_back(fmt::format(
          "compare: {}: the model's curve stops at amplitude {:.4g} of the measured {:.4g} to "
          "{:.4g} (no static solution past its largest load, or its mode leaves the sensor "
          "still); drawn clipped",
          models[i], reached, lo, hi));
    }
    c.models.push_back({label, b.amplitude, b.frequency_hz, b.damping_ratio});
  }
  return out;
}

}  // namespace jointlab::campaign
