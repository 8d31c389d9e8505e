// Stepped-sine acceptance: a single mass on a spring k0 with a 4-parameter Iwan element,
// held at one amplitude per sweep (response control), from microslip to macroslip.
//
// Simulation: harmonic balance with the exact first harmonic of the Iwan force. For
// x = A cos(theta) the Masing loop's descending branch is F(A) - 2 F((A - x)/2); its Fourier
// coefficients a1, b1 (by quadrature) give the complex force phasor
//   F = (k0 + a1/A - m w^2 - i b1/A) A,
// the force a controller must apply at each step to hold the amplitude A.
// Truth (independent of the loop): the model's first-harmonic pair, k1 = k0 + the in-phase
// first-harmonic stiffness integrated over the Jenkins sliders of the Iwan density (each of
// stiffness 1 and slip displacement phi < A contributes (t - sin 2t / 2)/pi with
// cos t = 1 - 2 phi/A; method.md), D the closed-form dissipation of iwan.h:
//   f = sqrt(k1/m) / 2 pi,   zeta = D / (2 pi k1 A^2).
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>
#include <numbers>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

#include "jointlab/modal/stepped_sine.h"
#include "jointlab/model/iwan.h"
#include "jointlab/tests/test_util.h"

namespace jointlab {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kMass = 1.0;  // kg
constexpr double kK0 = 2.0e5;  // N/m: with the Iwan's K_T, f = 79.6 Hz at low amplitude
const model::IwanParameters kIwan{5.0, 5.0e4, -0.5, 0.5};  // Fs, Kt, chi, beta

// Composite Simpson rule of f on [a, b] with n (even) intervals.
double simpson(const std::function<double(double)>& f, double a, double b, int n) {
  const double h = (b - a) / n;
  double s = f(a) + f(b);
  for (int i = 1; i < n; ++i) s += f(a + i * h) * (i % 2 ? 4 : 2);
  return s * h / 3;
}

// First-harmonic coefficients (a1, b1) of the Iwan force over x = A cos(theta), by
// quadrature of the Masing loop (the ascending half mirrors the descending one).
std::pair<double, double> masing_first_harmonic(const model::Iwan& iwan, double A) {
  auto branch = [&](double th) {
    const double x = A * std::cos(th);
    return iwan.force(A) - 2 * iwan.force((A - x) / 2);
  };
  // Split at the kink where (A - x)/2 reaches phi_max.
  std::vector<double> cuts = {0.0};
  if (A > iwan.phi_max()) cuts.push_back(std::acos(1 - 2 * iwan.phi_max() / A));
  cuts.push_back(kPi);
  double a1 = 0, b1 = 0;
  for (size_t k = 0; k + 1 < cuts.size(); ++k) {
    a1 += simpson([&](double t) { return branch(t) * std::cos(t); }, cuts[k], cuts[k + 1], 20000);
    b1 += simpson([&](double t) { return branch(t) * std::sin(t); }, cuts[k], cuts[k + 1], 20000);
  }
  return {2 * a1 / kPi, 2 * b1 / kPi};
}

// In-phase first-harmonic stiffness of the Iwan sliders at amplitude A (method.md).
double slider_first_harmonic_stiffness(const model::Iwan& iwan, double A) {
  const double chi = iwan.chi(), R = iwan.R(), pm = iwan.phi_max();
  auto g = [&](double phi) {
    if (phi >= A) return 1.0;
    const double t = std::acos(1 - 2 * phi / A);
    return (t - std::sin(2 * t) / 2) / kPi;
  };
  const double a = std::min(A, pm);
  // Sliders slipping at A (phi < a): substitute phi = a s^2 to tame phi^chi at 0.
  double k = simpson(
      [&](double s) {
        if (s <= 0) return 0.0;
        const double phi = a * s * s;
        return R * std::pow(phi, chi) * g(phi) * 2 * a * s;
      },
      0.0, 1.0, 20000);
  if (A < pm) k += R * (std::pow(pm, chi + 1) - std::pow(A, chi + 1)) / (chi + 1);
  return k + iwan.S() * g(pm);
}

struct Pair {
  double f_hz, zeta;
};

Pair first_harmonic_pair(const model::Iwan& iwan, double A) {
  const double k1 = kK0 + slider_first_harmonic_stiffness(iwan, A);
  return {std::sqrt(k1 / kMass) / (2 * kPi), iwan.dissipation(A) / (2 * kPi * k1 * A * A)};
}

// One response-controlled sweep over f_c (1 +- 6 zeta), 41 steps, holding the displacement
// amplitude A or (hold_acceleration) the acceleration amplitude w_c^2 A, as a lab's
// accelerometer-based controller does; the measured force magnitude and phase carry
// relative noise `noise`.
data::SteppedSineTable sweep(const model::Iwan& iwan, double A, const Pair& guess, double noise,
                             unsigned seed, bool hold_acceleration = false) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, noise);
  data::SteppedSineTable t;
  t.control = data::SineControl::kResponse;
  t.response_quantity = hold_acceleration ? Quantity::kAcceleration : Quantity::kDisplacement;
  const int n = 41;
  t.frequency_hz.resize(n), t.force.resize(n), t.response.resize(n), t.phase_rad.resize(n);
  const double half = 6 * guess.zeta * guess.f_hz;
  const double held = hold_acceleration ? std::pow(2 * kPi * guess.f_hz, 2) * A : A;
  auto [a1, b1] = masing_first_harmonic(iwan, A);
  for (int k = 0; k < n; ++k) {
    const double f = guess.f_hz - half + 2 * half * k / (n - 1), w = 2 * kPi * f;
    const double x = hold_acceleration ? held / (w * w) : A;
    if (hold_acceleration) std::tie(a1, b1) = masing_first_harmonic(iwan, x);
    const std::complex<double> force =
        std::complex<double>(kK0 + a1 / x - kMass * w * w, -b1 / x) * x;
    t.frequency_hz(k) = f;
    t.force(k) = std::abs(force) * (1 + g(rng));
    t.response(k) = held;
    t.phase_rad(k) = -std::arg(force) + g(rng) + (hold_acceleration ? kPi : 0.0);
  }
  return t;
}

