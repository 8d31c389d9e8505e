#include "jointlab/model/sim/simulated_record.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::model {

Eigen::Index resolve_dof(const Model& model, const std::string& text, const std::string& what) {
  const Eigen::Index n = model.size();
  if (!text.empty() && text.find_first_not_of("0123456789") == std::string::npos) {
    if (text.size() > 12) {
      throw InputError(
          fmt::format("{} = \"{}\": index outside the model's 0..{}", what, text, n - 1));
    }
    const Eigen::Index i = std::stoll(text);
    if (i >= n) {
      throw InputError(
          fmt::format("{} = \"{}\": index outside the model's 0..{}", what, text, n - 1));
    }
    return i;
  }
  if (text.find(':') != std::string::npos) {
    if (model.dof_labels.empty()) {
      throw InputError(fmt::format(
          "{} = \"{}\": a \"node:component\" label needs the model's matrices.dof_labels", what,
          text));
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      if (model.dof_labels[static_cast<size_t>(i)] == text) return i;
    }
    throw InputError(fmt::format("{} = \"{}\" is not a label of the model's dof_labels{}", what,
                                 text, missing_label_hint(model, text)));
  }
  throw InputError(fmt::format(
      "{} = \"{}\": expected a 0-based DOF index or a \"node:component\" label", what, text));
}

std::string dof_name(const Model& model, Eigen::Index dof) {
  if (!model.dof_labels.empty()) return model.dof_labels[static_cast<size_t>(dof)];
  return std::to_string(dof);
}

std::string sensor_channel_name(const Model& model, Eigen::Index dof) {
  if (model.dof_labels.empty()) return fmt::format("acc_{}", dof);
  const std::string& label = model.dof_labels[static_cast<size_t>(dof)];
  const auto colon = label.find(':');
  if (colon == std::string::npos) return "acc_" + label;
  static const char* const kNames[] = {"x", "y", "z", "rx", "ry", "rz"};
  const std::string node = label.substr(0, colon), comp = label.substr(colon + 1);
  std::string c = comp;
  if (comp.size() == 1 && comp[0] >= '1' && comp[0] <= '6') c = kNames[comp[0] - '1'];
  return fmt::format("acc_{}_{}", node, c);
}

std::string RecordOptions::error() const {
  if (!(noise >= 0 && noise < 10)) return fmt::format("noise {} must be in [0, 10)", noise);
  return "";
}

void check_sensors(const Model& model, const std::vector<Eigen::Index>& sensors) {
  std::set<std::string> names;
  for (const Eigen::Index dof : sensors) {
    if (!names.insert(sensor_channel_name(model, dof)).second) {
      throw InputError(fmt::format("simulate: sensor {} is given twice", dof_name(model, dof)));
    }
  }
}

data::Record make_simulated_record(const Model& model, const SimulationOptions& simulation,
                                   const SimulatedResponse& response,
                                   const SimulationSummary& summary, const RecordOptions& options) {
  if (const std::string e = options.error(); !e.empty()) throw InputError("simulate: " + e);
  check_sensors(model, simulation.sensors);
  data::Record rec;
  rec.fs = response.fs;
  rec.t0 = 0;
  rec.source = options.model_name;
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (size_t k = 0; k < simulation.sensors.size(); ++k) {
    data::Channel ch;
    ch.name = sensor_channel_name(model, simulation.sensors[k]);
    ch.quantity = Quantity::kAcceleration;
    ch.unit = si_unit(Quantity::kAcceleration);
    ch.samples = response.acceleration.col(static_cast<Eigen::Index>(k));
    if (options.noise > 0) {
      const double sd = options.noise * ch.samples.cwiseAbs().maxCoeff();
      for (Eigen::Index i = 0; i < ch.samples.size(); ++i) ch.samples(i) += sd * normal(rng);
    }
    rec.channels.push_back(std::move(ch));
  }
  if (options.include_force) {
    data::Channel f;
    f.name = "hammer";
    f.quantity = Quantity::kForce;
    f.unit = si_unit(Quantity::kForce);
    f.samples = response.force;
    rec.channels.push_back(std::move(f));
  }
  const HalfSinePulse& p = simulation.pulse;
  auto& md = rec.metadata;
  md["model"] = options.model_name;
  md["impact_dof"] = dof_name(model, p.dof);
  md["force_N"] = fmt::format("{}", p.force);
  md["pulse_s"] = fmt::format("{}", p.duration);
  md["pulse_start_s"] = fmt::format("{}", p.start);
  md["substeps"] = fmt::format("{}", summary.substeps);
  md["dt_s"] = fmt::format("{}", summary.dt);
  md["noise"] = fmt::format("{}", options.noise);
  md["seed"] = fmt::format("{}", options.seed);
  md["energy_closure"] = fmt::format("{:.3e}", summary.energy.relative_closure());
  md["test"] = "simulate";
  return rec;
}

}  // namespace jointlab::model
