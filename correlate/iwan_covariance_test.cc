// The Iwan update's uncertainties: sigmas at and past phi_max, under dense sampling and
// correlated noise, and none from a fit that did not converge.
#include "jointlab/correlate/iwan_update.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/correlate/iwan_covariance_detail.h"
#include "jointlab/correlate/iwan_update_test_fixtures.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/two_chain.h"

namespace jointlab::correlate {
namespace {

using iwan_test::box_around;
using iwan_test::FloorTruth;
using iwan_test::modal_backbone;

// The same curve ten times more densely: linear interpolation in ln q of every column.
MeasuredBackbone denser(const MeasuredBackbone& b, int factor) {
  const Eigen::Index n = b.amplitude.size(), m = (n - 1) * factor + 1;
  MeasuredBackbone d = sized_backbone(b.kind, b.sensor, m);
  d.modal = b.modal;
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Index k = std::min(i / factor, n - 2);
    const double w = static_cast<double>(i - k * factor) / factor;
    auto lerp = [&](const Eigen::VectorXd& v) { return (1 - w) * v(k) + w * v(k + 1); };
    d.amplitude(i) =
        std::exp((1 - w) * std::log(b.amplitude(k)) + w * std::log(b.amplitude(k + 1)));
    d.frequency_hz(i) = lerp(b.frequency_hz);
    d.damping_ratio(i) = lerp(b.damping_ratio);
    d.frequency_std_hz(i) = lerp(b.frequency_std_hz);
    d.damping_std(i) = lerp(b.damping_std);
  }
  return d;
}

// A measured amplitude on the fitted phi_max (a kink of the model, where minima like to sit):
// beta's sigma must not come out far below that of the same data with the point just past it
// (a Monte Carlo found 3-4 times too small a sigma in 7 of 40 fits, the central difference
// straddling the kink). Noiseless hits of the one-mode truth reaching 1.2 and 1.6 phi_max and a
// third exactly phi_max (or 1.001 phi_max), the fit started at the truth. Measured: 0.0126 on,
// 0.0121 past; with the central difference alone 0.00367 on, 3.3 times too small.
TEST(IwanUpdate, APointOnPhiMaxDoesNotShrinkBetasSigma) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  const auto beta_sigma = [&](double third_top) {
    IwanTarget target;
    for (const double top : {1.2 * phi, 1.6 * phi, third_top})
      target.curves.push_back(modal_backbone(truth, 30, 1e-8, top, 0, 0, 1));
    IwanUpdateOptions o;
    o.bounds = box_around(t.iwan);
    o.max_evaluations = 600;
    const IwanObjective obj(truth, "j", {}, {target}, o);
    IwanUpdateSummary s;
    const model::IwanParameters p = update_iwan(obj, o, &s);
    EXPECT_NEAR(p.beta, t.iwan.beta, 1e-3 * t.iwan.beta) << s.report();
    return s.relative_std(3);
  };
  const double on = beta_sigma(phi), past = beta_sigma(1.001 * phi);
  RecordProperty("beta_sigma_on_past", fmt::format("{} {}", on, past));
  std::printf("beta sigma with a point on phi_max %.3g, just past it %.3g\n", on, past);
  ASSERT_GT(past, 0);
  EXPECT_GT(on, 0.7 * past);
}