// The quadrature of the loop and the slider integral agree (two routes to one number):
// stiffness to 1e-9, dissipation -pi A b1 against iwan.h's closed form to 1e-8.
TEST(SteppedSineIwan, LoopQuadratureMatchesSliderIntegralAndClosedForm) {
  const model::Iwan iwan(kIwan);
  for (double r : {0.01, 0.3, 1.0, 3.0}) {
    const double A = r * iwan.phi_max();
    const auto [a1, b1] = masing_first_harmonic(iwan, A);
    EXPECT_TRUE(testing::Close(a1 / A, slider_first_harmonic_stiffness(iwan, A), 1e-9)) << r;
    EXPECT_TRUE(testing::Close(-kPi * A * b1, iwan.dissipation(A), 1e-8)) << r;
  }
}

// Acceptance: f within 0.01 % and zeta within 1 % of the model's first-harmonic pair, from
// 1 % of phi_max (microslip) to 3 phi_max (macroslip), with 0.1 % noise on the force and
// 1 mrad on the phase; each error also inside the stated uncertainty (k = 3).
TEST(SteppedSineIwan, ResponseControlledBackboneMatchesFirstHarmonicPair) {
  const model::Iwan iwan(kIwan);
  modal::SteppedSineOptions opt;
  opt.amplitude = Quantity::kDisplacement;
  double worst_f = 0, worst_z = 0;
  unsigned seed = 7;
  for (double r : {0.01, 0.03, 0.1, 0.3, 0.6, 1.0, 1.5, 3.0}) {
    const double A = r * iwan.phi_max();
    const Pair truth = first_harmonic_pair(iwan, A);
    const data::SteppedSineTable t = sweep(iwan, A, truth, 1e-3, seed++);
    const modal::SineBackbonePoint p = modal::extract_backbone_point(t, opt);
    ASSERT_EQ(p.status, modal::SineStatus::kOk) << p.report();
    const double ef = testing::rel_err(p.frequency_hz, truth.f_hz);
    const double ez = testing::rel_err(p.damping_ratio, truth.zeta);
    std::printf(
        "A/phi_max %5.2f: f %.6f Hz (err %.1e, std %.1e), zeta %.5f %% (err %.2e, std %.1e)\n", r,
        p.frequency_hz, ef, p.frequency_std_hz / truth.f_hz, 100 * p.damping_ratio, ez,
        p.damping_std / truth.zeta);
    worst_f = std::max(worst_f, ef);
    worst_z = std::max(worst_z, ez);
    EXPECT_LT(ef, 1e-4) << r;
    EXPECT_LT(ez, 0.01) << r;
    EXPECT_LE(std::abs(p.frequency_hz - truth.f_hz), p.frequency_std_hz) << r;
    EXPECT_LE(std::abs(p.damping_ratio - truth.zeta), p.damping_std) << r;
    EXPECT_TRUE(testing::Close(p.amplitude, A, 1e-12));
  }
  std::printf("worst errors: frequency %.2e, damping %.2e\n", worst_f, worst_z);
}

}  // namespace
}  // namespace jointlab

