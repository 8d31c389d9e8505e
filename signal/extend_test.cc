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
  EXPECT_EQ(e.before_valid, pad);  // stable both ways: all of it is faithful
  EXPECT_EQ(e.after_valid, pad);
  double worst = 0;
  for (Eigen::Index k = 0; k < e.samples.size(); ++k) {
    const double t = (k - pad) / fs;
    worst = std::max(worst, std::abs(e.samples(k) - two_modes(t)) / std::exp(-2.0 * t));
  }
  EXPECT_LT(worst, 1e-8);
}

// The continuations depend on the fit_length samples at each end alone, and continue_record
// gives extend_record's, without a copy of the record.
TEST(Extend, ContinuationsUseOnlyTheEnds) {
  const double fs = 1000;
  const Eigen::Index n = 20000, pad = 300, fit = 600;
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) x(k) = two_modes(k / fs) + 1e-4 * std::sin(0.77 * k * k);
  const Continuation whole = continue_record(x, pad, pad, 8, fit);
  const Continuation ends_after = continue_record(x.tail(fit), 0, pad, 8, fit);
  const Continuation ends_before = continue_record(x.head(fit), pad, 0, 8, fit);
  EXPECT_EQ(whole.after, ends_after.after);
  EXPECT_EQ(whole.before, ends_before.before);
  const Extension e = extend_record(x, pad, pad, 8, fit);
  EXPECT_EQ(e.samples.head(pad), whole.before);
  EXPECT_EQ(e.samples.tail(pad), whole.after);
  EXPECT_EQ(e.samples.segment(pad, n), x);
  EXPECT_EQ(e.before_valid, whole.before_valid);
  EXPECT_EQ(e.after_valid, whole.after_valid);
}

TEST(Extend, UnstableContinuationIsDropped) {
  // White noise has no recursion: whatever the model predicts must not exceed
  // max_growth times the data; here growth 0 forces the fallback to zeros.
  Eigen::VectorXd x = Eigen::VectorXd::Random(500);
  const Extension e = extend_record(x, 50, 50, 10, 400, 0.0);
  EXPECT_EQ(e.samples.head(50).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(e.samples.tail(50).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(e.before_valid, 0);
  EXPECT_EQ(e.after_valid, 0);
}

TEST(Extend, BlowUpIsCutWhereItHappens) {
  // The same two modes, the 97 Hz one damped at 60 /s: run backwards it grows by
  // e^60 per second and passes 20 times the data's RMS after some 60 ms. The
  // backward continuation keeps the faithful first half of what comes before
  // that point (exact to 1e-8 of the signal), fades the rest out and is zero
  // beyond; the forward one (decaying) is kept whole.
  const auto signal = [](double t) {
    return std::exp(-2.0 * t) * std::cos(2 * std::numbers::pi * 31 * t + 0.4) +
           0.3 * std::exp(-60.0 * t) * std::cos(2 * std::numbers::pi * 97 * t);
  };
  const double fs = 1000;
  const Eigen::Index n = 2000, pad = 300;
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) x(k) = signal(k / fs);
  const Extension e = extend_record(x, pad, pad, 8, 600, 20.0);
  EXPECT_EQ(e.after_valid, pad);
  ASSERT_GT(e.before_valid, 10);
  ASSERT_LT(e.before_valid, pad / 2);
  for (Eigen::Index j = 1; j <= e.before_valid; ++j) {  // faithful: j samples before the data
    const double t = -j / fs;
    EXPECT_NEAR(e.samples(pad - j), signal(t), 1e-8 * std::abs(signal(t)) + 1e-10) << j;
  }
  const double rms = std::sqrt(x.head(600).squaredNorm() / 600);  // what it was fitted on
  EXPECT_LE(e.samples.head(pad).cwiseAbs().maxCoeff(), 20.0 * rms * std::sqrt(2.0));
  EXPECT_EQ(e.samples.head(pad - 2 * e.before_valid - 1).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace jointlab::signal
