// update_linear(): the linear update as `jointlab update-linear` (docs/python.md).
#include "binding.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/correlate/update_tables.h"

namespace jointlab::python {
namespace {

// The status of update_linear() as a word for Python.
std::string linear_status_name(correlate::LinearUpdateStatus status) {
  switch (status) {
    case correlate::LinearUpdateStatus::kConverged:
      return "converged";
    case correlate::LinearUpdateStatus::kIterationLimit:
      return "iteration_limit";
    case correlate::LinearUpdateStatus::kTooFewPairs:
      return "too_few_pairs";
    case correlate::LinearUpdateStatus::kFailed:
      return "failed";
    case correlate::LinearUpdateStatus::kAmbiguous:
      return "ambiguous";
    case correlate::LinearUpdateStatus::kShapesRefused:
      return "shapes_refused";
    case correlate::LinearUpdateStatus::kPairsUnconfirmed:
      return "pairs_unconfirmed";
  }
  return "failed";
}

// --hold NAME[=VALUE], read as the command reads it: the whole VALUE a finite stiffness > 0
// ("1e7xyz" was held at 1e7).
correlate::ParameterHold hold_option(const std::string& h) {
  const size_t eq = h.rfind('=');
  correlate::ParameterHold ph{h.substr(0, eq), 0};
  if (eq != std::string::npos) {
    const std::string text = h.substr(eq + 1);
    char* end = nullptr;
    ph.value = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || std::isspace(text.front()) != 0 ||
        !std::isfinite(ph.value))
      throw InputError(fmt::format("--hold {}: {} is not a finite number", h, text));
    if (!(ph.value > 0))
      throw InputError(fmt::format("--hold {}: the value must be a stiffness > 0", h));
  }
  if (ph.name.empty()) throw InputError(fmt::format("--hold {}: expected NAME[=VALUE]", h));
  return ph;
}

// update_linear()'s keywords as the command's options name them.
struct LinearArgs {
  std::string rule;                                         // --rule
  std::optional<std::string> minimize;                      // --minimize
  double tolerance = 0;                                     // --tolerance
  double frequency_window = 0;                              // --frequency-window
  double mac_threshold = 0;                                 // --mac-threshold
  double frequency_std = 0;                                 // --frequency-std
  std::vector<std::string> hold;                            // --hold NAME[=VALUE]
  bool trust_signs = false;                                 // --trust-signs
  std::map<std::string, std::pair<double, double>> bounds;  // --bound NAME=LO:HI
  std::optional<std::pair<double, double>> bound_factors;   // --bound-factors LO:HI
  double alias_mac = 0;                                     // --alias-mac
};

// The options of the update, checked as the command checks them (progress and interrupt are
// the caller's).
correlate::LinearUpdateOptions linear_options(const LinearArgs& a) {
  correlate::LinearUpdateOptions o;
  o.alias_mac = a.alias_mac;
  // --bound NAME=LO:HI and --bound-factors LO:HI, checked as the command checks them.
  for (const auto& [name, range] : a.bounds) {
    const auto [lo, hi] = range;
    if (!(std::isfinite(lo) && std::isfinite(hi) && lo > 0 && lo < hi))
      throw InputError(
          fmt::format("--bound {}={}:{}: need 0 < LO < HI (stiffness values)", name, lo, hi));
    o.bounds.push_back({name, lo, hi});
  }
  if (a.bound_factors) {
    const auto [lo, hi] = *a.bound_factors;
    if (!(lo > 0 && lo < 1 && hi > 1 && std::isfinite(hi)))
      throw InputError(fmt::format("--bound-factors {}:{}: need 0 < LO < 1 < HI", lo, hi));
    o.lower_factor = lo;
    o.upper_factor = hi;
  }
  o.trust_signs = a.trust_signs;
  o.frequency_window = a.frequency_window;
  o.mac_threshold = a.mac_threshold;
  o.frequency_std = a.frequency_std;
  o.tolerance = a.tolerance;
  if (a.rule == "smallest") {
    o.rule = correlate::LinearRule::kSmallest;
    if (!a.minimize) throw InputError("update-linear: --rule smallest needs --minimize NAME");
    o.smallest_set = *a.minimize;
    if (!(o.tolerance > 0)) o.tolerance = 0.01;  // the paper's 1 %, as the command
  } else if (a.rule != "least-squares") {
    throw InputError(fmt::format("--rule {}: expected least-squares or smallest", a.rule));
  }
  for (const std::string& h : a.hold) o.holds.push_back(hold_option(h));
  if (const std::string e = o.error(); !e.empty())
    throw InputError(fmt::format("update-linear: {}", e));
  return o;
}

// One set's entry of 'parameters': its report's values, and its one-at-a-time sweep around the
// result as sweeps.csv's rows of the set: NaN where no pair is followed (rms_error) or the mode
// is unpaired or not followed by its shape (errors, a row per point, a column per measured mode
// in `modes` order).
py::dict linear_parameter(const correlate::ParameterReport& p, Eigen::Index measured_count) {
  py::dict d;
  d["initial"] = p.start;
  d["final"] = p.value;
  d["relative_std"] = p.relative_std ? py::object(py::float_(*p.relative_std)) : py::none();
  // Where relative_std is a third of the chi-square profile's 3-sigma distance (wider): the
  // local slope's, which the report names as understating it (None: relative_std is it).
  d["slope_std"] = p.slope_std ? py::object(py::float_(*p.slope_std)) : py::none();
  d["sensitivity"] = p.sensitivity;
  d["flat"] = p.flat;
  d["held"] = p.held;
  d["held_by_user"] = p.held_by_user;  // held by `hold`, not for being flat
  d["at_bound"] = p.at_bound;
  // As parameters.csv's identifiable: neither flat nor acting together with another set.
  d["identifiable"] = p.identifiable();
  d["acts_with"] = p.acts_with;
  // +1 / -1: the frequencies bound it from below / above only (not identifiable either).
  d["one_sided"] = p.one_sided;
  // As parameters.csv's column: the smallest value within the tolerance (None: not lowered).
  d["smallest_within_tolerance"] = p.smallest_within_tolerance > 0
                                       ? py::object(py::float_(p.smallest_within_tolerance))
                                       : py::object(py::none());
  d["lower"] = p.lower;  // its bounds [N/m or N m/rad]
  d["upper"] = p.upper;
  const auto n = static_cast<Eigen::Index>(p.sweep_factor.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd factor(n), rms(n);
  Eigen::MatrixXd errors = Eigen::MatrixXd::Constant(n, measured_count, nan);
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto kk = static_cast<size_t>(k);
    factor(k) = p.sweep_factor[kk];
    rms(k) = p.sweep_rms[kk].value_or(nan);
    for (Eigen::Index i = 0; i < measured_count; ++i) {
      const auto c = static_cast<size_t>(i);
      if (kk < p.sweep_errors.size() && c < p.sweep_errors[kk].size() && p.sweep_errors[kk][c])
        errors(k, i) = *p.sweep_errors[kk][c];
    }
  }
  py::dict sweep;
  sweep["factor"] = to_numpy(Eigen::VectorXd(factor));
  sweep["stiffness"] = to_numpy(Eigen::VectorXd(factor * p.value));
  sweep["rms_error"] = to_numpy(std::move(rms));
  sweep["errors"] = to_numpy(std::move(errors));
  d["sweep"] = sweep;
  return d;
}

// The objective and every set's stiffness after each iteration (the first: the start), as
// history.csv's columns.
py::dict linear_history(const correlate::LinearUpdateSummary& s) {
  py::dict history;
  const auto n = static_cast<Eigen::Index>(s.history.size());
  Eigen::VectorXd iteration(n), objective(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    iteration(i) = static_cast<double>(i);
    objective(i) = s.history[static_cast<size_t>(i)];
  }
  history["iteration"] = to_numpy(std::move(iteration));
  history["objective"] = to_numpy(std::move(objective));
  for (size_t k = 0; k < s.parameters.size(); ++k) {
    Eigen::VectorXd theta = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
    for (Eigen::Index i = 0; i < n && static_cast<size_t>(i) < s.theta_history.size(); ++i)
      if (static_cast<Eigen::Index>(k) < s.theta_history[static_cast<size_t>(i)].size())
        theta(i) = s.theta_history[static_cast<size_t>(i)](static_cast<Eigen::Index>(k));
    history[py::str(s.parameters[k].name)] = to_numpy(std::move(theta));
  }
  return history;
}

// Sets acting together, as the report's warning names them: the combination determined.
py::list linear_collinear(const correlate::LinearUpdateSummary& s) {
  py::list collinear;
  for (const correlate::CollinearSets& c : s.collinear) {
    py::dict d;
    std::vector<std::string> names;
    for (const int k : c.sets) names.push_back(s.parameters[static_cast<size_t>(k)].name);
    d["sets"] = names;
    d["determined"] = c.determined;
    d["correlation"] = c.correlation;
    const bool pair = c.sets.size() == 2;
    d["weight"] = pair ? py::object(py::float_(c.weight)) : py::object(py::none());
    d["value"] = pair ? py::object(py::float_(c.value)) : py::object(py::none());
    d["relative_std"] =
        pair && c.relative_std ? py::object(py::float_(*c.relative_std)) : py::object(py::none());
    collinear.append(d);
  }
  return collinear;
}

// The measured modes and their pairs at the result, as modes.csv; `spread`: per measured mode
// (by its id), the relative std its files' spread shows (> 0 only).
py::list linear_pairs(const correlate::LinearEvaluation& e,
                      const std::map<std::string, double>& spread) {
  py::list modes;
  for (Eigen::Index i = 0; i < e.measured_frequency_hz.size(); ++i) {
    const int j = e.pairing.model_for(static_cast<int>(i));
    py::dict d;
    // Its own number (the table's mode column, the band), as modes.csv writes it.
    const std::string id = e.measured_id(i);
    const bool number =
        !id.empty() && id.size() < 10 &&
        std::all_of(id.begin(), id.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
    d["measured"] = number ? py::object(py::int_(std::stoi(id))) : py::object(py::str(id));
    d["frequency_hz"] = e.measured_frequency_hz(i);
    d["model_mode"] = j < 0 ? py::object(py::none()) : py::object(py::int_(j + 1));
    d["model_frequency_hz"] =
        j < 0 ? py::object(py::none()) : py::object(py::float_(e.model_frequency_hz(i)));
    d["error"] = j < 0 ? py::object(py::none()) : py::object(py::float_(e.residuals(i)));
    const std::optional<double> mac = e.pair_mac(i);
    d["mac"] = mac ? py::object(py::float_(*mac)) : py::object(py::none());
    // The relative one-sigma uncertainty of its frequency that its files' spread shows (their
    // linear frequencies disagree beyond their stated uncertainties: the report's WARNING on the
    // band); None where they agree, or one file or a table gives it.
    const auto sd = spread.find(id);
    d["frequency_spread_std"] =
        sd == spread.end() ? py::object(py::none()) : py::object(py::float_(sd->second));
    modes.append(d);
  }
  return modes;
}

// The MAC at the result, as mac.csv: a row per measured mode ('modes' order), a column per
// model mode from 1 (those up to 1.5 times the highest measured frequency, and past every pair).
py::array_t<double> linear_mac(const correlate::LinearUpdateSummary& s) {
  const Eigen::MatrixXd& mac = s.final.mac;
  const Eigen::Index cols = correlate::mac_columns(s);
  py::array_t<double> mac_array({mac.rows(), cols});
  auto cell = mac_array.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < mac.rows(); ++i)
    for (Eigen::Index j = 0; j < cols; ++j) cell(i, j) = mac(i, j);
  return mac_array;
}

// update_linear()'s result: the summary as Python values.
py::dict linear_result(const correlate::LinearUpdateSummary& s,
                       const std::map<std::string, double>& spread) {
  py::dict parameters;
  for (const correlate::ParameterReport& p : s.parameters)
    parameters[py::str(p.name)] = linear_parameter(p, s.final.measured_frequency_hz.size());
  const py::list modes = linear_pairs(s.final, spread);
  py::dict result;
  result["parameters"] = parameters;
  result["modes"] = modes;
  result["history"] = linear_history(s);
  result["rule"] = s.rule;
  result["converged"] = s.status == correlate::LinearUpdateStatus::kConverged;
  result["status"] = linear_status_name(s.status);
  // kPairsUnconfirmed: the line naming the pairs, why and what to do ("" otherwise), and the
  // measured modes (as 'modes' numbers them) whose pairs the shapes do not confirm.
  result["unconfirmed"] = s.unconfirmed;
  py::list unconfirmed_modes;
  for (const int i : s.unconfirmed_modes)
    unconfirmed_modes.append(modes[static_cast<size_t>(i)]["measured"]);
  result["unconfirmed_modes"] = unconfirmed_modes;
  result["collinear"] = linear_collinear(s);
  // The standard deviations rest on the residuals' scatter (reduced_chi2 > 1: scaled by its root
  // and widened by Student's t), not on the stated frequency uncertainty.
  result["sigma_from_scatter"] = s.sigma_from_scatter;
  // None where no degree of freedom is left (the summary's 0 there is no chi-square).
  result["degrees_of_freedom"] = s.degrees_of_freedom;
  result["reduced_chi2"] =
      s.degrees_of_freedom > 0 ? py::object(py::float_(s.reduced_chi2)) : py::object(py::none());
  // The fits from different starts behind the result (1, or 1 + the restarts tried where the
  // fit from the start left scatter beyond the noise) and the report's line on them ("": none).
  result["starts"] = s.starts;
  result["restarts"] = s.restarts;
  result["warnings"] = s.warnings;
  result["mac"] = linear_mac(s);
  result["report"] = s.report();
  return result;
}

// update-linear: the same inputs, options and defaults as the command; the result as Python
// values, and the updated model file written when `out` is given.
py::dict update_linear(const PathArg& model_arg, const OneOrMany<std::string>& sets_arg,
                       const PathArg& sensors_arg, const std::optional<PathArg>& measured_arg,
                       const std::optional<PathArg>& modes_table_arg, const std::string& rule,
                       const std::optional<std::string>& minimize, double tolerance,
                       double frequency_window, double mac_threshold, double frequency_std,
                       const OneOrMany<std::string>& hold, const std::optional<PathArg>& out_arg,
                       const py::object& progress, bool trust_signs,
                       const std::map<std::string, std::pair<double, double>>& bounds,
                       const std::optional<std::pair<double, double>>& bound_factors,
                       double alias_mac) {
  check_progress(progress);
  const std::string model_path = text(model_arg), sensors_path = text(sensors_arg);
  const std::optional<std::string> measured = text(measured_arg),
                                   modes_table = text(modes_table_arg), out = text(out_arg);
  const std::vector<std::string>& sets = sets_arg.items;
  if (sets.empty()) throw InputError("update-linear: give at least one set to update (--set)");
  correlate::LinearUpdateOptions o =
      linear_options({rule, minimize, tolerance, frequency_window, mac_threshold, frequency_std,
                      hold.items, trust_signs, bounds, bound_factors, alias_mac});
  if (measured.has_value() == modes_table.has_value())
    throw InputError("update-linear: give either --measured DIR or --modes-table FILE");
  o.progress = [&progress](int iteration, double cost, double largest) {
    report(progress, fmt::format("update-linear: iteration {}, cost {:.4g}, largest frequency "
                                 "error {:.3g} %",
                                 iteration, cost, 100 * largest));
  };
  InterruptCheck interrupted;
  o.interrupt = [&interrupted] { interrupted(); };
  correlate::LinearUpdateSummary s;
  // Per measured mode (by its id), the relative std its files' spread shows (> 0 only).
  std::map<std::string, double> spread;
  {
    py::gil_scoped_release release;
    const model::Model m = model::read_model(model_path);
    const std::vector<correlate::Sensor> sensors =
        correlate::sensors_of(data::read_sensors_file(sensors_path), m);
    const correlate::MeasuredModes meas =
        measured
            ? correlate::measured_modes(data::read_process_run(*measured), sensors, nullptr,
                                        o.frequency_std)
            : correlate::measured_modes(
                  data::read_modes_table(*modes_table, correlate::channels_of(sensors)), sensors);
    for (Eigen::Index i = 0; i < meas.frequency_std.size(); ++i)
      if (meas.frequency_std(i) > 0) spread[meas.id(i)] = meas.frequency_std(i);
    const Eigen::VectorXd theta = correlate::update_linear(m, sets, sensors, meas, o, &s);
    if (const std::string why =
            correlate::linear_refusal(s, o, measured ? *measured : *modes_table);
        !why.empty())
      throw InputError("update-linear: " + why);
    const model::Model updated = correlate::StiffnessSets(m, sets).apply(theta);
    if (out) write_model(*out, updated);
  }
  return linear_result(s, spread);
}

}  // namespace

