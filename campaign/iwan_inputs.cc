#include "jointlab/campaign/iwan_inputs.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/campaign/iwan_fit.h"
#include "jointlab/campaign/iwan_targets.h"
#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/core/units.h"
#include "jointlab/correlate/mac.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/sim/simulated_record.h"

namespace jointlab::campaign {
namespace {

IwanInputs table_inputs(const model::Model& m, const IwanInputArgs& a, const std::string& command) {
  if (a.modes.size() != 1 || a.modes.front().find(':') != std::string::npos) {
    throw InputError(command +
                     ": with --backbone give one --mode R (the model mode every table belongs to)");
  }
  if (!a.stepped_sine.empty() || !a.channels.empty() || !a.measured.empty()) {
    throw InputError(command +
                     ": --backbone replaces --measured (with --channel and --stepped-sine)");
  }
  correlate::IwanTarget t;
  try {
    size_t used = 0;
    t.mode = std::stoi(a.modes.front(), &used);
    if (used != a.modes.front().size()) throw std::invalid_argument(a.modes.front());
  } catch (const std::exception&) {
    throw InputError(fmt::format("--mode {}: expected R, an integer from 1", a.modes.front()));
  }
  const model::LinearModes linear = model::linear_modes(m.mass, m.linear_stiffness());
  const int elastic = linear.size() - linear.rigid_count;
  if (t.mode < 1 || t.mode > elastic) {
    throw InputError(fmt::format("--mode {}: model mode {} does not exist: {} has {}",
                                 a.modes.front(), t.mode, a.model,
                                 counted(elastic, "elastic mode")));
  }
  const std::string quantity = a.amplitude.empty() ? "modal" : a.amplitude;
  correlate::AmplitudeQuantity amplitude = correlate::AmplitudeQuantity::kVelocity;
  std::vector<correlate::Sensor> sensors;
  if (quantity == "modal") {
    if (!a.dof.empty()) {
      throw InputError(
          "--dof: a modal amplitude is measured at no DOF (give --amplitude "
          "displacement, velocity or acceleration)");
    }
  } else {
    if (a.dof.empty()) {
      throw InputError(fmt::format(
          "--amplitude {}: give --dof NODE:COMP (or a 0-based index), where it was measured",
          quantity));
    }
    amplitude = correlate::amplitude_quantity(motion_quantity("--amplitude", quantity));
    correlate::Sensor s;
    s.dof = model::resolve_dof(m, a.dof, "--dof");
    s.channel = model::dof_name(m, s.dof);
    sensors.push_back(s);
  }
  // The amplitude column's unit, when given, must measure this quantity (none: modal).
  const std::optional<Quantity> measured =
      quantity == "modal" ? std::nullopt : parse_quantity(quantity);
  correlate::BackboneCurves read = correlate::backbone_curves(
      // One hit given twice would count as two: refused (read_backbone_tables).
      data::read_backbone_tables({a.backbones.begin(), a.backbones.end()}, measured),
      sensors.empty() ? -1 : 0);
  t.curves = std::move(read.curves);
  IwanInputs in;
  for (const std::string& file : a.backbones)
    in.data_name += (in.data_name.empty() ? "" : ", ") + file;
  in.sensors = std::move(sensors);
  in.targets = {std::move(t)};
  in.amplitude = amplitude;
  in.modal = quantity == "modal";
  in.amplitude_note = correlate::amplitude_reading(
      in.targets.front().mode, quantity, a.amplitude.empty(),
      in.sensors.empty() ? std::string() : in.sensors.front().channel, a.dof, read.unitless);
  return in;
}

// The measured column (band) paired with elastic mode `mode` (1-based) by update-linear's rules
// (correlate::pair_by_rules, default PairingRules: MAC >= 0.6, the model frequency within +-50 %
// of the band's, a mode invisible at the sensors never paired by MAC, a band whose shape is read
// at one sensor paired by frequency). A bare MAC argmax over every elastic mode let a high mode
// aliased at a few sensors take the band: a lap beam's 243 Hz band had MAC 0.99998 with mode 2
// (246.6 Hz) and 0.999996 with mode 32 (3797 Hz) at five z sensors, and `--mode 2` was refused.
// Returns -1 when none pairs; `why` then lists each band's frequency and MAC with the mode.
// The measured columns (bands) paired with elastic modes by update-linear's rules; `mac` and
// `model_hz` (elastic modes from 0) are filled for band_column_of's message.
correlate::RulePairing band_pairing(const model::LinearModes& linear,
                                    const std::vector<correlate::Sensor>& sensors,
                                    const correlate::MeasuredModes& measured, Eigen::MatrixXd& mac,
                                    Eigen::VectorXd& model_hz) {
  const int elastic = linear.size() - linear.rigid_count;
  const Eigen::MatrixXd at =
      correlate::shapes_at_sensors(sensors, linear.shapes.rightCols(elastic));
  model_hz.resize(elastic);
  for (int j = 0; j < elastic; ++j) model_hz(j) = linear.frequency_hz(linear.rigid_count + j);
  std::vector<bool> has_shape(static_cast<size_t>(measured.frequency_hz.size()));
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i)
    has_shape[static_cast<size_t>(i)] = (measured.shapes.col(i).array().abs() > 0.0).count() >= 2;
  mac = correlate::mac_matrix(measured.shapes, at);
  return correlate::pair_by_rules(mac, measured.frequency_hz, has_shape, model_hz,
                                  at.colwise().squaredNorm().transpose(),
                                  correlate::PairingRules{});
}

int band_column_of(const model::LinearModes& linear, const std::vector<correlate::Sensor>& sensors,
                   const correlate::MeasuredModes& measured, const std::vector<int>& bands,
                   int mode, std::string& why) {
  Eigen::MatrixXd mac;
  Eigen::VectorXd model_hz;
  const correlate::RulePairing rp = band_pairing(linear, sensors, measured, mac, model_hz);
  const correlate::PairingRules rules;
  for (const correlate::ModePair& p : rp.pairing.pairs) {
    if (p.model == mode - 1) return p.measured;
  }
  std::vector<std::string> seen;
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) {
    seen.push_back(fmt::format("band {} ({:.5g} Hz, MAC {:.3f})", bands[static_cast<size_t>(i)],
                               measured.frequency_hz(i), mac(i, mode - 1)));
  }
  why = fmt::format(
      "model mode {} ({:.5g} Hz) pairs with no measured band (a pair needs MAC >= {:g} at the "
      "sensors and the frequencies within {:g} %, the band not taken by a mode that matches it "
      "better): {}",
      mode, model_hz(mode - 1), rules.mac_threshold, 100 * rules.frequency_window,
      fmt::join(seen, ", "));
  return -1;
}

