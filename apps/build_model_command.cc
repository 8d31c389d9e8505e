// `jointlab build-model DESCRIPTION --out DIR`: riveted beam description (TOML) → finite-
// element model → Craig–Bampton reduced model directory (M.mtx, K.mtx, dofs.csv, model.toml).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/fe/riveted_beam.h"

namespace jointlab::apps {
namespace {

struct BuildModelArgs {
  std::string description;
  std::string out;
  int modes = -1;
  bool quiet = false;
  bool skip_check = false;
};

void run_build_model(const BuildModelArgs& args) {
  namespace fe = jointlab::model::fe;
  const auto t0 = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  fe::RivetedBeamDescription d = fe::read_riveted_beam_description(args.description);
  if (args.modes >= 0) d.fixed_interface_modes = args.modes;
  fe::BuildOptions options;
  if (!args.quiet)
    options.progress = [&](const std::string& s) { say(stderr, "[{:6.1f} s] {}\n", elapsed(), s); };
  const fe::ReducedModel m = fe::build_reduced_model(d, options);
  if (!m.summary.ok)
    throw InputError(
        fmt::format("{}: the reduction failed: {}", args.description, m.summary.report));
  if (!args.quiet) say(stderr, "[{:6.1f} s] writing {}\n", elapsed(), args.out);
  fe::write_model_directory(args.out, m);
  if (args.quiet) return;
  const Eigen::VectorXd f = fe::reduced_frequencies_hz(m);
  std::string freqs;
  for (int k = 6; k < std::min<int>(16, static_cast<int>(f.size())); ++k)
    freqs += fmt::format(" {:.2f}", f(k));
  say(stderr,
      "[{:6.1f} s] done: {} DOFs reduced to {} ({} boundary + {} modes)\n"
      "  assembly {:.2f} s, reduction {:.2f} s\n"
      "  first elastic frequencies with the joints at their linear stiffness [Hz]:{}\n",
      elapsed(), m.summary.full_dofs, m.stiffness.rows(), m.summary.boundary_dofs, m.summary.modes,
      m.summary.seconds_assembly, m.summary.seconds_reduction, freqs);
  if (args.skip_check) return;
  // The reduction's accuracy: reduced against full elastic frequencies (Ritz values lie above).
  const int n = std::min<int>(10, static_cast<int>(f.size()) - 6);
  const Eigen::VectorXd full = fe::full_elastic_frequencies_hz(d, n);
  std::string errs;
  double worst = 0;
  for (int k = 0; k < n; ++k) {
    const double e = f(6 + k) / full(k) - 1;
    worst = std::max(worst, std::abs(e));
    errs += fmt::format(" {:.3g}", 100 * e);
  }
  say(stderr,
      "[{:6.1f} s] reduction accuracy, first {}, reduced / full - 1 [%]:{}\n"
      "  largest {:.3g} % (raise reduction.fixed_interface_modes or --modes to lower it)\n",
      elapsed(), counted(n, "elastic mode"), errs, 100 * worst);
}

}  // namespace

void add_build_model_command(CLI::App& app) {
  auto args = std::make_shared<BuildModelArgs>();
  CLI::App* cmd = app.add_subcommand(
      "build-model",
      "Build the riveted beam finite-element model from a description file (TOML, SI units;\n"
      "see docs/model-description.md) and reduce it by Hurty/Craig-Bampton. Writes DIR/M.mtx,\n"
      "DIR/K.mtx, DIR/dofs.csv and DIR/model.toml (the model file of 'modes' and 'qsma').");
  cmd->add_option("DESCRIPTION", args->description, "riveted beam description (TOML)")->required();
  cmd->add_option("--out", args->out, "output model directory (created if missing)")->required();
  cmd->add_option("--modes", args->modes,
                  "fixed-interface modes kept (overrides reduction.fixed_interface_modes)")
      ->check(non_negative());
  cmd->add_flag("--quiet", args->quiet, "no progress messages on stderr");
  cmd->add_flag("--skip-check", args->skip_check,
                "do not compare the reduced frequencies with the full model's (saves one sparse "
                "eigen-solve of the full model)");
  cmd->callback([args] { run_build_model(*args); });
}

}  // namespace jointlab::apps
