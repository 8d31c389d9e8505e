// Quasi-Static Modal Analysis (Festjens; Lacayo & Allen) of one elastic mode.
//
// For mode r (mass-normalised phi_r, linear omega_r with joints at K_T) the static problem
//   K u + F_J(u) = alpha M phi_r,   Phi_rb^T M u = 0,
// is solved for rising load levels alpha [N/kg^(1/2), i.e. the modal force]; then
//   q = phi_r^T M u = (alpha + (B phi_r)^T h(r)) / omega_r^2         [m kg^(1/2)]
//   omega(alpha) = sqrt(alpha / q),   zeta(alpha) = D / (2 pi alpha q),
// D the energy one Masing cycle dissipates: the sum over Iwan elements of D(|r_j|).
// The problem is condensed to the joint coordinates (joint_condensation.h): each load
// level is a Newton solve of size n_J, continued from the previous level.
//
// What a test measures (method.md, "What a ring-down would show"). The secant pair above is
// the paper's. A ring-down at amplitude q rings at the first-harmonic frequency and decays
// by the energy lost per cycle against the energy stored at its turning point; a steady
// state at amplitude q balances that loss against the first-harmonic stiffness. Assume, as
// QSMA does, that the motion keeps the shape of the static deflection u(q) (one nonlinear
// mode, light damping, Masing elements): r_j(t) = r_j cos(theta) at each joint coordinate.
// - Turning point: the velocity vanishes and the deflection is the QSMA solution, so the
//   energy stored is E(q) = 1/2 u^T K_s u + sum_j E_j(|r_j|), K_s = K_lin - sum_j K_T,j
//   b_j b_j^T (the structure and its springs), E_j the element's turning-point energy
//   (iwan_cycle.h: sliders that slipped store k phi^2 / 2, an element past phi_max stores
//   its sliders at phi). With K_s u = alpha M phi_r - B^T F(r), F = K_T r - h, and
//   E_j'(r) = r F_j'(r):
//     dE/dq = alpha + sum_j (dr_j/dq) (h_j - r_j h'_j),
//   dr/dq = (dr/dalpha) / (dq/dalpha), dr/dalpha = (K_c - diag h')^{-1} K_c c (c = B phi_r /
//   omega_r^2), dq/dalpha = (1 + p^T diag(h') dr/dalpha) / omega_r^2, p = B phi_r.
//   One cycle loses D(q), so dq/dt = -D omega / (2 pi dE/dq) and
//     ringdown_damping_ratio = D / (2 pi q dE/dq).
// - First harmonic: over a cycle each element's force has the in-phase first harmonic
//   k_1,j(|r_j|) r_j cos(theta) (iwan_cycle.h) instead of its static F_j(r_j). Projecting the
//   first-harmonic restoring force K_s u + B^T (k_1 r) on phi_r (Galerkin, one mode):
//     omega_1^2 = (alpha + p^T (k_1 r - F(r))) / q = omega_r^2 - p^T diag(K_T - k_1) r / q,
//   ringdown_frequency_hz = omega_1 / (2 pi) (the damping is too light to shift it), and
//     harmonic_damping_ratio = D / (2 pi omega_1^2 q^2) = D / (2 pi k_1 q^2),
//   k_1 = omega_1^2 the first-harmonic modal stiffness (unit modal mass).
// The structure's own damping (Model::modal_ratio Z, JointCondensation::linear_damping()) adds
// to each damping column: a viscous modal damping loses 2 pi Z q dE/dq per cycle, so to first
// order damping_ratio, ringdown_damping_ratio and harmonic_damping_ratio each gain Z
// (method.md section 2 point 4); frequencies are left alone (Z^2 shifts below 1e-6 here).
// For one mass on a spring k0 with an Iwan element these are exactly (k0 + k_1)/m,
// D / (2 pi x^2 (k0 + F'(x))) and D / (2 pi (k0 + k_1) x^2) (model/qsma_test.cc).
//
// Range: without q_min, the curve starts where the damping is within
// microslip_deviation of its microslip power law zeta_0(q) = D(q B phi_r) /
// (2 pi omega_r^2 q^2) (the damping of the linear joint motion). Without q_max it ends at
// full macroslip of the coordinates that carry the mode's joint slip (at least 1 % of the
// largest slip, both in the linear mode and at the current load, past their phi_max) or at
// the largest load the structure carries (past it no static solution exists: the joints
// slide freely), whichever comes first; the end is bracketed to limit_tolerance. Its points
// sit densely through the transition: 30 % log-spaced in alpha up to the first element's
// onset of macroslip (one point on it), the rest from there to the end (log-spaced; below a
// limit load the last ones cluster 10 %, ..., 0.1 % under it, then the last converged
// level). With q_max it ends at q_max or at that limit load, log-spaced: past full
// macroslip each element carries F(r) = F_S and dissipates
// D(A) = 8 (E_max + F_S (A - phi_max)) - 4 A F_S (iwan.h) while the rest of the structure
// (springs in parallel) carries the load increase; without such a load path the limit load
// is the full-macroslip load. Amplitude increases along the curve.
#pragma once

#include <string>
#include <vector>

#include "jointlab/model/joint_condensation.h"

namespace jointlab::model {

/// Settings of qsma().
struct QsmaOptions {
  int points = 50;   ///< number of points on the curve (>= 2)
  double q_min = 0;  ///< first modal amplitude; 0: automatic (microslip)
  double q_max = 0;  ///< last modal amplitude (may lie past full macroslip); 0: automatic
  double microslip_deviation = 0.01;  ///< automatic start: |zeta/zeta_0 - 1| at most this
  double limit_tolerance = 1e-4;      ///< relative bracket of the end load
  int max_newton_iterations = 60;     ///< per load level

