#include "jointlab/model/iwan.h"

#include <array>
#include <cmath>
#include <vector>

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

using testing::Close;

// Parameter sets covering both signs of chi, no macroslip delta and a large one.
const std::vector<IwanParameters> kSets = {
    {40.0, 2.0e6, -0.5, 1.0}, {10.0, 5.0e5, -0.9, 0.0}, {3.0, 1.0e4, 0.5, 4.0}};

// Composite Simpson integral of f on [a, b] with n (even) intervals.
template <typename F>
double simpson(F f, double a, double b, int n) {
  const double h = (b - a) / n;
  double sum = f(a) + f(b);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * f(a + i * h);
  return sum * h / 3.0;
}

TEST(Iwan, ParametersDefineAConsistentSliderDensity) {
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    // K_T is the total slider stiffness int rho = R phi_max^(chi+1)/(chi+1) + S (exact algebra;
    // 1e-13 allows for rounding in the pow calls).
    EXPECT_TRUE(Close(iwan.R() * std::pow(iwan.phi_max(), p.chi + 1) / (p.chi + 1) + iwan.S(), p.Kt,
                      1e-13));
    // The virgin curve reaches F_S exactly at phi_max from below, and stays there.
    EXPECT_TRUE(Close(iwan.force(iwan.phi_max() * (1 - 1e-12)), p.Fs, 1e-10));
    EXPECT_EQ(iwan.force(2 * iwan.phi_max()), p.Fs);
    EXPECT_EQ(iwan.force(-2 * iwan.phi_max()), -p.Fs);
    // Tangent at the end of microslip is the delta's weight S.
    EXPECT_TRUE(Close(iwan.tangent(iwan.phi_max() * (1 - 1e-14)), iwan.S(), 1e-6, 1e-9 * p.Kt));
    EXPECT_EQ(iwan.tangent(0.0), p.Kt);
    EXPECT_EQ(iwan.force(0.0), 0.0);
  }
}

TEST(Iwan, VirginForceEqualsTheSliderIntegral) {
  // F(u) = int_0^u phi rho + u int_u^phimax rho + S min(u, phimax): an independent route
  // through the slider density, integrated numerically after the substitution
  // phi = t^(1/(chi+1)) that removes the phi^chi singularity. The integrand t^(1/(chi+1))
  // is still not smooth at t = 0 when chi > 0 (Simpson then converges as h^(1+1/(chi+1)),
  // about 1e-8 with 4000 intervals): 1e-7 relative.
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    const double e = 1.0 / (p.chi + 1);
    for (double frac : {0.01, 0.3, 0.77, 0.999}) {
      const double u = frac * iwan.phi_max();
      // rho dphi = R phi^chi dphi = R/(chi+1) dt with t = phi^(chi+1).
      const double k = iwan.R() / (p.chi + 1);
      const double tu = std::pow(u, p.chi + 1), tm = std::pow(iwan.phi_max(), p.chi + 1);
      const double slipped = simpson([&](double t) { return k * std::pow(t, e); }, 0, tu, 4000);
      const double stuck = u * k * (tm - tu);
      EXPECT_TRUE(Close(iwan.force(u), slipped + stuck + iwan.S() * u, 1e-7)) << frac;
    }
  }
}

TEST(Iwan, TangentEnergyAndSofteningAreConsistentDerivatives) {
  // Central differences with step 1e-6 phi_max: truncation ~1e-12 relative, rounding
  // ~1e-10; 1e-7 relative leaves margin for the u^(chi+1) curvature.
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    const double h = 1e-6 * iwan.phi_max();
    for (double frac : {-0.8, -0.1, 0.05, 0.5, 0.95, 1.5}) {
      const double u = frac * iwan.phi_max();
      const double dF = (iwan.force(u + h) - iwan.force(u - h)) / (2 * h);
      const double dE = (iwan.energy(u + h) - iwan.energy(u - h)) / (2 * h);
      const double dH = (iwan.softening_energy(u + h) - iwan.softening_energy(u - h)) / (2 * h);
      EXPECT_TRUE(Close(iwan.tangent(u), dF, 1e-7, 1e-9 * p.Kt)) << frac;
      EXPECT_TRUE(Close(iwan.force(u), dE, 1e-7, 1e-12 * p.Fs)) << frac;
      EXPECT_TRUE(Close(iwan.softening(u), dH, 1e-7, 1e-9 * p.Fs)) << frac;
      EXPECT_TRUE(Close(iwan.softening_tangent(u), p.Kt - iwan.tangent(u), 1e-15, 1e-15 * p.Kt));
    }
  }
}

