// Linear model updating: named joint stiffness sets tuned to measured linear frequencies.
//
// Parameters: theta_k > 0, the stiffness [N/m or N m/rad] shared by every joint element the
// model file names `name_k` ("spring.kz", or "iwan.rivet" whose elements enter at K_T):
//     K(theta) = K_0 + sum_k theta_k S_k,   S_k = sum over its elements of e e^T, e = e_a - e_b.
// Modes: K(theta) phi = omega^2 M phi, phi^T M phi = 1 (linear_modes.h), elastic modes only.
// Pairing (mac.h, pair_by_rules): at the start each measured shape is paired with a model mode
// by sensor MAC, gated by frequency (|f_model/f_exp - 1| <= frequency_window, 0.5 by default)
// and never with a mode invisible at the sensors; candidates alike at the sensors are told
// apart by frequency, and when neither can tell them the update stops (kAmbiguous) naming
// them. From then on every pair is followed by its full shape (mode_tracking.h: mass-weighted
// MAC with the previous accepted step, the step halved until the continuation is clear), so a
// pair never jumps to a mode that merely looks alike at a few sensors. At the result the pairs
// are made afresh by the same rules; when they differ, the fit runs again from there with the
// new pairs (at most three rounds), and pairs that still differ stop the update (kAmbiguous).
// Residuals over measured modes i
//     r_i = (f_model,p(i) - f_exp,i) / f_exp,i            (no residual when i is unpaired)
// each weighted by its own mode's relative frequency uncertainty
//     sigma_i = max(frequency_std, MeasuredModes::frequency_std_i),   w_i = frequency_std / sigma_i
// and the objective is 1/2 sum (w_i r_i)^2 (1/2 sum r_i^2 where every mode has the stated
// frequency_std): a mode whose files disagree counts for less, and widens only the sets it
// fixes. The chi-square sum (r_i / sigma_i)^2 below, the covariance, the profiles, the restarts'
// and the pairings' tests "within the noise" all use these weights. The optimiser (Ceres, trust
// region, bounds) works on x_k = ln theta_k, with the analytic eigenvalue sensitivity
//     d omega_i^2 / d theta_k = phi_i^T S_k phi_i,  so  d r_i / d x_k = theta_k phi_i^T S_k phi_i
//                                                         / (8 pi^2 f_model f_exp).
// Identifiability: s_k = max_i |d r_i / d x_k|, the largest relative frequency change per unit
// change of ln theta_k; a parameter with s_k below flat_sensitivity is flat (the objective
// does not see it). A flat set is not identified: it is held at its start (or where `holds`
// puts it) and the others are fitted again, so that no answer depends on where a flat set
// drifted between bounds nobody chose. One-at-a-time sweeps (theta_k times 10^[-d, d], the
// others held) follow every pair by its full shape from the result (the paper's Figure 3).
// Uncertainty at the result: covariance (J^T W^2 J)^-1 frequency_std^2 over the fitted sets,
// W = diag(w_i): each row of J over its own mode's sigma_i. Sets whose sensitivity columns nearly
// repeat one another (a singular value of J with unit columns below sqrt(1e-3)) act together: the
// frequencies fix only a combination (an Iwan element and a spring on one degree of freedom: their
// sum), so they are not identifiable and get no sigma; the inverse is then taken without those
// directions (the pseudo-inverse, right for the combinations and the other sets), the combination
// of two is named with its own sigma, and "fitted" below counts the combinations determined. With
// more pairs than fitted sets, the reduced chi-square
//     chi2_red = sum (r_i / sigma_i)^2 / (pairs - fitted)
// measures the scatter the model cannot explain (model-form error), and when it exceeds 1 the
// covariance is scaled by it: the scale is then estimated from the residuals, so the error over
// the scaled sigma follows Student's t over nu = pairs - fitted, and the covariance is widened
// by nu / (nu - 2) too, in part where chi2_red is below its one-sided 1-sigma point under the
// stated noise (the share growing from 0 at 1), and none is stated where nu <= 2.
// Smallest stiffness: with tolerance > 0, each flat parameter is then lowered to the
// smallest value (bisection in ln theta) at which every paired |r_i| is within the
// tolerance; when even its lower bound meets the tolerance the frequencies do not bound it
// and it stays held.
// The paper's rule (LinearRule::kSmallest): minimise theta_m of one named set subject to every
// paired |r_i| <= tolerance. Bisection on ln theta_m between its lower bound and the
// least-squares value; at each trial theta_m the other sets (flat ones held) are fitted by least
// squares, and the trial is feasible when every paired error is within the tolerance. When
// even the least-squares fit exceeds the tolerance the rule says so and keeps the
// least-squares result. A parameter that ends at a bound is reported with a warning.
// At the result the auto-MAC of the model shapes at the sensors flags model modes the sensors
// cannot tell apart (told apart here by frequency and by following full shapes).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "jointlab/correlate/mac.h"
#include "jointlab/correlate/mode_tracking.h"
#include "jointlab/correlate/noise_limits.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/model/model_file.h"

