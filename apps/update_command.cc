// `jointlab update-linear` and `jointlab update-iwan`: model updating against the output of
// `jointlab process` or, for update-iwan, backbone tables (docs/update-linear.md,
// docs/update-iwan.md; update-iwan's measured side is read by campaign/iwan_inputs.h, shared
// with `compare` and the Python module). Argument parsing only:
// reading measured data (data/ readers, correlate/measured_data.h), the updates (linear_update.h,
// iwan_update.h) and the tables written (correlate/update_tables.h, written atomically;
// model/model_file_writer.h) are library code.
#include <algorithm>
#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <CLI/CLI.hpp>

#include "jointlab/apps/commands.h"
#include "jointlab/apps/print.h"
#include "jointlab/campaign/backbone_comparison.h"
#include "jointlab/campaign/figures.h"
#include "jointlab/campaign/iwan_fit.h"
#include "jointlab/campaign/iwan_inputs.h"
#include "jointlab/campaign/iwan_targets.h"
#include "jointlab/campaign/update_figures.h"
#include "jointlab/core/error.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/correlate/update_tables.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/model/iwan.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/model_file_writer.h"

namespace jointlab::apps {
namespace {

namespace fs = std::filesystem;

struct LinearArgs {
  std::string model, measured, modes_table, sensors, out, rule = "least-squares";
  std::vector<std::string> sets, bounds, holds;
  std::vector<double> bound_factors;
  correlate::LinearUpdateOptions options;
};

// --bound NAME=LO:HI, absolute stiffness bounds of one set (0 < LO < HI, both finite).
correlate::ParameterBound parse_bound(const std::string& spec) {
  const size_t eq = spec.rfind('='), colon = spec.rfind(':');
  if (eq == std::string::npos || colon == std::string::npos || colon < eq) {
    throw InputError(fmt::format("--bound {}: expected NAME=LO:HI (stiffness values)", spec));
  }
  correlate::ParameterBound b;
  b.name = spec.substr(0, eq);
  for (const auto& [text, value] : {std::pair{spec.substr(eq + 1, colon - eq - 1), &b.lower},
                                    std::pair{spec.substr(colon + 1), &b.upper}}) {
    if (std::string why = finite_number(text, *value); !why.empty())
      throw InputError(fmt::format("--bound {}: {}", spec, why));
  }
  if (!(b.lower > 0 && b.lower < b.upper)) {
    throw InputError(fmt::format("--bound {}: need 0 < LO < HI (stiffness values)", spec));
  }
  return b;
}

// --hold NAME[=VALUE]: the set held at VALUE (default: the model's) instead of fitted.
correlate::ParameterHold parse_hold(const std::string& spec) {
  const size_t eq = spec.rfind('=');
  correlate::ParameterHold h{spec.substr(0, eq), 0};
  if (eq != std::string::npos) {
    if (std::string why = finite_number(spec.substr(eq + 1), h.value); !why.empty())
      throw InputError(fmt::format("--hold {}: {}", spec, why));
    if (!(h.value > 0))
      throw InputError(fmt::format("--hold {}: the value must be a stiffness > 0", spec));
  }
  if (h.name.empty()) throw InputError(fmt::format("--hold {}: expected NAME[=VALUE]", spec));
  return h;
}

void make_out_dir(const std::string& out) {
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec || !fs::is_directory(out)) {
    throw InputError(fmt::format("{}: cannot create the output directory", out));
  }
}

void run_update_linear(const LinearArgs& a) {
  correlate::LinearUpdateOptions options = a.options;
  for (const std::string& b : a.bounds) options.bounds.push_back(parse_bound(b));
  for (const std::string& h : a.holds) options.holds.push_back(parse_hold(h));
  if (a.bound_factors.size() == 2) {
    if (!(a.bound_factors[0] > 0 && a.bound_factors[0] < 1 && a.bound_factors[1] > 1)) {
      throw InputError(fmt::format("--bound-factors {}:{}: need 0 < LO < 1 < HI",
                                   a.bound_factors[0], a.bound_factors[1]));
    }
    options.lower_factor = a.bound_factors[0];
    options.upper_factor = a.bound_factors[1];
  }
  if (a.rule == "smallest") {
    options.rule = correlate::LinearRule::kSmallest;
    if (options.smallest_set.empty()) {
      throw InputError("update-linear: --rule smallest needs --minimize NAME (the set minimised)");
    }
    if (!(options.tolerance > 0)) options.tolerance = 0.01;  // the paper's 1 %
  }
  if (const std::string e = options.error(); !e.empty()) {
    throw InputError(fmt::format("update-linear: {}", e));
  }
  if (a.measured.empty() == a.modes_table.empty()) {
    throw InputError("update-linear: give either --measured DIR or --modes-table FILE");
  }
  const model::Model m = model::read_model(a.model);
  const std::vector<correlate::Sensor> sensors =
      correlate::sensors_of(data::read_sensors_file(a.sensors), m);
  const correlate::MeasuredModes measured =
      a.modes_table.empty()
          ? correlate::measured_modes(data::read_process_run(a.measured), sensors, nullptr,
                                      options.frequency_std)
          : correlate::measured_modes(
                data::read_modes_table(a.modes_table, correlate::channels_of(sensors)), sensors);
  // Progress on stderr: a fit of the example beam takes 10-50 s.
  options.progress = [](int iteration, double cost, double largest) {
    say(stderr, "update-linear: iteration {}, cost {:.4g}, largest frequency error {:.3g} %\n",
        iteration, cost, 100 * largest);
  };
  correlate::LinearUpdateSummary summary;
  const Eigen::VectorXd theta =
      correlate::update_linear(m, a.sets, sensors, measured, options, &summary);
  if (const std::string why = correlate::linear_refusal(
          summary, options, a.measured.empty() ? a.modes_table : a.measured);
      !why.empty()) {
    // Where undecided pairs stopped it, for the user to judge.
    if (summary.status == correlate::LinearUpdateStatus::kAmbiguous)
      say(stdout, "{}", summary.report());
    throw InputError("update-linear: " + why);
  }
  const model::Model updated = correlate::StiffnessSets(m, a.sets).apply(theta);
  make_out_dir(a.out);
  const fs::path out(a.out);
  model::write_model_file(out / "model.toml", updated);
  data::write_file_atomically(out / "parameters.csv", correlate::linear_parameters_csv(summary));
  data::write_file_atomically(out / "history.csv", correlate::linear_history_csv(summary));
  data::write_file_atomically(out / "modes.csv", correlate::linear_modes_csv(summary));
  data::write_file_atomically(out / "mac.csv", correlate::mac_matrix_csv(summary));
  data::write_file_atomically(out / "sweeps.csv", correlate::linear_sweeps_csv(summary));
  campaign::write_linear_figures(summary, out);
  // The report carries every warning once.
  say(stdout, "{}", summary.report());
}

struct IwanArgs : campaign::IwanInputArgs {
  std::string out, set, optimizer = "global-local", compare = "matched";
  std::string linear_damping = "hold";
  std::vector<double> pareto;
  std::vector<double> fs_range, gamma_range{0.05, 2.0}, chi_range{-0.95, 0.0},
      beta_range{0.01, 100.0};
  correlate::IwanUpdateOptions options;
};

// The LO:HI options given (a default shown in --help is the default box's own).
campaign::IwanRanges ranges_of(const IwanArgs& a) {
  const auto range = [](const std::vector<double>& r) {
    return r.size() == 2 ? campaign::IwanRange{{r[0], r[1]}} : std::nullopt;
  };
  return {range(a.fs_range), range(a.gamma_range), range(a.chi_range), range(a.beta_range)};
}

void check_iwan_args(const IwanArgs& a) {
  ranges_of(a).check();
  if (a.set.find('.') != std::string::npos && !a.set.starts_with("iwan.")) {
    throw InputError(fmt::format(
        "--set {}: update-iwan updates an Iwan set (iwan.<name> or <name>); springs are "
        "updated by update-linear",
        a.set));
  }
}

// The fit and its files, whatever the measured data came from (the measured linear modes, when
// known, give the Pareto front's per-mode errors).
void fit_and_write(const IwanArgs& a, const model::Model& m, const campaign::IwanInputs& in) {
  const std::string& data_name = in.data_name;
  correlate::IwanUpdateOptions o = a.options;
  o.amplitude = in.amplitude;
  o.optimizer = a.optimizer == "paper"       ? correlate::IwanOptimizer::kPaper
                : a.optimizer == "paper-log" ? correlate::IwanOptimizer::kPaperLog
                                             : correlate::IwanOptimizer::kGlobalLocal;
  o.comparison = a.compare == "secant" ? correlate::IwanComparison::kSecant
                                       : correlate::IwanComparison::kMatched;
  o.fit_linear_damping = a.linear_damping == "fit";
  // A model whose mode frequencies already match the measured linear ones (update-linear's
  // result) is said to be so, rather than sent to update-linear again.
  o.linear_part_updated = campaign::linear_part_matches(m, in.targets);
  // Long fits say how they go: every 250 evaluations, the best cost so far, on stderr.
  o.progress = campaign::progress_every(250, [](int evaluations, double best) {
    say(stderr, "update-iwan: {} QSMA evaluations, best cost {:.6g}\n", evaluations, best);
  });
  correlate::IwanObjective objective(m, a.set, in.sensors, in.targets, o);
  if (in.measured) objective.set_linear_modes(*in.measured, 0.6);  // every paired mode's error
  // The fit `run` makes (beta held first, freed when the data reach macroslip).
  const correlate::IwanUpdateSummary summary =
      campaign::checked_fit_iwan(objective, o, ranges_of(a), "update-iwan", data_name, nullptr);
  std::vector<correlate::ParetoPoint> front;
  if (!a.pareto.empty()) {
    o.bounds = ranges_of(a).bounds(objective.initial());
    front = correlate::pareto_front(objective, a.pareto, o);
  }
  const model::IwanParameters best = summary.best;
  make_out_dir(a.out);
  model::write_model_file(fs::path(a.out) / "model.toml",
                          objective.apply(best, summary.modal_ratio));
  data::write_file_atomically(fs::path(a.out) / "parameters.csv",
                              correlate::iwan_parameters_csv(summary));
  data::write_file_atomically(fs::path(a.out) / "history.csv",
                              correlate::iwan_history_csv(summary));
  if (!front.empty())
    data::write_file_atomically(fs::path(a.out) / "pareto.csv", correlate::pareto_csv(front));
  // backbones.png (one figure per mode: backbones_<k>.png past the first): the measured
  // backbones with the model at the start and at the result.
  const auto start = objective.model_curves(summary.start, summary.modal_ratio_start);
  const auto result = objective.model_curves(best, summary.modal_ratio);
  for (size_t k = 0; k < objective.targets().size(); ++k) {
    const correlate::IwanTarget& t = objective.targets()[k];
    campaign::BackboneComparison c;
    c.title = fmt::format("mode {}: measured and model (update-iwan)", t.mode);
    c.amplitude_label = campaign::amplitude_axis_label(in.modal, in.amplitude);
    c.measured = t.curves;
    for (const auto& [label, curve] :
         {std::pair{"model at the start", &start[k]}, std::pair{"model updated", &result[k]}}) {
      c.models.push_back({label, curve->amplitude, curve->frequency_hz, curve->damping_ratio});
    }
    const std::string name = k == 0 ? "backbones" : fmt::format("backbones_{}", k + 1);
    campaign::plot_backbone_comparison(c, fs::path(a.out) / (name + ".png"), {});
  }
  say(stdout, "{}",
      campaign::update_iwan_report(summary, m, objective.apply(best, summary.modal_ratio), a.set,
                                   in, front));
}

void run_update_iwan(const IwanArgs& a) {
  check_iwan_args(a);
  const model::Model m = model::read_model(a.model);
  const campaign::IwanInputs in = campaign::read_iwan_inputs(m, a, "update-iwan");
  if (!in.slip_screen.empty())
    say(stdout, "slip screen (points where other modes slip the joints):\n{}", in.slip_screen);
  fit_and_write(a, m, in);
}

// A LO:HI option of two finite numbers (each refused on its own when it is not one).
void range_option(CLI::App* cmd, const std::string& name, std::vector<double>& v,
                  const std::string& help) {
  cmd->add_option(name, v, help)->delimiter(':')->expected(2)->check(finite());
}

}  // namespace

