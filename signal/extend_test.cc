#include "jointlab/signal/extend.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace jointlab::signal {
namespace {

double two_modes(double t) {
  return std::exp(-2.0 * t) * std::cos(2 * std::numbers::pi * 31 * t + 0.4) +
         0.3 * std::exp(-5.0 * t) * std::cos(2 * std::numbers::pi * 97 * t);
}

TEST(Extend, ContinuesDampedSinusoidsBothWays) {
  // Two noiseless damped modes satisfy an order-4 recursion exactly; order 8
  // leaves room. The continuation must match the true signal to 1e-8 of its
  // size (limited by the least-squares conditioning, not by the model).
  const double fs = 1000;
  const Eigen::Index n = 2000, pad = 300;
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) x(k) = two_modes(k / fs);
  const Extension e = extend_record(x, pad, pad, 8, 600);
  ASSERT_EQ(e.samples.size(), n + 2 * pad);
  double worst = 0;
  for (Eigen::Index k = 0; k < e.samples.size(); ++k) {
    const double t = (k - pad) / fs;
    worst = std::max(worst, std::abs(e.samples(k) - two_modes(t)) / std::exp(-2.0 * t));
  }
  EXPECT_LT(worst, 1e-8);
}

TEST(Extend, UnstableContinuationIsDropped) {
  // White noise has no recursion: whatever the model predicts must not exceed
  // max_growth times the data; here growth 0 forces the fallback to zeros.
  Eigen::VectorXd x = Eigen::VectorXd::Random(500);
  const Extension e = extend_record(x, 50, 50, 10, 400, 0.0);
  EXPECT_EQ(e.samples.head(50).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(e.samples.tail(50).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace jointlab::signal
