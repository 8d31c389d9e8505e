// One measured mode the model does not match, found by leaving each out (linear_odd_mode.h).
#include "jointlab/correlate/linear_odd_mode.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <Eigen/Cholesky>

#include "jointlab/correlate/linear_fit.h"
#include "jointlab/correlate/linear_restarts.h"
#include "jointlab/correlate/linear_uncertainty.h"
#include "jointlab/correlate/noise_limits.h"

namespace jointlab::correlate::detail {
namespace {

// `measured` without mode (column) `drop`.
MeasuredModes without_mode(const MeasuredModes& measured, Eigen::Index drop) {
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < measured.frequency_hz.size(); ++i)
    if (i != drop) keep.push_back(i);
  return measured.columns(keep);
}

// The paired measured modes of `e`, the largest errors in sigmas of their own modes first (8 at
// most).
std::vector<int> largest_errors(const LinearEvaluation& e) {
  const auto weighted = [&](int i) {
    return e.residuals(i) * (e.weights.size() == e.residuals.size() ? e.weights(i) : 1.0);
  };
  std::vector<int> order;
  for (const ModePair& q : e.pairing.pairs) order.push_back(q.measured);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return std::abs(weighted(a)) > std::abs(weighted(b)); });
  if (order.size() > 8) order.resize(8);
  return order;
}

// A refit without one measured mode that fits within the noise (or far below the given).
struct Without {
  int mode = -1;
  double chi2 = 0;  // the refit's chi-square (not reduced)
  std::string text;
  double reduced = 0;  // the refit's reduced chi-square
};

// The fit again without one measured mode: the mode, the fit's summary and theta.
struct Refit {
  int mode;
  LinearUpdateSummary r;
  Eigen::VectorXd theta;
};

// The fits again without one measured mode each (fit_as_given from the start, no progress
// lines), each made on first asking: the check of a large misfit and the pull check that follows
// it where that finds nothing leave out the same modes, each refit a whole fit.
class Refits {
 public:
  Refits(const model::Model& model, const std::vector<std::string>& names,
         const std::vector<Sensor>& sensors, const MeasuredModes& measured,
         const LinearUpdateOptions& options)
      : model_(model), names_(names), sensors_(sensors), measured_(measured), options_(options) {
    options_.progress = nullptr;
  }
  Refits(const Refits&) = delete;
  Refits& operator=(const Refits&) = delete;

  /// The fit without measured mode i.
  const Refit& without(int i) {
    if (const auto it = done_.find(i); it != done_.end()) return it->second;
    Refit f{i, {}, {}};
    f.theta =
        fit_as_given(model_, names_, sensors_, without_mode(measured_, i), options_, false, f.r);
    return done_.emplace(i, std::move(f)).first->second;
  }
  /// The options the refits are made with.
  const LinearUpdateOptions& options() const { return options_; }

 private:
  const model::Model& model_;
  const std::vector<std::string>& names_;
  const std::vector<Sensor>& sensors_;
  const MeasuredModes& measured_;
  LinearUpdateOptions options_;
  std::map<int, Refit> done_;
};

// Whether refit `f` pairs every other mode of `e` and leaves scatter within the noise.
bool within_noise(const Refit& f, const LinearEvaluation& e) {
  const LinearUpdateSummary& r = f.r;
  return fitted(r) && r.degrees_of_freedom >= 1 &&
         r.final.pairing.pairs.size() + 1 >= e.pairing.pairs.size() &&
         r.reduced_chi2 <= reduced_chi2_limit(r.degrees_of_freedom);
}

// Refit `f` as named in a message: "0.474 over 3 (largest error 0.102 %; spring.kg 2.01e+06,
// spring.kt 8.004e+03)".
std::string refit_text(const Refit& f, const std::vector<std::string>& names) {
  const LinearUpdateSummary& r = f.r;
  std::vector<std::string> values;
  for (size_t k = 0; k < names.size() && k < r.parameters.size(); ++k)
    values.push_back(fmt::format("{} {:.4g}{}", names[k], f.theta(static_cast<Eigen::Index>(k)),
                                 r.parameters[k].held ? " (held)" : ""));
  return fmt::format("{:.3g} over {} (largest error {:.3g} %; {}{})", r.reduced_chi2,
                     r.degrees_of_freedom, 100 * r.final.max_error(), fmt::join(values, ", "),
                     r.starts > 1 ? fmt::format("; the best of {} starts", r.starts) : "");
}

