// Channels read reversed: at the start, and as the fit's misfit shows (linear_signs.h).
#include "jointlab/correlate/linear_signs.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/correlate/linear_fit.h"
#include "jointlab/correlate/mac.h"
#include "jointlab/correlate/noise_limits.h"
#include "jointlab/correlate/shape_checks.h"

namespace jointlab::correlate::detail {
namespace {

// Where the channels with measured entries other than `reversed` are at most one more than
// them, the clause saying that reversing those instead is the same (MAC ignores a shape's
// overall sign: with three of five channels mounted reversed the checks name the other two,
// and either fix fits alike); else "".
std::string same_as_the_others(const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                               const std::vector<int>& reversed) {
  std::vector<std::string> others;
  for (Eigen::Index k = 0; k < measured.shapes.rows(); ++k)
    if ((measured.shapes.row(k).array().abs() > 0.0).any() &&
        std::find(reversed.begin(), reversed.end(), static_cast<int>(k)) == reversed.end())
      others.push_back(sensors[static_cast<size_t>(k)].channel);
  if (others.empty() || others.size() > reversed.size() + 1) return "";
  return fmt::format(
      " (or, as a shape's sign as a whole is arbitrary, the same: {} reversed instead)",
      fmt::join(others, ", "));
}

// Whether every measured mode, its frequency times `scale`, has a visible model mode at the
// start within the frequency window `window` (|f_model / f - 1| <= window) that can be its
// partner: of MAC >= 0.9 with it where it has entries at three sensors or more, any otherwise.
bool every_mode_has_a_partner(const LinearEvaluation& start, const MeasuredModes& measured,
                              double scale, double window) {
  std::vector<char> visible(static_cast<size_t>(start.model_at_sensors.cols()), 1);
  for (const int h : start.hidden)
    if (h >= 0 && h < static_cast<int>(visible.size())) visible[static_cast<size_t>(h)] = 0;
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) {
    const double f = scale * measured.frequency_hz(i);
    const bool shape = (measured.shapes.col(i).array().abs() > 0.0).count() >= 3;
    bool found = false;
    for (Eigen::Index j = 0; j < start.model_at_sensors.cols() && !found; ++j)
      found = visible[static_cast<size_t>(j)] &&
              std::abs(start.all_model_frequency_hz(j) / f - 1) <= window &&
              (!shape || mac(measured.shapes.col(i), start.model_at_sensors.col(j)) >= 0.9);
    if (!found) return false;
  }
  return true;
}

}  // namespace

// What is wrong with the measured shapes against the model at the start (shape_checks.h), or "".
std::string shape_problem(const LinearEvaluation& start, const std::vector<Sensor>& sensors,
                          const MeasuredModes& measured, const LinearUpdateOptions& options) {
  std::vector<std::string> ids;
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i) ids.push_back(measured.id(i));
  if (std::string why =
          phaseless_shapes(measured.shapes, measured.frequency_hz, start.model_at_sensors,
                           start.all_model_frequency_hz, ids, options.frequency_window);
      !why.empty())
    return why;
  if (options.trust_signs) return "";
  const SignCheck c =
      check_channel_signs(measured.shapes, measured.frequency_hz, start.model_at_sensors,
                          start.all_model_frequency_hz, start.hidden, options.frequency_window);
  if (c.channels.empty()) return "";
  std::vector<std::string> names, signs;
  for (const int k : c.channels) {
    const Sensor& r = sensors[static_cast<size_t>(k)];
    names.push_back(r.channel);
    signs.push_back(fmt::format("{} sign {:+g}", r.channel, -r.sign));
  }
  const std::string which = fmt::format("{}", fmt::join(names, " and "));
  const bool one = names.size() == 1;
  return fmt::format(
      "channel{} {} read{} the model reversed: as given, {} of {} measured modes (with entries at "
      "three sensors or more) have a model mode within the frequency window at MAC >= 0.9 (mean "
      "best MAC {:.3f}); with {} reversed, {} of {} have (mean {:.3f}), so {} likely wrong "
      "(mounted the other way round): give {}{} in the sensors file (a campaign's [[channel]] "
      "sign), or, if the sign{} right, fit the shapes as given with --trust-signs (a campaign's "
      "update.linear trust_signs = true)",
      one ? "" : "s", which, one ? "s" : "", c.matched, c.counted, c.mean_mac, which,
      c.matched_reversed, c.counted, c.mean_mac_reversed, one ? "its sign is" : "their signs are",
      fmt::join(signs, " and "), same_as_the_others(sensors, measured, c.channels),
      one ? " is" : "s are");
}

