#include "jointlab/campaign/iwan_fit.h"

#include <cassert>
#include <cmath>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::campaign {

using correlate::IwanObjective;
using correlate::IwanUpdateOptions;
using correlate::IwanUpdateSummary;

namespace {

// Refuses a LO:HI range that is not inside the parameter's domain (model/iwan.h).
void check_range(const char* option, const IwanRange& r, const char* parameter, const char* shown) {
  if (!r) return;
  const model::ParameterDomain d = model::iwan_parameter_domain(parameter);
  if (!(d.contains(r->first) && d.contains(r->second) && r->first < r->second)) {
    throw InputError(fmt::format("{} {}:{}: need LO < HI with both {} {}", option, r->first,
                                 r->second, shown, d.text()));
  }
}

}  // namespace

void IwanRanges::check() const {
  check_range("--fs-range", fs, "Fs", "Fs");
  check_range("--gamma-range", gamma, "Kt", "Kt/Ks");
  check_range("--chi-range", chi, "chi", "chi");
  check_range("--beta-range", beta, "beta", "beta");
  if (beta && !(beta->first > 0)) {  // beta >= 0, but searched in ln beta
    throw InputError(
        fmt::format("--beta-range {}:{}: need 0 < LO < HI (beta is searched on a log scale)",
                    beta->first, beta->second));
  }
}

correlate::IwanBounds IwanRanges::bounds(const model::IwanParameters& start) const {
  correlate::IwanBounds b = correlate::default_iwan_bounds(start);
  if (fs) b.Fs_min = fs->first, b.Fs_max = fs->second;
  if (gamma) b.gamma_min = gamma->first, b.gamma_max = gamma->second;
  if (chi) b.chi_min = chi->first, b.chi_max = chi->second;
  if (beta) b.beta_min = beta->first, b.beta_max = beta->second;
  return b;
}

IwanUpdateSummary fit_iwan(const IwanObjective& objective, const IwanUpdateOptions& io,
                           const std::function<void(const std::string&)>& say) {
  IwanUpdateSummary best;
  IwanUpdateOptions held = io;
  if (!held.fixed_beta) held.fixed_beta = objective.initial().beta;
  correlate::update_iwan(objective, held, &best);
  // Beta held by this fit, not as asked: the report and parameters.csv say so.
  if (!io.fixed_beta && best.microslip_only())
    best.set_beta_held_by_fit(correlate::IwanBetaHold::kMicroslip);
  if (!io.fixed_beta && !best.microslip_only()) {
    if (say) {
      say("update: " + best.report() +
          "update: the data reach macroslip; Iwan identification with beta free");
    }
    IwanUpdateSummary full;
    correlate::update_iwan(objective, io, &full);
    // One history over both fits, whichever is kept: the free fit's evaluations numbered on
    // from the held fit's, the best the best of both so far; the evaluations of both counted.
    std::vector<correlate::IwanHistoryEntry> history = best.history;
    double so_far = history.empty() ? INFINITY : history.back().best;
    for (correlate::IwanHistoryEntry h : full.history) {
      h.evaluation += best.evaluations;
      so_far = std::min(so_far, h.cost);
      h.best = so_far;
      history.push_back(h);
    }
    const int evaluations = best.evaluations + full.evaluations;
    const int polish = best.polish_evaluations + full.polish_evaluations;
    if (full.final_cost < best.final_cost) {
      best = full;
    } else {
      best.set_beta_held_by_fit(correlate::IwanBetaHold::kFreeFitNoBetter, full.final_cost);
    }
    best.history = std::move(history);
    best.evaluations = evaluations;
    best.polish_evaluations = polish;
  }
  return best;
}

IwanUpdateSummary checked_fit_iwan(const IwanObjective& objective, IwanUpdateOptions options,
                                   const IwanRanges& ranges, const std::string& command,
                                   const std::string& data_name,
                                   const std::function<void(const std::string&)>& say) {
  ranges.check();
  options.bounds = ranges.bounds(objective.initial());
  if (const std::string e = options.error(); !e.empty()) {
    throw InputError(fmt::format("{}: {}", command, e));
  }
  const std::string data = data_name.empty() ? std::string() : data_name + ": ";
  // Frequencies no parameter set can reach: said with the numbers before any fit (before, the
  // fit's every cost was clipped to a penalty and the message blamed the amplitudes).
  if (const std::string e = correlate::unreachable_frequencies(objective, options); !e.empty()) {
    throw InputError(fmt::format("{}: {}{}", command, data, e));
  }
  IwanUpdateSummary summary = fit_iwan(objective, options, say);
  // No sample evaluated: the start comes back as the "result", which is none.
  if (summary.status == correlate::IwanUpdateStatus::kNoValidPoint) {
    throw InputError(fmt::format(
        "{}: no parameter set in the bounds gives a QSMA curve over the measured amplitudes{}{}",
        command, data_name.empty() ? std::string() : " of " + data_name,
        options.fixed_gamma > 0
            ? fmt::format(" with K_T held at {} x K_s = {:.6g} N/m", options.fixed_gamma,
                          options.fixed_gamma * objective.reference_stiffness())
            : std::string()));
  }
  return summary;
}

std::function<void(int, double)> progress_every(int every, std::function<void(int, double)> line,
                                                std::function<void()> between) {
  assert(every > 0);
  return [every, line = std::move(line), between = std::move(between), last = 0](
             int n, double best) mutable {
    if (n < last) last = 0;
    const bool due = n / every > last / every;
    last = n;
    if (due && line)
      line(n, best);
    else if (!due && between)
      between();
  };
}

std::string pareto_report(const std::vector<correlate::ParetoPoint>& front) {
  std::string text;
  for (const correlate::ParetoPoint& p : front) {
    text += fmt::format(
        "  Pareto gamma {:.4g}: Fs {:.6g} N, Kt {:.6g} N/m, chi {:.4g}, beta {:.4g}, linear "
        "error {:.3g} %, backbone cost {:.4g}{}\n",
        p.gamma, p.params.Fs, p.params.Kt, p.params.chi, p.params.beta, 100 * p.linear_error,
        p.backbone_cost, p.dominated ? " (dominated)" : "");
    if (p.mode_errors.empty()) continue;
    std::string line = "    linear error per measured mode [%]:";
    for (size_t i = 0; i < p.mode_errors.size(); ++i) {
      line += p.mode_errors[i] ? fmt::format(" {}: {:.3g}", i + 1, 100 * *p.mode_errors[i])
                               : fmt::format(" {}: unpaired", i + 1);
    }
    text += line + "\n";
  }
  return text;
}

}  // namespace jointlab::campaign
