// `jointlab compare MODEL... (--measured DIR --sensors FILE | --backbone FILE...) --mode R
// --out FIG [--label NAME]...`: the QSMA backbones of several models (ring-down columns) over the
// measured ones, frequency and damping against amplitude (the paper's Figures 5-7), with a CSV of
// the plotted model curves beside the figure. Argument parsing only: the measured side and the
// model curves (campaign/model_comparison.h) and the figure (campaign/backbone_comparison.h) are
// library code.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
#include "jointlab/campaign/backbone_comparison.h"
#include "jointlab/campaign/iwan_inputs.h"
#include "jointlab/campaign/model_comparison.h"
#include "jointlab/core/error.h"

namespace jointlab::apps {
namespace {

namespace fs = std::filesystem;

struct CompareArgs : campaign::IwanInputArgs {
  std::vector<std::string> models, labels;
  std::string mode, out;
  int points = 100;
};

void run_compare(CompareArgs a) {
  const std::string ext = fs::path(a.out).extension().string();
  if (ext != ".png" && ext != ".svg" && ext != ".pdf") {
    throw InputError(fmt::format("--out {}: the figure must end in .png, .svg or .pdf", a.out));
  }
  a.modes = {a.mode};
  const campaign::ModelComparison c = campaign::compare_models(a.models, a.labels, a, a.points);
  if (!c.slip_screen.empty())
    say(stdout, "slip screen (points where other modes slip the joints):\n{}", c.slip_screen);
  for (const std::string& note : c.notes) say(stderr, "{}\n", note);
  const fs::path csv = fs::path(a.out).replace_extension(".csv");
  if (const fs::path dir = fs::path(a.out).parent_path(); !dir.empty()) {
    std::error_code ec;  // one line, not an internal error (made only now: a refusal
                         // above leaves no folder behind)
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir))
      throw InputError(fmt::format("--out {}: cannot create the folder {}", a.out, dir.string()));
  }
  campaign::plot_backbone_comparison(c.figure, a.out, csv);
  say(stdout, "compare: wrote {} and {}\n", a.out, csv.string());
}

}  // namespace

void add_compare_command(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Draws the QSMA backbones of one or more models (ring-down columns, the model's own\n"
      "damping included) over measured backbones, frequency and damping against amplitude\n"
      "(the paper's Figures 5-7), as PNG, SVG or PDF by the extension of --out, with a CSV of\n"
      "the plotted model curves beside it (model,amplitude,frequency_hz,damping_ratio).\n"
      "A model curve that does not reach the measured range is drawn clipped and said so.");
  cmd->add_option("MODEL", args->models, "model files (TOML)")->required();
  cmd->add_option("--measured", args->measured, "output directory of 'jointlab process'");
  cmd->add_option("--sensors", args->sensors, "sensors file: channel,dof[,sign] (with --measured)");
  cmd->add_option("--channel", args->channels,
                  "channel whose backbones are drawn (repeatable; default: one channel for every "
                  "file, the files' reference channel of the band, or where they differ the "
                  "one with a backbone in the most files, said in the report)");
  cmd->add_option("--backbone", args->backbones,
                  "a measured backbone table (amplitude,frequency_hz,damping_ratio,...; "
                  "repeatable; instead of --measured)");
  cmd->add_option("--amplitude", args->amplitude,
                  "what the --backbone amplitude is: modal (default), or displacement, velocity "
                  "or acceleration at --dof")
      ->check(CLI::IsMember({"modal", "displacement", "velocity", "acceleration"}));
  cmd->add_option("--dof", args->dof, "model DOF the --backbone amplitude was measured at");
  cmd->add_option("--mode", args->mode,
                  "elastic model mode R (with --measured also R:BAND; default band: paired by MAC)")
      ->required();
  cmd->add_option("--label", args->labels, "legend name of each MODEL, in order (repeatable)");
  cmd->add_option("--points", args->points, "points per model curve (default 100)")
      ->check(CLI::Range(2, 100000));
  cmd->add_option("--out", args->out, "figure file (.png, .svg or .pdf)")->required();
  cmd->callback([args] { run_compare(*args); });
}

}  // namespace jointlab::apps
