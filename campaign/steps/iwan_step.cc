#include "jointlab/campaign/steps/iwan_step.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/campaign/iwan_fit.h"
#include "jointlab/campaign/iwan_inputs.h"
#include "jointlab/campaign/steps/known_parameters.h"
#include "jointlab/campaign/steps/update_settings.h"
#include "jointlab/core/error.h"
#include "jointlab/data/backbone_table.h"
#include "jointlab/modal/stepped_sine_output.h"

namespace jointlab::campaign {

using correlate::IwanObjective;
using correlate::IwanUpdateOptions;
using correlate::IwanUpdateSummary;

namespace {

// What each backbone is compared with, as update-iwan --compare: "matched" or "secant".
correlate::IwanComparison comparison(const UpdateSettings& in, const std::string& key,
                                     const CampaignSetting& s) {
  const std::string& v = in.text(key, s);
  if (v == "matched") return correlate::IwanComparison::kMatched;
  if (v == "secant") return correlate::IwanComparison::kSecant;
  in.fail(key, s, fmt::format("must be \"matched\" or \"secant\", not \"{}\"", v));
}

// [update.iwan] linear_damping: "hold" (the model's [damping] modal_ratio) or "fit".
bool fit_linear_damping(const UpdateSettings& in, const std::string& key,
                        const CampaignSetting& s) {
  const std::string& v = in.text(key, s);
  if (v == "hold") return false;
  if (v == "fit") return true;
  in.fail(key, s, fmt::format("must be \"hold\" or \"fit\", not \"{}\"", v));
}

// The backbone reader's message with update-iwan's option named as the campaign's key: run takes
// the amplitude quantity from [campaign] amplitude, and "a displacement amplitude needs
// --amplitude displacement" sent the user after an option run does not have.
std::string with_campaign_amplitude(const std::string& message) {
  static const std::regex option(R"(--amplitude (\w+))");
  return std::regex_replace(message, option, "amplitude = \"$1\" in [campaign]");
}

}  // namespace

void iwan_update_options(const Campaign& c, IwanUpdateOptions& io, IwanTargetOptions& to) {
  // A motion quantity: campaign.cc refuses a force amplitude.
  io.amplitude = correlate::amplitude_quantity(c.amplitude);
  to.amplitude = io.amplitude;
  const UpdateSettings in(c, "update.iwan");
  for (const auto& [key, s] : c.iwan_update.settings) {
    if (key == "max_evaluations")
      io.max_evaluations = in.whole(key, s, 1, 10000000);
    else if (key == "gamma")
      io.fixed_gamma = in.number(key, s);
    else if (key == "beta")
      io.fixed_beta = in.number(key, s);
    else if (key == "samples")
      io.samples = in.whole(key, s, 2, 10000000);
    else if (key == "local_starts")
      io.local_starts = in.whole(key, s, 1, 1000);
    else if (key == "seed")
      io.seed = static_cast<unsigned>(in.whole(key, s, 0, 2147483647));
    else if (key == "max_slip_share")
      to.max_slip_share = in.number(key, s);
    else if (key == "compare")
      io.comparison = comparison(in, key, s);
    else if (key == "linear_damping")
      io.fit_linear_damping = fit_linear_damping(in, key, s);
    else if (key == "linear_damping_max")
      io.linear_damping_max = in.number(key, s);
    else if (key == "accept_unconfirmed_pairs")
      in.flag(key, s);  // the campaign's own: accepts_unconfirmed_pairs()
    else
      in.unknown(key, s,
                 "gamma, beta, max_evaluations, samples, local_starts, seed, "
                 "max_slip_share, compare, linear_damping, linear_damping_max, "
                 "accept_unconfirmed_pairs");
  }
  if (const std::string e = io.error(); !e.empty())
    throw InputError(where(c.file.string(), 0, "update.iwan: " + e));
}

std::string iwan_set(const Campaign& c, const model::Model& m) {
  if (!c.iwan_update.sets.empty()) return c.iwan_update.sets.front();
  model::IwanParameters first;
  std::string set;
  if (!first_iwan(m, first, set))
    throw InputError(where(c.file.string(), 0, "update.iwan: the model has no Iwan joint"));
  return set;
}

std::vector<ModeBackbones> campaign_backbones(const Campaign& c, const MeasuredSide& m) {
  std::vector<ModeBackbones> modes(c.modes.size());
  for (size_t k = 0; k < c.modes.size(); ++k) {
    ModeBackbones& mb = modes[k];
    mb.name = c.modes[k].name;
    mb.model_mode = c.modes[k].model_mode;
    mb.fitted = c.iwan_update.fits(c.modes[k].name);
    mb.linear_frequency_hz = m.modes.frequency_hz(static_cast<Eigen::Index>(k));
    mb.curves = m.curves[k];
    mb.sensors.assign(mb.curves.size(), m.reference[k]);
    for (const PointStd& p : m.point_std[k]) {
      mb.frequency_std_hz.push_back(p.frequency_hz);
      mb.damping_std.push_back(p.damping);
      mb.coverage.push_back(p.coverage);
    }
    mb.scatter = m.scatter[k];
  }
  // Each mode's stepped-sine tests: one more entry of the same model mode, one curve per file,
  // each point weighed by its own uncertainty (kept apart from the hammer hits' scatter bins).
  for (size_t k = 0; k < c.modes.size(); ++k) {
    if (c.modes[k].stepped_sine.empty()) continue;
    ModeBackbones sine = stepped_sine_backbones(c, k, m.reference[k]);
    sine.fitted = c.iwan_update.fits(c.modes[k].name);
    sine.linear_frequency_hz = modes[k].linear_frequency_hz;
    modes.push_back(std::move(sine));
  }
  // Each mode's backbone tables (any source): one more entry of the same model mode, one curve
  // per table at the reference channel, each point weighed by its own uncertainty.
  for (size_t k = 0; k < c.modes.size(); ++k) {
    if (c.modes[k].backbones.empty()) continue;
    ModeBackbones tables;
    tables.name = c.modes[k].name + " (backbone tables)";
    tables.model_mode = c.modes[k].model_mode;
    tables.fitted = c.iwan_update.fits(c.modes[k].name);
    tables.linear_frequency_hz = modes[k].linear_frequency_hz;
    std::vector<std::string> unitless;  // read in SI, said in the report as update-iwan says it
    // One hit given twice would count as two: refused (read_backbone_tables).
    std::vector<data::BackboneTable> read;
    try {
      read = data::read_backbone_tables(c.modes[k].backbones, c.amplitude);
    } catch (const InputError& e) {
      throw InputError(with_campaign_amplitude(e.what()));
    }
    for (size_t i = 0; i < read.size(); ++i) {
      const std::filesystem::path& f = c.modes[k].backbones[i];
      const data::BackboneTable& t = read[i];
      if (t.amplitude_unit_assumed()) unitless.push_back(f.filename().string());
      Curve cv;
      cv.id = "table " + f.filename().string();  // never a hit's id: no slip screen across
      cv.amplitude = t.amplitude;
      cv.frequency_hz = t.frequency_hz;
      cv.damping = t.damping_ratio;
      cv.time_s = Eigen::VectorXd::Zero(t.size());
      tables.curves.push_back(std::move(cv));
      tables.frequency_std_hz.push_back(t.frequency_std_hz);
      tables.damping_std.push_back(t.damping_std);
      tables.coverage.push_back(t.coverage_factor);
      tables.sensors.push_back(m.reference[k]);
    }
    tables.scatter = summarize_scatter(tables.curves, ScatterOptions{});
    if (const std::string assumed =
            correlate::unitless_amplitudes(unitless, quantity_name(c.amplitude));
        !assumed.empty()) {
      tables.amplitude_note = tables.name + ": " + assumed;
    }
    modes.push_back(std::move(tables));
  }
  return modes;
}

ModeBackbones stepped_sine_backbones(const Campaign& c, size_t k, int sensor) {
  const CampaignMode& mode = c.modes[k];
  modal::SteppedSineOptions opt;
  opt.amplitude = c.amplitude;
  ModeBackbones mb;
  mb.name = mode.name + " (stepped sine)";
  mb.model_mode = mode.model_mode;
  for (const std::filesystem::path& f : mode.stepped_sine) {
    const modal::SteppedSineFileResult r = modal::extract_stepped_sine_file(f, c.quantity, opt);
    std::vector<size_t> rows;
    for (size_t i = 0; i < r.points.size(); ++i)
      if (r.points[i].status == modal::SineStatus::kOk) rows.push_back(i);
    std::sort(rows.begin(), rows.end(),
              [&](size_t a, size_t b) { return r.points[a].amplitude < r.points[b].amplitude; });
    if (rows.empty()) continue;
    const auto n = static_cast<Eigen::Index>(rows.size());
    Curve cv;
    cv.id = f.stem().string();
    cv.group = "stepped sine";
    cv.amplitude.resize(n), cv.frequency_hz.resize(n), cv.damping.resize(n);
    Eigen::VectorXd sf(n), sz(n);
    for (Eigen::Index j = 0; j < n; ++j) {
      const modal::SineBackbonePoint& p = r.points[rows[static_cast<size_t>(j)]];
      cv.amplitude(j) = p.amplitude, cv.frequency_hz(j) = p.frequency_hz;
      cv.damping(j) = p.damping_ratio, sf(j) = p.frequency_std_hz, sz(j) = p.damping_std;
    }
    mb.curves.push_back(std::move(cv));
    mb.frequency_std_hz.push_back(sf);
    mb.damping_std.push_back(sz);
    mb.coverage.push_back(opt.coverage_factor);
    mb.sensors.push_back(sensor);
    mb.kinds.push_back(correlate::BackboneKind::kSteppedSine);
  }
  if (mb.curves.empty()) {
    throw InputError(
        where(c.file.string(), 0,
              fmt::format("{}: no level of its stepped_sine files gave a point", mode.name)));
  }
  mb.scatter = summarize_scatter(mb.curves, ScatterOptions{});
  return mb;
}

IwanStep iwan_update_step(const Campaign& c, const model::Model& base,
                          const std::vector<correlate::Sensor>& sensors, const MeasuredSide& m,
                          const std::function<void(const std::string&)>& progress,
                          bool linear_updated, const std::function<void()>& interrupt) {
  const auto say = [&](const std::string& s) {
    if (progress) progress(s);
  };
  IwanStep step;
  if (!c.iwan_update.enabled) return step;
  step.set = iwan_set(c, base);
  IwanUpdateOptions io;
  IwanTargetOptions to;
  iwan_update_options(c, io, to);
  io.linear_part_updated = linear_updated;
  const std::vector<ModeBackbones> backbones = campaign_backbones(c, m);
  const IwanTargets targets = iwan_targets(base, sensors, backbones, to);
  if (const std::string why = targets.screened_out(backbones, to.max_slip_share); !why.empty()) {
    step.refused = true;
    step.note = "update.iwan: " + why +
                "; Iwan updating skipped ([update.iwan] max_slip_share sets the share)";
    return step;
  }
  if (targets.fitted.empty()) {
    step.note = "update.iwan: no mode names its model mode (model_mode); Iwan updating skipped";
    return step;
  }
  const IwanObjective objective(base, step.set, sensors, targets.fitted, io);
  // Per mode whose hits the slip screen emptied: its name and "every point but at most one of
  // ..., so those hits are left out of the fit", for the progress line and the report.
  std::vector<std::pair<std::string, std::string>> emptied;
  for (size_t k = 0; k < backbones.size(); ++k) {
    if (const std::string text = targets.hits_screened_out_text(k); !text.empty())
      emptied.emplace_back(backbones[k].name, text.substr(2));
  }
  std::string emptied_text;
  for (const auto& [mode, text] : emptied) emptied_text += fmt::format("; {}: {}", mode, text);
  say(
      fmt::format("update: Iwan identification of {} ({} modes, {} curves; {} points "
                  "left out where other modes carry over {:g} % of the joint slip{})",
                  step.set, targets.fitted.size(), targets.curves(), targets.screened,
                  100 * to.max_slip_share, emptied_text));
  // A fit of tens of seconds says how it goes: every 250 evaluations, the best cost so far.
  // Between those lines, `interrupt` (where given) may stop the fit.
  if (progress || interrupt) {
    io.progress = progress_every(
        250,
        [&](int evaluations, double best) {
          say(fmt::format("update: {} QSMA evaluations, best cost {:.6g}", evaluations, best));
        },
        interrupt);
  }
  // update-iwan's own fit, in its default box: frequencies no parameter set can reach, and a
  // box where no parameter set gives a curve over the amplitudes, are said with the numbers as
  // update-iwan says them, rather than fitted to (or returned as) a best that fits nothing.
  try {
    step.summary = checked_fit_iwan(objective, io, IwanRanges{}, "update.iwan", "", say);
  } catch (const InputError& e) {
    step.refused = true;
    step.note = std::string(e.what()) + "; Iwan updating skipped";
    return step;
  }
  step.beta_held = step.summary.held[3];  // as asked, in microslip, or the free fit no better
  step.curves = static_cast<int>(targets.curves());
  step.updated = objective.apply(step.summary.best, step.summary.modal_ratio);
  if (!c.truth.empty()) step.cost_known = objective.cost(read_truth(c.truth, truth_set(c)).iwan);
  // Each mode's backbone cost at the start and at the result, fitted or not: a mode the
  // one-mode QSMA cannot describe (its joints moved by another mode) stands out.
  for (const auto& [k, t] : targets.every) {
    const IwanObjective one(base, step.set, sensors, {t}, io);
    step.mode_costs.push_back({backbones[k].name, backbones[k].fitted, one.cost(step.summary.start),
                               one.cost(step.summary.best)});
  }
  step.ran = true;
  say("update: " + step.summary.report());
  // The set fitted against a mode whose joint dissipation other sets carry, in the model the fit
  // starts from: what misfits is their held values, not this set.
  step.warnings = set_share_warnings(base, step.set, sensors, targets.fitted, io.amplitude,
                                     "sets = [\"{}\"] in [update.iwan], its [[mode]]s in modes");
  for (const ModeBackbones& mb : backbones)
    if (!mb.amplitude_note.empty()) step.warnings.push_back("note: " + mb.amplitude_note);
  // The hits the slip screen emptied, named in the report too (the progress line above names
  // them; the report said only how many curves were fitted).
  for (const auto& [mode, text] : emptied)
    step.warnings.push_back(
        fmt::format("note: {}: other modes carry the joint slip at {}", mode, text));
  for (const std::string& w : step.warnings) say("update: " + w);
  return step;
}

bool accepts_unconfirmed_pairs(const Campaign& c) {
  const auto at = c.iwan_update.settings.find("accept_unconfirmed_pairs");
  if (at == c.iwan_update.settings.end()) return false;
  return UpdateSettings(c, "update.iwan").flag(at->first, at->second);
}

std::string iwan_stop_reason(const Campaign& c, const LinearStep& linear, const std::string& set) {
  if (!linear.ran) return "";
  const correlate::LinearUpdateSummary& s = linear.summary;
  if (s.status == correlate::LinearUpdateStatus::kPairsUnconfirmed &&
      !accepts_unconfirmed_pairs(c)) {
    std::vector<std::string> modes;
    for (const int i : s.unconfirmed_modes) modes.push_back(s.final.measured_id(i));
    const bool one = modes.size() == 1;
    return fmt::format(
        "update.iwan: not run: at the linear update's result the shapes do not confirm the "
        "pair{} of {} (MAC with the partner below update.linear mac_threshold {:g}, or pairs "
        "crosswise to the frequency order at two channels with a misfit left), so the "
        "updated model's modes may be paired crosswise with the measured ones and an Iwan joint "
        "identified on it would pass a wrong number on; the linear updating paragraph of the "
        "report says which modes and why. Add channels that see these modes apart or check "
        "their signs ([[channel]] sign), or, if the pairs are known to be right, set "
        "accept_unconfirmed_pairs = true in [update.iwan]",
        one ? "" : "s", fmt::join(modes, " and "), linear_update_options(c).mac_threshold);
  }
  // A [[mode]] whose model_mode is not the model mode its shape pairs it with: the Iwan update
  // would fit another mode's QSMA curve to this backbone (a typed model_mode = 2 for the beam's
  // first mode: K_T pressed to its bound at 5 % of the linear update's, F_S 6.2 times the truth,
  // the report warning only after the fit). Only a pair the shapes confirm (MAC at two channels
  // or more, at least the linear update's threshold) is evidence.
  const double threshold = linear_update_options(c).mac_threshold;
  for (size_t i = 0; i < linear.campaign_modes.size(); ++i) {
    const CampaignMode& mode = c.modes[static_cast<size_t>(linear.campaign_modes[i])];
    if (mode.model_mode <= 0 || !c.iwan_update.fits(mode.name)) continue;
    const auto row = static_cast<Eigen::Index>(i);
    const int j = s.final.pairing.model_for(static_cast<int>(i));
    const std::optional<double> mac = s.final.pair_mac(row);
    if (j < 0 || !mac || *mac < threshold || j + 1 == mode.model_mode) continue;
    const Eigen::VectorXd& f = s.final.all_model_frequency_hz;
    return fmt::format(
        "update.iwan: not run: [[mode]] '{}' gives model_mode = {}, but its measured shape pairs "
        "it with model mode {} ({:.5g} Hz, MAC {:.3f} at the channels; the measured linear "
        "frequency is {:.5g} Hz{}), so the Iwan update would fit mode {}'s QSMA curve to mode "
        "{}'s backbone; set model_mode = {} in that [[mode]], or check its band and channels if "
        "mode {} is meant",
        mode.name, mode.model_mode, j + 1, f(j), *mac, s.final.measured_frequency_hz(row),
        mode.model_mode - 1 < f.size()
            ? fmt::format(", model mode {}'s {:.5g} Hz", mode.model_mode, f(mode.model_mode - 1))
            : std::string(),
        mode.model_mode, j + 1, j + 1, mode.model_mode);
  }
  for (const correlate::ParameterReport& p : s.parameters) {
    if ((p.name != set && p.name != "iwan." + set) || p.acts_with.empty()) continue;
    return fmt::format(
        "update.iwan: not run: the linear update determines only a combination of {} and {} "
        "(their sensitivities repeat one another), not {}'s K_T alone, so the split the Iwan "
        "update would start from is arbitrary and so would be its joint; leave {} out of "
        "update.linear sets (its value as the model file gives it)",
        p.name, fmt::join(p.acts_with, ", "), p.name,
        p.acts_with.size() == 1 ? "one of them" : "all but one of them");
  }
  return "";
}

IwanStep iwan_update_after(const Campaign& c, const CampaignModelData& m, const LinearStep& linear,
                           const MeasuredSide& measured,
                           const std::function<void(const std::string&)>& progress,
                           const std::function<void()>& interrupt) {
  const model::Model& base = linear.ran ? linear.updated : m.model;
  if (c.iwan_update.enabled) {
    if (std::string why = iwan_stop_reason(c, linear, iwan_set(c, base)); !why.empty()) {
      IwanStep step;
      step.stopped = true;
      step.note = std::move(why);
      if (progress) progress(step.note);
      return step;
    }
  }
  return iwan_update_step(c, base, m.sensors, measured, progress, linear.ran, interrupt);
}

}  // namespace jointlab::campaign