// Refit `f` into `fits` where it pairs every other mode of `e` and leaves scatter within the
// noise and a hundredth of the `given` reduced chi-square, or less.
void judge_refit(const Refit& f, const LinearEvaluation& e, double given,
                 const std::vector<std::string>& names, std::vector<Without>& fits) {
  if (!within_noise(f, e) || !(given >= 100 * std::max(f.r.reduced_chi2, 1.0))) return;
  fits.push_back(
      {f.mode, f.r.reduced_chi2 * f.r.degrees_of_freedom, refit_text(f, names), f.r.reduced_chi2});
}

// Refit `f` into `far` where it pairs every other mode of `e` and leaves a reduced chi-square
// beyond the noise but a hundredth of the `given` one or less: the stated noise is then likely
// too small, and the mode left out holds 99 % of the misfit or more. The refit needs 2 degrees
// of freedom or more: over 1, its chi-square is a single draw of the noise, which falls below a
// hundredth of the total by chance (of two such components, one holds 99 % of their sum in 13 %
// of draws): the two chains' five lowest modes with 2 % noise stated 0.1 %, no mode off (seed 11),
// named mode 3, 5.45 % off (2.7 of that noise), "likely one the model does not match".
void judge_far_below(const Refit& f, const LinearEvaluation& e, double given,
                     const std::vector<std::string>& names, std::vector<Without>& far) {
  const LinearUpdateSummary& r = f.r;
  if (!fitted(r) || r.degrees_of_freedom < 2 ||
      r.final.pairing.pairs.size() + 1 < e.pairing.pairs.size() || within_noise(f, e) ||
      !(given >= 100 * std::max(r.reduced_chi2, 1.0)))
    return;
  far.push_back(
      {f.mode, r.reduced_chi2 * r.degrees_of_freedom, refit_text(f, names), r.reduced_chi2});
}

// Each mode of `order` left out in turn and the rest fitted again, the refits that fit within
// the noise in order of chi-square. Each refit from the start first; where none fits within the
// noise, those of the 3 largest errors again from the restarts (restart_if_misfit; 2 per set
// each, so at most 6 per set in all, on a result that was wrong anyway): the lap joint above
// with a row at 300 Hz the model does not have, left out, stopped where the whole table had
// (K_T 1.5e9) in 4 of 6 seeds, and the update ended "converged" with K_T held (flat) at 2e7
// against 6e7.
std::vector<Without> fits_without_each(const model::Model& model,
                                       const std::vector<std::string>& names,
                                       const std::vector<Sensor>& sensors,
                                       const MeasuredModes& measured, Refits& cache,
                                       const LinearEvaluation& e, double given,
                                       const std::vector<int>& order, std::vector<Without>& far) {
  std::vector<Without> fits;
  for (const int i : order) judge_refit(cache.without(i), e, given, names, fits);
  if (fits.empty()) {
    std::vector<Without> restarted;
    for (size_t q = 0; q < order.size() && q < 3; ++q) {
      Refit f = cache.without(order[q]);  // restarted here, as it is, in the cache
      const MeasuredModes without = without_mode(measured, f.mode);
      std::optional<TrackedPoint> end;
      restart_if_misfit(model, names, sensors, without, cache.options(), f.r, f.theta, end,
                        nullptr);
      judge_refit(f, e, given, names, fits);
      judge_far_below(f, e, given, names, restarted);
    }
    // Far below the given where none fits within the noise: each mode's best of its refits.
    if (fits.empty()) {
      for (const int i : order) {
        std::vector<Without> one;
        judge_far_below(cache.without(i), e, given, names, one);
        for (const Without& w : restarted)
          if (w.mode == i && (one.empty() || w.chi2 < one.front().chi2)) one = {w};
        far.insert(far.end(), one.begin(), one.end());
      }
      std::sort(far.begin(), far.end(),
                [](const Without& a, const Without& b) { return a.chi2 < b.chi2; });
    }
  }
  if (fits.empty()) return fits;
  std::sort(fits.begin(), fits.end(),
            [](const Without& a, const Without& b) { return a.chi2 < b.chi2; });
  return fits;
}

