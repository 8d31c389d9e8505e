#include "jointlab/signal/band_analytic.h"

#include <cmath>
#include <complex>
#include <numbers>

#include <gtest/gtest.h>

namespace jointlab::signal {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(BandGain, FlatInsideAndSmallOutside) {
  const Band b{40.0, 60.0};
  EXPECT_NEAR(band_gain(b, 0.25, 50.0), 1.0, 1e-8);           // 6 sigma from both edges
  EXPECT_NEAR(band_gain(b, 0.25, 45.0), 1.0 - 0.0228, 1e-3);  // lo + w: 1 - Phi(-2)
  EXPECT_NEAR(band_gain(b, 0.25, 40.0), 0.0228, 1e-3);        // lo: Phi(-2)
  EXPECT_EQ(band_gain(b, 0.25, 20.0), 0.0);
}

// A damped sinusoid far from the record's ends must come back as its exact
// analytic signal a e^{i theta}; the tolerance 1e-6 is far above rounding and
// far below any filter or Hilbert error that would matter.
TEST(BandAnalytic, RecoversDampedSinusoidAndIntegrates) {
  const double fs = 1000.0, f0 = 50.0, sigma = 0.5;
  const Eigen::Index n = 4000;
  Eigen::VectorXd acc(n);
  const double w0 = 2 * kPi * f0;
  for (Eigen::Index j = 0; j < n; ++j) {
    const double t = j / fs;
    // displacement x = e^{-sigma t} cos(w0 t); acceleration is its exact second derivative
    const double e = std::exp(-sigma * t);
    acc(j) = e * ((sigma * sigma - w0 * w0) * std::cos(w0 * t) + 2 * sigma * w0 * std::sin(w0 * t));
    // plus an out-of-band mode at 200 Hz
    acc(j) += 1e4 * std::cos(2 * kPi * 200 * t);
  }
  const Eigen::Index nfft = fast_size(2 * n);
  FftCache cache;
  const Eigen::VectorXcd X = cache.get(nfft).forward(acc);
  BandOptions opt;
  opt.order = 2;
  const BandSignal bs = band_analytic(X, n, nfft, fs, Band{35, 65}, opt, cache);
  double worst = 0;
  for (Eigen::Index j = 0; j < bs.baseband.size(); ++j) {
    const double t = j * bs.dt;
    if (t < 1.0 || t > 3.0) continue;  // away from both ends (filter transients)
    const std::complex<double> z = bs.baseband(j) * std::polar(1.0, 2 * kPi * bs.carrier_hz * t);
    const std::complex<double> exact = std::exp(-sigma * t) * std::polar(1.0, w0 * t);
    worst = std::max(worst, std::abs(z - exact) / std::abs(exact));
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_GT(bs.noise_bandwidth_hz, 20.0);
  EXPECT_LT(bs.noise_bandwidth_hz, 30.0);
}

// The gain at a complex frequency against the filter itself: a sinusoid decaying at
// sigma = 2 pi d on the band's sloping edge comes out multiplied by G(f + i d), in
// magnitude and phase (d = 0.8 edge standard deviations, where G(f + i d) differs from
// G(f) by 20 %). Tolerance 1e-6 as above.
TEST(BandGain, AtAComplexFrequencyIsWhatADecayingSinusoidPasses) {
  const double fs = 1000.0, f0 = 41.5, d = 0.5;
  const Band band{40, 50};
  const Eigen::Index n = 8000;
  Eigen::VectorXd x(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const double t = j / fs;
    x(j) = std::exp(-2 * kPi * d * t) * std::cos(2 * kPi * f0 * t);
  }
  const Eigen::Index nfft = fast_size(2 * n);
  FftCache cache;
  const Eigen::VectorXcd X = cache.get(nfft).forward(x);
  const BandSignal bs = band_analytic(X, n, nfft, fs, band, BandOptions{}, cache);
  const std::complex<double> g = band_gain(band, 0.25, std::complex<double>(f0, d));
  EXPECT_GT(std::abs(g - band_gain(band, 0.25, f0)), 0.1);
  double worst = 0;
  for (Eigen::Index j = 0; j < bs.baseband.size(); ++j) {
    const double t = j * bs.dt;
    if (t < 1.5 || t > 3.0) continue;  // past the onset's transient (1.2 s)
    const std::complex<double> z = bs.baseband(j) * std::polar(1.0, 2 * kPi * bs.carrier_hz * t);
    const std::complex<double> exact =
        std::exp(-2 * kPi * d * t) * std::polar(1.0, 2 * kPi * f0 * t);
    worst = std::max(worst, std::abs(z / exact - g));
  }
  EXPECT_LT(worst, 1e-6);
  // On the real axis it is the real gain.
  for (const double f : {39.0, 41.25, 43.0, 45.0, 49.0}) {
    EXPECT_NEAR(
        std::abs(band_gain(band, 0.25, std::complex<double>(f, 0.0)) - band_gain(band, 0.25, f)),
        0.0, 1e-14);
  }
}

TEST(BandAnalytic, FullRateGridIsTheSampleGrid) {
  const double fs = 500.0;
  const Eigen::Index n = 1000;
  Eigen::VectorXd x(n);
  for (Eigen::Index j = 0; j < n; ++j) x(j) = std::cos(2 * kPi * 40 * j / fs);
  const Eigen::Index nfft = fast_size(2 * n);
  FftCache cache;
  const Eigen::VectorXcd X = cache.get(nfft).forward(x);
  BandOptions opt;
  opt.full_rate = true;
  const BandSignal bs = band_analytic(X, n, nfft, fs, Band{20, 60}, opt, cache);
  EXPECT_DOUBLE_EQ(bs.dt, 1.0 / fs);
  EXPECT_EQ(bs.baseband.size(), n);
  EXPECT_NEAR(bs.baseband(500).real(), x(500), 1e-6);
  EXPECT_NEAR(std::abs(bs.baseband(500)), 1.0, 1e-6);
}

}  // namespace
}  // namespace jointlab::signal
