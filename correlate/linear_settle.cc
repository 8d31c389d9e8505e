// Pairs decided by the data at a fit's result (linear_settle.h).
#include "jointlab/correlate/linear_settle.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/correlate/noise_limits.h"

namespace jointlab::correlate::detail {
namespace {

// The model DOF where a sensor would best tell shapes `a` and `b` (full mass-normalised vectors)
// apart: among the DOFs no sensor reads (translations, components 1-3, where the model labels its
// DOFs; else every DOF), the one where their motions, each over its largest there, differ the
// most. As "9003:3 (there model mode 13 moves 0.82 of its largest and model mode 15 0.04)", its
// label or 0-based index; "" where none differs by 0.3 or more.
std::string telling_sensor(const model::Model& model, const std::vector<Sensor>& sensors,
                           const Eigen::Ref<const Eigen::VectorXd>& a, int mode_a,
                           const Eigen::Ref<const Eigen::VectorXd>& b, int mode_b) {
  std::vector<Eigen::Index> dofs;
  for (Eigen::Index d = 0; d < a.size(); ++d) {
    if (std::any_of(sensors.begin(), sensors.end(), [&](const Sensor& s) { return s.dof == d; }))
      continue;
    if (!model.dof_labels.empty()) {
      const std::string& l = model.dof_labels[static_cast<size_t>(d)];
      const size_t colon = l.find(':');
      if (colon == std::string::npos || l.substr(0, colon) == "0") continue;  // modal coordinate
      const std::string c = l.substr(colon + 1);
      if (c != "1" && c != "2" && c != "3") continue;
    }
    dofs.push_back(d);
  }
  double top_a = 0, top_b = 0;
  for (const Eigen::Index d : dofs) top_a = std::max(top_a, std::abs(a(d)));
  for (const Eigen::Index d : dofs) top_b = std::max(top_b, std::abs(b(d)));
  if (!(top_a > 0) || !(top_b > 0)) return "";
  Eigen::Index best = -1;
  double gap = 0.3;
  for (const Eigen::Index d : dofs) {
    const double g = std::abs(std::abs(a(d)) / top_a - std::abs(b(d)) / top_b);
    if (g >= gap) gap = g, best = d;
  }
  if (best < 0) return "";
  return fmt::format(
      "{} (there model mode {} moves {:.2f} of its largest and model mode {} {:.2f})",
      model.dof_labels.empty() ? fmt::format("DOF {}", best)
                               : model.dof_labels[static_cast<size_t>(best)],
      mode_a + 1, std::abs(a(best)) / top_a, mode_b + 1, std::abs(b(best)) / top_b);
}

}  // namespace

bool ratio_decides(double worse, int dof_worse, double better, int dof_better) {
  return worse >= variance_ratio_limit(dof_worse, dof_better) * better;
}

std::string ratio_undecided(double worse, int dof_worse, double better, int dof_better) {
  return fmt::format(
      "left {:.3g} over {}, {:.3g} times less, and without the stated noise only a ratio beyond "
      "{:.3g} (Fisher's F's 3-sigma point over {} and {} degrees of freedom) tells the two apart; "
      "if the noise is larger than stated, give it (--frequency-std)",
      better, dof_better, worse / better, variance_ratio_limit(dof_worse, dof_better), dof_worse,
      dof_better);
}

// What differs between two fitted pairings that the data cannot tell apart (`why`): each
// measured mode paired with another model mode (by shape), named with its partner at each result
// (its own numbering there), the sets that differ between the results, and the costs.
std::string differing_pairs(const LinearProblem& p, const TrackedPoint& a, double cost_a,
                            const TrackedPoint& b, double cost_b, const std::string& why) {
  const LinearEvaluation ea = p.evaluate(a), eb = p.evaluate(b);
  const auto partner = [&](const LinearEvaluation& e, int i) {
    const int j = e.pairing.model_for(i);
    if (j < 0) return std::string("unpaired");
    const std::optional<double> mac = e.pair_mac(i);
    return fmt::format("model mode {} ({:.5g} Hz{})", j + 1, e.all_model_frequency_hz(j),
                       mac ? fmt::format(", MAC {:.3f}", *mac) : "");
  };
  std::vector<std::string> modes, sets_a, sets_b;
  std::string sensor;  // where a sensor would tell the first such mode's two partners apart
  for (size_t i = 0; i < a.columns.size() && i < b.columns.size(); ++i) {
    if (same_partners(p.model.mass, a.modes, {a.columns[i]}, b.modes, {b.columns[i]})) continue;
    const int k = static_cast<int>(i);
    std::string between;
    if (a.columns[i] >= 0 && b.columns[i] >= 0) {
      const double c =
          a.modes.shapes.col(a.columns[i]).dot(p.model.mass * b.modes.shapes.col(b.columns[i]));
      between = fmt::format(" (mass-weighted MAC {:.2f} between the two)", c * c);
      if (sensor.empty())
        sensor = telling_sensor(p.model, p.sensors, a.modes.shapes.col(a.columns[i]),
                                ea.pairing.model_for(k), b.modes.shapes.col(b.columns[i]),
                                eb.pairing.model_for(k));
    }
    modes.push_back(fmt::format(
        "test mode {} ({:.5g} Hz) with {} at one and with {} at the other{}", p.measured.id(k),
        p.measured.frequency_hz(k), partner(ea, k), partner(eb, k), between));
  }
  for (int k = 0; k < p.size(); ++k) {
    if (std::abs(a.x(k) - b.x(k)) < 0.01) continue;
    sets_a.push_back(fmt::format("{} {:.4g}", p.names[static_cast<size_t>(k)], std::exp(a.x(k))));
    sets_b.push_back(fmt::format("{} {:.4g}", p.names[static_cast<size_t>(k)], std::exp(b.x(k))));
  }
  std::vector<std::string> holds;
  for (const std::string& x : sets_a) holds.push_back(x.substr(0, x.find(' ')) + "=VALUE");
  return fmt::format(
      "two results pair {}{}, and leave costs {:.4g} and {:.4g}, which the data cannot tell "
      "apart ({}): add a sensor that sees the partners apart{}{}, or leave the mode out of the "
      "table",
      fmt::join(modes, "; "),
      sets_a.empty() ? std::string()
                     : fmt::format(" (the first at {}, the second at {})", fmt::join(sets_a, ", "),
                                   fmt::join(sets_b, ", ")),
      cost_a, cost_b, why, sensor.empty() ? "" : ", e.g. at " + sensor,
      holds.empty() ? ""
                    : fmt::format(", hold the sets that differ at values known otherwise (--hold "
                                  "{})",
                                  fmt::join(holds, " --hold ")));
}

namespace {

// The pairs whose model partner changed its shape along the fit (mass-weighted MAC below 0.5
// between the start's partner and the result's: another mode took its place, through a
// veering or a new pairing) and whose MAC at the result cannot confirm the new partner (a
// shape at fewer than two sensors, or below the threshold): their measured rows, each with a
// line on it.
std::vector<std::pair<int, std::string>> unconfirmed_changes(
    const Eigen::SparseMatrix<double>& mass, const TrackedPoint& start, const TrackedPoint& end,
    const LinearEvaluation& at_end, const MeasuredModes& measured, double mac_threshold) {
  std::vector<std::pair<int, std::string>> out;
  for (size_t i = 0; i < end.columns.size() && i < start.columns.size(); ++i) {
    const int a = start.columns[i], b = end.columns[i];
    if (a < 0 || b < 0) continue;
    const Eigen::VectorXd mb = mass * end.modes.shapes.col(b);
    const double c = start.modes.shapes.col(a).dot(mb);
    const std::optional<double> mac = at_end.pair_mac(static_cast<Eigen::Index>(i));
    if (c * c >= 0.5 || (mac && *mac >= mac_threshold)) continue;
    out.emplace_back(
        static_cast<int>(i),
        fmt::format(
            "test mode {} ({:.5g} Hz) from model mode {} to {} (mass-weighted MAC {:.2f} "
            "between them; {})",
            measured.id(static_cast<Eigen::Index>(i)),
            measured.frequency_hz(static_cast<Eigen::Index>(i)), a + 1, b + 1, c * c,
            mac ? fmt::format("MAC {:.2f} at the sensors", *mac) : "no shape at two sensors"));
  }
  return out;
}

}  // namespace

// The pairings to try where the rules pair `at` (made afresh at `point`) by a guess: every
// combination of one candidate for each tie (each a swap, so the pairs stay one to one), or
// for the first `ties` ties alone; else `point`. At the start every tie is tried: a later tie
// is met only once an earlier guess is made, and trying the first tie's candidates alone
// left a fit "converged" on a wrong guess of the second. At a fit's result the first alone
// (each candidate there is a fit of its own, within each start's fit).
std::vector<TrackedPoint> candidate_pairings(const TrackedPoint& point, const LinearEvaluation& at,
                                             size_t ties) {
  std::vector<TrackedPoint> out{point};
  for (size_t k = 0; k < at.ties.size() && k < ties; ++k) {
    const PairingTie& tie = at.ties[k];
    std::vector<TrackedPoint> next;
    const size_t i = static_cast<size_t>(tie.measured);
    for (const TrackedPoint& base : out)
      for (int c : tie.candidates) {
        TrackedPoint t = base;
        for (int& col : t.columns)
          if (col == c) col = base.columns[i];
        t.columns[i] = c;
        if (std::none_of(next.begin(), next.end(),
                         [&](const TrackedPoint& o) { return o.columns == t.columns; }))
          next.push_back(std::move(t));
      }
    out = std::move(next);
  }
  return out;
}

// Whether the shapes decide for result `a` over result `b` where the frequencies cannot: every
// measured mode the two pair otherwise (by shape) has entries at three sensors or more, and a
// MAC with its partner of at least the threshold at `a` and below it, by 0.3 or more, at `b`.
// Following each shape through a veering keeps to its branch, so a fit may end with two modes
// of nearly one frequency paired crosswise, and the frequencies then fit either way: a wide lap
// plate's bending and twisting pair at 519 Hz (8 sensors, 0.3 % noise as stated) gave MAC 0.16
// and 0.05 one way and 0.998 and 0.994 the other, costs 1.93e-05 and 1.97e-05, and the update
// was refused as undecidable.
bool shapes_prefer(const LinearProblem& p, const TrackedPoint& a, const TrackedPoint& b) {
  const LinearEvaluation ea = p.evaluate(a), eb = p.evaluate(b);
  bool differ = false;
  for (size_t i = 0; i < a.columns.size() && i < b.columns.size(); ++i) {
    if (same_partners(p.model.mass, a.modes, {a.columns[i]}, b.modes, {b.columns[i]})) continue;
    differ = true;
    const auto k = static_cast<Eigen::Index>(i);
    if ((p.measured.shapes.col(k).array().abs() > 0.0).count() < 3) return false;
    const std::optional<double> ma = ea.pair_mac(k), mb = eb.pair_mac(k);
    if (!ma || !mb || !(*ma >= p.options.mac_threshold) || !(*mb < p.options.mac_threshold) ||
        !(*ma - *mb >= 0.3))
      return false;
  }
  return differ;
}

// Which of `points` (results whose costs the frequencies cannot tell apart) the shapes prefer
// over every other that pairs some mode otherwise (shapes_prefer()), or none.
std::optional<size_t> shapes_decide(const LinearProblem& p,
                                    const std::vector<const TrackedPoint*>& points) {
  for (size_t w = 0; w < points.size(); ++w) {
    bool all = true, any = false;
    for (size_t k = 0; k < points.size() && all; ++k) {
      if (k == w || same_partners(p.model.mass, points[w]->modes, points[w]->columns,
                                  points[k]->modes, points[k]->columns))
        continue;
      any = true;
      all = shapes_prefer(p, *points[w], *points[k]);
    }
    if (all && any) return w;
  }
  return std::nullopt;
}

// The warning where the shapes decided between results the frequencies could not: the kept
// result `a`, the other `b`, each mode they pair otherwise with its MAC at each.
std::string shapes_decided(const LinearProblem& p, const TrackedPoint& a, double cost_a,
                           const TrackedPoint& b, double cost_b) {
  const LinearEvaluation ea = p.evaluate(a), eb = p.evaluate(b);
  std::vector<std::string> modes;
  for (size_t i = 0; i < a.columns.size() && i < b.columns.size(); ++i) {
    if (same_partners(p.model.mass, a.modes, {a.columns[i]}, b.modes, {b.columns[i]})) continue;
    const auto k = static_cast<Eigen::Index>(i);
    modes.push_back(fmt::format("test mode {} ({:.5g} Hz) with {} rather than {}", p.measured.id(k),
                                p.measured.frequency_hz(k), pair_text(ea, static_cast<int>(i)),
                                pair_text(eb, static_cast<int>(i))));
  }
  return fmt::format(
      "the frequencies cannot tell two pairings apart (costs {:.4g} and {:.4g}, less than 9 "
      "apart in chi-square units), but the shapes can: kept the one that pairs {}",
      cost_a, cost_b, fmt::join(modes, "; "));
}

namespace {

// The candidate pairings at a fit's result (`again`, the pairs made afresh there; `fresh_end`
// its evaluation) not tried before, each recorded in `tried`. A pairing that leaves a followed
// mode unpaired would win on cost by dropping a residual: it is not a candidate; the weak pair
// is said instead, in `weak_pairs`.
std::vector<TrackedPoint> untried_candidates(const LinearProblem& p, const TrackedPoint& again,
                                             const LinearEvaluation& fresh_end,
                                             const TrackedPoint& point,
                                             std::vector<std::vector<int>>& tried,
                                             std::vector<PairWarning>& weak_pairs) {
  const MeasuredModes& measured = p.measured;
  const auto pairs_of = [](const TrackedPoint& t) {
    return std::count_if(t.columns.begin(), t.columns.end(), [](int c) { return c >= 0; });
  };
  std::vector<TrackedPoint> candidates;
  for (TrackedPoint& c : candidate_pairings(again, fresh_end, 1)) {
    if (std::find(tried.begin(), tried.end(), c.columns) != tried.end()) continue;
    tried.push_back(c.columns);
    if (pairs_of(c) < pairs_of(point)) {
      const LinearEvaluation followed = p.evaluate(point);
      for (size_t i = 0; i < c.columns.size(); ++i) {
        if (c.columns[i] >= 0 || point.columns[i] < 0) continue;
        weak_pairs.push_back(
            {static_cast<int>(i),
             fmt::format("test mode {} ({:.5g} Hz) is followed by its shape to {}, below the "
                         "MAC threshold at the result: check its measured shape",
                         measured.id(static_cast<Eigen::Index>(i)),
                         measured.frequency_hz(static_cast<Eigen::Index>(i)),
                         pair_text(followed, static_cast<int>(i)))});
      }
      continue;
    }
    candidates.push_back(std::move(c));
  }
  return candidates;
}

// One pairing fitted at a fit's result: its result, cost, termination and record.
struct Tried {
  TrackedPoint point;
  double cost = 0;
  ceres::TerminationType tt = ceres::CONVERGENCE;
  LinearUpdateSummary record;
};

// The followed pairs at `point` (first) and each candidate, fitted; `rounds` counts the fits.
std::vector<Tried> fit_candidates(const LinearProblem& p, const TrackedPoint& point,
                                  std::vector<TrackedPoint>& candidates,
                                  const std::vector<char>& held, int& rounds) {
  std::vector<Tried> results;
  results.push_back({point, p.evaluate(point).cost(), ceres::CONVERGENCE, {}});
  for (TrackedPoint& c : candidates) {
    Tried t{std::move(c), 0, ceres::CONVERGENCE, {}};
    t.tt = fit(p, t.point, held, &t.record);
    ++rounds;
    t.cost = p.evaluate(t.point).cost();
    results.push_back(std::move(t));
  }
  return results;
}

// The result of lowest cost (`best`), the results that pair some measured mode otherwise than
// it (by shape), compared with it once each (`others`), and the lowest of those (`runner`).
void rank_results(const LinearProblem& p, const std::vector<Tried>& results, size_t& best,
                  std::vector<size_t>& others, std::optional<size_t>& runner) {
  best = 0;
  for (size_t k = 1; k < results.size(); ++k)
    if (results[k].cost < results[best].cost) best = k;
  for (size_t k = 0; k < results.size(); ++k) {
    if (k == best || same_partners(p.model.mass, results[k].point.modes, results[k].point.columns,
                                   results[best].point.modes, results[best].point.columns))
      continue;
    others.push_back(k);
    if (!runner || results[k].cost < results[*runner].cost) runner = k;
  }
}

// The warning where the pairs followed by shape (results[0]) fit decisively better than the
// sensors' own: kept, said.
std::string kept_followed(const std::vector<Tried>& results, const LinearEvaluation& fresh_end) {
  std::vector<std::string> costs;
  for (size_t k = 0; k < results.size(); ++k)
    costs.push_back(fmt::format("{:.4g}{}", results[k].cost, k == 0 ? " as followed" : ""));
  return fmt::format(
      "at the result the sensors alone would pair differently ({}), but those pairs fit "
      "worse (costs {}): kept the pairs followed by shape",
      fresh_end.ambiguity.empty() ? "MAC and frequency" : fresh_end.ambiguity,
      fmt::join(costs, ", "));
}

// The winning candidate `w` as the fit's result so far: its status, and its history after
// the fit's in `record`.
void take_candidate(const Tried& w, Settled& out) {
  out.status = status_of(w.tt);
  out.record.history.insert(out.record.history.end(), w.record.history.begin(),
                            w.record.history.end());
  out.record.theta_history.insert(out.record.theta_history.end(), w.record.theta_history.begin(),
                                  w.record.theta_history.end());
  out.record.iterations += w.record.iterations;
}

}  // namespace

// Least squares with pairs followed by shape from `point`. At its result the pairs are made
// afresh by the rules; where they differ, or where the sensors cannot tell two candidates
// apart (a twisting mode veering with a bending mode), each candidate pairing is fitted too
// and the data decide: the lowest cost wins when it is lower by at least 9 (3 sigma) in
// chi-square units, 2 (c_other - c_best) / sigma_f^2; otherwise the shapes, where they can
// (shapes_decide); otherwise the pairs cannot be decided.
Settled settle(const LinearProblem& p, TrackedPoint point, const std::vector<char>& held) {
  Settled out;
  std::vector<std::vector<int>> tried{point.columns};
  out.status = status_of(fit(p, point, held, &out.record));
  out.rounds = 1;
  // The fit renumbers the modes where they cross: the candidates below are compared with the
  // followed pairs at the fit's result, not at its start (at the start's numbering the example
  // beam's followed pairs came back as a candidate, fitted again as "the sensors' pairs").
  tried.push_back(point.columns);
  for (int check = 0; check < 4; ++check) {
    TrackedPoint again = p.fresh(point.x, out.fresh_end);
    const LinearEvaluation& fresh_end = out.fresh_end;
    if (again.columns == point.columns && fresh_end.ambiguity.empty()) break;
    std::vector<TrackedPoint> candidates =
        untried_candidates(p, again, fresh_end, point, tried, out.weak_pairs);
    if (candidates.empty() && fresh_end.ambiguity.empty()) break;
    // The followed pairs and each candidate, fitted; the lowest cost wins unless a result that
    // pairs some measured mode with another model mode (by shape: a mode crossing between two
    // results renumbers the modes, and the example beam's sixth bending mode, model mode 9
    // with spring.rz at 1e5 and 10 with rz at 0.1, was taken for two pairings, "cannot be
    // decided" in 3 of 12 seeds of 0.1 % noise) fits within 9 chi-square units of it.
    std::vector<Tried> results = fit_candidates(p, point, candidates, held, out.rounds);
    size_t best = 0;
    std::vector<size_t> others;
    std::optional<size_t> runner;
    rank_results(p, results, best, others, runner);
    const double sf2 = p.options.frequency_std * p.options.frequency_std;
    if (runner && !(2 * (results[*runner].cost - results[best].cost) / sf2 >= 9)) {
      std::vector<size_t> close{best};
      for (const size_t k : others)
        if (2 * (results[k].cost - results[best].cost) / sf2 < 9) close.push_back(k);
      std::vector<const TrackedPoint*> points;
      for (const size_t k : close) points.push_back(&results[k].point);
      const std::optional<size_t> w = shapes_decide(p, points);
      if (!w) {
        out.ambiguity = fmt::format(
            "{}{}", fresh_end.ambiguity.empty() ? "" : fresh_end.ambiguity + "; fitted each way, ",
            differing_pairs(p, results[best].point, results[best].cost, results[*runner].point,
                            results[*runner].cost,
                            "less than 9 apart in chi-square units of the stated frequency noise"));
        for (const size_t k : close)
          if (k != best) out.rivals.push_back(results[k].point);
        if (best > 0) point = std::move(results[best].point);
        break;
      }
      const size_t other = close[*w] == best ? *runner : best;
      out.record.warnings.push_back(shapes_decided(p, results[close[*w]].point,
                                                   results[close[*w]].cost, results[other].point,
                                                   results[other].cost));
      best = close[*w];
      runner.reset();
    }
    if (best == 0) {
      if (runner) out.record.warnings.push_back(kept_followed(results, fresh_end));
      break;
    }
    take_candidate(results[best], out);
    point = std::move(results[best].point);
    tried.push_back(point.columns);
  }
  out.point = std::move(point);
  out.cost = p.evaluate(out.point).cost();
  return out;
}

// A fitted set that only pairs the sensors cannot confirm see (their partners changed along
// the fit) is not identified: the fit may have moved it until another mode sat at a measured
// frequency. With one sensor, spring.rz went from 100 to 2129 N m/rad that way (a twisting
// mode tuned onto a measured frequency), "converged" with a 7 % uncertainty, and the truth,
// 100, fitted as well. Returns why the update stops, or ""; where every fitted set is also
// seen by confirmed pairs the result stands and *warning says which pairs changed.
std::string unconfirmed_sets(const LinearProblem& p, const Eigen::SparseMatrix<double>& mass,
                             const TrackedPoint& start, const TrackedPoint& end,
                             const MeasuredModes& measured, const LinearUpdateOptions& options,
                             const std::vector<char>& held, const std::vector<std::string>& names,
                             std::string* warning) {
  const LinearEvaluation at = p.evaluate(end);
  const auto changes = unconfirmed_changes(mass, start, end, at, measured, options.mac_threshold);
  if (changes.empty()) return "";
  std::vector<std::string> lines, blind;
  std::vector<char> changed(static_cast<size_t>(at.residuals.size()), 0);
  for (const auto& [i, line] : changes) {
    lines.push_back(line);
    changed[static_cast<size_t>(i)] = 1;
  }
  // Seen by the changed pairs and by no other. A set no pair sees (kflat: every sensitivity
  // below flat_sensitivity) is flat, held by the flat rule whatever the pairs: naming it here
  // refused a fit that had found ka and kb exactly.
  for (int k = 0; k < p.size(); ++k) {
    if (held[static_cast<size_t>(k)]) continue;
    double seen = 0, seen_changed = 0;
    for (const ModePair& pr : at.pairing.pairs) {
      double& by = changed[static_cast<size_t>(pr.measured)] ? seen_changed : seen;
      by = std::max(by, std::abs(at.jacobian(pr.measured, k)));
    }
    if (seen < options.flat_sensitivity && seen_changed >= options.flat_sensitivity)
      blind.push_back(names[static_cast<size_t>(k)]);
  }
  const std::string what = fmt::format(
      "the partners of {} changed their shape along the fit (another mode took their place, "
      "through a veering or a new pairing) and the sensors cannot confirm the new ones",
      fmt::join(lines, "; "));
  if (blind.empty()) {
    *warning = what + "; every fitted set is also seen by confirmed pairs, so the result stands";
    return "";
  }
  return fmt::format(
      "{}; {} only these pairs see, so the fit may have moved it until another mode sat at a "
      "measured frequency: add sensors that see the modes apart, or hold it (--hold NAME)",
      what, fmt::join(blind, " and "));
}

}  // namespace jointlab::correlate::detail
