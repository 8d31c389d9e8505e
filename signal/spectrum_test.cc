#include "jointlab/signal/spectrum.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace jointlab::signal {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(Spectrum, SinusoidAmplitudeAndPeaks) {
  const double fs = 1024.0;
  const Eigen::Index n = 4096;  // 0.25 Hz bins: 30, 90, 200 Hz fall on bins
  Eigen::VectorXd x(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const double t = j / fs;
    x(j) = 2.0 * std::cos(2 * kPi * 30 * t) + 0.5 * std::cos(2 * kPi * 90 * t) +
           1.0 * std::sin(2 * kPi * 200 * t);
  }
  FftCache cache;
  const AmplitudeSpectrum s = amplitude_spectrum(x, fs, cache);
  const Eigen::Index k30 = 30 * 4;
  EXPECT_NEAR(s.frequency_hz(k30), 30.0, 1e-12);
  EXPECT_NEAR(s.amplitude(k30), 2.0, 1e-3);  // Hann scalloping is zero on-bin
  const auto peaks = strongest_peaks(s.amplitude, 3, 8);
  ASSERT_EQ(peaks.size(), 3u);
  EXPECT_NEAR(s.frequency_hz(peaks[0]), 30.0, 0.3);
  EXPECT_NEAR(s.frequency_hz(peaks[1]), 90.0, 0.3);
  EXPECT_NEAR(s.frequency_hz(peaks[2]), 200.0, 0.3);
  const auto two = strongest_peaks(s.amplitude, 2, 8);
  ASSERT_EQ(two.size(), 2u);  // the two most prominent: 30 and 200 Hz
  EXPECT_NEAR(s.frequency_hz(two[1]), 200.0, 0.3);
}

// lowpass_in_place (one buffer for a long record) gives lowpass()'s numbers.
TEST(Lowpass, InPlaceEqualsTheCopyingOne) {
  const double fs = 1000;
  const Eigen::Index n = 5000;
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k)
    x(k) = std::sin(2 * kPi * 40 * k / fs) + 0.5 * std::sin(2 * kPi * 300 * k / fs);
  FftCache cache;
  const Eigen::VectorXd y = lowpass(x, fs, 100, 200, cache);
  Eigen::VectorXcd data(fast_size(2 * n) / 2 + 1);
  Eigen::Map<Eigen::VectorXd> real(reinterpret_cast<double*>(data.data()), n);
  real = x;
  lowpass_in_place(data.data(), n, fs, 100, 200, cache);
  EXPECT_LT((real - y).cwiseAbs().maxCoeff(), 1e-12);
  // The 40 Hz part passes, the 300 Hz part is gone (away from the ends).
  double worst = 0;
  for (Eigen::Index k = 500; k < n - 500; ++k)
    worst = std::max(worst, std::abs(real(k) - std::sin(2 * kPi * 40 * k / fs)));
  EXPECT_LT(worst, 1e-4);
}

// A long record's low-pass (modal::channel_spectrum) is padded by two guards, the time its
// kernel's Gaussian factor exp(-2 pi^2 sd^2 t^2) (sd the edge's standard deviation) takes to
// fall to exp(-8), not to twice the record; the guard at each end is then dropped, so a kept
// sample sees the other end three guards away, at exp(-72). A ring-down from 1 into noise
// of 1e-6: between the guards the output is lowpass()'s but for rounding (7.6e-13 at the
// end, as in place and copying differ; required 1e-12, as there); not padded at all, the
// start shows at the end.
TEST(Lowpass, PaddedByTwoGuardsKeepsWhatLiesBetweenThem) {
  const double fs = 1000, f_pass = 100, f_stop = 200;
  const Eigen::Index n = 10000;
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    x(k) = std::exp(-2 * t) * std::cos(2 * kPi * 40 * t) + 1e-6 * std::sin(0.7 * k * k);
  }
  const double sd = (f_stop - f_pass) / 4;
  const auto guard = static_cast<Eigen::Index>(std::ceil(4 / sd / (2 * kPi) * fs));
  FftCache cache;
  const Eigen::VectorXd y = lowpass(x, fs, f_pass, f_stop, cache);
  const auto padded = [&](Eigen::Index pad) {
    const Eigen::Index nfft = fast_size(n + pad);
    Eigen::VectorXcd data(nfft / 2 + 1);
    Eigen::Map<Eigen::VectorXd> real(reinterpret_cast<double*>(data.data()), n);
    real = x;
    lowpass_in_place(data.data(), n, nfft, fs, f_pass, f_stop, cache);
    return Eigen::VectorXd(real.segment(guard, n - 2 * guard) - y.segment(guard, n - 2 * guard));
  };
  const Eigen::VectorXd d = padded(2 * guard);
  EXPECT_LT(d.cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(padded(0).tail(guard).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Integrate, TwiceIntegratedAccelerationIsDisplacement) {
  // x = g(t) cos(w t) with a Gaussian g that vanishes at both ends: its exact
  // second derivative, integrated twice in the frequency domain, must return x.
  // Nothing is left below 5 Hz, so the error is rounding: 1e-9 of the peak.
  const double fs = 2000.0, f = 37.0, w = 2 * kPi * f, tc = 2.0, s = 0.3;  // g(0) = g(4) = 3e-10
  const Eigen::Index n = 8000;
  Eigen::VectorXd acc(n), x_exact(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const double t = j / fs, u = (t - tc) / (s * s);
    const double g = std::exp(-0.5 * (t - tc) * u), g1 = -u * g, g2 = (u * u - 1 / (s * s)) * g;
    x_exact(j) = g * std::cos(w * t);
    acc(j) = g2 * std::cos(w * t) - 2 * g1 * w * std::sin(w * t) - g * w * w * std::cos(w * t);
  }
  FftCache cache;
  const Eigen::VectorXd x = integrate(acc, fs, 2, 5.0, cache);
  EXPECT_LT((x - x_exact).cwiseAbs().maxCoeff(), 1e-9);
}

}  // namespace
}  // namespace jointlab::signal
