#include "jointlab/model/iwan_cycle.h"

#include <vector>

#include <gtest/gtest.h>

#include "jointlab/tests/iwan_cycle_quadrature.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

using testing::Close;

// Both signs of chi, no macroslip delta and a large one (as iwan_test.cc), and chi 2.
const std::vector<IwanParameters> kSets = {{40.0, 2.0e6, -0.5, 1.0},
                                           {10.0, 5.0e5, -0.9, 0.0},
                                           {3.0, 1.0e4, 0.5, 4.0},
                                           {20.0, 1.0e6, 2.0, 0.5}};
const std::vector<double> kRatios = {1e-3, 0.1, 0.5, 0.9, 0.999, 1.0, 1.3, 4.0, 50.0};

TEST(IwanCycle, FirstHarmonicStiffnessMatchesTheMasingLoopByQuadrature) {
  // Micro- and macroslip amplitudes: the closed form with its Gauss-Legendre slip integral
  // against the exact hysteresis loop integrated in time (tests/iwan_cycle_quadrature.h,
  // ~1e-9); 1e-7 leaves a margin below the 1e-6 the QSMA columns are held to.
  for (const IwanParameters& p : kSets) {
    const Iwan iwan(p);
    const IwanCycle cycle(iwan);
    EXPECT_EQ(cycle.first_harmonic_stiffness(0.0), p.Kt);
    for (double ratio : kRatios) {
      const double a = ratio * iwan.phi_max();
      const double expected = testing::first_harmonic_by_quadrature(iwan, a);
      EXPECT_TRUE(Close(cycle.first_harmonic_stiffness(a), expected, 1e-7))
          << "chi " << p.chi << " A/phi_max " << ratio;
      EXPECT_EQ(cycle.first_harmonic_stiffness(-a), cycle.first_harmonic_stiffness(a));
    }
  }
}

// chi far above 0 (any chi > -1 is an element): the sliders gather at phi_max, s^chi at s = 1 in
// the slip integral, which 24 Gauss-Legendre nodes no longer resolve (J(1) 8e-4 off at chi 40,
// 13 % at 100), and past phi_max A^(chi+1) overflows (at 4 phi_max once chi exceeds about 510)
// where R A^(chi+1) J(phi_max / A) does not. phi_max about 1 m keeps R = F_S (chi+1) /
// (phi_max^(chi+2) (beta + c)) finite at chi 2000. Against the Masing loop by quadrature: 1e-7,
// as above (at chi 2000 and 4 phi_max its 2^16 intervals hold to 4e-11 of 2^20's); the slope
// against a central difference of step 1e-5 A (observed within 3e-9 of the slope at chi 400 and
// 2000; the quadrature's 6e-11 over a step of 1e-7 A would reach 1e-6), to 1e-6 of k / A.
TEST(IwanCycle, FirstHarmonicStiffnessHoldsForLargeChi) {
  for (const double chi : {40.0, 400.0, 2000.0}) {
    const Iwan iwan(IwanParameters{1.0e4, 1.0e4, chi, 1.0});
    const IwanCycle cycle(iwan);
    for (const double ratio : {0.5, 0.99, 1.3, 4.0}) {
      const double a = ratio * iwan.phi_max();
      double slope = 0;
      const double k = cycle.first_harmonic_stiffness(a, &slope);
      EXPECT_TRUE(Close(k, testing::first_harmonic_by_quadrature(iwan, a), 1e-7))
          << "chi " << chi << " A/phi_max " << ratio;
      const double h = 1e-5 * a;
      const double fd =
          (cycle.first_harmonic_stiffness(a + h) - cycle.first_harmonic_stiffness(a - h)) / (2 * h);
      EXPECT_NEAR(slope, fd, 1e-6 * k / a) << "chi " << chi << " A/phi_max " << ratio;
    }
  }
}

TEST(IwanCycle, FirstHarmonicSlopeIsTheDerivativeOfTheStiffness) {
  // Against a central difference of first_harmonic_stiffness with step h = 1e-5 A (away from
  // the kink at phi_max, ratio 1.0, where only one-sided derivatives exist): truncation
  // ~h^2 |k'''| / 6 ~ 1e-10 and rounding ~1e-16 k / h ~ 1e-11 of k / A, so 1e-7 of k / A
  // separates a wrong term (order k / A) by six decades.
  for (const IwanParameters& p : kSets) {
    const Iwan iwan(p);
    const IwanCycle cycle(iwan);
    for (double ratio : kRatios) {
      if (ratio == 1.0) continue;
      const double a = ratio * iwan.phi_max(), h = 1e-5 * a;
      const double fd =
          (cycle.first_harmonic_stiffness(a + h) - cycle.first_harmonic_stiffness(a - h)) / (2 * h);
      const double scale = cycle.first_harmonic_stiffness(a) / a;
      double slope = 0, slope_minus = 0;
      EXPECT_EQ(cycle.first_harmonic_stiffness(a, &slope), cycle.first_harmonic_stiffness(a));
      EXPECT_NEAR(slope, fd, 1e-7 * scale) << "chi " << p.chi << " A/phi_max " << ratio;
      cycle.first_harmonic_stiffness(-a, &slope_minus);
      EXPECT_EQ(slope_minus, -slope);
    }
  }
}

TEST(IwanCycle, TurningPointEnergyIsTheVirginWorkLessTheLoadingLoss) {
  // Loading along the virgin curve to A stores the turning-point energy and dissipates, in
  // every slider that slips, phi (A - phi): a quarter of one cycle's loss. So
  // E(A) = int_0^A F - D(A) / 4 (iwan.h closed forms; rounding only), and dE/dA = A F'(A)
  // (central differences, step 1e-6 A: truncation ~1e-12, rounding ~1e-10).
  for (const IwanParameters& p : kSets) {
    const Iwan iwan(p);
    const IwanCycle cycle(iwan);
    for (double ratio : kRatios) {
      const double a = ratio * iwan.phi_max();
      EXPECT_TRUE(
          Close(cycle.turning_point_energy(a), iwan.energy(a) - iwan.dissipation(a) / 4, 1e-12))
          << ratio;
      if (ratio == 1.0) continue;  // F' jumps from S to 0 there
      const double h = 1e-6 * a;
      const double slope =
          (cycle.turning_point_energy(a + h) - cycle.turning_point_energy(a - h)) / (2 * h);
      EXPECT_TRUE(Close(slope, a * iwan.tangent(a), 1e-7, 1e-9 * p.Kt * a)) << ratio;
    }
  }
}

}  // namespace
}  // namespace jointlab::model
