// update_iwan() and compare(): the Iwan update and the model curves over the measured ones.
#include "binding.h"

#include <cmath>

#include <fmt/format.h>

#include "jointlab/campaign/backbone_comparison.h"
#include "jointlab/campaign/iwan_fit.h"
#include "jointlab/campaign/iwan_inputs.h"
#include "jointlab/campaign/model_comparison.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/update_tables.h"

namespace jointlab::python {
namespace {

// The measured side of update_iwan() and compare() as the command's options name it (absent:
// the option not given).
campaign::IwanInputArgs iwan_input_args(const std::vector<std::string>& modes,
                                        const std::vector<std::string>& backbones,
                                        const std::optional<std::string>& amplitude,
                                        const std::optional<std::string>& dof,
                                        const std::optional<std::string>& measured,
                                        const std::optional<std::string>& sensors,
                                        const std::vector<std::string>& channels) {
  campaign::IwanInputArgs a;
  a.modes = modes;
  a.backbones = backbones;
  a.amplitude = amplitude.value_or("");
  a.dof = dof.value_or("");
  a.measured = measured.value_or("");
  a.sensors = sensors.value_or("");
  a.channels = channels;
  return a;
}

// update-iwan's --stepped-sine, --stepped-sine-channel, --stepped-sine-mode and --pareto (none:
// empty, "", 0: the command's defaults).
struct SteppedSineArgs {
  std::vector<std::string> folders;  // `jointlab stepped-sine` output folders
  std::string channel;               // the sensor channel of their response
  int mode = 0;                      // their elastic model mode (0: the first --mode)
  std::vector<double> pareto;        // gamma values of a Pareto front
};

// What the report says of the scatter between the hits' curves, where the model does not
// describe the data within their noise (misfit; else None, as with fewer than two curves of one
// mode): their count, the share of the chi-square each curve's own offset explains and
// the share their own offsets and slopes over a common curve explain, a curve lying apart from
// the others (None: none), and whether the sigmas rest on that scatter (one cluster per hit,
// Student's t), as the report's "the sigmas allow for it".
py::object iwan_scatter(const correlate::IwanUpdateSummary& summary) {
  if (!summary.evidence || summary.evidence->curves < 2) return py::none();
  const correlate::MisfitEvidence& e = *summary.evidence;
  py::dict d;
  d["curves"] = e.curves;
  d["offsets_share"] = e.between_curves_share;
  d["shapes_share"] = e.between_hits_share;
  d["apart"] = e.apart_curve.empty() ? py::object(py::none()) : py::object(py::str(e.apart_curve));
  d["sigmas_from_scatter"] = summary.scatter_explains_misfit();
  return d;
}

// One dict per row of parameters.csv (Fs, Kt, chi, beta, gamma = Kt / Ks when known), from
// the rows the file is written from; modal_ratio always, with its absolute std.
py::dict iwan_parameters(const correlate::IwanUpdateSummary& summary) {
  const std::vector<correlate::IwanParameterRow> rows = correlate::iwan_parameter_rows(summary);
  py::dict parameters;
  bool z_identifiable = false;
  for (const correlate::IwanParameterRow& r : rows) {
    if (r.name == "modal_ratio") {
      z_identifiable = r.identifiable;
      continue;
    }
    // gamma is Kt over the reference stiffness: Kt's hold, sigma, bound and note.
    const int k = r.name == "Fs" ? 0 : r.name == "chi" ? 2 : r.name == "beta" ? 3 : 1;
    py::dict d;
    d["initial"] = r.initial;
    d["final"] = r.final;
    d["relative_std"] = r.relative_std > 0 ? py::object(py::float_(r.relative_std)) : py::none();
    // Held as asked, as parameters.csv's held; beta held by the fit itself is not fitted either.
    d["held"] = r.held;
    d["fitted"] = !summary.held[static_cast<size_t>(k)];
    d["note"] = r.note;
    d["at_bound"] = r.at_bound;
    d["identifiable"] = r.identifiable;
    // The linear part's systematic effect (the report's "linear part:" line): the relative change
    // of the parameter per relative error of mode R's linear frequency from the rest of the
    // model, and the error of that frequency its sigma holds to; None where unknown.
    const double rate = summary.linear_part_sensitivity(k),
                 holds = summary.linear_part_tolerance(k);
    d["linear_part_sensitivity"] = rate != 0 && !r.held ? py::object(py::float_(rate)) : py::none();
    d["linear_part_tolerance"] = holds > 0 ? py::object(py::float_(holds)) : py::none();
    parameters[py::str(r.name)] = d;
  }
  py::dict z;
  z["initial"] = summary.modal_ratio_start;
  z["final"] = summary.modal_ratio;
  z["std"] = summary.modal_ratio_fitted && summary.modal_ratio_std > 0
                 ? py::object(py::float_(summary.modal_ratio_std))
                 : py::object(py::none());
  z["fitted"] = summary.modal_ratio_fitted;
  z["note"] = summary.parameter_note(4);  // as parameters.csv's modal_ratio row
  z["identifiable"] = z_identifiable;
  parameters["modal_ratio"] = z;
  return parameters;
}

// The Pareto front (pareto=): a dict per gamma, and the command's lines in the report.
py::list iwan_pareto(const std::vector<correlate::ParetoPoint>& front) {
  py::list pareto;
  for (const correlate::ParetoPoint& p : front) {
    py::dict d;
    d["gamma"] = p.gamma;
    d["Fs"] = p.params.Fs;
    d["Kt"] = p.params.Kt;
    d["chi"] = p.params.chi;
    d["beta"] = p.params.beta;
    d["linear_error"] = p.linear_error;
    d["backbone_cost"] = p.backbone_cost;
    d["dominated"] = p.dominated;
    py::list errors;  // per measured linear mode; None: unpaired
    for (const std::optional<double>& e : p.mode_errors)
      errors.append(e ? py::object(py::float_(*e)) : py::object(py::none()));
    d["mode_errors"] = errors;
    pareto.append(d);
  }
  return pareto;
}

// Every evaluation the model could evaluate, as history.csv: its number, cost and the best so
// far, and whether beta was held (the file's stage, "beta held" or "beta free").
py::dict iwan_history(const correlate::IwanUpdateSummary& summary) {
  std::vector<const correlate::IwanHistoryEntry*> kept;
  for (const correlate::IwanHistoryEntry& h : summary.history)
    if (std::isfinite(h.cost)) kept.push_back(&h);
  const auto n = static_cast<Eigen::Index>(kept.size());
  Eigen::VectorXd evaluation(n), objective(n), best(n);
  py::array_t<bool> beta_held(n);
  auto held = beta_held.mutable_unchecked<1>();
  for (Eigen::Index i = 0; i < n; ++i) {
    const correlate::IwanHistoryEntry& h = *kept[static_cast<size_t>(i)];
    evaluation(i) = h.evaluation;
    objective(i) = h.cost;
    best(i) = h.best;
    held(i) = h.beta_held;
  }
  py::dict history;
  history["evaluation"] = to_numpy(std::move(evaluation));
  history["objective"] = to_numpy(std::move(objective));
  history["best"] = to_numpy(std::move(best));
  history["beta_held"] = beta_held;
  return history;
}

// update-iwan (contract.md): backbone tables (data/backbone_table.h) or a `process` folder with
// its sensors, read as the command reads them (campaign/iwan_inputs.h); the options and defaults
// of the command; the fit `run` and the command make (campaign::checked_fit_iwan).
py::dict update_iwan(
    const std::string& model_path, const std::string& set, const std::vector<std::string>& modes,
    const std::vector<std::string>& backbones, const std::optional<std::string>& amplitude,
    const std::optional<std::string>& dof, const std::string& linear_damping,
    const std::optional<std::pair<double, double>>& fs_range,
    const std::pair<double, double>& gamma_range, const std::pair<double, double>& chi_range,
    const std::pair<double, double>& beta_range, int evaluations, unsigned seed,
    const std::optional<std::string>& out, const py::object& progress,
    const std::optional<std::string>& measured, const std::optional<std::string>& sensors,
    const std::vector<std::string>& channels, const correlate::IwanUpdateOptions& asked,
    const SteppedSineArgs& sine) {
  if (set.find('.') != std::string::npos && !set.starts_with("iwan."))
    throw InputError(
        fmt::format("--set {}: update-iwan updates an Iwan set (iwan.<name> or "
                    "<name>); springs are updated by update-linear",
                    set));
  if (linear_damping != "hold" && linear_damping != "fit")
    throw InputError(fmt::format("--linear-damping {}: expected hold or fit", linear_damping));
  if (amplitude && *amplitude != "modal" && *amplitude != "displacement" &&
      *amplitude != "velocity" && *amplitude != "acceleration")
    throw InputError(fmt::format(
        "--amplitude {}: expected modal, displacement, velocity or acceleration", *amplitude));
  const campaign::IwanRanges ranges{fs_range, gamma_range, chi_range, beta_range};
  ranges.check();
  correlate::IwanUpdateSummary summary;
  campaign::IwanInputs in;
  std::vector<std::string> shape_warnings;
  std::vector<correlate::ParetoPoint> front;
  std::string text;  // the command's report
  {
    py::gil_scoped_release release;
    const model::Model m = model::read_model(model_path);
    campaign::IwanInputArgs a =
        iwan_input_args(modes, backbones, amplitude, dof, measured, sensors, channels);
    a.model = model_path;
    a.stepped_sine = sine.folders;
    a.stepped_sine_channel = sine.channel;
    a.stepped_sine_mode = sine.mode;
    in = campaign::read_iwan_inputs(m, a, "update-iwan");
    if (!in.slip_screen.empty())
      report(progress,
             "slip screen (points where other modes slip the joints):\n" + in.slip_screen);
    correlate::IwanUpdateOptions o = asked;  // gamma, beta, linear_damping_max, threads
    o.amplitude = in.amplitude;
    o.fit_linear_damping = linear_damping == "fit";
    // As the command: a model whose modes match the measured linear frequencies is said to be
    // linearly updated, not sent to update-linear.
    o.linear_part_updated = campaign::linear_part_matches(m, in.targets);
    o.max_evaluations = evaluations;
    o.seed = seed;
    // Ctrl-C is checked at every evaluation the library reports (a 400-evaluation fit of the
    // example campaign ran its 8 s to the end; the global search reports in batches of 50), and a
    // line goes to `progress` at the first evaluation at or past each multiple of 250: the local
    // solves' count steps over some (a 423-evaluation fit of 400 said nothing). A second fit (beta
    // freed) counts from 0 again.
    InterruptCheck interrupted;
    o.progress = campaign::progress_every(
        250,
        [&progress](int n, double best) {
          report(progress,
                 fmt::format("update-iwan: {} QSMA evaluations, best cost {:.6g}", n, best));
        },
        [&interrupted] { interrupted(); });
    correlate::IwanObjective objective(m, set, in.sensors, in.targets, o);
    if (in.measured) objective.set_linear_modes(*in.measured, 0.6);
    summary =
        campaign::checked_fit_iwan(objective, o, ranges, "update-iwan", in.data_name, nullptr);
    if (!sine.pareto.empty()) {  // as the command: in the search box, after the fit
      o.bounds = ranges.bounds(objective.initial());
      front = correlate::pareto_front(objective, sine.pareto, o);
    }
    const model::Model updated = objective.apply(summary.best, summary.modal_ratio);
    text = campaign::update_iwan_report(summary, m, updated, set, in, front, "--set {}",
                                        &shape_warnings);
    if (out) write_model(*out, updated);
  }
  py::dict result;
  result["parameters"] = iwan_parameters(summary);
  // A cost the model could not evaluate (+inf) is None, never a number.
  const auto cost = [](double c) -> py::object {
    if (std::isfinite(c)) return py::cast(c);
    return py::none();
  };
  result["cost"] = cost(summary.final_cost);
  result["initial_cost"] = cost(summary.initial_cost);
  result["evaluations"] = summary.evaluations;
  // False: the search stopped before its local solve met its tolerance, and no sigma is stated.
  result["converged"] = summary.status == correlate::IwanUpdateStatus::kConverged;
  // True: Z fitted and the joint no better than a constant backbone (Fs, chi, beta not
  // identified; Kt and modal_ratio are the result).
  result["no_slip"] = summary.no_slip_seen();
  std::vector<std::string> warnings = summary.at_bounds;
  warnings.insert(warnings.end(), shape_warnings.begin(), shape_warnings.end());
  result["warnings"] = warnings;
  result["reduced_chi2"] = summary.reduced_chi2;
  // The residuals' effective number of independent points behind the sigmas (None: unknown).
  result["effective_points"] = summary.effective_points > 0
                                   ? py::object(py::float_(summary.effective_points))
                                   : py::object(py::none());
  result["noise_correlation"] = summary.effective_points > 0
                                    ? py::object(py::float_(summary.noise_correlation))
                                    : py::object(py::none());
  result["sigma_degrees_of_freedom"] =
      summary.effective_points > 0 ? py::object(py::float_(summary.sigma_degrees_of_freedom))
                                   : py::object(py::none());
  // The noise note's other evidence: the largest share of the chi-square one third of the points
  // (by amplitude) holds, about 1/3 for noise (None: unknown); and whether the reduced
  // chi-square lies significantly above 1 (the report's "does not describe the data" WARNING).
  result["amplitude_share"] = summary.amplitude_share > 0
                                  ? py::object(py::float_(summary.amplitude_share))
                                  : py::object(py::none());
  result["misfit"] = summary.misfit();
  result["scatter_between_hits"] = iwan_scatter(summary);
  result["pareto"] = iwan_pareto(front);
  result["history"] = iwan_history(summary);
  result["report"] = text;
  return result;
}

// `jointlab compare` without the figure unless `out` names one: the measured curves and each
// model's QSMA backbone over their range (campaign/model_comparison.h).
py::dict compare(const OneOrMany<PathArg>& model_args, const py::object& mode,
                 const OneOrMany<PathArg>& backbone_args,
                 const std::optional<std::string>& amplitude, const std::optional<std::string>& dof,
                 const std::optional<PathArg>& measured_arg,
                 const std::optional<PathArg>& sensors_arg,
                 const OneOrMany<std::string>& channels_arg,
                 const OneOrMany<std::string>& labels_arg, const Integer& points_arg,
                 const std::optional<PathArg>& out_arg) {
  const std::vector<std::string> models = text(model_args.items),
                                 backbones = text(backbone_args.items);
  const std::vector<std::string>&channels = channels_arg.items, &labels = labels_arg.items;
  const std::optional<std::string> measured = text(measured_arg), sensors = text(sensors_arg),
                                   out = text(out_arg);
  const int points = static_cast<int>(in_range(points_arg, "--points", 2, 100000));
  if (out) {
    const std::string ext = std::filesystem::path(*out).extension().string();
    if (ext != ".png" && ext != ".svg" && ext != ".pdf")
      throw InputError(fmt::format("--out {}: the figure must end in .png, .svg or .pdf", *out));
  }
  std::vector<std::string> modes;
  if (py::isinstance<py::str>(mode))
    modes = {mode.cast<std::string>()};
  else if (is_integer(mode))
    modes = {integer_text(mode)};
  else
    throw InputError("mode: expected an int or 'R:BAND'");
  const campaign::IwanInputArgs a =
      iwan_input_args(modes, backbones, amplitude, dof, measured, sensors, channels);
  // The figure's folder, made before the curves are computed: one that cannot be made is the
  // user's mistake, said as such (it was a RuntimeError after the QSMA curves).
  if (out) {
    const std::filesystem::path folder = std::filesystem::path(*out).parent_path();
    std::error_code ec;
    if (!folder.empty()) std::filesystem::create_directories(folder, ec);
    if (ec || !(folder.empty() || std::filesystem::is_directory(folder)))
      throw InputError(fmt::format("{}: cannot create the output directory", folder.string()));
  }
  campaign::ModelComparison c;
  {
    py::gil_scoped_release release;
    c = campaign::compare_models(models, labels, a, points);
    if (out) {
      const std::filesystem::path figure(*out);
      campaign::plot_backbone_comparison(c.figure, figure,
                                         std::filesystem::path(figure).replace_extension(".csv"));
    }
  }
  for (const std::string& note : c.notes)
    if (PyErr_WarnEx(PyExc_UserWarning, note.c_str(), 1) != 0) throw py::error_already_set();
  py::list measured_curves;
  for (correlate::MeasuredBackbone& b : c.figure.measured) {
    py::dict d;
    d["source"] = b.source;
    d["amplitude"] = to_numpy(std::move(b.amplitude));
    d["frequency_hz"] = to_numpy(std::move(b.frequency_hz));
    d["damping_ratio"] = to_numpy(std::move(b.damping_ratio));
    measured_curves.append(d);
  }
  py::list model_curves;
  for (size_t i = 0; i < c.figure.models.size(); ++i) {
    campaign::ModelCurve& m = c.figure.models[i];
    py::dict d;
    d["label"] = m.label;
    d["amplitude"] = to_numpy(std::move(m.amplitude));
    d["frequency_hz"] = to_numpy(std::move(m.frequency_hz));
    d["damping_ratio"] = to_numpy(std::move(m.damping));
    d["clipped"] = static_cast<bool>(c.clipped[i]);
    model_curves.append(d);
  }
  py::dict result;
  result["title"] = c.figure.title;
  result["amplitude_label"] = c.figure.amplitude_label;
  result["measured"] = measured_curves;
  result["models"] = model_curves;
  result["slip_screen"] = c.slip_screen;
  return result;
}

// update_iwan with `mode` as Python gives it: an int, an 'R:BAND' string or a list of either.
py::dict update_iwan_call(
    const PathArg& model, const std::string& set, const py::object& mode,
    const OneOrMany<PathArg>& backbones, const std::optional<std::string>& amplitude,
    const std::optional<std::string>& dof, const std::string& linear_damping,
    const std::optional<std::pair<double, double>>& fs_range,
    const std::pair<double, double>& gamma_range, const std::pair<double, double>& chi_range,
    const std::pair<double, double>& beta_range, const Integer& evaluations_arg,
    const Integer& seed_arg, const std::optional<PathArg>& out, const py::object& progress,
    const std::optional<PathArg>& measured, const std::optional<PathArg>& sensors,
    const OneOrMany<std::string>& channels, std::optional<double> gamma, std::optional<double> beta,
    double linear_damping_max, const Integer& threads, const std::string& optimizer,
    const std::string& compare, const OneOrMany<PathArg>& stepped_sine,
    const std::optional<std::string>& stepped_sine_channel, const Integer& stepped_sine_mode_arg,
    const OneOrMany<double>& pareto_arg) {
  check_progress(progress);
  const std::vector<double>& pareto = pareto_arg.items;
  // --seed, a UINT as the command reads it (-1 was pybind11's "incompatible function arguments").
  const auto seed = static_cast<unsigned>(in_range(seed_arg, "--seed", 0, 4294967295LL));
  const int stepped_sine_mode = as_int(stepped_sine_mode_arg, "--stepped-sine-mode", 0);
  if (stepped_sine_mode < 0)
    throw InputError(
        fmt::format("--stepped-sine-mode {}: elastic modes count from 1 (0: the first mode)",
                    stepped_sine_mode));
  for (const double g : pareto) {
    if (!(std::isfinite(g) && g > 0))
      throw InputError(fmt::format("--pareto {}: gamma values must be finite and > 0", g));
  }
  const SteppedSineArgs sine{text(stepped_sine.items), stepped_sine_channel.value_or(""),
                             stepped_sine_mode, pareto};
  // --gamma, --beta, --linear-damping-max and --threads, checked as the command checks them.
  correlate::IwanUpdateOptions asked;
  if (gamma) {
    if (!(std::isfinite(*gamma) && *gamma > 0))
      throw InputError(fmt::format("--gamma {}: must be a finite number > 0", *gamma));
    asked.fixed_gamma = *gamma;
  }
  if (beta) {
    if (!(std::isfinite(*beta) && *beta >= 0))
      throw InputError(
          fmt::format("--beta {}: must be a finite number >= 0 (0: no macroslip weight)", *beta));
    asked.fixed_beta = *beta;
  }
  if (!(linear_damping_max >= 1e-9 && linear_damping_max <= 0.999))
    throw InputError(
        fmt::format("--linear-damping-max {}: must be in [1e-09, 0.999]", linear_damping_max));
  asked.linear_damping_max = linear_damping_max;
  asked.threads = static_cast<int>(threads_option(threads));
  // --optimizer and --compare.
  if (optimizer != "paper" && optimizer != "paper-log" && optimizer != "global-local")
    throw InputError(
        fmt::format("--optimizer {}: expected paper, paper-log or global-local", optimizer));
  asked.optimizer = optimizer == "paper"       ? correlate::IwanOptimizer::kPaper
                    : optimizer == "paper-log" ? correlate::IwanOptimizer::kPaperLog
                                               : correlate::IwanOptimizer::kGlobalLocal;
  if (compare != "matched" && compare != "secant")
    throw InputError(fmt::format("--compare {}: expected matched or secant", compare));
  asked.comparison = compare == "secant" ? correlate::IwanComparison::kSecant
                                         : correlate::IwanComparison::kMatched;
  std::vector<std::string> modes;
  const auto one = [&](const py::handle& h) {
    if (py::isinstance<py::str>(h))
      modes.push_back(h.cast<std::string>());
    else if (is_integer(h))
      modes.push_back(integer_text(h));
    else
      throw InputError("mode: expected an int, 'R:BAND' or a list of them");
  };
  // A list, a tuple or a numpy array of modes (np.array([1, 2]) was read as one integer).
  if (py::isinstance<py::list>(mode) || py::isinstance<py::tuple>(mode) ||
      (py::isinstance<py::array>(mode) && py::reinterpret_borrow<py::array>(mode).ndim() > 0)) {
    for (const py::handle h : mode) one(h);
  } else {
    one(mode);
  }
  if (modes.empty()) throw InputError("mode: give at least one mode");
  return update_iwan(text(model), set, modes, text(backbones.items), amplitude, dof, linear_damping,
                     fs_range, gamma_range, chi_range, beta_range,
                     as_int(evaluations_arg, "--evaluations", 1), seed, text(out), progress,
                     text(measured), text(sensors), channels.items, asked, sine);
}

}  // namespace

void bind_iwan(py::module_& m) {
  m.def("update_iwan", &update_iwan_call, py::arg("model"), py::arg("set"), py::arg("mode"),
        py::arg("backbones") = std::vector<std::string>{}, py::arg("amplitude") = py::none(),
        py::arg("dof") = py::none(), py::arg("linear_damping") = "hold",
        py::arg("fs_range") = py::none(),
        py::arg("gamma_range") = std::pair<double, double>{0.05, 2.0},
        py::arg("chi_range") = std::pair<double, double>{-0.95, 0.0},
        py::arg("beta_range") = std::pair<double, double>{0.01, 100.0},
        py::arg("evaluations") = 1500, py::arg("seed") = 1u, py::arg("out") = py::none(),
        py::arg("progress") = py::none(), py::arg("measured") = py::none(),
        py::arg("sensors") = py::none(), py::arg("channels") = std::vector<std::string>{},
        py::arg("gamma") = py::none(), py::arg("beta") = py::none(),
        py::arg("linear_damping_max") = 0.05, py::arg("threads") = 0,
        py::arg("optimizer") = "global-local", py::arg("compare") = "matched",
        py::arg("stepped_sine") = std::vector<std::string>{},
        py::arg("stepped_sine_channel") = py::none(), py::arg("stepped_sine_mode") = 0,
        py::arg("pareto") = std::vector<double>{},
        R"(Updates one Iwan set to measured backbones (`jointlab update-iwan`): backbone tables, or
a `process` output folder with its sensors file.

model           model file (TOML), linear stiffness already updated
set             the Iwan set ('iwan.rivet' or 'rivet')
mode            the elastic model mode: with tables, the one every table belongs to (from 1);
                with `measured`, one or a list of R or 'R:BAND' (--mode, repeatable)
backbones       CSV tables amplitude,frequency_hz,damping_ratio[,frequency_std_hz,damping_std]
amplitude       tables: 'modal' (QSMA modal amplitude q, the default) or 'displacement' [m],
                'velocity' [m/s], 'acceleration' [m/s^2] at model DOF `dof` ('NODE:COMP' or an
                index)
measured, sensors, channels
                instead of tables: a `jointlab process` output folder, its sensors file
                (channel,dof) and, optionally, the channels to use (--measured, --sensors,
                --channel); the folder records its own amplitude quantity
linear_damping  'hold' (the model's [damping] modal_ratio) or 'fit' (identified with the joint)
linear_damping_max
                upper bound of a fitted modal_ratio (default 0.05, --linear-damping-max)
gamma, beta     hold Kt / Ks, or beta (0: no macroslip weight), at this value (--gamma, --beta)
fs_range, gamma_range, chi_range, beta_range, evaluations, seed, threads: as the command's
                options (threads: 0 every core; the result does not depend on it)
optimizer       'global-local' (default), 'paper' or 'paper-log' (--optimizer)
compare         'matched' (default: each backbone against the model pair its test shows) or
                'secant' (QSMA's secant pair, as the paper) (--compare)
stepped_sine, stepped_sine_channel, stepped_sine_mode
                `jointlab stepped-sine` output folders fitted with the hammer data, each
                against the steady-state pair; the sensor channel of their response (default:
                the only sensor) and their model mode (0: the first mode) (--stepped-sine,
                --stepped-sine-channel, --stepped-sine-mode)
pareto          gamma values of a Pareto front (--pareto): 'pareto' in the result, one dict per
                gamma (gamma, Fs, Kt, chi, beta, linear_error, backbone_cost, dominated,
                mode_errors: per measured linear mode, None where unpaired), and the
                command's lines in the report
out             write the updated model file here (its folder created), or None

Returns a dict: 'parameters' (Fs [N], Kt [N/m], chi, beta, and gamma = Kt / Ks as
parameters.csv's row -> initial, final, relative_std or None, held (as asked), fitted (False
where held, as asked or by the fit), at_bound, note and identifiable (as parameters.csv's),
linear_part_sensitivity (the relative change per relative error of mode R's linear frequency
from the rest of the model: the report's 'linear part:' line; -16 moves Kt by -1.6 % per 0.1 %)
and linear_part_tolerance (the relative error of that frequency its sigma holds to), None where
unknown; modal_ratio -> initial, final, std (absolute), fitted, note, identifiable), 'cost', 'initial_cost'
(None where the model cannot be evaluated), 'evaluations', 'converged' (False: the search
stopped short of a minimum and no sigma is stated), 'no_slip' (True where, the structure's own
damping fitted, a constant backbone fits as well: Fs, chi and beta are not identified),
'warnings' (parameters at a bound; a band whose shape does not look like its mode),
'reduced_chi2', 'misfit' (True: the reduced chi-square lies significantly above 1, the report's
WARNING that the model does not describe the data within their stated noise),
'effective_points' (the residuals' effective number of independent points; None where unknown),
'noise_correlation' (their AR(1) coefficient, corrected for what the fit absorbs),
'amplitude_share' (the largest share of the chi-square one third of the points, by amplitude,
holds: about 1/3 for noise; None where unknown), 'sigma_degrees_of_freedom' (the sigmas'
Student's t: effective points less the parameters fitted; 2 or fewer state no sigma),
'pareto' (with `pareto`: one dict per gamma, else []), 'history' (as history.csv: arrays
evaluation, objective, best so far, and beta_held for its stage; evaluations the model could
not evaluate left out), 'report'.

progress        callable taking one line, or None: the slip screen with several modes, and a
                line at the first evaluation at or past each multiple of 250. Ctrl-C ends the
                call with KeyboardInterrupt within an evaluation of the local solves, and
                after the batch of 50 samples of the global search (up to 0.4 s on the
                example campaign on two idle cores, 1.7 s on busy ones).

    r = jointlab.update_iwan("model.toml", "iwan.j", 1, ["bb.csv"], linear_damping="fit")
    r["parameters"]["chi"]["final"], r["parameters"]["modal_ratio"]["final"]
    r = jointlab.update_iwan("model.toml", "rivet", 1, measured="processed",
                             sensors="sensors.csv")
)");

  m.def("compare", &compare, py::arg("models"), py::arg("mode"),
        py::arg("backbones") = std::vector<std::string>{}, py::arg("amplitude") = py::none(),
        py::arg("dof") = py::none(), py::arg("measured") = py::none(),
        py::arg("sensors") = py::none(), py::arg("channels") = std::vector<std::string>{},
        py::arg("labels") = std::vector<std::string>{}, py::arg("points") = 100,
        py::arg("out") = py::none(),
        R"(The QSMA backbones of one or more models over measured ones (`jointlab compare`): the
data of the paper's Figures 5-7, and the figure itself where `out` names one.

models          model files (TOML) sharing their DOFs
mode            the elastic model mode (from 1); with `measured` also 'R:BAND'
backbones, amplitude, dof, measured, sensors, channels
                the measured side, as update_iwan() reads it
labels          a legend name per model (default: the file names)
points          points per model curve (default 100)
out             draw the figure here (.png, .svg, .pdf) with the model curves' CSV beside it

Returns a dict: 'title', 'amplitude_label', 'measured' (one dict per curve: source, amplitude,
frequency_hz, damping_ratio), 'models' (one dict per model: label, amplitude, frequency_hz,
damping_ratio, clipped: the curve stops short of the measured range, also a UserWarning saying
where), 'slip_screen'.

    c = jointlab.compare(["start.toml", "updated.toml"], 1, ["bb.csv"], labels=["start", "fit"])
    c["models"][1]["damping_ratio"]
)");
}

}  // namespace jointlab::python
