// Elementary functions over whole arrays, for the per-sample loops of an extraction.
//
// Each function fills `out` (same length as its inputs) with what the scalar std::
// function gives element by element, to within glibc's vector maths accuracy (at most
// 4 ulp; std:: is within 1): the envelope's logarithm and phase, the gain correction's
// model and its logarithm take one call each instead of a libm call a sample.
#pragma once

#include <Eigen/Core>

namespace jointlab::signal {

/// out_i = atan2(y_i, x_i) (the argument of x_i + i y_i, in [-pi, pi]).
void atan2_array(const Eigen::Ref<const Eigen::ArrayXd>& y,
                 const Eigen::Ref<const Eigen::ArrayXd>& x, Eigen::Ref<Eigen::ArrayXd> out);

/// out_i = exp(x_i).
void exp_array(const Eigen::Ref<const Eigen::ArrayXd>& x, Eigen::Ref<Eigen::ArrayXd> out);

/// out_i = log(x_i).
void log_array(const Eigen::Ref<const Eigen::ArrayXd>& x, Eigen::Ref<Eigen::ArrayXd> out);

/// sin_i = sin(x_i), cos_i = cos(x_i).
void sincos_array(const Eigen::Ref<const Eigen::ArrayXd>& x, Eigen::Ref<Eigen::ArrayXd> sin,
                  Eigen::Ref<Eigen::ArrayXd> cos);

/// out_i = erfc(x_i).
void erfc_array(const Eigen::Ref<const Eigen::ArrayXd>& x, Eigen::Ref<Eigen::ArrayXd> out);

}  // namespace jointlab::signal
