#include "jointlab/campaign/steps/model_side.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "jointlab/campaign/steps/stamp.h"
#include "jointlab/core/error.h"
#include "jointlab/data/table_writer.h"
#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/qsma.h"
#include "jointlab/model/sim/simulated_record.h"

namespace jointlab::campaign {

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;

// QSMA of campaign mode k's model mode in the measured amplitude, written to qsma_dir.
ModelCurve qsma_curve(const Campaign& c, const model::JointCondensation& jc,
                      const std::vector<Eigen::Index>& dofs, size_t k, const fs::path& qsma_dir,
                      const std::string& tag, std::string& note) {
  const CampaignMode& cm = c.modes[k];
  int ref = 0;
  for (size_t i = 0; i < c.channels.size(); ++i)
    if (c.channels[i].name == cm.reference) ref = static_cast<int>(i);
  model::QsmaOptions qo;
  qo.points = c.qsma_points;
  model::QsmaSummary qs;
  const std::vector<model::QsmaPoint> pts = qsma(jc, cm.model_mode, qo, &qs);
  note = qs.message;
  const Eigen::Index n = static_cast<Eigen::Index>(pts.size());
  ModelCurve curve;
  curve.amplitude.resize(n);
  curve.frequency_hz.resize(n);
  curve.damping.resize(n);
  const int power = c.amplitude == Quantity::kDisplacement ? 0
                    : c.amplitude == Quantity::kVelocity   ? 1
                                                           : 2;
  // The amplitude at the reference channel is its DOF's deflection (model::QsmaDof), as
  // update-iwan fits it, not |phi| q: in macroslip the deflected shape leaves the linear mode's.
  // Each point's joint solution, continued up the curve.
  const model::QsmaMode mode(jc, cm.model_mode);
  const model::QsmaDof at_reference(jc, cm.model_mode, dofs[ref]);
  Eigen::VectorXd r = Eigen::VectorXd::Zero(jc.size());
  Eigen::VectorXd q(n), alpha(n), slip(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double w = 2 * kPi * pts[i].frequency_hz;
    const double runaway = 1e6 * (r.lpNorm<Eigen::Infinity>() + jc.smallest_phi_max());
    if (!jc.solve(mode.g, pts[i].force_amplitude, r, runaway, 60).converged) {
      throw InputError(
          fmt::format("QSMA of campaign mode {}: the static solve at point {} of "
                      "its curve did not converge again",
                      k + 1, i + 1));
    }
    curve.amplitude(i) = at_reference.deflection(pts[i].force_amplitude, r) * std::pow(w, power);
    curve.frequency_hz(i) = pts[i].frequency_hz;
    curve.damping(i) = pts[i].damping_ratio;
    q(i) = pts[i].modal_amplitude;
    alpha(i) = pts[i].force_amplitude;
    slip(i) = pts[i].max_slip;
  }
  data::Table t;
  t.add("amplitude", curve.amplitude);
  t.add("frequency_hz", curve.frequency_hz);
  t.add("damping_ratio", curve.damping);
  t.add("modal_amplitude", q);
  t.add("force_amplitude", alpha);
  t.add("max_slip", slip);
  fs::create_directories(qsma_dir);
  data::write_table(qsma_dir / fmt::format("mode{}.{}.csv", k + 1, tag), t);
  return curve;
}

}  // namespace

fs::path prepare_model(const Campaign& c, const fs::path& out, const RunOptions& o,
                       RunSummary& summary) {
  if (c.model.description.empty()) return c.model.file;
  const auto say = [&](const std::string& s) {
    if (o.progress) o.progress(s);
  };
  const fs::path dir = out / "model";
  const fs::path model_path = dir / "model.toml";
  const std::string stamp =
      input_stamp({c.model.description},
                  fmt::format("fixed_interface_modes {}", c.model.fixed_interface_modes));
  if (!o.force && fs::exists(model_path) && stamp_matches(dir / "model.stamp", stamp)) {
    summary.model_reused = true;
    say(fmt::format("model: {} is up to date", model_path.string()));
    return model_path;
  }
  say(fmt::format("model: building from {}", c.model.description.string()));
  model::fe::RivetedBeamDescription d =
      model::fe::read_riveted_beam_description(c.model.description);
  if (c.model.fixed_interface_modes >= 0) d.fixed_interface_modes = c.model.fixed_interface_modes;
  model::fe::BuildOptions bo;
  bo.progress = [&](const std::string& s) { say("model: " + s); };
  bo.interrupt = o.interrupt;
  const model::fe::ReducedModel rm = model::fe::build_reduced_model(d, bo);
  if (!rm.summary.ok)
    throw InputError(fmt::format("{}: the reduction failed: {}", c.model.description.string(),
                                 rm.summary.report));
  fs::remove(dir / "model.stamp");
  model::fe::write_model_directory(dir, rm);
  write_stamp(dir / "model.stamp", stamp);
  summary.model_built = true;
  return model_path;
}

CampaignModelData read_campaign_model(const Campaign& c, const fs::path& file) {
  CampaignModelData d;
  d.file = file;
  d.model = model::read_model(file);
  for (const CampaignChannel& ch : c.channels) {
    d.dofs.push_back(model::resolve_dof(
        d.model, ch.dof, fmt::format("{}: channel '{}' dof", c.file.string(), ch.name)));
    d.sensors.push_back({ch.name, d.dofs.back(), ch.sign});
  }
  return d;
}

ModelSide evaluate_model(const Campaign& c, const model::Model& m,
                         const std::vector<Eigen::Index>& dofs, const std::string& label,
                         const fs::path& qsma_dir, const std::string& tag) {
  ModelSide s;
  const model::JointCondensation jc(m);
  const model::LinearModes& lm = jc.modes();
  const int rigid = lm.rigid_count, elastic = jc.elastic_count();
  int needed = 0;
  for (const CampaignMode& cm : c.modes) needed = std::max(needed, cm.model_mode);
  const int ncols = std::min(elastic, std::max(needed + 2, static_cast<int>(c.modes.size()) + 2));
  s.sensor_shapes.resize(static_cast<Eigen::Index>(dofs.size()), ncols);
  for (int j = 0; j < ncols; ++j) {
    s.shape_hz.push_back(lm.frequency_hz(rigid + j));
    for (size_t i = 0; i < dofs.size(); ++i)
      s.sensor_shapes(static_cast<Eigen::Index>(i), j) =
          c.channels[i].sign * lm.shapes(dofs[i], rigid + j);
  }
  for (size_t k = 0; k < c.modes.size(); ++k) {
    const CampaignMode& cm = c.modes[k];
    if (cm.model_mode < 1 || cm.model_mode > elastic) {
      s.frequency_hz.push_back(0);
      s.curves.push_back(ModelCurve{label, {}, {}, {}});
      continue;
    }
    s.frequency_hz.push_back(lm.frequency_hz(rigid + cm.model_mode - 1));
    std::string note;
    s.curves.push_back(qsma_curve(c, jc, dofs, k, qsma_dir, tag, note));
    s.curves.back().label = label;
    s.qsma_notes.push_back(fmt::format("{} ({}): {}", cm.name, label, note));
  }
  return s;
}

}  // namespace jointlab::campaign
