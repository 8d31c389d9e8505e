#include "jointlab/correlate/update_tables.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

namespace jointlab::correlate {
namespace {

std::string num(double x) {
  if (!std::isfinite(x)) throw std::logic_error("update files: non-finite result");
  return fmt::format("{:.10g}", x);
}

// A CSV cell for a name: quoted when it holds a comma or a quote.
std::string cell(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

std::string linear_parameters_csv(const LinearUpdateSummary& s) {
  std::string t =
      "name,initial,final,relative_std,sensitivity,identifiable,smallest_within_tolerance,"
      "status\n";
  for (const ParameterReport& p : s.parameters) {
    // Empty cells where there is no value: no standard deviation for a set not fitted.
    t += fmt::format("{},{},{},{},{},{},{},{}\n", cell(p.name), num(p.start), num(p.value),
                     p.relative_std ? num(*p.relative_std) : "", num(p.sensitivity),
                     p.identifiable() ? 1 : 0,
                     p.smallest_within_tolerance > 0 ? num(p.smallest_within_tolerance) : "",
                     p.held           ? (p.held_by_user ? "held" : "held (flat)")
                     : p.at_bound < 0 ? "at lower bound"
                     : p.at_bound > 0 ? "at upper bound"
                                      : "fitted");
  }
  return t;
}

std::string linear_history_csv(const LinearUpdateSummary& s) {
  std::string t = "iteration,objective";
  for (const ParameterReport& p : s.parameters) t += fmt::format(",{}", cell(p.name));
  t += "\n";
  for (size_t i = 0; i < s.history.size(); ++i) {
    t += fmt::format("{},{}", i, num(s.history[i]));
    if (i < s.theta_history.size()) {
      for (Eigen::Index k = 0; k < s.theta_history[i].size(); ++k)
        t += fmt::format(",{}", num(s.theta_history[i](k)));
    }
    t += "\n";
  }
  return t;
}

std::string linear_modes_csv(const LinearUpdateSummary& s) {
  const LinearEvaluation& e = s.final;
  std::string t = "measured,frequency_hz,model_mode,model_frequency_hz,error,mac\n";
  for (Eigen::Index i = 0; i < e.measured_frequency_hz.size(); ++i) {
    const int j = e.pairing.model_for(static_cast<int>(i));
    if (j < 0) {
      t += fmt::format("{},{},,,,\n", e.measured_id(i), num(e.measured_frequency_hz(i)));
    } else {
      // A MAC over fewer than two sensors is no evidence: its cell stays empty.
      const std::optional<double> mac = e.pair_mac(i);
      t += fmt::format("{},{},{},{},{},{}\n", e.measured_id(i), num(e.measured_frequency_hz(i)),
                       j + 1, num(e.model_frequency_hz(i)), num(e.residuals(i)),
                       mac ? num(*mac) : std::string());
    }
  }
  return t;
}

int mac_columns(const LinearUpdateSummary& s) {
  const LinearEvaluation& e = s.final;
  int cols = 0;
  for (const ModePair& p : e.pairing.pairs) cols = std::max(cols, p.model + 3);
  const double top = e.measured_frequency_hz.size() ? 1.5 * e.measured_frequency_hz.maxCoeff() : 0;
  for (Eigen::Index j = 0; j < e.all_model_frequency_hz.size(); ++j) {
    if (e.all_model_frequency_hz(j) <= top) cols = std::max(cols, static_cast<int>(j) + 1);
  }
  return std::min(cols, static_cast<int>(e.mac.cols()));
}

std::string mac_matrix_csv(const LinearUpdateSummary& s) {
  const Eigen::MatrixXd& mac = s.final.mac;
  const int cols = mac_columns(s);
  std::string t = "measured";
  for (int j = 0; j < cols; ++j) t += fmt::format(",model{}", j + 1);
  t += "\n";
  for (Eigen::Index i = 0; i < mac.rows(); ++i) {
    t += s.final.measured_id(i);
    for (int j = 0; j < cols; ++j) t += fmt::format(",{}", num(mac(i, j)));
    t += "\n";
  }
  return t;
}

std::string linear_sweeps_csv(const LinearUpdateSummary& s) {
  const Eigen::Index m = s.final.measured_frequency_hz.size();
  std::string t = "set,factor,stiffness,rms_error";
  for (Eigen::Index i = 0; i < m; ++i) t += ",error" + s.final.measured_id(i);
  t += "\n";
  for (const ParameterReport& p : s.parameters) {
    for (size_t k = 0; k < p.sweep_factor.size(); ++k) {
      // Empty cells where a mode is unpaired or could not be followed by its shape.
      t +=
          fmt::format("{},{},{},{}", cell(p.name), num(p.sweep_factor[k]),
                      num(p.sweep_factor[k] * p.value), p.sweep_rms[k] ? num(*p.sweep_rms[k]) : "");
      for (Eigen::Index i = 0; i < m; ++i) {
        t += ',';
        const size_t c = static_cast<size_t>(i);
        if (k < p.sweep_errors.size() && c < p.sweep_errors[k].size() && p.sweep_errors[k][c])
          t += num(*p.sweep_errors[k][c]);
      }
      t += "\n";
    }
  }
  return t;
}

std::vector<IwanParameterRow> iwan_parameter_rows(const IwanUpdateSummary& s,
                                                  double identifiable_std) {
  auto rel = [&](int k) { return s.held[k] || !s.improved ? -1.0 : s.relative_std(k); };
  const double ks = s.reference_stiffness;
  // Below phi_max the data fix K_T, chi and R only: Fs and beta are not identified separately.
  // `held` is true where held as asked (--gamma, --beta); beta held by the fit itself is false
  // with its note (before, true, as if asked).
  const bool micro = s.microslip_only();
  const auto row = [&](const char* name, double initial, double final, double relative_std,
                       bool held, bool separately_identified, int bound, std::string note) {
    IwanParameterRow r{name, initial, final, relative_std, false, held, bound, std::move(note)};
    r.identifiable = relative_std > 0 && separately_identified && relative_std <= identifiable_std;
    return r;
  };
  // chi is judged by what it sets, the damping's slope 1 + chi over ln amplitude (D ~ A^(chi+3),
  // method.md), not by its own relative sigma: chi 0.0064 +/- 0.006 (93 % of chi, 0.6 % of the
  // slope) was "not identifiable", chi -0.9 +/- 0.18 (20 %, the slope 0.1 +/- 0.18) was.
  const auto chi_row = [&] {
    IwanParameterRow r = row("chi", s.start.chi, s.best.chi, rel(2), s.held_as_asked(2), true,
                             s.bound_side[2], s.parameter_note(2));
    r.identifiable = r.relative_std > 0 &&
                     r.relative_std * std::abs(s.best.chi) <= identifiable_std * (1 + s.best.chi);
    return r;
  };
  std::vector<IwanParameterRow> rows = {
      row("Fs", s.start.Fs, s.best.Fs, rel(0), s.held_as_asked(0), !micro, s.bound_side[0],
          s.parameter_note(0)),
      row("Kt", s.start.Kt, s.best.Kt, rel(1), s.held_as_asked(1), true, s.bound_side[1],
          s.parameter_note(1)),
      chi_row(),
      row("beta", s.start.beta, s.best.beta, rel(3), s.held_as_asked(3), !micro, s.bound_side[3],
          s.parameter_note(3)),
  };
  if (s.modal_ratio_fitted) {
    rows.push_back(row("modal_ratio", s.modal_ratio_start, s.modal_ratio,
                       s.improved && s.modal_ratio_std > 0 && s.modal_ratio > 0
                           ? s.modal_ratio_std / s.modal_ratio
                           : -1.0,
                       false, true, s.bound_side[4], s.parameter_note(4)));
  }
  // gamma = K_T / K_s, the paper's stiffness factor, is Kt again and no parameter of its own:
  // last, after the rows the contract lists (Fs, Kt, chi, beta and, when fitted, modal_ratio).
  if (ks > 0) {
    rows.push_back(row("gamma", s.start.Kt / ks, s.best.Kt / ks, rel(1), s.held_as_asked(1), true,
                       s.bound_side[1], s.parameter_note(1)));
  }
  return rows;
}

std::string iwan_parameters_csv(const IwanUpdateSummary& s, double identifiable_std) {
  std::string t = "name,initial,final,relative_std,identifiable,held,at_bound,note\n";
  for (const IwanParameterRow& r : iwan_parameter_rows(s, identifiable_std)) {
    t += fmt::format("{},{},{},{},{},{},{},{}\n", r.name, num(r.initial), num(r.final),
                     r.relative_std > 0 ? num(r.relative_std) : "", r.identifiable ? 1 : 0,
                     r.held ? 1 : 0,
                     r.at_bound < 0   ? "lower"
                     : r.at_bound > 0 ? "upper"
                                      : "",
                     cell(r.note));
  }
  return t;
}

std::string iwan_history_csv(const IwanUpdateSummary& s) {
  std::string t = "evaluation,objective,best,stage\n";
  for (const IwanHistoryEntry& h : s.history) {
    // A parameter set the model could not evaluate has no objective value: left out (its
    // evaluation number is skipped), never written as a number.
    if (!std::isfinite(h.cost)) continue;
    t += fmt::format("{},{},{},{}\n", h.evaluation, num(h.cost), num(h.best),
                     h.beta_held ? "beta held" : "beta free");
  }
  return t;
}

std::string pareto_csv(const std::vector<ParetoPoint>& front) {
  size_t modes = 0;
  for (const ParetoPoint& p : front) modes = std::max(modes, p.mode_errors.size());
  std::string t = "gamma,Fs,Kt,chi,beta,linear_error,backbone_cost,dominated";
  for (size_t i = 0; i < modes; ++i) t += fmt::format(",linear_error{}", i + 1);
  t += "\n";
  for (const ParetoPoint& p : front) {
    t += fmt::format("{},{},{},{},{},{},{},{}", num(p.gamma), num(p.params.Fs), num(p.params.Kt),
                     num(p.params.chi), num(p.params.beta), num(p.linear_error),
                     num(p.backbone_cost), p.dominated ? 1 : 0);
    for (size_t i = 0; i < modes; ++i) {
      t += ',';
      if (i < p.mode_errors.size() && p.mode_errors[i]) t += num(*p.mode_errors[i]);
    }
    t += "\n";
  }
  return t;
}

}  // namespace jointlab::correlate
