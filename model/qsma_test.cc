#include "jointlab/model/qsma.h"

#include <cmath>
#include <numbers>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <Eigen/LU>

#include "jointlab/core/error.h"
#include "jointlab/model/iwan_cycle.h"
#include "jointlab/tests/all_dof_newton.h"
#include "jointlab/tests/frame_element.h"
#include "jointlab/tests/iwan_cycle_quadrature.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

using testing::Close;
constexpr double kTwoPi = 2 * std::numbers::pi;

Eigen::SparseMatrix<double> sparse(const Eigen::MatrixXd& m) { return m.sparseView(); }

// The closed form of method.md section 3 for a mass (or reduced mass) mu on a spring k0 in
// parallel with an Iwan element, at joint amplitude x: the secant omega^2 and zeta; what a
// ring-down shows, omega_1^2 = (k0 + k_1) / mu and zeta = D / (2 pi x dE/dx) with
// dE/dx = x (k0 + F'(x)) (energy form, exact); what a steady state shows,
// zeta = D / (2 pi (k0 + k_1) x^2). k_1 is the first-harmonic stiffness of the Iwan element
// by independent quadrature of its Masing loop (tests/iwan_cycle_quadrature.h, ~1e-9).
struct ClosedForm {
  double omega2, zeta, ringdown_omega2, ringdown_zeta, harmonic_zeta;
};
ClosedForm closed_form(const Iwan& iwan, double k0, double mu, double x) {
  const double force = k0 * x + iwan.force(x), d = iwan.dissipation(x);
  const double k1 = k0 + testing::first_harmonic_by_quadrature(iwan, x);
  return {force / (mu * x), d / (kTwoPi * force * x), k1 / mu,
          d / (kTwoPi * x * x * (k0 + iwan.tangent(x))), d / (kTwoPi * k1 * x * x)};
}

// Frequency and damping at every point against the closed form. The curve's points come
// from Newton solves converged to 1e-12 of the forces: 1e-6 relative is the acceptance
// threshold (observed agreement is ~1e-12).
void expect_closed_form(const std::vector<QsmaPoint>& curve, const Iwan& iwan, double k0,
                        double mu) {
  ASSERT_GE(curve.size(), 2u);
  for (size_t i = 0; i < curve.size(); ++i) {
    const QsmaPoint& p = curve[i];
    const double x = p.max_slip;
    EXPECT_TRUE(Close(p.modal_amplitude, std::sqrt(mu) * x, 1e-9)) << i;
    const ClosedForm cf = closed_form(iwan, k0, mu, x);
    EXPECT_TRUE(Close(p.frequency_hz, std::sqrt(cf.omega2) / kTwoPi, 1e-6)) << i;
    EXPECT_TRUE(Close(p.damping_ratio, cf.zeta, 1e-6)) << i;
    EXPECT_TRUE(Close(p.ringdown_frequency_hz, std::sqrt(cf.ringdown_omega2) / kTwoPi, 1e-6)) << i;
    EXPECT_TRUE(Close(p.ringdown_damping_ratio, cf.ringdown_zeta, 1e-6)) << i;
    EXPECT_TRUE(Close(p.harmonic_damping_ratio, cf.harmonic_zeta, 1e-6)) << i;
    if (i > 0) {
      EXPECT_GT(p.modal_amplitude, curve[i - 1].modal_amplitude);
    }
  }
}

const IwanParameters kRivet{40.0, 2.0e6, -0.5, 1.0};

Model sdof(double m, double k0, const IwanParameters& p) {
  Model model;
  model.mass = sparse(Eigen::MatrixXd::Constant(1, 1, m));
  model.stiffness = sparse(Eigen::MatrixXd::Constant(1, 1, k0));
  model.joints.push_back({0, kGround, "iwan.rivet", p.Kt, Iwan(p)});
  return model;
}

Model free_pair(double m1, double m2, double k0, const IwanParameters& p) {
  Model model;
  Eigen::MatrixXd M(2, 2), K(2, 2);
  M << m1, 0, 0, m2;
  K << k0, -k0, -k0, k0;
  model.mass = sparse(M);
  model.stiffness = sparse(K);
  model.joints.push_back({1, 0, "iwan.rivet", p.Kt, Iwan(p)});
  return model;
}

