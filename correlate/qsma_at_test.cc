#include "jointlab/correlate/qsma_at.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/correlate/two_chain.h"
#include "jointlab/tests/all_dof_newton.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::correlate {
namespace {

// The load, frequencies and damping ratios of two QSMA points agree to relative `tolerance`.
void expect_same_point(const model::QsmaPoint& a, const model::QsmaPoint& b, double tolerance) {
  EXPECT_TRUE(testing::Close(a.force_amplitude, b.force_amplitude, tolerance));
  EXPECT_TRUE(testing::Close(a.frequency_hz, b.frequency_hz, tolerance));
  EXPECT_TRUE(testing::Close(a.damping_ratio, b.damping_ratio, tolerance));
  EXPECT_TRUE(testing::Close(a.ringdown_frequency_hz, b.ringdown_frequency_hz, tolerance));
  EXPECT_TRUE(testing::Close(a.ringdown_damping_ratio, b.ringdown_damping_ratio, tolerance));
  EXPECT_TRUE(testing::Close(a.harmonic_damping_ratio, b.harmonic_damping_ratio, tolerance));
}

double amplitude(const model::QsmaPoint& p, int power) {
  return p.modal_amplitude * std::pow(2 * std::numbers::pi * p.frequency_hz, power);
}

// The Iwan two-chain structure, condensed.
model::JointCondensation iwan_chains() {
  TwoChainParameters p;
  p.iwan = true;
  return model::JointCondensation(two_chain_structure(p));
}

// qsma() of mode 1 at `points` load levels up to `reach` times the modal amplitude where its
// automatic range ends, and how that automatic range ended.
struct LongCurve {
  std::vector<model::QsmaPoint> curve;
  model::QsmaTermination automatic_end;
};
LongCurve long_curve(const model::JointCondensation& jc, int points, double reach) {
  model::QsmaSummary qs;
  const auto automatic = model::qsma(jc, 1, {}, &qs);
  const model::QsmaTermination automatic_end = qs.termination;
  model::QsmaOptions o;
  o.points = points;
  o.q_max = reach * automatic.back().modal_amplitude;
  return {model::qsma(jc, 1, o, &qs), automatic_end};
}

// The amplitudes s = scale q omega^p of the curve's points, each moved up by 0.1-0.3 % (off
// qsma()'s own points: none sits on the element's phi_max, where Newton hands over), ascending.
std::vector<double> off_curve_amplitudes(const std::vector<model::QsmaPoint>& curve, int power,
                                         double scale = 1.0) {
  std::vector<double> s;
  for (const auto& c : curve)
    s.push_back(scale * amplitude(c, power) * (1 + 1e-3 * (1 + s.size() % 3)));
  std::sort(s.begin(), s.end());
  return s;
}

// Second method: qsma() marches up in load; its points, converted to amplitudes s = q omega^p,
// must come back from qsma_at() with the same load, frequency and damping. The curve runs to
// three times the full-macroslip amplitude, across the knee. Both solve the same static problem
// to 1e-12 of the forces and qsma_at() places s to 1e-10, so they agree to about 1e-9.
TEST(QsmaAt, ReproducesQsmaPointsAcrossTheMacroslipKnee) {
  const model::JointCondensation jc = iwan_chains();
  const auto [curve, automatic_end] = long_curve(jc, 40, 3);
  ASSERT_EQ(automatic_end, model::QsmaTermination::kFullMacroslip);
  ASSERT_GE(curve.size(), 40u);
  const double phi_max = jc.phi_max(0);
  for (int power = 0; power <= 2; ++power) {
    std::vector<double> s;
    for (const auto& c : curve) s.push_back(amplitude(c, power));
    const auto at = qsma_at(jc, 1, power, s);
    ASSERT_EQ(at.size(), curve.size());
    int past_knee = 0;
    for (size_t i = 0; i < curve.size(); ++i) {
      SCOPED_TRACE(::testing::Message() << "power " << power << ", point " << i);
      EXPECT_TRUE(at[i].reached);
      EXPECT_TRUE(testing::Close(amplitude(at[i].point, power), s[i], 1e-9));
      EXPECT_TRUE(testing::Close(at[i].point.force_amplitude, curve[i].force_amplitude, 1e-8));
      EXPECT_TRUE(testing::Close(at[i].point.frequency_hz, curve[i].frequency_hz, 1e-9));
      EXPECT_TRUE(testing::Close(at[i].point.damping_ratio, curve[i].damping_ratio, 1e-8));
      EXPECT_TRUE(testing::Close(at[i].point.max_slip, curve[i].max_slip, 1e-8));
      past_knee += curve[i].max_slip > phi_max;
    }
    EXPECT_GE(past_knee, 3);  // the comparison covers macroslip
  }
}

// Newton against the bracketing iteration on the same amplitudes, secant and first-harmonic,
// across the knee: Newton places s to rounding (1e-12 asked; the bracketing stops at 1e-10 in
// ln s), and every column agrees to 1e-8 (the bracketing's 1e-10 times the columns' slopes
// d ln column / d ln s <= ~10, with margin).
TEST(QsmaAt, NewtonAgreesWithTheBracketingIteration) {
  const model::JointCondensation jc = iwan_chains();
  const auto [curve, automatic_end] = long_curve(jc, 40, 3);
  ASSERT_GE(curve.size(), 40u);
  for (AmplitudeFrequency frequency :
       {AmplitudeFrequency::kSecant, AmplitudeFrequency::kFirstHarmonic}) {
    const bool harmonic = frequency == AmplitudeFrequency::kFirstHarmonic;
    for (int power = 0; power <= 2; ++power) {
      const std::vector<double> s = off_curve_amplitudes(curve, power);
      const auto newton = qsma_at(jc, 1, power, s, frequency, QsmaAtSolver::kNewton);
      const auto bracketing = qsma_at(jc, 1, power, s, frequency, QsmaAtSolver::kBracketing);
      ASSERT_EQ(newton.size(), s.size());
      ASSERT_EQ(bracketing.size(), s.size());
      for (size_t i = 0; i < s.size(); ++i) {
        SCOPED_TRACE(::testing::Message()
                     << "harmonic " << harmonic << ", power " << power << ", point " << i);
        const model::QsmaPoint& a = newton[i].point;
        const model::QsmaPoint& b = bracketing[i].point;
        const double f = harmonic ? a.ringdown_frequency_hz : a.frequency_hz;
        EXPECT_TRUE(testing::Close(a.modal_amplitude * std::pow(2 * std::numbers::pi * f, power),
                                   s[i], 1e-12));
        expect_same_point(a, b, 1e-8);
      }
    }
  }
}

// A sensor's amplitude is its deflection u_d omega^p (qsma_at.h), which in macroslip is not
// |phi[d]| q omega^p. Third method: the all-DOF Newton (tests/all_dof_newton.h: every DOF, no
// condensation, no constraint modes) solved at each load level of qsma()'s curve gives u_d
// there; qsma_at() given s = |u_d| omega^p at that DOF must return the same load and columns.
// The two-chain model spans 2e5 to 1e10 N/m, so solutions to 1e-12 of the forces agree to
// ~1e-8 in u (and less in alpha, s rising faster than alpha in macroslip): 1e-7 is the
// threshold. The sensor sits on chain A's free end, whose deflection per q falls more than 1 %
// below the linear shape's at the top of the curve (checked: reading q |phi[d]| there would
// miss the load by far more than the threshold).
TEST(QsmaAt, SensorAmplitudesAreTheAllDofDeflectionAtTheSensor) {
  TwoChainParameters parameters;
  parameters.iwan = true;
  const model::Model m = two_chain_structure(parameters);
  const model::JointCondensation jc(m);
  const auto [curve, automatic_end] = long_curve(jc, 30, 3);
  ASSERT_GE(curve.size(), 30u);
  const Eigen::Index dof = parameters.n - 1;  // chain A's last mass
  const int column = jc.modes().rigid_count;
  const double ph = std::abs(jc.modes().shapes(dof, column));
  testing::AllDofNewton reference(m, jc.modes(), column);
  std::vector<double> deflection;
  for (const auto& c : curve) {
    ASSERT_TRUE(reference.solve(c.force_amplitude));
    deflection.push_back(std::abs(reference.u()(dof)));
  }
  EXPECT_GT(curve.back().modal_amplitude * ph / deflection.back() - 1, 0.01)
      << "the curve does not reach where the linear shape misreads the sensor";
  for (AmplitudeFrequency frequency :
       {AmplitudeFrequency::kSecant, AmplitudeFrequency::kFirstHarmonic}) {
    const bool harmonic = frequency == AmplitudeFrequency::kFirstHarmonic;
    for (int power = 0; power <= 2; ++power) {
      std::vector<double> s;
      for (size_t i = 0; i < curve.size(); ++i) {
        const double f = harmonic ? curve[i].ringdown_frequency_hz : curve[i].frequency_hz;
        s.push_back(deflection[i] * std::pow(2 * std::numbers::pi * f, power));
      }
      const auto at = qsma_at(jc, 1, power, s, frequency, QsmaAtSolver::kNewton, dof);
      ASSERT_EQ(at.size(), curve.size());
      for (size_t i = 0; i < curve.size(); ++i) {
        SCOPED_TRACE(::testing::Message()
                     << "harmonic " << harmonic << ", power " << power << ", point " << i);
        const model::QsmaPoint& a = at[i].point;
        EXPECT_TRUE(at[i].reached);
        EXPECT_TRUE(testing::Close(a.force_amplitude, curve[i].force_amplitude, 1e-7));
        EXPECT_TRUE(testing::Close(a.modal_amplitude, curve[i].modal_amplitude, 1e-7));
        EXPECT_TRUE(testing::Close(a.frequency_hz, curve[i].frequency_hz, 1e-7));
        EXPECT_TRUE(testing::Close(a.damping_ratio, curve[i].damping_ratio, 1e-7));
        EXPECT_TRUE(testing::Close(a.ringdown_frequency_hz, curve[i].ringdown_frequency_hz, 1e-7));
      }
    }
  }
}

// Newton against the bracketing iteration for a sensor's amplitude, as for q above: the
// bordered system's tangent now carries du_d/dr and du_d/dalpha. Off the curve's own points,
// across the knee, at chain A's grounded first mass (on the joint's near side) and its free end
// (beyond it). Newton's point, re-solved by an
// ordinary static solve at its load, has |u_d| omega^p = s to 1e-9 (the re-solve's 1e-12 of the
// forces times the model's conditioning); every column agrees with the bracketing's to 1e-8, as for
// q.
TEST(QsmaAt, SensorNewtonAgreesWithTheBracketingIteration) {
  const model::JointCondensation jc = iwan_chains();
  const auto [curve, automatic_end] = long_curve(jc, 40, 3);
  ASSERT_GE(curve.size(), 40u);
  const model::QsmaMode mode(jc, 1);
  for (const Eigen::Index dof : {Eigen::Index{0}, Eigen::Index{5}}) {
    const model::QsmaDof sensor(jc, 1, dof);
    for (AmplitudeFrequency frequency :
         {AmplitudeFrequency::kSecant, AmplitudeFrequency::kFirstHarmonic}) {
      const bool harmonic = frequency == AmplitudeFrequency::kFirstHarmonic;
      for (int power = 0; power <= 2; ++power) {
        const std::vector<double> s = off_curve_amplitudes(curve, power, sensor.shape);
        const auto newton = qsma_at(jc, 1, power, s, frequency, QsmaAtSolver::kNewton, dof);
        const auto bracketing = qsma_at(jc, 1, power, s, frequency, QsmaAtSolver::kBracketing, dof);
        ASSERT_EQ(newton.size(), s.size());
        ASSERT_EQ(bracketing.size(), s.size());
        Eigen::VectorXd r = Eigen::VectorXd::Zero(jc.size());
        for (size_t i = 0; i < s.size(); ++i) {
          SCOPED_TRACE(::testing::Message() << "DOF " << dof << ", harmonic " << harmonic
                                            << ", power " << power << ", point " << i);
          const model::QsmaPoint& a = newton[i].point;
          const model::QsmaPoint& b = bracketing[i].point;
          ASSERT_TRUE(newton[i].reached);
          ASSERT_TRUE(jc.solve(mode.g, a.force_amplitude, r, 1e6, 60).converged);
          const double f = harmonic ? a.ringdown_frequency_hz : a.frequency_hz;
          EXPECT_TRUE(testing::Close(
              sensor.deflection(a.force_amplitude, r) * std::pow(2 * std::numbers::pi * f, power),
              s[i], 1e-9));
          EXPECT_TRUE(testing::Close(a.modal_amplitude, b.modal_amplitude, 1e-8));
          expect_same_point(a, b, 1e-8);
        }
      }
    }
  }
}

// The ring-down and first-harmonic columns: a test's signal oscillates at the first-harmonic
// frequency, so its amplitude is q omega_1^p. qsma() points converted that way must come back
// with every column, the ring-down and harmonic damping included (same solves, same formulas:
// to the 1e-10 placement of s, about 1e-8 after the damping's slope). Except at the point
// qsma() puts exactly on the element's phi_max: there the ring-down damping jumps (the
// element's beta sliders all slip at once, so the tangent stiffness, hence dE/dq, drops), and
// a point 1e-10 away may lie on either side.
TEST(QsmaAt, FirstHarmonicAmplitudesGiveTheRingdownAndHarmonicColumns) {
  const model::JointCondensation jc = iwan_chains();
  const std::vector<model::QsmaPoint> curve = long_curve(jc, 25, 2).curve;
  for (int power = 0; power <= 2; ++power) {
    std::vector<double> s;
    for (const auto& c : curve)
      s.push_back(c.modal_amplitude *
                  std::pow(2 * std::numbers::pi * c.ringdown_frequency_hz, power));
    const auto at = qsma_at(jc, 1, power, s, AmplitudeFrequency::kFirstHarmonic);
    ASSERT_EQ(at.size(), curve.size());
    int on_the_jump = 0;
    for (size_t i = 0; i < curve.size(); ++i) {
      SCOPED_TRACE(::testing::Message() << "power " << power << ", point " << i);
      const model::QsmaPoint& a = at[i].point;
      if (std::abs(curve[i].max_slip / jc.phi_max(0) - 1) < 1e-8) {
        ++on_the_jump;
        continue;
      }
      EXPECT_TRUE(testing::Close(a.modal_amplitude, curve[i].modal_amplitude, 1e-8));
      EXPECT_TRUE(testing::Close(a.ringdown_frequency_hz, curve[i].ringdown_frequency_hz, 1e-9));
      EXPECT_TRUE(testing::Close(a.ringdown_damping_ratio, curve[i].ringdown_damping_ratio, 1e-7));
      EXPECT_TRUE(testing::Close(a.harmonic_damping_ratio, curve[i].harmonic_damping_ratio, 1e-7));
    }
    EXPECT_LE(on_the_jump, 1);
  }
}

// A single mass on an Iwan element to ground (and nothing else): the load cannot exceed F_S, so
// the amplitudes grow without bound as alpha approaches it. Below they are exact.
// A point within 1e-11 of phi_max reports the ring-down damping of the side its amplitude is on
// (issue 28: one 1e-10 below phi_max gave the post-knee 1.264e-2 instead of 9.374e-3). One mass
// (q = x) on k0 with an Iwan element: below phi_max dE/dx = x (k0 + F'(x)), F' = K_T -
// R x^(chi+1) / (chi+1); above it F' = 0, so the two sides differ by the tangent K_T - R ...
// (here 30 % of the damping) while the amplitudes differ by 2e-11: each side to 1e-6.
TEST(QsmaAt, APointAtTheKneeReportsTheSideItsAmplitudeIsOn) {
  const model::IwanParameters iw{40.0, 2.0e6, -0.5, 0.2};
  const double k0 = 1.0e6;
  const model::JointCondensation jc(one_mode_structure(k0, iw));
  const model::Iwan iwan(iw);
  const double phi = iwan.phi_max();
  for (const double eps : {1e-11, 3e-11, 1e-10}) {
    for (const int side : {-1, 1}) {
      const double x = phi * (1 + side * eps);
      const auto at = qsma_at(jc, 1, 0, {0.5 * phi, x}, AmplitudeFrequency::kFirstHarmonic);
      ASSERT_EQ(at.size(), 2u);
      const double tangent = side < 0 ? iwan.tangent(phi * (1 - 1e-9)) : 0.0;
      const double expected = iwan.dissipation(x) / (2 * std::numbers::pi * x * x * (k0 + tangent));
      EXPECT_TRUE(testing::Close(at[1].point.ringdown_damping_ratio, expected, 1e-6))
          << "eps " << eps << " side " << side << ": " << at[1].point.ringdown_damping_ratio
          << " vs " << expected;
    }
  }
}

TEST(QsmaAt, AmplitudesUpToTheLimitLoad) {
  model::Model m;
  m.mass.resize(1, 1);
  m.stiffness.resize(1, 1);
  m.mass.insert(0, 0) = 1.0;
  model::Joint j;
  j.a = 0;
  j.element = "iwan.rivet";
  j.stiffness = 1e6;
  j.iwan = model::Iwan(10.0, 1e6, -0.5, 1.0);
  m.joints.push_back(j);
  model::validate_model(m);
  const model::JointCondensation jc(m);
  const int mode = 1;
  const double phi_max = jc.phi_max(0);
  const double omega2 = jc.modes().omega2(0);
  const double ph = std::abs(jc.modes().shapes(0, 0));
  // Displacement amplitude s = q: deep in microslip (stiffness within (1e-8)^(chi+1) = 1e-4 of
  // K_T), at phi_max, and 1e6 phi_max.
  const std::vector<double> s{1e-8 * phi_max / ph, phi_max / ph, 1e6 * phi_max / ph};
  const auto at = qsma_at(jc, mode, 0, s);
  ASSERT_EQ(at.size(), 3u);
  EXPECT_TRUE(at[0].reached);
  EXPECT_TRUE(testing::Close(at[0].point.modal_amplitude, s[0], 1e-9));
  EXPECT_TRUE(testing::Close(at[0].point.frequency_hz, std::sqrt(omega2) / (2 * std::numbers::pi),
                             1e-3));  // microslip: the linear frequency
  EXPECT_TRUE(at[1].reached);
  EXPECT_TRUE(testing::Close(at[1].point.max_slip, phi_max, 1e-9));
  // At phi_max the element carries F_S: alpha phi[0] = F_S.
  EXPECT_TRUE(testing::Close(at[1].point.force_amplitude * ph, 10.0, 1e-8));
  // With beta > 0 the force is exactly F_S past phi_max: at alpha phi[0] = F_S every larger
  // slip is an equilibrium. The far amplitude is either found on that plateau or flagged. (The
  // static solve balances forces to 1e-12 of K_T u, here 1e6 F_S: the load to about 1e-6.)
  EXPECT_TRUE(testing::Close(at[2].point.force_amplitude * ph, 10.0, 1e-5));
  if (at[2].reached) {
    EXPECT_TRUE(testing::Close(at[2].point.modal_amplitude, s[2], 1e-9));
  }
  EXPECT_THROW(qsma_at(jc, 3, 0, s), InputError);
}

}  // namespace
}  // namespace jointlab::correlate
