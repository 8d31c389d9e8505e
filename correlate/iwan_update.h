// Iwan updating: the four parameters of one named Iwan set from measured backbones.
//
// Parameters p = (F_S [N], gamma, chi, beta) shared by every element of the set, with
// K_T = gamma K_s, K_s the set's linear stiffness in the given model (from the linear update).
// update_iwan() searches p against the objective (iwan_objective.h: the residuals over the
// measured backbones of iwan_backbone.h, the model curve, the comparison) with the optimiser of
// the options (iwan_options.h), and states the result with its uncertainty, what its misfit
// points at and a report (IwanUpdateSummary). This header includes those three, so that a caller
// needs it alone.
// Pareto front: for each gamma of a list the other three parameters are updated; each point
// gives the linear-frequency error |f_model,R - f_lin,exp| / f_lin,exp and the backbone cost.
#pragma once

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/iwan_backbone.h"
#include "jointlab/correlate/iwan_objective.h"
#include "jointlab/correlate/iwan_options.h"
#include "jointlab/model/iwan.h"

namespace jointlab::correlate {

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
  kOneHit,  ///< one of several curves carries all its information (one_curve_share): that hit's
            ///< joint's, whose scatter between hits no one hit shows: no sigma
  kHeldBetaRejected,  ///< fitted at a beta held as asked (--beta) that the data past phi_max
                      ///< reject (IwanUpdateSummary::held_beta_rejected()): no sigma
  kUnknown            ///< the covariance could not be formed at the result
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
  /// With beta held as asked (--beta) and the data past phi_max: how much a local solve from
  /// the result with beta freed lowers the chi-square (0: not tested), and the beta it reaches.
  double held_beta_chi2_drop = 0;
  double held_beta_freed = 0;  ///< the beta that local solve reaches
  /// The drop beyond which the data reject the beta held: the 1 in 1000 point of chi-square
  /// with one degree of freedom (10.83) times the freed fit's reduced chi-square where above 1.
  double held_beta_drop_limit = 0;
  /// Whether the data reject the beta held as asked (held_beta_chi2_drop above its limit): the
  /// other parameters' sigmas, given that beta, are not the joint's.
  bool held_beta_rejected() const {
    return held_beta_drop_limit > 0 && held_beta_chi2_drop > held_beta_drop_limit;
  }
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
  /// Per parameter (F_S, K_T, chi, beta) with curves of two or more hits: the largest share of
  /// its information at the result that one hit's curves alone carry (curves of one source, its
  /// channels or modes, together; 1 - its variance over its variance without them; 1 where the
  /// others leave it undetermined), and that hit's first curve (0-based, -1 where not computed):
  /// near 1 the parameter is that one hit's.
  std::array<double, 4> one_curve_share{};
  std::array<int, 4> one_curve{{-1, -1, -1, -1}};  ///< the curve of one_curve_share
  std::array<std::string, 4> one_curve_name;       ///< its source (file), or "curve N"
  int curves = 0;                                  ///< measured curves fitted, over every mode
  /// The hits behind them: curves of one source (a record's channels or modes) are one hit
  int hits = 0;
  /// True where parameter k (F_S, K_T, chi, beta) rests on one of several curves alone
  /// (one_curve_share above 0.99): the rest leave it next to undetermined.
  bool rests_on_one_curve(int k) const;
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
  /// sigmas: offsets of each curve from the others explain half the chi-square or more, or the
  /// curves differ in shape where they overlap while the model describes what they share
  /// (MisfitEvidence::hits_differ_in_shape()), three or more hits, and no curve lies apart from
  /// the others (MisfitEvidence::apart_curve: offsets that follow a hit are no random scatter).
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