  /// What is wrong with these options, or "".
  std::string error() const;
};

/// One point of a QSMA curve.
struct QsmaPoint {
  double force_amplitude = 0;         ///< load level alpha
  double modal_amplitude = 0;         ///< q = phi_r^T M u
  double frequency_hz = 0;            ///< sqrt(alpha/q) / (2 pi)
  double damping_ratio = 0;           ///< D / (2 pi alpha q)
  double max_slip = 0;                ///< largest |relative displacement| over the Iwan joints [m]
  double ringdown_frequency_hz = 0;   ///< first-harmonic frequency of the deflection [Hz]
  double ringdown_damping_ratio = 0;  ///< D / (2 pi q dE/dq): a ring-down's envelope decay
  double harmonic_damping_ratio = 0;  ///< D / (2 pi k_1 q^2): a steady state at amplitude q
};

/// Why a QSMA curve ends.
enum class QsmaTermination {
  kReachedQmax,      ///< the requested q_max
  kFullMacroslip,    ///< every Iwan element the mode moves is past its phi_max
  kLimitLoad,        ///< no static solution past this load: the joints slide freely
  kJointsNotLoaded,  ///< the mode does not move any Iwan joint (give q_max for a linear curve)
  kEmptyRange,       ///< q_min lies beyond the end of the curve
};

/// What happened in a qsma() call.
struct QsmaSummary {
  QsmaTermination termination = QsmaTermination::kEmptyRange;  ///< why the curve ends
  double end_force = 0;            ///< alpha of the last point (the limit load for kLimitLoad)
  double end_modal_amplitude = 0;  ///< q of the last point
  int solves = 0;                  ///< static solves, including range search and bracketing
  int newton_iterations = 0;       ///< Hessian factorizations over every solve
  std::string message;             ///< one line on the termination
  /// True when a level of the output grid could not be solved or evaluated: qsma() then
  /// returns no curve and `message` says where (a curve short of its points is never
  /// returned as if complete).
  bool incomplete = false;

  /// A short paragraph: termination, end load, work done.
  std::string report() const;
};

/// What qsma_point() needs of one mode, computed once per curve rather than once per point.
struct QsmaMode {
  /// The constants of elastic mode `mode` (1-based) of `model`.
  QsmaMode(const JointCondensation& model, int mode);
  double omega2 = 0;  ///< omega_r^2 of the linear structure
  Eigen::VectorXd p;  ///< the mode's joint coordinates B phi_r
  Eigen::VectorXd g;  ///< K_c p / omega_r^2: the joint load of unit alpha
};

/// The static deflection at one matrix DOF d of mode `mode`'s QSMA solutions, linear in the
/// solution r and its load level alpha: u_d = z^T r + e alpha (joint_condensation.h: u = Psi r
/// + alpha (phi_r - Psi p) / omega_r^2). What a sensor at d measures; not q phi_r[d] once the
/// joints slip, the deflected shape then differing from the linear mode's.
struct QsmaDof {
  /// The constants of `dof` (0-based matrix index) on elastic mode `mode` (1-based); InputError
  /// if the model carries no constraint modes or has no such DOF.
  QsmaDof(const JointCondensation& model, int mode, Eigen::Index dof);
  Eigen::VectorXd z;  ///< du_d/dr: row d of the constraint modes Psi
  double e = 0;       ///< du_d/dalpha at fixed r: (phi_r[d] - z^T p) / omega_r^2
  double sign = 1;    ///< the sign of phi_r[d]: sign u_d > 0 along the curve's linear start
  double shape = 0;   ///< |phi_r[d]|
  /// sign * u_d at (alpha, r) [m].
  double deflection(double alpha, const Eigen::Ref<const Eigen::VectorXd>& r) const {
    return sign * (z.dot(r) + e * alpha);
  }
};

/// The point of elastic mode `mode` (1-based) at a converged static solution r of load level
/// alpha, with every column; solver_tangent (dr/dalpha from the solve, may be empty) stands in
/// where the tangent matrix is singular.
QsmaPoint qsma_point(const JointCondensation& model, int mode, double alpha,
                     const Eigen::VectorXd& r, const Eigen::VectorXd& solver_tangent);

/// qsma_point() with the mode's constants given; first_harmonic, when not null, is
/// model.first_harmonic_stiffness(r) computed already.
QsmaPoint qsma_point(const JointCondensation& model, const QsmaMode& mode, double alpha,
                     const Eigen::VectorXd& r, const Eigen::VectorXd& solver_tangent,
                     const Eigen::VectorXd* first_harmonic = nullptr);

/// qsma_point() where the exact tangent dr/dalpha = (K_c - diag h'(r))^{-1} g at r itself is
/// known (no factorisation); first_harmonic as above.
QsmaPoint qsma_point_with_tangent(const JointCondensation& model, const QsmaMode& mode,
                                  double alpha, const Eigen::VectorXd& r,
                                  const Eigen::VectorXd& tangent,
                                  const Eigen::VectorXd* first_harmonic = nullptr);

/// QSMA curve of elastic mode `mode` (1-based, as numbered by `jointlab modes`); InputError if no
/// such mode or the options are invalid (checked always), std::invalid_argument without a
/// summary.
std::vector<QsmaPoint> qsma(const JointCondensation& model, int mode, const QsmaOptions& options,
                            QsmaSummary* summary);

}  // namespace jointlab::model