// Whether measured mode i of `e` has no shape the MAC can read. Such a mode rests on the nearest
// model frequency at the start, which a start far from the truth gets wrong: a trial's lap joint
// at one sensor (model mode 3 not in the table, K_T started at a third of the truth) paired its
// 376 Hz mode with model mode 7 (385 Hz at the start) where the truth's mode 6 (359 Hz at the
// start) is it, in 3 of 8 seeds, and blaming the mode alone would have had the user drop a mode
// the model has.
bool by_frequency(const LinearEvaluation& e, int i) {
  return static_cast<size_t>(i) < e.mac_reads_shape.size() &&
         !e.mac_reads_shape[static_cast<size_t>(i)];
}

// How measured mode i of `e` is paired, for the message.
std::string partner(const LinearEvaluation& e, const MeasuredModes& measured, int i) {
  if (!by_frequency(e, i)) return fmt::format("paired with {}", pair_text(e, i));
  const int j = e.pairing.model_for(i);
  int next = -1;
  for (int k = 0; k < static_cast<int>(e.all_model_frequency_hz.size()); ++k) {
    if (k == j) continue;
    const double d = std::abs(std::log(e.all_model_frequency_hz(k) / measured.frequency_hz(i)));
    if (next < 0 ||
        d < std::abs(std::log(e.all_model_frequency_hz(next) / measured.frequency_hz(i))))
      next = k;
  }
  return fmt::format(
      "paired by frequency alone (no shape at two sensors) with model mode {} ({:.5g} Hz; the "
      "next nearest is model mode {}, {:.5g} Hz)",
      j + 1, e.all_model_frequency_hz(j), next + 1,
      next >= 0 ? e.all_model_frequency_hz(next) : 0.0);
}

// The refusal naming the one mode `w` whose leaving out fits within the noise (`noise`, the
// stated noise for the message).
std::string one_mode_named(const Without& w, const MeasuredModes& measured,
                           const LinearUpdateSummary& s, const std::string& noise) {
  const LinearEvaluation& e = s.final;
  const double given = s.reduced_chi2;
  const int i = w.mode;
  const std::string head = fmt::format(
      "test mode {} ({:.5g} Hz), {}, {:+.3g} % off, leaves a reduced chi-square of {:.3g} over "
      "{} degrees of freedom (largest frequency error {:.3g} %), far beyond the stated noise "
      "({}); without it the other {} pair and fit to {}, within that noise",
      measured.id(i), measured.frequency_hz(i), partner(e, measured, i), 100 * e.residuals(i),
      given, s.degrees_of_freedom, 100 * e.max_error(), noise, e.pairing.pairs.size() - 1, w.text);
  if (by_frequency(e, i)) {
    return fmt::format(
        "{}. Without a shape its pair rests on the nearest model frequency at the start, which "
        "a start far from the truth gets wrong, or it may be a mode the model does not have or "
        "a wrong frequency: give its shape at two sensors or more, or start the sets nearer "
        "(the model file's values; the fit without it is above), or leave it out of the table "
        "(its row; in a campaign, list the other [[mode]] names in [update.linear] modes) to "
        "update on the others",
        head);
  }
  return fmt::format(
      "{}. It is likely one the model does not match: a mode the model does not have (an "
      "in-plane, torsion or fixture mode, or a spurious peak), a wrong frequency, or the model "
      "may lack what moves it: check it, and leave it out of the table (its row; in a "
      "campaign, list the other [[mode]] names in [update.linear] modes) to update on the "
      "others",
      head);
}