void add_update_commands(CLI::App& app) {
  auto la = std::make_shared<LinearArgs>();
  CLI::App* lin = app.add_subcommand(
      "update-linear",
      "Updates named joint stiffness sets (spring.<name>, iwan.<name> at Kt) so the model's\n"
      "linear frequencies match the measured ones (the paper's first step).\n"
      "Pairing: at the start each test mode pairs with the model mode of highest MAC at the\n"
      "sensors within the frequency window (modes invisible at the sensors never pair; modes\n"
      "alike at the sensors are told apart by frequency, else the command stops and says\n"
      "which); then every pair is followed by its full shape as the stiffness moves, and\n"
      "checked again at the result, where two neighbouring modes the sensors cannot tell\n"
      "apart are also fitted with their partners exchanged: the data decide, or the command\n"
      "stops and says the pairs cannot be decided (give such modes at two sensors that see\n"
      "them apart). A set the frequencies do not see (FLAT) is held.\n"
      "Before any fit the shapes are checked: shapes without phase (magnitudes) and one or\n"
      "two channels whose signs read the model reversed (reversed, more modes match a model\n"
      "mode at MAC >= 0.9) are refused, saying which; so is a fit whose misfit (beyond the\n"
      "noise) such a reversal fits away (docs/update-linear.md).\n"
      "Reads DIR/summary.json of 'jointlab process' (or --modes-table). Writes into OUTDIR:\n"
      "  model.toml (+ matrices)  the updated model\n"
      "  parameters.csv           name,initial,final,relative_std,... (1 sigma; where the\n"
      "                           frequencies scatter more than --frequency-std gives, widened\n"
      "                           by the reduced chi-square and by Student's t over the degrees\n"
      "                           of freedom left: none with 2 or fewer)\n"
      "  modes.csv                measured,frequency_hz,model_mode,model_frequency_hz,error,mac\n"
      "                           (error a fraction; empty cells: unpaired; an empty mac: a\n"
      "                           shape at fewer than two sensors, which a MAC cannot read)\n"
      "  history.csv/.png         objective and every stiffness per iteration (Figure 2)\n"
      "  sweeps.csv/.png          one-at-a-time sweeps, modes followed by shape (Figure 3)\n"
      "  mac_start.png, mac.png   MAC at the start and at the result, pairs framed (Figure 4)\n"
      "  mac.csv                  the MAC matrix at the result (measured x model modes)\n"
      "Progress on stderr, the report (with every warning once) on stdout.\n"
      "Example: jointlab update-linear beam/model.toml --measured processed --sensors\n"
      "  sensors.csv --set iwan.rivet --set spring.rz --out linear");
  lin->add_option("MODEL", la->model, "model file (TOML)")->required();
  lin->add_option("--measured", la->measured, "output directory of 'jointlab process'");
  lin->add_option("--modes-table", la->modes_table,
                  "measured modes as a table: mode,frequency_hz[,<channel>...] (instead of "
                  "--measured)");
  lin->add_option("--sensors", la->sensors, "sensors file: channel,dof[,sign]")->required();
  lin->add_option("--set", la->sets, "element name to update (repeat for more)")->required();
  lin->add_option("--out", la->out, "output directory")->required();
  lin->add_option("--rule", la->rule,
                  "least-squares (default) or smallest: the paper's rule, the smallest "
                  "--minimize set with every paired frequency error within --tolerance")
      ->check(CLI::IsMember({"least-squares", "smallest"}));
  lin->add_option("--minimize", la->options.smallest_set,
                  "the set the smallest rule minimises (e.g. spring.kx)");
  lin->add_option("--tolerance", la->options.tolerance,
                  "largest frequency error as a fraction: the smallest rule's bound (default "
                  "0.01); with least-squares, flat sets are lowered to the smallest value "
                  "within it (default 0: off)");
  lin->add_option("--bound", la->bounds,
                  "NAME=LO:HI: absolute stiffness bounds of one set (repeatable)");
  range_option(lin, "--bound-factors", la->bound_factors,
               "bounds of every other set as factors of its start LO:HI (default 1e-3:1e3)");
  lin->add_option("--mac-threshold", la->options.mac_threshold,
                  "smallest MAC of a mode pair (default 0.6)");
  lin->add_option("--frequency-window", la->options.frequency_window,
                  "pairs also need |f_model / f_test - 1| within this (default 0.5; 0: off)");
  lin->add_option("--hold", la->holds,
                  "NAME[=VALUE]: hold a set at VALUE (default: the model's) instead of "
                  "fitting it (repeatable)");
  lin->add_option("--frequency-std", la->options.frequency_std,
                  "relative uncertainty of the measured frequencies, for the standard "
                  "deviations and the reduced chi-square (default 0.001)");
  lin->add_flag("--trust-signs", la->options.trust_signs,
                "fit the shapes with the sensors file's signs even when one or two channels "
                "read the model reversed");
  lin->add_option("--alias-mac", la->options.alias_mac,
                  "warn when two model modes have an auto-MAC at the sensors above this "
                  "(default 0.9)");
  lin->callback([la] { run_update_linear(*la); });

  auto ia = std::make_shared<IwanArgs>();
  CLI::App* iw = app.add_subcommand(
      "update-iwan",
      "Updates the four parameters of one Iwan set (Fs, Kt = gamma Ks, chi, beta) so QSMA\n"
      "backbones match the measured ones (and, with --linear-damping fit, the model's own\n"
      "modal damping ratio). Reads DIR/summary.json and the band CSVs of 'jointlab process',\n"
      "or --backbone tables; writes OUTDIR/model.toml, parameters.csv, history.csv,\n"
      "backbones.png (backbones_<k>.png for each further mode; pareto.csv with --pareto),\n"
      "and prints a report (progress on stderr).");
  iw->add_option("MODEL", ia->model, "model file (TOML), linear stiffness already updated")
      ->required();
  iw->add_option("--measured", ia->measured,
                 "output directory of 'jointlab process' (or give --backbone tables)");
  iw->add_option("--sensors", ia->sensors, "sensors file: channel,dof[,sign] (with --measured)");
  iw->add_option("--backbone", ia->backbones,
                 "a measured backbone table, one curve per file: CSV amplitude,frequency_hz,"
                 "damping_ratio[,frequency_std_hz,damping_std], rows in any order (repeatable; "
                 "instead of --measured and --sensors)");
  iw->add_option("--amplitude", ia->amplitude,
                 "what the --backbone amplitude is: modal (default: the QSMA modal amplitude q "
                 "of mode R), or displacement, velocity or acceleration at --dof")
      ->check(CLI::IsMember({"modal", "displacement", "velocity", "acceleration"}));
  iw->add_option("--dof", ia->dof,
                 "model DOF (NODE:COMP label or 0-based index) the --backbone amplitude was "
                 "measured at");
  iw->add_option("--linear-damping", ia->linear_damping,
                 "hold (default): keep the model's [damping] modal_ratio (none: 0); fit: "
                 "identify it with the Iwan parameters, in [0, --linear-damping-max]")
      ->check(CLI::IsMember({"hold", "fit"}));
  iw->add_option("--linear-damping-max", ia->options.linear_damping_max,
                 "upper bound of a fitted modal_ratio (default 0.05)")
      ->check(CLI::Range(1e-9, 0.999));
  iw->add_option("--set", ia->set, "Iwan set to update (iwan.<name> or <name>)")->required();
  iw->add_option("--mode", ia->modes,
                 "elastic model mode R, with measured band BAND (default: the band paired by "
                 "MAC); repeat for more")
      ->required();
  iw->add_option("--stepped-sine", ia->stepped_sine,
                 "output directory of 'jointlab stepped-sine': its backbones are fitted with the "
                 "hammer data, each against the steady-state pair (repeatable)");
  iw->add_option("--stepped-sine-channel", ia->stepped_sine_channel,
                 "sensor channel the stepped-sine response was measured at (default: the only "
                 "sensor)");
  iw->add_option("--stepped-sine-mode", ia->stepped_sine_mode,
                 "elastic model mode of the stepped-sine backbones (default: the first --mode)")
      ->check(CLI::PositiveNumber);
  iw->add_option("--channel", ia->channels,
                 "channel whose backbones are used (repeatable; default: one channel for every "
                 "file, the files' reference channel of the band, or where they differ the "
                 "one with a backbone in the most files, said in the report)");
  iw->add_option("--optimizer", ia->optimizer, "paper, paper-log or global-local (default)")
      ->check(CLI::IsMember({"paper", "paper-log", "global-local"}));
  iw->add_option(
        "--compare", ia->compare,
        "matched (default): each backbone against the model pair its test shows (ring-down "
        "or steady state); secant: against QSMA's secant pair, as the paper")
      ->check(CLI::IsMember({"matched", "secant"}));
  iw->add_option("--gamma", ia->options.fixed_gamma, "hold Kt / Ks at this value")
      ->check(positive());
  iw->add_option_function<double>(
        "--beta", [ia](const double& beta) { ia->options.fixed_beta = beta; },
        "hold beta at this value (0: no macroslip weight)")
      ->check(non_negative());
  iw->add_option("--pareto", ia->pareto, "gamma values of a Pareto front, comma separated")
      ->delimiter(',');
  iw->add_option("--evaluations", ia->options.max_evaluations,
                 "budget of QSMA evaluations of each fit (default 1500); when beta is freed for a "
                 "second fit, that fit has its own, so the total can reach twice it");
  iw->add_option("--seed", ia->options.seed, "random seed (default 1)");
  iw->add_option("--threads", ia->options.threads,
                 "threads evaluating samples (default 0: every core); the result does not "
                 "depend on it")
      ->check(in_range(0, 1024));
  range_option(iw, "--fs-range", ia->fs_range, "Fs bounds LO:HI [N] (default start/30:start*30)");
  range_option(iw, "--gamma-range", ia->gamma_range, "Kt/Ks bounds LO:HI (default 0.05:2)");
  range_option(iw, "--chi-range", ia->chi_range,
               "chi bounds LO:HI, any chi > -1 (default -0.95:0, a Coulomb interface's)");
  range_option(iw, "--beta-range", ia->beta_range, "beta bounds LO:HI (default 0.01:100)");
  iw->add_option("--out", ia->out, "output directory")->required();
  iw->callback([ia] { run_update_iwan(*ia); });
}

}  // namespace jointlab::apps
