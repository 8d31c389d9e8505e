// `jointlab compare MODEL... (--measured DIR --sensors FILE | --backbone FILE...) --mode R
// --out FIG [--label NAME]...`: the QSMA backbones of several models (ring-down columns) over the
// measured ones, frequency and damping against amplitude (the paper's Figures 5-7), with a CSV of
// the plotted model curves beside the figure. Argument parsing only: the measured side
// (campaign/iwan_inputs.h), the model curves (correlate::model_backbone) and the figure
// (campaign/backbone_comparison.h) are library code.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
#include "jointlab/campaign/backbone_comparison.h"
#include "jointlab/campaign/iwan_inputs.h"
#include "jointlab/core/error.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/model_file.h"

namespace jointlab::apps {
namespace {

namespace fs = std::filesystem;

struct CompareArgs : campaign::IwanInputArgs {
  std::vector<std::string> models, labels;
  std::string mode, out;
  int points = 100;
};

void run_compare(CompareArgs a) {
  if (!a.labels.empty() && a.labels.size() != a.models.size()) {
    throw InputError(fmt::format("compare: {} --label for {} models: give one per model or none",
                                 a.labels.size(), a.models.size()));
  }
  const std::string ext = fs::path(a.out).extension().string();
  if (ext != ".png" && ext != ".svg" && ext != ".pdf") {
    throw InputError(fmt::format("--out {}: the figure must end in .png, .svg or .pdf", a.out));
  }
  // The measured side against the first model (every model shares its DOFs).
  a.model = a.models.front();
  a.modes = {a.mode};
  const model::Model first = model::read_model(a.model);
  const campaign::IwanInputs in = campaign::read_iwan_inputs(first, a, "compare");
  if (!in.slip_screen.empty())
    say(stdout, "slip screen (points where other modes slip the joints):\n{}", in.slip_screen);
  const correlate::IwanTarget& target = in.targets.front();
  double lo = INFINITY, hi = 0;
  for (const correlate::MeasuredBackbone& c : target.curves) {
    lo = std::min(lo, c.amplitude.minCoeff());
    hi = std::max(hi, c.amplitude.maxCoeff());
  }
  const correlate::MeasuredBackbone& ref = target.curves.front();
  campaign::BackboneComparison c;
  c.title = fmt::format("mode {}: measured and {} model{}", target.mode, a.models.size(),
                        a.models.size() == 1 ? "" : "s");
  c.amplitude_label = campaign::amplitude_axis_label(in.modal, in.amplitude);
  c.measured = target.curves;
  for (size_t i = 0; i < a.models.size(); ++i) {
    const model::Model m = i == 0 ? first : model::read_model(a.models[i]);
    if (m.size() != first.size()) {
      throw InputError(fmt::format("{}: {} DOFs where {} has {}: the models must share their DOFs",
                                   a.models[i], m.size(), a.models.front(), first.size()));
    }
    if (m.iwan_count() == 0) {
      throw InputError(where(a.models[i], 0, "the model has no Iwan joint; QSMA needs one"));
    }
    model::ModesOptions mo;
    mo.elastic_count = target.mode;
    const model::JointCondensation jc(m, mo);
    if (target.mode > jc.elastic_count()) {
      throw InputError(fmt::format("--mode {}: {} has {} elastic modes", target.mode, a.models[i],
                                   jc.elastic_count()));
    }
    const int col = jc.modes().rigid_count + target.mode - 1;
    const double phi =
        in.modal ? 1.0 : std::abs(jc.modes().shapes(in.sensors[ref.sensor].dof, col));
    const int power = in.modal ? 0 : correlate::amplitude_power(in.amplitude);
    std::string label = a.labels.empty() ? a.models[i] : a.labels[i];
    correlate::ModelBackbone b;
    if (phi > 0) {
      // The deflection at the sensor's DOF, as update-iwan fits it (not phi q).
      const std::optional<Eigen::Index> dof =
          in.modal ? std::nullopt : std::optional<Eigen::Index>(in.sensors[ref.sensor].dof);
      b = correlate::model_backbone(jc, target.mode, dof, power, ref.kind,
                                    correlate::IwanComparison::kMatched, lo, hi, a.points);
    } else {
      b.clipped = true;
    }
    if (b.clipped) {
      const double reached = b.amplitude.size() > 0 ? b.amplitude.maxCoeff() : 0.0;
      label += " (clipped)";
      say(stderr,
          "compare: {}: the model's curve stops at amplitude {:.4g} of the measured {:.4g} to "
          "{:.4g} (no static solution past its largest load, or its mode leaves the sensor "
          "still); drawn clipped\n",
          a.models[i], reached, lo, hi);
    }
    c.models.push_back({label, b.amplitude, b.frequency_hz, b.damping_ratio});
  }
  const fs::path csv = fs::path(a.out).replace_extension(".csv");
  if (!fs::path(a.out).parent_path().empty()) fs::create_directories(fs::path(a.out).parent_path());
  campaign::plot_backbone_comparison(c, a.out, csv);
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
                  "channel whose backbones are drawn (repeatable; default: each file's reference "
                  "channel of the band)");
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
