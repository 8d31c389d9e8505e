#include "jointlab/modal/clipping.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include <gtest/gtest.h>

namespace jointlab::modal {
namespace {

// A 150 Hz ring-down at 51.2 kHz (341 samples a cycle), damping 0.3 %, peak 1, from sample 0.
Eigen::VectorXd ring(Eigen::Index n, double zeta = 0.003) {
  const double w = 2 * std::numbers::pi * 150, dt = 1.0 / 51200;
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt;
    x(k) = std::exp(-zeta * w * t) * std::sin(w * t + 0.3);
  }
  return x;
}

// Clipped at 0.6 of its peak, both ways: every sample past the range is pinned, and the last
// pinned sample is the last whose unclipped value lies beyond it (found here independently).
TEST(Clipping, ARingDownCutAtItsRangeIsFound) {
  const Eigen::VectorXd x = ring(20000);
  const Eigen::VectorXd clipped = x.cwiseMin(0.6).cwiseMax(-0.6);
  Eigen::Index beyond = 0, last = -1;
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    if (std::abs(x(k)) >= 0.6) {
      ++beyond;
      last = k;
    }
  }
  const Clipping c = find_clipping(clipped);
  ASSERT_TRUE(c.found());
  EXPECT_TRUE(c.high_pinned);
  EXPECT_TRUE(c.low_pinned);
  EXPECT_EQ(c.high, 0.6);
  EXPECT_EQ(c.low, -0.6);
  EXPECT_EQ(c.samples, beyond);
  EXPECT_EQ(c.last, last);
}

// Only the positive side past the range (an offset signal, or an asymmetric range).
TEST(Clipping, OneSideAlone) {
  const Eigen::VectorXd clipped = ring(20000).cwiseMin(0.8);
  const Clipping c = find_clipping(clipped);
  ASSERT_TRUE(c.found());
  EXPECT_TRUE(c.high_pinned);
  EXPECT_FALSE(c.low_pinned);
}

// The same ring-down unclipped: its extremes are reached once each.
TEST(Clipping, AnUnclippedRingDownIsNot) { EXPECT_FALSE(find_clipping(ring(20000)).found()); }

// Recorded by a coarse recorder: a 16-bit range of which the ring-down uses 1 % (its peak
// 327 steps), so that the samples around its first peak share the top code (a run of
// several), while the next peak, 1.9 % lower (the decay of a cycle), is 6 steps below it.
// A finely sampled peak is not a clipped one.
TEST(Clipping, ACoarselyRecordedPeakIsNot) {
  const double step = 1.0 / 32768;
  const Eigen::VectorXd x = (0.01 * ring(20000) / step).array().round() * step;
  Eigen::Index at_top = 0;
  const double top = x.maxCoeff();
  for (Eigen::Index k = 0; k < x.size(); ++k) at_top += x(k) == top;
  ASSERT_GE(at_top, 3);  // the run the rule must not mistake for clipping
  EXPECT_FALSE(find_clipping(x).found());
}

// One pinned run (the impact alone past the range, the ring-down within it): no clipped peak
// of the ring-down, nothing to say.
TEST(Clipping, OnePinnedRunIsNot) {
  Eigen::VectorXd x = 0.5 * ring(20000);
  x.segment(10, 5).setConstant(2.0);
  EXPECT_FALSE(find_clipping(x).found());
  x.segment(400, 3).setConstant(2.0);  // a second run at the same value: pinned
  const Clipping c = find_clipping(x);
  EXPECT_TRUE(c.found());
  EXPECT_EQ(c.samples, 8);
  EXPECT_EQ(c.last, 402);
}

// A sine of `amplitude` at f (Hz) sampled at fs, phase phi, damping zeta, for n samples, each
// written as a CSV writes it with `digits` significant digits and read back.
Eigen::VectorXd written_sine(double f, double fs, double phi, double zeta, Eigen::Index n,
                             int digits, double amplitude = 1.0) {
  Eigen::VectorXd x(n);
  const double w = 2 * std::numbers::pi * f;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    char text[64];
    std::snprintf(text, sizeof text, "%.*g", digits,
                  amplitude * std::exp(-zeta * w * t) * std::sin(w * t + phi));
    x(k) = std::strtod(text, nullptr);
  }
  return x;
}

// A clean sine of constant amplitude reaches its largest and smallest values at every peak:
// 50 Hz at 1 kHz, 7 digits (its peaks fall on samples, 250 of them at exactly 1 and -1); 125
// Hz at 1 kHz with its peaks midway between two samples, 6 digits (two equal samples a peak);
// and one barely damped (zeta 1e-6 at 80 Hz, 5120 Hz, 4 digits: the first 40 peaks read
// 1.000). Before, each was called clipped and read from its last peak on; no peak is flat.
TEST(Clipping, AConstantOrBarelyDampedSineIsNot) {
  const Eigen::VectorXd on_samples = written_sine(50, 1000, 0, 0, 5000, 7);
  Eigen::Index at_top = 0;
  for (Eigen::Index k = 0; k < on_samples.size(); ++k) at_top += on_samples(k) == 1.0;
  ASSERT_GE(at_top, 100);  // the repeats the old rule took for clipping
  EXPECT_FALSE(find_clipping(on_samples).found());
  const Eigen::VectorXd midway = written_sine(125, 1000, std::numbers::pi / 8, 0, 5000, 6);
  EXPECT_FALSE(find_clipping(midway).found());
  const Eigen::VectorXd barely = written_sine(80, 5120, 0.3, 1e-6, 51200, 4);
  EXPECT_FALSE(find_clipping(barely).found());
}

// The same sines cut at 0.8 of their peak (a recorder's range) are clipped: every peak is
// flat over several samples (a fifth of a cycle: 4 samples at 50 Hz, 1 kHz; 2 at 125 Hz,
// 1 kHz, which is no flat run, and 13 at 80 Hz, 5120 Hz).
TEST(Clipping, TheSameSinesCutAtTheirRangeAre) {
  const Eigen::VectorXd cut = written_sine(50, 1000, 0, 0, 5000, 7).cwiseMin(0.8).cwiseMax(-0.8);
  const Clipping c = find_clipping(cut);
  ASSERT_TRUE(c.found());
  EXPECT_TRUE(c.high_pinned);
  EXPECT_TRUE(c.low_pinned);
  Eigen::Index last = cut.size() - 1;  // the last sample at the range, found here apart
  while (std::abs(cut(last)) != 0.8) --last;
  EXPECT_EQ(c.last, last);
  const Eigen::VectorXd barely = written_sine(80, 5120, 0.3, 1e-6, 51200, 4);
  EXPECT_TRUE(find_clipping(barely.cwiseMin(0.8).cwiseMax(-0.8)).found());
}

TEST(Clipping, EmptyAndConstantChannels) {
  EXPECT_FALSE(find_clipping(Eigen::VectorXd()).found());
  EXPECT_FALSE(find_clipping(Eigen::VectorXd::Constant(100, 3.0)).found());
}

}  // namespace
}  // namespace jointlab::modal
