// Standard deviations of the fitted sets at the result and the chi-square's scale
// (linear_uncertainty.h).
#include "jointlab/correlate/linear_uncertainty.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/students_t.hpp>

#include "jointlab/correlate/linear_collinear.h"
#include "jointlab/correlate/noise_limits.h"

namespace jointlab::correlate::detail {
namespace {

// The reduced chi-square that noise of the stated size exceeds in one fit in 6.3 (the one-sided
// 1-sigma point of the chi-square distribution over degrees_of_freedom > 0, divided by it: 1.72
// over 3).
double reduced_chi2_one_sigma(int degrees_of_freedom) {
  const boost::math::chi_squared chi2(degrees_of_freedom);
  return boost::math::quantile(chi2, 0.841344746) / degrees_of_freedom;
}

// The factor sqrt(1 + w (nu / (nu - 2) - 1)) by which standard deviations scaled by a reduced
// chi-square c > 1 over nu degrees of freedom are widened for Student's t, or 0 where nu <= 2
// (none can be stated). The share w grows from 0 at c = 1 (the scatter the stated noise gives
// on average) to 1 at its one-sided 1-sigma point (1.72 over 3 degrees of freedom): in between
// the stated noise is still a likely cause. Linearised (a normal error over the scale
// max(1, c) sigma^2, 3 degrees of freedom), noise as stated gives z-scores of RMS 0.93 without
// the t, 0.83 with it in full from c = 1 on (a sigma 1.73 times wider at c = 1.01 than at 0.99)
// and 0.86 with it in part; noise 1.5 to 5 times the stated 1.17-1.56 without, 0.93-0.99 in
// full and 0.98-1.03 in part.
double t_widening(double reduced_chi2, int degrees_of_freedom) {
  if (!(reduced_chi2 > 1)) return 1;
  const std::optional<double> t = student_t_variance(degrees_of_freedom);
  if (!t) return 0;
  const double w =
      std::clamp((reduced_chi2 - 1) / (reduced_chi2_one_sigma(degrees_of_freedom) - 1), 0.0, 1.0);
  return std::sqrt(1 + w * (*t - 1));
}

}  // namespace

double sigma_variance(const LinearProblem& p, const LinearUpdateSummary& s) {
  const double sf = p.options.frequency_std;
  return sf * sf * (s.sigma_from_scatter ? s.reduced_chi2 * s.t_widening * s.t_widening : 1.0);
}

// A profile's rise of 9 marks 3 standard deviations of a normal error; where the scale is the
// scatter's, the error over its widened sigma follows Student's t, whose 0.99865 point lies
// farther out: 5.51 over 5 degrees of freedom, 4.27 of its widened sigmas (a rise of 18.2). A
// profile walked only to 9 then stops short where it flattens: the 16-rivet stacked beam with
// one tip sensor and its frequency noise understated 3x (0.3 % as 0.1 %) stated its bolts at
// 8.14e6 +/- 63.1 % (truth 6e7, 3.2 of those off) and its rivets 2.66 off, reduced chi-square
// 2.85 over 5, below its limit; walked to 18.2, the bolts are bounded from below only (no
// sigma, as in 18 of 19 seeds) and the rivets 3.70e7 +/- 25.9 % (2.37 off).
double three_sigma_rise(const LinearUpdateSummary& s) {
  if (!s.sigma_from_scatter || !(s.t_widening > 1)) return 9;
  const int nu = s.degrees_of_freedom;
  const std::optional<double> t = student_t_variance(nu);
  if (!t) return 9;
  const double q = boost::math::quantile(boost::math::students_t(nu), 0.99865) / std::sqrt(*t);
  const double w = std::clamp((s.t_widening * s.t_widening - 1) / (*t - 1), 0.0, 1.0);
  return 9 + w * (q * q - 9);
}

// What the standard deviations of a scatter-set scale are, for the report: "rest on the
// scatter: widened by sqrt(2.21) and, as that scale is itself estimated from 3 degrees of
// freedom (Student's t), by 1.73", or why none is stated.
std::string scatter_widening(const LinearUpdateSummary& s) {
  const int nu = s.degrees_of_freedom;
  const char* plural = nu == 1 ? "" : "s";
  if (s.t_widening == 0)
    return fmt::format(
        "would rest on the scatter, but a scale estimated from {} degree{} of freedom leaves an "
        "error over its sigma with no finite standard deviation (Student's t needs more than 2): "
        "none is stated; add measured modes",
        nu, plural);
  const double full = std::sqrt(*student_t_variance(nu));
  if (s.t_widening >= full * (1 - 1e-12))
    return fmt::format(
        "rest on the scatter: widened by sqrt({:.3g}) and, as that scale is itself estimated "
        "from {} degree{} of freedom (Student's t), by {:.3g}",
        s.reduced_chi2, nu, plural, s.t_widening);
  const boost::math::chi_squared chi2(nu);
  return fmt::format(
      "rest on the scatter: widened by sqrt({:.3g}) and, as that scale is itself estimated from "
      "{} degree{} of freedom, by {:.3g} (Student's t's {:.3g} in part: noise of the stated size "
      "still scatters this much in one fit in {:.2g})",
      s.reduced_chi2, nu, plural, s.t_widening, full,
      1 / boost::math::cdf(boost::math::complement(chi2, s.reduced_chi2 * nu)));
}

// Standard deviations of the fitted sets at the result (its Jacobian). Sets acting together
// (sensitivity_directions) have none, the combination they determine is named, and the degrees
// of freedom count the combinations determined. Where the frequencies of
// the least-squares fit `ls` scatter more than their stated uncertainty gives (reduced
// chi-square above 1; at the least-squares point: a rule that then moves to its tolerance adds
// errors on purpose, not scatter), the scale is the scatter's: the covariance is scaled by the
// reduced chi-square and, as that scale is itself estimated from nu = pairs - fitted degrees of
// freedom, widened by Student's t's variance nu / (nu - 2) (student_t_variance); none is stated
// where nu <= 2. Without the t, twoj's two joints fitted to five modes at three sensors with
// 0.5 % noise and the default 0.1 % gave z-scores of RMS 1.63 and 1.37 over 40 seeds (largest
// |z| 4.25): t over 3 degrees of freedom has a standard deviation of sqrt(3).
void report_uncertainty(const LinearProblem& p, const Eigen::VectorXd& theta,
                        const LinearEvaluation& at, const LinearEvaluation& ls,
                        const std::vector<char>& held, LinearUpdateSummary& s) {
  std::vector<int> fitted;
  s.collinear.clear();
  for (int k = 0; k < p.size(); ++k) {
    s.parameters[k].relative_std.reset();
    s.parameters[k].slope_std.reset();
    s.parameters[k].acts_with.clear();
    if (!held[static_cast<size_t>(k)] && !s.parameters[k].flat) fitted.push_back(k);
  }
  // Each row over its own mode's sigma: (J^T W^2 J)^-1 frequency_std^2 is the covariance.
  const Eigen::MatrixXd jw = p.weighted_jacobian(at);
  Eigen::MatrixXd j(jw.rows(), static_cast<Eigen::Index>(fitted.size()));
  for (size_t c = 0; c < fitted.size(); ++c) j.col(c) = jw.col(fitted[c]);
  const SensitivityDirections d =
      fitted.empty() ? SensitivityDirections{} : sensitivity_directions(j);
  const int pairs = static_cast<int>(ls.pairing.pairs.size());
  s.degrees_of_freedom = pairs - d.rank;
  const double sf = p.options.frequency_std;
  s.frequency_std = sf;
  s.mode_frequency_std = mode_sigma(p.measured, sf);
  s.chi2 = ls.weighted_squared_norm() / (sf * sf);
  s.reduced_chi2 = s.degrees_of_freedom > 0 ? s.chi2 / s.degrees_of_freedom : 0.0;
  s.sigma_from_scatter = s.degrees_of_freedom > 0 && s.reduced_chi2 > 1;
  s.t_widening = s.sigma_from_scatter ? t_widening(s.reduced_chi2, s.degrees_of_freedom) : 1.0;
  if (fitted.empty()) return;
  const std::string noise =
      stated_noise(sf, s.mode_frequency_std, [&](Eigen::Index i) { return p.measured.id(i); });
  // A model-form error only where noise of the stated size would rarely scatter so far (above
  // the one-sided 3-sigma point of the chi-square distribution: 4.45 over 4 degrees of freedom;
  // "above 1" was said for 7 of 20 fits of exact data with the stated noise).
  if (s.degrees_of_freedom > 0 && s.reduced_chi2 > reduced_chi2_limit(s.degrees_of_freedom)) {
    s.warnings.push_back(fmt::format(
        "the frequencies scatter beyond their stated uncertainty ({}): reduced chi-square "
        "{:.3g} over {} degrees of freedom (noise of that size stays below {:.3g} but once in 740 "
        "fits), so the model does not describe them to within it (model-form error); the "
        "standard deviations {}",
        noise, s.reduced_chi2, s.degrees_of_freedom, reduced_chi2_limit(s.degrees_of_freedom),
        scatter_widening(s)));
  }
  Eigen::MatrixXd cov;
  if (s.t_widening > 0) {
    cov = d.inverse * sigma_variance(p, s);
    for (size_t c = 0; c < fitted.size(); ++c) {
      const double v = cov(c, c);
      if (v >= 0 && std::isfinite(v)) s.parameters[fitted[c]].relative_std = std::sqrt(v);
    }
  }
  report_collinear(fitted, theta, j, d, cov, s);
  report_collinear_with_held_flat(p, theta, at, held, fitted, cov, s);
  // (A sign-flipped sensor paired a 505 Hz test mode with a model mode then at 748 Hz, the one
  // pair for the one set, and the fit moved K_T 528-fold to match it exactly, "converged".)
  if (s.degrees_of_freedom == 0 && s.t_widening > 0) {
    // With no degree of freedom left a fit reaches every frequency unless a bound or the
    // pairs stop it: errors beyond 3 sigma at a pair are said (a reversed channel once left
    // 26.6 % with this warning saying the fit matched exactly).
    const double chi2 = ls.weighted_squared_norm() / (sf * sf);
    s.warnings.push_back(
        chi2 > 9.0 * pairs
            ? fmt::format(
                  "{} pair(s) for {} fitted set(s): no degree of freedom is left, and yet the fit "
                  "leaves errors up to {:.3g} % (chi-square {:.3g}): a bound stopped it, or no "
                  "stiffness meets these pairs; nothing checks the pairs or the model, so add "
                  "measured modes or sensors",
                  pairs, fitted.size(), 100 * ls.max_error(), chi2)
            : fmt::format(
                  "{} pair(s) for {} fitted set(s): no degree of freedom is left, so the fit "
                  "matches the frequencies exactly whatever the pairs and nothing checks them or "
                  "the model (the standard deviations only assume the stated {}); add "
                  "measured modes or sensors",
                  pairs, fitted.size(), noise));
  }
}

}  // namespace jointlab::correlate::detail
