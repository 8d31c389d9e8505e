// What the Iwan objective's files share (internal): each measured point's stated one-sigma
// uncertainties, which the residuals, the misfit evidence and the floor count read alike.
#pragma once

#include <Eigen/Core>

#include "jointlab/correlate/iwan_backbone.h"

namespace jointlab::correlate::iwan_detail {

/// Point j's stated one-sigma uncertainties (frequency [Hz], damping ratio; 0: none stated): the
/// file's expanded uncertainty over its coverage factor (process's k = 3 was read as sigma, and
/// the reduced chi-square came out 9 times too small).
inline Eigen::Vector2d stated_sigma(const MeasuredBackbone& c, Eigen::Index j) {
  return Eigen::Vector2d(c.frequency_std_hz(j), c.damping_std(j)) / c.coverage_factor;
}

}  // namespace jointlab::correlate::iwan_detail