// What read_iwan_inputs reads a process folder's --modes from.
struct ProcessSide {
  const IwanInputArgs& args;
  const std::vector<correlate::Sensor>& sensors;
  const data::ProcessRun& run;
  const correlate::MeasuredModes& measured;
  const std::vector<int>& bands;  // measured's column -> process band
  const model::LinearModes& linear;
};

// The folder's other bands, each paired with a model mode (band_pairing) that no --mode names,
// as modes the update does not fit: the slip screen reads the other modes' slip in each hit
// from them, as `run` reads it from a campaign's other [[mode]]s. Without them a lone --mode
// kept every point: a beam struck at its end, --mode 3 alone, fitted mode 3's damping that mode
// 1 carried (chi -0.487 +/- 3.5 % against the truth's -0.35) where `run` left every point out.
// A band without a backbone at any channel gives nothing to screen with and is skipped.
std::vector<ModeBackbones> screen_only_modes(const ProcessSide& side,
                                             const std::vector<ModeBackbones>& given,
                                             const std::vector<BandOfMode>& given_bands) {
  Eigen::MatrixXd mac;
  Eigen::VectorXd model_hz;
  const correlate::RulePairing rp =
      band_pairing(side.linear, side.sensors, side.measured, mac, model_hz);
  std::vector<ModeBackbones> out;
  for (const correlate::ModePair& p : rp.pairing.pairs) {
    const int mode = p.model + 1, band = side.bands[static_cast<size_t>(p.measured)];
    if (std::any_of(given.begin(), given.end(),
                    [&](const ModeBackbones& g) { return g.model_mode == mode; }) ||
        std::any_of(given_bands.begin(), given_bands.end(),
                    [&](const BandOfMode& g) { return g.band == band; }))
      continue;
    try {
      ModeBackbones mb = process_run_backbones(side.run, side.sensors, band, {}, ScatterOptions{});
      mb.name = fmt::format("band {} (mode {}, screen only)", band, mode);
      mb.model_mode = mode;
      mb.fitted = false;
      out.push_back(std::move(mb));
    } catch (const InputError&) {
      // No backbone in this band: no other mode's slip to read from it.
    }
  }
  return out;
}

