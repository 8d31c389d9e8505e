#include "jointlab/modal/stepped_sine.h"

#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "jointlab/tests/test_util.h"

namespace jointlab::modal {
namespace {

using testing::Close;
constexpr double kTwoPi = 2 * std::numbers::pi;

struct Mode {
  double f_n = 80.3, zeta = 0.002;
  std::complex<double> q{-2.5, 0.0};  // modal constant [1/kg]
  std::complex<double> r0{1e-8, 2e-10}, r1{3e-9, 0};
  bool viscous = false;
  std::complex<double> h(double f) const {
    const double w = kTwoPi * f, wn = kTwoPi * f_n, wc = kTwoPi * 80.0;
    const double b = viscous ? 2 * zeta * wn * w : 2 * zeta * wn * wn;
    return q / std::complex<double>(wn * wn - w * w, b) + r0 + r1 * (w - wc) / wc;
  }
};

// A table of acceleration response / force over 79..81 Hz with relative complex noise `noise`.
data::SteppedSineTable table_of(const Mode& mode, data::SineControl control, double noise,
                                unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, noise);
  data::SteppedSineTable t;
  t.control = control;
  t.response_quantity = Quantity::kAcceleration;
  const int n = 41;
  t.frequency_hz.resize(n), t.force.resize(n), t.response.resize(n), t.phase_rad.resize(n);
  for (int k = 0; k < n; ++k) {
    const double f = 79.0 + 0.05 * k, w = kTwoPi * f;
    const std::complex<double> a = -w * w * mode.h(f) * std::complex<double>(1 + g(rng), g(rng));
    const double force = 0.7;
    t.frequency_hz(k) = f;
    t.force(k) = force;
    t.response(k) = std::abs(a) * force;
    t.phase_rad(k) = std::arg(a);
  }
  return t;
}

TEST(SteppedSineFit, RecoversAnExactHystereticModeWithResiduals) {
  const Mode mode;
  const auto t = table_of(mode, data::SineControl::kResponse, 0.0, 1);
  const SineFit fit = fit_single_mode(t.frequency_hz, receptance(t), {});
  ASSERT_TRUE(fit.converged);
  // Exact data: the optimum is the truth to rounding (1e-9 relative, 1e-12 in zeta).
  EXPECT_TRUE(Close(fit.frequency_hz, mode.f_n, 1e-10));
  EXPECT_TRUE(Close(fit.damping_ratio, mode.zeta, 1e-8));
  EXPECT_TRUE(Close(fit.modal_constant.real(), mode.q.real(), 1e-7));
  EXPECT_TRUE(Close(fit.residual0.real(), mode.r0.real(), 1e-5));
  EXPECT_LT(fit.rms, 1e-9);
}

TEST(SteppedSineFit, ViscousModelRecoversAViscousMode) {
  Mode mode;
  mode.viscous = true;
  mode.zeta = 0.004;
  const auto t = table_of(mode, data::SineControl::kResponse, 0.0, 1);
  SteppedSineOptions opt;
  opt.damping = SineDamping::kViscous;
  const SineFit fit = fit_single_mode(t.frequency_hz, receptance(t), opt);
  ASSERT_TRUE(fit.converged);
  EXPECT_TRUE(Close(fit.frequency_hz, mode.f_n, 1e-10));
  EXPECT_TRUE(Close(fit.damping_ratio, mode.zeta, 1e-8));
}

// With noise, the errors over 200 draws must match the stated one-sigma uncertainties: the
// RMS of error / sigma within 0.8..1.25 (its sampling spread over 200 draws is about 5 %).
TEST(SteppedSineFit, UncertaintiesMatchTheScatterOfNoisyFits) {
  const Mode mode;
  double sf = 0, sz = 0;
  const int draws = 200;
  for (int d = 0; d < draws; ++d) {
    const auto t = table_of(mode, data::SineControl::kResponse, 0.01, 100 + d);
    const SineFit fit = fit_single_mode(t.frequency_hz, receptance(t), {});
    ASSERT_TRUE(fit.converged);
    sf += std::pow((fit.frequency_hz - mode.f_n) / fit.frequency_sigma_hz, 2);
    sz += std::pow((fit.damping_ratio - mode.zeta) / fit.damping_sigma, 2);
  }
  const double rf = std::sqrt(sf / draws), rz = std::sqrt(sz / draws);
  std::printf("RMS error / sigma over %d draws: frequency %.3f, damping %.3f\n", draws, rf, rz);
  EXPECT_GT(rf, 0.8);
  EXPECT_LT(rf, 1.25);
  EXPECT_GT(rz, 0.8);
  EXPECT_LT(rz, 1.25);
}

TEST(SteppedSineBackbone, ResponseControlledPointIsTheFitAtTheLevel) {
  const Mode mode;
  const auto t = table_of(mode, data::SineControl::kResponse, 0.0, 1);
  // Hold the response at 20 m/s^2 by scaling the force (the FRF is unchanged).
  auto held = t;
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    held.force(k) = t.force(k) * 20.0 / t.response(k);
    held.response(k) = 20.0;
  }
  const SineBackbonePoint p = extract_backbone_point(held, {});
  ASSERT_EQ(p.status, SineStatus::kOk) << p.message;
  EXPECT_TRUE(p.damping_direct);
  EXPECT_TRUE(Close(p.frequency_hz, mode.f_n, 1e-10));
  EXPECT_TRUE(Close(p.damping_ratio, mode.zeta, 1e-8));
  const double w = kTwoPi * mode.f_n;
  EXPECT_TRUE(Close(p.amplitude, 20.0 / w, 1e-10));  // velocity at f_n
  EXPECT_TRUE(Close(p.displacement_m, 20.0 / (w * w), 1e-10));
  SteppedSineOptions disp;
  disp.amplitude = Quantity::kDisplacement;
  EXPECT_TRUE(Close(extract_backbone_point(held, disp).amplitude, 20.0 / (w * w), 1e-10));
}

