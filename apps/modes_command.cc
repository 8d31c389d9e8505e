// `jointlab modes MODEL [--count N] --out FILE`: the lowest linear modes of a model file with
// every joint at its linear stiffness, as CSV mode,frequency_hz,kind.
#include <memory>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"

namespace jointlab::apps {
namespace {

struct ModesArgs {
  std::string model;
  std::string out;
  int count = 20;
};

void run_modes(const ModesArgs& args) {
  const model::Model m = model::read_model(args.model);
  model::ModesOptions options;
  options.count = args.count;
  const model::LinearModes modes = model::linear_modes(m, options);
  std::string text = "mode,frequency_hz,kind\n";
  int elastic = 0;
  for (int i = 0; i < modes.size(); ++i) {
    const bool rigid = modes.rigid(i);
    text += fmt::format("{},{:.10g},{}\n", rigid ? 0 : ++elastic, modes.frequency_hz(i),
                        rigid ? "rigid" : "elastic");
  }
  data::write_file_atomically(args.out, text);
  // The structure's own damping is the same for every elastic mode: one line, not a column.
  say(stdout, "modal damping ratio of every elastic mode: {:.6g} ({})\n", m.modal_ratio,
      m.modal_ratio > 0 ? "the model's [damping] modal_ratio" : "the model has no [damping]");
}

}  // namespace

void add_modes_command(CLI::App& app) {
  auto args = std::make_shared<ModesArgs>();
  CLI::App* cmd = app.add_subcommand(
      "modes",
      "Linear modes of a model file with every joint at its linear stiffness (Iwan: Kt).\n"
      "Writes CSV mode,frequency_hz,kind in ascending frequency; rigid-body modes are\n"
      "numbered 0 (kind 'rigid', frequency 0), elastic modes from 1. Prints the damping\n"
      "ratio of every elastic mode (the model's [damping] modal_ratio, 0 without one).");
  cmd->add_option("MODEL", args->model, "model file (TOML)")->required();
  cmd->add_option("--count", args->count, "number of modes, lowest first (default 20)")
      ->check(positive());
  cmd->add_option("--out", args->out, "output CSV file")->required();
  cmd->callback([args] { run_modes(*args); });
}

}  // namespace jointlab::apps
