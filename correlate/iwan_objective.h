// The Iwan objective: QSMA of one Iwan set at given parameters against the measured backbones
// (iwan_backbone.h), as residuals weighted by the measured scatter.
//
// Residuals, over the N measured points of every curve, weighted by the measured scatter:
//     r_f,j = (f_model(a_j) - f_j) / (sigma_f,j sqrt(N)),  r_z,j = (zeta_model(a_j) - zeta_j)
//                                                                   / (sigma_z,j sqrt(N)),
// sigma floored at frequency_floor f_j and damping_floor zeta_j; cost = sum r^2 (a mean
// squared normalised error: about 2 when the model is within the scatter).
#pragma once

#include <array>
#include <atomic>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/iwan_backbone.h"
#include "jointlab/correlate/iwan_options.h"
#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/model/iwan.h"
#include "jointlab/model/iwan_set_model.h"
#include "jointlab/model/model_file.h"

namespace jointlab::correlate {

/// What the model's misfit at a result shows of its likelier causes (IwanObjective::
/// misfit_evidence()): a linear-limit frequency far off the measured one points at the linear
/// model or the mode, a damping far above the model's at the units of the damping column.
/// The most damping any Iwan joint of chi <= 0 adds per relative frequency drop in microslip, on
/// the ring-down definitions (first-harmonic frequency, decay over stored energy) as on QSMA's
/// secant ones: 4 (chi + 1) / (pi (chi + 3)) to first order for the secant, rising with chi to
/// 4 / (3 pi) at chi = 0 for both (method.md's closed forms; at chi -0.3 0.330 and 0.326);
/// iwan_rise_limit(0).
inline constexpr double kIwanRiseLimit = 4 / (3 * M_PI);

/// The most damping any Iwan joint of exponent chi or below adds per relative frequency drop in
/// microslip, on either definition: the larger of the secant's 4 (chi + 1) / (pi (chi + 3)) and
/// the first harmonic's 4 / (pi (chi + 2) (chi + 3) G(chi)), G = 1 / (chi + 1) - J(1)
/// (model/iwan_cycle.h), both rising with chi (checked from -0.99 to 2000): kIwanRiseLimit at
/// chi 0, 0.510 at 0.3, 0.873 at 2, 1.80 at 10, without bound as chi grows (the first harmonic's;
/// the secant's tends to 4 / pi). chi <= model::kIwanCycleChiMax.
double iwan_rise_limit(double chi);

struct MisfitEvidence {
  int mode = 0;                    ///< the target (model mode R) these numbers are of
  double low_frequency_hz = 0;     ///< median measured frequency at each curve's lowest amplitudes
  double low_frequency_error = 0;  ///< median (f_model - f) / f there (the linear-limit offset)
  double low_frequency_noise = 0;  ///< median relative one-sigma of those frequencies (floored)
  double mode_hz = 0;              ///< mode R's linear frequency in the model as given
  double linear_hz = 0;       ///< mode R's linear frequency at the result (K_T as fitted or held)
  int nearer_mode = 0;        ///< an elastic mode far nearer low_frequency_hz (0: none)
  double nearer_mode_hz = 0;  ///< its linear frequency in the model as given
  double damping_factor = 0;  ///< median measured / model damping over every point
  double damping_max = 0;     ///< largest measured damping ratio
  /// Median measured damping ratio at each curve's lowest amplitudes (the points of
  /// low_frequency_hz), the fitted model's there, and the median measured one over every point.
  double low_damping = 0, low_model_damping = 0, median_damping = 0;
  /// Median over the curves of the share of each one's softening at its low end: the measured
  /// frequency's drop from its lowest fifth of points by amplitude to its second fifth, over
  /// the drop from the lowest fifth to the highest (medians of each); NaN: unknown (fewer than
  /// 10 points a curve, or no softening). A joint's power law softens from zero amplitude on
  /// (0.040-0.053 for chi -0.5 over three and a half decades); a joint kept slipping by another
  /// mode is flat there (-0.002 to 0.017). It only leans between the two: a joint nearly linear in
  /// amplitude (chi -0.05: 0.005) reads flat, data that start near the other mode's slip soften.
  double low_softening_share = NAN;
  /// Median measured frequency at each curve's highest amplitudes (its highest tenth of points,
  /// at least 3), and the median (f_model - f) / f and relative one-sigma (floored) there.
  double high_frequency_hz = 0, high_frequency_error = 0, high_frequency_noise = 0;
  /// Between each curve's lowest fifth and second fifth of points by amplitude (medians of each,
  /// curves of 10 points or more): the measured damping's rise over the measured frequency's
  /// relative drop, each summed over the curves (NaN: unknown); by how many of its standard
  /// deviations (the stated sigmas, floored) the rise exceeds kIwanRiseLimit times the drop; and
  /// the largest ratio over the curves of the second fifth's highest amplitude to the lowest.
  double low_rise_ratio = NAN, low_rise_excess = NAN, low_rise_span = 0;
  /// The rise and the drop behind low_rise_ratio, and their variances (NaN: unknown), so that the
  /// excess can be judged against the limit of the fitted chi (low_rise_excess_at()).
  double low_rise = NAN, low_drop = NAN, low_rise_variance = NAN, low_drop_variance = NAN;
  /// By how many standard deviations the rise exceeds `limit` times the drop (NaN: unknown):
  /// (rise - limit drop) / sqrt(var rise + limit^2 var drop).
  double low_rise_excess_at(double limit) const {
    return (low_rise - limit * low_drop) /
           std::sqrt(low_rise_variance + limit * limit * low_drop_variance);
  }
  int targets = 0;  ///< the objective's targets (modes): one K_T sets every linear limit
  /// Curves that disagree with one another (scatter between hits): over every target with two
  /// or more curves, the share of the sum of squared residuals that one offset per curve from
  /// its target's other curves explains (frequency and damping apart: sum over curves of n_c
  /// (mean_c - mean)^2 of the normalised residuals, over their sum of squares); 0 with one curve
  /// per target.
  double between_curves_share = 0;
  int curves = 0;  ///< the curves of the targets with two or more
  /// Curves whose shapes disagree where their amplitudes overlap (scatter that reshapes the
  /// curves, F_S and K_T off in opposite senses, rather than offsetting them): over every target
  /// with two or more curves, frequency and damping apart, the normalised residuals against ln
  /// amplitude are fitted by a common curve (piecewise linear, about a knot per three points a
  /// curve, so that any smooth misfit of the model, the same at the same amplitude for every
  /// hit, lies in it) and then with each curve's own offset and slope added. A model error gives
  /// the same residual at the same amplitude whatever the hit, so only hits that disagree with
  /// one another, data against data, gain more than noise does: the chi-square gained
  /// (between_hits_chi2, about between_hits_dof under the stated noise), and its share of the
  /// whole chi-square. Where the curves share no amplitudes nothing is gained.
  double between_hits_share = 0;
  double between_hits_chi2 = 0;  ///< the chi-square the curves' own offsets and slopes gain
  int between_hits_dof = 0;      ///< the parameters they add beyond the common curve
  /// The chi-square the common curve alone gains (the misfit the curves share at each
  /// amplitude, model error's part) and its rank: about common_dof where the model describes
  /// what the hits share.
  double common_chi2 = 0;
  int common_dof = 0;  ///< the common curve's parameters (its knots, frequency and damping)
  /// True where the curves disagree in shape with one another and the model describes what
  /// they share: their own offsets and slopes gain a chi-square the stated noise reaches less
  /// than 1 time in 1000 (between_hits_chi2 over between_hits_dof) and explain a quarter of the
  /// whole chi-square or more (between_hits_share), while the common curve gains no more than
  /// the noise reaches 999 times in 1000 (common_chi2 over common_dof). Three hits of the
  /// one-mode truth with F_S and K_T scattered 5 % and 2 % between them, over one range or
  /// rising levels from one floor, where the offsets alone explained under half: shares
  /// 0.26-0.67, common curves 10-34 over 22; models wrong with the hits alike (chi held at -0.6
  /// on chi -0.2 data, the linear part 0.4 % stiff, another mode's slip, the structure's own
  /// damping missing): shares at most 0.05; scatter and the linear part 0.4 % stiff together:
  /// common curves 92-734.
  bool hits_differ_in_shape() const;
  /// Each curve of those targets fitted alone, linearised about the result: its residuals less
  /// their least-squares projection on its own slopes in those of (ln F_S, ln K_T, chi, ln beta)
  /// the fit frees (each_hit_held), which a curve whose joint differs from the others' only in
  /// those parameters leaves at the noise. The chi-square they keep (about each_hit_dof under the
  /// stated noise) and its degrees of freedom (points less the slopes' rank, frequency and
  /// damping, summed over the curves).
  double each_hit_chi2 = 0;
  int each_hit_dof = 0;  ///< degrees of freedom of each_hit_chi2
  /// Which of (F_S, K_T, chi, beta) each curve's own fit held at the result, as the fit held
  /// them (--gamma, --beta, beta held by the fit, or at a bound of the search box), but a value
  /// --gamma or --beta states about which the curves' own values scatter (Student's t of their
  /// mean over the curves less 1 degrees of freedom reaching 5 % or more), freed there. The
  /// structure's own damping Z, where fitted inside its range, is each curve's own.
  std::array<bool, 4> each_hit_held{};
  /// Whether each curve's own fit freed the structure's own damping Z too (fitted inside its
  /// range).
  bool each_hit_own_damping = false;
  /// What a common curve of the measured frequency's residuals in ln amplitude (as
  /// between_hits_share's) then gains beyond each curve's own fit, F against the rest's own
  /// scatter (so noise stated too small leaves it near 1): the misfit every hit shares at the
  /// same amplitude, a model error's; and its degrees of freedom (the curve's rank, the rest's).
  double shared_frequency_f = 0;
  int shared_frequency_dof = 0, shared_frequency_rest_dof = 0;  ///< F's degrees of freedom
  /// True where scatter between hits does not explain the misfit alone: each curve fitted alone
  /// keeps a chi-square the stated noise reaches less than 1 time in 1000 (each_hit_chi2) and a
  /// common frequency curve gains an F its rest's scatter reaches less than 1 time in 100
  /// (shared_frequency_f): a model error beside the scatter, which pulls every parameter further
  /// than the hits' scatter shows. Three hits of the one-mode truth, F_S and K_T scattered 5 %
  /// and 2 % between them, with the linear part 0.4 % stiff (seeds 0-199): 78 of 78 such fits
  /// over one range and 150 of 153 at rising levels that the offset rule named scatter (z up to
  /// 5.5 and 8.5) are caught; of 580 fits of scatter alone 4 (a top hit whose F_S lies 9-12 %
  /// from the others', beyond the linearisation), of 191 with the noise stated half its size 5.
  bool model_misses_each_hit() const;
  /// Range over those curves of each one's mean relative offset from the fitted model, less
  /// its target's mean: (f / f_model - 1) and (zeta / zeta_model - 1).
  Eigen::Vector2d frequency_offsets = Eigen::Vector2d::Zero();
  Eigen::Vector2d damping_offsets = Eigen::Vector2d::Zero();
  /// A curve unlike the others (empty: none): of a target with four or more curves, the one
  /// whose offset (frequency or damping) lies farthest from the mean of its target's others, in
  /// their spread and its own noise, with a chance below 1 % (Bonferroni over the curves and the
  /// two quantities) that random scatter between hits puts it there (Student's t with the others
  /// less 1 degrees of freedom). Its offsets do not scatter with the others': they follow that
  /// hit (another strike point, another mode slipping the joint), and a cluster covariance that
  /// reads them as random understates the error.
  std::string apart_curve;
  double apart_t = 0;                                      ///< its t (above); 0: none
  Eigen::Vector2d apart_offset = Eigen::Vector2d::Zero();  ///< its (frequency, damping) offset
  /// Range of the others' offsets of the quantity that sets it apart (frequency or damping).
  Eigen::Vector2d apart_others = Eigen::Vector2d::Zero();
  bool apart_in_damping = false;  ///< apart_t is of the damping offsets (else frequency)
  int apart_points = 0;           ///< its points
  /// Its lowest and highest amplitude (the options' amplitude quantity, SI units).
  Eigen::Vector2d apart_amplitude = Eigen::Vector2d::Zero();
};

/// The objective: QSMA of the set at given parameters against the measured backbones.
class IwanObjective {
 public:
  /// Prepares the objective; InputError if the set is not an Iwan set of the model, a mode or
  /// sensor is out of range, or a curve is empty or not positive. The model is evaluated at each
  /// measured amplitude (qsma_at.h). Of the options it takes the measured amplitude quantity,
  /// the comparison and the two floors.
  IwanObjective(const model::Model& model, const std::string& set,
                const std::vector<Sensor>& sensors, std::vector<IwanTarget> targets,
                const IwanUpdateOptions& options);
  /// K_s: the set's linear stiffness in the model [N/m].
  double reference_stiffness() const { return Ks_; }
  /// The set's parameters in the model.
  const model::IwanParameters& initial() const { return initial_; }
  /// Number of residuals.
  int residual_count() const { return residual_count_; }
  /// Residuals at p (K_T = p.Kt); false if the model could not be evaluated there. The model
  /// comes from the set-up shared by every evaluation (model/iwan_set_model.h). Thread-safe.
  bool residuals(const model::IwanParameters& p, double* r) const;
  /// The same the slow way, as before either speed-up: the model condensed from scratch at p
  /// (every mode, a new factorisation) and each amplitude bracketed by full static solves
  /// (qsma_at.h); the reference the fast evaluation is checked and timed against.
  bool residuals_from_scratch(const model::IwanParameters& p, double* r) const;
  /// Residuals at p with the structure's own damping ratio at z (not fitted, not the model's):
  /// the Jacobian column of Z and the covariance need it held. Thread-safe.
  bool residuals_at(const model::IwanParameters& p, double z, double* r) const;
  /// Sum of squared residuals at p, however large; nullopt if the model cannot be evaluated
  /// there.
  std::optional<double> try_cost(const model::IwanParameters& p) const;
  /// try_cost(), or a finite penalty of 1e6 if the model cannot be evaluated at p (for reports
  /// that compare costs; the update itself never takes the penalty for a cost).
  double cost(const model::IwanParameters& p) const;
  /// The structure's own damping ratio Z the residuals at p use: the model's when held, the
  /// best one in [0, linear_damping_max] at p when fitted; nullopt if p cannot be evaluated.
  std::optional<double> linear_damping(const model::IwanParameters& p) const;
  /// True when the objective identifies Z (IwanUpdateOptions::fit_linear_damping).
  bool fits_linear_damping() const { return fit_z_; }
  /// The model's own damping ratio (Model::modal_ratio).
  double model_linear_damping() const { return z_model_; }
  /// Amplitude of the point each residual belongs to (in its curve's quantity).
  const std::vector<double>& residual_amplitude() const { return residual_amplitude_; }
  /// Largest joint slip [m] (QSMA max_slip) at the lowest and at the highest measured amplitude
  /// over the targets, at p; (0, 0) if the model cannot be evaluated there.
  Eigen::Vector2d slip_range(const model::IwanParameters& p) const;
  /// Index of the curve (over every target, in order) each residual belongs to.
  const std::vector<int>& residual_curve() const { return residual_curve_; }
  /// The frequency [Hz] of elastic mode `mode` (1-based) with every element of the set slipped
  /// (no stiffness: QSMA's high-amplitude limit, the elements' force a constant F_S) and stuck
  /// at K_T = gamma K_s (its low-amplitude limit): (slipped, stuck). Every ordered eigenvalue
  /// falls as a stiffness falls, so the mode's frequency lies between the two at any amplitude
  /// and any K_T up to gamma K_s. (NaN, NaN) where the linear modes cannot be found.
  Eigen::Vector2d frequency_reach(int mode, double gamma) const;
  /// Relative linear-frequency error of every target at p (0 for targets without one).
  double linear_error(const model::IwanParameters& p) const;
  /// Gives the measured linear modes (shapes at the sensors) for linear_errors().
  void set_linear_modes(const MeasuredModes& measured, double mac_threshold);
  /// (f_model - f_exp) / f_exp of every measured linear mode at p, MAC-paired (empty:
  /// unpaired); empty without set_linear_modes().
  std::vector<std::optional<double>> linear_errors(const model::IwanParameters& p) const;
  /// linear_errors() at K_T = gamma K_s for each gamma, the pairs made by the pairing rules at
  /// gamma = 1 (the model as given) and followed from there by their full shapes along the
  /// gammas (mode_tracking.h), as the linear update follows them; empty entries: unpaired or
  /// not followed. Only K_T moves the linear modes, so F_S, chi and beta do not enter.
  std::vector<std::vector<std::optional<double>>> linear_errors_along(
      const std::vector<double>& gammas) const;
  /// QSMA evaluations so far.
  int evaluations() const { return evaluations_; }
  /// A copy of the model with the set at p (the model's own damping unchanged).
  model::Model apply(const model::IwanParameters& p) const;
  /// A copy of the model with the set at p and its own damping ratio at z.
  model::Model apply(const model::IwanParameters& p, double z) const;
  /// Per target, the model at (p, z) over its measured amplitude range (model_backbone(), with
  /// its first curve's sensor, kind and the comparison of the options).
  std::vector<ModelBackbone> model_curves(const model::IwanParameters& p, double z,
                                          int points = 80) const;
  /// Relative RMS errors (frequency, damping) of the model at (p, z) over every measured
  /// point, (f_model - f_j) / f_j and (zeta_model - zeta_j) / zeta_j; nullopt if p cannot be
  /// evaluated.
  std::optional<Eigen::Vector2d> rms_errors(const model::IwanParameters& p, double z) const;
  /// The same for the best constants (the constant minimising each relative RMS).
  Eigen::Vector2d constant_rms_errors() const;
  /// MisfitEvidence of the model at (p, z), of the target whose linear-limit offset is largest,
  /// each curve's own fit holding the parameters (F_S, K_T, chi, beta) `held` holds, as the fit
  /// did, but those also `stated` (held at a value the options state: --gamma, --beta) where the
  /// curves' own values of them scatter about it (MisfitEvidence::each_hit_held); nullopt if p
  /// cannot be evaluated.
  std::optional<MisfitEvidence> misfit_evidence(const model::IwanParameters& p, double z,
                                                const std::array<bool, 4>& held = {},
                                                const std::array<bool, 4>& stated = {}) const;
  /// The targets (the measured backbones).
  const std::vector<IwanTarget>& targets() const { return targets_; }
  /// Residuals at (p, z), as residuals_at(), of the model with its structure's stiffness K (the
  /// matrix without the joints) times `factor`: the derivative of the fit with respect to an
  /// error of the linear part (IwanUpdateSummary::linear_part_sensitivity). Evaluated on a model
  /// set up anew; false where it cannot be evaluated.
  bool residuals_with_structure_stiffness(const model::IwanParameters& p, double z, double factor,
                                          double* r) const;
  /// How many measured points state an uncertainty (std > 0) below the floors: (points,
  /// frequencies below frequency_floor f, dampings below damping_floor zeta); those are raised
  /// to the floor.
  Eigen::Vector3i floored_points() const;