// The refusal naming the one mode `w` whose leaving out leaves a hundredth of the given reduced
// chi-square or less, though not the stated noise (`noise`): a trial's stacked beam (y and z
// bending modes within 1-5 %, five sensors, a fixture row at 255 Hz whose shape was noise, 0.3 %
// frequency noise under the default 0.1 %) paired the row with a bending mode at 308 Hz (MAC
// 0.825, +20.7 %), the fit ran the bolts to their lower bound (2e4 against 6e7) and ended
// "converged" with errors of -17.7 % and -10.5 % and a reduced chi-square of 1.43e4; without the
// row the rest fit to 6.8, and with --frequency-std 0.003 the row was named already.
std::string far_below_named(const Without& w, const MeasuredModes& measured,
                            const LinearUpdateSummary& s, const std::string& noise) {
  const LinearEvaluation& e = s.final;
  const int i = w.mode;
  return fmt::format(
      "test mode {} ({:.5g} Hz), {}, {:+.3g} % off, leaves a reduced chi-square of {:.3g} over "
      "{} degrees of freedom (largest frequency error {:.3g} %), far beyond the stated noise "
      "({}); without it the other {} pair and fit to {}, beyond that noise too but {:.3g} times "
      "lower: the frequencies likely scatter more than stated (give their own uncertainty with "
      "--frequency-std), and this mode far more. It is likely one the model does not match or "
      "paired wrongly{}: check it, and leave it out of the table (its row; in a campaign, list "
      "the other [[mode]] names in [update.linear] modes) to update on the others",
      measured.id(i), measured.frequency_hz(i), partner(e, measured, i), 100 * e.residuals(i),
      s.reduced_chi2, s.degrees_of_freedom, 100 * e.max_error(), noise, e.pairing.pairs.size() - 1,
      w.text, s.reduced_chi2 / std::max(w.reduced, 1e-300),
      by_frequency(e, i) ? " (without a shape its pair rests on the nearest model frequency at "
                           "the start: give its shape at two sensors or more)"
                         : " (a mode the model does not have, such as an in-plane, torsion or "
                           "fixture mode or a spurious peak, or a wrong frequency)");
}

// The refusal naming every mode of `fits`, the data unable to tell which is wrong.
std::string modes_named(const std::vector<Without>& fits, const MeasuredModes& measured,
                        const LinearUpdateSummary& s, const std::string& noise) {
  const LinearEvaluation& e = s.final;
  const double given = s.reduced_chi2;
  std::vector<std::string> ids, each;
  for (const Without& w : fits) {
    ids.push_back(measured.id(w.mode));
    each.push_back(
        fmt::format("without test mode {} ({:.5g} Hz, {}, {:+.3g} % off) the others "
                    "fit to {}",
                    measured.id(w.mode), measured.frequency_hz(w.mode),
                    partner(e, measured, w.mode), 100 * e.residuals(w.mode), w.text));
  }
  return fmt::format(
      "one of test modes {} is likely one the model does not match or paired wrongly, and the "
      "data cannot tell which: the fit leaves a reduced chi-square of {:.3g} over {} degrees of "
      "freedom (largest frequency error {:.3g} %), far beyond the stated noise ({}); {}, "
      "each within that noise. Check those modes (a mode the model does not have, a wrong "
      "frequency, a pair by frequency alone from a start far from the truth, or a model that "
      "lacks what moves it), and leave the one that is wrong out of the table (its row; in a "
      "campaign, list the other [[mode]] names in [update.linear] modes)",
      fmt::join(ids, ids.size() == 2 ? " and " : ", "), given, s.degrees_of_freedom,
      100 * e.max_error(), noise, fmt::join(each, "; "));
}

