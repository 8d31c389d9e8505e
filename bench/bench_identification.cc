// Iwan identification on the example campaign (data/examples/riveted-campaign): evaluations of
// its Iwan objective per second, the objective's set-up, the speed-up over evaluating from
// scratch (the code before the set-up was shared) in the same run, and the whole update_iwan()
// with the campaign's optimiser and 1 500 evaluations on one and two threads.
//
// Run: build/bin/jointlab_bench_identification [--benchmark_filter=...]
//
// Cases (built once, outside the timings, into a temporary folder):
//   /0 example: the campaign's steps up to the Iwan update as `jointlab run` takes them
//      (campaign/steps/): the model built from examples/riveted_beam/description.toml (24
//      rivets, 48 Iwan coordinates), the nine hits processed and summarised, the linear update
//      of iwan.rivet, the targets of mode 1;
//   /1 rivets96: the same description with 96 rivets (192 Iwan coordinates, its joint values,
//      no linear update) against the same measured backbones.
// Parameters: 1 500 sets drawn as the global-local optimiser's global phase draws them (log
// uniform in the campaign's bounds: F_S within a factor 30 of the start, gamma 0.3..3,
// chi -0.95..0, beta 0.01..100).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "jointlab/bench/bench_scratch.h"
#include "jointlab/campaign/campaign.h"
#include "jointlab/campaign/campaign_run.h"
#include "jointlab/campaign/iwan_targets.h"
#include "jointlab/campaign/steps/hits.h"
#include "jointlab/campaign/steps/iwan_step.h"
#include "jointlab/campaign/steps/linear_step.h"
#include "jointlab/campaign/steps/measured_side.h"
#include "jointlab/campaign/steps/model_side.h"
#include "jointlab/campaign/steps/validate.h"
#include "jointlab/core/parallel.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/fe/riveted_beam.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/linear_modes.h"

