// Fixtures the Iwan update's tests share (internal to the tests, not installed): the two-chain
// truth with one noisy velocity backbone, the search box around a start, the one-mode truth
// with the structure's own damping (FloorTruth) and its backbones, and a fit's summary and
// misfit evidence as update-iwan reports them.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/qsma_at.h"
#include "jointlab/correlate/two_chain.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/qsma.h"

namespace jointlab::correlate::iwan_test {

// Truth: the two-chain structure with its A1-A2 joint an Iwan element (Fs 20 N, Kt 5e5 N/m,
// chi -0.5, beta 1). Mode 1 (chain A) moves it; the sensor sits on A5 and reads velocity.
struct Synthetic {
  TwoChainParameters truth;
  std::vector<Sensor> sensors{{"a5", 5, -1.0}};
  IwanTarget target;
  Synthetic() {
    truth.iwan = true;
    const model::Model m = two_chain_structure(truth);
    target.mode = 1;
    // 0.05 % frequency and 3 % damping scatter, like hits of one level.
    target.curves.push_back(
        synthetic_backbone(m, 1, sensors, 0, AmplitudeQuantity::kVelocity, 30, 2.0, 5e-4, 0.03, 7));
  }
};

// The search box of these tests around a start: F_S within a factor 30 of it, gamma 0.05-2,
// chi -0.95-0, beta 0.01-100.
inline IwanBounds box_around(const TwoChainParameters& start) {
  return {start.Fs / 30, start.Fs * 30, 0.05, 2.0, -0.95, 0.0, 0.01, 100};
}

// The same box around an Iwan parameter set's F_S.
inline IwanBounds box_around(const model::IwanParameters& start) {
  return {start.Fs / 30, start.Fs * 30, 0.05, 2.0, -0.95, 0.0, 0.01, 100};
}

// Ring-down backbones of the truth in modal amplitude q (QSMA's ring-down pair plus Z), `points`
// log-spaced from q_lo to q_hi, with relative Gaussian noise of sd f_noise in frequency and
// z_noise in damping (the std columns say so), serially correlated along the points as AR(1)
// of coefficient rho (0: independent), frequency and damping apart.
inline MeasuredBackbone modal_backbone(const model::Model& truth, int points, double q_lo,
                                       double q_hi, double f_noise, double z_noise, unsigned seed,
                                       double rho = 0) {
  const model::JointCondensation jc(truth);
  std::vector<double> q(static_cast<size_t>(points));
  for (int i = 0; i < points; ++i)
    q[static_cast<size_t>(i)] = q_lo * std::pow(q_hi / q_lo, i / (points - 1.0));
  const std::vector<QsmaAtPoint> at = qsma_at(jc, 1, 0, q, AmplitudeFrequency::kFirstHarmonic);
  EXPECT_EQ(at.size(), q.size());
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  MeasuredBackbone b = sized_backbone(BackboneKind::kRingdown, 0, points);
  b.modal = true;
  const double innovation = std::sqrt(1 - rho * rho);  // unit marginal variance
  double ef = 0, ez = 0;
  for (int i = 0; i < points; ++i) {
    const model::QsmaPoint& p = at[static_cast<size_t>(i)].point;
    b.amplitude(i) = q[static_cast<size_t>(i)];
    ef = i == 0 ? n(rng) : rho * ef + innovation * n(rng);
    ez = i == 0 ? n(rng) : rho * ez + innovation * n(rng);
    b.frequency_hz(i) = p.ringdown_frequency_hz * (1 + f_noise * ef);
    b.damping_ratio(i) = p.ringdown_damping_ratio * (1 + z_noise * ez);
    b.frequency_std_hz(i) = f_noise * p.ringdown_frequency_hz;
    b.damping_std(i) = z_noise * p.ringdown_damping_ratio;
  }
  return b;
}

// Truth of the damping-floor checks: 177 Hz, K_T 4 % of the stiffness, F_S 0.5 N (phi_max
// 1.8e-5 m), chi -0.5, beta 0.5 and a floor Z = 5e-4 (the joints' damping runs from 1e-5 at
// the lowest amplitude, far below Z, to 3e-2 past phi_max: both the floor and the joint shape
// the curves).
struct FloorTruth {
  double k_total = std::pow(2 * M_PI * 177.0, 2);
  model::IwanParameters iwan{0.5, 0.04 * std::pow(2 * M_PI * 177.0, 2), -0.5, 0.5};
  double k0 = 0.96 * k_total;
  double z = 5e-4;
  model::Model truth() const { return one_mode_structure(k0, iwan, z); }
  // The model the fit starts from: every Iwan parameter off (F_S x3, K_T x0.8, chi -0.3, beta
  // 2) and no floor.
  model::Model start() const {
    return one_mode_structure(k0, {iwan.Fs * 3, iwan.Kt * 0.8, -0.3, 2.0}, 0.0);
  }
  // A start a little off the truth (F_S x1.3, K_T x0.9, chi -0.4, beta 0.7), so the fit moves.
  model::IwanParameters near() const { return {iwan.Fs * 1.3, iwan.Kt * 0.9, -0.4, 0.7}; }
  // Three hits of 60 points each from q = 1e-8 m to 1.5, 2 and 2.5 phi_max, 1e-4 frequency and
  // 2 % damping noise.
  IwanTarget target(int points = 60, int hits = 3) const {
    IwanTarget t;
    const double phi = model::Iwan(iwan).phi_max();
    for (int h = 0; h < hits; ++h)
      t.curves.push_back(
          modal_backbone(truth(), points, 1e-8, (1.5 + 0.5 * h) * phi, 1e-4, 0.02, 11 + h));
    return t;
  }
  IwanUpdateOptions options() const {
    IwanUpdateOptions o;
    o.fit_linear_damping = true;
    o.bounds = {iwan.Fs / 300, iwan.Fs * 300, 0.05, 2.0, -0.95, 0.0, 0.01, 100};
    o.max_evaluations = 1500;
    return o;
  }
};

// A summary of a fit that ended as `status` after `evaluations` QSMA evaluations, over
// `residuals` residuals at reduced chi-square `chi2`: the report's wording, no fit run.
inline IwanUpdateSummary reported_fit(IwanUpdateStatus status, int evaluations, size_t residuals,
                                      double chi2) {
  IwanUpdateSummary s;
  s.improved = true;
  s.status = status;
  s.evaluations = evaluations;
  s.residuals = residuals;
  s.reduced_chi2 = chi2;
  return s;
}

// Misfit evidence of mode 1: the measured low-amplitude frequency, its relative noise and the
// model's mode 1 as given; the damping factor and largest damping as given.
inline MisfitEvidence mode_one_evidence(double low_hz, double noise, double mode_hz,
                                        double damping_factor, double damping_max) {
  MisfitEvidence e;
  e.mode = 1;
  e.low_frequency_hz = low_hz;
  e.low_frequency_noise = noise;
  e.mode_hz = mode_hz;
  e.damping_factor = damping_factor;
  e.damping_max = damping_max;
  return e;
}

}  // namespace jointlab::correlate::iwan_test