TEST(JointCondensation, AStiffPenaltySpringIsExactOrRefused) {
  // A structure spring k_1 from DOF 1 to ground, a penalty spring k_s from DOF 0 to DOF 1
  // and an Iwan joint from DOF 0 to ground: C = (K_lin^-1)_00 = (k_s + k_1) / (K_T k_s +
  // K_T k_1 + k_s k_1) in closed form. A Cholesky solve carries error ~ eps k_s / (k_1 + K_T)
  // ~ 5e-18 k_s / k_1 here: 5e-8 at k_s = 1e10 k_1, within 1e-6 of the closed form; 5e-5 at
  // 1e13 and 5e-3 at 1e15, beyond the 1e-6 the condensation accepts: refused, naming the
  // stiffest joint, rather than analysed with a wrong flexibility.
  const double k1 = 1e5;
  for (double ratio : {1e10, 1e13, 1e15}) {
    const double ks = ratio * k1;
    Model model;
    Eigen::MatrixXd M(2, 2), K = Eigen::MatrixXd::Zero(2, 2);
    M << 1.0, 0, 0, 2.0;
    K(1, 1) = k1;
    model.mass = sparse(M);
    model.stiffness = sparse(K);
    model.joints.push_back({0, kGround, "iwan.rivet", kRivet.Kt, Iwan(kRivet)});
    model.joints.push_back({0, 1, "spring.penalty", ks, std::nullopt});
    if (ratio > 1e12) {
      const std::string m = testing::input_error_of([&] { JointCondensation{model}; });
      EXPECT_NE(m.find("resolved only to"), std::string::npos) << ratio << ": " << m;
      EXPECT_NE(m.find(fmt::format("{:.3g} N/m", ks)), std::string::npos) << m;
      continue;
    }
    const JointCondensation jc(model);
    ASSERT_EQ(jc.size(), 1);
    const double expected = (ks + k1) / (kRivet.Kt * ks + kRivet.Kt * k1 + ks * k1);
    EXPECT_TRUE(Close(jc.flexibility()(0, 0), expected, 1e-6))
        << ratio << ": " << jc.flexibility()(0, 0) << " vs " << expected;
  }
}

TEST(JointCondensation, SofteningAndHarmonicTogetherMatchEachAlone) {
  // Two elements of different chi and phi_max on one coordinate, one on another: every
  // column of the joint evaluation against softening(), first_harmonic_stiffness() and the
  // slope of each element's own cycle summed per coordinate, at rest, in microslip of both,
  // between the two phi_max and past both, of either sign. The same laws in another order
  // of operations: 1e-12 relative (rounding is ~1e-15).
  const IwanParameters second{10.0, 5e5, -0.8, 0.2}, grounded{30.0, 1e6, 0.0, 3.0};
  Model model = free_pair(1.0, 2.0, 1e5, kRivet);
  model.joints.push_back({1, 0, "iwan.rivet", 5e5, Iwan(second)});
  model.joints.push_back({0, kGround, "iwan.rivet", 1e6, Iwan(grounded)});
  const std::vector<std::vector<IwanCycle>> elements{
      {IwanCycle(Iwan(kRivet)), IwanCycle(Iwan(second))}, {IwanCycle(Iwan(grounded))}};
  const JointCondensation jc(model);
  ASSERT_EQ(jc.size(), 2);
  const double pm = jc.phi_max(0);
  for (double ratio : {0.0, 1e-4, 0.3, 0.7, 0.99, 1.5, 40.0}) {
    for (double sign : {1.0, -1.0}) {
      Eigen::VectorXd r(2);
      r << sign * ratio * pm, -sign * ratio * jc.phi_max(1);
      Eigen::VectorXd h, dh, k1, dk1, h_alone, dh_alone, slope = Eigen::VectorXd::Zero(2);
      jc.softening_and_harmonic(r, h, dh, k1, dk1);
      jc.softening(r, h_alone, dh_alone);
      const Eigen::VectorXd k1_alone = jc.first_harmonic_stiffness(r);
      for (int j = 0; j < 2; ++j) {
        for (const IwanCycle& c : elements[j]) {
          double s = 0;
          c.first_harmonic_stiffness(r(j), &s);
          slope(j) += s;
        }
        EXPECT_NEAR(h(j), h_alone(j), 1e-12 * std::abs(h_alone(j))) << ratio << " " << j;
        EXPECT_NEAR(dh(j), dh_alone(j), 1e-12 * std::abs(dh_alone(j))) << ratio << " " << j;
        EXPECT_NEAR(k1(j), k1_alone(j), 1e-12 * k1_alone(j)) << ratio << " " << j;
        EXPECT_NEAR(dk1(j), slope(j), 1e-12 * std::abs(slope(j))) << ratio << " " << j;
      }
    }
  }
}

