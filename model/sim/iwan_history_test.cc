#include "jointlab/model/sim/iwan_history.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/model/iwan_hysteresis.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

using testing::Close;

const IwanParameters kSets[] = {
    {40.0, 2.0e6, -0.5, 1.0}, {10.0, 5.0e5, -0.8, 0.0}, {5.0, 1.0e5, 0.3, 0.2}};

// A history with reversals of random size, some past phi_max, and a decaying stretch
// (nested loops that never close, the memory a ring-down builds).
std::vector<double> random_history(double pm, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> u{0.0};
  double x = 0, dir = 1;
  for (int rev = 0; rev < 60; ++rev) {
    const double target = dir * pm * 1.6 * unit(rng) * unit(rng);
    const int n = 3 + static_cast<int>(10 * unit(rng));
    for (int i = 1; i <= n; ++i) u.push_back(x + (target - x) * i / n);
    x = target, dir = -dir;
  }
  for (int rev = 0; rev < 40; ++rev) {
    const double target = (rev % 2 ? -1 : 1) * 0.5 * pm * std::pow(0.93, rev);
    for (int i = 1; i <= 5; ++i) u.push_back(x + (target - x) * i / 5);
    x = target;
  }
  return u;
}

// Both implementations integrate the same piecewise-linear slider state in closed form;
// they differ by rounding in pow and in the order of sums: 1e-10 of F_S.
constexpr double kForceTol = 1e-10;

TEST(IwanHistory, ForcesMatchTheReferenceHysteresis) {
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    for (unsigned seed : {1u, 2u, 3u}) {
      IwanHistory h(iwan);
      IwanHysteresis ref(iwan);
      for (double u : random_history(iwan.phi_max(), seed)) {
        const double f_ref = ref.update(u);
        const double f_trial = h.trial(u).force;
        const double f = h.commit(u).force;
        ASSERT_EQ(f, f_trial);
        ASSERT_TRUE(Close(f, f_ref, 0, kForceTol * p.Fs)) << u;
        ASSERT_TRUE(Close(h.force_from_state(), f_ref, 0, kForceTol * p.Fs)) << u;
      }
      EXPECT_LE(h.memory(), ref.memory() + 1);
    }
  }
}

TEST(IwanHistory, TangentIsTheDerivativeOfTheTrialForce) {
  // Central differences of the trial force inside a move; the force is smooth there
  // (C^1 with a bounded second derivative away from phi* = 0), so a step of 1e-6 of the
  // move leaves a truncation error of order 1e-12 relative and rounding 1e-10 / 1e-6.
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    const double pm = iwan.phi_max();
    IwanHistory h(iwan);
    for (double u : {0.7 * pm, -0.3 * pm, 0.2 * pm}) h.commit(u);
    for (double d : {0.05, 0.4, -0.1, -0.6, -1.1, -1.5}) {  // none on a kink
      const double u = 0.2 * pm + d * pm, eps = 1e-6 * std::abs(d) * pm;
      const double fd = (h.trial(u + eps).force - h.trial(u - eps).force) / (2 * eps);
      EXPECT_TRUE(Close(h.trial(u).tangent, fd, 1e-5, 1e-5 * p.Kt)) << d;
    }
  }
}

TEST(IwanHistory, WorkIsTheIntegralOfTheForce) {
  // Composite Simpson over 2000 panels. Right after the reversal the force goes as
  // K_T d - c d^(chi+2), so the rule's error falls only as h^(chi+3) (h^2.2 for chi = -0.8):
  // about 1e-8 of the work; 1e-6 leaves room.
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    const double pm = iwan.phi_max();
    IwanHistory h(iwan);
    for (double u : {0.5 * pm, -0.2 * pm}) h.commit(u);
    for (double target : {0.1 * pm, 0.9 * pm, 2.0 * pm, -0.5 * pm, -1.5 * pm}) {
      const double u0 = h.displacement();
      const int n = 2000;
      const double step = (target - u0) / n;
      double sum = h.trial(u0).force + h.trial(target).force;
      for (int i = 1; i < n; ++i) sum += (i % 2 ? 4 : 2) * h.trial(u0 + i * step).force;
      const double simpson = sum * step / 3;
      EXPECT_TRUE(Close(h.trial(target).work, simpson, 1e-6, 1e-9 * p.Fs * pm)) << target;
    }
  }
}

TEST(IwanHistory, EnergyIsStoredOrDissipated) {
  // Stored energy kept move by move equals the slider state's integral, and stored plus
  // dissipated equals the work done on the element; dissipation never decreases.
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    const double scale = p.Fs * iwan.phi_max();
    IwanHistory h(iwan);
    double work = 0, last_dissipated = 0;
    for (double u : random_history(iwan.phi_max(), 7)) {
      work += h.commit(u).work;
      ASSERT_GE(h.dissipated_energy(), last_dissipated);
      last_dissipated = h.dissipated_energy();
      ASSERT_TRUE(Close(h.stored_energy(), h.stored_energy_from_state(), 1e-9, 1e-11 * scale));
      ASSERT_TRUE(Close(h.stored_energy() + h.dissipated_energy(), work, 1e-9, 1e-11 * scale));
    }
  }
}

TEST(IwanHistory, SymmetricCycleDissipatesTheClosedForm) {
  // After the first quarter cycle the loop A -> -A -> A is a Masing loop of amplitude A:
  // its dissipation is D(A) of iwan.h, in microslip and in macroslip.
  for (const auto& p : kSets) {
    const Iwan iwan(p);
    for (double frac : {1e-3, 0.05, 0.5, 0.99, 1.5}) {
      const double A = frac * iwan.phi_max();
      IwanHistory h(iwan);
      h.commit(A);
      const double before = h.dissipated_energy();
      for (int i = 1; i <= 40; ++i) h.commit(A * std::cos(M_PI * i / 20));  // one cycle
      const double cycle = h.dissipated_energy() - before;
      EXPECT_TRUE(Close(cycle, iwan.dissipation(A), 1e-9)) << frac;
      // Stored energy returns to its value at the same point of the loop.
      EXPECT_TRUE(Close(h.force(), iwan.force(A), 1e-10, 1e-12 * p.Fs));
    }
  }
}

TEST(IwanHistory, MacroslipCarriesTheSlipForceWithZeroTangent) {
  const Iwan iwan(kSets[0]);
  IwanHistory h(iwan);
  const IwanMove m = h.trial(1.3 * iwan.phi_max());
  EXPECT_EQ(m.force, iwan.slip_force());
  EXPECT_EQ(m.tangent, 0.0);
  EXPECT_EQ(h.trial(0.0).tangent, iwan.stiffness());  // no move: every slider sticks
  h.commit(2 * iwan.phi_max());
  // After a reversal the Masing branch F_r - 2 F((u_r - u)/2) has the virgin tangent at
  // (u_r - u)/2, and every slider sticks at the reversal point itself.
  EXPECT_TRUE(
      Close(h.trial(1.9 * iwan.phi_max()).tangent, iwan.tangent(0.05 * iwan.phi_max()), 1e-12));
  EXPECT_EQ(h.trial(2 * iwan.phi_max()).tangent, iwan.stiffness());
}

}  // namespace
}  // namespace jointlab::model
