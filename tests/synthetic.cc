#include "jointlab/tests/synthetic.h"

#include <array>
#include <cmath>
#include <numbers>
#include <random>

namespace jointlab::testing {

namespace {
struct State {
  double a, theta;
};
State rate(const SlowFlowMode& m, const State& s) {
  const double wn = m.omega_n(s.a), z = m.zeta(s.a);
  return {-z * wn * s.a, wn * std::sqrt(1 - z * z)};
}
}  // namespace

SlowFlowSignal slow_flow(const SlowFlowMode& mode, double fs, Eigen::Index n) {
  SlowFlowSignal out;
  out.a.resize(n);
  out.displacement.resize(n);
  out.velocity.resize(n);
  out.acceleration.resize(n);
  State s{mode.a0, mode.theta0};
  const double h = 1.0 / fs;
  for (Eigen::Index k = 0; k < n; ++k) {
    // Exact derivatives of a cos(theta) along the flow:
    //   x' = a' cos - a th' sin,  x'' = a'' cos - (2 a' th' + a th'') sin - a th'^2 cos,
    // with a'' = (d a'/da) a' and th'' = (d th'/da) a' (central differences in a,
    // relative step 1e-5: error ~1e-10 of these already small terms).
    const State r = rate(mode, s);
    const double da = 1e-5 * s.a;
    const State rp = rate(mode, {s.a + da, s.theta}), rm = rate(mode, {s.a - da, s.theta});
    const double a2 = (rp.a - rm.a) / (2 * da) * r.a;
    const double th2 = (rp.theta - rm.theta) / (2 * da) * r.a;
    const double c = std::cos(s.theta), sn = std::sin(s.theta);
    out.a(k) = s.a;
    out.displacement(k) = s.a * c;
    out.velocity(k) = r.a * c - s.a * r.theta * sn;
    out.acceleration(k) =
        a2 * c - (2 * r.a * r.theta + s.a * th2) * sn - s.a * r.theta * r.theta * c;
    const State k1 = rate(mode, s);
    const State k2 = rate(mode, {s.a + 0.5 * h * k1.a, s.theta + 0.5 * h * k1.theta});
    const State k3 = rate(mode, {s.a + 0.5 * h * k2.a, s.theta + 0.5 * h * k2.theta});
    const State k4 = rate(mode, {s.a + h * k3.a, s.theta + h * k3.theta});
    s.a += h / 6 * (k1.a + 2 * k2.a + 2 * k3.a + k4.a);
    s.theta += h / 6 * (k1.theta + 2 * k2.theta + 2 * k3.theta + k4.theta);
  }
  return out;
}

ThreeModeRecord three_mode_record(double f1_hz, double duration_s, double noise, unsigned seed,
                                  double higher) {
  ThreeModeRecord r;
  const Eigen::Index n = static_cast<Eigen::Index>(std::round(duration_s * r.fs));
  const double w1 = 2 * std::numbers::pi * f1_hz;
  // Microslip-like backbone: s(a) rises from 0 to 1 around a_ref (log-smooth).
  const double a0 = 1e-3, a_ref = 2e-4;
  auto s = [a_ref](double a) {
    const double x = std::pow(a / a_ref, 0.9);
    return x / (1 + x);
  };
  r.first.omega_n = [w1, s](double a) { return w1 * (1.0 - 0.035 * s(a)); };
  r.first.zeta = [s](double a) { return 0.001 + 0.0085 * s(a); };
  r.first.a0 = a0;
  r.first.theta0 = 0.3;
  SlowFlowMode m2{[w1](double) { return 2.7 * w1; }, [](double) { return 0.002; }, 2e-4 * higher,
                  1.0};
  SlowFlowMode m3{[w1](double) { return 6.1 * w1; }, [](double) { return 0.003; }, 5e-5 * higher,
                  2.0};
  const SlowFlowSignal s1 = slow_flow(r.first, r.fs, n);
  const SlowFlowSignal s2 = slow_flow(m2, r.fs, n);
  const SlowFlowSignal s3 = slow_flow(m3, r.fs, n);
  r.first_amplitude = s1.a;
  r.displacement = s1.displacement + s2.displacement + s3.displacement;
  r.acceleration = s1.acceleration + s2.acceleration + s3.acceleration;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  const double nd = noise * r.displacement.cwiseAbs().maxCoeff();
  const double na = noise * r.acceleration.cwiseAbs().maxCoeff();
  for (Eigen::Index k = 0; k < n; ++k) {
    r.displacement(k) += nd * g(rng);
    r.acceleration(k) += na * g(rng);
  }
  return r;
}

InternalResonanceRecord internal_resonance_record(double alpha, double x10, double zeta2,
                                                  double noise, unsigned seed, double duration_s,
                                                  double x20, double phase2, double phase1,
                                                  double f2_hz, double zeta1) {
  InternalResonanceRecord r;
  r.f2_hz = f2_hz;
  r.zeta1 = zeta1;
  const Eigen::Index n = static_cast<Eigen::Index>(std::round(duration_s * r.fs));
  const Eigen::Index pre = static_cast<Eigen::Index>(std::round(0.05 * r.fs));
  const double w1 = 2 * std::numbers::pi * r.f1_hz, w2 = 2 * std::numbers::pi * r.f2_hz;
  const double z1 = r.zeta1;
  using State = std::array<double, 4>;  // x1, v1, x2, v2
  const auto rate = [&](const State& y) {
    return State{y[1], -2 * z1 * w1 * y[1] - w1 * w1 * y[0] - alpha * y[0] * y[2], y[3],
                 -2 * zeta2 * w2 * y[3] - w2 * w2 * y[2] - 0.5 * alpha * y[0] * y[0]};
  };
  const auto axpy = [](const State& y, double h, const State& k) {
    return State{y[0] + h * k[0], y[1] + h * k[1], y[2] + h * k[2], y[3] + h * k[3]};
  };
  constexpr int kSteps = 8;
  const double h = 1.0 / (r.fs * kSteps);
  State y{x10 * std::cos(phase1), -w1 * x10 * std::sin(phase1), x20 * std::cos(phase2),
          -w2 * x20 * std::sin(phase2)};
  r.velocity = Eigen::VectorXd::Zero(n);
  r.amplitude1 = Eigen::VectorXd::Zero(n);
  r.amplitude2 = Eigen::VectorXd::Zero(n);
  for (Eigen::Index k = pre; k < n; ++k) {
    r.velocity(k) = y[1] + 0.7 * y[3];
    r.amplitude1(k) = std::hypot(y[0], y[1] / w1);
    r.amplitude2(k) = std::hypot(y[2], y[3] / w2);
    for (int s = 0; s < kSteps; ++s) {
      const State k1 = rate(y), k2 = rate(axpy(y, h / 2, k1)), k3 = rate(axpy(y, h / 2, k2)),
                  k4 = rate(axpy(y, h, k3));
      for (int i = 0; i < 4; ++i) y[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    }
  }
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, noise);
  for (Eigen::Index k = 0; k < n; ++k) r.velocity(k) += g(rng);
  return r;
}

}  // namespace jointlab::testing
