// QSMA of one mode evaluated exactly at given amplitudes (no grid, no interpolation).
//
// The QSMA curve (model/qsma.h) is parametrised by the load level alpha of
// K u + F_J(u) = alpha M phi_r; at each level q = phi_r^T M u and omega = sqrt(alpha / q).
// A backbone gives amplitudes s = q omega^p of the modal amplitude (p = 0), or of a sensor's
// displacement, velocity or acceleration at DOF d: s = |u_d| omega^p (p = 0, 1, 2), u_d the
// static deflection there (model::QsmaDof: linear in r and alpha). Not |phi_r[d]| q omega^p:
// once the joints slip the deflected shape is no longer the linear mode's (a root joint of a
// clamped beam: u_tip / (q phi_tip) 0.991 at 0.72 phi_max, 0.980 at 1.6 phi_max), which read as
// q would put F_S 0.6-2.6 % low. omega is the secant frequency sqrt(alpha / q) or, as the
// signal a test records oscillates at, the first-harmonic frequency (model/qsma.h). qsma_at()
// finds, for each s_i, the load level with ln s(alpha) = ln s_i by Newton's method on the
// bordered system
// [K_c r - h(r) = alpha g, ln s(r, alpha) = ln s_i] in (r, ln alpha), from the Euler
// predictor of the previous amplitude: one factorisation of the condensed joint problem
// (joint_condensation.h) per step, quadratic convergence to rounding (~1e-14 in ln s), and
// the last factorisation is the exact tangent the point's ring-down damping needs. Where
// Newton does not converge (a kink of the Iwan law at phi_max, a limit point) a bracketed
// secant (Illinois) iteration on ln alpha of full static solves takes over, to 1e-10.
// Accurate where a fixed grid interpolated at the data is not: at the macroslip knee, where q
// grows fast at almost constant alpha. Past the largest load the structure carries (no static
// solution), amplitudes the model cannot reach get the last reachable point, flagged.
#pragma once

#include <optional>
#include <vector>

#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/qsma.h"

namespace jointlab::correlate {

/// One curve point at a requested amplitude.
struct QsmaAtPoint {
  model::QsmaPoint point;  ///< the QSMA point (force and modal amplitude, f, zeta, max slip)
  bool reached = false;    ///< false: beyond the largest amplitude the model carries
};

/// Which frequency omega turns the modal amplitude q into the measured s = q omega^power.
enum class AmplitudeFrequency {
  kSecant,        ///< sqrt(alpha / q), the paper's QSMA frequency
  kFirstHarmonic  ///< the first-harmonic frequency (a ring-down's or a steady state's)
};

/// How qsma_at() places each amplitude on the curve.
enum class QsmaAtSolver {
  kNewton,     ///< bordered Newton, bracketing where it does not converge (above)
  kBracketing  ///< bracketing alone: the slower reference Newton is checked against
};

/// QSMA of elastic mode `mode` (1-based) at each amplitude s_i = q omega^power, or with `dof`
/// (0-based matrix index) s_i = |u_dof| omega^power, the static deflection there (ascending,
/// > 0), with every column of the point; empty if a static solve fails below the requested
/// amplitudes. InputError if there is no such mode, or the mode leaves `dof` still, or the
/// model carries no constraint modes (JointCondensation) to read it.
std::vector<QsmaAtPoint> qsma_at(const model::JointCondensation& model, int mode, int power,
                                 const std::vector<double>& amplitudes,
                                 AmplitudeFrequency frequency = AmplitudeFrequency::kSecant,
                                 QsmaAtSolver solver = QsmaAtSolver::kNewton,
                                 std::optional<Eigen::Index> dof = std::nullopt);

}  // namespace jointlab::correlate