namespace {

namespace fs = std::filesystem;
using namespace jointlab;

constexpr int kEvaluations = 1500;
constexpr int kFromScratch = 20;

fs::path work_dir() {
  static const fs::path dir = bench::scratch_dir("identification");
  return dir;
}

// One identification problem: everything update_iwan() needs.
struct Case {
  model::Model base;
  std::vector<correlate::Sensor> sensors;
  std::string set;
  std::vector<correlate::IwanTarget> targets;
  correlate::IwanUpdateOptions options;
  std::vector<model::IwanParameters> samples;
  double prepare_s = 0;
};

// Parameter sets drawn as the global phase draws them, in the campaign's bounds.
void draw_samples(Case& c, const model::IwanParameters& start, double Ks) {
  c.options.bounds.Fs_min = start.Fs / 30;
  c.options.bounds.Fs_max = start.Fs * 30;
  c.options.max_evaluations = kEvaluations;
  const correlate::IwanBounds& b = c.options.bounds;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto log_uniform = [&](double lo, double hi) {
    return std::exp(std::log(lo) + u(rng) * (std::log(hi) - std::log(lo)));
  };
  for (int i = 0; i < kEvaluations; ++i) {
    const double fs = log_uniform(b.Fs_min, b.Fs_max);
    const double gamma = log_uniform(b.gamma_min, b.gamma_max);
    const double chi = b.chi_min + u(rng) * (b.chi_max - b.chi_min);
    const double beta = log_uniform(b.beta_min, b.beta_max);
    c.samples.push_back({fs, gamma * Ks, chi, beta});
  }
}

correlate::IwanObjective make_objective(const Case& c) {
  return correlate::IwanObjective(c.base, c.set, c.sensors, c.targets, c.options);
}

// The objective with other options (the floor fitted).
correlate::IwanObjective make_objective(const Case& c, const correlate::IwanUpdateOptions& o) {
  return correlate::IwanObjective(c.base, c.set, c.sensors, c.targets, o);
}

// The cases: 0 the example campaign's Iwan update (everything before update_iwan(), as
// `jointlab run` takes it); 1 the same measured backbones against the example description
// with 96 rivets (built here, its description's joint values, no linear update).
const Case& problem(int which) {
  using Clock = std::chrono::steady_clock;
  static const std::vector<Case> cases = [] {
    std::vector<Case> out(2);
    const auto t0 = Clock::now();
    const fs::path file =
        fs::path(JOINTLAB_SOURCE_DIR) / "data/examples/riveted-campaign/campaign.toml";
    const campaign::Campaign c = campaign::read_campaign(file);
    campaign::RunOptions ro;
    ro.out = work_dir();
    campaign::RunSummary rs;
    const fs::path model_file = campaign::prepare_model(c, work_dir(), ro, rs);
    const campaign::CampaignModelData data = campaign::validate_model(c, model_file);
    const std::vector<campaign::HitData> hits = campaign::process_hits(c, work_dir(), ro, rs);
    const campaign::MeasuredSide measured =
        campaign::summarise_measured(c, hits, work_dir() / "scatter", {});
    const campaign::LinearStep linear = campaign::linear_update_step(c, data, measured.modes, {});
    const std::vector<campaign::ModeBackbones> backbones =
        campaign::campaign_backbones(c, measured);
    Case& e = out[0];
    e.base = linear.ran ? linear.updated : data.model;
    e.sensors = data.sensors;
    e.set = campaign::iwan_set(c, e.base);
    campaign::IwanTargetOptions to;
    campaign::iwan_update_options(c, e.options, to);
    e.targets = campaign::iwan_targets(e.base, e.sensors, backbones, to).fitted;
    {
      const correlate::IwanObjective objective = make_objective(e);
      draw_samples(e, objective.initial(), objective.reference_stiffness());
    }
    e.prepare_s = std::chrono::duration<double>(Clock::now() - t0).count();

    const auto t1 = Clock::now();
    model::fe::RivetedBeamDescription d =
        model::fe::read_riveted_beam_description(c.model.description);
    d.rivets = model::fe::staggered_rivets(d.length, d.overlap, 96, 0.00635);
    model::fe::write_model_directory(work_dir() / "model96", model::fe::build_reduced_model(d, {}));
    const campaign::CampaignModelData data96 =
        campaign::validate_model(c, work_dir() / "model96" / "model.toml");
    Case& r = out[1];
    r.base = data96.model;
    r.sensors = data96.sensors;
    r.set = e.set;
    r.options = e.options;
    r.options.bounds = {};
    r.targets = campaign::iwan_targets(r.base, r.sensors, backbones, to).fitted;
    {
      const correlate::IwanObjective objective = make_objective(r);
      draw_samples(r, objective.initial(), objective.reference_stiffness());
    }
    r.prepare_s = std::chrono::duration<double>(Clock::now() - t1).count();
    return out;
  }();
  return cases[static_cast<size_t>(which)];
}

double evaluate_all(const Case& c, const correlate::IwanObjective& objective, int count,
                    bool from_scratch) {
  std::vector<double> r(static_cast<size_t>(objective.residual_count()));
  double sum = 0;
  for (int i = 0; i < count; ++i) {
    const model::IwanParameters& p = c.samples[static_cast<size_t>(i)];
    const bool ok = from_scratch ? objective.residuals_from_scratch(p, r.data())
                                 : objective.residuals(p, r.data());
    if (ok)
      for (double v : r) sum += v * v;
  }
  return sum;
}

const char* kNames[] = {"example", "rivets96"};

// The objective's set-up: every linear mode of the model once, its condensation.
void BM_ObjectiveSetUp(benchmark::State& state) {
  const Case& c = problem(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(make_objective(c).residual_count());
  state.counters["dofs"] = static_cast<double>(c.base.size());
  state.counters["case_prepare_s"] = c.prepare_s;
  state.SetLabel(kNames[state.range(0)]);
}
BENCHMARK(BM_ObjectiveSetUp)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);

// 1 500 evaluations on one thread, objective set-up excluded.
void BM_Evaluations(benchmark::State& state) {
  const Case& c = problem(static_cast<int>(state.range(0)));
  const correlate::IwanObjective objective = make_objective(c);
  for (auto _ : state) benchmark::DoNotOptimize(evaluate_all(c, objective, kEvaluations, false));
  state.counters["evaluations_per_s"] =
      benchmark::Counter(kEvaluations, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["measured_points"] = objective.residual_count() / 2;
  state.SetLabel(kNames[state.range(0)]);
}
BENCHMARK(BM_Evaluations)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1);

// The example's 1 500 evaluations on both cores (each set on its own, as the optimiser's
// rounds and Jacobians run them), set-up excluded; `identical_to_one_thread` is 1 when the
// costs of the first 100 sets equal, bit for bit, those evaluated again on one thread.
void BM_EvaluationsTwoThreads(benchmark::State& state) {
  const Case& c = problem(0);
  const correlate::IwanObjective objective = make_objective(c);
  const auto n = static_cast<size_t>(objective.residual_count());
  std::vector<double> costs(c.samples.size());
  for (auto _ : state) {
    parallel_for(
        c.samples.size(), 2, [n] { return std::vector<double>(n); },
        [&](size_t i, std::vector<double>& r) {
          double sum = -1;  // -1: not evaluable there
          if (objective.residuals(c.samples[i], r.data())) {
            sum = 0;
            for (double v : r) sum += v * v;
          }
          costs[i] = sum;
        });
  }
  std::vector<double> r(n);
  bool identical = true;
  for (size_t i = 0; i < 100; ++i) {
    double sum = -1;
    if (objective.residuals(c.samples[i], r.data())) {
      sum = 0;
      for (double v : r) sum += v * v;
    }
    identical = identical && sum == costs[i];
  }
  state.counters["evaluations_per_s"] =
      benchmark::Counter(kEvaluations, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["identical_to_one_thread"] = identical;
  state.SetLabel(kNames[0]);
}
BENCHMARK(BM_EvaluationsTwoThreads)->Unit(benchmark::kMillisecond)->Iterations(1);

// Where an evaluation from scratch spends its time, on the first parameter sets: the model
// copy with the set at p, every linear mode (dense), the condensation with every mode (what
// the evaluation from scratch builds) and with the lowest elastic mode only (Lanczos), the
// whole evaluation from scratch.
void BM_FromScratchParts(benchmark::State& state) {
  using Clock = std::chrono::steady_clock;
  const Case& c = problem(static_cast<int>(state.range(0)));
  const int count = state.range(0) == 0 ? kFromScratch : kFromScratch / 4;
  const correlate::IwanObjective objective = make_objective(c);
  double apply = 0, modes = 0, condensation = 0, condensation_one = 0, total = 0;
  for (auto _ : state) {
    for (int i = 0; i < count; ++i) {
      const model::IwanParameters& p = c.samples[static_cast<size_t>(i)];
      const auto t0 = Clock::now();
      const model::Model m = objective.apply(p);
      const auto t1 = Clock::now();
      benchmark::DoNotOptimize(model::linear_modes(m).omega2.data());
      const auto t2 = Clock::now();
      benchmark::DoNotOptimize(model::JointCondensation(m).size());
      const auto t3 = Clock::now();
      model::ModesOptions one;
      one.elastic_count = 1;
      benchmark::DoNotOptimize(model::JointCondensation(m, one).size());
      const auto t4 = Clock::now();
      std::vector<double> r(static_cast<size_t>(objective.residual_count()));
      benchmark::DoNotOptimize(objective.residuals_from_scratch(p, r.data()));
      const auto t5 = Clock::now();
      apply += std::chrono::duration<double>(t1 - t0).count();
      modes += std::chrono::duration<double>(t2 - t1).count();
      condensation += std::chrono::duration<double>(t3 - t2).count();
      condensation_one += std::chrono::duration<double>(t4 - t3).count();
      total += std::chrono::duration<double>(t5 - t4).count();
    }
  }
  const double n = static_cast<double>(state.iterations()) * count / 1e3;
  state.counters["apply_ms"] = apply / n;
  state.counters["every_mode_ms"] = modes / n;
  state.counters["condensation_ms"] = condensation / n;
  state.counters["condensation_one_mode_ms"] = condensation_one / n;
  state.counters["from_scratch_ms"] = total / n;
  state.SetLabel(kNames[state.range(0)]);
}
BENCHMARK(BM_FromScratchParts)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1);

// Per evaluation, the same parameter sets in one run: the fast evaluation against the slow one
// (IwanObjective::residuals_from_scratch: the code before the set-up was shared and Newton
// placed the amplitudes), the speed-up, the set-up's share of 1 500 evaluations, and the
// relative difference of the cost between the two over 80 sets: largest, median, and how many
// exceed 1e-9 (where the cost is huge, deep in macroslip, the damping's ill-conditioned
// dE/dq magnifies the two eigen-solves' rounding).
void BM_Speedup(benchmark::State& state) {
  using Clock = std::chrono::steady_clock;
  const Case& c = problem(static_cast<int>(state.range(0)));
  const int count = state.range(0) == 0 ? kFromScratch : kFromScratch / 4;
  double setup = 0, fast = 0, scratch = 0;
  std::vector<double> differences;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    const correlate::IwanObjective objective = make_objective(c);
    const auto t1 = Clock::now();
    benchmark::DoNotOptimize(evaluate_all(c, objective, count, false));
    const auto t2 = Clock::now();
    benchmark::DoNotOptimize(evaluate_all(c, objective, count, true));
    const auto t3 = Clock::now();
    setup += std::chrono::duration<double>(t1 - t0).count();
    fast += std::chrono::duration<double>(t2 - t1).count();
    scratch += std::chrono::duration<double>(t3 - t2).count();
    std::vector<double> a(static_cast<size_t>(objective.residual_count())), b(a.size());
    for (const model::IwanParameters& p : c.samples) {
      if (!objective.residuals(p, a.data()) || !objective.residuals_from_scratch(p, b.data()))
        continue;
      double ca = 0, cb = 0;
      for (size_t k = 0; k < a.size(); ++k) ca += a[k] * a[k], cb += b[k] * b[k];
      differences.push_back(std::abs(ca - cb) / cb);
      if (&p - c.samples.data() >= 4 * count) break;
    }
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["setup_ms"] = 1e3 * setup / n;
  state.counters["evaluation_ms"] = 1e3 * fast / (n * count);
  state.counters["from_scratch_ms"] = 1e3 * scratch / (n * count);
  state.counters["speedup"] = scratch / fast;
  state.counters["setup_share_1500"] = setup / (setup + fast / count * kEvaluations);
  std::sort(differences.begin(), differences.end());
  if (!differences.empty()) {
    state.counters["cost_rel_difference_max"] = differences.back();
    state.counters["cost_rel_difference_median"] = differences[differences.size() / 2];
    state.counters["cost_over_1e-9"] = static_cast<double>(
        differences.end() - std::upper_bound(differences.begin(), differences.end(), 1e-9));
    state.counters["cost_compared"] = static_cast<double>(differences.size());
  }
  state.SetLabel(kNames[state.range(0)]);
}
BENCHMARK(BM_Speedup)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1);