// A point a little past the fitted phi_max lies on the steep branch of the ring-down damping
// there, and its slope 1e-4 away pins phi_max as if that branch went on; a little further the
// point is back on the shallow branch, where the cost has another minimum about as low. Six
// points of the one-mode truth, three times apart in q, the fifth at 0.9 phi_max and the sixth
// at 2.7 phi_max (1e-4 frequency and 2 % damping noise, 20 seeds, start F_S x1.5, K_T x0.9, chi
// -0.4, beta 0.8): before the probe two sigmas out, seed 17 put F_S 5.8 % off with 0.61 % stated
// (z -9.5) and beta 23 % off with 4.2 % (z +5.4); now the largest |z| is 2.1 (F_S) and 2.5
// (beta), and a fit whose direction only the kink fixes states no sigma for it. Acceptance: every
// stated |z| below 3.5 (a sigma off by the old factor of 4 fails it; 30 honest fits pass with
// room), RMS z below 1.5 (30 seeds: 0.65-1.06 per parameter).
TEST(IwanUpdate, APointJustPastPhiMaxDoesNotPinItsSigma) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const model::Model start =
      one_mode_structure(t.k0, {t.iwan.Fs * 1.5, t.iwan.Kt * 0.9, -0.4, 0.8}, 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.threads = 1;
  const double truth_p[] = {t.iwan.Fs, t.iwan.Kt, t.iwan.chi, t.iwan.beta};
  double sum2 = 0;
  int stated = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    IwanTarget target;
    target.curves.push_back(modal_backbone(truth, 6, 0.9 * phi / 81, 2.7 * phi, 1e-4, 0.02, seed));
    const IwanObjective obj(start, "j", {}, {target}, o);
    IwanUpdateSummary s;
    const model::IwanParameters p = update_iwan(obj, o, &s);
    const double found[] = {p.Fs, p.Kt, p.chi, p.beta};
    for (int k = 0; k < 4; ++k) {
      if (!(s.relative_std(k) > 0)) continue;
      const double z = k == 2 ? (found[k] - truth_p[k]) / (std::abs(found[k]) * s.relative_std(k))
                              : (found[k] / truth_p[k] - 1) / s.relative_std(k);
      EXPECT_LT(std::abs(z), 3.5) << "seed " << seed << " parameter " << k << "\n" << s.report();
      sum2 += z * z;
      ++stated;
    }
  }
  ASSERT_GT(stated, 40);
  EXPECT_LT(std::sqrt(sum2 / stated), 1.5);
}

// The sigma does not shrink with sampling density (method.md section 2 point 5): the same
// noisy curve resampled ten times more densely gives each sigma within 30 % of the sparse
// fit's, where independent-point (Gauss-Newton) sigma would shrink by sqrt(10) = 3.2.
TEST(IwanUpdate, SigmaDoesNotDependOnTheSamplingDensity) {
  const FloorTruth t;
  const IwanTarget sparse = t.target(40, 1);
  IwanTarget dense = sparse;
  dense.curves[0] = denser(sparse.curves[0], 10);
  IwanUpdateSummary ss, sd;
  const model::Model start = t.start();
  IwanUpdateOptions o = t.options();
  o.max_evaluations = 3000;
  update_iwan(IwanObjective(start, "j", {}, {sparse}, o), o, &ss);
  update_iwan(IwanObjective(start, "j", {}, {dense}, o), o, &sd);
  std::printf("sparse:\n%sdense:\n%s", ss.report().c_str(), sd.report().c_str());
  for (int k = 0; k < 4; ++k) {
    ASSERT_GT(ss.relative_std(k), 0) << k;
    EXPECT_NEAR(sd.relative_std(k) / ss.relative_std(k), 1.0, 0.3) << k;
    RecordProperty("sigma_ratio_" + std::to_string(k),
                   std::to_string(sd.relative_std(k) / ss.relative_std(k)));
  }
  ASSERT_GT(ss.modal_ratio_std, 0);
  EXPECT_NEAR(sd.modal_ratio_std / ss.modal_ratio_std, 1.0, 0.3);
}

// Sigma under strongly correlated noise (method.md section 2 point 5): one 200-point curve of
// the one-mode truth up to twice phi_max whose noise (1e-4 f, 2 % zeta, stated as such) is
// AR(1) with rho 0.95 along the points (correlation time 39 points, about 5 independent points
// per frequency or damping sequence). Over 12 seeds the z-scores (error / stated sigma) of K_T
// and chi, pooled, must have a root mean square within 0.6-1.5: one sigma means one sigma, the
// upper limit with room for 24 draws (the RMS of 24 standard normals lies within 0.7-1.3 at
// 95 %), the lower one against a sigma inflated far past the spread. Measured: RMS 1.86 before
// the bias-corrected AR(1) covariance (HAC and tau from the residuals alone), 1.30 with it, 1.27
// with the floor taken last and t at n_eff - p.
TEST(IwanUpdate, SigmaHoldsUnderStronglyCorrelatedNoise) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const model::Model start = one_mode_structure(t.k0, t.near(), 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.max_evaluations = 600;
  double sum = 0;
  int count = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    IwanTarget target;
    target.curves.push_back(modal_backbone(truth, 200, 1e-8, 2 * phi, 1e-4, 0.02, seed, 0.95));
    const IwanObjective obj(start, "j", {}, {target}, o);
    IwanUpdateSummary s;
    const model::IwanParameters p = update_iwan(obj, o, &s);
    ASSERT_TRUE(s.improved) << s.report();
    ASSERT_GT(s.relative_std(1), 0) << s.report();
    ASSERT_GT(s.relative_std(2), 0) << s.report();
    const double z_kt = std::log(p.Kt / t.iwan.Kt) / s.relative_std(1);
    const double z_chi = (p.chi - t.iwan.chi) / (s.relative_std(2) * std::abs(p.chi));
    std::printf("seed %u: z K_T %+.2f, z chi %+.2f, effective points %.3g\n", seed, z_kt, z_chi,
                s.effective_points);
    sum += z_kt * z_kt + z_chi * z_chi;
    count += 2;
  }
  const double rms = std::sqrt(sum / count);
  RecordProperty("z_rms", std::to_string(rms));
  std::printf("RMS z of K_T and chi over 12 seeds: %.3g\n", rms);
  EXPECT_GT(rms, 0.6);
  EXPECT_LT(rms, 1.5);
}