// Why a fit's misfit is one or two channels read reversed, or "". The start's check
// (shape_problem) cannot tell when every measured mode matches some model mode either way:
// on the example beam with s2 and s4 reversed and modes 1, 4 and 5 alone, all three matched as
// given, the fit paired mode 5 with a model mode 38 % away and gave K_T 5.1e6 against 1.2e7,
// "converged", with reduced chi-square 7.6e4. So where a fit leaves scatter beyond the noise
// (reduced_chi2_limit) and the reversal that matches the shapes best at the start matches as
// many modes with a higher mean MAC (SignCheck::best_looks_better), that reversal is fitted
// too; when it pairs as many modes and its reduced chi-square is within the noise, or a
// hundredth of the given signs' (a model-form error both share), the signs are refused.
std::string misfit_of_signs(const model::Model& model, const std::vector<std::string>& names,
                            const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                            const LinearUpdateOptions& options, const LinearUpdateSummary& s) {
  // The scatter per degree of freedom and where noise keeps it; with none left (as many pairs
  // as fitted sets) the whole chi-square, which a fit that reached every frequency leaves near
  // 0, against 3 sigma at each pair (a bound stopped it, or pairs no stiffness can meet).
  const double sf2 = options.frequency_std * options.frequency_std;
  const auto misfit = [&](const LinearUpdateSummary& x) {
    if (x.degrees_of_freedom >= 1)
      return std::pair{x.reduced_chi2, reduced_chi2_limit(x.degrees_of_freedom)};
    return std::pair{x.final.weighted_squared_norm() / sf2,
                     9.0 * static_cast<double>(x.final.pairing.pairs.size())};
  };
  const auto [given, given_limit] = misfit(s);
  if (options.trust_signs || !fitted(s) || !(given > given_limit)) return "";
  const SignCheck c =
      check_channel_signs(measured.shapes, measured.frequency_hz, s.start.model_at_sensors,
                          s.start.all_model_frequency_hz, s.start.hidden, options.frequency_window);
  if (!c.best_looks_better()) return "";
  std::vector<Sensor> reversed = sensors;
  std::vector<std::string> which, signs;
  for (const int k : c.best) {
    Sensor& r = reversed[static_cast<size_t>(k)];
    r.sign = -r.sign;
    which.push_back(r.channel);
    signs.push_back(fmt::format("{} sign {:+g}", r.channel, r.sign));
  }
  LinearUpdateOptions o = options;
  o.trust_signs = true;
  o.progress = nullptr;
  LinearUpdateSummary r;
  fit_as_given(model, names, reversed, measured, o, false, r);
  if (!fitted(r) || (s.degrees_of_freedom >= 1 && r.degrees_of_freedom < 1) ||
      r.final.pairing.pairs.size() < s.final.pairing.pairs.size())
    return "";
  const auto [again, again_limit] = misfit(r);
  if (!(again <= std::max(again_limit, given / 100))) return "";
  const std::string scatter =
      s.degrees_of_freedom >= 1
          ? fmt::format("a reduced chi-square of {:.3g} over {} degrees of freedom", given,
                        s.degrees_of_freedom)
          : fmt::format("a chi-square of {:.3g} with no degree of freedom left", given);
  const bool one = which.size() == 1;
  return fmt::format(
      "channel{} {} likely read{} the model reversed: as given, the fit leaves {} (largest "
      "frequency error {:.3g} %), beyond the noise the frequencies state; with {} reversed it "
      "leaves {:.3g} (largest error {:.3g} %), pairing {} of {} measured modes, so the fit tells "
      "what the shapes alone did not: give {}{} in the sensors file (a campaign's [[channel]] "
      "sign), or, if the sign{} right, fit the shapes as given with --trust-signs (a campaign's "
      "update.linear trust_signs = true)",
      one ? "" : "s", fmt::join(which, " and "), one ? "s" : "", scatter, 100 * s.final.max_error(),
      fmt::join(which, " and "), again, 100 * r.final.max_error(), r.final.pairing.pairs.size(),
      measured.frequency_hz.size(), fmt::join(signs, " and "),
      same_as_the_others(sensors, measured, c.best), one ? " is" : "s are");
}