void bind_linear(py::module_& m) {
  m.def(
      "update_linear", &update_linear, py::arg("model"), py::arg("sets"), py::arg("sensors"),
      py::arg("measured") = py::none(), py::arg("modes_table") = py::none(),
      py::arg("rule") = "least-squares", py::arg("minimize") = py::none(),
      py::arg("tolerance") = 0.0, py::arg("frequency_window") = 0.5, py::arg("mac_threshold") = 0.6,
      py::arg("frequency_std") = 1e-3, py::arg("hold") = std::vector<std::string>{},
      py::arg("out") = py::none(), py::arg("progress") = py::none(), py::arg("trust_signs") = false,
      py::arg("bounds") = std::map<std::string, std::pair<double, double>>{},
      py::arg("bound_factors") = py::none(), py::arg("alias_mac") = 0.9,
      R"(Updates named joint stiffness sets to measured linear frequencies (`jointlab update-linear`).

model          model file (TOML)
sets           element names to update, e.g. ["iwan.rivet", "spring.rz"], or one name
sensors        sensors file (channel,dof[,sign])
measured       a `jointlab process` output folder, or modes_table: mode,frequency_hz[,<channel>...]
rule           'least-squares' (default) or 'smallest' (with minimize=NAME, tolerance default 0.01)
frequency_window, mac_threshold, frequency_std, hold=["NAME[=VALUE]"], alias_mac: as the
               command's options
bounds         {"NAME": (lo, hi)}: absolute stiffness bounds of sets (--bound NAME=LO:HI)
bound_factors  (lo, hi): bounds of every other set as factors of its start (default 1e-3, 1e3)
trust_signs    fit with the sensors file's signs even when one channel reads the model reversed
out            write the updated model file here (its matrices beside it), or None
progress       callable taking one line per optimiser iteration, or None. Ctrl-C ends the
               call with KeyboardInterrupt at the next model solve (0.1 s of checking), in the
               fit, its refits, sweeps and chi-square profile alike

Pairs are made by sensor MAC within the frequency window and followed by full shape (see
docs/update-linear.md). Returns a dict: 'parameters' (name -> initial, final [N/m or N*m/rad],
relative_std (one sigma, relative) or None, slope_std (where relative_std is the chi-square
profile's, wider: the local slope's, which the report says understates it; else None),
sensitivity, flat, held, held_by_user (held by `hold`), at_bound, identifiable, acts_with,
one_sided (+1 / -1: bound by the frequencies from below / above only), smallest_within_tolerance
(None: not lowered), lower, upper (its bounds), sweep (the one-at-a-time sweep, as sweeps.csv:
arrays factor, stiffness, rms_error, errors [point, measured mode]; NaN where no pair was
followed)), 'history' (as history.csv: arrays iteration, objective and each set's stiffness),
'modes' (measured, frequency_hz, model_mode, model_frequency_hz, error
(relative), mac; None where unpaired; frequency_spread_std: the relative one-sigma spread of the
files' linear frequencies where they disagree, the report's WARNING on the band, else None), 'rule',
'converged' (False also where the shapes do not confirm the pairs at the result), 'status'
('converged', 'iteration_limit', 'failed' or 'pairs_unconfirmed'), 'unconfirmed' (the report's
line on pairs the shapes do not confirm, or ''), 'unconfirmed_modes' (their measured modes),
'collinear' (sets acting together: sets, determined, correlation and, for two sets a and b, the
combination theta_a + weight theta_b determined: weight, value, relative_std),
'mac' (the MAC matrix at the result, as mac.csv: a row per measured mode, a column per
model mode from 1), 'degrees_of_freedom' (pairs less fitted sets), 'reduced_chi2' (None where none is left),
'sigma_from_scatter' (True: the sigmas rest on the residuals' scatter, not the stated noise),
'starts' (fits from different starts behind the result), 'restarts' (the report's line on them,
or ''), 'warnings', 'report'. Undecidable pairs, a channel reading the model reversed and shapes without
phase raise InputError saying which.

    r = jointlab.update_linear("model.toml", ["iwan.rivet"], "sensors.csv", measured="processed")
    r["parameters"]["iwan.rivet"]["final"]
)");
}

}  // namespace jointlab::python