namespace jointlab::correlate {

/// K(theta) = K_0 + sum_k theta_k S_k for named joint element sets of a model.
class StiffnessSets {
 public:
  /// Splits the model's joint stiffness into the named sets; InputError for a name no joint uses.
  StiffnessSets(const model::Model& model, std::vector<std::string> names);
  /// Number of parameters.
  int size() const { return static_cast<int>(names_.size()); }
  /// Element names, one per parameter.
  const std::vector<std::string>& names() const { return names_; }
  /// The model's current stiffness of each set.
  const Eigen::VectorXd& initial() const { return initial_; }
  /// S_k: the stiffness pattern of set k (unit stiffness).
  const Eigen::SparseMatrix<double>& pattern(int k) const { return patterns_[k]; }
  /// K(theta).
  Eigen::SparseMatrix<double> stiffness(const Eigen::Ref<const Eigen::VectorXd>& theta) const;
  /// A copy of the model with each set at theta_k (Iwan elements: K_T = theta_k).
  model::Model apply(const Eigen::Ref<const Eigen::VectorXd>& theta) const;

 private:
  const model::Model* model_;
  std::vector<std::string> names_;
  Eigen::VectorXd initial_;
  Eigen::SparseMatrix<double> fixed_;  // K_0 plus every joint not in a set
  std::vector<Eigen::SparseMatrix<double>> patterns_;
};

/// Measured linear modal data: frequencies and complex shapes at the sensors.
struct MeasuredModes {
  Eigen::VectorXd frequency_hz;     ///< one per measured mode [Hz]
  Eigen::MatrixXcd shapes;          ///< rows: sensors (in sensor order), columns: modes
  std::vector<std::string> labels;  ///< a name per mode for reports ("band1"), may be empty
  /// Each mode's own name in reports and files: the table's `mode` number, the band's number, the
  /// campaign's mode name; empty (or an empty entry): its position, 1, 2, ...
  std::vector<std::string> ids;
  /// What reading the data found worth saying (a strongly complex shape realised as real):
  /// update_linear() puts them first among its report's warnings.
  std::vector<std::string> warnings;
  /// Per mode, the relative one-sigma uncertainty of its frequency that its data show (files
  /// that disagree: measured_data.h linear_spread()); empty or 0: none. update_linear() divides
  /// that mode's residual by the larger of it and its frequency_std (each mode its own).
  Eigen::VectorXd frequency_std;
  /// ids[i], or i + 1 where it has none.
  std::string id(Eigen::Index i) const;
  /// The modes in columns `keep`, in that order, each with its frequency, shape, label ("" where
  /// it has none) and id (id(i): its own name stays where its position changes); no warnings.
  MeasuredModes columns(const std::vector<Eigen::Index>& keep) const;
};

/// One evaluation of the linear objective.
struct LinearEvaluation {
  Pairing pairing;                     ///< measured-model pairs (by rules, or followed)
  Eigen::VectorXd model_frequency_hz;  ///< paired model frequency per measured mode (0: unpaired)
  Eigen::VectorXd residuals;           ///< r_i
  Eigen::MatrixXd jacobian;            ///< d r_i / d ln theta_k
  Eigen::VectorXd all_model_frequency_hz;  ///< every elastic model frequency
  Eigen::VectorXd measured_frequency_hz;   ///< the measured frequencies
  /// Per measured mode, whether its MAC reads a shape (entries at two sensors or more);
  /// where not, its MAC is no evidence and is reported empty.
  std::vector<bool> mac_reads_shape;
  Eigen::MatrixXd mac;                    ///< MAC, measured x elastic model modes
  Eigen::MatrixXd model_at_sensors;       ///< elastic model shapes at the sensors
  std::vector<int> hidden;                ///< model modes invisible at the sensors
  std::string ambiguity;                  ///< pairing by rules: what it cannot decide, or ""
  std::vector<PairingTie> ties;           ///< pairing by rules: the modes paired by a guess
  std::vector<std::string> measured_ids;  ///< MeasuredModes::ids
  /// Per measured mode, w_i = frequency_std / sigma_i, the weight of its residual in the cost and
  /// the chi-square (update_linear() sets it; empty: 1 each)
  Eigen::VectorXd weights;
  /// Measured mode i's own name (MeasuredModes::id).
  std::string measured_id(Eigen::Index i) const;
  /// sum (w_i r_i)^2 (sum r_i^2 where weights is empty).
  double weighted_squared_norm() const;
  /// 1/2 sum (w_i r_i)^2.
  double cost() const { return 0.5 * weighted_squared_norm(); }
  /// The MAC of measured mode i's pair where it reads a shape; nothing when i is unpaired or
  /// its shape has fewer than two sensors.
  std::optional<double> pair_mac(Eigen::Index i) const;
  /// Largest |r_i| over paired modes.
  double max_error() const;
};

/// Evaluates pairing (pair_by_rules, afresh), residuals and their analytic Jacobian at theta.
LinearEvaluation evaluate_linear(const StiffnessSets& sets, const model::Model& model,
                                 const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                                 const Eigen::Ref<const Eigen::VectorXd>& theta,
                                 const PairingRules& rules);

/// evaluate_linear() with the default rules but this MAC threshold and frequency window
/// (0: no window).
LinearEvaluation evaluate_linear(const StiffnessSets& sets, const model::Model& model,
                                 const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                                 const Eigen::Ref<const Eigen::VectorXd>& theta,
                                 double mac_threshold, double frequency_window = 0);

/// Residuals and Jacobian at theta for given pairs (measured mode i with elastic model column
/// columns[i], -1: unpaired), the model's elastic modes at theta given.
LinearEvaluation evaluate_pairs(const StiffnessSets& sets, const std::vector<Sensor>& sensors,
                                const MeasuredModes& measured,
                                const Eigen::Ref<const Eigen::VectorXd>& theta,
                                const ElasticModes& modes, const std::vector<int>& columns);

/// The stop rule of update_linear().
enum class LinearRule {
  kLeastSquares,  ///< least-squares frequency errors (flat sets lowered with tolerance > 0)
  kSmallest,      ///< the paper's: smallest `smallest_set` with every error within tolerance
};

/// Absolute bounds of one named set (overriding lower_factor and upper_factor).
struct ParameterBound {
  std::string name;  ///< element name ("spring.kx")
  double lower = 0;  ///< smallest stiffness, > 0
  double upper = 0;  ///< largest stiffness, > lower
};

/// A set held at a value (0: at its start) instead of fitted.
struct ParameterHold {
  std::string name;  ///< element name ("spring.rz")
  double value = 0;  ///< stiffness, > 0; 0: the model's
};

/// Settings of update_linear().
struct LinearUpdateOptions {
  double mac_threshold = 0.6;  ///< pairs below this MAC are not made
  double lower_factor = 1e-3;  ///< bounds: theta_k in [start * lower_factor, start * upper_factor]
  double upper_factor = 1e3;   ///< (both > 0, lower_factor < 1 < upper_factor)
  std::vector<ParameterBound> bounds;  ///< absolute bounds of named sets (override the factors)
  LinearRule rule = LinearRule::kLeastSquares;  ///< stop rule
  std::string smallest_set;       ///< kSmallest: the set minimised (a name of the sets)
  double frequency_window = 0.5;  ///< > 0: pairs also need |f_model/f_exp - 1| <= this
  double visibility = 1e-6;       ///< model modes below this squared norm at the sensors (relative)
                                  ///< are never paired by MAC (mac.h, PairingRules)
  std::vector<ParameterHold> holds;  ///< sets held, not fitted
  double alias_mac = 0.9;            ///< auto-MAC of two model modes at the sensors above: warned
  int max_iterations = 100;          ///< Ceres iterations
  double tolerance = 0;  ///< > 0: flat sets lowered to the smallest within it; kSmallest's bound
  double flat_sensitivity = 1e-3;  ///< s_k below this: flat
  double frequency_std = 1e-3;     ///< relative frequency uncertainty for confidence
  double sweep_decades = 2;        ///< one-at-a-time sweep over theta * 10^[-d, d]
  int sweep_points = 9;            ///< points of the sweep (>= 2)
  /// Fit the shapes whatever their signs: no reversed-channel check (shape_checks.h).
  bool trust_signs = false;
  /// Called after each optimiser iteration with (iteration, cost, largest |r_i|).
  std::function<void(int, double, double)> progress;
  /// Called before each model solve of the fit, its refits, profiles and sweeps, also on the
  /// sweeps' worker threads (so it must be thread-safe); it may throw to stop the work (the Python
  /// module's Ctrl-C). Refits keep it where they drop `progress`.
  std::function<void()> interrupt;
  /// What is wrong with these options, or "".
  std::string error() const;
};

/// What update_linear() found about one parameter.
struct ParameterReport {
  std::string name;        ///< element name
  double start = 0;        ///< starting stiffness
  double value = 0;        ///< updated stiffness
  double sensitivity = 0;  ///< s_k at the solution
  bool flat = false;       ///< s_k < flat_sensitivity
  /// A flat set held back at its start: where the fit had taken it, and s_k there (0: not so)
  double drifted_to = 0, drifted_sensitivity = 0;
  bool held = false;          ///< not fitted: held by the user, or flat
  bool held_by_user = false;  ///< held by LinearUpdateOptions::holds
  /// Fitted sets whose sensitivities this one's nearly repeats (LinearUpdateSummary::collinear):
  /// the frequencies determine a combination of them, not this set alone (empty: none).
  std::vector<std::string> acts_with;
  /// +1: the frequencies bound it from below only, -1: from above only (moved that way to its
  /// bound, the other sets fitted again, the chi-square rises by less than 9, or the pairs are
  /// lost first: a stiffness whose sensitivity dies away as it stiffens); 0: both ways, or not
  /// checked
  int one_sided = 0;
  std::optional<double> relative_std;  ///< one-sigma relative uncertainty (none: not fitted)
  /// Where relative_std is a third of the chi-square profile's 3-sigma distance, wider than the
  /// local slope gives: the local slope's (none: relative_std is the local slope's)
  std::optional<double> slope_std;
  double smallest_within_tolerance = 0;  ///< set when the tolerance formulation lowered it
  double lower = 0, upper = 0;           ///< its bounds
  int at_bound = 0;                      ///< -1: ends at its lower bound, +1: upper, 0: inside
  std::vector<double> sweep_factor;      ///< theta_k multipliers of the sweep
  /// RMS relative frequency error over the followed pairs at each multiplier (none: no pair)
  std::vector<std::optional<double>> sweep_rms;
  /// r_i of every measured mode at each multiplier, its pair followed by shape (none: unpaired
  /// or not followed)
  std::vector<std::vector<std::optional<double>>> sweep_errors;
  /// Identified by the frequencies: neither flat, nor acting together with another set, nor
  /// bounded from one side only.
  bool identifiable() const { return !flat && acts_with.empty() && one_sided == 0; }
};

/// Fitted sets whose sensitivities nearly repeat one another: a direction of their ln theta the
/// frequencies do not see (a singular value of the Jacobian, its columns scaled to unit length,
/// below sqrt(1e-3): for two sets, a correlation of their sensitivities above 0.999), such as
/// an Iwan element and a spring on the same degree of freedom, of which only the sum counts.
struct CollinearSets {
  std::vector<int> sets;   ///< indices of LinearUpdateSummary::parameters, ascending
  int determined = 0;      ///< combinations of them the frequencies determine (< sets.size())
  double correlation = 0;  ///< two sets: |cos| of the angle between their sensitivity columns
  /// Two sets a, b: the combination w = theta_a + weight theta_b the frequencies determine, its
  /// value at the result and one-sigma relative uncertainty (none where none is stated); with
  /// more sets, weight and value are 0, and value is 0 (no relative_std) where w is not constant
  /// along the frequencies' valley (valley_low < valley_high below).
  double weight = 0, value = 0;
  std::optional<double> relative_std;
  /// Two sets: where w changes along the valley of equal fit (set a moved, the others fitted
  /// again, the chi-square within 9 of the result's) by more than half its standard deviation
  /// (a curved combination, such as two springs in series), the least and largest w there and
  /// set a's range walked; all 0 where w holds along it.
  double valley_low = 0, valley_high = 0, walked_low = 0, walked_high = 0;
};

/// Why update_linear() stopped.
enum class LinearUpdateStatus {
  kConverged,       ///< the optimiser met its convergence test
  kIterationLimit,  ///< max_iterations reached
  kTooFewPairs,     ///< fewer paired modes than needed to say anything (none)
  kFailed,          ///< the optimiser failed (numerical)
  kAmbiguous,       ///< the pairs cannot be decided (see LinearUpdateSummary::ambiguity)
  kShapesRefused,   ///< a channel reads reversed, or shapes lack their phase (shape_problem)
  /// The fit ended (converged or at its iteration limit), but at the result a paired measured
  /// mode's MAC with its partner is below mac_threshold: its pair rests on the start's MACs and
  /// on following shapes, not on its shape (LinearUpdateSummary::unconfirmed says which, and why)
  kPairsUnconfirmed,
};

/// Outcome of update_linear().
struct LinearUpdateSummary {
  LinearUpdateStatus status = LinearUpdateStatus::kFailed;  ///< termination
  double initial_cost = 0;                                  ///< objective at the start
  double final_cost = 0;                                    ///< objective at the result
  int iterations = 0;                                       ///< optimiser iterations
  std::vector<double> history;                 ///< objective after each iteration (first: start)
  std::vector<Eigen::VectorXd> theta_history;  ///< every set's stiffness at each history entry
  std::string rule;            ///< the rule that produced the result, for the headline
  bool tolerance_met = true;   ///< kSmallest: false when no stiffness meets the tolerance
  std::string ambiguity;       ///< kAmbiguous: which modes, and why
  std::string units;           ///< kAmbiguous: why it looks like rad/s read as Hz, or ""
  std::string shape_problem;   ///< kShapesRefused: what is wrong with the shapes
  std::string unconfirmed;     ///< kPairsUnconfirmed: the pairs, why, and what to do
  bool fit_converged = false;  ///< kPairsUnconfirmed: the fit itself met its convergence test
  int rounds = 0;              ///< fits run (a new round when the pairs change)
  double reduced_chi2 = 0;     ///< sum (r_i/sigma_i)^2 / (pairs - fitted); 0: no dof left
  double chi2 = 0;             ///< sum (r_i/sigma_i)^2 of the least-squares fit
  /// Fits from different starts behind the result: 1, or 1 + the restarts tried where the fit
  /// from the start left scatter beyond the noise (reduced_chi2_limit)
  int starts = 1;
  /// The restarts tried and which won, for the report ("": none tried)
  std::string restarts;
  /// kPairsUnconfirmed: the measured modes (rows) whose pairs the shapes do not confirm
  std::vector<int> unconfirmed_modes;
  /// pairs - fitted sets (sets acting together count as the combinations determined)
  int degrees_of_freedom = 0;
  double frequency_std = 0;  ///< the stated relative frequency uncertainty
  /// Per measured mode, the relative frequency uncertainty its residual was divided by:
  /// max(frequency_std, MeasuredModes::frequency_std_i)
  Eigen::VectorXd mode_frequency_std;
  /// The standard deviations rest on the scatter (reduced_chi2 > 1, with a degree of freedom
  /// left): sqrt(reduced_chi2) times those of the stated noise, and widened by Student's t
  /// (t_widening); false: they assume the stated frequency_std.
  bool sigma_from_scatter = false;
  /// The factor by which sigma_from_scatter standard deviations are widened for Student's t over
  /// nu = degrees_of_freedom: sqrt(nu / (nu - 2)) once reduced_chi2 passes its one-sided 1-sigma
  /// point under the stated noise, part of it between 1 and there; 0 where nu <= 2 leaves none
  /// stated; 1 where the stated noise sets them.
  double t_widening = 1;
  LinearEvaluation start;             ///< pairing and residuals at the start
  Eigen::MatrixXd final_mac;          ///< MAC (measured x elastic model modes) at the result
  std::vector<std::string> warnings;  ///< parameters at bounds, aliased modes, unmet tolerance
  std::vector<ParameterReport> parameters;  ///< per parameter
  std::vector<CollinearSets> collinear;     ///< fitted sets acting together, each group once
  LinearEvaluation final;                   ///< pairing and residuals at the result
  /// One paragraph: status, cost, pairs, per-mode errors, parameters, warnings.
  std::string report() const;
};

/// Pairs of model modes (columns of shapes at the sensors) whose auto-MAC is at least
/// threshold: the sensors cannot tell them apart. Each entry (j, k, MAC), j < k.
struct AliasedModes {
  int a = 0, b = 0;  ///< model columns
  double mac = 0;    ///< their auto-MAC at the sensors
};
/// Every aliased pair among the given model shapes at the sensors.
std::vector<AliasedModes> aliased_modes(const Eigen::Ref<const Eigen::MatrixXd>& at_sensors,
                                        double threshold);

/// Why update_linear() gave no result (no measured mode paired, pairs that cannot be decided, or
/// shapes refused: the command refuses each), or "" when it gave one; `source` names the measured
/// data in the message ("" for none).
std::string linear_refusal(const LinearUpdateSummary& summary, const LinearUpdateOptions& options,
                           const std::string& source);

/// Updates the named sets of `model` to the measured frequencies; returns theta.
/// InputError for bad options, unknown sets or inconsistent sensors/measured shapes (a
/// measured mode whose shape is zero at every sensor while others have shapes among them).
Eigen::VectorXd update_linear(const model::Model& model, const std::vector<std::string>& sets,
                              const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                              const LinearUpdateOptions& options, LinearUpdateSummary* summary);

}  // namespace jointlab::correlate
