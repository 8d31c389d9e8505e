// `jointlab simulate MODEL --impact DOF --force N --duration S --fs HZ --out FILE`: a virtual
// hammer test of a model with Iwan joints, written as a test file of the contract.
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
#include "jointlab/core/error.h"
#include "jointlab/data/record_writer.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/sim/ringdown_simulation.h"
#include "jointlab/model/sim/simulated_record.h"

namespace jointlab::apps {
namespace {

struct SimulateArgs {
  std::string model;
  std::string impact;
  std::vector<std::string> sensors;
  std::string out;
  model::SimulationOptions options;
  model::RecordOptions record;
  bool quiet = false;
  bool modal_damping_given = false;
};

void run_simulate(SimulateArgs& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  const model::Model m = model::read_model(args.model);
  model::SimulationOptions o = args.options;
  // The model's own damping ([damping] modal_ratio) unless --modal-damping says otherwise.
  if (!args.modal_damping_given) o.modal_damping = m.modal_ratio;
  o.pulse.dof = model::resolve_dof(m, args.impact, "--impact");
  o.sensors.clear();
  if (args.sensors.empty()) {
    o.sensors.push_back(o.pulse.dof);
  } else {
    for (const std::string& s : args.sensors)
      o.sensors.push_back(model::resolve_dof(m, s, "--sensors"));
  }
  if (const std::string e = args.record.error(); !e.empty()) throw InputError("simulate: --" + e);
  // Everything the record's writing could refuse, refused before the simulation's seconds.
  model::check_sensors(m, o.sensors);
  data::check_record_destination(args.out);
  if (!args.quiet) {
    o.progress = [&](const std::string& s) { say(stderr, "[{:6.1f} s] {}\n", elapsed(), s); };
    say(stderr, "[{:6.1f} s] {}: {} DOFs, {} joints ({} Iwan); impact at {} with {} N\n", elapsed(),
        args.model, m.size(), m.joints.size(), m.iwan_count(), model::dof_name(m, o.pulse.dof),
        o.pulse.force);
  }
  model::SimulationSummary summary;
  const model::SimulatedResponse r = model::simulate_ringdown(m, o, &summary);
  if (summary.status != model::SimulationStatus::kOk) {
    throw InputError(
        fmt::format("simulate: {}: {}; no record is written (a smaller step, --substeps, may help)",
                    args.model, summary.message));
  }
  args.record.model_name = args.model;
  const data::Record rec = model::make_simulated_record(m, o, r, summary, args.record);
  data::write_record(args.out, rec);
  if (!args.quiet) {
    say(stderr, "[{:6.1f} s] {}\n[{:6.1f} s] wrote {}\n", elapsed(), summary.report(), elapsed(),
        args.out);
  }
}

}  // namespace

void add_simulate_command(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "Virtual hammer test: strike a model with Iwan joints with a half-sine force pulse,\n"
      "integrate its ring-down (Newmark average acceleration, exact Iwan hysteresis) and\n"
      "write the sensors' accelerations [m/s^2] as a test file for 'process' (CSV; .uff and\n"
      ".mat by extension). DOFs are 0-based indices or \"node:component\" labels. The energy\n"
      "balance of the run is reported on stderr. See docs/simulate.md.");
  cmd->add_option("MODEL", args->model, "model file (TOML)")->required();
  cmd->add_option("--impact", args->impact, "struck DOF (index or node:component)")->required();
  cmd->add_option("--force", args->options.pulse.force, "peak force of the pulse [N]")->required();
  cmd->add_option("--duration", args->options.duration, "record length [s]")
      ->required()
      ->check(positive());
  cmd->add_option("--fs", args->options.fs, "sample rate of the record [Hz]")
      ->required()
      ->check(positive());
  cmd->add_option("--sensors", args->sensors,
                  "recorded DOFs (indices or node:component; default: the impact DOF)");
  cmd->add_option("--out", args->out, "output test file (.csv, .uff, .mat)")->required();
  cmd->add_option("--pulse", args->options.pulse.duration, "pulse length [s] (default 0.0005)")
      ->check(positive());
  cmd->add_option("--pulse-start", args->options.pulse.start,
                  "time the pulse starts (pre-trigger) [s] (default 0.01)")
      ->check(non_negative());
  cmd->add_option("--substeps", args->options.substeps,
                  "integration steps per sample (default 0: automatic, Newmark period error "
                  "of the first elastic mode below 1e-5, at least 4)")
      ->check(in_range(0, 100000));
  cmd->add_option_function<double>(
         "--modal-damping",
         [args](double z) {
           args->options.modal_damping = z;
           args->modal_damping_given = true;
         },
         "damping ratio of every elastic mode (linear part; default: the model's [damping] "
         "modal_ratio, 0 without one)")
      ->check(in_range(0.0, 0.999));
  cmd->add_option("--rayleigh-mass", args->options.rayleigh_mass,
                  "alpha of C = alpha M + beta K [1/s] (default 0)")
      ->check(non_negative());
  cmd->add_option("--rayleigh-stiffness", args->options.rayleigh_stiffness,
                  "beta of C = alpha M + beta K [s] (default 0)")
      ->check(non_negative());
  cmd->add_option("--cutoff", args->options.output_cutoff_hz,
                  "modes above this frequency are left out of the recorded signals [Hz] "
                  "(default 0.45 fs)")
      ->check(non_negative());
  cmd->add_option("--noise", args->record.noise,
                  "white noise standard deviation as a fraction of each channel's peak "
                  "(default 0)")
      ->check(in_range(0.0, 9.99));
  cmd->add_option("--seed", args->record.seed, "noise seed (default 1)");
  cmd->add_flag("--force-channel", args->record.include_force,
                "also write the hammer force as channel 'hammer [N]'");
  cmd->add_flag("--quiet", args->quiet, "no progress or energy report on stderr");
  cmd->callback([args] { run_simulate(*args); });
}

}  // namespace jointlab::apps
