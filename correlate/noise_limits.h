// How far a fit's scatter may go before its stated noise is in doubt, and how much a standard
// deviation estimated from few residuals widens: the chi-square and Student's t limits the
// linear update, the Iwan update and the measured side's spread test share.
#pragma once

#include <optional>

namespace jointlab::correlate {

/// The reduced chi-square that noise of the stated size exceeds once in 740 fits (the one-sided
/// 3-sigma point of the chi-square distribution over degrees_of_freedom > 0, divided by it).
double reduced_chi2_limit(int degrees_of_freedom);

/// The ratio of two fits' reduced chi-squares (over `degrees_of_freedom_a` and
/// `degrees_of_freedom_b` > 0) that noise of one unknown size exceeds once in 740 pairs of fits:
/// the one-sided 3-sigma point of Fisher's F over those degrees of freedom (740 over 2 and 2).
/// It tells two fits apart without the stated noise, which their ratio does not use.
double variance_ratio_limit(int degrees_of_freedom_a, int degrees_of_freedom_b);

/// nu / (nu - 2), the variance of Student's t over nu degrees of freedom: a parameter's error over
/// a standard deviation whose scale was estimated from the residuals of a fit with nu degrees of
/// freedom left follows t_nu, not a normal, so such a variance is widened by it. Nothing where
/// nu <= 2 (an infinite variance: no standard deviation can be stated).
std::optional<double> student_t_variance(double degrees_of_freedom);

}  // namespace jointlab::correlate