 private:
  const model::Model* model_;
  std::string set_;
  std::vector<Sensor> sensors_;
  std::vector<IwanTarget> targets_;
  AmplitudeQuantity amplitude_;
  double f_floor_, z_floor_;
  IwanComparison comparison_;
  double Ks_ = 0;
  model::IwanParameters initial_;
  int residual_count_ = 0;
  std::vector<int> residual_curve_;
  std::vector<double> residual_amplitude_;
  bool fit_z_ = false;
  double z_model_ = 0, z_max_ = 0.05;
  MeasuredModes linear_modes_;
  double linear_mac_ = 0.6;
  std::shared_ptr<const model::IwanSetModel> set_model_;  // null: every evaluation from scratch
  mutable std::atomic<int> evaluations_ = 0;
  // Residuals at p; z_fixed (not null) sets the structure's own damping, else the model's or
  // the best (fitted); z_used (not null) receives it.
  // values (not null, residual_count long) receives the model's frequency and damping (Z
  // included) in the residuals' order.
  bool evaluate(const model::IwanParameters& p, double* r, Eigen::Vector2d* slip, bool from_scratch,
                const double* z_fixed = nullptr, double* z_used = nullptr,
                double* values = nullptr) const;
};

/// "" when each target's measured frequencies overlap what its mode can reach (frequency_reach()
/// at the largest K_T of the options: fixed_gamma, else bounds.gamma_max); else one sentence per
/// target whose every frequency lies above the stuck or below the slipped frequency, with the
/// numbers: no Iwan parameters can fit it, whatever the amplitudes.
std::string unreachable_frequencies(const IwanObjective& objective,
                                    const IwanUpdateOptions& options);

}  // namespace jointlab::correlate
