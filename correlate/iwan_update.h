// Iwan updating: the four parameters of one named Iwan set from measured backbones.
//
// Parameters p = (F_S [N], gamma, chi, beta) shared by every element of the set, with
// K_T = gamma K_s, K_s the set's linear stiffness in the given model (from the linear update).
// Model curve: QSMA of elastic mode R (qsma.h) gives q, omega(q), zeta(q). The measuring
// sensor (dof d, sign s) sees the displacement amplitude x = |u_d|, u_d the QSMA deflection
// at d (qsma_at.h; q |phi_R[d]| only while the joints stick: in macroslip the deflected shape
// leaves the linear mode's); the amplitude of the quantity `process` reported is a = x omega^p
// (p = 0, 1, 2 for displacement, velocity, acceleration), omega the frequency the signal
// oscillates at.
// Like with like (the default, IwanComparison::kMatched): a ring-down backbone is compared
// with what a ring-down of the model shows, the first-harmonic frequency and
// D / (2 pi q dE/dq) (QSMA's ring-down columns); a stepped-sine backbone with what a steady
// state shows, the first-harmonic frequency and D / (2 pi k_1 q^2); omega above is the
// first-harmonic frequency. kSecant compares every backbone with the paper's secant pair
// sqrt(alpha/q), D / (2 pi alpha q), omega the secant frequency. The model frequency and damping
// are evaluated exactly at each measured amplitude a_j (qsma_at.h: one static solve per secant
// step, no grid), so the macroslip knee is where the model puts it.
// Residuals, over the N measured points of every curve, weighted by the measured scatter:
//     r_f,j = (f_model(a_j) - f_j) / (sigma_f,j sqrt(N)),  r_z,j = (zeta_model(a_j) - zeta_j)
//                                                                   / (sigma_z,j sqrt(N)),
// sigma floored at frequency_floor f_j and damping_floor zeta_j; cost = sum r^2 (a mean
// squared normalised error: about 2 when the model is within the scatter).
// Optimisers, on one interface and one budget of QSMA evaluations:
//   kPaper       the paper's Monte Carlo: `samples` uniform samples in the bounds, keep the
//                best, contract the bounds to +-contraction around it, repeat until a round
//                brings no improvement or the budget is spent;
//   kPaperLog    the same with F_S, gamma and beta sampled logarithmically;
//   kGlobalLocal logarithmic sampling with half the budget, then Ceres (central differences on
//                ln F_S, ln gamma, chi, ln beta) from the best `local_starts` samples.
// Pareto front: for each gamma of a list the other three parameters are updated; each point
// gives the linear-frequency error |f_model,R - f_lin,exp| / f_lin,exp and the backbone cost.
#pragma once

#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/model/iwan.h"
#include "jointlab/model/iwan_set_model.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/model_file.h"

