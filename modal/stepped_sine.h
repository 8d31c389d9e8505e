// Backbone points from stepped-sine sweeps (docs/stepped-sine.md), one point per level.
//
// Each step of a sweep gives the first harmonics of force F and response Y (data/stepped_sine.h).
// With p the response's order of differentiation from displacement (0, 1, 2) its
// displacement-equivalent receptance is H(w) = Y e^{i phi} / (F (i w)^p), w = 2 pi f, for
// the convention x(t) = Re(X e^{i w t}) (the response lags the force through resonance).
//
// Single-mode model, fitted by Ceres to the complex H at every step:
//   hysteretic (default):  H(w) = Q / (w_n^2 - w^2 + 2 i zeta w_n^2)    + R0 + R1 (w - w_c)/w_c
//   viscous:               H(w) = Q / (w_n^2 - w^2 + 2 i zeta w_n w)    + R0 + R1 (w - w_c)/w_c
// with complex modal constant Q and residual terms R0 (the other modes, constant over the
// band) and R1 (their slope), w_c the centre of the band. Rate-independent (Masing) joint
// friction makes the first-harmonic quadrature force independent of w: the hysteretic form
// is exact for a mode held at one amplitude, and at w = w_n both give zeta = D/(2 pi k_1 A^2),
// k_1 the first-harmonic stiffness and D the energy lost per cycle.
// Residuals are weighted by 1/|H| (relative errors: a sine fit's amplitude and phase errors
// scale with the signal). Uncertainty: the covariance s^2 (J^T J)^-1 of the least-squares fit, s^2
// = RSS / (2m - n) (m steps, n real parameters), J the exact Jacobian (ceres::Jet).
//
// Response-controlled sweeps hold the response amplitude, so the structure is quasi-linear
// at that level: the fit's w_n and zeta are the backbone point, at the response amplitude
// interpolated at f_n. Force-controlled sweeps pass through amplitudes: their point is the
// phase resonance, where the response is in quadrature with the force (arg(H / Q) = -pi/2,
// Q's phase rounded to 0 or pi), linearly interpolated between steps; it lies on the
// first-harmonic backbone exactly. Its damping is less direct: the energy balance there,
// zeta = |Q| F / (2 w^2 X) (X displacement amplitude), needs the modal constant |Q|: from
// response-controlled levels of the same mode and sensor when there are (it does not depend
// on amplitude), else from the fit of the force-controlled sweep itself, whose amplitude
// varies (then biased: by 8-70 % on the Iwan oscillator of the tests).
#pragma once

#include <complex>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/core/units.h"
#include "jointlab/data/stepped_sine.h"

namespace jointlab::modal {

/// Form of the damping term of the single-mode model.
enum class SineDamping { kHysteretic, kViscous };

/// Settings of the single-mode fit and of the backbone point.
struct SteppedSineOptions {
  Quantity amplitude = Quantity::kVelocity;        ///< quantity of the backbone amplitude
  SineDamping damping = SineDamping::kHysteretic;  ///< damping term of the model
  int residual_terms = 2;                          ///< 0: none, 1: R0, 2: R0 and R1
  double coverage_factor = 3.0;                    ///< reported uncertainties are k * sigma
  int max_iterations = 200;                        ///< Ceres iterations
  /// Empty if usable, else what is wrong.
  std::string check() const;
};

/// The fitted single-mode model of one sweep.
struct SineFit {
  double frequency_hz = 0;              ///< f_n
  double damping_ratio = 0;             ///< zeta
  double frequency_sigma_hz = 0;        ///< one-sigma uncertainty of f_n
  double damping_sigma = 0;             ///< one-sigma uncertainty of zeta
  std::complex<double> modal_constant;  ///< Q [m/N s^-2]
  double modal_constant_rel_sigma = 0;  ///< one-sigma relative uncertainty of |Q|
  std::complex<double> residual0;       ///< R0 [m/N]
  std::complex<double> residual1;       ///< R1 [m/N]
  double rms = 0;                       ///< RMS over the steps of |H - model| / |H|
  int iterations = 0;                   ///< Ceres iterations
  bool converged = false;               ///< Ceres reported convergence
};

/// Outcome of one level.
enum class SineStatus { kOk, kNoResonance, kFitFailed };

/// One backbone point and how it was found.
struct SineBackbonePoint {
  SineStatus status = SineStatus::kFitFailed;                ///< kOk when the point is usable
  std::string message;                                       ///< why not, or a note
  data::SineControl control = data::SineControl::kResponse;  ///< the sweep's control
  double amplitude = 0;             ///< amplitude of options.amplitude at f_n, SI
  double displacement_m = 0;        ///< displacement amplitude at f_n [m]
  double force_n = 0;               ///< force amplitude at f_n [N]
  double frequency_hz = 0;          ///< backbone frequency
  double damping_ratio = 0;         ///< backbone damping ratio
  double frequency_std_hz = 0;      ///< k * sigma
  double damping_std = 0;           ///< k * sigma
  bool damping_direct = true;       ///< false: from energy balance with a modal constant
  bool own_modal_constant = false;  ///< the energy balance used the sweep's own |Q|
  SineFit fit;                      ///< the single-mode fit of the sweep
  /// One line: level, f, zeta and their uncertainties, or the reason there is none.
  std::string report() const;
};

/// Displacement-equivalent receptance H of every step of a table [m/N].
Eigen::VectorXcd receptance(const data::SteppedSineTable& table);

/// Fits the single-mode model to H at frequencies f; InputError for a bad options struct.
SineFit fit_single_mode(const Eigen::Ref<const Eigen::VectorXd>& frequency_hz,
                        const Eigen::Ref<const Eigen::VectorXcd>& h,
                        const SteppedSineOptions& options);

/// A modal constant measured elsewhere (a response-controlled level of the same mode and
/// sensor) for the energy balance of force-controlled levels.
struct ModalConstant {
  double magnitude = 0;  ///< |Q| [m/N s^-2]; 0: use the sweep's own fit
  double rel_sigma = 0;  ///< one-sigma relative uncertainty of |Q|
};

/// The backbone point of one level (response- or force-controlled as the table says).
SineBackbonePoint extract_backbone_point(const data::SteppedSineTable& table,
                                         const SteppedSineOptions& options,
                                         const ModalConstant& modal_constant = {});

/// |Q| of the response-controlled points that have one (the median, with the largest of their
/// relative uncertainties), or magnitude 0 when none does.
ModalConstant response_modal_constant(const std::vector<SineBackbonePoint>& points);

}  // namespace jointlab::modal
