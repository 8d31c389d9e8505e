#include "jointlab/model/iwan_hysteresis.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

using testing::Close;

// chi 2 too: any chi > -1 is an element, and the first-harmonic tests take this as reference.
const IwanParameters kSets[] = {
    {40.0, 2.0e6, -0.5, 1.0}, {10.0, 5.0e5, -0.8, 0.0}, {5.0, 1.0e5, 2.0, 0.5}};

// The closed-form segment integrals differ from the closed-form virgin curve only by
// rounding in pow: 1e-11 relative to F_S.
constexpr double kExact = 1e-11;

TEST(IwanHysteresis, VirginLoadingFollowsTheVirginCurve) {
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    IwanHysteresis h(iwan);
    for (double frac = 0.01; frac < 2.0; frac += 0.07) {
      const double u = frac * iwan.phi_max();
      EXPECT_TRUE(Close(h.update(u), iwan.force(u), kExact, kExact * p.Fs)) << frac;
    }
  }
}

TEST(IwanHysteresis, ReversalBranchesObeyMasing) {
  // After a reversal at (u_r, F_r): F = F_r - 2 F((u_r - u)/2) going down, then back on the
  // virgin curve (mirrored) once u passes -u_r.
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    for (double ur_frac : {0.3, 0.9, 1.7}) {
      IwanHysteresis h(iwan);
      const double ur = ur_frac * iwan.phi_max();
      const double fr = h.update(ur);
      for (double u = ur; u > -2.5 * ur; u -= 0.05 * ur) {
        const double expected = u >= -ur ? fr - 2 * iwan.force((ur - u) / 2) : iwan.force(u);
        EXPECT_TRUE(Close(h.update(u), expected, kExact, kExact * p.Fs)) << ur_frac << " " << u;
      }
    }
  }
}

TEST(IwanHysteresis, ClosedInnerLoopIsWipedOut) {
  const Iwan iwan(kSets[0]);
  IwanHysteresis h(iwan);
  const double pm = iwan.phi_max();
  h.update(0.6 * pm);
  h.update(-0.2 * pm);
  h.update(0.3 * pm);
  EXPECT_GT(h.memory(), 3);
  h.update(0.1 * pm);  // inner loop inside the first unloading branch
  h.update(0.8 * pm);  // passes both earlier maxima: back on the virgin curve
  EXPECT_TRUE(Close(h.force(), iwan.force(0.8 * pm), kExact, kExact * iwan.slip_force()));
  EXPECT_EQ(h.memory(), 2);
}

TEST(IwanHysteresis, SteadyLoopAreaIsTheClosedFormDissipation) {
  // Trapezoid rule over 20000 steps of the branch A -> -A -> A: the force is C^1 between
  // the reversals, error ~1e-8 relative.
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    for (double frac : {0.1, 0.8, 1.0, 2.5}) {
      const double A = frac * iwan.phi_max();
      IwanHysteresis h(iwan);
      h.update(A);
      const int n = 10000;
      double area = 0, u_prev = A, f_prev = h.force();
      for (int leg = 0; leg < 2; ++leg) {
        for (int i = 1; i <= n; ++i) {
          const double u = leg == 0 ? A - 2 * A * i / n : -A + 2 * A * i / n;
          const double f = h.update(u);
          area += 0.5 * (f + f_prev) * (u - u_prev);
          u_prev = u;
          f_prev = f;
        }
      }
      // Hysteresis loops run clockwise in (u, F): the work int F du over a cycle is +D.
      EXPECT_TRUE(Close(area, iwan.dissipation(A), 1e-6)) << frac;
    }
  }
}

TEST(IwanHysteresis, MatchesAFineJenkinsDiscretisation) {
  // Second method: N Jenkins sliders in bins of equal stiffness (t = phi^(chi+1) uniform),
  // each at the slip displacement of its bin's midpoint in t, plus the macroslip slider.
  // Midpoint quadrature in t converges as 1/N^2 away from the reversal kinks and 1/N at
  // them: 2e-4 F_S for N = 20000 under a random history.
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    const int n = 20000;
    const double tmax = std::pow(iwan.phi_max(), p.chi + 1);
    const double w = iwan.R() / (p.chi + 1) * tmax / n;
    std::vector<double> phi(n + 1), weight(n + 1, w), s(n + 1, 0.0);
    for (int i = 0; i < n; ++i) phi[i] = std::pow((i + 0.5) * tmax / n, 1 / (p.chi + 1));
    phi[n] = iwan.phi_max();
    weight[n] = iwan.S();

    IwanHysteresis h(iwan);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> step(-0.6, 0.6);
    double u = 0;
    for (int k = 0; k < 60; ++k) {
      const double u_new =
          std::clamp(u + step(rng) * iwan.phi_max(), -1.5 * iwan.phi_max(), 1.5 * iwan.phi_max());
      const double d = u_new - u;
      double f = 0;
      for (int i = 0; i <= n; ++i) {
        s[i] = std::clamp(s[i] + d, -phi[i], phi[i]);
        f += weight[i] * s[i];
      }
      u = u_new;
      EXPECT_TRUE(Close(h.update(u), f, 0.0, 2e-4 * p.Fs)) << k;
    }
  }
}

}  // namespace
}  // namespace jointlab::model