// "4.9 %" or "4.9 to 5.3 %": a share at the two ends of a range, the smaller first.
std::string percent_range(double a, double b) {
  const double lo = 100 * std::min(a, b), hi = 100 * std::max(a, b);
  const auto text = [](double x) {
    return x >= 10 ? fmt::format("{:.0f}", x) : fmt::format("{:.2g}", x);
  };
  const std::string l = text(lo), h = text(hi);
  return l == h ? l + " %" : fmt::format("{} to {} %", l, h);
}

// Per mode, the channel its hits were read at where their reference channels differ, and each
// hit the scatter summary flags and iwan_targets leaves out of the fit (a hit left out is named,
// not only counted in "8 curves").
std::vector<std::string> curve_notes(const std::vector<ModeBackbones>& modes) {
  std::vector<std::string> notes;
  for (const ModeBackbones& mb : modes) {
    if (!mb.channel_note.empty()) notes.push_back(mb.name + ", " + mb.channel_note);
    if (!mb.scatter.options.exclude_outliers) continue;
    for (const HitDeviation& h : mb.scatter.hits) {
      if (!h.outlier) continue;
      notes.push_back(fmt::format(
          "{}: {} is left out of the fit: its curve lies off the other hits' ({}; the scatter "
          "summary flags a robust |z| over {:g})",
          mb.name, h.id, h.reason, mb.scatter.options.outlier_threshold));
    }
  }
  return notes;
}

// A --mode R or R:BAND as given (band 0: none given).
struct ModeSpec {
  int mode = 0;
  int band = 0;
};

ModeSpec mode_spec(const std::string& spec) {
  ModeSpec out;
  const size_t colon = spec.find(':');
  try {
    size_t used = 0;
    out.mode = std::stoi(spec.substr(0, colon), &used);
    if (used != spec.substr(0, colon).size()) throw std::invalid_argument(spec);
    if (colon != std::string::npos) {
      out.band = std::stoi(spec.substr(colon + 1), &used);
      if (used != spec.size() - colon - 1) throw std::invalid_argument(spec);
    }
  } catch (const std::exception&) {
    throw InputError(fmt::format("--mode {}: expected R or R:BAND (integers from 1)", spec));
  }
  if (out.mode < 1 || (colon != std::string::npos && out.band < 1)) {
    throw InputError(fmt::format("--mode {}: mode and band count from 1", spec));
  }
  return out;
}

// The backbones of one --mode: its band (given, or the one MAC-paired with the model mode), read
// as `run` reads them; `band_of_mode` gains the band where it has linear data.
ModeBackbones mode_backbones(const std::string& spec, const ProcessSide& p,
                             std::vector<BandOfMode>& band_of_mode) {
  const ModeSpec ms = mode_spec(spec);
  const int elastic = p.linear.size() - p.linear.rigid_count;
  if (ms.mode > elastic) {
    throw InputError(fmt::format("--mode {}: model mode {} does not exist: {} has {} (1 to {})",
                                 spec, ms.mode, p.args.model, counted(elastic, "elastic mode"),
                                 elastic));
  }
  if (ms.band > 0 && std::none_of(p.run.bands.begin(), p.run.bands.end(),
                                  [&](const data::ProcessBand& b) { return b.band == ms.band; })) {
    std::set<int> numbers;
    for (const data::ProcessBand& b : p.run.bands) numbers.insert(b.band);
    std::string have;
    for (int b : numbers) have += (have.empty() ? "" : ", ") + std::to_string(b);
    throw InputError(fmt::format("--mode {}: {} has no band {} (bands: {})", spec, p.args.measured,
                                 ms.band, have.empty() ? "none" : have));
  }
  int col = -1, band = ms.band;
  if (band == 0) {
    std::string why;
    col = band_column_of(p.linear, p.sensors, p.measured, p.bands, ms.mode, why);
    if (col < 0) {
      throw InputError(fmt::format(
          "--mode {}: {}; if one of these bands is this mode's, give R:BAND", spec, why));
    }
    band = p.bands[static_cast<size_t>(col)];
  } else {
    for (size_t i = 0; i < p.bands.size(); ++i) {
      if (p.bands[i] == band) col = static_cast<int>(i);
    }
  }
  // Every band's backbones with their scatter summary; targets built as `run` builds them.
  ModeBackbones mb =
      process_run_backbones(p.run, p.sensors, band, p.args.channels, ScatterOptions{});
  mb.name = "mode " + spec;
  mb.model_mode = ms.mode;
  if (col >= 0) {
    mb.linear_frequency_hz = p.measured.frequency_hz(col);
    band_of_mode.push_back({spec, ms.mode, band, col});
  }
  return mb;
}