TEST(Iwan, DissipationIsTheMasingAreaOnBothBranches) {
  // D(A) = 8 int_0^A F du - 4 A F(A), integrated numerically: Simpson on [0, min(A, phi_max)]
  // (F is C^1 there; its u^(chi+2) term limits Simpson to about h^(chi+3), below 1e-8
  // with 20000 intervals), exactly on the constant macroslip part. 1e-6 relative.
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    const double pm = iwan.phi_max();
    for (double frac : {0.02, 0.4, 0.9, 1.0, 1.3, 4.0}) {
      const double A = frac * pm;
      const double a1 = std::min(A, pm);
      double integral = simpson([&](double u) { return iwan.force(u); }, 0, a1, 20000);
      if (A > pm) integral += p.Fs * (A - pm);
      const double masing = 8 * integral - 4 * A * iwan.force(A);
      EXPECT_TRUE(Close(iwan.dissipation(A), masing, 1e-6, 1e-12 * p.Fs * pm)) << frac;
      EXPECT_EQ(iwan.dissipation(-A), iwan.dissipation(A));
    }
    // Continuous at phi_max (both closed forms meet): 1e-12 relative, rounding only.
    EXPECT_TRUE(Close(iwan.dissipation(pm * (1 - 1e-15)), iwan.dissipation(pm), 1e-12));
    // Deep macroslip: the loop is a rectangle of height 2 F_S minus the rounded corners,
    // so D/A -> 4 F_S.
    EXPECT_TRUE(Close(iwan.dissipation(1e6 * pm) / (1e6 * pm), 4 * p.Fs, 1e-5));
  }
}

TEST(Iwan, JetGivesExactDerivativesInDisplacementAndParameters) {
  using J = ceres::Jet<double, 5>;  // d/du, d/dFs, d/dKt, d/dchi, d/dbeta
  const IwanParameters p = kSets[0];
  const BasicIwan<J> jiwan(J(p.Fs, 1), J(p.Kt, 2), J(p.chi, 3), J(p.beta, 4));
  const Iwan iwan(p);
  // Central differences in each of the five variables; relative step 1e-6:
  // truncation ~1e-12, rounding ~1e-10 -> compare at 1e-6.
  auto with = [&](int k, double d) {
    IwanParameters q = p;
    double u = 0.6 * iwan.phi_max();
    if (k == 0) u += d;
    if (k == 1) q.Fs += d;
    if (k == 2) q.Kt += d;
    if (k == 3) q.chi += d;
    if (k == 4) q.beta += d;
    const Iwan e(q);
    return std::array<double, 3>{e.force(u), e.dissipation(u), e.tangent(u)};
  };
  const J u(0.6 * iwan.phi_max(), 0);
  const J f = jiwan.force(u), d = jiwan.dissipation(u), t = jiwan.tangent(u);
  EXPECT_EQ(f.a, iwan.force(u.a));
  EXPECT_EQ(d.a, iwan.dissipation(u.a));
  const double scale[5] = {iwan.phi_max(), p.Fs, p.Kt, 1.0, 1.0};
  for (int k = 0; k < 5; ++k) {
    const double h = 1e-6 * scale[k];
    const auto up = with(k, h), dn = with(k, -h);
    EXPECT_TRUE(Close(f.v[k], (up[0] - dn[0]) / (2 * h), 1e-6, 1e-9 * std::abs(f.a / scale[k])))
        << k;
    EXPECT_TRUE(Close(d.v[k], (up[1] - dn[1]) / (2 * h), 1e-6, 1e-9 * std::abs(d.a / scale[k])))
        << k;
    EXPECT_TRUE(Close(t.v[k], (up[2] - dn[2]) / (2 * h), 1e-6, 1e-9 * std::abs(t.a / scale[k])))
        << k;
  }
}

