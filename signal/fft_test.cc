#include "jointlab/signal/fft.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace jointlab::signal {
namespace {

TEST(Fft, CosineOnABinHasHalfLengthMagnitude) {
  // X[k] of cos(2 pi k0 j / n) is n/2 at k0 (unscaled forward), exactly up to rounding.
  const Eigen::Index n = 360, k0 = 17;
  Eigen::VectorXd x(n);
  for (Eigen::Index j = 0; j < n; ++j) x(j) = std::cos(2 * std::numbers::pi * k0 * j / double(n));
  Fft fft(n);
  const Eigen::VectorXcd X = fft.forward(x);
  ASSERT_EQ(X.size(), n / 2 + 1);
  EXPECT_NEAR(std::abs(X(k0)), n / 2.0, 1e-9);
  EXPECT_NEAR(std::abs(X(k0 + 1)), 0.0, 1e-9);
}

TEST(Fft, ComplexInverseOfHermitianSpectrumRestoresSignal) {
  const Eigen::Index n = 210;
  Eigen::VectorXd x = Eigen::VectorXd::Random(n);
  Fft fft(n);
  const Eigen::VectorXcd half = fft.forward(x);
  Eigen::VectorXcd full(n);
  for (Eigen::Index k = 0; k < n; ++k) full(k) = k <= n / 2 ? half(k) : std::conj(half(n - k));
  const Eigen::VectorXcd back = fft.inverse_complex(full);
  EXPECT_LT((back.real() - x).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(back.imag().cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Fft, FastSizesHaveOnlySmallPrimes) {
  EXPECT_EQ(fast_size(1000), 1000);
  EXPECT_EQ(fast_size(1031), 1050);  // 2 * 3 * 5^2 * 7
  EXPECT_EQ(fast_size(11), 12);
}

}  // namespace
}  // namespace jointlab::signal