// Each --stepped-sine folder's backbones, one more mode each (--stepped-sine-mode, default
// `first_mode`), measured at --stepped-sine-channel.
std::vector<ModeBackbones> stepped_sine_modes(const ProcessSide& p, int first_mode) {
  const IwanInputArgs& a = p.args;
  std::vector<ModeBackbones> out;
  if (a.stepped_sine.empty()) return out;
  int sensor = 0;
  if (!a.stepped_sine_channel.empty()) {
    sensor = correlate::find_sensor(p.sensors, a.stepped_sine_channel);
    if (sensor < 0) {
      throw InputError(fmt::format("--stepped-sine-channel {}: not in the sensors file {}",
                                   a.stepped_sine_channel, a.sensors));
    }
  } else if (p.sensors.size() != 1) {
    throw InputError(
        "--stepped-sine: give --stepped-sine-channel, the sensor the sweeps' response was "
        "measured at");
  }
  const int mode = a.stepped_sine_mode > 0 ? a.stepped_sine_mode : first_mode;
  for (const std::string& dir : a.stepped_sine) {
    const data::SteppedSineRun ss = data::read_stepped_sine_run(dir);
    if (ss.amplitude != p.run.amplitude) {
      throw InputError(
          fmt::format("--stepped-sine {}: its amplitude quantity differs from --measured {}'s; run "
                      "'jointlab stepped-sine' with the same --amplitude as 'jointlab process'",
                      dir, a.measured));
    }
    ModeBackbones mb = stepped_sine_run_backbones(ss, sensor, ScatterOptions{});
    mb.name = fmt::format("stepped sine {}", dir);
    mb.model_mode = mode;
    out.push_back(std::move(mb));
  }
  return out;
}

}  // namespace

IwanInputs read_iwan_inputs(const model::Model& m, const IwanInputArgs& a,
                            const std::string& command) {
  if (!a.backbones.empty()) return table_inputs(m, a, command);
  if (a.measured.empty() || a.sensors.empty()) {
    throw InputError(command +
                     ": give --measured DIR with --sensors FILE, or --backbone FILE (repeatable)");
  }
  if (!a.amplitude.empty() || !a.dof.empty()) {
    throw InputError(command +
                     ": --amplitude and --dof describe --backbone tables; a --measured folder "
                     "records its own amplitude quantity and sensors");
  }
  const std::vector<correlate::Sensor> sensors =
      correlate::sensors_of(data::read_sensors_file(a.sensors), m);
  const data::ProcessRun run = data::read_process_run(a.measured);
  std::vector<int> bands;
  const correlate::MeasuredModes measured = correlate::measured_modes(run, sensors, &bands);
  const model::LinearModes linear = model::linear_modes(m.mass, m.linear_stiffness());
  const ProcessSide side{a, sensors, run, measured, bands, linear};
  std::vector<ModeBackbones> modes;
  std::vector<BandOfMode> band_of_mode;
  for (const std::string& spec : a.modes) modes.push_back(mode_backbones(spec, side, band_of_mode));
  for (ModeBackbones& mb : stepped_sine_modes(side, modes.empty() ? 0 : modes.front().model_mode))
    modes.push_back(std::move(mb));
  IwanInputs in;
  in.curve_notes = curve_notes(modes);
  // The folder's other modes screen the fitted points as `run`'s other [[mode]]s do.
  std::string screened_with;
  for (ModeBackbones& mb : screen_only_modes(side, modes, band_of_mode)) {
    screened_with += (screened_with.empty() ? "" : ", ") + mb.name;
    modes.push_back(std::move(mb));
  }
  IwanTargetOptions target_options;
  target_options.amplitude = correlate::amplitude_quantity(run.amplitude);
  const IwanTargets built = iwan_targets(m, sensors, modes, target_options);
  // Say per mode how many points the slip screen leaves out; when it leaves no mode anything,
  // say that rather than that nothing was measured.
  if (modes.size() > 1) in.slip_screen = built.screen_report(modes);
  if (!screened_with.empty())
    in.slip_screen +=
        fmt::format("  the other modes' slip read from {}'s {}\n", a.measured, screened_with);
  if (const std::string why = built.screened_out(modes, target_options.max_slip_share);
      !why.empty())
    throw InputError(fmt::format("{}: {}", command, why));
  if (built.fitted.empty())
    throw InputError(fmt::format("{}: no mode has a backbone of at least two points", command));
  in.sensors = sensors;
  in.targets = built.fitted;
  in.amplitude = correlate::amplitude_quantity(run.amplitude);
  in.measured = measured;
  in.data_name = a.measured;
  in.bands = std::move(band_of_mode);
  return in;
}

