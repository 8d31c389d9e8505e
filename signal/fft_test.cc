#include "jointlab/signal/fft.h"

#include <algorithm>
#include <cmath>
#include <complex>
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

// In place (a long record's spectrum, no copy): the numbers of forward() and inverse_real(),
// for even and odd sizes and for a size whose plans are made and dropped each time.
TEST(Fft, InPlaceTransformsEqualTheCopyingOnes) {
  for (const Eigen::Index n : {Eigen::Index{360}, Eigen::Index{945}, fast_size(4200000)}) {
    SCOPED_TRACE(n);
    const Eigen::VectorXd x = Eigen::VectorXd::Random(n * 2 / 3);
    Fft fft(n);
    const Eigen::VectorXcd X = fft.forward(x);
    for (int again = 0; again < 2; ++again) {
      Eigen::VectorXcd data(n / 2 + 1);
      Eigen::Map<Eigen::VectorXd> real(reinterpret_cast<double*>(data.data()), 2 * data.size());
      real.setZero();
      real.head(x.size()) = x;
      fft.forward_in_place(data.data());
      EXPECT_LT((data - X).cwiseAbs().maxCoeff(), 1e-9 * X.cwiseAbs().maxCoeff());
      fft.inverse_real_in_place(data.data());
      EXPECT_LT((real.head(x.size()) - x).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LT(real.segment(x.size(), n - x.size()).cwiseAbs().maxCoeff(), 1e-12);
    }
  }
}

// Through a buffer: forward()'s numbers up to rounding, for even and odd sizes, each twice (the
// plan kept), from inputs aligned two ways, and for a size above the buffered ones (in place).
TEST(Fft, BufferedForwardEqualsTheCopyingOne) {
  for (const Eigen::Index n :
       {Eigen::Index{360}, Eigen::Index{945}, fast_size((Eigen::Index{1} << 17) + 1)}) {
    SCOPED_TRACE(n);
    const Eigen::VectorXd x = Eigen::VectorXd::Random(n * 2 / 3);
    Fft fft(n);
    const Eigen::VectorXcd X = Fft(n).forward(x);  // another object: fft's first use is below
    for (int shift = 0; shift < 2; ++shift) {
      for (int again = 0; again < 2; ++again) {
        // data at `shift` doubles into a complex buffer one longer: 16-byte and 8-byte offsets.
        Eigen::VectorXcd storage = Eigen::VectorXcd::Zero(n / 2 + 2);
        auto* real = reinterpret_cast<double*>(storage.data()) + shift;
        std::copy(x.data(), x.data() + x.size(), real);
        auto* data = reinterpret_cast<std::complex<double>*>(real);
        fft.forward_through_buffer(data);
        double worst = 0;
        for (Eigen::Index k = 0; k <= n / 2; ++k) worst = std::max(worst, std::abs(data[k] - X(k)));
        EXPECT_LT(worst, 1e-9 * X.cwiseAbs().maxCoeff());
      }
    }
  }
}

TEST(Fft, FastSizesHaveOnlySmallPrimes) {
  EXPECT_EQ(fast_size(1000), 1000);
  EXPECT_EQ(fast_size(1031), 1050);  // 2 * 3 * 5^2 * 7
  EXPECT_EQ(fast_size(11), 12);
}

}  // namespace
}  // namespace jointlab::signal
