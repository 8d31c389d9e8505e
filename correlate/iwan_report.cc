// The Iwan update's report (IwanUpdateSummary::report()): the outcome, the parameters with their
// sigmas, the linear part's effect, and the warnings and notes on bounds, misfit, convergence,
// serial correlation, floors, slip and kinks.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/correlate/iwan_cause_detail.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/model/iwan.h"

namespace jointlab::correlate {
namespace {

using iwan_detail::amplitudes_read_too_large;
using iwan_detail::amplitudes_read_too_small;
using iwan_detail::kt_stopped_short;
using iwan_detail::model_as_given_matches;

// "its largest slip at the highest measured amplitude, 8.3e-12 m, is 3.6e-08 of phi_max 0.000232
// m" (joint_hardly_moved()), or that it leaves the joint still.
std::string hardly_moved_words(const IwanUpdateSummary& s) {
  if (!(s.top_slip > 0))
    return fmt::format(
        "it leaves the joint still: no slip at any measured amplitude, phi_max {:.3g} m",
        s.phi_max);
  return fmt::format(
      "its largest slip at the highest measured amplitude, {:.3g} m, is {:.2g} of phi_max {:.3g} m",
      s.top_slip, s.top_slip / s.phi_max, s.phi_max);
}

// The (F_S, beta) pairs that fit microslip data alike (slip_force_at_beta() of the result at a few
// betas, those whose phi_max stays above the largest measured slip), as the end of the report's
// slip line.
std::string microslip_family(const IwanUpdateSummary& s) {
  std::vector<std::string> pairs;
  for (const double b : {0.25, 0.5, 1.0, 2.0, 4.0}) {
    model::IwanParameters p = s.best;
    p.Fs = slip_force_at_beta(s.best, b);
    p.beta = b;
    if (!(p.Fs > 0) || !(model::Iwan(p).phi_max() > s.top_slip)) continue;
    pairs.push_back(fmt::format("{:.3g} N at beta {:g}", p.Fs, b));
  }
  if (pairs.empty()) return "";
  return fmt::format(
      ": every (Fs, beta) with the fitted Kt and chi and the same microslip dissipation fits "
      "these data alike ({}){}",
      fmt::join(pairs, ", "),
      s.beta_held_as_asked() ? std::string()
                             : std::string("; data past phi_max separate them, or hold beta at a "
                                           "known value with --beta"));
}

// The first line: the outcome, the evaluations, the cost and the linear frequency error.
std::string outcome_line(const IwanUpdateSummary& s) {
  const bool monte_carlo = s.optimizer != IwanOptimizer::kGlobalLocal;
  const std::string outcome = s.status == IwanUpdateStatus::kNoValidPoint ? "no valid sample"
                              : !s.improved          ? "no candidate improved on the start"
                              : !s.at_bounds.empty() ? "stopped at a bound of the search range"
                              : s.status == IwanUpdateStatus::kBudget
                                  ? (monte_carlo ? "not converged (the evaluation budget ran out "
                                                   "with the Monte Carlo still improving)"
                                                 : "not converged (the local solve from the best "
                                                   "point was still descending when its "
                                                   "evaluations ran out)")
                              : monte_carlo ? "converged (a Monte Carlo round brought no gain)"
                                            : "converged (the local solve from the best point met "
                                              "its tolerance)";
  // A cost the model could not evaluate is said so, never printed as a number.
  const auto cost_text = [](double c) {
    return std::isfinite(c) ? fmt::format("{:.4g}", c) : std::string("(not evaluable)");
  };
  // The polish may pass the budget: say by how much, so the count is not read as a bug.
  const std::string past =
      s.polish_evaluations > 0
          ? fmt::format(
                " ({} of them past the budget, carrying the local solve from the best "
                "point on toward its tolerance)",
                s.polish_evaluations)
          : std::string();
  std::string out = fmt::format(
      "Iwan update: {}, {} QSMA evaluations{}, {} {}, cost {} -> {}, {}\n", outcome, s.evaluations,
      past, s.rounds, monte_carlo ? "Monte Carlo rounds" : "local refinements",
      cost_text(s.initial_cost), cost_text(s.final_cost),
      s.linear_known ? fmt::format("linear frequency error {:.3g} %", 100 * s.linear_error)
                     : std::string("no measured linear frequency to compare"));
  return out;
}

// The words of sigma_reason(), as parameters.csv's and Python's notes say them.
std::string sigma_words(const IwanUpdateSummary& s, int k) {
  switch (s.sigma_reason(k)) {
    case IwanSigmaReason::kStated:
      return fmt::format(" +/- {:.2g} %", 100 * s.relative_std(k));
    case IwanSigmaReason::kGivenBetaAsHeld:
      return fmt::format(" +/- {:.2g} % given beta = {:.4g} as held (microslip only)",
                         100 * s.relative_std(k), s.best.beta);
    case IwanSigmaReason::kHeldAsAsked:
      return " (held)";
    case IwanSigmaReason::kBetaHeldMicroslip:
      return " (held at its start by the fit, not fitted: microslip only)";
    case IwanSigmaReason::kBetaHeldFreeNoBetter:
      return " (held at its start by the fit, not fitted: the fit with it free did no better, "
             "below)";
    case IwanSigmaReason::kStart:
      return " (the start: no candidate improved on it)";
    case IwanSigmaReason::kNoSlip:
      return " (not identified: no slip in the data, below)";
    case IwanSigmaReason::kMicroslipFamily:
      return k == 0 ? " (not identified apart from beta: microslip only)"
                    : " (not identified apart from Fs: microslip only)";
    case IwanSigmaReason::kNotConverged:
      return " (no sigma: not converged)";
    case IwanSigmaReason::kGivenBeta: {
      const double conditional = std::sqrt(std::max(s.covariance(0, 0), 0.0));
      return fmt::format(
          " given beta = {:.4g} (not identified, microslip only: the data fix only the "
          "combination of Fs and beta, below{})",
          s.best.beta,
          conditional > 0 && !s.misfit_sets_the_error()
              ? fmt::format("; +/- {:.2g} % at that beta", 100 * conditional)
              : "");
    }
    case IwanSigmaReason::kTooFewPoints:
      return " (sigma unknown: too few independent points, below)";
    case IwanSigmaReason::kAtKink:
      return " (sigma unknown: fixed only by points at phi_max, from one side, below)";
    case IwanSigmaReason::kModelMisfit:
      return " (no sigma: the model does not describe the data, below)";
    case IwanSigmaReason::kOneHit:
      return " (no sigma: rests on one hit alone, below)";
    case IwanSigmaReason::kHeldBetaRejected:
      return " (no sigma: given a beta the data reject, below)";
    case IwanSigmaReason::kUnknown:
      return " (sigma unknown: no covariance at the result)";
  }
  return "";
}

// Each parameter with its one-sigma relative uncertainty where known; held ones say so.
std::string parameter_lines(const IwanUpdateSummary& s) {
  std::string out;
  out += fmt::format(
      "  Fs {:.6g} -> {:.6g} N{}, Kt {:.6g} -> {:.6g} N/m{}, chi {:.4g} -> {:.4g}{}, beta {:.4g} "
      "-> {:.4g}{}\n",
      s.start.Fs, s.best.Fs, sigma_words(s, 0), s.start.Kt, s.best.Kt, sigma_words(s, 1),
      s.start.chi, s.best.chi, sigma_words(s, 2), s.start.beta, s.best.beta, sigma_words(s, 3));
  if (s.modal_ratio_fitted) {
    out += fmt::format(
        "  modal_ratio (the structure's own damping) {:.6g} -> {:.6g}{}; the best constant "
        "backbone (joint barely slipping) costs {:.4g}\n",
        s.modal_ratio_start, s.modal_ratio,
        s.sigma_reason(4) == IwanSigmaReason::kStated
            ? fmt::format(" +/- {:.2g}", s.modal_ratio_std)
            : sigma_words(s, 4),
        s.constant_cost);
  } else if (s.modal_ratio_start > 0) {
    out += fmt::format("  modal_ratio {:.4g} held (the model's own damping, in every damping)\n",
                       s.modal_ratio_start);
  }
  return out;
}

// The linear part's systematic effect (linear_part_sensitivity): an error of the rest of the
// model that K_T takes up leaves white residuals and moves the parameters by many of their
// sigmas (the one-mode truth with K 0.1 % stiffer: K_T -2.4 % +/- 0.07-0.09 %, F_S -5 % +/-
// 0.3-0.4 %, reduced chi-square 1.14-1.31, and nothing said), so the rates are stated, and the
// accuracy of the linear frequency each stated sigma needs.
std::string linear_part_line(const IwanUpdateSummary& s) {
  std::string out;
  if (s.linear_part_sensitivity.cwiseAbs().maxCoeff() > 0 && s.frequency_per_stiffness != 0) {
    static const char* names[] = {"Fs", "Kt", "chi", "beta"};
    std::vector<std::string> moves, holds;
    for (const int k : {1, 0, 2, 3}) {
      if (s.linear_part_sensitivity(k) == 0) continue;
      // A rate below 0.001 % per 0.1 % is no move worth its digits (chi of a one-mode fit:
      // -1.2e-08 %), and a sigma that holds to a 10 % error of the linear frequency is not
      // limited by the linear part (that chi: "4e+06 %").
      const double move = 100 * 1e-3 * s.linear_part_sensitivity(k);
      moves.push_back(std::abs(move) < 1e-3 ? fmt::format("{} by less than 0.001 %", names[k])
                                            : fmt::format("{} by {:+.2g} %", names[k], move));
      if (const double t = s.linear_part_tolerance(k); t > 0 && t <= 0.1)
        holds.push_back(fmt::format("{:.2g} % ({})", 100 * t, names[k]));
    }
    out += fmt::format(
        "  linear part: a 0.1 % error in mode {}'s linear frequency from the rest of the model "
        "(its stiffness without the joints {:.3g} % off) moves {}{}{}; {}\n",
        s.sensitivity_mode, 0.1 / std::abs(s.frequency_per_stiffness), fmt::join(moves, ", "),
        s.held[1]
            ? std::string()
            : std::string(", and leaves no trace in the residuals: Kt takes the frequency up"),
        holds.empty() ? std::string()
                      : fmt::format("; the sigmas hold only where that frequency is right to {}",
                                    fmt::join(holds, ", ")),
        s.linear_part_updated
            ? "the model's linear frequencies match the measured ones (a linear update's "
              "result): the error left in its linear part carries into the parameters at these "
              "rates"
            : "fit the model's linear part to measured linear frequencies (update-linear) before "
              "reading the parameters closer than that");
  }
  return out;
}

// The warning that the data show no slip (no_slip_seen()).
std::string no_slip_line(const IwanUpdateSummary& s) {
  const bool no_slip = s.no_slip_seen();
  std::string out;
  if (no_slip) {
    out += fmt::format(
        "  WARNING: no slip in these data: the best constant backbone (the joint stuck, Kt and "
        "the structure's own damping fitted) fits them as well as any Iwan joint (cost {:.4g} "
        "against {:.4g}, a gain below what {} more parameters give by chance 1 time in 20). "
        "The measured frequency and damping do not change with amplitude beyond their noise: "
        "Fs, chi and beta are not identified, whatever the search, and Kt and modal_ratio are "
        "the result; {}\n",
        s.final_cost, s.constant_cost, s.held[3] ? "two" : "three",
        // A mode that hardly moves the joint: larger amplitudes of it are out of reach.
        s.joint_hardly_moved()
            ? fmt::format(
                  "this mode hardly moves the joint ({}), so larger amplitudes of it would not "
                  "reach phi_max: a mode whose shape slips the joint would identify it",
                  hardly_moved_words(s))
            : std::string(
                  "larger amplitudes, where the frequency falls, would identify the joint"));
  }
  return out;
}

// Where the result is the start: why, and what would change it.
std::string start_line(const IwanUpdateSummary& s) {
  const bool no_slip = s.no_slip_seen();
  std::string out;
  if (!s.improved || s.status == IwanUpdateStatus::kNoValidPoint) {
    out += fmt::format(
        "  the result is the start{}.{}\n",
        s.status == IwanUpdateStatus::kNoValidPoint ? " (no sample could be evaluated)" : "",
        no_slip ? " No slip in the data (above): no start would do better."
        : s.joint_hardly_moved()
            ? fmt::format(
                  " The measured modes hardly move the joint here ({}): the joint barely shapes "
                  "these backbones, so neither wider bounds nor another start would change "
                  "them; a mode whose shape slips the joint would identify it",
                  hardly_moved_words(s))
        : s.optimizer == IwanOptimizer::kGlobalLocal
            ? " Widen the bounds or give a better start."
            : " The Monte Carlo's uniform samples rarely land near the optimum in wide bounds: "
              "use the global-local optimiser (--optimizer global-local).");
  }
  return out;
}

// One line per bound a parameter ended at (at_bounds), saying what put it there.
std::string bound_lines(const IwanUpdateSummary& s, const std::string& cause, bool kt_short,
                        bool kt_range) {
  const bool no_slip = s.no_slip_seen();
  std::string out;
  // Fs and beta drift together along the microslip family: a bound there is no better fit
  // beyond it, and widening the range only moves them along (Fs 38 % when it was tried).
  const bool family = !s.held[3] && s.microslip_only();
  // The relative sigma stated for the parameter a bound line names (0: none stated).
  const auto stated_at_bound = [&](const std::string& b) {
    static const char* prefixes[] = {"Fs", "gamma", "chi", "beta"};
    for (int k = 0; k < 4; ++k)
      if (b.rfind(prefixes[k], 0) == 0)
        return s.sigma_reason(k) == IwanSigmaReason::kStated ? s.relative_std(k) : 0.0;
    return 0.0;
  };
  for (const std::string& b : s.at_bounds) {
    const bool along = family && (b.rfind("Fs", 0) == 0 || b.rfind("beta", 0) == 0);
    const bool kt = b.rfind("gamma", 0) == 0 && kt_short;
    // Past phi_max throughout, K_T, chi and beta show only weakly: their bound is where the search
    // drifted along what the data leave free (a table from 2.7 to 27 phi_max ran K_T to gamma 2
    // with a sigma of 2.8e4 %, and was told to widen it and update-linear first).
    const bool weak = s.macroslip_only() && cause.empty() && b.rfind("Fs", 0) != 0;
    if (no_slip && b.rfind("gamma", 0) != 0) {
      out += fmt::format(
          "  WARNING: {}: the data show no slip (above), so nothing holds it; a wider range "
          "moves it, not the fit\n",
          b);
    } else if (weak) {
      out += fmt::format(
          "  WARNING: {}: the data lie past phi_max at every amplitude (below), where Kt, chi and "
          "beta show only weakly, so it ended there along what the data leave free; a wider range "
          "moves it, not the fit\n",
          b);
    } else if (along) {
      out += fmt::format(
          "  WARNING: {}: the microslip data fix Fs and beta only together, so it ended there "
          "along that family; a wider range moves it, not the fit\n",
          b);
    } else if (kt && !kt_range && !cause.empty()) {
      out += fmt::format(
          "  WARNING: {}: the measured low-amplitude frequency pressed it there, beyond the "
          "linear limit Kt reaches in its range (below); a wider range would let Kt take up {} "
          "rather than fit the joint\n",
          b, s.evidence->nearer_mode > 0 ? "another mode's frequency" : "the linear part's error");
    } else if (b.rfind("Fs", 0) == 0 && !cause.empty() &&
               (amplitudes_read_too_large(s) || amplitudes_read_too_small(s))) {
      // A wider range does cure it, with Fs then scaled by the amplitudes' factor.
      out += fmt::format(
          "  WARNING: {}: the amplitudes pressed it there (below); a wider range would let Fs "
          "take up their factor, no joint's slip force where they were read as another quantity\n",
          b);
    } else if (b.rfind("Fs", 0) == 0 && !cause.empty() && !s.held[0] && s.bound_side[0] > 0 &&
               s.joint_hardly_moved()) {
      // F_S at its upper bound with the fitted joint hardly slipping: the misfit set the joint
      // aside, and F_S drifts where nothing holds it. A per-cent damping column on microslip
      // tables (F_S 1500 N, the joint at 8e-4 phi_max) was told "a wider range would not cure
      // that"; --fs-range 1:1e7 moved F_S to 23751 N at cost 2430 -> 2423 (0.3 %).
      out += fmt::format(
          "  WARNING: {}: there the fitted joint hardly slips ({:.2g} phi_max at the highest "
          "amplitude): the misfit below set the joint aside, so nothing in these data holds Fs; a "
          "wider range moves it, not the fit, and Fs is no slip force of the joint until the "
          "cause below is mended\n",
          b, s.top_slip / s.phi_max);
    } else if (b.rfind("chi", 0) == 0 && s.bound_side[2] > 0 &&
               cause.find(iwan_detail::kLargerChiWords) != std::string::npos) {
      // The low end's damping rises more steeply than a joint of chi up to the bound gives: a
      // wider range may cure it (FloorTruth's joint at chi 0.3 fitted with chi stopped at 0).
      out += fmt::format(
          "  WARNING: {}: the low end's damping rises more steeply than a joint of chi up to it "
          "gives (below); a wider range lets the fit take a larger chi, if the damping column is "
          "in its unit\n",
          b);
    } else if (b.rfind("chi", 0) == 0 && s.bound_side[2] > 0 && !s.held[2] && !cause.empty()) {
      // A joint of larger chi is an element the range left out, which the cause below names
      // beside: a wider range may cure the misfit (an SDOF joint at chi 0.3 fitted in the default
      // range was told "a wider range would not cure that").
      out += fmt::format(
          "  WARNING: {}: the misfit below pressed it there; a joint of larger chi, which the "
          "range left out, may be what the data ask for: a wider --chi-range tells\n",
          b);
    } else if (!cause.empty() && !kt) {
      out += fmt::format(
          "  WARNING: {}: the misfit below pressed it there; a wider range would not cure that\n",
          b);
    } else if (const double sd = stated_at_bound(b); sd > 0.5) {
      // A parameter the data hardly fix (not identifiable, its sigma over half its value) ends
      // at a bound along what they leave free: the lap joint's mode 2, whose joint barely moves,
      // put gamma at 2 +/- 78 % (the truth 1.6) and was told to widen the range.
      out += fmt::format(
          "  WARNING: {}: the data hardly fix it (+/- {:.2g} %), so it ended there along what "
          "they leave free; a wider range moves it, not the fit\n",
          b, 100 * sd);
    } else {
      out += fmt::format("  WARNING: {}: the best fit may lie outside the range, widen it\n", b);
    }
  }
  return out;
}

// A beta held as asked that the data past phi_max reject: freed, it lowers the chi-square beyond
// its 1 in 1000 point, and the others' sigmas given it are not the joint's.
std::string held_beta_line(const IwanUpdateSummary& s) {
  if (!s.held_beta_rejected()) return "";
  return fmt::format(
      "  WARNING: the data reach macroslip, where beta is identified, and reject beta = {:.4g} as "
      "held (--beta): freed from this result it goes to {:.4g} and lowers the chi-square by {:.3g} "
      "(its 1 in 1000 point for one parameter: {:.3g}); the other parameters take up its error, "
      "so no sigma is given; hold beta at a value the data allow, or leave --beta out\n",
      s.best.beta, s.held_beta_freed, s.held_beta_chi2_drop, s.held_beta_drop_limit);
}

// The fit with beta freed lost to the one with it held at its start: beta is then no result
// of the data, which reach macroslip where it is identified (before: "beta ... (held)", as if
// asked, and held 1 in parameters.csv).
std::string free_beta_line(const IwanUpdateSummary& s, const std::string& cause) {
  std::string out;
  if (s.held[3] && s.beta_hold == IwanBetaHold::kFreeFitNoBetter) {
    out += fmt::format(
        "  WARNING: the data reach macroslip, where beta is identified, but the fit with beta "
        "free ended at cost {:.4g}, above this fit's {:.4g} with beta held at its start {:.4g}: "
        "beta is not fitted and has no sigma, and the other parameters{} hold at that beta; {}\n",
        s.free_fit_cost, s.final_cost, s.best.beta,
        (s.relative_std.array() > 0).any() ? " and their sigmas" : "",
        // With the model not describing the data (a cause named), beta from a longer search
        // would be fitted to that misfit (the velocity tables read as the modal amplitude: beta
        // free 6.426e6 against held 6.389e6, and "a larger --evaluations (e.g. 19416)").
        cause.empty() ? fmt::format("run again with a larger --evaluations (e.g. {}), or hold "
                                    "beta at a known value with --beta",
                                    4 * std::max(s.evaluations, 1500))
                      : std::string("mend the cause named above first (a longer search would fit "
                                    "beta to that misfit, not to the joint), or hold beta at a "
                                    "known value with --beta"));
  }
  return out;
}

// K_T sets the stuck joint's linear frequencies, which update-linear fits to the measured
// ones first. Where the fit moves it far, it likely takes up the linear model's error: a
// backbone 5 % below an un-updated model moved K_T by -49 % and beta by +82 %, chi 8.6 sigma
// off, all within the noise and without a word.
// Where the residuals name a likelier cause (misfit_cause()), that is said instead.
std::string kt_moved_line(const IwanUpdateSummary& s, const std::string& cause) {
  std::string out;
  if (s.improved && !s.held[1] && s.start.Kt > 0 && std::abs(s.best.Kt / s.start.Kt - 1) > 0.25 &&
      cause.empty() && !s.macroslip_only()) {
    // After the linear update (linear_part_updated, as the "linear part:" line reads it) the
    // start is that update's K_T: sending the user to update-linear again sent them in a circle.
    out += fmt::format(
        "  note: Kt moved from {:.6g} to {:.6g} N/m ({:+.0f} %): {}\n", s.start.Kt, s.best.Kt,
        100 * (s.best.Kt / s.start.Kt - 1),
        s.linear_part_updated
            ? "away from the model's, whose linear frequencies match the measured ones (a "
              "linear update's result): the backbones' low-amplitude limit disagrees with those "
              "frequencies, or Kt takes up what beta and chi do not describe; hold Kt at the "
              "model's (--gamma 1) and see whether the fit still holds"
            : "where the model's linear frequencies were not fitted to the measured ones first "
              "(update-linear), the fit takes their error up into Kt, beta and chi; update them "
              "first, or hold Kt (--gamma, Kt / Ks) and see whether the fit still holds");
  }
  return out;
}

// A fit that did not converge stopped where its evaluations ran out, not at a minimum: said
// whatever the chi-square (a fit at cost 1.31 where the minimum costs 0.73 looked fine at a
// reduced chi-square of 0.68 and stated chi 4.6 sigma off), with no sigma.
std::string not_converged_line(const IwanUpdateSummary& s, const std::string& cause,
                               bool kt_range) {
  const bool no_slip = s.no_slip_seen();
  const bool monte_carlo = s.optimizer != IwanOptimizer::kGlobalLocal;
  std::string out;
  if (s.improved && s.status == IwanUpdateStatus::kBudget) {
    // Where the misfit has a named cause, or K_T's range stopped it, that comes first: a longer
    // search cures neither.
    const std::string advice =
        no_slip
            ? std::string("the data show no slip (above), which a longer search does not change")
        : !cause.empty() ? std::string(
                               "mend the cause named above first (a longer search cures a misfit "
                               "only where the search is at fault)")
        : kt_range ? std::string("widen the range named above first")
        // A longer search of data past phi_max throughout ended at the same cost, chi at its
        // bound and no sigma: the data, not the search, leave K_T, chi and beta free.
        : s.macroslip_only()
            ? std::string(
                  "the data lie past phi_max at every amplitude (below), where Kt, chi and beta "
                  "show only weakly, so a longer search may not fix them: data at amplitudes "
                  "below phi_max would")
            : fmt::format("run again with a larger --evaluations (e.g. {})",
                          4 * std::max(s.evaluations, 1500));
    // What the residuals where it stopped would suggest is said as that, not as a finding.
    const std::string tentative = s.tentative_cause();
    out += fmt::format(
        "  WARNING: the fit did not converge: {}; the parameters are where it stopped, not a "
        "best fit, and no sigma is stated; {}{}\n",
        monte_carlo ? "the Monte Carlo was still improving when its evaluation budget ran out"
                    : "the local solve from the best point was still descending when its "
                      "evaluations (its share of the budget and as many again) ran out",
        advice,
        tentative.empty()
            ? std::string()
            : fmt::format(". Where it stopped, the residuals alone would suggest the "
                          "following, no finding while the fit has not converged (a converged "
                          "fit may describe the data): {}",
                          tentative));
  }
  return out;
}

// A search that stopped at a bound with a misfit may have missed the best fit: 12 of 20
// three-hit fits at the default 1500 ended at chi-square 9.7 with the truth costing 1.8
// there, all 40 converged with 6000.
// (Not where K_T's range alone kept it from the measured frequency: its bound's line says so.)
// Where chi is free at its upper bound, a joint of larger chi may be the best fit: FloorTruth's
// joint at chi 0.3 fitted in the default range (chi at most 0) was sent to a longer search
// alone (reduced chi-square 6.4; with --chi-range -0.9:0.9, 0.98 at chi 0.306).
std::string stopped_at_bound_line(const IwanUpdateSummary& s, const std::string& cause,
                                  bool kt_range) {
  std::string out;
  if (s.improved && s.misfit() && cause.empty() && !kt_range &&
      s.status != IwanUpdateStatus::kBudget && !s.at_bounds.empty()) {
    out += fmt::format(
        "  WARNING: the search stopped at a bound with the model not describing the data: it "
        "may have missed the best fit rather than the model being wrong; run again with a "
        "larger --evaluations (e.g. {}){} before judging the model\n",
        4 * std::max(s.evaluations, 1500),
        !s.held[2] && s.bound_side[2] > 0
            ? fmt::format(", or with a wider --chi-range: chi ended at its upper bound {:g}, and a "
                          "joint of larger chi, which the range left out, may be the best fit",
                          s.best.chi)
            : std::string());
  }
  return out;
}

// The relative RMS errors at the result and of the best constants.
std::string rms_line(const IwanUpdateSummary& s) {
  std::string out;
  if (s.rms_errors.any()) {
    out += fmt::format(
        "  relative RMS error: frequency {:.3g}, damping {:.3g} (the best constants: {:.3g}, "
        "{:.3g})\n",
        s.rms_errors(0), s.rms_errors(1), s.constant_rms_errors(0), s.constant_rms_errors(1));
  }
  return out;
}

// Below this serial correlation the residuals are read as independent, the points as few rather
// than waves: n (1 - rho) / (1 + rho) keeps over 80 % of them.
constexpr double kSerialCorrelation = 0.1;

// Residuals that run in waves along a curve leave few independent points: too few, and no
// sigma is stated rather than a wrong one (a 200-point curve with AR(1) noise of rho 0.98 has
// about 2 per sequence); few, and the sigmas allow for it but rest on them.
// Too few points even if every residual were independent: said as such, not as waves (a
// correlation read off 3 points sent the user after waves). Below kSerialCorrelation the
// residuals are independent and the points merely few, said as such (a 6-point curve was told
// "serially correlated (0 from one point to the next)").
std::string serial_lines(const IwanUpdateSummary& s) {
  std::string out;
  const double fitted = std::round(s.effective_points - s.sigma_degrees_of_freedom);
  // Where no sigma is stated (the misfit sets the error, or none is identified) there is none
  // to allow for the few points: the velocity tables read as the modal amplitude were told
  // "the sigmas allow for it (Student's t, 3.08 degrees of freedom)" above "no sigma is stated".
  const std::string allowance =
      (s.relative_std.array() > 0).any()
          ? fmt::format(
                "the sigmas allow for it (Student's t, {:.3g} degrees of freedom) but rest "
                "on these few",
                s.sigma_degrees_of_freedom)
          : std::string("no sigma is stated, so none rests on these few");
  if (s.improved && s.effective_points > 0 && !(s.sigma_degrees_of_freedom > 2) &&
      static_cast<double>(s.residuals) - fitted <= 2) {
    out += fmt::format(
        "  WARNING: {} points ({} residuals) leave {:.0f} beyond the {:.0f} parameters fitted even "
        "if independent: too few to state a sigma (more than 2 needed); more points, or more "
        "curves, would give one\n",
        s.residuals / 2, s.residuals, std::max(0.0, static_cast<double>(s.residuals) - fitted),
        fitted);
  } else if (s.improved && s.effective_points > 0 && !(s.sigma_degrees_of_freedom > 2) &&
             s.noise_correlation < kSerialCorrelation) {
    out += fmt::format(
        "  WARNING: the {} residuals ({} points), each independent of the next (serial "
        "correlation {:.2g}, corrected for what the fit absorbs), amount to {:.2g} independent "
        "points, too few to state a sigma (more than {:.0f}, 2 beyond the parameters fitted, "
        "needed); more points, or more curves, would give one\n",
        s.residuals, s.residuals / 2, s.noise_correlation, s.effective_points,
        s.effective_points - s.sigma_degrees_of_freedom + 2);
  } else if (s.improved && s.effective_points > 0 && !(s.sigma_degrees_of_freedom > 2)) {
    out += fmt::format(
        "  WARNING: the residuals run in long waves along the curves (serial correlation {:.3g} "
        "from one point to the next, corrected for what the fit absorbs): the {} residuals amount "
        "to {:.2g} independent points, too few to state a sigma (more than {:.0f}, 2 beyond the "
        "parameters fitted, needed); {}\n",
        s.noise_correlation, s.residuals, s.effective_points,
        s.effective_points - s.sigma_degrees_of_freedom + 2,
        s.misfit() ? "with the model not describing the data (below), the waves are its misfit"
                   : "more curves (hits), or longer ones, would give one");
  } else if (s.improved && s.effective_points > 0 && s.effective_points < 30 &&
             s.noise_correlation < kSerialCorrelation) {
    out += fmt::format(
        "  note: the {} residuals ({} points) are few, each independent of the next (serial "
        "correlation {:.2g}, corrected for what the fit absorbs): they amount to {:.3g} "
        "independent points; {}\n",
        s.residuals, s.residuals / 2, s.noise_correlation, s.effective_points, allowance);
  } else if (s.improved && s.effective_points > 0 && s.effective_points < 30) {
    out += fmt::format(
        "  note: the residuals are serially correlated along the curves ({:.3g} from one point "
        "to the next, corrected for what the fit absorbs): the {} residuals amount to {:.3g} "
        "independent points; {}\n",
        s.noise_correlation, s.residuals, s.effective_points, allowance);
  }
  return out;
}

// The reduced chi-square, and whether the model describes the data within their noise.
std::string chi_square_line(const IwanUpdateSummary& s, const std::string& cause) {
  std::string out;
  out += fmt::format("  reduced chi-square {:.3g}", s.reduced_chi2);
  // With no sigma stated (too few effective points) there is no bound to speak of.
  const bool any_sigma = (s.relative_std.array() > 0).any();
  // Scatter between curves (the cause above) is in the sigmas with three or more curves.
  const bool scatter = s.evidence && s.evidence->curves >= 3 &&
                       cause.find("curves disagree with one another") != std::string::npos;
  out += s.misfit() ? std::string(
                          ": WARNING the model does not describe the data within their "
                          "stated noise") +
                          (scatter     ? " (the scatter between the curves, above)\n"
                           : any_sigma ? "; the uncertainties (scaled by it) are a lower bound\n"
                                       : "\n")
                    : " (the model describes the data within their stated noise)\n";
  return out;
}

// No sigma where the misfit, not the noise, sets the error (misfit_sets_the_error()): say
// why, with the numbers that decided it.
std::string no_sigma_line(const IwanUpdateSummary& s, const std::string& cause) {
  std::string out;
  if (s.misfit_sets_the_error()) {
    const double k = static_cast<double>(s.residuals) / 6;
    const bool waves = !(s.noise_correlation < 0.3);
    const bool gathered = !(s.amplitude_share < 1.0 / 3 + 3 * std::sqrt((2.0 / 9) / (1.5 * k + 1)));
    out += fmt::format(
        "  WARNING: no sigma is stated: the model does not describe the data (reduced "
        "chi-square {:.3g}, beyond the {:.3g} the noise reaches over the {:.3g} independent "
        "points) and the residuals are no noise ({}): what the misfit pulls the parameters to, "
        "not the noise, sets their error, which no sigma from the residuals measures. {}\n",
        s.reduced_chi2, 1 + 3 * std::sqrt(2.0 / s.effective_points), s.effective_points,
        waves && gathered
            ? fmt::format("they run in waves, serial correlation {:.2g} from one point to the "
                          "next, and one third of the amplitudes holds {:.0f} % of the "
                          "chi-square",
                          s.noise_correlation, 100 * s.amplitude_share)
        : waves ? fmt::format("they run in waves, serial correlation {:.2g} from one point to "
                              "the next",
                              s.noise_correlation)
                : fmt::format("one third of the amplitudes holds {:.0f} % of the chi-square",
                              100 * s.amplitude_share),
        cause.empty()
            ? "Find what the model lacks (another mode slipping the joint in the same hit, the "
              "linear part, the structure's own damping, a held parameter) before reading the "
              "parameters"
            : "Mend the cause named above first");
  }
  return out;
}

// A misfit whose residuals look like noise: uncorrelated from point to point (the AR(1)
// coefficient, corrected for what the fit absorbs, below 0.3) and spread evenly over the
// amplitudes (no third of the points, by amplitude, holds more than 1/3 of the chi-square by
// 3 of its standard deviations under noise: a share of chi-square(k) in a sum of three is
// Beta(k/2, k), of variance (2/9) / (3k/2 + 1), k a third of the points, not of the
// residuals, as frequency or damping alone may carry the chi-square). A model's misfit runs
// in waves instead: 60-point backbones of the one-mode truth with 1.5e-3 frequency noise
// stated as 1.5e-4 fitted at reduced chi-square 33 to 71 over 16 seeds, serial correlation 0
// to 0.25, largest third's share 0.39 to 0.52 (the note in all 16); the same data of a
// chi -0.2 joint with chi held near -0.6 at 264 to 322, serial correlation 0.94 to 0.99 (no
// note; its thirds, 0.42 to 0.49, were no less even: the correlation tells the two apart, the
// thirds a misfit gathered at some amplitudes). A note, not a cause: a misfit can look white,
// so the stated noise is only what to check first.
std::string noise_like_note(const IwanUpdateSummary& s) {
  std::string out;
  if (s.misfit() && s.residuals_look_like_noise()) {
    out += fmt::format(
        "  note: the residuals are uncorrelated from point to point (serial correlation {:.2g}) "
        "and spread evenly over the amplitudes, as noise is, where a wrong model's run in "
        "waves: the stated uncertainties may be about sqrt(reduced chi-square) = {:.2g} times "
        "too small\n",
        s.noise_correlation, std::sqrt(s.reduced_chi2));
  }
  return out;
}

// Far below 1 (by more than 3 of its standard deviations): the stated noise is larger than
// the residuals' scatter, and the sigmas, which never shrink the stated noise, are that much
// too wide (one table's uncertainties stated 10 times too large: reduced chi-square 0.0074,
// every z-score within 0.15 over 6 seeds, and nothing said). Not where floors raised them
// (their note, below). Its standard deviation is sqrt(2 / n) over the residuals' effective
// number n of independent points, not over their count: the example campaign's 978
// residuals amount to 18.3 points, and its 0.669 (0.82 of the stated scatter, common over
// 18 points) was called far below 1 against a limit of 0.86 from the count.
std::string far_below_note(const IwanUpdateSummary& s) {
  std::string out;
  const double independent =
      s.effective_points > 0 ? s.effective_points : static_cast<double>(s.residuals);
  if (!s.misfit() && s.residuals > 0 && s.floored(1) == 0 && s.floored(2) == 0 &&
      s.reduced_chi2 < 1 - 3 * std::sqrt(2.0 / independent)) {
    out += fmt::format(
        "  note: the reduced chi-square lies far below 1: the residuals scatter about {:.2g} "
        "times the stated uncertainties, which overstate the noise; the sigmas rest on them "
        "(never shrunk below them) and are as much too wide. State each point's one-sigma "
        "uncertainty (an expanded one, k sigma, with a coverage_factor column giving k)\n",
        std::sqrt(s.reduced_chi2));
  }
  return out;
}

// A stated uncertainty below a floor is raised to it, and the sigmas and the chi-square then
// rest on the floor (40 fits of data with 1e-5 noise stated as such: sigmas about 10 times the
// actual errors, reduced chi-square 0.008, and nothing said).
std::string floor_note(const IwanUpdateSummary& s) {
  std::string out;
  if (s.improved && (s.floored(1) > 0 || s.floored(2) > 0)) {
    out += fmt::format(
        "  note: the stated uncertainties of {} of {} frequencies and {} of {} dampings lie below "
        "the floors ({:.3g} f, {:.3g} zeta) and were raised to them: the uncertainties and the "
        "chi-square above rest on the floors there\n",
        s.floored(1), s.floored(0), s.floored(2), s.floored(0), s.frequency_floor, s.damping_floor);
  }
  return out;
}

// The joint slip over the measured amplitudes against phi_max: microslip, macroslip or both.
std::string slip_line(const IwanUpdateSummary& s) {
  std::string out;
  if (s.top_slip > 0 && s.phi_max > 0) {
    out += fmt::format(
        "  largest joint slip {:.3g} to {:.3g} m over the measured amplitudes, phi_max {:.3g} m: "
        "{}\n",
        s.bottom_slip, s.top_slip, s.phi_max,
        s.microslip_only()
            ? "microslip only, Fs and beta are not identified separately" + microslip_family(s)
        : s.macroslip_only()
            ? std::string(
                  "macroslip only: every measured amplitude lies past phi_max, which fixes Fs (the "
                  "plateau) while Kt, chi and beta, which shape the joint below phi_max, show "
                  "only weakly (their sigmas say how weakly); data at amplitudes below phi_max "
                  "would identify them")
            : std::string("the data reach macroslip"));
  }
  return out;
}

// The note on parameters fixed only at a kink (sigma_reason() kAtKink).
std::string kink_note(const IwanUpdateSummary& s) {
  std::string out;
  std::vector<std::string> at_kink;
  static const char* names[] = {"Fs", "Kt", "chi", "beta"};
  for (int k = 0; k < 4; ++k)
    if (s.sigma_reason(k) == IwanSigmaReason::kAtKink) at_kink.push_back(names[k]);
  if (!at_kink.empty()) {
    out += fmt::format(
        "  note: {} {} fixed only by the slopes of points at phi_max (an element's onset of "
        "macroslip between two sigmas each way), which hold on one side of it only: no sigma is "
        "stated; more points past phi_max would fix {}\n",
        fmt::join(at_kink, " and "), at_kink.size() > 1 ? "are" : "is",
        at_kink.size() > 1 ? "them" : "it");
  }
  return out;
}

// The note on parameters that rest on one of several hits alone (sigma_reason() kOneHit), by hit.
std::string one_hit_note(const IwanUpdateSummary& s) {
  static const char* names[] = {"Fs", "Kt", "chi", "beta"};
  std::string out;
  std::vector<bool> done(4, false);
  for (int k = 0; k < 4; ++k) {
    if (done[k] || s.sigma_reason(k) != IwanSigmaReason::kOneHit) continue;
    std::vector<std::string> these, noise;
    for (int j = k; j < 4; ++j) {
      if (s.sigma_reason(j) != IwanSigmaReason::kOneHit || s.one_curve[j] != s.one_curve[k])
        continue;
      done[j] = true;
      these.push_back(names[j]);
      const double sd = std::sqrt(std::max(s.covariance(j, j), 0.0));
      const double rel = j != 2 ? sd : std::abs(s.best.chi) > 0 ? sd / std::abs(s.best.chi) : 0.0;
      if (rel > 0) noise.push_back(fmt::format("{} +/- {:.2g} %", names[j], 100 * rel));
    }
    const bool many = these.size() > 1;
    out += fmt::format(
        "  note: {} {} on one hit alone, {} (the other hits carry under 1 % of {} information): "
        "{} that hit's joint's, and how far the joint changed between hits (settling, "
        "re-tightening: a few per cent in Fs is common) no one hit can show, so no sigma is "
        "stated{}; two or more hits over that hit's amplitudes would measure that scatter and "
        "give a sigma\n",
        fmt::join(these, " and "), many ? "rest" : "rests", s.one_curve_name[k],
        many ? "their" : "its", many ? "they are" : "it is",
        noise.empty() ? ""
                      : fmt::format(". That hit's noise alone gives {}, which {} for the "
                                    "joint only if it did not change between hits",
                                    fmt::join(noise, ", "), noise.size() > 1 ? "hold" : "holds"));
  }
  return out;
}

// What the stated sigmas of several hits' curves allow for: the joint as it was in those hits.
// Three hits at rising levels, one each, F_S 2 % and K_T 1 % scattered between hits (the one-mode
// truth, 40 seeds): where the hits' joints happened to agree with one another, the curves agree
// too, and K_T came out more than 3 of its sigmas from the joint's mean in 6 of the 24 fits that
// stated it from the noise (K_T 0.35, 0.55 and 0.55 % above the mean in one such campaign). At
// 5 % and 2 % (seeds 0-199, four level layouts) 18 of 43 such fits, up to z -28 (K_T 1.8, 1.4
// and 1.7 % below the mean: the fit found the hits' joint, K_T -1.7 %). No statistic of the
// curves tells it: three hits that agree by chance are, to the data, three hits of a joint that
// did not change, so the note says so rather than widening by a scatter no residual shows.
std::string several_hits_note(const IwanUpdateSummary& s) {
  if (s.curves < 2 || s.scatter_explains_misfit()) return "";
  bool stated = false;
  for (int k = 0; k < 4; ++k) stated = stated || s.sigma_reason(k) == IwanSigmaReason::kStated;
  if (!stated) return "";
  return fmt::format(
      "  note: the sigmas are of the joint as it was in the hits of these {} curves: how far the "
      "joint changes "
      "from hit to hit (settling, re-tightening) they allow for only as far as the hits' curves "
      "disagree, and hits whose joints happen to agree with one another show none of it: no "
      "statistic of these curves can tell them from hits of a joint that did not change (three "
      "hits at rising levels, K_T scattered 1 % between hits: K_T more than 3 sigma from the "
      "joint's mean in 6 of 24 such fits; F_S and K_T scattered 5 % and 2 %: in 18 of 43, up to "
      "28 sigma); hits repeated at each level measure that scatter\n",
      s.curves);
}

}  // namespace

std::string IwanUpdateSummary::report() const {
  std::string out = outcome_line(*this);
  out += parameter_lines(*this);
  out += linear_part_line(*this);
  out += no_slip_line(*this);
  out += start_line(*this);
  const std::string cause = misfit_cause();
  // K_T sets the linear limit: at a bound short of the measured low-amplitude frequency, that
  // frequency pressed it there. Where the model as given (gamma 1) matches it, the range stopped
  // the fit (widen it); else a wider range would let K_T take up the linear part's error or
  // another mode's frequency, as a curve 1.5 % above the model ran K_T to gamma 2 (the plain
  // "would not cure that" was wrong there: a wider range does move it onto the data).
  const bool kt_short = kt_stopped_short(*this);
  const bool kt_range = kt_short && model_as_given_matches(*evidence) && evidence->nearer_mode == 0;
  out += bound_lines(*this, cause, kt_short, kt_range);
  if (!cause.empty()) {
    out += fmt::format(
        "  WARNING: the model does not describe the data, and the residuals point at the data "
        "or the model rather than the search: {}\n",
        cause);
  }
  out += free_beta_line(*this, cause);
  out += held_beta_line(*this);
  out += kt_moved_line(*this, cause);
  out += not_converged_line(*this, cause, kt_range);
  out += stopped_at_bound_line(*this, cause, kt_range);
  out += rms_line(*this);
  out += serial_lines(*this);
  if (improved && reduced_chi2 > 0) {
    out += chi_square_line(*this, cause);
    out += no_sigma_line(*this, cause);
    out += noise_like_note(*this);
    out += far_below_note(*this);
  }
  out += floor_note(*this);
  out += slip_line(*this);
  out += kink_note(*this);
  out += one_hit_note(*this);
  out += several_hits_note(*this);
  return out;
}

}  // namespace jointlab::correlate
