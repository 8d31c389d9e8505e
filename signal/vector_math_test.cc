#include "jointlab/signal/vector_math.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

namespace jointlab::signal {
namespace {

// Units in the last place between a and b (0 for equal values, infinities and NaNs alike).
double ulps(double a, double b) {
  if (a == b || (std::isnan(a) && std::isnan(b))) return 0;
  if (!std::isfinite(a) || !std::isfinite(b)) return std::numeric_limits<double>::infinity();
  const double scale = std::max(std::abs(a), std::abs(b));
  const double ulp = scale >= std::numeric_limits<double>::min()
                         ? std::ldexp(1.0, std::ilogb(scale) - 52)
                         : std::numeric_limits<double>::denorm_min();
  return std::abs(a - b) / ulp;
}

// Lengths 0 to 9 exercise every remainder after the vector blocks of 2 and 4; the values
// spread over the ranges the extraction meets (phases of thousands of radians, logarithms of
// 1e-300 to 1e300, decays of exp(-700)) and the special ones.
Eigen::ArrayXd values(Eigen::Index n, double lo, double hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  Eigen::ArrayXd x(n);
  for (double& v : x) v = u(rng);
  return x;
}

// glibc states its vector functions within 4 ulp of the exact result and its scalar ones within
// 1: the two may then differ by 5.
constexpr double kUlps = 5;

TEST(VectorMath, EachFunctionGivesTheScalarOnesValuesWithinFiveUlp) {
  for (Eigen::Index n : {0, 1, 2, 3, 4, 5, 7, 9, 1000}) {
    const Eigen::ArrayXd phase = values(n, -3e3, 3e3, 1);
    const Eigen::ArrayXd lg = values(n, -700, 700, 2);
    const Eigen::ArrayXd y = values(n, -2, 2, 3), x = values(n, -2, 2, 4);
    Eigen::ArrayXd pos = values(n, -690, 690, 5);
    pos = pos.exp();
    const Eigen::ArrayXd e = values(n, -6, 27, 6);
    Eigen::ArrayXd a(n), b(n);
    atan2_array(y, x, a);
    for (Eigen::Index i = 0; i < n; ++i) EXPECT_LE(ulps(a(i), std::atan2(y(i), x(i))), kUlps);
    exp_array(lg, a);
    for (Eigen::Index i = 0; i < n; ++i) EXPECT_LE(ulps(a(i), std::exp(lg(i))), kUlps) << lg(i);
    log_array(pos, a);
    for (Eigen::Index i = 0; i < n; ++i) EXPECT_LE(ulps(a(i), std::log(pos(i))), kUlps);
    sincos_array(phase, a, b);
    for (Eigen::Index i = 0; i < n; ++i) {
      EXPECT_LE(ulps(a(i), std::sin(phase(i))), kUlps) << phase(i);
      EXPECT_LE(ulps(b(i), std::cos(phase(i))), kUlps) << phase(i);
    }
    erfc_array(e, a);
    for (Eigen::Index i = 0; i < n; ++i) EXPECT_LE(ulps(a(i), std::erfc(e(i))), kUlps) << e(i);
  }
}

TEST(VectorMath, SpecialValuesAsTheScalarFunctionsHaveThem) {
  constexpr double inf = std::numeric_limits<double>::infinity(), pi = std::numbers::pi;
  Eigen::ArrayXd y(6), x(6), out(6);
  y << 0.0, -0.0, 1.0, -1.0, 0.0, 1e-310;
  x << 1.0, 1.0, 0.0, 0.0, -1.0, -1.0;
  atan2_array(y, x, out);
  EXPECT_EQ(out(0), 0.0);
  EXPECT_TRUE(std::signbit(out(1)));  // the sign of a zero picks the side of the cut
  EXPECT_NEAR(out(2), pi / 2, 1e-15);
  EXPECT_NEAR(out(3), -pi / 2, 1e-15);
  EXPECT_NEAR(out(4), pi, 1e-15);
  EXPECT_NEAR(out(5), pi, 1e-15);
  Eigen::ArrayXd v(5), r(5);
  v << -inf, -800, 0.0, 709, inf;
  exp_array(v, r);
  EXPECT_EQ(r(0), 0.0);
  EXPECT_EQ(r(1), 0.0);
  EXPECT_EQ(r(2), 1.0);
  EXPECT_LE(ulps(r(3), std::exp(709.0)), kUlps);
  EXPECT_EQ(r(4), inf);
  v << 1e-300, 1.0, 4.9e-324, inf, 1e300;
  log_array(v, r);
  EXPECT_LE(ulps(r(0), std::log(1e-300)), kUlps);
  EXPECT_EQ(r(1), 0.0);
  EXPECT_LE(ulps(r(2), std::log(4.9e-324)), kUlps);  // a subnormal
  EXPECT_EQ(r(3), inf);
  EXPECT_LE(ulps(r(4), std::log(1e300)), kUlps);
  // In place: out may be the input.
  Eigen::ArrayXd w = Eigen::ArrayXd::LinSpaced(7, 0.5, 3.5), w0 = w;
  log_array(w, w);
  for (Eigen::Index i = 0; i < w.size(); ++i) EXPECT_LE(ulps(w(i), std::log(w0(i))), kUlps);
}

}  // namespace
}  // namespace jointlab::signal
