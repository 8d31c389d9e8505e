// The Iwan update's searches (internal): evaluations with their bookkeeping (history, best,
// budget, progress), the paper's Monte Carlo, the global-local search and the constant-backbone
// candidate of a fit with Z free.
#pragma once

#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "jointlab/core/parallel.h"
#include "jointlab/correlate/iwan_coordinates_detail.h"
#include "jointlab/correlate/iwan_update.h"

namespace jointlab::correlate::iwan_detail {

/// Evaluations with bookkeeping: history, best, budget, progress.
struct Tracker {
  const IwanObjective& objective;    ///< what is evaluated
  const IwanUpdateOptions& options;  ///< the budget, threads and progress callback
  IwanUpdateSummary& summary;        ///< receives the history
  int start_evaluations;             ///< the objective's evaluations before this update
  Vec4 best_v = Vec4::Zero();        ///< the best point so far
  double best = INFINITY;            ///< its cost

  /// Evaluations of this update so far.
  int used() const { return objective.evaluations() - start_evaluations; }
  /// True when the budget is spent.
  bool spent() const { return used() >= options.max_evaluations; }
  /// Records cost c at v as the latest evaluation.
  void record(const Vec4& v, double c) { record(v, c, used()); }
  /// Records cost c at v as evaluation `evaluation`: history, best, progress.
  void record(const Vec4& v, double c, int evaluation) {
    if (c < best) {
      best = c;
      best_v = v;
    }
    summary.history.push_back({evaluation, c, best, options.fixed_beta.has_value()});
    if (options.progress) options.progress(evaluation, best);
  }
  /// Costs of vs (evaluated on options.threads threads, each independent of the others), then
  /// recorded in their order: the outcome does not depend on the number of threads.
  std::vector<double> eval(const std::vector<Vec4>& vs) {
    std::vector<double> c(vs.size());
    const int base = used();
    parallel_for(
        vs.size(), static_cast<unsigned>(options.threads), [] { return 0; },
        [&](size_t i, int) {
          // A set the model cannot evaluate costs +inf: never a best, never a number written.
          c[i] = objective.try_cost(to_params(vs[i], objective.reference_stiffness()))
                     .value_or(INFINITY);
        });
    for (size_t i = 0; i < vs.size(); ++i) record(vs[i], c[i], base + static_cast<int>(i) + 1);
    return c;
  }
};

/// The paper's Monte Carlo (log_scale: F_S, gamma and beta sampled logarithmically) until a round
/// brings no gain (kConverged) or the budget is spent (kBudget).
void monte_carlo(Tracker& tr, bool log_scale, std::mt19937& rng);

/// Logarithmic samples with half the budget, then local solves from the best (and `extra`, may
/// be null), then the polish of the best point; sets the summary's status and rounds.
void global_local(Tracker& tr, std::mt19937& rng, const std::pair<double, Vec4>* extra);

/// One local solve (Levenberg-Marquardt in the search box) from v, stopped when the evaluations
/// used reach `limit` or after `iterations` iterations; true when it met its tolerance.
bool local_solve(Tracker& tr, const Vec4& v, int limit, int iterations);

/// The constant-backbone candidate of a fit with Z free, evaluated: (cost, v).
std::pair<double, Vec4> constant_candidate(Tracker& tr);

}  // namespace jointlab::correlate::iwan_detail
