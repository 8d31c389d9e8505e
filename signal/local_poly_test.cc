#include "jointlab/signal/local_poly.h"

#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Dense>

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

// A second method: the same weighted fits by QR of sqrt(W) X, the sandwich covariance and
// the refits written out with dense matrices. The power sums (two samples at a time, the
// last of an odd count alone) and the nested Cholesky factors must agree with it to
// rounding: 1e-9 relative (the normal equations of a degree-5 window square a condition
// number of about 1e3), for every degree, odd and even sample counts, strides and
// off-centre evaluation.
TEST(LocalPoly, AgreesWithADenseWeightedLeastSquaresFit) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  const double dt = 0.01;
  Eigen::VectorXd y1(400), y2(400);
  for (int i = 0; i < 400; ++i) {
    const double t = i * dt;
    y1(i) = std::sin(3 * t) + noise(rng);
    y2(i) = 2 - 0.7 * t + 0.1 * t * t * t + noise(rng);
  }
  const auto dense = [&](const Eigen::VectorXd& y, double centre, double h, int degree,
                         Eigen::Index stride, double offset, int columns) {
    std::vector<double> taus, ws, ys;
    // The grid points in [centre - h, centre + h], every stride-th from the first.
    const auto first = static_cast<Eigen::Index>(std::ceil((centre - h) / dt));
    const auto last = static_cast<Eigen::Index>(std::floor((centre + h) / dt));
    for (Eigen::Index i = first; i <= last; i += stride) {
      const double tau = (i * dt - centre) / h;
      taus.push_back(tau);
      ws.push_back(std::pow(1 - tau * tau, 2));
      ys.push_back(y(i));
    }
    const auto n = static_cast<Eigen::Index>(taus.size());
    Eigen::MatrixXd X(n, columns);
    Eigen::VectorXd w(n), v(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      for (int j = 0; j < columns; ++j) X(i, j) = std::pow(taus[i], j);
      w(i) = ws[i];
      v(i) = ys[i];
    }
    const Eigen::VectorXd sw = w.cwiseSqrt();
    const Eigen::VectorXd beta =
        (sw.asDiagonal() * X).colPivHouseholderQr().solve(sw.cwiseProduct(v));
    Eigen::VectorXd gv(columns), gs = Eigen::VectorXd::Zero(columns);
    for (int j = 0; j < columns; ++j) {
      gv(j) = std::pow(offset, j);
      if (j > 0) gs(j) = j * std::pow(offset, j - 1);
    }
    LocalFit f;
    f.value = gv.dot(beta);
    f.slope = gs.dot(beta) / h;
    if (columns == degree + 1) {
      const Eigen::VectorXd r = v - X * beta;
      const double s2 = w.dot(r.cwiseProduct(r)) / w.sum();
      const Eigen::MatrixXd Ainv = (X.transpose() * w.asDiagonal() * X).inverse();
      const Eigen::MatrixXd cov =
          s2 * Ainv * (X.transpose() * w.cwiseProduct(w).asDiagonal() * X) * Ainv;
      f.value_std = std::sqrt(gv.dot(cov * gv));
      f.slope_std = std::sqrt(gs.dot(cov * gs)) / h;
      f.residual_rms = std::sqrt(s2);
      f.samples = static_cast<int>(n);
    }
    return f;
  };
  int checked = 0;
  for (int degree = 1; degree <= 5; ++degree) {
    for (const Eigen::Index stride : {1, 2, 3}) {
      for (const double h : {0.33, 0.405, 0.77}) {
        for (const double offset : {0.0, -0.5, 0.35}) {
          const double centre = 1.9 + 0.013 * degree;
          const auto [a, b] =
              fit_local_pair(y1, y2, 0.0, dt, centre, h, degree, 1.0, stride, offset);
          // Four series in one call: each one's numbers exactly as the pair gives them.
          const auto quad =
              fit_local_quad({&y2, &y1, &y1, &y2}, 0.0, dt, centre, h, degree, 1.0, stride, offset);
          for (const auto& [x, ref] : {std::pair{quad[0], b}, std::pair{quad[1], a},
                                       std::pair{quad[2], a}, std::pair{quad[3], b}}) {
            EXPECT_EQ(x.value, ref.value);
            EXPECT_EQ(x.slope, ref.slope);
            EXPECT_EQ(x.value_std, ref.value_std);
            EXPECT_EQ(x.slope_std, ref.slope_std);
            EXPECT_EQ(x.value_change, ref.value_change);
            EXPECT_EQ(x.slope_change, ref.slope_change);
            EXPECT_EQ(x.residual_rms, ref.residual_rms);
          }
          for (const auto& [fit, y] : {std::pair{a, &y1}, std::pair{b, &y2}}) {
            const LocalFit d = dense(*y, centre, h, degree, stride, offset, degree + 1);
            const LocalFit d1 = dense(*y, centre, h, degree, stride, offset, degree + 2);
            const LocalFit d2 = dense(*y, centre, h, degree, stride, offset, degree + 3);
            const auto near = [](double x, double ref, double scale) {
              return std::abs(x - ref) <= 1e-9 * scale;
            };
            ASSERT_EQ(fit.samples, d.samples);
            const double vs = std::abs(d.value) + 1, ss = std::abs(d.slope) + 1;
            EXPECT_TRUE(near(fit.value, d.value, vs)) << degree << " " << stride << " " << h;
            EXPECT_TRUE(near(fit.slope, d.slope, ss)) << degree << " " << stride << " " << h;
            EXPECT_TRUE(near(fit.value_std, d.value_std, d.value_std));
            EXPECT_TRUE(near(fit.slope_std, d.slope_std, d.slope_std));
            EXPECT_TRUE(near(fit.residual_rms, d.residual_rms, d.residual_rms));
            EXPECT_TRUE(near(fit.value_change, std::abs(d1.value - d.value), vs));
            EXPECT_TRUE(near(fit.slope_change, std::abs(d2.slope - d.slope), ss));
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, 270);
}

}  // namespace
}  // namespace jointlab::signal
