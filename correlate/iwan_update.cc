// The Iwan update: the fit driver (search, the start as a candidate, bounds, slips, covariance,
// misfit evidence, linear-part sensitivity) and the Pareto front over gamma.
#include "jointlab/correlate/iwan_update.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <random>
#include <string>

#include <fmt/format.h>
#include <boost/math/distributions/students_t.hpp>

#include "jointlab/core/error.h"
#include "jointlab/correlate/iwan_coordinates_detail.h"
#include "jointlab/correlate/iwan_covariance_detail.h"
#include "jointlab/correlate/iwan_search_detail.h"
#include "jointlab/correlate/iwan_sensitivity_detail.h"
#include "jointlab/correlate/noise_limits.h"
#include "jointlab/model/iwan.h"

namespace jointlab::correlate {

namespace {

using iwan_detail::Box;
using iwan_detail::constant_candidate;
using iwan_detail::covariance;
using iwan_detail::global_local;
using iwan_detail::held_parameters;
using iwan_detail::initial_box;
using iwan_detail::linear_part_sensitivity;
using iwan_detail::local_solve;
using iwan_detail::monte_carlo;
using iwan_detail::SerialNoise;
using iwan_detail::t_degrees_of_freedom;
using iwan_detail::to_params;
using iwan_detail::to_x;
using iwan_detail::Tracker;
using iwan_detail::Vec4;
using iwan_detail::widen_for_scatter;

// The free parameters of v that end within 1e-3 of their range (in the search coordinates x) of
// a bound, and a fitted Z that ends at one, e.g. "Fs at its upper bound 2000 N" (the bound itself,
// to rounding) or "Fs 1985 N, near its upper bound 2000 N" (within the tolerance: the search was
// pressing on it); `side` receives -1 / +1 per parameter (F_S, K_T, chi, beta, Z) at or near its
// lower / upper bound.
std::vector<std::string> bounds_reached(const IwanUpdateOptions& options, const Vec4& v,
                                        std::optional<double> z, std::array<int, 5>& side) {
  const Box box = initial_box(options);
  const Vec4 x = to_x(v), lo = to_x(box.lo), hi = to_x(box.hi);
  static const char* names[] = {"Fs", "gamma (Kt/Ks)", "chi", "beta"};
  static const char* units[] = {" N", "", "", ""};
  std::vector<std::string> out;
  side.fill(0);
  for (int k = 0; k < 4; ++k) {
    if (!(hi(k) > lo(k))) continue;  // held
    const double tol = 1e-3 * (hi(k) - lo(k)), exact = 1e-9 * (hi(k) - lo(k));
    const double value = v(k);
    const auto say = [&](const char* which, double bound, double distance) {
      return distance <= exact
                 ? fmt::format("{} at its {} bound {:.6g}{}", names[k], which, bound, units[k])
                 : fmt::format("{} {:.6g}{}, near its {} bound {:.6g}{}", names[k], value, units[k],
                               which, bound, units[k]);
    };
    if (x(k) <= lo(k) + tol) {
      side[k] = -1;
      out.push_back(say("lower", box.lo(k), x(k) - lo(k)));
    } else if (x(k) >= hi(k) - tol) {
      side[k] = 1;
      out.push_back(say("upper", box.hi(k), hi(k) - x(k)));
    }
  }
  // Z is the weighted mean of the damping residuals clamped to [0, zmax] (IwanObjective): at a
  // bound it is the bound itself, so only the bound itself is called one (a tolerance of 1e-3
  // zmax called a fitted 2e-5 "at its lower bound 0" beside its value).
  if (z) {
    const double zmax = options.linear_damping_max;
    if (*z <= 0) {
      side[4] = -1;
      out.push_back("modal_ratio at its lower bound 0 (the joints explain all the damping)");
    } else if (*z >= zmax) {
      side[4] = 1;
      out.push_back(fmt::format("modal_ratio at its upper bound {:.6g}", zmax));
    }
  }
  return out;
}

void set_slips(const IwanObjective& objective, IwanUpdateSummary& s) {
  const Eigen::Vector2d slip = objective.slip_range(s.best);
  s.bottom_slip = slip(0);
  s.top_slip = slip(1);
  s.phi_max = model::Iwan(s.best).phi_max();
}

// The summary's fields known before the search: the start, what is held, the floors.
void start_summary(const IwanObjective& objective, const IwanUpdateOptions& options,
                   IwanUpdateSummary& s) {
  s = IwanUpdateSummary{};
  s.optimizer = options.optimizer;
  s.start = objective.initial();
  s.held = held_parameters(options);
  s.modal_ratio_start = objective.model_linear_damping();
  s.modal_ratio_fitted = objective.fits_linear_damping();
  s.residuals = static_cast<size_t>(objective.residual_count());
  s.floored = objective.floored_points();
  s.frequency_floor = options.frequency_floor;
  s.damping_floor = options.damping_floor;
  s.reference_stiffness = objective.reference_stiffness();
  s.linear_known = std::any_of(objective.targets().begin(), objective.targets().end(),
                               [](const IwanTarget& t) { return t.linear_frequency_hz > 0; });
}

// The search the options name, from the constant-backbone candidate where Z is fitted.
void search(Tracker& tr) {
  const IwanObjective& objective = tr.objective;
  const IwanUpdateOptions& options = tr.options;
  IwanUpdateSummary& s = tr.summary;
  std::mt19937 rng(options.seed);
  std::optional<std::pair<double, Vec4>> constant;
  if (objective.fits_linear_damping()) {
    constant = constant_candidate(tr);
    s.constant_cost = constant->first;
  }
  switch (options.optimizer) {
    case IwanOptimizer::kPaper:
      monte_carlo(tr, false, rng);
      break;
    case IwanOptimizer::kPaperLog:
      monte_carlo(tr, true, rng);
      break;
    case IwanOptimizer::kGlobalLocal:
      global_local(tr, rng, constant ? &*constant : nullptr);
      break;
  }
}

// The start with the held parameters at their held values: K_T = gamma K_s as asked.
model::IwanParameters held_start(const IwanObjective& objective, const IwanUpdateOptions& options,
                                 const model::IwanParameters& given) {
  model::IwanParameters start = given;
  if (options.fixed_gamma > 0) start.Kt = options.fixed_gamma * objective.reference_stiffness();
  if (options.fixed_beta) start.beta = *options.fixed_beta;
  return start;
}

// The summary's best, final cost and whether the search improved on the start, and the best in
// search coordinates. The start is a candidate too when it lies in the search box (held
// parameters at their values): never hand back parameters that fit worse, nor any outside the
// given ranges.
Vec4 choose_best(const Tracker& tr, const model::IwanParameters& start, IwanUpdateSummary& s) {
  const IwanObjective& objective = tr.objective;
  const IwanUpdateOptions& options = tr.options;
  const Box box = initial_box(options);
  const double Ks = objective.reference_stiffness();
  const Vec4 start_v(start.Fs, start.Kt / Ks, start.chi, start.beta);
  bool start_inside = true;
  for (int k = 0; k < 4; ++k) {
    const double slack = 1e-12 * std::max(std::abs(box.lo(k)), std::abs(box.hi(k)));
    start_inside =
        start_inside && start_v(k) >= box.lo(k) - slack && start_v(k) <= box.hi(k) + slack;
  }
  const double start_cost = !start_inside ? INFINITY
                            : start.Kt == s.start.Kt && start.beta == s.start.beta
                                ? s.initial_cost
                                : objective.try_cost(start).value_or(INFINITY);
  Vec4 best_v;
  if (start_cost <= tr.best) {
    s.improved = false;
    best_v = start_v;
    s.best = start;
    s.final_cost = start_cost;
  } else {
    // Inside the box also after the round trip through the search coordinates (exp(log(60))
    // is 59.99999999999999).
    best_v = tr.best_v.cwiseMax(box.lo).cwiseMin(box.hi);
    s.best = to_params(best_v, Ks);
    s.final_cost = tr.best;
  }
  return best_v;
}

// What the result is besides its parameters: Z, the bounds reached, the linear error, the slips
// and the RMS errors.
void describe_result(const IwanObjective& objective, const IwanUpdateOptions& options,
                     const Vec4& best_v, IwanUpdateSummary& s) {
  s.modal_ratio = objective.linear_damping(s.best).value_or(s.modal_ratio_start);
  s.at_bounds = bounds_reached(
      options, best_v, s.modal_ratio_fitted ? std::optional<double>(s.modal_ratio) : std::nullopt,
      s.bound_side);
  if (!s.improved) s.at_bounds.clear(), s.bound_side.fill(0);  // the start: not a fit's end
  s.linear_error = objective.linear_error(s.best);
  set_slips(objective, s);
  if (const auto e = objective.rms_errors(s.best, s.modal_ratio)) s.rms_errors = *e;
  s.constant_rms_errors = objective.constant_rms_errors();
}

// The parameters the covariance is over: (F_S, gamma, chi, beta) not held (0-3), and Z (4) where
// fitted.
std::vector<int> free_parameters(const IwanUpdateSummary& s) {
  std::vector<int> free;
  for (int k = 0; k < 4; ++k)
    if (!s.held[k]) free.push_back(k);
  if (s.modal_ratio_fitted) free.push_back(4);
  return free;
}

// The covariance at the result over `free` (beta dropped from it where the data fix F_S and beta
// only together), and the residuals' noise behind it.
Eigen::MatrixXd parameter_covariance(const IwanObjective& objective, const Vec4& best_v,
                                     std::vector<int>& free, SerialNoise& noise,
                                     IwanUpdateSummary& s) {
  iwan_detail::CurveShares shares;
  Eigen::MatrixXd cov = covariance(objective, free, best_v, s.modal_ratio, &s.reduced_chi2, &noise,
                                   &s.fixed_at_kink, &shares);
  // Too few effective points is no flat direction: holding beta would not make it a sigma.
  const auto too_few = [&] {
    return noise.effective_points > 0 &&
           !(t_degrees_of_freedom(noise.effective_points, static_cast<int>(free.size())) > 2);
  };
  // Microslip data fix R, not F_S and beta apart (a flat direction: H singular or nearly so):
  // the covariance of the others with beta held (F_S then stands for R), beta's sigma unknown.
  const auto beta = std::find(free.begin(), free.end(), 3);
  if (beta != free.end() && ((cov.size() == 0 && !too_few()) || s.microslip_only())) {
    free.erase(beta);
    cov = covariance(objective, free, best_v, s.modal_ratio, &s.reduced_chi2, &noise,
                     &s.fixed_at_kink, &shares);
  }
  s.one_curve_share = shares.share;
  s.one_curve = shares.curve;
  std::vector<std::string> names;
  for (const IwanTarget& t : objective.targets())
    for (const MeasuredBackbone& c : t.curves)
      names.push_back(!c.source.empty() ? c.source : fmt::format("curve {}", names.size() + 1));
  s.curves = static_cast<int>(names.size());
  s.hits = static_cast<int>(iwan_detail::curve_hits(objective).second.size());
  for (size_t k = 0; k < 4; ++k)
    if (s.one_curve[k] >= 0 && s.one_curve[k] < static_cast<int>(names.size()))
      s.one_curve_name[k] = names[static_cast<size_t>(s.one_curve[k])];
  return cov;
}

// The summary's covariance, relative sigmas and Z's sigma from cov over `free`, none where the
// data fix F_S only with beta or the fit did not converge.
void set_sigmas(const std::vector<int>& free, const Eigen::MatrixXd& cov, IwanUpdateSummary& s) {
  if (cov.size() > 0) {
    for (size_t i = 0; i < free.size(); ++i) {
      for (size_t j = 0; j < free.size(); ++j) {
        if (free[i] < 4 && free[j] < 4) s.covariance(free[i], free[j]) = cov(i, j);
      }
      if (free[i] == 4) s.modal_ratio_std = std::sqrt(std::max(cov(i, i), 0.0));
    }
  }
  for (int k = 0; k < 4; ++k) {
    const double sd = std::sqrt(std::max(s.covariance(k, k), 0.0));
    s.relative_std(k) = k != 2 ? sd : std::abs(s.best.chi) > 0 ? sd / std::abs(s.best.chi) : 0.0;
  }
  // With beta free and the data in microslip, F_S's sigma above is that at beta held: F_S then
  // stands for R, not for itself, and is not known (40 microslip fits of 3 hits: F_S 35 % off
  // with a stated 0.7 %, z 33). With beta held, by the user or the run, it is F_S given beta.
  if (!s.held[3] && s.microslip_only()) s.relative_std(0) = 0;
  // Not converged: the point is where the search stopped, not a minimum, and a covariance there
  // describes the slope it was still descending, not the data (7 of 12 one-curve fits at the
  // default budget stated chi 4.6 sigma off before the polish).
  if (s.status == IwanUpdateStatus::kBudget) {
    s.relative_std.setZero();
    s.covariance.setZero();
    s.modal_ratio_std = 0;
  }
}

// The variance factor of Student's t with nu degrees of freedom for the sigmas of scatter
// between curves: nu / (nu - 2); with three curves (nu = 2, an infinite variance) the square of
// t's 95 % quantile over the normal's, (4.303 / 1.960)^2 = 4.82, so that 1.96 sigma is t's 95 %
// interval (IwanUpdateSummary::scatter_explains_misfit()).
std::optional<double> scatter_t_variance(double nu) {
  if (const std::optional<double> v = student_t_variance(nu)) return v;
  if (nu != 2) return std::nullopt;
  const double q = boost::math::quantile(boost::math::students_t(nu), 0.975);
  return q * q / (1.959963984540054 * 1.959963984540054);
}

// Whether the data reject a beta held as asked (--beta): a local solve from the result with beta
// freed, and the chi-square it gains (IwanUpdateSummary::held_beta_rejected()). Tested only where
// the data reach past phi_max (in microslip beta is not identified apart from F_S) and the fit
// converged inside the box. Before, --beta 0.45 on a joint of 0.5 (three hits without scatter,
// into deep macroslip) stated chi -0.4946 +/- 0.21 % against the joint's -0.5, 3-6 sigma off in
// 40 of 40 fits, the report warning only of a reduced chi-square of 1.3; freed, beta lowered the
// chi-square by 16.5-77 (0.0-10.8 at the joint's 0.5).
void test_held_beta(const IwanObjective& objective, const IwanUpdateOptions& options,
                    const Vec4& best_v, int free_count, IwanUpdateSummary& s) {
  // Where the hits' scatter explains the misfit the hits, not the points, are the samples, and
  // the points' chi-square overstates what freeing beta gains: F_S and K_T scattered 5 % / 2 %
  // between five hits, beta held at the joint's 0.5, 5 of 40 fits "rejected" it so (their
  // sigmas widened by that scatter state none beyond 3 there).
  if (!options.fixed_beta || s.status != IwanUpdateStatus::kConverged || !s.improved ||
      s.microslip_only() || !(s.top_slip > 0) || s.residuals == 0 || s.scatter_explains_misfit())
    return;
  IwanUpdateOptions freed = options;
  freed.fixed_beta.reset();
  freed.progress = nullptr;
  const Box box = initial_box(freed);
  if (!(*options.fixed_beta > box.lo(3) && *options.fixed_beta < box.hi(3))) return;
  IwanUpdateSummary scratch;
  Tracker tr{objective, freed, scratch, objective.evaluations()};
  local_solve(tr, best_v, 400, 50);
  if (!std::isfinite(tr.best) || !(tr.best < s.final_cost)) return;
  const double half = static_cast<double>(s.residuals) / 2;  // cost * N: the chi-square
  const double dof = static_cast<double>(s.residuals) - free_count - 1;
  s.held_beta_chi2_drop = (s.final_cost - tr.best) * half;
  s.held_beta_freed = tr.best_v(3);
  s.held_beta_drop_limit = 10.828 * std::max(1.0, tr.best * half / std::max(dof, 1.0));
}

}  // namespace

// Where scatter between the curves explains the misfit the sigmas rest on the cluster
// covariance, whose variance has the hits (the clusters) less 1 degrees of freedom: Student's t
// with the fewer of those and the points' (the seven curves of the two joint sets: 6 against
// 160). Curves of one hit share its joint: three hits at two channels each are three samples.
// The hits' factor replaces the points' only where it is the larger: three hits' 4.82 (a 95 %
// quantile's square, not a variance) lies below the points' nu / (nu - 2) between 2 and 2.52 of
// their degrees of freedom, and the swap narrowed the covariance there (by 0.80 at 2.4, 0.12 at
// 2.05).
void iwan_detail::widen_for_scatter(const IwanUpdateSummary& s, Eigen::MatrixXd& cov) {
  if (s.scatter_explains_misfit() && cov.size() > 0) {
    const double nu = static_cast<double>(std::min(s.evidence->curves, s.hits) - 1);
    const std::optional<double> wide = scatter_t_variance(nu),
                                narrow = student_t_variance(s.sigma_degrees_of_freedom);
    if (wide && narrow) cov *= std::max(1.0, *wide / *narrow);
  }
}

model::IwanParameters update_iwan(const IwanObjective& objective, const IwanUpdateOptions& options,
                                  IwanUpdateSummary* summary) {
  if (const std::string e = options.error(); !e.empty()) throw InputError("update-iwan: " + e);
  IwanUpdateSummary local;
  IwanUpdateSummary& s = summary ? *summary : local;
  start_summary(objective, options, s);
  Tracker tr{objective, options, s, objective.evaluations()};
  s.initial_cost = objective.try_cost(s.start).value_or(INFINITY);
  search(tr);
  s.evaluations = tr.used();
  const model::IwanParameters start = held_start(objective, options, s.start);
  if (!std::isfinite(tr.best)) {
    s.status = IwanUpdateStatus::kNoValidPoint;
    s.improved = false;
    s.best = start;
    s.final_cost = objective.try_cost(start).value_or(INFINITY);
    s.modal_ratio = objective.linear_damping(start).value_or(s.modal_ratio_start);
    return start;
  }
  const Vec4 best_v = choose_best(tr, start, s);
  describe_result(objective, options, best_v, s);
  std::vector<int> free = free_parameters(s);
  SerialNoise noise;
  Eigen::MatrixXd cov = parameter_covariance(objective, best_v, free, noise, s);
  s.effective_points = noise.effective_points;
  s.sigma_degrees_of_freedom =
      t_degrees_of_freedom(noise.effective_points, static_cast<int>(free.size()));
  s.noise_correlation = noise.rho;
  s.amplitude_share = noise.amplitude_share;
  // Only a misfit has a cause to name (an eigensolution of the model as given, so not always).
  // Each curve's own fit holds what this fit held: the options' and the fit's holds, and a
  // parameter pinned at a bound of the search box, which the fit could move no further either
  // (beta at the upper bound 0.35 of --beta-range 0.1:0.35 on a joint of 0.5, three hits
  // scattered 5 % / 2 %: freed there, each curve's beta took up the shared error, a chi-square of
  // 211 over 168 and F 1.81, and the offsets were named scatter with sigmas stated, as for
  // --beta 0.35 before 05cc406). A value --gamma or --beta states is freed there where the
  // curves' own values scatter about it (misfit_evidence()'s `stated`).
  if (s.misfit()) {
    std::array<bool, 4> held = s.held;
    for (size_t k = 0; k < 4; ++k) held[k] = held[k] || s.bound_side[k] != 0;
    s.evidence = objective.misfit_evidence(s.best, s.modal_ratio, held,
                                           iwan_detail::held_parameters(options));
  }
  widen_for_scatter(s, cov);
  set_sigmas(free, cov, s);
  test_held_beta(objective, options, best_v, static_cast<int>(free.size()), s);
  // How far an error of the rest of the model moves the parameters, which no residual shows
  // where K_T takes it up (a converged fit's minimum only: elsewhere the gradient is not 0).
  if (s.status == IwanUpdateStatus::kConverged && s.improved)
    linear_part_sensitivity(objective, free, best_v, s.modal_ratio, s);
  s.linear_part_updated = options.linear_part_updated;
  // Every other parameter whose words state no sigma (the start, data without slip) has no
  // number either: parameters.csv and Python read relative_std, the report sigma_reason(), and a
  // start that no candidate improved on stated its sigma in Python where the report said
  // "(sigma unknown)" and parameters.csv left it empty.
  s.clear_unstated_sigmas();
  return s.best;
}

std::vector<ParetoPoint> pareto_front(const IwanObjective& objective,
                                      const std::vector<double>& gammas,
                                      const IwanUpdateOptions& options) {
  std::vector<ParetoPoint> out;
  for (double g : gammas) {
    if (!(g > 0)) throw InputError(fmt::format("Pareto front: gamma {} must be > 0", g));
    IwanUpdateOptions o = options;
    o.fixed_gamma = g;
    IwanUpdateSummary s;
    ParetoPoint p;
    p.gamma = g;
    p.params = update_iwan(objective, o, &s);
    if (s.status == IwanUpdateStatus::kNoValidPoint) {
      throw InputError(fmt::format(
          "Pareto front: at gamma {} (K_T = {:.6g} N/m) no parameter set in the bounds gives a "
          "QSMA curve over the measured amplitudes",
          g, g * objective.reference_stiffness()));
    }
    p.linear_error = s.linear_error;
    p.backbone_cost = s.final_cost;
    out.push_back(p);
  }
  // Every measured linear mode's error, its pair followed by shape along the gammas; the
  // linear error of a point is the largest of them when there are any.
  const std::vector<std::vector<std::optional<double>>> along =
      objective.linear_errors_along(gammas);
  for (size_t i = 0; i < out.size(); ++i) {
    out[i].mode_errors = along[i];
    double largest = -1;
    for (const std::optional<double>& e : along[i])
      if (e) largest = std::max(largest, std::abs(*e));
    if (largest >= 0) out[i].linear_error = largest;
  }
  for (ParetoPoint& a : out) {
    for (const ParetoPoint& b : out) {
      if (&a != &b && b.linear_error <= a.linear_error && b.backbone_cost <= a.backbone_cost &&
          (b.linear_error < a.linear_error || b.backbone_cost < a.backbone_cost)) {
        a.dominated = true;
      }
    }
  }
  return out;
}

}  // namespace jointlab::correlate
