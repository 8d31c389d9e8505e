// The Iwan update's searches: the paper's Monte Carlo, the global-local search (logarithmic
// samples, then Ceres from the best) and the constant-backbone candidate.
#include "jointlab/correlate/iwan_search_detail.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include <ceres/ceres.h>

#include "jointlab/core/parallel.h"
#include "jointlab/correlate/iwan_coordinates_detail.h"
#include "jointlab/correlate/iwan_update.h"

namespace jointlab::correlate::iwan_detail {
namespace {

constexpr int kBatch = 50;              // samples evaluated between two progress reports
constexpr int kLocalIterations = 50;    // iterations of a local solve within its share
constexpr int kPolishIterations = 200;  // iterations of the polish of the best point

// A uniform sample of box b (F_S, gamma and beta on a log scale where log_scale).
Vec4 sample(const Box& b, bool log_scale, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Vec4 v;
  for (int i = 0; i < 4; ++i) {
    const double t = u(rng);
    const bool lg = log_scale && i != 2 && b.lo(i) > 0;
    v(i) = lg ? std::exp(std::log(b.lo(i)) + t * (std::log(b.hi(i)) - std::log(b.lo(i))))
              : b.lo(i) + t * (b.hi(i) - b.lo(i));
  }
  return v;
}

}  // namespace

void monte_carlo(Tracker& tr, bool log_scale, std::mt19937& rng) {
  const Box full = initial_box(tr.options);
  Box box = full;
  double previous = INFINITY;
  while (!tr.spent()) {
    const int n = std::min(tr.options.samples, tr.options.max_evaluations - tr.used());
    for (int done = 0; done < n;) {
      std::vector<Vec4> vs;
      for (; done < n && static_cast<int>(vs.size()) < kBatch; ++done)
        vs.push_back(sample(box, log_scale, rng));
      tr.eval(vs);
    }
    ++tr.summary.rounds;
    if (!(tr.best < previous)) {
      tr.summary.status = IwanUpdateStatus::kConverged;
      return;
    }
    previous = tr.best;
    for (int i = 0; i < 4; ++i) {
      const double d = tr.options.contraction * std::max(std::abs(tr.best_v(i)), 1e-3);
      box.lo(i) = std::max(full.lo(i), tr.best_v(i) - d);
      box.hi(i) = std::min(full.hi(i), tr.best_v(i) + d);
    }
  }
  tr.summary.status = IwanUpdateStatus::kBudget;
}

namespace {

// Residuals with central-difference Jacobians (QSMA is not templated on the scalar). Not
// ceres::NumericDiffCostFunction: its step is |x| times a relative size, which vanishes for
// ln gamma and ln beta near 0, where the 1e-10 accuracy of qsma_at would swamp the difference;
// a fixed step of 1e-4 in x keeps that error near 1e-6 of the derivative.
class IwanCost : public ceres::CostFunction {
 public:
  IwanCost(Tracker& tr, std::array<bool, 4> held) : tr_(tr), held_(held) {
    set_num_residuals(tr.objective.residual_count());
    mutable_parameter_block_sizes()->push_back(4);
  }
  bool Evaluate(double const* const* x, double* r, double** jac) const override {
    const double Ks = tr_.objective.reference_stiffness();
    const Vec4 v = with_held(to_v(x[0]));
    if (!tr_.objective.residuals(to_params(v, Ks), r)) {
      tr_.record(v, INFINITY);
      return false;
    }
    double c = 0;
    for (int i = 0; i < num_residuals(); ++i) c += r[i] * r[i];
    tr_.record(v, c);
    if (!jac || !jac[0]) return true;
    const int m = num_residuals();
    // The 2 x 4 shifted residual vectors, each independent: on the option's threads.
    const double h = 1e-4;
    std::vector<std::vector<double>> shifted(8, std::vector<double>(m));
    std::array<char, 8> ok{};
    parallel_for(
        8, static_cast<unsigned>(tr_.options.threads), [] { return 0; },
        [&](size_t j, int) {
          const int k = static_cast<int>(j / 2);
          if (held_[k]) return;
          double xs[4];
          std::copy(x[0], x[0] + 4, xs);
          xs[k] += j % 2 == 0 ? h : -h;
          ok[j] = tr_.objective.residuals(to_params(with_held(to_v(xs)), Ks), shifted[j].data());
        });
    for (int k = 0; k < 4; ++k) {
      if (held_[k]) {
        for (int i = 0; i < m; ++i) jac[0][i * 4 + k] = 0;
        continue;
      }
      if (!ok[2 * k] || !ok[2 * k + 1]) return false;
      const std::vector<double>&rp = shifted[2 * k], &rm = shifted[2 * k + 1];
      for (int i = 0; i < m; ++i) jac[0][i * 4 + k] = (rp[i] - rm[i]) / (2 * h);
    }
    return true;
  }

