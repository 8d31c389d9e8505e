// `jointlab qsma MODEL --mode R [--points N] [--qmin Q] [--qmax Q] --out FILE`: Quasi-Static
// Modal Analysis of elastic mode R of a model file, as CSV
// force_amplitude,modal_amplitude,frequency_hz,damping_ratio,max_slip,ringdown_frequency_hz,
// ringdown_damping_ratio,harmonic_damping_ratio.
#include <memory>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
#include "jointlab/core/error.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/qsma.h"
#include "jointlab/model/qsma_output.h"

namespace jointlab::apps {
namespace {

struct QsmaArgs {
  std::string model;
  std::string out;
  int mode = 0;
  model::QsmaOptions options;
};

void run_qsma(const QsmaArgs& args) {
  if (const std::string e = args.options.error(); !e.empty()) {
    throw InputError(fmt::format("qsma: {}", e));
  }
  const model::Model m = model::read_model(args.model);
  if (m.iwan_count() == 0) {
    throw InputError(where(args.model, 0, "the model has no Iwan joint; QSMA needs one"));
  }
  // Only the modes up to R: sparse shift-invert on models of more than 100 DOFs.
  model::ModesOptions modes;
  modes.elastic_count = args.mode;
  const model::JointCondensation condensed(m, modes);
  model::QsmaSummary summary;
  const auto curve = model::qsma(condensed, args.mode, args.options, &summary);
  if (curve.empty()) throw InputError(fmt::format("qsma: {}", summary.message));
  model::write_qsma_csv(args.out, curve);
  if (summary.termination == model::QsmaTermination::kLimitLoad) {
    say(stderr, "jointlab qsma: {}\n", summary.message);
  }
}

}  // namespace

void add_qsma_command(CLI::App& app) {
  auto args = std::make_shared<QsmaArgs>();
  CLI::App* cmd = app.add_subcommand(
      "qsma",
      "Quasi-Static Modal Analysis of elastic mode R (numbered as in 'modes'): frequency and\n"
      "damping versus amplitude from static solutions K u + F_J(u) = alpha M phi_R.\n"
      "Writes CSV force_amplitude,modal_amplitude,frequency_hz,damping_ratio,max_slip,\n"
      "ringdown_frequency_hz,ringdown_damping_ratio,harmonic_damping_ratio with amplitude\n"
      "increasing (secant values, what a ring-down shows, what a steady state shows).\n"
      "Without --qmin/--qmax the curve runs from microslip to full macroslip of the joints\n"
      "carrying the mode's slip or to the largest load the joints carry (then on stderr).");
  cmd->add_option("MODEL", args->model, "model file (TOML)")->required();
  cmd->add_option("--mode", args->mode, "elastic mode, from 1")->required()->check(positive());
  cmd->add_option("--points", args->options.points, "number of points (default 50)")
      ->check(in_range(2, 100000));
  cmd->add_option("--qmin", args->options.q_min, "first modal amplitude q")->check(positive());
  cmd->add_option("--qmax", args->options.q_max, "last modal amplitude q")->check(positive());
  cmd->add_option("--out", args->out, "output CSV file")->required();
  cmd->callback([args] { run_qsma(*args); });
}

}  // namespace jointlab::apps