// The paired modes of the result whose leaving out moves, to first order, some fitted set by
// `screen` or more standard deviations of the two fits (as pull_of() judges a refit): the
// deletion formulas of linear least squares over the weighted rows j_i of the sets with a
// standard deviation (covariance A^-1 sigma_f^2, A = J^T J) and the weighted residuals r_i;
// with u = A^-1 j_i^T and h_i = j_i u, the move is u r_i / (1 - h_i), the chi-square falls by
// r_i^2 / (1 - h_i) / sigma_f^2, and the refit's covariance is (A^-1 + u u^T / (1 - h_i))
// sigma_f^2, times the refit's reduced chi-square where above 1. A screen: only where one is
// found are the modes fitted again (a fit each). A mode that alone fixes a set (1 - h_i at
// rounding) leaves it unseen, without a standard deviation: not one.
std::vector<int> pulling_candidates(const LinearUpdateSummary& s, double frequency_std,
                                    double screen) {
  const LinearEvaluation& e = s.final;
  std::vector<int> sets, rows;
  for (size_t k = 0; k < s.parameters.size(); ++k)
    if (!s.parameters[k].held && s.parameters[k].relative_std && *s.parameters[k].relative_std > 0)
      sets.push_back(static_cast<int>(k));
  for (const ModePair& q : e.pairing.pairs) rows.push_back(q.measured);
  if (sets.empty() || rows.size() <= sets.size() || s.degrees_of_freedom < 2 ||
      e.jacobian.cols() < static_cast<Eigen::Index>(s.parameters.size()))
    return {};
  const auto w = [&](int i) { return e.weights.size() == e.residuals.size() ? e.weights(i) : 1.0; };
  Eigen::MatrixXd j(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(sets.size()));
  Eigen::VectorXd r(j.rows());
  for (Eigen::Index a = 0; a < j.rows(); ++a) {
    const int i = rows[static_cast<size_t>(a)];
    r(a) = w(i) * e.residuals(i);
    for (Eigen::Index c = 0; c < j.cols(); ++c)
      j(a, c) = w(i) * e.jacobian(i, sets[static_cast<size_t>(c)]);
  }
  const Eigen::LDLT<Eigen::MatrixXd> jtj(j.transpose() * j);
  if (jtj.info() != Eigen::Success) return {};
  const Eigen::VectorXd inverse_diagonal =
      jtj.solve(Eigen::MatrixXd::Identity(j.cols(), j.cols())).diagonal();
  const double sf2 = frequency_std * frequency_std;
  std::vector<int> out;
  for (Eigen::Index a = 0; a < j.rows(); ++a) {
    const Eigen::VectorXd u = jtj.solve(j.row(a).transpose());
    const double rest = 1 - j.row(a).dot(u);
    if (!(rest > 1e-9)) continue;
    const double again =
        std::max(0.0, s.chi2 - r(a) * r(a) / rest / sf2) / (s.degrees_of_freedom - 1);
    bool pulls = false;
    for (Eigen::Index c = 0; c < j.cols() && !pulls; ++c) {
      const double given =
          *s.parameters[static_cast<size_t>(sets[static_cast<size_t>(c)])].relative_std;
      const double refit = (inverse_diagonal(c) + u(c) * u(c) / rest) * sf2 * std::max(1.0, again);
      pulls = std::abs(u(c) * r(a) / rest) >= screen * std::sqrt(given * given + refit);
    }
    if (pulls) out.push_back(rows[static_cast<size_t>(a)]);
  }
  return out;
}

// How far refit `f` moves a set from the result `s`: the largest |ln(theta_f / theta_s)| over
// the sets with a standard deviation at both, in standard deviations of the two
// (hypot(sigma_s, sigma_f)), with the clause saying it; 0 and "" where none.
std::pair<double, std::string> pull_of(const Refit& f, const LinearUpdateSummary& s,
                                       const std::vector<std::string>& names) {
  std::pair<double, std::string> out{0.0, ""};
  for (size_t k = 0; k < names.size() && k < s.parameters.size() && k < f.r.parameters.size();
       ++k) {
    const ParameterReport &a = s.parameters[k], &b = f.r.parameters[k];
    if (a.held || b.held || !a.relative_std || !b.relative_std || !(a.value > 0)) continue;
    const double v = f.theta(static_cast<Eigen::Index>(k));
    const double z = std::abs(std::log(v / a.value)) / std::hypot(*a.relative_std, *b.relative_std);
    if (!(z > out.first)) continue;
    out = {z,
           fmt::format("{} at {:.4g} (+/- {:.3g} %) against {:.4g} (+/- {:.3g} %) with it, {:.3g} "
                       "standard deviations of the two apart",
                       names[k], v, 100 * *b.relative_std, a.value, 100 * *a.relative_std, z)};
  }
  return out;
}