TEST(Qsma, MassOnSpringWithIwanToGroundMatchesTheClosedForm) {
  const double m = 0.5, k0 = 1.0e6;
  const JointCondensation model(sdof(m, k0, kRivet));
  QsmaSummary summary;
  const auto curve = qsma(model, 1, QsmaOptions{}, &summary);
  expect_closed_form(curve, Iwan(kRivet), k0, m);
  // The spring carries any load: the curve ends at full macroslip, bracketed to 1e-4 in
  // alpha (the last point is just past phi_max).
  EXPECT_EQ(summary.termination, QsmaTermination::kFullMacroslip) << summary.report();
  const double pm = Iwan(kRivet).phi_max();
  EXPECT_GE(curve.back().max_slip, pm);
  EXPECT_LT(curve.back().max_slip, pm * 1.001);
  EXPECT_LT(curve[curve.size() - 2].max_slip, pm);
  // The start is inside microslip: damping within 1 % of the power law
  // zeta_0 = D(x) / (2 pi (k0 + K_T) x^2) at the same x.
  const double x0 = curve.front().max_slip;
  const double zeta0 = Iwan(kRivet).dissipation(x0) / (kTwoPi * (k0 + kRivet.Kt) * x0 * x0);
  EXPECT_TRUE(Close(curve.front().damping_ratio, zeta0, 0.01));
  EXPECT_FALSE(Close(curve.front().damping_ratio, zeta0, 0.001));  // not absurdly far down
  EXPECT_EQ(curve.size(), 50u);
}

// chi above 0 (method.md: -1 < chi): every column of the one-mass curve, the ring-down frequency
// (first-harmonic stiffness) too, against the closed form at chi 0.5 and 2, to 1e-6 as above, and
// the curve still ends just past phi_max. 10 points: the closed form's quadrature of the Masing
// loop costs 20 ms a point.
TEST(Qsma, MassOnSpringWithChiAboveZeroMatchesTheClosedForm) {
  const double m = 0.5, k0 = 1.0e6;
  for (const double chi : {0.5, 2.0}) {
    const IwanParameters p{kRivet.Fs, kRivet.Kt, chi, kRivet.beta};
    ASSERT_EQ(iwan_parameter_error(p), "");
    const JointCondensation model(sdof(m, k0, p));
    QsmaSummary summary;
    const auto curve = qsma(model, 1, QsmaOptions{.points = 10}, &summary);
    expect_closed_form(curve, Iwan(p), k0, m);
    EXPECT_EQ(summary.termination, QsmaTermination::kFullMacroslip) << summary.report();
    EXPECT_GE(curve.back().max_slip, Iwan(p).phi_max());
    EXPECT_LT(curve.back().max_slip, Iwan(p).phi_max() * 1.001);
  }
}

TEST(Qsma, TwoFreeMassesUseTheReducedMass) {
  const double m1 = 0.3, m2 = 0.7, k0 = 5.0e5;
  const Model model = free_pair(m1, m2, k0, kRivet);
  const JointCondensation condensed(model);
  ASSERT_EQ(condensed.modes().rigid_count, 1);
  ASSERT_EQ(condensed.elastic_count(), 1);
  QsmaOptions options;
  options.points = 30;
  QsmaSummary summary;
  const auto curve = qsma(condensed, 1, options, &summary);
  EXPECT_EQ(curve.size(), 30u);
  expect_closed_form(curve, Iwan(kRivet), k0, m1 * m2 / (m1 + m2));
}

TEST(Qsma, IwanAloneHasALimitLoadAtTheSlipForce) {
  // Two free masses joined by the Iwan element only: past F_S no equilibrium exists.
  // alpha M phi puts sqrt(mu) alpha on the joint, so alpha_lim = F_S / sqrt(mu).
  const double m1 = 0.3, m2 = 0.7, mu = m1 * m2 / (m1 + m2);
  const JointCondensation condensed(free_pair(m1, m2, 0.0, kRivet));
  QsmaSummary summary;
  const auto curve = qsma(condensed, 1, QsmaOptions{}, &summary);
  EXPECT_EQ(summary.termination, QsmaTermination::kLimitLoad) << summary.report();
  const double limit = kRivet.Fs / std::sqrt(mu);
  // The bracket is 1e-4; the contract asks for 1 %.
  EXPECT_TRUE(Close(curve.back().force_amplitude, limit, 2e-4));
  EXPECT_LE(curve.back().force_amplitude, limit);
  expect_closed_form(curve, Iwan(kRivet), 0.0, mu);
  // Dense near the end: the previous point is within 1 % of the limit.
  EXPECT_GT(curve[curve.size() - 2].force_amplitude, 0.99 * limit);
}

TEST(Qsma, ExplicitModalAmplitudeRange) {
  const double m = 0.5, k0 = 1.0e6;
  const JointCondensation model(sdof(m, k0, kRivet));
  QsmaOptions options;
  options.points = 10;
  options.q_min = 1e-7;
  options.q_max = 2e-5;
  QsmaSummary summary;
  const auto curve = qsma(model, 1, options, &summary);
  ASSERT_EQ(curve.size(), 10u);
  EXPECT_EQ(summary.termination, QsmaTermination::kReachedQmax);
  // The range ends are found by a root search on q to 1e-13 in ln q.
  EXPECT_TRUE(Close(curve.front().modal_amplitude, 1e-7, 1e-10));
  EXPECT_TRUE(Close(curve.back().modal_amplitude, 2e-5, 1e-10));
  expect_closed_form(curve, Iwan(kRivet), k0, m);

  options.q_min = 1.0;  // far beyond the limit of an Iwan-only pair
  options.q_max = 0;
  const JointCondensation pair(free_pair(0.3, 0.7, 0.0, kRivet));
  EXPECT_TRUE(qsma(pair, 1, options, &summary).empty());
  EXPECT_EQ(summary.termination, QsmaTermination::kEmptyRange);
}