 private:
  // v with the held parameters at their values: their coordinates in x are placeholders (ln 0
  // of beta held at 0 is no finite coordinate).
  Vec4 with_held(Vec4 v) const {
    const IwanUpdateOptions& o = tr_.options;
    if (held_[1]) v(1) = o.fixed_gamma;
    if (held_[3]) v(3) = *o.fixed_beta;
    return v;
  }

  Tracker& tr_;
  std::array<bool, 4> held_;
};

class BudgetCallback : public ceres::IterationCallback {
 public:
  BudgetCallback(const Tracker& tr, int limit) : tr_(tr), limit_(limit) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return tr_.used() >= limit_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  const Tracker& tr_;
  int limit_;
};

}  // namespace

// One local solve (Ceres, Levenberg-Marquardt on x = (ln F_S, ln gamma, chi, ln beta) in the
// search box) from v, stopped when the evaluations used reach `limit` or after `iterations`
// iterations; true when it met its tolerance (ceres::CONVERGENCE).
bool local_solve(Tracker& tr, const Vec4& v, int limit, int iterations) {
  const Box full = initial_box(tr.options);
  const std::array<bool, 4> held = held_parameters(tr.options);
  std::vector<int> constant;
  for (int k = 0; k < 4; ++k)
    if (held[k]) constant.push_back(k);
  Vec4 x = to_x(v);
  for (int k = 0; k < 4; ++k)
    if (held[k]) x(k) = 0;  // a placeholder (IwanCost uses the held values)
  ceres::Problem problem;
  problem.AddResidualBlock(new IwanCost(tr, held), nullptr, x.data());
  const Vec4 lo = to_x(full.lo), hi = to_x(full.hi);
  if (!constant.empty()) problem.SetManifold(x.data(), new ceres::SubsetManifold(4, constant));
  for (int k = 0; k < 4; ++k) {
    if (held[k]) continue;
    problem.SetParameterLowerBound(x.data(), k, lo(k));
    problem.SetParameterUpperBound(x.data(), k, hi(k));
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = iterations;
  so.logging_type = ceres::SILENT;  // outcomes reach the user through the summary
  so.function_tolerance = 1e-10;
  so.parameter_tolerance = 1e-8;
  BudgetCallback cb(tr, limit);
  so.callbacks.push_back(&cb);
  ceres::Solver::Summary cs;
  ceres::Solve(so, &problem, &cs);
  return cs.termination_type == ceres::CONVERGENCE;
}

// `extra` (may be null): a candidate already evaluated with its cost, refined by the local
// solve whatever its rank among the samples (the constant-backbone candidate).
// The budget bounds the exploration: half of it samples the box, the rest is shared among the
// local solves from the best samples, each stopped at its share. The local solve that found the
// best point is then carried on from there to its tolerance (the polish), past the budget if
// need be, by at most another budget: sigmas are taken at a minimum, not where a share ran out.
// (Before, 7 of 12 one-curve fits of the cantilever at the default 1500 stopped mid-descent,
// cost 1.31 where 6000 evaluations reached 0.73, chi 4.6 sigma off, and were reported.)
void global_local(Tracker& tr, std::mt19937& rng, const std::pair<double, Vec4>* extra) {
  const IwanUpdateOptions& o = tr.options;
  const Box full = initial_box(o);
  std::vector<std::pair<double, Vec4>> samples;
  const int n_global =
      std::min(std::max(o.samples, o.max_evaluations / 2), o.max_evaluations - tr.used());
  for (int done = 0; done < n_global;) {
    std::vector<Vec4> vs;
    for (; done < n_global && static_cast<int>(vs.size()) < kBatch; ++done)
      vs.push_back(sample(full, true, rng));
    const std::vector<double> c = tr.eval(vs);
    for (size_t i = 0; i < vs.size(); ++i) samples.emplace_back(c[i], vs[i]);
  }
  std::sort(samples.begin(), samples.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  int starts = o.local_starts;
  if (extra && std::isfinite(extra->first)) {
    samples.insert(samples.begin() + std::min<size_t>(samples.size(), o.local_starts), *extra);
    ++starts;
  }
  // Whether the local solve that last lowered the best met its tolerance (none yet: a sample).
  bool best_converged = false;
  for (int s = 0; s < starts && s < static_cast<int>(samples.size()); ++s) {
    if (!std::isfinite(samples[s].first)) continue;
    const int remaining = o.max_evaluations - tr.used();
    if (remaining <= 9) break;
    const double before = tr.best;
    const bool converged =
        local_solve(tr, samples[s].second, tr.used() + remaining / (starts - s), kLocalIterations);
    ++tr.summary.rounds;
    if (tr.best < before) best_converged = converged;
  }
  tr.summary.polish_evaluations = 0;
  if (!best_converged && std::isfinite(tr.best)) {
    const int used = tr.used();
    best_converged = local_solve(tr, tr.best_v, used + o.max_evaluations, kPolishIterations);
    tr.summary.polish_evaluations = tr.used() - used;
  }
  tr.summary.status = best_converged ? IwanUpdateStatus::kConverged : IwanUpdateStatus::kBudget;
}

// The constant-backbone candidate of a fit with Z free: a joint that barely slips over the data
// (F_S at its upper bound, chi at its largest: the microslip damping (a / phi_max)^(chi + 1) is
// then smallest) with K_T placing the frequency (golden-section search of the cost on ln gamma),
// and Z at its best. A linear damping with such a joint contains the constant model, so the fit
// can never end worse than the best constant: this candidate is recorded and refined.
std::pair<double, Vec4> constant_candidate(Tracker& tr) {
  const IwanUpdateOptions& o = tr.options;
  const Box box = initial_box(o);
  const model::IwanParameters start = tr.objective.initial();
  Vec4 v(box.hi(0), box.lo(1), box.hi(2), std::clamp(start.beta, box.lo(3), box.hi(3)));
  if (o.fixed_beta) v(3) = *o.fixed_beta;
  auto at = [&](double ln_gamma) {
    Vec4 w = v;
    w(1) = std::exp(ln_gamma);
    return tr.eval({w}).front();
  };
  if (box.hi(1) > box.lo(1)) {
    const double phi = (std::sqrt(5.0) - 1) / 2;
    double a = std::log(box.lo(1)), b = std::log(box.hi(1));
    double c = b - phi * (b - a), d = a + phi * (b - a);
    double fc = at(c), fd = at(d);
    for (int i = 0; i < 30 && !tr.spent(); ++i) {
      if (fc < fd) {
        b = d, d = c, fd = fc;
        c = b - phi * (b - a);
        fc = at(c);
      } else {
        a = c, c = d, fc = fd;
        d = a + phi * (b - a);
        fd = at(d);
      }
    }
    v(1) = std::exp(fc < fd ? c : d);
  }
  return {tr.eval({v}).front(), v};
}

}  // namespace jointlab::correlate::iwan_detail