// A linear mode under force control: the quadrature point is f_n (to the linear
// interpolation between steps 0.05 Hz apart: the phase's curvature there is nil by
// symmetry, 1e-5 relative allowed) and the energy balance gives zeta (|Q| exact, the force
// and amplitude interpolated linearly across the peak: 1 %).
TEST(SteppedSineBackbone, ForceControlledPointIsThePhaseResonance) {
  Mode mode;
  mode.r0 = mode.r1 = 0;
  const auto t = table_of(mode, data::SineControl::kForce, 0.0, 1);
  const SineBackbonePoint p = extract_backbone_point(t, {});
  ASSERT_EQ(p.status, SineStatus::kOk) << p.message;
  EXPECT_FALSE(p.damping_direct);
  EXPECT_TRUE(Close(p.frequency_hz, mode.f_n, 1e-5));
  EXPECT_TRUE(Close(p.damping_ratio, mode.zeta, 0.01));
}

TEST(SteppedSineBackbone, ReversedPhaseConventionIsReported) {
  auto t = table_of(Mode{}, data::SineControl::kResponse, 0.0, 1);
  t.phase_rad = -t.phase_rad;
  const SineBackbonePoint p = extract_backbone_point(t, {});
  EXPECT_NE(p.status, SineStatus::kOk);
  EXPECT_NE(p.report().find("no backbone point"), std::string::npos);
}

TEST(SteppedSineBackbone, ResonanceOutsideTheSweepGivesNoPoint) {
  Mode mode;
  mode.f_n = 83.0;
  const auto t = table_of(mode, data::SineControl::kResponse, 0.001, 1);
  const SineBackbonePoint p = extract_backbone_point(t, {});
  EXPECT_EQ(p.status, SineStatus::kNoResonance) << p.report();
}

}  // namespace
}  // namespace jointlab::modal