TEST(Qsma, QmaxPastFullMacroslipContinuesOnTheMacroslipBranch) {
  // Mass on a spring with an Iwan element to ground, q_max at 4 phi_max: past phi_max the
  // element carries F = F_S and dissipates D(A) = 8 (E_max + F_S (A - phi_max)) - 4 A F_S,
  // the spring k0 carries the rest, and the curve still follows the closed form (1e-6, as
  // below phi_max: same Newton tolerance, the macroslip branch is exact in iwan.h).
  const double m = 0.5, k0 = 1.0e6;
  const Iwan iwan(kRivet);
  const double pm = iwan.phi_max();
  const JointCondensation model(sdof(m, k0, kRivet));
  QsmaOptions options;
  options.points = 40;
  options.q_min = 0.5 * pm * std::sqrt(m);
  options.q_max = 4 * pm * std::sqrt(m);
  QsmaSummary summary;
  const auto curve = qsma(model, 1, options, &summary);
  EXPECT_EQ(summary.termination, QsmaTermination::kReachedQmax) << summary.report();
  ASSERT_EQ(curve.size(), 40u);
  EXPECT_TRUE(Close(curve.back().modal_amplitude, options.q_max, 1e-10));
  expect_closed_form(curve, iwan, k0, m);
  // sqrt(m) alpha = k0 x + F(x) is about 40 N at x = phi_max / 2, 70 N at phi_max and
  // 160 N at 4 phi_max: with alpha log-spaced about 60 % of the points lie in macroslip,
  // where the closed form is the explicit plateau:
  // omega^2 = (k0 x + F_S) / (m x), zeta = D(x) / (2 pi (k0 x + F_S) x).
  int past = 0;
  for (const QsmaPoint& p : curve) {
    const double x = p.max_slip;
    if (x <= pm) continue;
    ++past;
    const double force = k0 * x + kRivet.Fs;
    const double e_max = iwan.energy(pm);
    const double d = 8 * (e_max + kRivet.Fs * (x - pm)) - 4 * x * kRivet.Fs;
    EXPECT_TRUE(Close(p.frequency_hz, std::sqrt(force / (m * x)) / kTwoPi, 1e-6)) << x;
    EXPECT_TRUE(Close(p.damping_ratio, d / (kTwoPi * force * x), 1e-6)) << x;
  }
  EXPECT_GE(past, 20);
  // One point sits on the onset of macroslip (the kink of the curve), found to 1e-13 in
  // ln(x / phi_max).
  int onset = 0;
  for (const QsmaPoint& p : curve) onset += Close(p.max_slip, pm, 1e-11) ? 1 : 0;
  EXPECT_EQ(onset, 1);

  // Without a parallel load path (Iwan-only free pair) a q_max past macroslip still ends at
  // the limit load alpha_lim = F_S / sqrt(mu).
  const double m1 = 0.3, m2 = 0.7, mu = m1 * m2 / (m1 + m2);
  const JointCondensation pair(free_pair(m1, m2, 0.0, kRivet));
  options.q_min = 0;
  options.q_max = 4 * pm * std::sqrt(mu);
  const auto limited = qsma(pair, 1, options, &summary);
  EXPECT_EQ(summary.termination, QsmaTermination::kLimitLoad) << summary.report();
  EXPECT_TRUE(Close(limited.back().force_amplitude, kRivet.Fs / std::sqrt(mu), 2e-4));
  expect_closed_form(limited, iwan, 0.0, mu);
}

