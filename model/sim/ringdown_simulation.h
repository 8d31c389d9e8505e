// Impact ring-down of a model with Iwan joints: implicit time integration of
//   M u'' + C u' + K_lin u - B^T h(B u, history) = e_d p(t),
// K_lin = K + every joint at its linear stiffness (springs k, Iwan K_T; model_file.h),
// r = B u the Iwan joint coordinates (row j of B is e_a - e_b, or e_a to ground; Iwan
// elements on the same pair of DOFs share one coordinate) and h_j = sum over its elements
// of K_T r - F(r, history) >= 0 the softening, F the exact Masing force (iwan_history.h).
// p(t) is a half-sine hammer pulse on DOF d: p = P sin(pi (t - t0) / T) on [t0, t0 + T].
// Units: m, kg, N, s; rotational DOFs in rad with their moment units.
//
// The linear part is diagonalised once by its normal modes (u = Phi eta, Phi^T M Phi = I,
// Phi^T K_lin Phi = Omega^2; rigid-body modes included), with modal or Rayleigh damping
// c_i = 2 zeta omega_i + alpha + beta omega_i^2 (C = alpha M + beta K_lin plus modal zeta
// on elastic modes). Newmark's average acceleration rule (gamma = 1/2, beta = 1/4:
// unconditionally stable, no numerical damping, period error (omega dt)^2 / 12) gives per
// step eta = eta_p + diag(1/k_hat) Psi^T h(r), Psi = B Phi, so the joint coordinates solve
//   S^{-1} (r - r_p) - h(r) = 0,   S = Psi diag(1/k_hat) Psi^T,   r_p = Psi eta_p,
// a Newton problem of size n_J (symmetric positive definite Jacobian S^{-1} - diag(h'),
// line search on the step's incremental potential). S^{-1} is formed once per run.
//
// Energy balance (per run): input W = int p u_d' dt equals kinetic T = 1/2 u'^T M u' plus
// strain V (linear springs and structure, plus the energy stored in the Iwan sliders) plus
// the energy the joints dissipate D_J plus the energy C dissipates D_C. The scheme keeps
// this exactly for the linear part; what remains, W - T - V - D_J - D_C, is the quadrature
// error of the joint work over the steps (it falls as dt^2) and the Newton tolerance.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/model/model_file.h"

namespace jointlab::model {

/// A half-sine hammer pulse on one DOF.
struct HalfSinePulse {
  Eigen::Index dof = 0;    ///< loaded matrix DOF (0-based)
  double force = 0;        ///< peak force P [N]
  double duration = 5e-4;  ///< pulse length T [s]
  double start = 0.01;     ///< time the pulse starts t0 [s]

  /// The force at time t [N].
  double operator()(double t) const;
  /// The pulse's impulse 2 P T / pi [N s].
  double impulse() const;
};

/// Settings of simulate_ringdown().
struct SimulationOptions {
  HalfSinePulse pulse;                ///< the impact
  std::vector<Eigen::Index> sensors;  ///< DOFs whose motion is recorded
  double fs = 0;                      ///< output sample rate [Hz]
  double duration = 0;                ///< record length [s]; samples at k / fs, k < fs duration
  int substeps = 0;                   ///< integration steps per sample; 0: automatic (below)
  double frequency_error = 1e-5;      ///< automatic substeps: (omega_1 dt)^2/12 at most this
  double modal_damping = 0;           ///< zeta of every elastic mode (fraction)
  double rayleigh_mass = 0;           ///< alpha of C = alpha M + beta K_lin [1/s]
  double rayleigh_stiffness = 0;      ///< beta of C = alpha M + beta K_lin [s]
  double output_cutoff_hz = 0;        ///< modes above it are left out of the sensor signals
                                      ///< (an ideal anti-aliasing filter); 0: 0.45 fs
  double newton_tolerance = 1e-11;    ///< Newton stops when |dr| <= this * |r| (max norms)
  int max_newton_iterations = 50;     ///< per step
  std::function<void(const std::string&)> progress;  ///< optional: a line per 10 % of the run

  /// What is wrong with these options for a model of `size` DOFs, or "".
  std::string error(Eigen::Index size) const;
};

/// Energy bookkeeping of a run [J].
struct EnergyBalance {
  double input = 0;               ///< work of the applied force
  double kinetic = 0;             ///< 1/2 u'^T M u' at the end
  double strain = 0;              ///< linear strain plus Iwan stored energy at the end
  double joint_stored = 0;        ///< the Iwan sliders' share of strain
  double joint_dissipated = 0;    ///< dissipated by the Iwan joints
  double damping_dissipated = 0;  ///< dissipated by the linear damping C

  /// input - kinetic - strain - joint_dissipated - damping_dissipated.
  double closure() const;
  /// |closure| / input (0 when nothing was put in).
  double relative_closure() const;
  /// One line with every term and the closure error.
  std::string report() const;
};

/// How a run ended.
enum class SimulationStatus {
  kOk,            ///< the whole record was integrated
  kNewtonFailed,  ///< a step's joint problem did not converge; the record is cut there
};

/// What happened in a simulate_ringdown() call.
struct SimulationSummary {
  SimulationStatus status = SimulationStatus::kOk;  ///< termination
  std::string message;                              ///< one line on the termination
  double dt = 0;                                    ///< integration step [s]
  int substeps = 0;                                 ///< steps per output sample
  long steps = 0;                                   ///< steps taken
  long newton_iterations = 0;                       ///< factorizations over every step
  int max_step_iterations = 0;                      ///< the most any step needed
  int modes = 0;                                    ///< modes integrated (rigid included)
  int rigid_modes = 0;                              ///< rigid-body modes among them
  int output_modes = 0;                             ///< modes in the sensor signals
  int joint_coordinates = 0;                        ///< n_J
  double lowest_elastic_hz = 0;                     ///< first elastic linear frequency [Hz]
  double max_joint_displacement = 0;                ///< largest |r_j| over the run [m]
  double max_phi_ratio = 0;                         ///< largest |r_j| / phi_max over the run
  EnergyBalance energy;                             ///< energy at the end of the run

  /// A short paragraph: termination, step, work, energy balance.
  std::string report() const;
};

/// The recorded motion at the sensors, sampled at fs.
struct SimulatedResponse {
  double fs = 0;                 ///< sample rate [Hz]
  Eigen::MatrixXd acceleration;  ///< samples x sensors [m/s^2 or rad/s^2]
  Eigen::MatrixXd velocity;      ///< samples x sensors [m/s or rad/s]
  Eigen::MatrixXd displacement;  ///< samples x sensors [m or rad]
  Eigen::VectorXd force;         ///< the pulse at each sample [N]
};

/// Simulates the impact; InputError if the options do not fit the model. A run cut short
/// (summary status) returns the samples integrated so far.
SimulatedResponse simulate_ringdown(const Model& model, const SimulationOptions& options,
                                    SimulationSummary* summary);

}  // namespace jointlab::model
