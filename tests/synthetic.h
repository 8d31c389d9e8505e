// Synthetic ring-downs with a prescribed backbone (method.md section 3).
//
// Each mode follows the slow flow
//   da/dt = -zeta(a) omega_n(a) a,   dtheta/dt = omega_n(a) sqrt(1 - zeta(a)^2),
// integrated by classical Runge-Kutta at the sample rate (the flow varies on the
// scale of 1/sigma, hundreds of samples, so the step error is far below 1e-10).
// The displacement is a cos(theta); velocity and acceleration are its exact time
// derivatives (chain rule through the flow), not numerical differences.
#pragma once

#include <functional>
#include <vector>

#include <Eigen/Core>

namespace jointlab::testing {

/// A mode's backbone: natural frequency [rad/s] and damping ratio as functions of amplitude [m].
struct SlowFlowMode {
  std::function<double(double)> omega_n;  ///< omega_n(a) [rad/s]
  std::function<double(double)> zeta;     ///< zeta(a)
  double a0 = 1.0;                        ///< initial displacement amplitude [m]
  double theta0 = 0.0;                    ///< initial phase [rad]
};

/// Samples of one mode: amplitude, displacement, velocity and acceleration.
struct SlowFlowSignal {
  Eigen::VectorXd a;             ///< displacement amplitude a(t_k)
  Eigen::VectorXd displacement;  ///< a cos(theta)
  Eigen::VectorXd velocity;      ///< exact d/dt of displacement
  Eigen::VectorXd acceleration;  ///< exact d2/dt2 of displacement
};

/// Integrates the slow flow at fs for n samples.
SlowFlowSignal slow_flow(const SlowFlowMode& mode, double fs, Eigen::Index n);

/// The acceptance-style test record: three modes, the first strongly nonlinear
/// (frequency falls about 3 % and damping rises from 0.1 % to 0.8 % over 2.5
/// decades of amplitude), white noise at `noise` of the record's peak.
struct ThreeModeRecord {
  double fs = 5120.0;               ///< sample rate [Hz]
  Eigen::VectorXd displacement;     ///< sum of modes plus noise [m]
  Eigen::VectorXd acceleration;     ///< sum of modes plus noise [m/s^2]
  SlowFlowMode first;               ///< the first mode's backbone (the truth)
  Eigen::VectorXd first_amplitude;  ///< the first mode's a(t_k) [m]
};

/// Builds the three-mode record; `seed` selects the noise realisation and `higher`
/// scales the amplitudes of modes 2 and 3 (1: the third mode dominates the acceleration).
ThreeModeRecord three_mode_record(double f1_hz, double duration_s, double noise, unsigned seed,
                                  double higher = 1.0);

}  // namespace jointlab::testing
