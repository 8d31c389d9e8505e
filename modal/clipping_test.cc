#include "jointlab/modal/clipping.h"

#include <cmath>
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

TEST(Clipping, EmptyAndConstantChannels) {
  EXPECT_FALSE(find_clipping(Eigen::VectorXd()).found());
  EXPECT_FALSE(find_clipping(Eigen::VectorXd::Constant(100, 3.0)).found());
}

}  // namespace
}  // namespace jointlab::modal
