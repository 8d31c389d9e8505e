#include "jointlab/campaign/steps/known_parameters.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>
#include <Eigen/Core>

#include "jointlab/core/error.h"
#include "jointlab/correlate/iwan_update.h"

namespace jointlab::campaign {

namespace fs = std::filesystem;

Truth read_truth(const fs::path& path, const std::string& set) {
  Truth t;
  if (path.empty()) return t;
  toml::table doc;
  try {
    doc = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    throw InputError(where(path.string(), static_cast<long>(e.source().begin.line),
                           std::string(e.description())));
  }
  // [iwan] holds the fitted set's values, or one table per set ([iwan.bolt], [iwan.rivet]) of
  // which the fitted one is read: a model with two sets has two truths, and a truth file of
  // two tables was refused as `missing iwan.Fs`.
  std::string table = "iwan";
  const toml::table* iwan = doc["iwan"].as_table();
  if (iwan && !iwan->contains("Fs")) {
    std::vector<std::string> sets;
    for (auto&& [key, value] : *iwan)
      if (value.is_table()) sets.push_back("iwan." + std::string(key.str()));
    if (!sets.empty()) {
      const std::string bare = set.starts_with("iwan.") ? set.substr(5) : set;
      if (bare.empty()) {
        throw InputError(where(
            path.string(), 0,
            fmt::format("[iwan] holds the known values of {} sets ({}): name the fitted one in "
                        "[update.iwan] sets, and its known values are read from its table",
                        sets.size(), fmt::join(sets, ", "))));
      }
      if (!(*iwan)[bare].is_table()) {
        throw InputError(where(path.string(), 0,
                               fmt::format("no [iwan.{}] for the fitted set iwan.{} (tables: {})",
                                           bare, bare, fmt::join(sets, ", "))));
      }
      table = "iwan." + bare;
      iwan = (*iwan)[bare].as_table();
    }
  }
  const auto get = [&](const toml::table* from, const std::string& name, const char* key,
                       bool required) {
    const auto v = from ? (*from)[key].value<double>() : std::nullopt;
    if (!v && required)
      throw InputError(where(path.string(), 0, fmt::format("missing {}.{}", name, key)));
    return v.value_or(0.0);
  };
  t.present = true;
  t.iwan = {get(iwan, table, "Fs", true), get(iwan, table, "Kt", true),
            get(iwan, table, "chi", true), get(iwan, table, "beta", true)};
  // The one domain of model files (model::iwan_parameter_domain): chi > -1, above 0 too.
  if (const std::string e = model::iwan_parameter_error(t.iwan); !e.empty())
    throw InputError(where(path.string(), 0, fmt::format("{}: {}", table, e)));
  const toml::table* scatter = doc["scatter"].as_table();
  t.scatter_kt = get(scatter, "scatter", "Kt", false);
  t.scatter_fs = get(scatter, "scatter", "Fs", false);
  return t;
}

std::string truth_set(const Campaign& c) {
  return c.iwan_update.sets.empty() ? std::string() : c.iwan_update.sets.front();
}

bool first_iwan(const model::Model& m, model::IwanParameters& p, std::string& set,
                const std::string& want) {
  for (const model::Joint& j : m.joints) {
    if (!j.iwan) continue;
    if (!want.empty() && j.element != want && j.element != "iwan." + want) continue;
    p = {j.iwan->slip_force(), j.iwan->stiffness(), j.iwan->chi(), j.iwan->beta()};
    set = j.element;
    return true;
  }
  return false;
}

// The slip force that, with beta, keeps p's Kt, chi and R (the microslip response):
// from R = Fs (chi+1) / (phi_max^(chi+2) (beta+c)), phi_max = Fs (1+beta) / (Kt (beta+c)),
// c = (chi+1)/(chi+2):  Fs^(chi+1) = (chi+1) (Kt (beta+c))^(chi+2) / (R (1+beta)^(chi+2) (beta+c)).
namespace {

// ln D(u) of an Iwan element at slip amplitude u, and its gradient with respect to
// x = (ln F_S, ln K_T, chi, ln beta) by central differences.
double log_dissipation(const model::IwanParameters& p, double u) {
  return std::log(model::Iwan(p).dissipation(u));
}
Eigen::Vector4d log_dissipation_gradient(const model::IwanParameters& p, double u) {
  Eigen::Vector4d g;
  for (int k = 0; k < 4; ++k) {
    const double h = 1e-5;
    model::IwanParameters a = p, b = p;
    if (k == 0) a.Fs *= std::exp(h), b.Fs *= std::exp(-h);
    if (k == 1) a.Kt *= std::exp(h), b.Kt *= std::exp(-h);
    if (k == 2) a.chi += h, b.chi -= h;
    if (k == 3) a.beta *= std::exp(h), b.beta *= std::exp(-h);
    g(k) = (log_dissipation(a, u) - log_dissipation(b, u)) / (2 * h);
  }
  return g;
}

// The "Updated versus known" table as it is filled, with the tallies its verdict needs.
struct KnownTable {
  ReportTable tb;
  int recovered = 0, judged = 0;
  std::vector<std::string> missed, unidentified, unjudged;