// A joint far softer than the structure (the one-mode equivalent of a bolted-beam fit:
// K_T / k0 = 1.9e-4, phi_max = 959 m): its damping stays on the microslip power law up to
// macroslip, which once drove the automatic start to alpha ~ 1e125 (a crash on the empty
// curve) and left 11 identical rows for q in [1e-7, 1e-3]. Both ranges now follow the closed
// form (1e-6, as for every SDOF curve here) with distinct, increasing amplitudes.
TEST(Qsma, AJointFarSofterThanTheStructureFollowsTheClosedForm) {
  const IwanParameters soft{5.1e4, 66.9, -0.52, 2.29};
  const double k0 = 3.47e5;
  const JointCondensation model(sdof(1.0, k0, soft));
  QsmaSummary summary;
  const auto full = qsma(model, 1, QsmaOptions{}, &summary);
  EXPECT_EQ(full.size(), 50u) << summary.report();
  expect_closed_form(full, Iwan(soft), k0, 1.0);
  EXPECT_EQ(summary.termination, QsmaTermination::kFullMacroslip) << summary.report();
  // The start is well inside microslip: at most 10 % of phi_max.
  EXPECT_LE(full.front().max_slip, 0.1 * Iwan(soft).phi_max());
  QsmaOptions options;
  options.q_min = 1e-7;
  options.q_max = 1e-3;
  options.points = 11;
  const auto range = qsma(model, 1, options, &summary);
  ASSERT_EQ(range.size(), 11u) << summary.report();
  expect_closed_form(range, Iwan(soft), k0, 1.0);
  EXPECT_TRUE(Close(range.front().modal_amplitude, 1e-7, 1e-10));
  EXPECT_TRUE(Close(range.back().modal_amplitude, 1e-3, 1e-10));
  // q_max = 1e100: reached (the spring carries any load), not cut off after 2^200 of the start.
  options.q_max = 1e100;
  options.points = 50;
  const auto huge = qsma(model, 1, options, &summary);
  ASSERT_EQ(huge.size(), 50u) << summary.report();
  EXPECT_EQ(summary.termination, QsmaTermination::kReachedQmax) << summary.report();
  EXPECT_TRUE(Close(huge.back().modal_amplitude, 1e100, 1e-10));
  // The secant pair against the closed form (the quadrature behind the first-harmonic closed
  // form does not reach 1e100 phi_max); every column finite, amplitude increasing.
  const Iwan iwan(soft);
  for (size_t i = 0; i < huge.size(); ++i) {
    const QsmaPoint& p = huge[i];
    const double x = p.max_slip, force = k0 * x + iwan.force(x);
    EXPECT_TRUE(Close(p.frequency_hz, std::sqrt(force / x) / kTwoPi, 1e-6)) << i;
    EXPECT_TRUE(Close(p.damping_ratio, iwan.dissipation(x) / (kTwoPi * force * x), 1e-6)) << i;
    for (double v : {p.ringdown_frequency_hz, p.ringdown_damping_ratio, p.harmonic_damping_ratio})
      EXPECT_TRUE(std::isfinite(v)) << i;
    if (i > 0) {
      EXPECT_GT(p.modal_amplitude, huge[i - 1].modal_amplitude) << i;
    }
  }
}

TEST(Qsma, BadModeAndOptions) {
  const JointCondensation model(sdof(1.0, 1e6, kRivet));
  QsmaSummary summary;
  EXPECT_THROW(qsma(model, 2, QsmaOptions{}, &summary), InputError);
  EXPECT_THROW(qsma(model, 0, QsmaOptions{}, &summary), InputError);
  QsmaOptions o;
  o.points = 1;
  EXPECT_NE(o.error(), "");
  o.points = 10;
  o.q_min = 2;
  o.q_max = 1;
  EXPECT_NE(o.error(), "");
  Model linear = sdof(1.0, 1e6, kRivet);
  linear.joints[0].iwan.reset();
  EXPECT_THROW(JointCondensation{linear}, InputError);
}

TEST(Qsma, ExtremeParametersFinishQuicklyOrAreRefusedWithAMessage) {
  // chi = 5: a legal, steep power law; the curve follows the closed form as any other.
  const IwanParameters steep{40.0, 2.0e6, 5.0, 1.0};
  const JointCondensation model(sdof(0.5, 1e6, steep));
  QsmaOptions options;
  options.points = 12;
  QsmaSummary summary;
  expect_closed_form(qsma(model, 1, options, &summary), Iwan(steep), 1e6, 0.5);
  // Kt = 1e-300 (R underflows to 0), Fs = 1e250 (Fs phi_max overflows) and Kt = 1e200
  // (phi_max ~ 1e-199 m: a cycle's dissipation underflows to zero damping): refused with a
  // message naming the element, not solved for minutes or reported as undamped.
  for (const IwanParameters& p :
       {IwanParameters{40.0, 1e-300, -0.5, 1.0}, IwanParameters{1e250, 2.0e6, -0.5, 1.0},
        IwanParameters{40.0, 1e200, -0.5, 1.0}}) {
    const std::string m = testing::input_error_of([&] { JointCondensation{sdof(0.5, 1e6, p)}; });
    EXPECT_NE(m.find("double precision"), std::string::npos) << m;
  }
  // chi = 150 (in the domain, chi > -1): phi_max 4e-5 m raised to chi + 2 underflows and R
  // overflows, which the message names (before: phi_max and Fs phi_max alone, both ordinary);
  // chi = 2500 lies above what the slip integral is verified for.
  std::string m = testing::input_error_of([&] {
    JointCondensation{sdof(0.5, 1e6, IwanParameters{40.0, 2.0e6, 150.0, 1.0})};
  });
  EXPECT_NE(m.find("slider density R = inf"), std::string::npos) << m;
  m = testing::input_error_of([&] {
    JointCondensation{sdof(0.5, 1e6, IwanParameters{40.0, 2.0e6, 2500.0, 1.0})};
  });
  EXPECT_NE(m.find("chi = 2500, above 2000, the largest for which its first-harmonic slip "
                   "integral is verified"),
            std::string::npos)
      << m;
  // A structure of 1e200 N/m holds the joint 5e193 times more stiffly than its Kt: its slip
  // is rounding noise, refused with a message.
  const JointCondensation rigid(sdof(0.5, 1e200, kRivet));
  m = testing::input_error_of([&] { qsma(rigid, 1, options, &summary); });
  EXPECT_NE(m.find("below rounding"), std::string::npos) << m;
}