namespace jointlab {
namespace {

// Holding the acceleration instead of the displacement lets the displacement change as
// (f_n/f)^2 across the sweep, so the joints' stiffness follows the frequency: near f_n the
// dynamic stiffness K(X(w)) - m w^2 has the slope of an effective mass m (1 + s), with
// s = d ln k1 / d ln A. A single-mode fit cannot tell that from the mass, so it returns
// zeta / (1 + s) (f_n stays right to first order). This is a limit of one-level fits, stated
// in docs/stepped-sine.md; the test checks the extraction behaves as that first-order
// analysis says (ratio within 15 % of the predicted departure, plus 0.2 %), with s from
// the slider integral, and that f_n stays within 0.1 %. Not at A = phi_max itself: there k1
// has a kink (every slider slips), the sweep sees both slopes, and the ratio was 1.083
// against 1.052 predicted.
TEST(SteppedSineIwan, AccelerationHeldSweepBiasIsTheFirstOrderOne) {
  const model::Iwan iwan(kIwan);
  modal::SteppedSineOptions opt;
  opt.amplitude = Quantity::kDisplacement;
  for (double r : {0.01, 0.1, 0.6, 1.5, 3.0}) {
    const double A = r * iwan.phi_max();
    const Pair guess = first_harmonic_pair(iwan, A);
    const modal::SineBackbonePoint p =
        modal::extract_backbone_point(sweep(iwan, A, guess, 0.0, 1, true), opt);
    ASSERT_EQ(p.status, modal::SineStatus::kOk) << p.report();
    const double x = p.amplitude;  // displacement at f_n
    const Pair truth = first_harmonic_pair(iwan, x);
    const double k_hi = kK0 + slider_first_harmonic_stiffness(iwan, x * 1.001);
    const double k_lo = kK0 + slider_first_harmonic_stiffness(iwan, x / 1.001);
    const double slope = std::log(k_hi / k_lo) / (2 * std::log(1.001));
    const double predicted = 1 / (1 + slope), measured = p.damping_ratio / truth.zeta;
    const double ef = testing::rel_err(p.frequency_hz, truth.f_hz);
    std::printf(
        "acceleration held, A/phi_max %5.2f: f err %.1e; zeta ratio %.4f, first-order %.4f\n", r,
        ef, measured, predicted);
    EXPECT_LT(ef, 1e-3) << r;
    EXPECT_NEAR(measured, predicted, 0.15 * std::abs(predicted - 1) + 2e-3) << r;
  }
}

}  // namespace
}  // namespace jointlab

namespace jointlab {
namespace {

// First-harmonic dynamic stiffness of the oscillator's spring and joint at amplitude A,
// tabulated on a log grid (linear interpolation in ln A) for the force-controlled sweeps.
class HarmonicTable {
 public:
  explicit HarmonicTable(const model::Iwan& iwan) {
    for (int i = 0; i <= kN; ++i) {
      const double A = iwan.phi_max() * std::pow(10.0, -3.0 + 4.0 * i / kN);
      const auto [a1, b1] = masing_first_harmonic(iwan, A);
      ln_a_.push_back(std::log(A));
      k_.push_back(kK0 + a1 / A);
      h_.push_back(-b1 / A);
    }
  }
  // K(A) + i h(A).
  std::complex<double> operator()(double A) const {
    const double u = std::clamp((std::log(A) - ln_a_.front()) / (ln_a_[1] - ln_a_[0]), 0.0,
                                static_cast<double>(kN) - 1e-9);
    const auto i = static_cast<size_t>(u);
    const double t = u - static_cast<double>(i);
    return {k_[i] + t * (k_[i + 1] - k_[i]), h_[i] + t * (h_[i + 1] - h_[i])};
  }
  double lo() const { return std::exp(ln_a_.front()); }
  double hi() const { return std::exp(ln_a_.back()); }

