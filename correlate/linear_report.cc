// The linear update's report text and its refusals (linear_update.h:
// LinearUpdateSummary::report, linear_refusal).
#include <algorithm>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <boost/math/distributions/chi_squared.hpp>

#include "jointlab/correlate/linear_uncertainty.h"
#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/noise_limits.h"

namespace jointlab::correlate {

using detail::scatter_widening;
using detail::stated_noise;

namespace {

// Where the degrees of freedom are too few to check the stated noise: how often noise three
// times the stated would scatter as little as the result's (a chi-square of dof * reduced / 9
// or less), when that is 5 % or more; else "". The chain and rotor with 0.3 % noise and the
// default 0.1 % stated, one degree of freedom left, gave a reduced chi-square of 0.99 and kg at
// +/- 0.344 %, 6.5 of those from the truth: three times the noise scatters so little 26 % of
// the time.
std::string few_degrees_note(const LinearUpdateSummary& s) {
  if (s.degrees_of_freedom <= 0 || !(s.reduced_chi2 >= 0)) return "";
  const boost::math::chi_squared dist(s.degrees_of_freedom);
  const double p = boost::math::cdf(dist, s.degrees_of_freedom * s.reduced_chi2 / 9);
  if (!(p >= 0.05)) return "";
  return fmt::format(
      ", which {} cannot check: noise three times larger scatters as little {:.0f} % of the "
      "time, so give the frequencies' own uncertainty (--frequency-std)",
      s.degrees_of_freedom == 1 ? "one degree of freedom"
                                : fmt::format("{} degrees of freedom", s.degrees_of_freedom),
      100 * p);
}

// One row of the report's table per measured mode: its frequency, its partner's and the error.
std::string mode_rows(const LinearEvaluation& final) {
  std::string out;
  for (Eigen::Index i = 0; i < final.residuals.size(); ++i) {
    const int j = final.pairing.model_for(static_cast<int>(i));
    const double fe = final.measured_frequency_hz(i);
    if (j < 0) {
      out += fmt::format("  {:>8}  {:>10.5g}  unpaired\n", final.measured_id(i), fe);
      continue;
    }
    const std::optional<double> mac = final.pair_mac(i);
    out +=
        fmt::format("  {:>8}  {:>10.5g}  {:>10}  {:>12.5g}  {:>9.3f}  {}\n", final.measured_id(i),
                    fe, j + 1, final.model_frequency_hz(i), 100 * final.residuals(i),
                    mac ? fmt::format("{:.3f}", *mac) : "  -  (no shape)");
  }
  return out;
}

// The report's line on one set: start, value, sensitivity and what the frequencies say of it
// (`t_widening` 0: no standard deviation stated). Where the pairs cannot be decided (`undecided`)
// there is no value (the ambiguity line says why, and where the fits differ). Before, such a report
// said "iwan.rivet: 1e+07 -> 0", a value no fit gave.
std::string parameter_line(const ParameterReport& p, double t_widening, double level,
                           bool undecided) {
  if (undecided)
    return fmt::format("  {}: {:.6g} -> not decided (the pairs cannot be decided)\n", p.name,
                       p.start);
  std::string what;
  if (p.flat)
    what = p.smallest_within_tolerance > 0 ? "  FLAT (not identified by the frequencies)"
                                           : "  FLAT (not identified by the frequencies): held";
  else if (p.held)
    what = "  held";
  else if (!p.acts_with.empty())
    what = fmt::format("  NOT IDENTIFIED alone: acts together with {} (below)",
                       fmt::join(p.acts_with, ", "));
  else if (p.one_sided != 0)
    what = fmt::format("  NOT IDENTIFIED: bounded from {} only (below)",
                       p.one_sided > 0 ? "below" : "above");
  else if (p.relative_std && p.slope_std)
    what = fmt::format(
        "  +/- {:.3g} % ({}; the local slope's {:.3g} % understates it)", 100 * *p.relative_std,
        level == 9 ? std::string("a third of where the chi-square's profile rises by 9")
                   : fmt::format("a third of where the chi-square's profile reaches Student's t's "
                                 "3 standard deviations, a rise of {:.3g}",
                                 level),
        100 * *p.slope_std);
  else if (p.relative_std)
    what = fmt::format("  +/- {:.3g} %", 100 * *p.relative_std);
  else if (t_widening == 0)
    what = "  no standard deviation (see the reduced chi-square)";
  // A set held back from where the fit took it is flat there, not here: both are said.
  const std::string drifted = p.drifted_to > 0
                                  ? fmt::format(" here, {:.3g} at {:.6g} where the fit took it",
                                                p.drifted_sensitivity, p.drifted_to)
                                  : "";
  std::string out = fmt::format("  {}: {:.6g} -> {:.6g}  sensitivity {:.3g}{}{}", p.name, p.start,
                                p.value, p.sensitivity, drifted, what);
  if (p.smallest_within_tolerance > 0) out += "  (smallest within tolerance)";
  out += "\n";
  return out;
}

}  // namespace

std::string LinearUpdateSummary::report() const {
  static const char* names[] = {"converged",
                                "iteration limit",
                                "no mode paired",
                                "failed",
                                "pairs cannot be decided",
                                "measured shapes refused",
                                "pairs unconfirmed by the shapes"};
  const std::string how =
      status != LinearUpdateStatus::kPairsUnconfirmed
          ? names[static_cast<int>(status)]
          : fmt::format("{} (the fit {})", names[static_cast<int>(status)],
                        fit_converged ? "converged" : "reached its iteration limit");
  // "converged" where every set ended held says nothing of the sets: a layout whose modes no
  // set moves (y sensors on a stacked beam's in-plane modes) read "converged" with each set
  // "1e+07 -> 1e+07".
  const bool none_fitted =
      !parameters.empty() && std::all_of(parameters.begin(), parameters.end(),
                                         [](const ParameterReport& p) { return p.held; });
  std::string out = fmt::format(
      "linear update ({}): {}, {} iterations in {} round{}, cost {:.4g} -> {:.4g}, {} of {} "
      "measured modes paired, largest frequency error {:.3g} %{}\n",
      rule, how, iterations, rounds, rounds == 1 ? "" : "s", initial_cost, final_cost,
      final.pairing.pairs.size(), final.residuals.size(), 100 * final.max_error(),
      none_fitted && status == LinearUpdateStatus::kConverged
          ? "; no set fitted: each is held (below), so these modes identify none of them"
          : "");
  if (!ambiguity.empty()) out += fmt::format("  {}\n", ambiguity);
  if (!restarts.empty()) out += fmt::format("  {}\n", restarts);
  if (!shape_problem.empty()) out += fmt::format("  {}\n", shape_problem);
  if (!unconfirmed.empty()) out += fmt::format("  {}\n", unconfirmed);
  out += "  measured  f_exp [Hz]  model mode  f_model [Hz]  error [%]    MAC\n";
  out += mode_rows(final);
  const auto id = [&](Eigen::Index i) { return final.measured_id(i); };
  const std::string noise = stated_noise(frequency_std, mode_frequency_std, id);
  if (noise != stated_noise(frequency_std, Eigen::VectorXd(), id))
    out += fmt::format(
        "  frequency uncertainty: {} (a mode whose files disagree: its residual is divided by its "
        "own, so it weighs less and widens only the sets it fixes)\n",
        noise);
  if (degrees_of_freedom > 0) {
    // Scatter below the 3-sigma level does not make the stated noise right: with few degrees of
    // freedom, noise several times larger often scatters as little.
    const double limit = reduced_chi2_limit(degrees_of_freedom);
    const bool any_fitted = std::any_of(parameters.begin(), parameters.end(),
                                        [](const ParameterReport& p) { return !p.held; });
    out += fmt::format(
        "  reduced chi-square {:.3g} over {} degrees of freedom{}\n", reduced_chi2,
        degrees_of_freedom,
        reduced_chi2 > limit || !any_fitted ? ""
        : reduced_chi2 > 1
            ? fmt::format(" (more than noise of the stated {} gives on average, below {:.3g}, "
                          "its 3-sigma level: the scatter cannot tell whether the noise is that "
                          "or larger, so the standard deviations {})",
                          noise, limit, scatter_widening(*this))
            : fmt::format(" (no more than noise of the stated {} gives; the standard "
                          "deviations assume that noise{})",
                          noise, few_degrees_note(*this)));
  }
  for (const ParameterReport& p : parameters)
    out += parameter_line(p, t_widening, detail::three_sigma_rise(*this),
                          status == LinearUpdateStatus::kAmbiguous);
  for (const std::string& w : warnings) out += fmt::format("  WARNING: {}\n", w);
  return out;
}

std::string linear_refusal(const LinearUpdateSummary& summary, const LinearUpdateOptions& options,
                           const std::string& source) {
  if (summary.status == LinearUpdateStatus::kAmbiguous && !summary.units.empty())
    return fmt::format("{}{}; were they in Hz, the pairs cannot be decided: {}",
                       source.empty() ? "" : source + ": ", summary.units, summary.ambiguity);
  if (summary.status == LinearUpdateStatus::kAmbiguous)
    return "the pairs cannot be decided: " + summary.ambiguity;
  if (summary.status == LinearUpdateStatus::kShapesRefused)
    return fmt::format("{}{}", source.empty() ? "" : source + ": ", summary.shape_problem);
  if (summary.status != LinearUpdateStatus::kTooFewPairs) return "";
  return fmt::format(
      "no measured mode{} pairs with a model mode (MAC >= {}, frequency within {:g} %)",
      source.empty() ? "" : " of " + source, options.mac_threshold, 100 * options.frequency_window);
}

}  // namespace jointlab::correlate
