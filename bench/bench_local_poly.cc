// The local fit of a ring-down's envelope and phase (signal/local_poly.h: a pair of series,
// degree 3, each one's value and slope, their uncertainties and the refits at degrees 4 and 5)
// against the values and slopes alone of the three degrees from Eigen's dense weighted least
// squares (a design matrix, then an LLT of the normal equations for each degree; no
// uncertainties, so the comparison favours it), on windows of 48, 83 and 160 samples (the
// estimates thin long windows to about 48 samples; 83 is the bench record's mean). Items per
// second are fits per second: their ratio is the kernel's speed-up (measured: 6-7 times).
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>

#include <Eigen/Dense>

#include "jointlab/signal/local_poly.h"

namespace {

constexpr int kDegree = 3;

// Two series of 4096 samples at dt = 1 and the window centres the fits step through.
struct Series {
  Eigen::VectorXd a = Eigen::VectorXd::Random(4096), b = Eigen::VectorXd::Random(4096);
  static double centre(int i) { return 1000.0 + 0.37 * (i % 1000); }
};

void BM_LocalFitPair(benchmark::State& state) {
  const Series s;
  const double half = static_cast<double>(state.range(0)) / 2;
  int i = 0;
  for (auto _ : state) {
    const auto fits = jointlab::signal::fit_local_pair(s.a, s.b, 0.0, 1.0, Series::centre(i++),
                                                       half, kDegree, 1.0, 1, 0.1);
    benchmark::DoNotOptimize(fits);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_LocalFitPair)->Arg(48)->Arg(83)->Arg(160);

// The value, slope and their refits' changes of both series by dense algebra.
void BM_DenseFitPair(benchmark::State& state) {
  const Series s;
  const double half = static_cast<double>(state.range(0)) / 2;
  int i = 0;
  for (auto _ : state) {
    const double c = Series::centre(i++);
    const auto first = static_cast<Eigen::Index>(std::ceil(c - half));
    const auto n = static_cast<Eigen::Index>(std::floor(c + half)) - first + 1;
    Eigen::MatrixXd X(n, kDegree + 3);
    Eigen::VectorXd w(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const double tau = (static_cast<double>(first + k) - c) / half;
      w(k) = (1 - tau * tau) * (1 - tau * tau);
      double p = 1;
      for (int j = 0; j < kDegree + 3; ++j, p *= tau) X(k, j) = p;
    }
    const Eigen::MatrixXd WX = w.asDiagonal() * X;
    std::array<double, 4> out{};
    for (int columns = kDegree + 1; columns <= kDegree + 3; ++columns) {
      const Eigen::LLT<Eigen::MatrixXd> llt(X.leftCols(columns).transpose() * WX.leftCols(columns));
      for (int series = 0; series < 2; ++series) {
        const Eigen::VectorXd& y = series == 0 ? s.a : s.b;
        const Eigen::VectorXd beta =
            llt.solve(WX.leftCols(columns).transpose() * y.segment(first, n));
        out[static_cast<size_t>(2 * series)] += beta(0);
        out[static_cast<size_t>(2 * series + 1)] += beta(1);
      }
    }
    benchmark::DoNotOptimize(out);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DenseFitPair)->Arg(48)->Arg(83)->Arg(160);

}  // namespace

BENCHMARK_MAIN();