std::string update_iwan_report(const correlate::IwanUpdateSummary& s, const model::Model& given,
                               const model::Model& updated, const std::string& set,
                               const IwanInputs& in,
                               const std::vector<correlate::ParetoPoint>& front,
                               const std::string& set_option, std::vector<std::string>* warnings) {
  std::string text = s.report();
  if (!in.amplitude_note.empty()) text += "  " + in.amplitude_note + "\n";
  for (const std::string& note : in.curve_notes) text += "  note: " + note + "\n";
  std::vector<std::string> lines = band_shape_warnings(updated, in);
  // A set fitted against a mode whose joint dissipation other sets carry: what misfits is the
  // other sets' held values, not this set.
  for (std::string& line :
       set_share_warnings(given, set, in.sensors, in.targets, in.amplitude, set_option))
    lines.push_back(std::move(line));
  for (const std::string& line : lines) text += "  " + line + "\n";
  if (warnings) *warnings = std::move(lines);
  return text + pareto_report(front);
}

std::vector<std::string> band_shape_warnings(const model::Model& updated, const IwanInputs& in) {
  std::vector<std::string> lines;
  if (!in.measured) return lines;
  // The smallest MAC at the sensors of a --mode's band with that mode of the updated model
  // without a warning: the MAC pairing's threshold (band_column_of's 0.6). The
  // updated model, not the start: a start far off may order the modes differently. A low MAC
  // means the band, or the sensors file, belongs to another mode: the parameters then fit that
  // mode's data. Said, not refused: a poorly measured shape of the right mode may look like
  // nothing.
  constexpr double kBandMacThreshold = 0.6;
  for (const BandOfMode& b : in.bands) {
    const correlate::ModeShapeMatch match =
        correlate::mode_shape_match(updated, in.sensors, *in.measured, b.column, b.mode);
    if (match.mac >= kBandMacThreshold) continue;
    // "; or a sign: with channel s1 reversed ..." where a sign explains the low MAC.
    std::string sign;
    if (!match.reversed.empty()) {
      std::vector<std::string> names;
      for (const int k : match.reversed)
        names.push_back(in.sensors[static_cast<size_t>(k)].channel);
      sign = fmt::format(
          "; or a sign: with {} {} reversed its MAC with mode {} is {:.2g}, so check {} sign in "
          "the sensors file",
          names.size() == 1 ? "channel" : "channels", fmt::join(names, " and "), b.mode,
          match.reversed_mac, names.size() == 1 ? "its" : "their");
    }
    lines.push_back(fmt::format(
        "WARNING: --mode {}: band {}'s measured shape and mode {} of the updated model have MAC "
        "{:.2g} at the sensors (below {:g}){}: the band, or the sensors file, may belong to "
        "another mode, and the parameters then fit that mode's data{}",
        b.spec, b.band, b.mode, match.mac, kBandMacThreshold,
        match.best_mode != b.mode ? fmt::format("; it looks most like mode {} (MAC {:.2g})",
                                                match.best_mode, match.best_mac)
                                  : std::string(),
        sign));
  }
  return lines;
}

std::vector<std::pair<std::string, double>> iwan_set_shares(const model::Model& m,
                                                            const model::LinearModes& linear,
                                                            int mode, double q) {
  const int col = linear.rigid_count + mode - 1;
  std::vector<std::pair<std::string, double>> out;
  if (mode < 1 || col >= linear.size()) return out;
  const Eigen::VectorXd phi = linear.shapes.col(col);
  double total = 0;
  for (const model::Joint& j : m.joints) {
    if (!j.iwan) continue;
    const double slip = std::abs(phi(j.a) - (j.b == model::kGround ? 0.0 : phi(j.b))) * q;
    const double d = j.iwan->dissipation(slip);
    auto at =
        std::find_if(out.begin(), out.end(), [&](const auto& e) { return e.first == j.element; });
    if (at == out.end()) at = out.insert(out.end(), {j.element, 0.0});
    at->second += d;
    total += d;
  }
  if (!(total > 0)) return {};
  for (auto& e : out) e.second /= total;
  return out;
}