// Where the fit leaves scatter beyond the noise (not far beyond: misfit_of_one_mode's first
// test) and a paired mode pulls a set: leaving it out, the others fit within the noise with
// that set `kPull` or more standard deviations of the two fits away. The sets of the result
// then rest on a mode the others contradict, and their standard deviations, widened by the
// scatter as if every mode shared it, do not cover that: a trial's wide lap plate (three
// sensors, five bending and twisting modes with 0.1 % noise and a row at 450 Hz whose shape
// was noise) paired the row with a mode K_T moves (MAC 0.78 at three sensors), and the fit
// pulled K_T from 1.3e7 to 5.9e6 to meet it, "converged" at +/- 0.94 % (58 of those off) with
// a reduced chi-square of 7.4; so in 6 of 12 seeds. Returns the refusal naming the mode, with
// every mode whose leaving out fits within 9 chi-square units of the best such refit (the data
// cannot tell them apart), or "" (no mode pulls so: the scatter is shared, and the widened
// standard deviations stand). The two chains with noise five times the stated move no set by
// more than 1.4 such standard deviations (200 seeds, none refused, their test's CPU the same).
std::string pulled_by_one_mode(const std::vector<std::string>& names, const MeasuredModes& measured,
                               const LinearUpdateOptions& options, const LinearUpdateSummary& s,
                               Refits& cache) {
  constexpr double kPull = 3;
  const LinearEvaluation& e = s.final;
  // The modes that may pull, then those of largest error (the 8 at most; a mode that pulls
  // meets its partner and may have the smallest error of all).
  std::vector<int> order = pulling_candidates(s, options.frequency_std, 2.0);
  if (order.empty()) return "";
  for (const int i : largest_errors(e))
    if (std::find(order.begin(), order.end(), i) == order.end()) order.push_back(i);
  std::vector<Refit> within;
  std::vector<std::string> pulls;
  double best = 0, best_pulled = 0;
  bool any_pulled = false;
  for (const int i : order) {
    const Refit& f = cache.without(i);
    if (!within_noise(f, e)) continue;
    const double chi2 = f.r.reduced_chi2 * f.r.degrees_of_freedom;
    auto [z, text] = pull_of(f, s, names);
    if (within.empty() || chi2 < best) best = chi2;
    if (z >= kPull && (!any_pulled || chi2 < best_pulled)) best_pulled = chi2;
    any_pulled = any_pulled || z >= kPull;
    pulls.push_back(z >= kPull ? std::move(text) : "");
    within.push_back(f);
  }
  // A pulling refit among those the data cannot tell from the best: the mode that pulls may be
  // the wrong one, or another whose leaving out fits as well.
  if (!any_pulled || best_pulled - best >= 9) return "";
  std::vector<size_t> by_mode(within.size());
  for (size_t q = 0; q < by_mode.size(); ++q) by_mode[q] = q;
  std::sort(by_mode.begin(), by_mode.end(),
            [&](size_t a, size_t b) { return within[a].mode < within[b].mode; });
  std::vector<std::string> ids, each;
  for (const size_t q : by_mode) {
    const Refit& f = within[q];
    if (f.r.reduced_chi2 * f.r.degrees_of_freedom - best >= 9) continue;
    ids.push_back(measured.id(f.mode));
    each.push_back(fmt::format(
        "without test mode {} ({:.5g} Hz, {}, {:+.3g} % off) the others fit within that "
        "noise to {}{}",
        measured.id(f.mode), measured.frequency_hz(f.mode), partner(e, measured, f.mode),
        100 * e.residuals(f.mode), refit_text(f, names),
        pulls[q].empty() ? "" : ", with " + pulls[q]));
  }
  const std::string noise = stated_noise(options.frequency_std, s.mode_frequency_std,
                                         [&](Eigen::Index i) { return measured.id(i); });
  return fmt::format(
      "{} likely one the model does not match{}: the fit leaves a reduced chi-square of {:.3g} "
      "over {} degrees of freedom (largest frequency error {:.3g} %), beyond the stated noise "
      "({}); {}. A set one mode pulls so far from where the others put it is not a result (its "
      "standard deviation, widened by the scatter, does not cover the pull): "
      "check {} (a mode the model does not have: an in-plane, torsion or fixture mode, or a "
      "spurious peak; a wrong frequency; a pair by frequency alone from a start far from the "
      "truth; or a model that lacks what moves it), and leave {} out of the table (its row; in a "
      "campaign, list the other [[mode]] names in [update.linear] modes); if the frequencies' "
      "noise is larger than stated, give it (--frequency-std)",
      ids.size() == 1 ? fmt::format("test mode {} is", ids[0])
                      : fmt::format("one of test modes {} is",
                                    fmt::join(ids, ids.size() == 2 ? " and " : ", ")),
      ids.size() == 1 ? "" : ", and the data cannot tell which", s.reduced_chi2,
      s.degrees_of_freedom, 100 * e.max_error(), noise, fmt::join(each, "; "),
      ids.size() == 1 ? "it" : "those modes", ids.size() == 1 ? "it" : "the one that is wrong");
}

}  // namespace

