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

/// Two modes in 1:2 internal resonance (issue 26's double beam): mode coordinates x1 at
/// f1 = 122 Hz (damping 0.3 %) and x2 at f2 = 243 Hz (damping `zeta2`) with the quadratic
/// coupling of the potential alpha/2 x1^2 x2:
///   x1'' + 2 z1 w1 x1' + w1^2 x1 + alpha x1 x2 = 0,
///   x2'' + 2 z2 w2 x2' + w2^2 x2 + alpha/2 x1^2 = 0,
/// from x1 = x10, x2 = 0 at rest (mode 1 struck), classical Runge-Kutta with 8 steps per
/// sample. Energy flows from mode 1 to mode 2 and back while x1 is large, and mode 1's
/// square drives mode 2's coordinate at exactly twice mode 1's frequency. The sensor reads
/// v1 + 0.7 v2 after 0.05 s of pre-trigger, plus white noise of standard deviation `noise`.
struct InternalResonanceRecord {
  double fs = 5120.0;          ///< sample rate [Hz]
  Eigen::VectorXd velocity;    ///< the sensor [m/s]
  Eigen::VectorXd amplitude1;  ///< mode 1's amplitude sqrt(x1^2 + (v1 / w1)^2) [m]
  Eigen::VectorXd amplitude2;  ///< mode 2's amplitude sqrt(x2^2 + (v2 / w2)^2) [m]
  double f1_hz = 122.0, f2_hz = 243.0, zeta1 = 0.003;
};

/// Builds the internal-resonance record (`duration_s` long, noise realisation `seed`). Mode i
/// starts at x_i = A_i cos(phase_i), x_i' = -w_i A_i sin(phase_i) (A_1 = x10, A_2 = x20): a
/// hammer blow, from rest at x = 0 with the velocity stepping at the impact, is phase -pi/2.
/// Mode 2 lies at `f2_hz` (243 Hz, 1 Hz below 2 f1, by default); mode 1's damping is `zeta1`.
InternalResonanceRecord internal_resonance_record(double alpha, double x10, double zeta2,
                                                  double noise, unsigned seed,
                                                  double duration_s = 4.0, double x20 = 0.0,
                                                  double phase2 = 0.0, double phase1 = 0.0,
                                                  double f2_hz = 243.0, double zeta1 = 0.003);

}  // namespace jointlab::testing