// Why a fit's misfit is frequencies in rad/s read as Hz, or "" (linear_signs.h).
std::string misfit_of_units(const model::Model& model, const std::vector<std::string>& names,
                            const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                            const LinearUpdateOptions& options, const LinearUpdateSummary& s) {
  if (!fitted(s) || s.degrees_of_freedom < 1 ||
      !(s.reduced_chi2 > reduced_chi2_limit(s.degrees_of_freedom)))
    return "";
  const double to_hz = 0.5 / std::numbers::pi;
  const double window = options.frequency_window > 0 ? options.frequency_window : 0.5;
  if (!every_mode_has_a_partner(s.start, measured, to_hz, window)) return "";
  MeasuredModes hz = measured;
  hz.frequency_hz *= to_hz;
  LinearUpdateOptions o = options;
  o.progress = nullptr;
  LinearUpdateSummary r;
  fit_as_given(model, names, sensors, hz, o, false, r);
  if (!fitted(r) || r.degrees_of_freedom < 1 ||
      r.final.pairing.pairs.size() < s.final.pairing.pairs.size() ||
      !(r.reduced_chi2 <= std::max(reduced_chi2_limit(r.degrees_of_freedom), s.reduced_chi2 / 100)))
    return "";
  // The pair of largest error as given, to show the unit.
  const LinearEvaluation& e = s.final;
  Eigen::Index worst = e.pairing.pairs.front().measured;
  for (const ModePair& p : e.pairing.pairs)
    if (std::abs(e.residuals(p.measured)) > std::abs(e.residuals(worst))) worst = p.measured;
  return fmt::format(
      "the frequencies look like angular frequencies (rad/s) read as Hz: as given, the fit "
      "leaves a reduced chi-square of {:.3g} over {} degrees of freedom (largest frequency error "
      "{:.3g} %: test mode {} at {:.5g} paired with model mode {} at {:.5g} Hz); divided by 2 pi "
      "they fit to {:.3g} over {} (largest error {:.3g} %), pairing {} of {} measured modes: "
      "give frequency_hz in Hz (rad/s divided by 2 pi)",
      s.reduced_chi2, s.degrees_of_freedom, 100 * e.max_error(), measured.id(worst),
      measured.frequency_hz(worst), e.pairing.model_for(static_cast<int>(worst)) + 1,
      e.model_frequency_hz(worst), r.reduced_chi2, r.degrees_of_freedom, 100 * r.final.max_error(),
      r.final.pairing.pairs.size(), measured.frequency_hz.size());
}

namespace {

// Kuhn's augmenting path from measured mode i over `candidates` (model columns, nearest first):
// whether i gets a partner in `partner_of` (model column -> measured mode, -1 free).
bool augment(int i, const std::vector<std::vector<int>>& candidates, std::vector<int>& partner_of,
             std::vector<char>& seen) {
  for (const int j : candidates[static_cast<size_t>(i)]) {
    if (seen[static_cast<size_t>(j)]) continue;
    seen[static_cast<size_t>(j)] = 1;
    const int other = partner_of[static_cast<size_t>(j)];
    if (other < 0 || augment(other, candidates, partner_of, seen)) {
      partner_of[static_cast<size_t>(j)] = i;
      return true;
    }
  }
  return false;
}

}  // namespace

// Why undecided pairs look like frequencies in rad/s read as Hz, or "" (linear_signs.h). A true
// Hz table cannot be named so unless its lowest mode is above 2 pi / (1 + w) times the model's
// lowest visible mode (4.19 times it at w = 0.5; the example beam's 128 Hz, divided by 2 pi, is
// 20 Hz, against its first elastic mode at 121 Hz).
std::string undecided_units(const MeasuredModes& measured, const LinearUpdateOptions& options,
                            const LinearUpdateSummary& s) {
  const bool misfit = fitted(s) && s.degrees_of_freedom >= 1 &&
                      s.reduced_chi2 > reduced_chi2_limit(s.degrees_of_freedom);
  if (s.status != LinearUpdateStatus::kAmbiguous && !misfit) return "";
  return angular_units(measured, options, s.start);
}

// Why a table of frequencies alone looks like rad/s read as Hz before any fit, or ""
// (linear_signs.h): angular_units() at the start.
std::string units_before_fit(const model::Model& model, const std::vector<std::string>& names,
                             const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                             const LinearUpdateOptions& options, LinearEvaluation& start) {
  if (measured.frequency_hz.size() < 3 || (measured.shapes.array().abs() > 0.0).any()) return "";
  const StiffnessSets sets(model, names);
  const LinearProblem p = make_problem(sets, model, names, sensors, measured, options);
  p.fresh(p.begin().array().log(), start);
  return angular_units(measured, options, start, 0.25);
}