// Why a fit's misfit is one measured mode that the model does not match, or "". A trial's lap
// joint (three sensors on one strip, five bending modes with 0.1 % noise and a sixth row at
// 450 Hz with a shape of noise, a mode the model does not have) paired that row with a torsion
// mode at 355 Hz (MAC 0.82 at three sensors, -21 %), and the fit drove K_T to 1e10 and spring.rxy
// to 6.8e5 to meet it: "converged", reduced chi-square 9.7e3, K_T then "held (flat)" at its start
// (truth 4e7), in 3 of 6 seeds. So where a fit leaves scatter beyond the noise, and by far
// (reduced chi-square at least 100), each paired mode (the 8 of largest error at most) is left out
// in turn and the rest fitted again; those whose leaving out pairs every other mode and leaves
// scatter within the noise (and a hundredth of the given, or less) are named and the update
// refused: a mode the model does not have, a wrong frequency, or a model that lacks what moves it.
// One is named alone only where its refit's chi-square is below every other's by 9 or more (3
// sigma): with the two-chain structure's first mode 15 % high, leaving out its fifth mode also
// fits within the noise (a chi-square of 7.3 over 2 degrees of freedom, ka moved from 5e5 to
// 2.4e6 past a crossing) and the largest error at the result was the fifth's, not the first's.
// Below 100 (beyond the noise all the same), or where no refit passes, a mode is named where it
// pulls a set (pulled_by_one_mode): a misfit of 7 gave K_T 58 standard deviations off before.
std::string misfit_of_one_mode(const model::Model& model, const std::vector<std::string>& names,
                               const std::vector<Sensor>& sensors, const MeasuredModes& measured,
                               const LinearUpdateOptions& options, const LinearUpdateSummary& s) {
  const double given = s.reduced_chi2;
  if (!fitted(s) || s.degrees_of_freedom < 2 || !(given > reduced_chi2_limit(s.degrees_of_freedom)))
    return "";
  Refits cache(model, names, sensors, measured, options);
  if (!(given > 100)) return pulled_by_one_mode(names, measured, options, s, cache);
  const LinearEvaluation& e = s.final;
  std::vector<Without> far;
  const std::vector<Without> fits =
      fits_without_each(model, names, sensors, measured, cache, e, given, largest_errors(e), far);
  const std::string noise = stated_noise(options.frequency_std, s.mode_frequency_std,
                                         [&](Eigen::Index i) { return measured.id(i); });
  // One mode alone far below the rest (its chi-square below every other's by 9 in the units of
  // its own scatter) where none fits within the stated noise.
  if (fits.empty() && !far.empty() &&
      (far.size() == 1 || far[1].chi2 - far[0].chi2 >= 9 * std::max(far[0].reduced, 1.0)))
    return far_below_named(far[0], measured, s, noise);
  if (fits.empty()) return pulled_by_one_mode(names, measured, options, s, cache);
  if (fits.size() == 1 || fits[1].chi2 - fits[0].chi2 >= 9)
    return one_mode_named(fits[0], measured, s, noise);
  return modes_named(fits, measured, s, noise);
}

}  // namespace jointlab::correlate::detail