  // The row of quantity `name`: recovered where |got / known - 1| <= tol (`why` says whence the
  // tolerance).
  void judge(const std::string& name, double got, double known, double tol,
             const std::string& why) {
    const double r = got / known - 1;
    // No tolerance (none planted, and the update stated no sigma: a misfit, too few points):
    // not judged, rather than "NO" at any difference (the two-set beam's K_T, 1.25 % off).
    if (!(tol > 0)) {
      unjudged.push_back(name);
      tb.rows.push_back({name, fmt::format("{:.4g}", got), fmt::format("{:.4g}", known),
                         fmt::format("{:+.2f} %", 100 * r), "none known",
                         "not judged (no sigma stated)"});
      return;
    }
    const bool ok = std::abs(r) <= tol;
    ++judged;
    if (ok)
      ++recovered;
    else
      missed.push_back(name);
    tb.rows.push_back({name, fmt::format("{:.4g}", got), fmt::format("{:.4g}", known),
                       fmt::format("{:+.2f} %", 100 * r),
                       fmt::format("{:.1f} % ({})", 100 * tol, why), ok ? "yes" : "NO"});
  }

  // Twice the planted scatter where the truth file plants one, else twice the update's own
  // sigma (0: none known). Before, a truth file without [scatter] left K_T and F_S with no
  // tolerance, and so "NO recovered" at any difference (F_S -0.30 % with +/- 0.35 % stated).
  void judge_planted(const std::string& name, double got, double known, double planted,
                     double own_std) {
    if (planted > 0)
      judge(name, got, known, 2 * planted, fmt::format("2 x planted {:.1f} %", 100 * planted));
    else
      judge(name, got, known, 2 * own_std,
            fmt::format("2 x its uncertainty {:.2g} %, none planted", 100 * own_std));
  }
};

// The update's own sigma: at least the scatter between the hits' backbones from three hits
// on (the cluster-robust covariance), else the points' noise.
std::string own_sigma(int curves) {
  return curves >= 3
             ? fmt::format("2 x its uncertainty, at least the scatter between the {} hits", curves)
             : std::string("2 x its uncertainty");
}

// Backbones that stay in microslip: the identified combination judged, the dissipation per
// cycle of one element at the geometric middle of the measured slip range (D = 4 R
// u^(chi+3)/((chi+2)(chi+3)) below phi_max), Fs and beta said to be not identifiable, and the
// family of (Fs, beta) pairs that share the identified Kt, chi and R. Returns the paragraph's
// words on it.
std::string judge_microslip(const KnownComparison& k, KnownTable& j) {
  const model::IwanParameters& t = k.truth.iwan;
  const model::IwanParameters& u = k.updated;
  const double uref = std::sqrt(k.iwan.bottom_slip * k.iwan.top_slip);
  const Eigen::Vector4d gt = log_dissipation_gradient(t, uref);
  const double planted = std::hypot(gt(0) * k.truth.scatter_fs, gt(1) * k.truth.scatter_kt);
  const Eigen::Vector4d gu = log_dissipation_gradient(u, uref);
  const double own_sd = std::sqrt(std::max(0.0, gu.dot(k.iwan.covariance * gu)));
  const double tol = 2 * std::max(planted, own_sd);
  j.judge(fmt::format("D({:.3g} m) [J]", uref), std::exp(log_dissipation(u, uref)),
          std::exp(log_dissipation(t, uref)), tol,
          planted >= own_sd ? fmt::format("2 x planted {:.1f} % via Kt and Fs", 100 * planted)
                            : fmt::format("2 x its uncertainty {:.1f} %", 100 * own_sd));
  j.unidentified = {"Fs", "beta"};
  j.tb.rows.push_back({"Fs [N]", fmt::format("{:.4g}", u.Fs), fmt::format("{:.4g}", t.Fs),
                       fmt::format("{:+.2f} %", 100 * (u.Fs / t.Fs - 1)), "-",
                       "not identifiable (microslip)"});
  j.tb.rows.push_back({"beta", fmt::format("{:.4g}", u.beta), fmt::format("{:.4g}", t.beta),
                       fmt::format("{:+.2f} %", 100 * (u.beta / t.beta - 1)), "-",
                       "not identifiable (held)"});
  // The family of (Fs, beta) pairs that share the identified Kt, chi and R.
  const double fs_known_beta = correlate::slip_force_at_beta(u, t.beta);
  j.tb.rows.push_back({fmt::format("Fs at the known beta {:.4g} [N]", t.beta),
                       fmt::format("{:.4g}", fs_known_beta), fmt::format("{:.4g}", t.Fs),
                       fmt::format("{:+.2f} %", 100 * (fs_known_beta / t.Fs - 1)), "-",
                       "not judged (the identified family Fs(beta))"});
  std::vector<std::string> family;
  for (const double b : {0.25, 0.5, 1.0, 2.0, 4.0})
    family.push_back(fmt::format("{:.3g} N at beta {:g}", correlate::slip_force_at_beta(u, b), b));
  const std::string family_text = fmt::format(
      " Every (Fs, beta) pair with the identified Kt, chi and R fits these backbones alike: "
      "{}; at the known beta {:.4g} it gives Fs = {:.4g} N (known {:.4g} N).",
      fmt::join(family, ", "), t.beta, fs_known_beta, t.Fs);
  std::string micro = fmt::format(
      " The backbones stay in microslip: over the measured amplitudes the most loaded joint "
      "slips {:.3g} to {:.3g} m, at most {:.0f} % of phi_max ({:.3g} m in the updated model). "
      "Below phi_max an Iwan element's response depends on Kt, chi and R alone, so these data "
      "fix Kt, chi and R but not Fs and beta separately: beta is held at its starting value "
      "{:.4g} and Fs is the slip force that gives the identified R with it. The table "
      "compares the identified combination instead: D(u), the energy one joint element "
      "dissipates per cycle at the middle slip u = {:.3g} m (D = 4 R u^(chi+3) / ((chi+2) "
      "(chi+3))), whose planted scatter follows from that of Kt and Fs. Fs and beta need "
      "backbones that reach past phi_max.",
      k.iwan.bottom_slip, k.iwan.top_slip, 100 * k.iwan.top_slip / k.iwan.phi_max, k.iwan.phi_max,
      u.beta, uref);
  micro += family_text;
  return micro;
}

// Backbones that reach macroslip: Fs judged, and beta unless the campaign held it.
void judge_macroslip(const KnownComparison& k, KnownTable& j) {
  const model::IwanParameters& t = k.truth.iwan;
  const model::IwanParameters& u = k.updated;
  j.judge_planted("Fs [N]", u.Fs, t.Fs, k.truth.scatter_fs, k.iwan.relative_std(0));
  if (k.beta_held) {
    j.unidentified.push_back("beta");
    j.tb.rows.push_back({"beta", fmt::format("{:.4g}", u.beta), fmt::format("{:.4g}", t.beta),
                         fmt::format("{:+.2f} %", 100 * (u.beta / t.beta - 1)), "-",
                         "held by the campaign"});
  } else {
    j.judge("beta", u.beta, t.beta, 2 * k.iwan.relative_std(3), own_sigma(k.curves));
  }
}

// The paragraph's verdict: how many identified quantities the update recovers, which are not
// judged and which the data cannot identify.
std::string verdict_of(const KnownTable& j) {
  std::string verdict =
      j.judged == 0 && !j.unjudged.empty()
          ? std::string("no identified quantity has a tolerance to judge it by")
      : j.judged == 0 ? std::string("no quantity was identified by an update, so none is judged")
      : j.missed.empty()
          ? fmt::format("the update recovers all {} identified quantities within the tolerance",
                        j.judged)
          : fmt::format("the update recovers {} of {} identified quantities; NOT recovered: {}",
                        j.recovered, j.judged, fmt::join(j.missed, ", "));
  if (!j.unjudged.empty())
    verdict += fmt::format("; not judged, the update stating no sigma for them: {}",
                           fmt::join(j.unjudged, ", "));
  if (!j.unidentified.empty())
    verdict +=
        fmt::format("; not identifiable from these data: {}", fmt::join(j.unidentified, ", "));
  return verdict;
}

// The tolerance's source per quantity: planted scatter where the truth file gives it, else
// the update's own uncertainty (without any planted, "planted ... (Kt 0.0 %, Fs 0.0 %)" was
// said beside "where none was planted (Kt, Fs, chi, beta)").
std::string tolerance_of(const KnownComparison& k) {
  std::vector<std::string> planted, from_fit;
  if (k.truth.scatter_kt > 0)
    planted.push_back(fmt::format("Kt {:.1f} %", 100 * k.truth.scatter_kt));
  else
    from_fit.emplace_back("Kt");
  if (k.truth.scatter_fs > 0)
    planted.push_back(fmt::format("Fs {:.1f} %", 100 * k.truth.scatter_fs));
  else
    from_fit.emplace_back("Fs");
  from_fit.emplace_back("chi");
  from_fit.emplace_back("beta");
  // The update's covariance is at least the cluster-robust one (one cluster per hit) only
  // with three curves or more (IwanObjective's covariance); with fewer it rests on the points.
  const std::string robust = k.curves >= 3 ? fmt::format(
                                                 " (at least what the scatter between the {} hits' "
                                                 "backbones gives: they, not their points, are the "
                                                 "independent samples)",
                                                 k.curves)
                                           : std::string();
  return planted.empty()
             ? fmt::format(
                   "Tolerance: none was planted (Kt, Fs, chi, beta): twice the update's own "
                   "one-sigma uncertainty{}",
                   robust)
             : fmt::format(
                   "Tolerance: twice the planted one-sigma hit-to-hit scatter ({}); where "
                   "none was planted ({}), twice the update's own one-sigma uncertainty, "
                   "which the planted scatter causes{}",
                   fmt::join(planted, ", "), fmt::join(from_fit, ", "), robust);
}

}  // namespace

// The "Known parameters" table and paragraph: per quantity the updated and the known value,
// the difference, the tolerance (twice the planted one-sigma scatter where scatter was planted,
// else twice the update's own one-sigma uncertainty) and whether
// the update recovers it. Parameters the data cannot identify are said to be so.
void compare_with_known(const KnownComparison& k, const std::string& truth_name, ReportSection& s) {
  const model::IwanParameters& t = k.truth.iwan;
  const model::IwanParameters& u = k.updated;
  KnownTable j;
  j.tb = {"Updated versus known (" + truth_name + ")",
          {"quantity", "updated", "known", "difference", "tolerance", "recovered"},
          {}};
  if (k.kt_updated) j.judge_planted("Kt [N/m]", u.Kt, t.Kt, k.truth.scatter_kt, k.kt_std);
  std::string micro;
  if (k.iwan_ran) {
    j.judge("chi", u.chi, t.chi, 2 * k.iwan.relative_std(2), own_sigma(k.curves));
    if (k.iwan.microslip_only())
      micro = judge_microslip(k, j);
    else
      judge_macroslip(k, j);
  } else {
    j.unidentified = {"Fs", "chi", "beta"};
    micro =
        " Fs, chi and beta are not identified (update.iwan is off): their starting values stand.";
  }
  s.tables.push_back(j.tb);
  const std::string verdict = verdict_of(j);
  if (k.iwan_ran && k.cost_known > 0)
    micro += fmt::format(
        " The backbone cost is {:.4g} at the known parameters and {:.4g} at the updated ones{}.",
        k.cost_known, k.iwan.final_cost,
        k.iwan.final_cost <= k.cost_known ? " (the optimiser reaches at least the known fit)"
                                          : " (the optimiser stopped short of the known fit)");
  s.paragraphs.push_back(
      fmt::format("Known parameters ({}): {}. {}.{}", truth_name, verdict, tolerance_of(k), micro));
}

}  // namespace jointlab::campaign