// chi above 0 (method.md's domain, -1 < chi): at chi 0.5 and 2 the parameters are valid and the
// element follows method.md's closed forms, written out here with c = (chi+1)/(chi+2):
// phi_max = F_S (1+beta) / (K_T (beta+c)), F(u) = K_T u - R u^(chi+2) / ((chi+1)(chi+2)),
// D(A) = 4 R A^(chi+3) / ((chi+2)(chi+3)), E_max = K_T phi_max^2/2 - R phi_max^(chi+3) /
// ((chi+1)(chi+2)(chi+3)) (1e-12 relative: the same algebra, rounding only); and, by routes
// that do not use them, F reaches F_S at phi_max with tangent K_T beta / (1+beta) there (1e-9:
// one-sided difference 1e-10 phi_max below phi_max), E_max is the Simpson integral of F on
// [0, phi_max] and D(A) the Masing area 8 int_0^A F - 4 A F(A) (2000 intervals on a C^2
// integrand for chi >= 0: error ~h^4, 1e-9 relative allowed).
TEST(Iwan, ChiAboveZeroFollowsTheClosedForms) {
  for (const double chi : {0.5, 2.0}) {
    const IwanParameters p{40.0, 2.0e6, chi, 1.5};
    ASSERT_EQ(iwan_parameter_error(p), "") << chi;
    const Iwan iwan(p);
    const double c = (chi + 1) / (chi + 2);
    const double pm = p.Fs * (1 + p.beta) / (p.Kt * (p.beta + c));
    const double R = p.Fs * (chi + 1) / (std::pow(pm, chi + 2) * (p.beta + c));
    EXPECT_TRUE(Close(iwan.phi_max(), pm, 1e-12)) << chi;
    EXPECT_TRUE(Close(iwan.R(), R, 1e-12)) << chi;
    for (const double frac : {0.01, 0.3, 0.9}) {
      const double u = frac * pm;
      EXPECT_TRUE(Close(iwan.force(u),
                        p.Kt * u - R * std::pow(u, chi + 2) / ((chi + 1) * (chi + 2)), 1e-12))
          << chi << " " << frac;
      EXPECT_TRUE(
          Close(iwan.dissipation(u), 4 * R * std::pow(u, chi + 3) / ((chi + 2) * (chi + 3)), 1e-12))
          << chi << " " << frac;
      if (frac < 0.1) continue;  // below, D is the small difference of 8 int F and 4 u F
      const double masing =
          8 * simpson([&](double x) { return iwan.force(x); }, 0, u, 2000) - 4 * u * iwan.force(u);
      EXPECT_TRUE(Close(iwan.dissipation(u), masing, 1e-9)) << chi << " " << frac;
    }
    const double e_max =
        p.Kt * pm * pm / 2 - R * std::pow(pm, chi + 3) / ((chi + 1) * (chi + 2) * (chi + 3));
    EXPECT_TRUE(Close(iwan.energy(pm), e_max, 1e-12)) << chi;
    EXPECT_TRUE(Close(e_max, simpson([&](double x) { return iwan.force(x); }, 0, pm, 2000), 1e-9))
        << chi;
    EXPECT_TRUE(Close(iwan.force(pm * (1 - 1e-12)), p.Fs, 1e-9)) << chi;
    EXPECT_TRUE(Close(iwan.tangent(pm * (1 - 1e-10)), p.Kt * p.beta / (1 + p.beta), 1e-9)) << chi;
  }
}

TEST(Iwan, ParameterErrorsNameTheField) {
  EXPECT_EQ(iwan_parameter_error({40, 2e6, -0.5, 1}), "");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, -0.5, 0}), "");
  EXPECT_EQ(iwan_parameter_error({0, 2e6, -0.5, 1}), "Fs = 0 must be > 0");
  EXPECT_EQ(iwan_parameter_error({40, -1, -0.5, 1}), "Kt = -1 must be > 0");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, -1, 1}), "chi = -1 must be > -1");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, -1.5, 1}), "chi = -1.5 must be > -1");
  // chi above 0 is an element too (method.md: -1 < chi): more sliders at large slip
  // displacements, F'(phi_max) = K_T beta / (1 + beta) >= 0 whatever chi.
  EXPECT_EQ(iwan_parameter_error({40, 2e6, 0.5, 1}), "");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, 2, 1}), "");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, 1e6, 1}), "");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, 0, 1}), "");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, INFINITY, 1}), "chi = inf must be a finite number > -1");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, NAN, 1}), "chi = nan must be a finite number > -1");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, -0.5, INFINITY}),
            "beta = inf must be a finite number >= 0");
  EXPECT_EQ(iwan_parameter_error({40, INFINITY, -0.5, 1}), "Kt = inf must be a finite number > 0");
  EXPECT_EQ(iwan_parameter_error({NAN, 2e6, -0.5, 1}), "Fs = nan must be a finite number > 0");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, -INFINITY, 1}),
            "chi = -inf must be a finite number > -1");
  EXPECT_EQ(iwan_parameter_domain("chi").text(), "> -1");
  EXPECT_EQ(iwan_parameter_domain("Kt").text(), "> 0");
  EXPECT_EQ(iwan_parameter_error({40, 2e6, -0.5, -0.1}), "beta = -0.1 must be >= 0");
}

}  // namespace
}  // namespace jointlab::model
