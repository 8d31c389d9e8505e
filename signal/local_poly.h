// Weighted local polynomial regression: smooth value and slope of y(t) at a centre.
//
// Around a centre c with half-width h, samples (t_i, y_i) with |t_i - c| < h are
// fitted by y ~ sum_{j<=p} beta_j tau^j, tau = (t - c)/h, with biweight weights
// w_i = (1 - tau_i^2)^2. The slope at c is beta_1 / h (analytic derivative of the
// fit, never a difference of noisy samples). Its statistical standard deviation
// comes from the weighted residuals through the sandwich formula
//   Cov(beta) = s^2 (X'WX)^-1 (X'W^2X) (X'WX)^-1,   s^2 = sum w r^2 / sum w,
// multiplied by `correlation` (how many consecutive samples make one independent
// one, e.g. the sample rate over the noise bandwidth). The value's model (bias)
// error is estimated by refitting at degree p + 1 and the slope's at degree p + 2:
// in a symmetric window the slope at the centre is set by the odd powers alone,
// so one more even power would leave it where it is.
#pragma once

#include <array>

#include <Eigen/Core>

namespace jointlab::signal {

/// Result of one local fit.
struct LocalFit {
  double value = 0.0;         ///< fitted y(c)
  double value_std = 0.0;     ///< statistical one-sigma of value
  double value_change = 0.0;  ///< |value(degree p+1) - value(degree p)|: model-error estimate
  double slope = 0.0;         ///< fitted dy/dt at c (degree p)
  double slope_std = 0.0;     ///< statistical one-sigma of slope
  double slope_change = 0.0;  ///< |slope(degree p+2) - slope(degree p)|: model-error estimate
  double residual_rms = 0.0;  ///< weighted RMS of y - fit
  int samples = 0;            ///< samples used
};

/// Fits y(t) on the uniform grid t_i = t_first + i dt around `centre` with half-width h,
/// using every `stride`-th sample (pass the correlation of the strided samples), and
/// evaluates the fit at centre + offset h (|offset| <= 1; off-centre serves record ends).
/// Requires at least degree + 3 samples inside the window (asserts).
LocalFit fit_local(const Eigen::Ref<const Eigen::VectorXd>& y, double t_first, double dt,
                   double centre, double half_width, int degree, double correlation,
                   Eigen::Index stride = 1, double offset = 0.0);

/// The same fit of two series on one grid (the design is built once).
std::array<LocalFit, 2> fit_local_pair(const Eigen::VectorXd& y1, const Eigen::VectorXd& y2,
                                       double t_first, double dt, double centre, double half_width,
                                       int degree, double correlation, Eigen::Index stride = 1,
                                       double offset = 0.0);

/// The same fit of four series on one grid (each series' numbers as fit_local_pair gives them).
std::array<LocalFit, 4> fit_local_quad(const std::array<const Eigen::VectorXd*, 4>& ys,
                                       double t_first, double dt, double centre, double half_width,
                                       int degree, double correlation, Eigen::Index stride = 1,
                                       double offset = 0.0);

}  // namespace jointlab::signal