 private:
  static constexpr int kN = 800;
  std::vector<double> ln_a_, k_, h_;
};

// Force-controlled up-sweep at force amplitude F0: at each step the amplitude on the branch
// followed from below (the root of |K(A) - m w^2 + i h(A)| A = F0 nearest the previous one,
// in ln A), as a slow sweep of a softening mode does until it jumps.
data::SteppedSineTable force_sweep(const HarmonicTable& hb, double F0, double f_lo, double f_hi,
                                   int n) {
  data::SteppedSineTable t;
  t.control = data::SineControl::kForce;
  t.response_quantity = Quantity::kDisplacement;
  t.frequency_hz.resize(n), t.force.resize(n), t.response.resize(n), t.phase_rad.resize(n);
  double previous = 0;
  for (int k = 0; k < n; ++k) {
    const double f = f_lo + (f_hi - f_lo) * k / (n - 1), w = 2 * kPi * f;
    auto g = [&](double A) { return std::abs(hb(A) - kMass * w * w) * A - F0; };
    std::vector<double> roots;
    const int scan = 4000;
    double a0 = hb.lo(), g0 = g(a0);
    for (int i = 1; i <= scan; ++i) {
      const double a1 = hb.lo() * std::pow(hb.hi() / hb.lo(), static_cast<double>(i) / scan);
      const double g1 = g(a1);
      if ((g0 < 0) != (g1 < 0)) {
        double lo = a0, hi = a1;
        for (int it = 0; it < 60; ++it) {
          const double mid = std::sqrt(lo * hi);
          ((g(mid) < 0) == (g0 < 0) ? lo : hi) = mid;
        }
        roots.push_back(std::sqrt(lo * hi));
      }
      a0 = a1, g0 = g1;
    }
    EXPECT_FALSE(roots.empty());
    double A = roots.front();
    if (previous > 0) {
      for (double r : roots) {
        if (std::abs(std::log(r / previous)) < std::abs(std::log(A / previous))) A = r;
      }
    }
    previous = A;
    const std::complex<double> force = (hb(A) - kMass * w * w) * A;
    t.frequency_hz(k) = f;
    t.force(k) = F0;
    t.response(k) = A;
    t.phase_rad(k) = -std::arg(force);
  }
  return t;
}

// Force control: the phase resonance lies on the first-harmonic backbone (K(A) = m w^2 there
// exactly), so its frequency matches the pair at its own amplitude to the linear
// interpolation between steps (0.02 Hz apart here; 2e-5 allowed). Its damping is the energy
// balance with a modal constant: with |Q| from a response-controlled level (as the command
// does) within 1 % (the interpolation of force and amplitude between steps); with the
// sweep's own |Q| it is far off (measured 8 %, 26 %, 73 % at these forces), which is why the
// command prefers the response-controlled levels' |Q| and flags the other.
TEST(SteppedSineIwan, ForceControlledPhaseResonanceLiesOnTheBackbone) {
  const model::Iwan iwan(kIwan);
  const HarmonicTable hb(iwan);
  modal::SteppedSineOptions opt;
  opt.amplitude = Quantity::kDisplacement;
  // |Q| from one response-controlled level in microslip, with noise as in the acceptance test.
  const double A0 = 0.05 * iwan.phi_max();
  const modal::SineBackbonePoint rc =
      modal::extract_backbone_point(sweep(iwan, A0, first_harmonic_pair(iwan, A0), 1e-3, 3), opt);
  ASSERT_EQ(rc.status, modal::SineStatus::kOk);
  const modal::ModalConstant q = modal::response_modal_constant({rc});
  EXPECT_TRUE(testing::Close(q.magnitude, 1 / kMass, 3 * q.rel_sigma));
  for (double F0 : {0.05, 0.5, 2.0}) {
    const data::SteppedSineTable t = force_sweep(hb, F0, 74.0, 80.0, 301);
    const modal::SineBackbonePoint own = modal::extract_backbone_point(t, opt);
    const modal::SineBackbonePoint p = modal::extract_backbone_point(t, opt, q);
    ASSERT_EQ(p.status, modal::SineStatus::kOk) << p.report();
    EXPECT_TRUE(own.own_modal_constant);
    EXPECT_FALSE(p.own_modal_constant);
    const Pair truth = first_harmonic_pair(iwan, p.amplitude);
    const double ef = testing::rel_err(p.frequency_hz, truth.f_hz);
    const double ez = testing::rel_err(p.damping_ratio, truth.zeta);
    std::printf("force %.2f N: A/phi_max %.3f, f err %.1e, zeta err %.2e (own |Q|: %.2e)\n", F0,
                p.amplitude / iwan.phi_max(), ef, ez,
                testing::rel_err(own.damping_ratio, truth.zeta));
    EXPECT_LT(ef, 2e-5) << F0;
    EXPECT_LT(ez, 0.01) << F0;
  }
}

}  // namespace
}  // namespace jointlab