// ---------------------------------------------------------------------------------------
// Multi-rivet model: two stacked free-free planar beams, each with DOFs (u, w, theta) per
// node where u is the axial displacement of its contact face (a rigid offset e from the
// centroid: u_centroid = u_face + e theta). Ten rivets join the faces: an Iwan element on
// the relative u, stiff linear springs on w and theta.
struct Beams {
  Model model;
  std::vector<Eigen::Index> top_u;  // axial DOFs of the top beam
};

Beams stacked_beams(int elements, const IwanParameters& iwan, double parallel_spring = 0) {
  const testing::StackedBeams s = testing::stacked_beam_matrices(elements);
  const int nodes = s.nodes, per_beam = s.per_beam;
  Beams out;
  out.model.mass = sparse(s.M);
  out.model.stiffness = sparse(s.K);
  for (int i = 0; i < nodes; ++i) out.top_u.push_back(per_beam + 3 * i);
  const int rivets = 10;
  for (int k = 0; k < rivets; ++k) {
    const int node = static_cast<int>(std::lround((k + 0.5) * nodes / rivets - 0.5));
    const Eigen::Index bot = 3 * node, top = per_beam + 3 * node;
    out.model.joints.push_back({top, bot, "iwan.x", iwan.Kt, Iwan(iwan)});
    if (parallel_spring > 0) {
      out.model.joints.push_back({top, bot, "spring.x", parallel_spring, std::nullopt});
    }
    out.model.joints.push_back({top + 1, bot + 1, "spring.z", 1e9, std::nullopt});
    out.model.joints.push_back({top + 2, bot + 2, "spring.r", 1e3, std::nullopt});
  }
  return out;
}

// Index (1-based elastic) of the mode whose joint motion is most uniform: the two beams
// sliding against each other.
int sliding_mode(const JointCondensation& c) {
  int best = 1;
  double best_score = 0;
  for (int r = 1; r <= std::min(c.elastic_count(), 12); ++r) {
    const Eigen::VectorXd s = c.joint_shapes().col(c.modes().rigid_count + r - 1);
    const double score = std::abs(s.sum()) / s.cwiseAbs().sum();
    if (score > best_score) best_score = score, best = r;
  }
  return best;
}

// Energy stored at a turning point of the all-DOF solution u (qsma.h): the elastic energy
// of the structure and its springs, 1/2 u^T K_lin u - sum_j K_T,j r_j^2 / 2, plus each Iwan
// element's stored energy at its slip amplitude.
double stored_energy(const Model& model, const Eigen::VectorXd& u) {
  double e = 0.5 * u.dot(model.linear_stiffness() * u);
  for (const Joint& j : model.joints) {
    if (!j.iwan) continue;
    const double r = u(j.a) - u(j.b);
    e += IwanCycle(*j.iwan).turning_point_energy(r) - 0.5 * j.iwan->stiffness() * r * r;
  }
  return e;
}

