// One measured backbone of one mode from one hit, with the time of each point: what the
// scatter summaries, the joint-slip screen and the Iwan targets of a campaign share.
// Units: time in seconds after the record's start, amplitude in the SI unit of the
// amplitude quantity, frequency in Hz, damping ratio as a fraction.
#pragma once

#include <string>

#include <Eigen/Core>

namespace jointlab::correlate {

/// One backbone of one mode from one hit.
struct Curve {
  std::string id;                  ///< the hit (file stem)
  std::string group;               ///< the hit's group (force level)
  Eigen::VectorXd time_s;          ///< time of each point after the record's start [s]
  Eigen::VectorXd amplitude;       ///< amplitude of each point [SI], > 0
  Eigen::VectorXd frequency_hz;    ///< natural frequency of each point [Hz]
  Eigen::VectorXd damping;         ///< damping ratio of each point
  bool has_linear = false;         ///< the linear values below are set
  double linear_frequency_hz = 0;  ///< the hit's low-amplitude frequency [Hz]
  double linear_damping = 0;       ///< the hit's low-amplitude damping ratio
};

}  // namespace jointlab::correlate