// A fit that does not converge states no sigma and says so, whatever its chi-square: a budget of
// the 100 samples alone leaves no local solve, and the polish of the best sample (100 more
// evaluations) stops short of the tolerance. Before, such fits stated sigmas at the point the
// budget left them (the cantilever: chi 4.6 sigma off at reduced chi-square 0.68, no warning).
TEST(IwanUpdate, AFitThatDidNotConvergeStatesNoSigma) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  IwanTarget target;
  target.curves.push_back(modal_backbone(truth, 60, 1e-8, 2 * phi, 1e-4, 0.02, 3));
  const model::Model start =
      one_mode_structure(t.k0, {t.iwan.Fs * 3, t.iwan.Kt * 0.8, -0.3, 2.0}, 0.0);
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.max_evaluations = o.samples;
  const IwanObjective obj(start, "j", {}, {target}, o);
  IwanUpdateSummary s;
  update_iwan(obj, o, &s);
  SCOPED_TRACE(s.report());
  ASSERT_TRUE(s.improved);
  ASSERT_EQ(s.status, IwanUpdateStatus::kBudget);
  EXPECT_EQ(s.relative_std, Eigen::Vector4d::Zero());
  EXPECT_EQ(s.covariance, Eigen::Matrix4d::Zero());
  EXPECT_NE(s.report().find("Iwan update: not converged"), std::string::npos);
  EXPECT_NE(s.report().find("(no sigma: not converged)"), std::string::npos);
  EXPECT_NE(s.report().find("WARNING: the fit did not converge"), std::string::npos);
  EXPECT_NE(s.report().find("run again with a larger --evaluations (e.g. "), std::string::npos);
}

// Where scatter between three hits explains the misfit, the sigmas take Student's t over the hits
// less 1 (2 degrees of freedom: the square of its 95 % quantile over the normal's, (4.303 /
// 1.960)^2 = 4.82) in place of the points' nu / (nu - 2), which covariance() put in. That is a
// widening only where the points have more degrees of freedom: between 2 and 2.52 of them their
// own factor exceeds 4.82, and the swap narrowed the covariance, by 0.80 at 2.4 (a sigma 10 %
// smaller) and toward 0 near 2. The stated covariance is never below the points' own (exact:
// the factor is 1 there, so 1e-12 for rounding), and with many points it is 4.82 times theirs.
TEST(IwanUpdate, WideningForScatterBetweenHitsNeverNarrows) {
  IwanUpdateSummary s;
  s.improved = true;
  s.residuals = 180;
  s.reduced_chi2 = 9;  // a misfit
  s.hits = 3;
  s.evidence = MisfitEvidence{};
  s.evidence->curves = 3;
  s.evidence->between_curves_share = 0.9;
  ASSERT_TRUE(s.scatter_explains_misfit());
  const double t2 = std::pow(4.302652729911275 / 1.959963984540054, 2);
  for (const double nu : {2.05, 2.2, 2.4, 2.5, 2.52, 2.6, 3.0, 5.0, 50.0}) {
    s.sigma_degrees_of_freedom = nu;
    Eigen::MatrixXd cov = Eigen::MatrixXd::Identity(2, 2);
    iwan_detail::widen_for_scatter(s, cov);
    EXPECT_GE(cov(0, 0), 1 - 1e-12) << nu;
    EXPECT_NEAR(cov(0, 0), std::max(1.0, t2 / (nu / (nu - 2))), 1e-9) << nu;
    EXPECT_EQ(cov(0, 1), 0.0) << nu;
  }
}

}  // namespace
}  // namespace jointlab::correlate