namespace jointlab::correlate {

/// The amplitude quantity of measured backbones (as `process --amplitude`).
enum class AmplitudeQuantity { kDisplacement, kVelocity, kAcceleration };

/// Power of omega that turns a modal amplitude into this quantity's (0, 1 or 2).
int amplitude_power(AmplitudeQuantity q);

/// How a backbone was measured, hence which model pair it is compared with.
enum class BackboneKind {
  kRingdown,    ///< free decay (`process`): first-harmonic frequency, ring-down damping
  kSteppedSine  ///< one steady state per level (`stepped-sine`): first-harmonic pair
};

/// Which model columns measured backbones are compared with.
enum class IwanComparison {
  kMatched,  ///< each backbone with the pair of its kind (ring-down or first-harmonic)
  kSecant    ///< every backbone with QSMA's secant pair sqrt(alpha/q), D/(2 pi alpha q)
};

/// One measured backbone curve: points of one channel (or pooled hits of it).
struct MeasuredBackbone {
  BackboneKind kind = BackboneKind::kRingdown;  ///< how it was measured
  int sensor = 0;  ///< index into the sensors: where the amplitude is measured
  /// True: `amplitude` is the QSMA modal amplitude q of the target's mode (mass-normalised
  /// shape; no sensor, `sensor` unused, the amplitude quantity of the options does not apply).
  bool modal = false;
  std::string source;                ///< where it was read (file), for messages; may be empty
  Eigen::VectorXd amplitude;         ///< amplitude a_j (SI units of the quantity), > 0
  Eigen::VectorXd frequency_hz;      ///< f_j [Hz]
  Eigen::VectorXd damping_ratio;     ///< zeta_j
  Eigen::VectorXd frequency_std_hz;  ///< k sigma_f,j [Hz] as read (0: the floor)
  Eigen::VectorXd damping_std;       ///< k sigma_z,j as read (0: the floor)
  /// k of the two std columns: `process` and `stepped-sine` write expanded uncertainties
  /// (k = 3 by default, their `coverage_factor`); the objective weighs each point by std / k.
  double coverage_factor = 1.0;
};

/// The measured data of one model mode.
struct IwanTarget {
  int mode = 1;                          ///< elastic model mode R (1-based, as `modes`)
  std::vector<MeasuredBackbone> curves;  ///< its measured backbones
  double linear_frequency_hz = 0;        ///< measured linear frequency (0: unknown)
};

/// Bounds of the Iwan parameters (F_S, gamma and beta > 0; -1 < chi).
struct IwanBounds {
  double Fs_min = 1, Fs_max = 1e3;         ///< [N]
  double gamma_min = 0.3, gamma_max = 3;   ///< K_T / K_s
  double chi_min = -0.95, chi_max = 0;     ///< exponent
  double beta_min = 0.01, beta_max = 100;  ///< macroslip weight
};

/// The default search box of `update-iwan` and `run`: F_S within a factor 30 of the start's,
/// gamma 0.05-2, chi -0.95-0, beta 0.01-100.
IwanBounds default_iwan_bounds(const model::IwanParameters& start);

/// Which optimiser update_iwan() runs.
enum class IwanOptimizer { kPaper, kPaperLog, kGlobalLocal };

/// Settings of update_iwan().
struct IwanUpdateOptions {
  IwanOptimizer optimizer = IwanOptimizer::kGlobalLocal;  ///< method
  IwanBounds bounds;                                      ///< search box
  double fixed_gamma = 0;                                 ///< > 0: gamma held at this value
  std::optional<double> fixed_beta;  ///< beta held at this value (>= 0; 0: no macroslip weight)
  AmplitudeQuantity amplitude = AmplitudeQuantity::kVelocity;  ///< measured amplitude quantity
  IwanComparison comparison = IwanComparison::kMatched;        ///< model columns compared
  int samples = 100;                                           ///< samples per Monte Carlo round
  double contraction = 0.03;      ///< Monte Carlo: bounds contract to +-this around the best
  int max_evaluations = 1500;     ///< budget of QSMA evaluations
  int local_starts = 3;           ///< global-local: Ceres starts from the best samples
  double frequency_floor = 1e-4;  ///< sigma_f at least this times f
  double damping_floor = 0.02;    ///< sigma_z at least this times zeta
  unsigned seed = 1;              ///< random seed
  /// Threads evaluating the samples of a round (0: every core); the result does not depend
  /// on it.
  int threads = 0;
  /// Called after every evaluation with (evaluations, best cost so far).
  std::function<void(int, double)> progress;
  /// The structure's own damping (Model::modal_ratio Z, added to every model damping):
  /// false holds the model's; true identifies it with the Iwan parameters, in
  /// [0, linear_damping_max]. Damping residuals are linear in Z, so at any Iwan parameters the
  /// best Z is the weighted mean of the measured damping minus the joints' (clamped to its
  /// range): every candidate is scored at its own best Z (variable projection).
  bool fit_linear_damping = false;
  double linear_damping_max = 0.05;  ///< upper bound of a fitted Z
  /// True when the model's linear part was fitted to measured linear frequencies before this
  /// update (the campaign's linear step): the report states the linear part's systematic effect
  /// on the parameters (IwanUpdateSummary::linear_part_sensitivity) without sending to
  /// update-linear.
  bool linear_part_updated = false;
  /// What is wrong with these options, or "".
  std::string error() const;
};

/// A model's backbone as a measured one of `kind` would show it (the ring-down or steady-state
/// pair; with IwanComparison::kSecant the secant pair), in the measured amplitude a =
/// |u_d| omega^power (u_d the QSMA deflection at the measuring DOF; q and power 0 for the
/// modal amplitude), at `points` amplitudes log-spaced over [a_lo, a_hi]; the model's own damping
/// (JointCondensation::linear_damping) included.
struct ModelBackbone {
  Eigen::VectorXd amplitude;      ///< a [SI of the measured amplitude]
  Eigen::VectorXd frequency_hz;   ///< f [Hz]
  Eigen::VectorXd damping_ratio;  ///< zeta
  bool clipped = false;  ///< true: the model does not reach the top of the range (no static
                         ///< solution past its largest load) or fails below it; the curve stops
};

/// model_backbone() of elastic mode `mode` (1-based), its amplitude the modal amplitude q
/// (no dof) or the QSMA deflection at matrix DOF `dof` times omega^power (qsma_at.h, as
/// update-iwan fits it); InputError if there is no such mode or it leaves `dof` still.
ModelBackbone model_backbone(const model::JointCondensation& model, int mode,
                             std::optional<Eigen::Index> dof, int power, BackboneKind kind,
                             IwanComparison comparison, double a_lo, double a_hi, int points);

/// What the model's misfit at a result shows of its likelier causes (IwanObjective::
/// misfit_evidence()): a linear-limit frequency far off the measured one points at the linear
/// model or the mode, a damping far above the model's at the units of the damping column.
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
  int targets = 0;  ///< the objective's targets (modes): one K_T sets every linear limit
  /// Curves that disagree with one another (scatter between hits): over every target with two
  /// or more curves, the share of the sum of squared residuals that one offset per curve from
  /// its target's other curves explains (frequency and damping apart: sum over curves of n_c
  /// (mean_c - mean)^2 of the normalised residuals, over their sum of squares); 0 with one curve
  /// per target.
  double between_curves_share = 0;
  int curves = 0;  ///< the curves of the targets with two or more
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
  /// MisfitEvidence of the model at (p, z), of the target whose linear-limit offset is largest;
  /// nullopt if p cannot be evaluated.
  std::optional<MisfitEvidence> misfit_evidence(const model::IwanParameters& p, double z) const;
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

/// Why update_iwan() stopped.
enum class IwanUpdateStatus {
  kConverged,     ///< no further improvement (Monte Carlo) or Ceres converged
  kBudget,        ///< the evaluation budget was spent (global-local: the polish of the best
                  ///< point too) before convergence; no sigma is stated
  kNoValidPoint,  ///< no sample could be evaluated
};

/// Who held beta, where IwanUpdateSummary::held says it was held.
enum class IwanBetaHold {
  kOptions,         ///< the options (`--beta`, a campaign's [update.iwan] beta): as asked
  kMicroslip,       ///< the fit, at its start: the data stay in microslip (campaign::fit_iwan)
  kFreeFitNoBetter  ///< the fit, at its start: the data reach macroslip but the fit with beta
                    ///< freed ended at a higher cost (campaign::fit_iwan)
};

/// Why a parameter of an Iwan update states a sigma or not (IwanUpdateSummary::sigma_reason()):
/// the one decision behind the report's parameter line, parameters.csv's relative_std and note,
/// Python's and the campaign report's, so that they cannot disagree.
enum class IwanSigmaReason {
  kStated,                ///< fitted, its sigma stated
  kGivenBetaAsHeld,       ///< F_S of microslip data with beta held as asked: sigma given that beta
  kHeldAsAsked,           ///< held by the options (--gamma, --beta; modal_ratio not fitted)
  kBetaHeldMicroslip,     ///< beta held at its start by the fit: the data stay in microslip
  kBetaHeldFreeNoBetter,  ///< beta held at its start by the fit: the fit with it free did no better
  kStart,                 ///< no candidate improved on the start: the start, no fit
  kNoSlip,                ///< F_S, chi or beta of data without slip (no_slip_seen())
  kMicroslipFamily,       ///< F_S or beta, both free, of microslip data: not identified apart
  kNotConverged,          ///< the fit did not converge (kBudget): no sigma
  kGivenBeta,     ///< F_S of microslip data with beta held by the fit: F_S at that beta, no result
  kTooFewPoints,  ///< too few effective independent points (sigma_degrees_of_freedom <= 2)
  kAtKink,        ///< fixed only by points at a kink (an element's phi_max), from one side
  kModelMisfit,   ///< the model does not describe the data and its residuals are no noise
                  ///< (IwanUpdateSummary::misfit_sets_the_error()): no sigma
  kUnknown        ///< the covariance could not be formed at the result
};

/// The slip force that gives Iwan parameters p's microslip response (K_T, chi and R; F = K_T u -
/// R u^(chi+2) / ((chi+1)(chi+2)) below phi_max) at another beta: below phi_max the two sets are
/// the same element, so microslip data cannot tell them apart.
double slip_force_at_beta(const model::IwanParameters& p, double beta);

/// One objective value on the way.
struct IwanHistoryEntry {
  int evaluation = 0;      ///< evaluations so far
  double cost = 0;         ///< the cost of this evaluation (+inf: the model could not be evaluated)
  double best = 0;         ///< the best cost so far
  bool beta_held = false;  ///< evaluated with beta held (IwanUpdateOptions::fixed_beta)
};

/// Outcome of update_iwan().
struct IwanUpdateSummary {
  IwanUpdateStatus status = IwanUpdateStatus::kNoValidPoint;  ///< termination
  model::IwanParameters start;                                ///< the model's parameters
  model::IwanParameters best;                                 ///< the updated parameters
  double initial_cost = 0;    ///< cost at start (+inf: the model cannot be evaluated there)
  double final_cost = 0;      ///< cost at best (+inf: kNoValidPoint and the start not evaluable)
  double linear_error = 0;    ///< relative linear-frequency error at best
  bool linear_known = false;  ///< some target has a measured linear frequency (else no error)
  int evaluations = 0;        ///< QSMA evaluations
  int rounds = 0;             ///< Monte Carlo rounds or local starts
  /// Global-local: QSMA evaluations (counted in `evaluations`) of the polish, the local solve
  /// that found the best point carried on from there toward its tolerance after its share of
  /// the budget ran out, by up to another budget (0: it converged within its share).
  int polish_evaluations = 0;
  IwanOptimizer optimizer = IwanOptimizer::kGlobalLocal;  ///< the method used
  bool improved = true;  ///< false: no sample beat the start (held parameters at their values)
  /// Free parameters that end at a bound of the search box, e.g. "Fs at its upper bound 2000 N".
  std::vector<std::string> at_bounds;
  /// Per parameter (F_S, K_T, chi, beta, modal_ratio): -1 at its lower bound, +1 at its upper
  /// bound, 0 inside (or held).
  std::array<int, 5> bound_side{};
  /// Which of (F_S, K_T, chi, beta) were held (their sigma is not a number): by the options, and
  /// beta also by the fit itself (beta_hold).
  std::array<bool, 4> held{};
  /// Who held beta where held[3] (set_beta_held_by_fit()).
  IwanBetaHold beta_hold = IwanBetaHold::kOptions;
  /// kFreeFitNoBetter: the cost the fit with beta freed ended at (above final_cost).
  double free_fit_cost = 0;
  /// Marks beta as held by the fit at its start for `why` (not by the options): with the data in
  /// microslip F_S then stands for the combination of F_S and beta the data fix (the microslip
  /// dissipation R at that beta) and states no sigma of its own (covariance keeps the one given
  /// beta); `free_cost` is the cost of the fit with beta freed (kFreeFitNoBetter).
  void set_beta_held_by_fit(IwanBetaHold why, double free_cost = 0);
  /// True where beta was held by the options (the user), not by the fit.
  bool beta_held_as_asked() const { return held[3] && beta_hold == IwanBetaHold::kOptions; }
  /// Parameter k (F_S, K_T, chi, beta) held as asked (by the options), not by the fit.
  bool held_as_asked(int k) const { return k == 3 ? beta_held_as_asked() : held[k]; }
  /// Why parameter k (F_S, K_T, chi, beta; 4: modal_ratio) states a sigma or not. A sigma is
  /// stated (relative_std(k) > 0, modal_ratio_std > 0) exactly for kStated and kGivenBetaAsHeld.
  IwanSigmaReason sigma_reason(int k) const;
  /// What parameter k's value is, where it is not simply fitted (held, and by whom; not
  /// identified apart from another; F_S given beta; why no sigma), in a few words without a
  /// comma (parameters.csv's note column, Python's, the campaign report's), from sigma_reason();
  /// "" for a fitted parameter with its sigma. k = 4: modal_ratio.
  std::string parameter_note(int k) const;
  /// Sets relative_std (and modal_ratio_std) to 0 wherever sigma_reason() states none, so every
  /// reader of the numbers agrees with the words (update_iwan() and set_beta_held_by_fit() call
  /// it).
  void clear_unstated_sigmas();
  /// One-sigma relative uncertainty of (F_S, K_T, chi, beta) at best (of |chi| for chi; 0 where
  /// unknown or held, and all 0 when the fit did not converge, kBudget): the larger of a
  /// serial-correlation robust (Newey-West, HAC) sandwich over each curve's points ordered by
  /// amplitude, with a bandwidth of a tenth of the curve so that it does not depend on how densely
  /// the curve is sampled, and the Gauss-Newton covariance scaled by the reduced chi-square when
  /// that exceeds 1; with three or more curves the cluster-robust covariance (one cluster per
  /// curve) as a further lower limit, and the covariance of AR(1) noise at its coefficient
  /// corrected for what the fit absorbs; widened for few effective_points (Student's t), and 0
  /// (unknown) where they are 3 or fewer.
  Eigen::Vector4d relative_std = Eigen::Vector4d::Zero();
  /// Covariance of x = (ln F_S, ln K_T, chi, ln beta) behind relative_std (0 rows and columns
  /// for held parameters; all 0 when unknown).
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
  double modal_ratio_start = 0;     ///< the model's own damping ratio Z
  double modal_ratio = 0;           ///< Z at best: fitted, else the model's
  bool modal_ratio_fitted = false;  ///< Z was identified (IwanUpdateOptions::fit_linear_damping)
  double modal_ratio_std = 0;       ///< one-sigma absolute uncertainty of a fitted Z (0: unknown)
  /// The best constant-backbone candidate's cost (a joint that barely slips, the frequency
  /// matched, Z fitted); 0 when Z is not fitted. The result is never worse.
  double constant_cost = 0;
  /// Relative RMS errors of frequency and damping at best over every point (0 when unknown),
  /// and of the best constants (the constant-backbone model's floor to beat).
  Eigen::Vector2d rms_errors = Eigen::Vector2d::Zero();
  Eigen::Vector2d constant_rms_errors = Eigen::Vector2d::Zero();
  /// Reduced chi-square at best: sum of squared normalised residuals over (2N - free
  /// parameters); about 1 when the model describes the data within their stated noise.
  double reduced_chi2 = 0;
  /// The residuals' noise read as AR(1) along each curve: its lag-1 coefficient, corrected for
  /// the slow part the fit absorbs (0 when unknown).
  double noise_correlation = 0;
  /// The effective number of independent points the residuals amount to (about residuals x
  /// (1 - rho) / (1 + rho), at least 1 per curve's frequencies or dampings; 0 when unknown).
  double effective_points = 0;
  /// The largest share of the squared residuals at the result that one third of the points
  /// holds, each curve's points cut in thirds by amplitude and pooled over curves: about 1/3
  /// for residuals spread evenly over the amplitudes, as noise is (0 when unknown).
  double amplitude_share = 0;
  /// Student's t degrees of freedom of the sigmas: effective_points less the parameters fitted;
  /// 2 or fewer state no sigma.
  double sigma_degrees_of_freedom = 0;
  /// Per parameter (F_S, K_T, chi, beta): true where only the slopes of residuals at a kink of
  /// the model (a point whose secants two sigmas each way differ: an element's phi_max between)
  /// fix it; a slope there holds on one side only, so no sigma is stated.
  std::array<bool, 4> fixed_at_kink{};
  double reference_stiffness = 0;  ///< K_s: gamma = K_T / K_s [N/m]
  size_t residuals = 0;            ///< number of residuals (2 per measured point)
  /// IwanObjective::floored_points(), and the floors (relative frequency, relative damping)
  Eigen::Vector3i floored = Eigen::Vector3i::Zero();
  double frequency_floor = 0, damping_floor = 0;  ///< the floors of the options
  /// The linear part's systematic sensitivity, per parameter (F_S, K_T, chi, beta): the relative
  /// change of the result (of |chi| for chi; 0 for a held parameter) per relative change of mode
  /// `sensitivity_mode`'s linear frequency (at the result's K_T) made by an error of the rest of
  /// the model, its structure's stiffness K (the matrix without the joints). At the minimum the
  /// cost's gradient stays 0 as K moves, so dx/ds = -(J^T J)^-1 J^T dr/ds (s = ln of K's factor,
  /// Gauss-Newton), over the free parameters of the covariance. No residual shows such an error
  /// where K_T is free: K_T takes the linear frequency up and the rest bends to follow (the
  /// one-mode truth with K 0.1 % stiffer: reduced chi-square 1.14-1.31, white residuals, K_T
  /// -2.4 %, F_S -5 %). All 0 when unknown (not converged, the start, no Jacobian).
  Eigen::Vector4d linear_part_sensitivity = Eigen::Vector4d::Zero();
  int sensitivity_mode = 0;  ///< the model mode R whose linear frequency the sensitivity is per
  /// d ln f_R / d ln K at the result: the share of mode R's strain energy in the structure
  /// (without the joints), halved; converts the sensitivity to one per error of K.
  double frequency_per_stiffness = 0;
  bool linear_part_updated = false;  ///< IwanUpdateOptions::linear_part_updated
  /// The relative error of mode R's linear frequency (from the rest of the model) that moves
  /// parameter k (F_S, K_T, chi, beta) by its stated sigma: relative_std(k) /
  /// |linear_part_sensitivity(k)|; the sigma holds only where the linear part is right to that.
  /// 0 where either is unknown or no sigma is stated.
  double linear_part_tolerance(int k) const;
  /// IwanObjective::misfit_evidence() at best (empty when unknown): what the report's warnings
  /// name as a misfit's likelier cause instead of a wider range or a longer search.
  std::optional<MisfitEvidence> evidence;
  /// True when reduced_chi2 is significantly above 1 (by more than 3 of its standard deviations
  /// sqrt(2 / dof)): the model does not describe the data within their noise and the sigma is a
  /// lower bound.
  bool misfit() const;
  /// True when the residuals look like noise: uncorrelated from point to point
  /// (noise_correlation below 0.3) and spread evenly over the amplitudes (amplitude_share within
  /// three of its standard deviations under noise of 1/3); false when unknown.
  bool residuals_look_like_noise() const;
  /// True when the misfit, not the noise, sets the parameters' error, so no sigma is stated
  /// (IwanSigmaReason::kModelMisfit): reduced_chi2 above 1 by more than three of its standard
  /// deviations over the effective_points (sqrt(2 / n_eff): serially correlated noise scatters
  /// it more than the count says), residuals that are no noise (residuals_look_like_noise()),
  /// and no scatter between curves that explains it (scatter_explains_misfit()).
  bool misfit_sets_the_error() const;
  /// True when random scatter between hits explains the misfit, so the cluster-robust covariance
  /// (one cluster per curve, Student's t with the curves less 1 degrees of freedom) states the
  /// sigmas: offsets of each curve from the others explain half the chi-square or more, four or
  /// more curves (more than 2 degrees of freedom), and no curve lies apart from the others
  /// (MisfitEvidence::apart_curve: offsets that follow a hit are no random scatter).
  bool scatter_explains_misfit() const;
  /// True when the largest joint slip at the highest measured amplitude (top_slip) stays below
  /// 1e-3 of phi_max: the fitted modes hardly move the joint, so the joint barely shapes them.
  bool joint_hardly_moved() const;
  /// True when Z was fitted and the fit is no better than the best constant backbone (the
  /// joint stuck) beyond what its extra parameters give by chance 1 time in 20: the data show
  /// no slip, and F_S, chi and beta are not identified.
  bool no_slip_seen() const;
  double bottom_slip = 0;  ///< largest joint slip at the lowest measured amplitude, at best [m]
  double top_slip = 0;     ///< largest joint slip at the highest measured amplitude, at best [m]
  double phi_max = 0;      ///< the slip at which an element reaches macroslip, at best [m]
  /// True when the data stay in microslip at best (top_slip < phi_max): then only K_T, chi and R
  /// are identified, not F_S and beta separately (docs/update-iwan.md).
  bool microslip_only() const { return top_slip > 0 && top_slip < phi_max; }
  /// True when the data lie past phi_max at every measured amplitude at best (bottom_slip >
  /// phi_max): F_S shows (the plateau), K_T, chi and beta, which shape the joint below phi_max,
  /// only weakly.
  bool macroslip_only() const { return phi_max > 0 && bottom_slip > phi_max; }
  std::vector<IwanHistoryEntry> history;  ///< every evaluation
  /// Where the model does not describe the data (misfit()) and `evidence` shows a likelier
  /// cause than the search (a wrong mode, the linear model, the damping column's units), that
  /// cause in one sentence; else "". A fit that did not converge (kBudget) names only what
  /// rests on the model as given (a wrong mode): its residuals are not a best fit's.
  std::string misfit_cause() const;
  /// Where the fit did not converge, what its residuals where it stopped would suggest as a
  /// cause, if that were the best fit (no finding: the report qualifies it); else "".
  std::string tentative_cause() const;
  /// One paragraph: optimiser outcome, parameters, cost.
  std::string report() const;
};

/// Updates the Iwan set against the objective; returns the best parameters, always inside the
/// bounds (the start is a candidate only when it lies inside them). Held parameters
/// (fixed_gamma, fixed_beta) are held at their values in every candidate, the start included;
/// status kNoValidPoint (and the start returned) when no candidate could be evaluated.
model::IwanParameters update_iwan(const IwanObjective& objective, const IwanUpdateOptions& options,
                                  IwanUpdateSummary* summary);

/// One point of the Pareto front of linear-frequency error against backbone cost.
struct ParetoPoint {
  double gamma = 0;              ///< K_T / K_s held
  model::IwanParameters params;  ///< the best parameters at this gamma
  double linear_error = 0;       ///< largest |relative linear-frequency error| over every
                                 ///< paired measured linear mode (else the fitted modes')
  double backbone_cost = 0;      ///< the backbone cost
  /// Linear-frequency error of every measured linear mode (IwanObjective::set_linear_modes),
  /// (f_model - f_exp) / f_exp of its paired model mode, followed by shape along the gammas
  /// (IwanObjective::linear_errors_along); empty entries: unpaired or not followed.
  std::vector<std::optional<double>> mode_errors;
  bool dominated = false;  ///< another point is better in both
};

/// Updates (F_S, chi, beta) at each gamma and marks the non-dominated points; InputError when
/// no parameter set can be evaluated at one of the gammas.
std::vector<ParetoPoint> pareto_front(const IwanObjective& objective,
                                      const std::vector<double>& gammas,
                                      const IwanUpdateOptions& options);

}  // namespace jointlab::correlate
