#include "jointlab/tests/small_campaign.h"

#include <fmt/format.h>

#include "jointlab/data/record_writer.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file_writer.h"
#include "jointlab/model/sim/ringdown_simulation.h"
#include "jointlab/model/sim/simulated_record.h"
#include "jointlab/tests/cli.h"

namespace jointlab::testing {

namespace fs = std::filesystem;

namespace {

// Sensor DOFs (A2 and A6) and the struck DOF (A6).
constexpr Eigen::Index kSensorA = 1, kSensorB = 5, kImpact = 5;

// Chain A's first mode: the lowest elastic mode moving chain A more than chain B.
int chain_a_mode(const model::Model& m, int n, double& frequency_hz) {
  const model::LinearModes lm = model::linear_modes(m.mass, m.linear_stiffness());
  for (int j = lm.rigid_count; j < lm.size(); ++j) {
    if (lm.shapes.col(j).head(n).norm() > lm.shapes.col(j).tail(n).norm()) {
      frequency_hz = lm.frequency_hz(j);
      return j - lm.rigid_count + 1;
    }
  }
  return 0;
}

}  // namespace

SmallCampaign make_small_campaign(const fs::path& dir, const std::string& extra,
                                  const std::vector<double>& forces) {
  SmallCampaign s;
  s.dir = dir;
  fs::create_directories(dir);
  s.truth.iwan = true;
  s.start = s.truth;
  s.start.ka *= 0.8;
  s.start.chi = -0.3;
  const model::Model truth = correlate::two_chain_structure(s.truth);
  s.model_mode = chain_a_mode(truth, s.truth.n, s.frequency_hz);
  s.band = {0.85 * s.frequency_hz, 1.15 * s.frequency_hz};
  s.model = dir / "model.toml";
  model::write_model_file(s.model, correlate::two_chain_structure(s.start));
  s.sensors = dir / "sensors.csv";
  write_text(s.sensors.string(), fmt::format("channel,dof,sign\nacc_{},{},1\nacc_{},{},1\n",
                                             kSensorA, kSensorA, kSensorB, kSensorB));
  std::string files;
  for (size_t i = 0; i < forces.size(); ++i) {
    model::SimulationOptions so;
    so.pulse.dof = kImpact;
    so.pulse.force = forces[i];
    so.pulse.duration = 0.002;
    so.sensors = {kSensorA, kSensorB};
    so.fs = 1000;
    so.duration = 2.0;
    so.modal_damping = 0;
    model::SimulationSummary summary;
    const model::SimulatedResponse r = model::simulate_ringdown(truth, so, &summary);
    model::RecordOptions ro;
    ro.model_name = "two-chain truth";
    ro.noise = 1e-4;
    ro.seed = 10 + i;
    const fs::path hit = dir / fmt::format("hit{}.csv", i + 1);
    data::write_csv_record(hit, model::make_simulated_record(truth, so, r, summary, ro));
    s.hits.push_back(hit);
    files += fmt::format("{}\"{}\"", i ? ", " : "", hit.filename().string());
  }
  s.campaign = dir / "campaign.toml";
  write_text(s.campaign.string(),
             fmt::format("[campaign]\nname = \"two chains\"\nquantity = \"acceleration\"\n"
                         "amplitude = \"velocity\"\n\n[model]\nfile = \"model.toml\"\n\n"
                         "[[group]]\nname = \"all\"\nlevel = \"{} to {} N\"\nfiles = [{}]\n\n"
                         "[[channel]]\nname = \"acc_{}\"\ndof = \"{}\"\n\n"
                         "[[channel]]\nname = \"acc_{}\"\ndof = \"{}\"\n\n"
                         "[[mode]]\nname = \"mode A1\"\nband = [{:.3f}, {:.3f}]\nmodel_mode = {}\n"
                         "reference = \"acc_{}\"\n\n[qsma]\npoints = 20\n\n{}",
                         forces.front(), forces.back(), files, kSensorA, kSensorA, kSensorB,
                         kSensorB, s.band[0], s.band[1], s.model_mode, kSensorB, extra));
  return s;
}

}  // namespace jointlab::testing