// The rule of undecided_units() at the start `start`, whatever the fit gave.
std::string angular_units(const MeasuredModes& measured, const LinearUpdateOptions& options,
                          const LinearEvaluation& start, double max_window) {
  const Eigen::Index n = measured.frequency_hz.size();
  const Eigen::Index models =
      std::min(start.all_model_frequency_hz.size(), start.model_at_sensors.cols());
  if (n == 0 || models == 0) return "";
  const double to_hz = 0.5 / std::numbers::pi;
  const double window =
      std::min(options.frequency_window > 0 ? options.frequency_window : 0.5, max_window);
  std::vector<char> visible(static_cast<size_t>(models), 1);
  for (const int h : start.hidden)
    if (h >= 0 && h < static_cast<int>(models)) visible[static_cast<size_t>(h)] = 0;
  // Each mode's candidates divided by 2 pi, nearest in ln f first.
  std::vector<std::vector<int>> candidates(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const double f = to_hz * measured.frequency_hz(i);
    const bool shape = (measured.shapes.col(i).array().abs() > 0.0).count() >= 3;
    std::vector<int>& c = candidates[static_cast<size_t>(i)];
    for (Eigen::Index j = 0; j < models; ++j)
      if (visible[static_cast<size_t>(j)] &&
          std::abs(start.all_model_frequency_hz(j) / f - 1) <= window &&
          (!shape || mac(measured.shapes.col(i), start.model_at_sensors.col(j)) >= 0.9))
        c.push_back(static_cast<int>(j));
    std::sort(c.begin(), c.end(), [&](int a, int b) {
      return std::abs(std::log(start.all_model_frequency_hz(a) / f)) <
             std::abs(std::log(start.all_model_frequency_hz(b) / f));
    });
    if (c.empty()) return "";
  }
  std::vector<int> partner_of(static_cast<size_t>(models), -1);
  for (int i = 0; i < static_cast<int>(n); ++i) {
    std::vector<char> seen(static_cast<size_t>(models), 0);
    if (!augment(i, candidates, partner_of, seen)) return "";
  }
  // Read as Hz, the visible model modes below the table's lowest mode by more than the window.
  const double lowest = measured.frequency_hz.minCoeff();
  int below = 0;
  for (Eigen::Index j = 0; j < models; ++j)
    below +=
        visible[static_cast<size_t>(j)] && start.all_model_frequency_hz(j) < (1 - window) * lowest;
  if (below == 0) return "";
  std::vector<int> model_of(static_cast<size_t>(n), -1);
  for (Eigen::Index j = 0; j < models; ++j)
    if (partner_of[static_cast<size_t>(j)] >= 0)
      model_of[static_cast<size_t>(partner_of[static_cast<size_t>(j)])] = static_cast<int>(j);
  // Uncrossed where the windows allow (the Kuhn matching may pair two neighbours crosswise).
  const auto allowed = [&](Eigen::Index i, int j) {
    const std::vector<int>& c = candidates[static_cast<size_t>(i)];
    return std::find(c.begin(), c.end(), j) != c.end();
  };
  for (bool swapped = true; swapped;) {
    swapped = false;
    for (Eigen::Index a = 0; a < n; ++a)
      for (Eigen::Index b = 0; b < n; ++b) {
        int& ja = model_of[static_cast<size_t>(a)];
        int& jb = model_of[static_cast<size_t>(b)];
        if (measured.frequency_hz(a) < measured.frequency_hz(b) && ja > jb && allowed(a, jb) &&
            allowed(b, ja)) {
          std::swap(ja, jb);
          swapped = true;
        }
      }
  }
  std::vector<std::string> pairs;
  double farthest = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const int j = model_of[static_cast<size_t>(i)];
    const double f = to_hz * measured.frequency_hz(i);
    farthest = std::max(farthest, std::abs(start.all_model_frequency_hz(j) / f - 1));
    pairs.push_back(fmt::format("{} ({:.5g} Hz) with model mode {} ({:.5g} Hz)", measured.id(i), f,
                                j + 1, start.all_model_frequency_hz(j)));
  }
  return fmt::format(
      "the frequencies look like angular frequencies (rad/s) read as Hz: divided by 2 pi, each "
      "measured mode has a model mode of its own at the start within {:.3g} % (test mode {}), "
      "while read as Hz the table's lowest mode ({:.5g} Hz) lies above {} visible model mode{} "
      "by more than the frequency window ({:g} %), none of them measured: give frequency_hz in "
      "Hz (rad/s divided by 2 pi)",
      100 * farthest, fmt::join(pairs, ", "), lowest, below, below == 1 ? "" : "s", 100 * window);
}

}  // namespace jointlab::correlate::detail