// The ring-down columns of point i against their definitions evaluated on all DOFs:
// omega_1^2 = phi^T (K_lin u - sum_j B_j^T (K_T - k_1(r_j)) r_j) / q (the first-harmonic
// joint forces, Galerkin on phi), and D / (2 pi q dE/dq) with dE/dq by central differences
// of the reference at alpha (1 -+ 1e-5) (truncation ~1e-10, solver noise ~1e-12 / 1e-5:
// 1e-5 relative), skipped where an element crosses phi_max inside the difference.
void expect_ringdown_columns(const Model& model, const JointCondensation& condensed, int column,
                             testing::AllDofNewton& ref, const QsmaPoint& p, size_t i) {
  const Eigen::VectorXd u = ref.u(), phi = condensed.modes().shapes.col(column);
  const double q = ref.q();
  double w1 = phi.dot(model.linear_stiffness() * u);
  for (const Joint& j : model.joints) {
    if (!j.iwan) continue;
    const double r = u(j.a) - u(j.b);
    const double k1 = IwanCycle(*j.iwan).first_harmonic_stiffness(r);
    w1 -= (phi(j.a) - phi(j.b)) * (j.iwan->stiffness() - k1) * r;
  }
  w1 /= q;
  EXPECT_TRUE(Close(p.ringdown_frequency_hz, std::sqrt(w1) / kTwoPi, 1e-6)) << i;
  if (i % 4 != 2) return;  // the differences cost two solves: every fourth point
  const double delta = 1e-5;
  double e[2], qs[2];
  Eigen::VectorXd us[2];
  for (int side = 0; side < 2; ++side) {
    const double f = side == 0 ? 1 - delta : 1 + delta;
    ref.set(u * f);
    ASSERT_TRUE(ref.solve(p.force_amplitude * f));
    us[side] = ref.u();
    e[side] = stored_energy(model, ref.u());
    qs[side] = ref.q();
  }
  ref.set(u);
  for (const Joint& j : model.joints) {
    if (!j.iwan) continue;
    const double pm = j.iwan->phi_max();
    if ((std::abs(us[0](j.a) - us[0](j.b)) < pm) != (std::abs(us[1](j.a) - us[1](j.b)) < pm)) {
      return;
    }
  }
  const double slope = (e[1] - e[0]) / (qs[1] - qs[0]);
  const double d = condensed.dissipation(condensed.joint_motion(u));
  EXPECT_TRUE(Close(p.ringdown_damping_ratio, d / (kTwoPi * q * slope), 1e-5)) << i;
}

// Runs the reference along the condensed curve's load levels and returns its own end
// load, found by the same predicate (no solution, or full macroslip) bracketed to 1e-4.
void compare_with_all_dofs(const Beams& beams, const JointCondensation& condensed, int mode,
                           QsmaTermination expected_end, QsmaOptions options = {}) {
  QsmaSummary summary;
  options.points = 40;
  const auto curve = qsma(condensed, mode, options, &summary);
  ASSERT_EQ(summary.termination, expected_end) << summary.report();
  const int column = condensed.modes().rigid_count + mode - 1;
  testing::AllDofNewton ref(beams.model, condensed.modes(), column);
  const double omega2 = condensed.modes().omega2(column);
  for (size_t i = 0; i < curve.size(); ++i) {
    const QsmaPoint& p = curve[i];
    ASSERT_TRUE(ref.solve(p.force_amplitude)) << "reference failed at point " << i;
    const double q = ref.q();
    const Eigen::VectorXd r = condensed.joint_motion(ref.u());
    // Same definitions evaluated on the all-DOF solution.
    const double freq = std::sqrt(p.force_amplitude / q) / kTwoPi;
    const double zeta = condensed.dissipation(r) / (kTwoPi * p.force_amplitude * q);
    // Both solutions are converged to 1e-12 of the forces; the model's condition number
    // (~1e6) leaves them ~1e-10 apart. 1e-6 is the acceptance threshold.
    EXPECT_TRUE(Close(p.modal_amplitude, q, 1e-6)) << i;
    EXPECT_TRUE(Close(p.frequency_hz, freq, 1e-6)) << i;
    EXPECT_TRUE(Close(p.damping_ratio, zeta, 1e-6, 1e-15)) << i;
    EXPECT_TRUE(Close(p.max_slip, r.cwiseAbs().maxCoeff(), 1e-6)) << i;
    (void)omega2;
    // The deflection read off the joint solution (QsmaDof: u_d = z^T r + e alpha, from the
    // constraint modes with the rigid-body motion removed) against the all-DOF solution, at
    // the top beam's axial DOFs at its ends and middle and its first transverse one: the same
    // 1e-6 of the largest displacement (both solutions to 1e-12 of the forces, condition ~1e6).
    const double umax = ref.u().lpNorm<Eigen::Infinity>();
    const std::vector<Eigen::Index>& top = beams.top_u;
    for (const Eigen::Index d : {top.front(), top[top.size() / 2], top.back(), top.front() + 1}) {
      const QsmaDof at(condensed, mode, d);
      EXPECT_NEAR(at.sign * at.deflection(p.force_amplitude, r), ref.u()(d), 1e-6 * umax)
          << i << " DOF " << d;
    }
    expect_ringdown_columns(beams.model, condensed, column, ref, p, i);
  }
  if (expected_end == QsmaTermination::kFullMacroslip) return;  // the range rule is checked apart
  // The reference's own end: march up by 2 % from the condensed curve's tenth-to-last
  // point, then bisect to 1e-4.
  ASSERT_GE(curve.size(), 10u);
  const double a0 = curve[curve.size() - 10].force_amplitude;
  ASSERT_TRUE(ref.solve(a0));
  Eigen::VectorXd good = ref.u();
  double lo = a0, hi = 0;
  for (double a = a0 * 1.02; a < a0 * 100; a *= 1.02) {
    ref.set(good * (a / lo));  // proportional predictor
    // The same range rule as qsma(): full macroslip ends the curve only without q_max.
    if (!ref.solve(a) || (options.q_max == 0 && ref.full_macroslip()) ||
        (options.q_max > 0 && ref.q() >= options.q_max)) {
      hi = a;
      break;
    }
    good = ref.u();
    lo = a;
  }
  ASSERT_GT(hi, 0);
  while (hi / lo - 1 > 1e-4) {
    const double mid = std::sqrt(lo * hi);
    ref.set(good * (mid / lo));
    if (!ref.solve(mid) || (options.q_max == 0 && ref.full_macroslip()) ||
        (options.q_max > 0 && ref.q() >= options.q_max)) {
      hi = mid;
    } else {
      good = ref.u();
      lo = mid;
    }
  }
  // Both place the end within 1 % (the contract); each bracket is 1e-4.
  EXPECT_TRUE(Close(curve.back().force_amplitude, lo, 0.01)) << "reference end " << lo;
  EXPECT_TRUE(Close(curve.back().force_amplitude, lo, 1e-3)) << "reference end " << lo;
}

