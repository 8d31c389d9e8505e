#include "jointlab/signal/local_poly.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace jointlab::signal {
namespace {

TEST(LocalPoly, ExactOnPolynomials) {
  // A quadratic is reproduced exactly: slope 2 + 2*0.3*c at the centre.
  const double dt = 0.01;
  Eigen::VectorXd y(200);
  for (int i = 0; i < 200; ++i) {
    const double t = i * dt;
    y(i) = 1.0 + 2.0 * t + 0.3 * t * t;
  }
  const LocalFit f = fit_local(y, 0.0, dt, 1.0, 0.4, 2, 1.0);
  EXPECT_NEAR(f.slope, 2.0 + 0.6 * 1.0, 1e-10);
  EXPECT_NEAR(f.value, 1.0 + 2.0 + 0.3, 1e-10);
  EXPECT_LT(f.residual_rms, 1e-10);
  EXPECT_LT(f.slope_change, 1e-9);
}

TEST(LocalPoly, SlopeStdMatchesScatterOfWhiteNoise) {
  // With independent noise the stated one-sigma must match the observed scatter
  // of slopes over many realisations: within 10 % for 2000 draws (the sampling
  // error of a standard deviation from 2000 draws is about 1.6 %).
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  const double dt = 0.002;
  double sum2 = 0, stated = 0;
  const int draws = 2000;
  for (int k = 0; k < draws; ++k) {
    Eigen::VectorXd y(300);
    for (int i = 0; i < 300; ++i) y(i) = -0.5 * i * dt + noise(rng);
    const LocalFit f = fit_local(y, 0.0, dt, 0.3, 0.25, 2, 1.0);
    sum2 += (f.slope + 0.5) * (f.slope + 0.5);
    stated += f.slope_std;
  }
  const double observed = std::sqrt(sum2 / draws);
  EXPECT_NEAR(stated / draws / observed, 1.0, 0.1);
}

}  // namespace
}  // namespace jointlab::signal
