// Iwan updating: the paper's Monte Carlo, its log-sampled variant and global-then-local
// (correlate/iwan_update.h) from 20 random starts on one synthetic truth, same budget of QSMA
// evaluations. Prints median and worst final objective, evaluations and time per optimiser.
// Run: build/bin/jointlab_bench_iwan_update [budget]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/two_chain.h"

using namespace jointlab::correlate;

int main(int argc, char** argv) {
  const int budget = argc > 1 ? std::atoi(argv[1]) : 1500;
  TwoChainParameters truth;
  truth.iwan = true;
  const std::vector<Sensor> sensors{{"a5", 5, -1.0}};
  IwanTarget target;
  target.mode = 1;
  target.curves.push_back(synthetic_backbone(two_chain_structure(truth), 1, sensors, 0,
                                             AmplitudeQuantity::kVelocity, 30, 1.0, 5e-4, 0.03, 7));
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> factor(std::log(3.0), std::log(10.0));
  std::bernoulli_distribution up(0.5);
  auto off = [&](double v) { return v * std::exp((up(rng) ? 1 : -1) * factor(rng)); };
  const char* names[] = {"paper", "paper-log", "global-local"};
  std::vector<double> cost[3], evals[3], secs[3];
  int wins = 0;
  for (int s = 0; s < 20; ++s) {
    TwoChainParameters start = truth;
    start.Fs = off(truth.Fs);
    start.ka = off(truth.ka);
    start.beta = off(truth.beta);
    start.chi = -0.1;
    const jointlab::model::Model m = two_chain_structure(start);
    const IwanObjective obj(m, "rivet", sensors, {target}, IwanUpdateOptions{});
    double c[3];
    for (int k = 0; k < 3; ++k) {
      IwanUpdateOptions o;
      o.optimizer = static_cast<IwanOptimizer>(k);
      // Bounds a decade and a half around the (wrong) start, as a user would set them.
      o.bounds = {start.Fs / 30, start.Fs * 30, 1.0 / 30,        30.0,
                  -0.95,         0.0,           start.beta / 30, start.beta * 30};
      o.max_evaluations = budget;
      o.seed = 100 + s;
      IwanUpdateSummary sum;
      const auto t0 = std::chrono::steady_clock::now();
      update_iwan(obj, o, &sum);
      const double dt =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      cost[k].push_back(sum.final_cost);
      evals[k].push_back(sum.evaluations);
      secs[k].push_back(dt);
      c[k] = sum.final_cost;
    }
    if (c[2] < c[0]) ++wins;
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return 0.5 * (v[(v.size() - 1) / 2] + v[v.size() / 2]);
  };
  std::printf("20 starts (Fs, Kt, beta off by 3-10x), budget %d QSMA evaluations\n", budget);
  std::printf("%-13s %14s %14s %12s %12s\n", "optimiser", "median cost", "worst cost",
              "median evals", "median s");
  for (int k = 0; k < 3; ++k) {
    std::printf("%-13s %14.4g %14.4g %12.0f %12.3f\n", names[k], median(cost[k]),
                *std::max_element(cost[k].begin(), cost[k].end()), median(evals[k]),
                median(secs[k]));
  }
  std::printf("global-local below paper in %d of 20 starts\n", wins);
  return 0;
}