const IwanParameters kBeamRivet{150.0, 2.0e7, -0.5, 0.5};

TEST(Qsma, TenRivetBeamsMatchTheAllDofNewtonInBending) {
  const Beams beams = stacked_beams(20, kBeamRivet);
  const JointCondensation condensed(beams.model);
  ASSERT_EQ(condensed.modes().rigid_count, 3);  // u, w, theta of the riveted pair
  ASSERT_EQ(condensed.size(), 10);
  // Mode 1 bends the pair; when every rivet slides the beams still bend separately, so
  // the curve would end at full macroslip, reached only at absurd amplitudes by the
  // rivets next to the middle (whose slip the symmetric mode hardly excites). Compare up
  // to a modal amplitude where the outer rivets are deep in macroslip instead.
  QsmaOptions options;
  options.q_max = 3e-3;
  compare_with_all_dofs(beams, condensed, 1, QsmaTermination::kReachedQmax, options);
}

TEST(Qsma, TenRivetBeamsSlidingModeHasTheLimitLoadOfLimitAnalysis) {
  const Beams beams = stacked_beams(20, kBeamRivet);
  const JointCondensation condensed(beams.model);
  const int mode = sliding_mode(condensed);
  compare_with_all_dofs(beams, condensed, mode, QsmaTermination::kLimitLoad);

  // Third truth: the only mechanism once every rivet slides is the rigid sliding d of the
  // top beam over the bottom one (u_top = 1), so virtual work gives
  // alpha_lim |phi^T M d| = 10 F_S.
  QsmaSummary summary;
  const auto curve = qsma(condensed, mode, QsmaOptions{}, &summary);
  const int column = condensed.modes().rigid_count + mode - 1;
  Eigen::VectorXd d = Eigen::VectorXd::Zero(beams.model.size());
  for (Eigen::Index i : beams.top_u) d(i) = 1;
  const double work = std::abs(condensed.modes().shapes.col(column).dot(beams.model.mass * d));
  EXPECT_TRUE(Close(curve.back().force_amplitude, 10 * kBeamRivet.Fs / work, 2e-4));
}

TEST(Qsma, DefaultRangeOnStackedBeamsWithSpringsInParallelEndsAtTheJointsFullMacroslip) {
  // A spring in parallel with every Iwan element carries load past macroslip: the default
  // curve ends at full macroslip of the rivets carrying the mode's joint slip, not at the
  // absurd amplitudes where the rivets next to the middle (hardly moved by the bending
  // mode) would slide too.
  const Beams beams = stacked_beams(20, kBeamRivet, 2.0e6);
  const JointCondensation condensed(beams.model);
  QsmaOptions options;
  options.points = 40;
  QsmaSummary summary;
  const auto curve = qsma(condensed, 1, options, &summary);
  ASSERT_EQ(curve.size(), 40u);
  EXPECT_EQ(summary.termination, QsmaTermination::kFullMacroslip) << summary.report();
  const double pm = Iwan(kBeamRivet).phi_max();
  EXPECT_GE(curve.back().max_slip, pm);
  EXPECT_LE(curve.back().max_slip, 100 * pm);
  // Most points between the onset of macroslip (the first rivet at phi_max) and the end;
  // one sits on the onset (found to 1e-13 in ln(slip / phi_max)).
  int transition = 0;
  for (const QsmaPoint& p : curve) transition += p.max_slip >= pm * (1 - 1e-11) ? 1 : 0;
  EXPECT_GT(transition, 20) << "of 40";
  RecordProperty("end_slip_over_phi_max", std::to_string(curve.back().max_slip / pm));
  RecordProperty("points_in_transition", transition);
  compare_with_all_dofs(beams, condensed, 1, QsmaTermination::kFullMacroslip, options);
}

}  // namespace
}  // namespace jointlab::model
