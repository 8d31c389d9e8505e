// The per-sample elementary functions of a ring-down extraction (signal/vector_math.h)
// against the scalar std:: loop they replace, on one band signal's worth of samples
// (8192, a coarse grid of a few seconds): atan2 (the envelope's phase), exp and sin/cos (the
// gain correction's model of the mode), log (the envelope's logarithm). Items per second are
// samples per second: the vector versions' ratio to the scalar ones is the speed-up.
#include <benchmark/benchmark.h>

#include <cmath>

#include <Eigen/Core>

#include "jointlab/signal/vector_math.h"

namespace {

constexpr Eigen::Index kSamples = 8192;

Eigen::ArrayXd ramp(double lo, double hi) { return Eigen::ArrayXd::LinSpaced(kSamples, lo, hi); }

void BM_Atan2Scalar(benchmark::State& state) {
  const Eigen::ArrayXd y = ramp(-1, 1).sin(), x = ramp(-2, 3).cos();
  Eigen::ArrayXd out(kSamples);
  for (auto _ : state) {
    for (Eigen::Index i = 0; i < kSamples; ++i) out(i) = std::atan2(y(i), x(i));
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * kSamples);
}
BENCHMARK(BM_Atan2Scalar);

void BM_Atan2Array(benchmark::State& state) {
  const Eigen::ArrayXd y = ramp(-1, 1).sin(), x = ramp(-2, 3).cos();
  Eigen::ArrayXd out(kSamples);
  for (auto _ : state) {
    jointlab::signal::atan2_array(y, x, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * kSamples);
}
BENCHMARK(BM_Atan2Array);

void BM_ExpScalar(benchmark::State& state) {
  const Eigen::ArrayXd x = ramp(-30, 0);
  Eigen::ArrayXd out(kSamples);
  for (auto _ : state) {
    for (Eigen::Index i = 0; i < kSamples; ++i) out(i) = std::exp(x(i));
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * kSamples);
}
BENCHMARK(BM_ExpScalar);

void BM_ExpArray(benchmark::State& state) {
  const Eigen::ArrayXd x = ramp(-30, 0);
  Eigen::ArrayXd out(kSamples);
  for (auto _ : state) {
    jointlab::signal::exp_array(x, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * kSamples);
}
BENCHMARK(BM_ExpArray);

void BM_LogScalar(benchmark::State& state) {
  const Eigen::ArrayXd x = ramp(-30, 0).exp();
  Eigen::ArrayXd out(kSamples);
  for (auto _ : state) {
    for (Eigen::Index i = 0; i < kSamples; ++i) out(i) = std::log(x(i));
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * kSamples);
}
BENCHMARK(BM_LogScalar);

void BM_LogArray(benchmark::State& state) {
  const Eigen::ArrayXd x = ramp(-30, 0).exp();
  Eigen::ArrayXd out(kSamples);
  for (auto _ : state) {
    jointlab::signal::log_array(x, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * kSamples);
}
BENCHMARK(BM_LogArray);

void BM_SinCosScalar(benchmark::State& state) {
  const Eigen::ArrayXd x = ramp(0, 2000);
  Eigen::ArrayXd s(kSamples), c(kSamples);
  for (auto _ : state) {
    for (Eigen::Index i = 0; i < kSamples; ++i) {
      s(i) = std::sin(x(i));
      c(i) = std::cos(x(i));
    }
    benchmark::DoNotOptimize(s.data());
    benchmark::DoNotOptimize(c.data());
  }
  state.SetItemsProcessed(state.iterations() * kSamples);
}
BENCHMARK(BM_SinCosScalar);

void BM_SinCosArray(benchmark::State& state) {
  const Eigen::ArrayXd x = ramp(0, 2000);
  Eigen::ArrayXd s(kSamples), c(kSamples);
  for (auto _ : state) {
    jointlab::signal::sincos_array(x, s, c);
    benchmark::DoNotOptimize(s.data());
    benchmark::DoNotOptimize(c.data());
  }
  state.SetItemsProcessed(state.iterations() * kSamples);
}
BENCHMARK(BM_SinCosArray);

}  // namespace

BENCHMARK_MAIN();