std::vector<std::string> set_share_warnings(const model::Model& m, const std::string& set,
                                            const std::vector<correlate::Sensor>& sensors,
                                            const std::vector<correlate::IwanTarget>& targets,
                                            correlate::AmplitudeQuantity amplitude,
                                            const std::string& option) {
  std::vector<std::string> lines;
  const std::string full = set.starts_with("iwan.") ? set : "iwan." + set;
  const model::LinearModes linear = model::linear_modes(m.mass, m.linear_stiffness());
  const int power = correlate::amplitude_power(amplitude);
  for (const correlate::IwanTarget& t : targets) {
    const int col = linear.rigid_count + t.mode - 1;
    if (t.mode < 1 || col >= linear.size()) continue;
    // The measured range as modal amplitudes, through the linear mode's shape at each sensor.
    double q_low = std::numeric_limits<double>::infinity(), q_high = 0;
    for (const correlate::MeasuredBackbone& c : t.curves) {
      double shape = 1;
      if (!c.modal) {
        if (c.sensor < 0 || c.sensor >= static_cast<int>(sensors.size())) continue;
        shape = std::abs(linear.shapes(sensors[static_cast<size_t>(c.sensor)].dof, col));
      }
      if (!(shape > 0)) continue;
      for (Eigen::Index i = 0; i < c.amplitude.size(); ++i) {
        const double omega = 2 * std::numbers::pi * c.frequency_hz(i);
        const double q = c.amplitude(i) / (shape * (c.modal ? 1.0 : std::pow(omega, power)));
        if (!(q > 0) || !std::isfinite(q)) continue;
        q_low = std::min(q_low, q), q_high = std::max(q_high, q);
      }
    }
    if (!(q_high > 0)) continue;
    const auto low = iwan_set_shares(m, linear, t.mode, q_low),
               high = iwan_set_shares(m, linear, t.mode, q_high);
    if (low.empty() || high.empty()) continue;
    const auto share = [&](const std::vector<std::pair<std::string, double>>& v,
                           const std::string& name) {
      for (const auto& [n, x] : v)
        if (n == name) return x;
      return 0.0;
    };
    const double own_low = share(low, full), own_high = share(high, full);
    if (own_low >= 0.5 || own_high >= 0.5) continue;
    std::vector<std::string> others;
    std::string carrier;
    double most = -1;
    for (const auto& [name, x] : low) {
      if (name == full) continue;
      const double y = share(high, name);
      others.push_back(fmt::format("{} {}", name, percent_range(x, y)));
      if (x + y > most) most = x + y, carrier = name;
    }
    lines.push_back(fmt::format(
        "WARNING: mode {}'s joint dissipation comes mostly from other Iwan sets than {}: in the "
        "model as given, over the measured amplitudes (modal amplitude {:.3g} to {:.3g}, read "
        "through the linear mode's shape), {} carries {} of it ({}). The fit moves {} "
        "to take up what the other sets' held values miss, so its parameters, sigmas and the "
        "causes named above read their misfit as {}'s. Fit the set that carries mode {} against "
        "it ({}), then {} against a mode it carries",
        t.mode, full, q_low, q_high, full, percent_range(own_low, own_high),
        fmt::join(others, ", "), full, full, t.mode, fmt::format(fmt::runtime(option), carrier),
        full));
  }
  return lines;
}

bool linear_part_matches(const model::Model& m, const std::vector<correlate::IwanTarget>& targets,
                         double tolerance) {
  if (targets.empty()) return false;
  const model::LinearModes linear = model::linear_modes(m.mass, m.linear_stiffness());
  for (const correlate::IwanTarget& t : targets) {
    const int col = linear.rigid_count + t.mode - 1;
    if (t.mode < 1 || col >= linear.size() || !(t.linear_frequency_hz > 0)) return false;
    if (!(std::abs(linear.frequency_hz(col) / t.linear_frequency_hz - 1) <= tolerance))
      return false;
  }
  return true;
}

}  // namespace jointlab::campaign
