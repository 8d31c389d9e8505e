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

TEST(LocalPoly, OffCentreEvaluationIsExactOnPolynomials) {
  // A cubic fitted by a cubic is reproduced anywhere in the window: evaluated
  // half a half-width off centre, value and slope equal the closed form.
  const double dt = 0.01;
  Eigen::VectorXd y(200);
  const auto f = [](double t) { return 0.5 - t + 0.2 * t * t - 0.05 * t * t * t; };
  for (int i = 0; i < 200; ++i) y(i) = f(i * dt);
  const double centre = 1.0, h = 0.4, at = centre + 0.5 * h;
  const LocalFit fit = fit_local(y, 0.0, dt, centre, h, 3, 1.0, 1, 0.5);
  EXPECT_NEAR(fit.value, f(at), 1e-10);
  EXPECT_NEAR(fit.slope, -1.0 + 0.4 * at - 0.15 * at * at, 1e-9);
}

TEST(LocalPoly, SlopeChangeSeesTheBiasOfASymmetricWindow) {
  // y = t^5 about c = 0: a cubic's slope at the centre is biased by the t^5
  // term, which only the degree-5 refit resolves (a degree-4 refit adds an even
  // power and leaves the slope where it is). The degree-5 refit is exact, so the
  // change must equal the cubic's whole error.
  const double dt = 0.001;
  Eigen::VectorXd y(2001);
  for (int i = 0; i <= 2000; ++i) {
    const double t = -1.0 + i * dt;
    y(i) = t * t * t * t * t;
  }
  const LocalFit fit = fit_local(y, -1.0, dt, 0.0, 0.8, 3, 1.0);
  ASSERT_GT(std::abs(fit.slope), 1e-3);  // the true slope is 0: the cubic is biased
  EXPECT_NEAR(fit.slope_change, std::abs(fit.slope), 1e-9);
}

}  // namespace
}  // namespace jointlab::signal
