// Issue 2 acceptance: a single mass on a spring with a 4-parameter Iwan element
// in parallel, rung down from an initial velocity by a small time integrator
// written here (Jenkins sliders, velocity Verlet), processed from its
// acceleration. The backbone must agree with the closed-form QSMA of method.md
// section 3:
//   omega^2 = (k0 q + F(q)) / (m q),   zeta = D(q) / (2 pi (k0 q + F(q)) q).
// Everything here is independent of model/: the Iwan formulas are re-derived
// from method.md and the slider model from the Iwan density R phi^chi + S delta.
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/data/record.h"
#include "jointlab/modal/process.h"
#include "jointlab/tests/test_util.h"

namespace jointlab {
namespace {

constexpr double kPi = std::numbers::pi;

struct IwanClosedForm {
  double Fs, Kt, chi, beta, phi_max, R, S;
  IwanClosedForm(double fs, double kt, double x, double b) : Fs(fs), Kt(kt), chi(x), beta(b) {
    const double c = (chi + 1) / (chi + 2);
    phi_max = Fs * (1 + beta) / (Kt * (beta + c));
    R = Fs * (chi + 1) / (std::pow(phi_max, chi + 2) * (beta + c));
    S = Fs / phi_max * beta / (beta + c);
  }
  double force(double u) const {  // virgin curve, 0 <= u < phi_max
    return Kt * u - R * std::pow(u, chi + 2) / ((chi + 1) * (chi + 2));
  }
  double dissipation(double a) const {  // per cycle, microslip
    return 4 * R * std::pow(a, chi + 3) / ((chi + 2) * (chi + 3));
  }
};

// Jenkins sliders discretising the density R phi^chi on (0, phi_max) into bins
// of equal stiffness (each slider at its bin's stiffness-weighted mean slip
// displacement), plus the S slider at phi_max.
struct Sliders {
  std::vector<double> k, phi, pos;  // stiffness, slip displacement, slider position
  Sliders(const IwanClosedForm& iw, int n) {
    const double e = iw.chi + 1;
    const double total = iw.R * std::pow(iw.phi_max, e) / e;
    for (int j = 0; j < n; ++j) {
      const double a = iw.phi_max * std::pow(double(j) / n, 1 / e);
      const double b = iw.phi_max * std::pow(double(j + 1) / n, 1 / e);
      k.push_back(total / n);
      // centroid of phi weighted by R phi^chi on [a, b]
      phi.push_back((std::pow(b, e + 1) - std::pow(a, e + 1)) / (e + 1) /
                    ((std::pow(b, e) - std::pow(a, e)) / e));
    }
    k.push_back(iw.S);
    phi.push_back(iw.phi_max);
    pos.assign(k.size(), 0.0);
  }
  double force(double x) {  // updates the slider positions (history)
    double f = 0;
    for (size_t i = 0; i < k.size(); ++i) {
      const double d = x - pos[i];
      if (d > phi[i]) pos[i] = x - phi[i];
      if (d < -phi[i]) pos[i] = x + phi[i];
      f += k[i] * (x - pos[i]);
    }
    return f;
  }
};

TEST(SdofIwanRingdown, ProcessedBackboneMatchesClosedFormQsma) {
  const double m = 1.0, k0 = std::pow(2 * kPi * 100.0, 2);
  const IwanClosedForm iw(10.0, 0.25 * k0, -0.5, 0.1);
  const double fs = 5120.0, duration = 6.0;
  const int substeps = 10;
  const double a0 = 0.05 * iw.phi_max;  // microslip; zeta about 0.35 % at the top
  const double w0 = std::sqrt((k0 + iw.Kt) / m);

  Sliders sl(iw, 1000);
  const double h = 1.0 / (fs * substeps);
  double x = 0, v = w0 * a0;
  double acc = -(k0 * x + sl.force(x)) / m;
  const auto n = static_cast<Eigen::Index>(duration * fs);
  data::Channel ch;
  ch.name = "acc";
  ch.quantity = Quantity::kAcceleration;
  ch.samples.resize(n);
  for (Eigen::Index s = 0; s < n; ++s) {
    ch.samples(s) = acc;
    for (int j = 0; j < substeps; ++j) {
      x += v * h + 0.5 * acc * h * h;
      const double next = -(k0 * x + sl.force(x)) / m;
      v += 0.5 * (acc + next) * h;
      acc = next;
    }
  }
  data::Record rec;
  rec.source = "sdof.csv";
  rec.fs = fs;
  rec.channels.push_back(ch);

  modal::ProcessOptions opt;
  const double f0 = w0 / (2 * kPi);
  opt.bands = {{0.7 * f0, 1.3 * f0}};
  opt.ringdown.amplitude = Quantity::kDisplacement;
  signal::FftCache cache;
  const modal::RecordResult res = modal::process_record(rec, opt, cache);
  ASSERT_EQ(res.results.size(), 1u);
  const modal::Ringdown& r = res.results[0].ringdown;
  ASSERT_EQ(r.summary.status, modal::RingdownStatus::kOk) << r.summary.message;
  const modal::Backbone& b = r.backbone;
  double worst_f = 0, worst_z = 0;
  for (Eigen::Index i = 0; i < b.size(); ++i) {
    const double q = b.displacement(i);
    const double kq = k0 * q + iw.force(q);
    const double f_qsma = std::sqrt(kq / (m * q)) / (2 * kPi);
    const double z_qsma = iw.dissipation(q) / (2 * kPi * kq * q);
    worst_f = std::max(worst_f, testing::rel_err(b.frequency_hz(i), f_qsma));
    worst_z = std::max(worst_z, testing::rel_err(b.damping(i), z_qsma));
  }
  std::printf(
      "SDOF Iwan: %ld points over %.2f decades, worst frequency error %.2e, worst "
      "damping error %.4f\n",
      long(b.size()), r.summary.amplitude_decades, worst_f, worst_z);
  // Issue 2: within 0.05 % in frequency and 2 % in damping over the span
  // reported. QSMA's energy bookkeeping differs from the ring-down by O(zeta)
  // (about 1 % at zeta = 0.35 %), which the 2 % leaves room for; the sliders'
  // discretisation (1000 bins) and Verlet's period error (1e-5) are far smaller.
  EXPECT_GE(r.summary.amplitude_decades, 1.0);
  EXPECT_LE(worst_f, 5e-4);
  EXPECT_LE(worst_z, 0.02);
}

}  // namespace
}  // namespace jointlab