// The example campaign's update_iwan() (its optimiser, beta held as `run` holds it first) with
// a budget of 1 500 evaluations, objective set-up included, on 1 and 2 threads.
void BM_Identification(benchmark::State& state) {
  const Case& c = problem(0);
  correlate::IwanUpdateOptions o = c.options;
  o.threads = static_cast<int>(state.range(0));
  correlate::IwanUpdateSummary s;
  for (auto _ : state) {
    const correlate::IwanObjective objective = make_objective(c);
    o.fixed_beta = objective.initial().beta;
    correlate::update_iwan(objective, o, &s);
  }
  state.counters["evaluations"] = s.evaluations;
  state.counters["final_cost"] = s.final_cost;
  state.counters["Fs"] = s.best.Fs;
  state.counters["Kt"] = s.best.Kt;
  state.counters["chi"] = s.best.chi;
}
BENCHMARK(BM_Identification)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

// The same with the structure's own damping identified too (--linear-damping fit, issue 28): the
// floor is profiled out of every evaluation (no extra QSMA evaluation) and a constant-backbone
// candidate is refined as one more local start; the budget is the same 1 500 evaluations.
void BM_IdentificationWithFloor(benchmark::State& state) {
  const Case& c = problem(0);
  correlate::IwanUpdateOptions o = c.options;
  o.threads = 1;
  o.fit_linear_damping = true;
  correlate::IwanUpdateSummary s;
  for (auto _ : state) {
    const correlate::IwanObjective objective = make_objective(c, o);
    o.fixed_beta = objective.initial().beta;
    correlate::update_iwan(objective, o, &s);
  }
  state.counters["evaluations"] = s.evaluations;
  state.counters["final_cost"] = s.final_cost;
  state.counters["modal_ratio"] = s.modal_ratio;
  state.counters["chi"] = s.best.chi;
}
BENCHMARK(BM_IdentificationWithFloor)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

int main(int argc, char** argv) { return jointlab::bench::run_benchmarks(argc, argv, work_dir()); }
