#include "jointlab/tests/synthetic.h"

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

}  // namespace jointlab::testing
