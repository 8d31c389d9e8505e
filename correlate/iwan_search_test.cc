// The Iwan update's search: the global and local optimisers recover the parameters of
// synthetic backbones (ring-down, stepped sine, sensors, scatter between hits), Monte Carlo
// variants, the Pareto front, boxes, budgets and held parameters.
#include "jointlab/correlate/iwan_update.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/correlate/iwan_update_test_fixtures.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/mode_tracking.h"
#include "jointlab/correlate/two_chain.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/qsma.h"
#include "jointlab/tests/all_dof_newton.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::correlate {
namespace {

using iwan_test::box_around;
using iwan_test::FloorTruth;
using iwan_test::modal_backbone;
using iwan_test::Synthetic;

// The default update in the box around the start, with a budget of `evaluations`.
IwanUpdateOptions options_around(const TwoChainParameters& start, int evaluations) {
  IwanUpdateOptions o;
  o.bounds = box_around(start);
  o.max_evaluations = evaluations;
  return o;
}

// A start off the truth in every parameter: F_S x1.5, K_T x1.2, chi -0.3, beta 0.6.
TwoChainParameters start_off(const TwoChainParameters& truth) {
  TwoChainParameters start = truth;
  start.Fs *= 1.5;
  start.ka *= 1.2;
  start.chi = -0.3;
  start.beta = 0.6;
  return start;
}

// Noiseless ring-down backbones of the truth's mode 1 (20 points each), three hits reaching
// 1.2, 1.6 and 2 times the full-macroslip amplitude, made of the given model columns; the
// model at start_off() of the truth.
struct NoiselessHits {
  TwoChainParameters truth;
  std::vector<Sensor> sensors{{"a5", 5, -1.0}};
  IwanTarget target;
  TwoChainParameters start;
  model::Model m;
  explicit NoiselessHits(IwanComparison columns) {
    truth.iwan = true;
    for (const double top : {1.2, 1.6, 2.0}) {
      target.curves.push_back(synthetic_backbone(two_chain_structure(truth), 1, sensors, 0,
                                                 AmplitudeQuantity::kVelocity, 20, top, 0, 0, 1,
                                                 BackboneKind::kRingdown, columns));
    }
    start = start_off(truth);
    m = two_chain_structure(start);
  }
};

// F_S, K_T, chi and beta of p each within relative `tolerance` of the truth's.
void expect_parameters(const model::IwanParameters& p, const TwoChainParameters& truth,
                       double tolerance) {
  EXPECT_TRUE(testing::Close(p.Fs, truth.Fs, tolerance));
  EXPECT_TRUE(testing::Close(p.Kt, truth.ka, tolerance));
  EXPECT_TRUE(testing::Close(p.chi, truth.chi, tolerance));
  EXPECT_TRUE(testing::Close(p.beta, truth.beta, tolerance));
}

// Samples on two threads give the bit-identical result of one thread (same draws, costs
// recorded in draw order, the Jacobian's shifted evaluations independent of each other).
TEST(IwanUpdate, TwoThreadsGiveTheResultOfOne) {
  Synthetic s;
  TwoChainParameters start = s.truth;
  start.Fs *= 3;
  start.ka *= 3;
  const model::Model m = two_chain_structure(start);
  for (IwanOptimizer method : {IwanOptimizer::kGlobalLocal, IwanOptimizer::kPaperLog}) {
    IwanUpdateSummary one, two;
    model::IwanParameters p[2];
    for (int threads : {1, 2}) {
      const IwanObjective obj(m, "rivet", s.sensors, {s.target}, {});
      IwanUpdateOptions o;
      o.optimizer = method;
      o.bounds = box_around(start);
      o.max_evaluations = 300;
      o.threads = threads;
      p[threads - 1] = update_iwan(obj, o, threads == 1 ? &one : &two);
    }
    EXPECT_EQ(p[0].Fs, p[1].Fs);
    EXPECT_EQ(p[0].Kt, p[1].Kt);
    EXPECT_EQ(p[0].chi, p[1].chi);
    EXPECT_EQ(p[0].beta, p[1].beta);
    EXPECT_EQ(one.final_cost, two.final_cost);
    EXPECT_EQ(one.evaluations, two.evaluations);
    ASSERT_EQ(one.history.size(), two.history.size());
    for (size_t i = 0; i < one.history.size(); ++i) {
      EXPECT_EQ(one.history[i].evaluation, two.history[i].evaluation) << i;
      EXPECT_EQ(one.history[i].cost, two.history[i].cost) << i;
    }
  }
}

TEST(IwanUpdate, GlobalLocalRecoversTheParametersFromFarOff) {
  Synthetic s;
  // Start: Fs x3, Kt x3 (K_s = 1.5e6, so the truth is gamma = 1/3), chi -0.1, beta / 5.
  TwoChainParameters start = s.truth;
  start.Fs *= 3;
  start.ka *= 3;
  start.chi = -0.1;
  start.beta /= 5;
  const model::Model m = two_chain_structure(start);
  const IwanObjective obj(m, "iwan.rivet", s.sensors, {s.target}, {});
  IwanUpdateOptions o;
  o.optimizer = IwanOptimizer::kGlobalLocal;
  o.bounds = box_around(start);
  o.max_evaluations = 1500;
  IwanUpdateSummary sum;
  const model::IwanParameters p = update_iwan(obj, o, &sum);
  SCOPED_TRACE(sum.report());
  RecordProperty("report", sum.report());  // in --gtest_output=xml
  std::printf("%s", sum.report().c_str());
  // Issue 5: Kt within 2 %, Fs, chi and beta within 5 %. The truth backbone runs to twice
  // the full-macroslip amplitude: microslip fixes Kt, chi and R (below phi_max the virgin
  // curve depends on them alone), the macroslip plateau F = F_S fixes F_S, and with R the
  // onset phi_max, hence beta (docs/update-iwan.md). Observed: Kt -0.09 %, Fs -0.04 %,
  // chi -0.1 %, beta +2.1 %.
  EXPECT_TRUE(testing::Close(p.Kt, 5e5, 0.02));
  EXPECT_TRUE(testing::Close(p.Fs, 20.0, 0.05));
  EXPECT_TRUE(testing::Close(p.chi, -0.5, 0.05));
  EXPECT_TRUE(testing::Close(p.beta, 1.0, 0.05));
  const model::Iwan truth(20.0, 5e5, -0.5, 1.0);
  EXPECT_TRUE(testing::Close(model::Iwan(p).R(), truth.R(), 0.05));
  EXPECT_FALSE(sum.microslip_only());                  // the data run past phi_max
  EXPECT_LE(sum.evaluations, o.max_evaluations + 30);  // a Jacobian (9) may finish past it
  EXPECT_LT(sum.final_cost, sum.initial_cost);
  ASSERT_FALSE(sum.history.empty());
  EXPECT_EQ(sum.history.back().best, sum.final_cost);
}

// Three hits whose backbones reach past the joint's macroslip (tops at 1.2, 1.6 and 2 times the
// full-macroslip amplitude), with processing-like scatter (2e-4 in frequency, 2 % in damping,
// as the std columns say). The model is evaluated at each measured amplitude, so at the truth
// the residuals are the planted noise itself: the truth's cost equals the noise's cost. The
// update must then find every parameter within 2 % and the truth within three reported sigma.
struct MacroslipHits {
  TwoChainParameters truth;
  std::vector<Sensor> sensors{{"a5", 5, -1.0}};
  IwanTarget target;
  double noise_cost = 0;  // sum of squared normalised planted noise / N
  explicit MacroslipHits(unsigned seed) {
    truth.iwan = true;
    const model::Model m = two_chain_structure(truth);
    const double tops[] = {1.2, 1.6, 2.0};
    double sum = 0;
    int n = 0;
    for (int h = 0; h < 3; ++h) {
      const MeasuredBackbone b = synthetic_backbone(m, 1, sensors, 0, AmplitudeQuantity::kVelocity,
                                                    30, tops[h], 2e-4, 0.02, seed + h);
      const MeasuredBackbone c = synthetic_backbone(m, 1, sensors, 0, AmplitudeQuantity::kVelocity,
                                                    30, tops[h], 0, 0, seed + h);
      for (Eigen::Index j = 0; j < b.amplitude.size(); ++j) {
        const double sf = std::max(b.frequency_std_hz(j), 1e-4 * b.frequency_hz(j));
        const double sz = std::max(b.damping_std(j), 0.02 * b.damping_ratio(j));
        sum += std::pow((b.frequency_hz(j) - c.frequency_hz(j)) / sf, 2) +
               std::pow((b.damping_ratio(j) - c.damping_ratio(j)) / sz, 2);
        ++n;
      }
      target.curves.push_back(b);
    }
    noise_cost = sum / n;
  }
};

TEST(IwanUpdate, MacroslipHitsRecoverEveryParameterWithinItsUncertainty) {
  const MacroslipHits s(41);
  TwoChainParameters start = s.truth;
  start.Fs *= 2;
  start.ka *= 1.3;
  start.chi = -0.3;
  start.beta = 0.5;
  const model::Model m = two_chain_structure(start);
  const IwanObjective obj(m, "rivet", s.sensors, {s.target}, {});
  const model::IwanParameters known{s.truth.Fs, s.truth.ka, s.truth.chi, s.truth.beta};
  // Exact evaluation: the truth's cost is the planted noise's, to the solver's accuracy.
  EXPECT_TRUE(testing::Close(obj.cost(known), s.noise_cost, 1e-6));
  // The ring-down damping jumps where the element reaches phi_max (its beta sliders slip at
  // once), so the cost is only piecewise smooth near the knee: 1500 evaluations stopped at
  // 2.11 against the truth's 1.91, 3000 reach below it.
  const IwanUpdateOptions o = options_around(start, 3000);
  IwanUpdateSummary sum;
  const model::IwanParameters p = update_iwan(obj, o, &sum);
  SCOPED_TRACE(sum.report());
  std::printf("%s  cost at the truth %.4g (planted noise %.4g)\n", sum.report().c_str(),
              obj.cost(known), s.noise_cost);
  EXPECT_FALSE(sum.microslip_only());
  EXPECT_LE(sum.final_cost, obj.cost(known) * 1.001);
  const double found[] = {p.Fs, p.Kt, p.chi, p.beta};
  const double truth[] = {s.truth.Fs, s.truth.ka, s.truth.chi, s.truth.beta};
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(k);
    EXPECT_TRUE(testing::Close(found[k], truth[k], 0.02));
    // relative_std is of ln F_S, ln K_T, ln beta and of chi relative to |chi|.
    const double err = k == 2 ? std::abs(found[k] - truth[k]) / std::abs(found[k])
                              : std::abs(std::log(found[k] / truth[k]));
    EXPECT_GT(sum.relative_std(k), 0.0);
    EXPECT_LE(err, 3 * sum.relative_std(k));
  }
}

// A sensor's backbone read as it is measured, independently of the code under test: the truth's
// QSMA load levels (three hits to 1.2, 1.6 and 2 times the full-macroslip amplitude, 30 points
// each), at each the all-DOF Newton (tests/all_dof_newton.h: every DOF, no condensation) gives
// the velocity amplitude |u_5| omega_1 at sensor a5; the ring-down columns carry Gaussian noise
// (2e-4 in frequency, 2 % in damping, stated so). With `misread` the amplitude is the linear
// mode's |phi_5| q omega_1 instead: what the fit took a sensor's amplitude for before.
IwanTarget all_dof_sensor_hits(const TwoChainParameters& truth, unsigned seed, bool misread) {
  const model::Model m = two_chain_structure(truth);
  const model::JointCondensation jc(m);
  const Eigen::Index dof = 5;
  const int column = jc.modes().rigid_count;
  testing::AllDofNewton reference(m, jc.modes(), column);
  model::QsmaSummary qs;
  const double end = model::qsma(jc, 1, {}, &qs).back().modal_amplitude;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  IwanTarget target;
  target.mode = 1;
  for (const double top : {1.2, 1.6, 2.0}) {
    model::QsmaOptions o;
    o.points = 30;
    o.q_max = top * end;
    o.q_min = 0.01 * o.q_max;
    const auto curve = model::qsma(jc, 1, o, &qs);
    MeasuredBackbone b = sized_backbone(BackboneKind::kRingdown, 0, o.points);
    for (Eigen::Index i = 0; i < o.points; ++i) {
      const model::QsmaPoint& p = curve[static_cast<size_t>(i)];
      EXPECT_TRUE(reference.solve(p.force_amplitude));
      const double x = misread ? std::abs(jc.modes().shapes(dof, column)) * p.modal_amplitude
                               : std::abs(reference.u()(dof));
      b.amplitude(i) = x * 2 * std::numbers::pi * p.ringdown_frequency_hz;
      b.frequency_hz(i) = p.ringdown_frequency_hz * (1 + 2e-4 * g(rng));
      b.damping_ratio(i) = p.ringdown_damping_ratio * (1 + 0.02 * g(rng));
      b.frequency_std_hz(i) = 2e-4 * p.ringdown_frequency_hz;
      b.damping_std(i) = 0.02 * p.ringdown_damping_ratio;
    }
    target.curves.push_back(b);
  }
  return target;
}

// The issue: a sensor's amplitude was turned into the modal amplitude with the linear shape,
// a = |phi[d]| q omega^p, where the deflected shape of a slipping joint differs (a root joint
// of a clamped beam: u_tip / (q phi_tip) 0.980 at 1.6 phi_max), and F_S came out 0.6-2.6 % low,
// outside its stated sigma. Fitted against the all-DOF deflection at the sensor, F_S must lie
// within 3 of its stated sigma of the truth on each of three seeds (|z| <= 3: a miss of a
// correct sigma once in 370 draws); the same data misread with the linear shape must not
// (checked, so the test can fail: the misreading moves F_S by more than 3 sigma here).
TEST(IwanUpdate, SensorBackbonesGiveSlipForceWithinItsSigma) {
  TwoChainParameters truth;
  truth.iwan = true;
  TwoChainParameters start = truth;
  start.Fs *= 2;
  start.ka *= 1.3;
  start.chi = -0.3;
  start.beta = 0.5;
  const model::Model m = two_chain_structure(start);
  const std::vector<Sensor> sensors{{"a5", 5, -1.0}};
  const auto z_fs = [&](unsigned seed, bool misread) {
    const IwanObjective obj(m, "rivet", sensors, {all_dof_sensor_hits(truth, seed, misread)}, {});
    IwanUpdateSummary sum;
    const model::IwanParameters p = update_iwan(obj, options_around(start, 3000), &sum);
    EXPECT_GT(sum.relative_std(0), 0.0) << sum.report();
    const double z = std::log(p.Fs / truth.Fs) / sum.relative_std(0);
    std::printf("seed %u%s: F_S %.5g (%+.3f %%), sigma %.3g %%, z %+.2f\n", seed,
                misread ? " (misread)" : "", p.Fs, 100 * (p.Fs / truth.Fs - 1),
                100 * sum.relative_std(0), z);
    return z;
  };
  for (const unsigned seed : {41u, 42u, 43u}) {
    EXPECT_LE(std::abs(z_fs(seed, false)), 3.0) << "seed " << seed;
  }
  EXPECT_GT(std::abs(z_fs(41, true)), 3.0) << "the misread amplitude is not told apart";
}

// Like with like: noiseless ring-down backbones straight from QSMA's ring-down columns of the
// truth (first-harmonic frequency, D / (2 pi q dE/dq), amplitude at the first-harmonic
// frequency), three hits reaching 1.2, 1.6 and 2 times the full-macroslip amplitude. Compared
// with the ring-down columns (the default) the truth's cost is 0 up to the 1e-10 placement of
// the amplitudes, and the update from a start off in every parameter gives the truth back
// within 0.5 % (noiseless data: what is left is the optimiser's tolerance on a flat valley of
// F_S against beta). Compared with the secant pair the same data cost far more at the truth:
// the two definitions differ by more than the damping floor of 2 % past the knee.
TEST(IwanUpdate, RingdownBackbonesGiveTheirParametersBackComparedLikeWithLike) {
  const NoiselessHits c(IwanComparison::kMatched);
  const model::IwanParameters known{c.truth.Fs, c.truth.ka, c.truth.chi, c.truth.beta};
  const IwanObjective like(c.m, "rivet", c.sensors, {c.target}, {});
  IwanUpdateOptions secant_pair;
  secant_pair.comparison = IwanComparison::kSecant;
  const IwanObjective secant(c.m, "rivet", c.sensors, {c.target}, secant_pair);
  std::printf("cost at the truth: ring-down columns %.3g, secant pair %.3g\n", like.cost(known),
              secant.cost(known));
  EXPECT_LT(like.cost(known), 1e-12);
  EXPECT_GT(secant.cost(known), 1.0);
  IwanUpdateSummary sum;
  const model::IwanParameters p = update_iwan(like, options_around(c.start, 800), &sum);
  SCOPED_TRACE(sum.report());
  std::printf("%s", sum.report().c_str());
  expect_parameters(p, c.truth, 0.005);
}

// The secant option keeps the paper's comparison: backbones made of QSMA's secant pair (as the
// paper's synthetic data) give their parameters back when compared with it, within 0.5 % as
// above.
TEST(IwanUpdate, SecantBackbonesGiveTheirParametersBackComparedWithTheSecantPair) {
  const NoiselessHits c(IwanComparison::kSecant);
  IwanUpdateOptions o = options_around(c.start, 800);
  o.comparison = IwanComparison::kSecant;
  const IwanObjective obj(c.m, "rivet", c.sensors, {c.target}, o);
  EXPECT_LT(obj.cost({c.truth.Fs, c.truth.ka, c.truth.chi, c.truth.beta}), 1e-12);
  IwanUpdateSummary sum;
  const model::IwanParameters p = update_iwan(obj, o, &sum);
  SCOPED_TRACE(sum.report());
  expect_parameters(p, c.truth, 0.005);
}

// Hammer and stepped sine together. Ring-downs pass through macroslip within a cycle or two,
// so their backbones stay in microslip (here: three hits topping at 0.3, 0.4 and 0.5 times the
// full-macroslip amplitude, 2e-4 in frequency and 2 % in damping as `process` gives); a
// stepped sine holds each level, so its points reach past the knee (one sweep set of 10 levels
// up to twice the full-macroslip amplitude, scatter 1e-4 and 3 %, each point compared with the
// first-harmonic pair). Fitted jointly from a start off in every parameter, F_S and beta come
// back within 5 % and K_T and chi within 2 %; the ring-downs alone are microslip only, where
// K_T, chi and R = f(F_S, beta) are identified but F_S and beta are not separately.
struct HammerAndSteppedSine {
  TwoChainParameters truth;
  std::vector<Sensor> sensors{{"a5", 5, -1.0}};
  IwanTarget hammer, sine;
  HammerAndSteppedSine() {
    truth.iwan = true;
    const model::Model m = two_chain_structure(truth);
    unsigned seed = 300;
    for (const double top : {0.3, 0.4, 0.5}) {
      hammer.curves.push_back(synthetic_backbone(m, 1, sensors, 0, AmplitudeQuantity::kVelocity, 20,
                                                 top, 2e-4, 0.02, seed++));
    }
    sine.curves.push_back(synthetic_backbone(m, 1, sensors, 0, AmplitudeQuantity::kVelocity, 10,
                                             2.0, 1e-4, 0.03, seed++, BackboneKind::kSteppedSine));
  }
};

TEST(IwanUpdate, HammerAndSteppedSineTogetherIdentifySlipForceAndBeta) {
  const HammerAndSteppedSine s;
  const TwoChainParameters start = start_off(s.truth);
  const model::Model m = two_chain_structure(start);
  IwanTarget both = s.hammer;
  both.curves.push_back(s.sine.curves.front());
  const IwanObjective obj(m, "rivet", s.sensors, {both}, {});
  const IwanUpdateOptions o = options_around(start, 800);
  IwanUpdateSummary sum;
  const model::IwanParameters p = update_iwan(obj, o, &sum);
  SCOPED_TRACE(sum.report());
  std::printf("hammer + stepped sine: %s", sum.report().c_str());
  EXPECT_FALSE(sum.microslip_only());
  EXPECT_TRUE(testing::Close(p.Fs, s.truth.Fs, 0.05));
  EXPECT_TRUE(testing::Close(p.beta, s.truth.beta, 0.05));
  EXPECT_TRUE(testing::Close(p.Kt, s.truth.ka, 0.02));
  EXPECT_TRUE(testing::Close(p.chi, s.truth.chi, 0.02));
  // The ring-downs alone never leave microslip at the truth: F_S and beta are one family.
  const IwanObjective hammer(m, "rivet", s.sensors, {s.hammer}, {});
  const model::IwanParameters known{s.truth.Fs, s.truth.ka, s.truth.chi, s.truth.beta};
  const Eigen::Vector2d slip = hammer.slip_range(known);
  EXPECT_LT(slip(1), model::Iwan(known).phi_max());
}

// A campaign in miniature: 8 hits whose joints scatter about the truth (K_T 2 %, F_S 3 %, one
// sigma, as the example campaign), each backbone stopping at 30 % of the full-macroslip
// amplitude, so every joint stays in microslip. The update with beta held (the campaign's
// first pass) must find K_T, chi and the microslip dissipation within twice the planted scatter,
// say that the data are microslip only, and reach at least the fit of the known parameters.
TEST(IwanUpdate, MicroslipHitsWithPlantedScatterRecoverKtChiAndDissipation) {
  TwoChainParameters truth;
  truth.iwan = true;
  truth.beta = 0.8;
  const double s_kt = 0.02, s_fs = 0.03;
  const std::vector<Sensor> sensors{{"a5", 5, -1.0}};
  IwanTarget target;
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  for (unsigned hit = 0; hit < 8; ++hit) {
    TwoChainParameters h = truth;
    h.ka *= 1 + s_kt * g(rng);
    h.Fs *= 1 + s_fs * g(rng);
    // Processing-like noise: 2e-4 in frequency, 2 % in damping.
    target.curves.push_back(synthetic_backbone(two_chain_structure(h), 1, sensors, 0,
                                               AmplitudeQuantity::kVelocity, 20, 0.3, 2e-4, 0.02,
                                               100 + hit));
  }
  // Start: K_T -15 %, F_S +50 %, chi -0.3, beta 1 (held there: not the truth's 0.8).
  TwoChainParameters start = truth;
  start.ka *= 0.85;
  start.Fs *= 1.5;
  start.chi = -0.3;
  start.beta = 1.0;
  const model::Model m = two_chain_structure(start);
  const IwanObjective obj(m, "rivet", sensors, {target}, {});
  IwanUpdateOptions o;
  o.bounds = {start.Fs / 30, start.Fs * 30, 0.3, 3.0, -0.95, 0.0, 0.01, 100};
  o.fixed_beta = 1.0;
  o.max_evaluations = 600;
  IwanUpdateSummary sum;
  const model::IwanParameters p = update_iwan(obj, o, &sum);
  SCOPED_TRACE(sum.report());
  std::printf("%s", sum.report().c_str());
  const model::IwanParameters known{truth.Fs, truth.ka, truth.chi, truth.beta};
  EXPECT_TRUE(sum.microslip_only());
  EXPECT_GT(sum.top_slip, sum.bottom_slip);
  EXPECT_LT(sum.top_slip, model::Iwan(known).phi_max());
  EXPECT_EQ(p.beta, 1.0);
  // Never worse than the known parameters (up to the Ceres tolerance).
  EXPECT_LE(sum.final_cost, obj.cost(known) * 1.001);
  // K_T within twice its planted scatter.
  EXPECT_TRUE(testing::Close(p.Kt, truth.ka, 2 * s_kt));
  // chi: no scatter planted; within twice the cluster-robust uncertainty the planted scatter
  // causes, which must be a real, small number (0 would mean "unknown").
  EXPECT_GT(sum.relative_std(2), 0.0);
  EXPECT_LT(sum.relative_std(2), 0.1);
  EXPECT_NEAR(p.chi, truth.chi, 2 * sum.relative_std(2) * std::abs(p.chi));
  EXPECT_EQ(sum.relative_std(3), 0.0);  // beta held
  // The identified combination: D at the middle slip. Planted scatter of ln D = ln R + const:
  // R ~ F_S^-(chi+1) K_T^(chi+2), so sqrt(((chi+1) 3 %)^2 + ((chi+2) 2 %)^2) = 3.4 %.
  const double u = std::sqrt(sum.bottom_slip * sum.top_slip);
  const double s_d = std::hypot((truth.chi + 1) * s_fs, (truth.chi + 2) * s_kt);
  EXPECT_TRUE(
      testing::Close(model::Iwan(p).dissipation(u), model::Iwan(known).dissipation(u), 2 * s_d));
  // F_S on its own is not identified: with beta held at 1 it must move away from the truth to
  // keep R (here by more than the planted scatter), which is why the report does not judge it.
  EXPECT_FALSE(testing::Close(p.Fs, truth.Fs, 2 * s_fs));
  // With beta held F_S has the sigma it has at that beta.
  EXPECT_GT(sum.relative_std(0), 0.0);

  // With beta free, ending in microslip, F_S stands for R and its own sigma is unknown: it is
  // not stated (before: a sigma of under 1 % for an F_S that moves freely with beta).
  IwanUpdateOptions free_beta = o;
  free_beta.fixed_beta.reset();
  IwanUpdateSummary sf;
  update_iwan(obj, free_beta, &sf);
  SCOPED_TRACE(sf.report());
  if (sf.microslip_only()) {
    EXPECT_EQ(sf.relative_std(0), 0.0);
    EXPECT_EQ(sf.relative_std(3), 0.0);
    EXPECT_NE(sf.report().find("(not identified apart from Fs: microslip only)"),
              std::string::npos);
    EXPECT_NE(sf.report().find("Fs " + fmt::format("{:.6g} -> {:.6g} N", sf.start.Fs, sf.best.Fs) +
                               " (not identified apart from beta: microslip only)"),
              std::string::npos);
  } else {
    ADD_FAILURE() << "the fit with beta free left microslip";
  }
}

// A search that did not converge says so and what --evaluations to use, whatever the
// chi-square (before, only with a misfit: a fit cut off at reduced chi-square 0.68 said nothing);
// one that stopped at a bound with a misfit says it may have missed the best fit, and nothing of
// it when the model describes the data.
TEST(IwanUpdate, AShortSearchWithAMisfitSuggestsMoreEvaluations) {
  IwanUpdateSummary s;
  s.improved = true;
  s.status = IwanUpdateStatus::kBudget;
  s.evaluations = 2807;
  s.residuals = 180;
  s.reduced_chi2 = 9.69;
  const std::string short_fit = "WARNING: the fit did not converge";
  EXPECT_NE(s.report().find(short_fit), std::string::npos) << s.report();
  EXPECT_NE(s.report().find("--evaluations (e.g. 11228)"), std::string::npos) << s.report();
  s.reduced_chi2 = 0.68;  // the cantilever's: no misfit, and still not converged
  EXPECT_NE(s.report().find(short_fit), std::string::npos) << s.report();
  s.status = IwanUpdateStatus::kConverged;
  EXPECT_EQ(s.report().find(short_fit), std::string::npos) << s.report();
  const std::string missed = "it may have missed the best fit rather than the model being wrong";
  s.at_bounds = {"Fs at its upper bound 600 N"};
  s.reduced_chi2 = 9.69;
  EXPECT_NE(s.report().find(missed), std::string::npos) << s.report();
  s.reduced_chi2 = 1.1;  // within 1 + 3 sqrt(2 / 180) = 1.32
  EXPECT_EQ(s.report().find(missed), std::string::npos) << s.report();
}

// beta = 0 (no macroslip delta, method.md) is in the domain and can be held: every optimiser
// keeps it at exactly 0 (its search coordinate ln beta is no finite number, so the held value
// must not go through it), and with noiseless backbones of a beta = 0 truth reaching 1.2 to 2
// times full macroslip the global-local update recovers F_S, K_T and chi.
TEST(IwanUpdate, BetaHeldAtZero) {
  TwoChainParameters truth;
  truth.iwan = true;
  truth.beta = 0;
  const std::vector<Sensor> sensors{{"a5", 5, -1.0}};
  IwanTarget target;
  for (const double top : {1.2, 1.6, 2.0}) {
    target.curves.push_back(synthetic_backbone(two_chain_structure(truth), 1, sensors, 0,
                                               AmplitudeQuantity::kVelocity, 20, top, 0, 0, 1));
  }
  TwoChainParameters start = start_off(truth);
  start.beta = 0;
  const model::Model m = two_chain_structure(start);  // the objective refers to it
  const IwanObjective obj(m, "rivet", sensors, {target}, {});
  for (const IwanOptimizer optimizer :
       {IwanOptimizer::kGlobalLocal, IwanOptimizer::kPaper, IwanOptimizer::kPaperLog}) {
    SCOPED_TRACE(static_cast<int>(optimizer));
    IwanUpdateOptions o = options_around(start, 400);
    o.optimizer = optimizer;
    o.fixed_beta = 0.0;
    IwanUpdateSummary sum;
    const model::IwanParameters p = update_iwan(obj, o, &sum);
    SCOPED_TRACE(sum.report());
    std::printf("%s", sum.report().c_str());
    EXPECT_NE(sum.status, IwanUpdateStatus::kNoValidPoint);
    EXPECT_EQ(p.beta, 0.0);
    EXPECT_TRUE(std::isfinite(sum.final_cost));
    EXPECT_LT(sum.final_cost, sum.initial_cost);
    EXPECT_EQ(sum.relative_std(3), 0.0);  // held
    // Noiseless data and the right beta: the local search ends at the truth. 1e-3 allows for
    // the finite-difference Jacobian and Ceres' stopping tolerances.
    if (optimizer == IwanOptimizer::kGlobalLocal) {
      EXPECT_TRUE(testing::Close(p.Fs, truth.Fs, 1e-3)) << p.Fs;
      EXPECT_TRUE(testing::Close(p.Kt, truth.ka, 1e-3)) << p.Kt;
      EXPECT_TRUE(testing::Close(p.chi, truth.chi, 1e-3)) << p.chi;
    }
  }
  IwanUpdateOptions bad = options_around(start, 400);
  bad.fixed_beta = -0.1;
  EXPECT_EQ(bad.error(), "fixed_beta must be a finite number >= 0");
}

TEST(IwanUpdate, MonteCarloVariantsImproveAndParetoFrontMarksDominance) {
  Synthetic s;
  const model::Model m = two_chain_structure(s.truth);
  const IwanObjective obj(m, "rivet", s.sensors, {s.target}, {});
  IwanUpdateOptions o;
  o.bounds = {5, 80, 0.5, 1.5, -0.9, -0.1, 0.1, 10};
  o.max_evaluations = 300;
  for (IwanOptimizer opt : {IwanOptimizer::kPaper, IwanOptimizer::kPaperLog}) {
    o.optimizer = opt;
    IwanUpdateSummary sum;
    update_iwan(obj, o, &sum);
    EXPECT_GT(sum.rounds, 0);
    EXPECT_LE(sum.evaluations, o.max_evaluations);
    // The best of 300 samples in this box beats a start 10 % off in Kt.
    EXPECT_LT(sum.final_cost, obj.cost({20, 5.5e5, -0.5, 1.0}));
  }
  IwanTarget t = s.target;
  t.linear_frequency_hz = 57.9;
  const IwanObjective obj2(m, "rivet", s.sensors, {t}, {});
  o.optimizer = IwanOptimizer::kGlobalLocal;
  o.max_evaluations = 200;
  const auto front = pareto_front(obj2, {0.8, 1.0}, o);
  ASSERT_EQ(front.size(), 2u);
  // gamma = 1 is the truth: its point matches both the linear frequency and the backbone,
  // so it dominates gamma = 0.8.
  EXPECT_FALSE(front[1].dominated);
  EXPECT_TRUE(front[0].dominated);
  EXPECT_LT(front[1].linear_error, 0.01);
}

// Started at the truth inside the box, no Monte Carlo sample beats the start (cost 0 there):
// the summary says so and names the working method. With gamma held the result holds it too.
TEST(IwanUpdate, MonteCarloSaysWhenNoSampleImprovesAndHeldGammaIsHeld) {
  Synthetic s;
  const model::Model m = two_chain_structure(s.truth);
  const IwanObjective obj(m, "rivet", s.sensors, {s.target}, {});
  IwanUpdateOptions o;
  o.optimizer = IwanOptimizer::kPaper;
  o.bounds = {10, 40, 0.5, 1.5, -0.9, -0.1, 0.1, 10};
  o.max_evaluations = 200;
  IwanUpdateSummary sum;
  const model::IwanParameters p = update_iwan(obj, o, &sum);
  EXPECT_FALSE(sum.improved);
  EXPECT_EQ(p.Fs, 20.0);
  EXPECT_TRUE(sum.at_bounds.empty());
  EXPECT_NE(sum.report().find("no candidate improved"), std::string::npos) << sum.report();
  EXPECT_NE(sum.report().find("global-local"), std::string::npos) << sum.report();
  // The start is no fit: no sigma anywhere, and the same words in the report and the notes
  // (parameters.csv, Python). Before, the report said "(sigma unknown)" where the notes said
  // "the start: no candidate improved on it".
  EXPECT_EQ(sum.relative_std, Eigen::Vector4d::Zero());
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(sum.sigma_reason(k), IwanSigmaReason::kStart);
    EXPECT_EQ(sum.parameter_note(k), "the start: no candidate improved on it");
  }
  EXPECT_NE(sum.report().find("Fs 20 -> 20 N (the start: no candidate improved on it)"),
            std::string::npos)
      << sum.report();
  // gamma held at 0.8 while the start is at 1: never the start's K_T.
  o.fixed_gamma = 0.8;
  const model::IwanParameters q = update_iwan(obj, o, &sum);
  EXPECT_DOUBLE_EQ(q.Kt, 0.8 * obj.reference_stiffness());
}

// A box that excludes the truth (F_S = 20 N, the start): the result lies inside the box, never
// at the better-fitting start; the local search's summary names the bound the fit ends at (the
// cost falls towards F_S = 20, so F_S ends at the lower bound 60 N) instead of calling it
// converged.
TEST(IwanUpdate, ABoxWithoutTheStartGivesAResultInsideItAndNamesTheBound) {
  Synthetic s;
  const model::Model m = two_chain_structure(s.truth);
  const IwanObjective obj(m, "rivet", s.sensors, {s.target}, {});
  for (const IwanOptimizer method : {IwanOptimizer::kPaper, IwanOptimizer::kGlobalLocal}) {
    IwanUpdateOptions o;
    o.optimizer = method;
    o.bounds = {60, 80, 0.5, 1.5, -0.9, -0.1, 0.1, 10};
    o.max_evaluations = 200;
    IwanUpdateSummary sum;
    const model::IwanParameters p = update_iwan(obj, o, &sum);
    EXPECT_GE(p.Fs, 60.0);
    EXPECT_LE(p.Fs, 80.0);
    EXPECT_EQ(sum.best.Fs, p.Fs);
    EXPECT_TRUE(sum.improved);
    EXPECT_EQ(sum.report().find("no candidate improved"), std::string::npos) << sum.report();
    // A bound is called one only at the bound itself (to rounding); short of it, within 1e-3 of
    // the range, the value is named beside it ("Fs 60.3 N, near its lower bound 60 N").
    for (const std::string& b : sum.at_bounds) {
      if (!b.starts_with("Fs")) continue;
      if (b.find("near") == std::string::npos) {
        EXPECT_NEAR(p.Fs, b.find("lower") != std::string::npos ? 60.0 : 80.0, 1e-9 * 80) << b;
      } else {
        EXPECT_NE(b.find(fmt::format("Fs {:.6g} N, near its", p.Fs)), std::string::npos) << b;
      }
    }
    if (method == IwanOptimizer::kPaper) continue;  // its samples rarely land on a bound
    ASSERT_FALSE(sum.at_bounds.empty()) << sum.report();
    EXPECT_EQ(sum.at_bounds.front(), "Fs at its lower bound 60 N") << sum.report();
    EXPECT_NE(sum.report().find("WARNING: Fs at its lower bound 60 N"), std::string::npos)
        << sum.report();
    EXPECT_EQ(sum.report().find("Iwan update: converged"), std::string::npos) << sum.report();
  }
}

// --linear-damping fit on noisy backbones of a planted joint and floor: every parameter, the
// floor included, within 2 % of the truth and within 3 of its stated sigma. With 180 points
// at 2 % damping and 1e-4 frequency noise the stated sigma are 0.1-1 %, so 2 % is the issue's
// acceptance with room, and 3 sigma a test of the sigma itself (a sigma ten times too small
// would fail it).
TEST(IwanUpdate, FitsTheStructuresOwnDampingWithTheJoint) {
  const FloorTruth t;
  const model::Model start = t.start();
  const IwanObjective obj(start, "j", {}, {t.target()}, t.options());
  IwanUpdateSummary s;
  const model::IwanParameters p = update_iwan(obj, t.options(), &s);
  RecordProperty("report", s.report());
  std::printf("%s", s.report().c_str());
  ASSERT_TRUE(s.improved) << s.report();
  EXPECT_TRUE(s.at_bounds.empty()) << s.report();
  const double truth[] = {t.iwan.Fs, t.iwan.Kt, t.iwan.chi, t.iwan.beta};
  const double found[] = {p.Fs, p.Kt, p.chi, p.beta};
  for (int k = 0; k < 4; ++k) {
    const double rel = std::abs(found[k] / truth[k] - 1);
    EXPECT_LT(rel, 0.02) << k << "\n" << s.report();
    ASSERT_GT(s.relative_std(k), 0) << k;
    EXPECT_LT(rel, 3 * s.relative_std(k)) << k << "\n" << s.report();
  }
  EXPECT_LT(std::abs(s.modal_ratio / t.z - 1), 0.02) << s.report();
  ASSERT_GT(s.modal_ratio_std, 0);
  EXPECT_LT(std::abs(s.modal_ratio - t.z), 3 * s.modal_ratio_std) << s.report();
  // Never worse than the best constant backbone (a candidate of the fit).
  EXPECT_LE(s.final_cost, s.constant_cost);
  // The updated model carries the floor.
  EXPECT_EQ(obj.apply(p, s.modal_ratio).modal_ratio, s.modal_ratio);
}

// chi above 0 is an Iwan element (method.md: -1 < chi): FloorTruth's one-mode joint and floor at
// chi 0.3, started at chi 0.2 (F_S x3, K_T x0.8, beta 2, no floor). With --chi-range -0.9:0.9
// every parameter comes back within 3 of its stated sigma (measured: chi 0.3062 +/- 2.8 %, 0.7
// sigma off; as above, 3 sigma tests the sigma itself). A range stopping at 0, the default's
// modelling choice (a Coulomb interface's microslip dissipation rises at most as A^3, chi <= 0),
// leaves the fit at chi's upper bound, and it says so (the bound line, "stopped at a bound",
// reduced chi-square 6.4 and no sigma) rather than claiming convergence. Before, the start was
// refused (chi = 0.2 must be in (-1, 0]) and so was the range.
TEST(IwanUpdate, ChiAboveZeroIsRecoveredInARangeThatReachesIt) {
  FloorTruth t;
  t.iwan.chi = 0.3;
  const model::IwanParameters start_p{t.iwan.Fs * 3, t.iwan.Kt * 0.8, 0.2, 2.0};
  ASSERT_EQ(model::iwan_parameter_error(start_p), "");
  const model::Model start = one_mode_structure(t.k0, start_p, 0.0);
  const IwanTarget target = t.target();
  const auto fit = [&](double chi_max) {
    IwanUpdateOptions o = t.options();
    o.bounds.chi_min = -0.9;
    o.bounds.chi_max = chi_max;
    const IwanObjective obj(start, "j", {}, {target}, o);
    IwanUpdateSummary s;
    update_iwan(obj, o, &s);
    return s;
  };
  const IwanUpdateSummary wide = fit(0.9);
  SCOPED_TRACE(wide.report());
  ASSERT_TRUE(wide.improved);
  EXPECT_TRUE(wide.at_bounds.empty());
  const double truth[] = {t.iwan.Fs, t.iwan.Kt, t.iwan.chi, t.iwan.beta};
  const double found[] = {wide.best.Fs, wide.best.Kt, wide.best.chi, wide.best.beta};
  for (int k = 0; k < 4; ++k) {
    ASSERT_GT(wide.relative_std(k), 0) << k;
    EXPECT_LT(std::abs(found[k] / truth[k] - 1), 3 * wide.relative_std(k)) << k;
  }
  RecordProperty("chi", fmt::format("{} +/- {}", wide.best.chi,
                                    wide.relative_std(2) * std::abs(wide.best.chi)));
  const IwanUpdateSummary fenced = fit(0.0);
  SCOPED_TRACE(fenced.report());
  EXPECT_EQ(fenced.best.chi, 0.0);
  EXPECT_EQ(fenced.bound_side[2], 1);
  EXPECT_NE(fenced.report().find("WARNING: chi at its upper bound 0"), std::string::npos);
  EXPECT_EQ(fenced.report().find("Iwan update: converged"), std::string::npos);
  // The longer search is not all the report asks for: a wider chi range too.
  EXPECT_NE(fenced.report().find("or with a wider --chi-range: chi ended at its upper bound 0"),
            std::string::npos);
}

// The budget bounds the global search, not the final descent. The trial's cantilever (one curve,
// default 1500 evaluations): 7 of 12 fits ended "evaluation budget spent" with the best point's
// local solve cut off mid-descent at its share of the budget (cost 1.31 where the minimum, found
// with 6000, costs 0.73; chi 4.6 sigma off), stated with sigmas and a reduced chi-square of 0.68
// that raised no warning. The same here: the one-mode model with the joint 60 % of the
// stiffness (chi -0.3, beta 0.6), one 60-point curve up to 2.5 phi_max with AR(1) noise (rho
// 0.9) of 0.2 % in frequency and 5 % in damping, started off (F_S x0.71, K_T x0.91, chi -0.5,
// beta 1). Before: seeds 2 and 12 ended "budget spent" at cost 0.975 and 1.405, the fits with
// 6000 evaluations at 0.7535 and 1.1095 (themselves "budget spent"). Now the local solve from the
// best point is carried on to its tolerance: both converge at the default budget, to the cost of
// the 6000-evaluation fit within 1e-3 (measured: 0.7537 and 1.1091, 722 and 1 049 evaluations past
// the budget).
TEST(IwanUpdate, TheBestLocalSolveIsCarriedToItsToleranceAtTheDefaultBudget) {
  const double k_total = std::pow(2 * M_PI * 13.3, 2);
  const model::IwanParameters truth_p{0.7, 0.6 * k_total, -0.3, 0.6};
  const model::IwanParameters start_p{truth_p.Fs * 0.71, truth_p.Kt * 0.91, -0.5, 1.0};
  const model::Model truth = one_mode_structure(0.4 * k_total, truth_p, 0.0);
  const model::Model start = one_mode_structure(0.4 * k_total, start_p, 0.0);
  const double phi = model::Iwan(truth_p).phi_max();
  for (const unsigned seed : {2u, 12u}) {
    IwanTarget target;
    target.curves.push_back(
        modal_backbone(truth, 60, 1e-3 * phi, 2.5 * phi, 2e-3, 0.05, seed, 0.9));
    const auto fit = [&](int evaluations) {
      IwanUpdateOptions o;
      o.bounds = default_iwan_bounds(start_p);
      o.max_evaluations = evaluations;
      const IwanObjective obj(start, "j", {}, {target}, o);
      IwanUpdateSummary s;
      update_iwan(obj, o, &s);
      return s;
    };
    const IwanUpdateSummary s = fit(1500), long_fit = fit(6000);
    SCOPED_TRACE(fmt::format("seed {}\n{}with 6000:\n{}", seed, s.report(), long_fit.report()));
    RecordProperty(fmt::format("cost_seed{}", seed),
                   fmt::format("{} {}", s.final_cost, long_fit.final_cost));
    EXPECT_EQ(s.status, IwanUpdateStatus::kConverged);
    EXPECT_NE(s.report().find("converged (the local solve from the best point met its tolerance)"),
              std::string::npos);
    EXPECT_LT(s.final_cost, long_fit.final_cost * (1 + 1e-3));
    // A sigma at the minimum, where the fit converged.
    EXPECT_GT(s.relative_std(2), 0);
  }
}

// The Pareto rows' linear errors follow each pair by its shape along the gammas: chain A's
// first mode (57.9 Hz at gamma 1) rises through chain B's (59.9 Hz) as K_T grows tenfold. The
// errors at gamma = 0.5 ... 20 must equal those of a walk on a 2000-step grid (mass-weighted MAC
// with the previous step) to rounding (1e-9), measured mode 1 staying on chain A.
TEST(IwanUpdate, ParetoLinearErrorsFollowEachPairByItsShape) {
  TwoChainParameters p;
  p.iwan = true;
  const model::Model m = two_chain_structure(p);
  const std::vector<Sensor> sensors{{"a1", 1, 1.0}, {"a2", 2, 1.0}, {"b1", 7, 1.0}, {"b2", 8, 1.0}};
  const model::LinearModes lm = model::linear_modes(m.mass, m.linear_stiffness());
  MeasuredModes meas;
  meas.frequency_hz.resize(4);
  meas.shapes.resize(4, 4);
  const Eigen::MatrixXd at = shapes_at_sensors(sensors, lm.shapes);
  for (int i = 0; i < 4; ++i) {
    meas.frequency_hz(i) = lm.frequency_hz(i);
    meas.shapes.col(i) = at.col(i).cast<std::complex<double>>();
  }
  IwanTarget target;
  target.curves.push_back(
      synthetic_backbone(m, 1, sensors, 0, AmplitudeQuantity::kVelocity, 10, 1.2, 0, 0, 1));
  IwanObjective obj(m, "rivet", sensors, {target}, {});
  obj.set_linear_modes(meas, 0.6);
  const std::vector<double> gammas{0.5, 1, 2, 5, 10, 20};
  const auto along = obj.linear_errors_along(gammas);
  ASSERT_EQ(along.size(), gammas.size());
  const StiffnessSets sets(m, {"iwan.rivet"});
  const double k0 = sets.initial()(0);
  for (const int direction : {-1, 1}) {
    const double end = direction > 0 ? std::log(20.0) : std::log(0.5);
    ElasticModes before = elastic_modes(m.mass, sets.stiffness(Eigen::VectorXd::Constant(1, k0)));
    std::vector<int> cols{0, 1, 2, 3};
    TrackingOptions loose;
    loose.min_mac = 0;
    loose.margin = 0;
    const int steps = 2000;
    for (int step = 1; step <= steps; ++step) {
      const double g = std::exp(end * step / steps);
      const ElasticModes after =
          elastic_modes(m.mass, sets.stiffness(Eigen::VectorXd::Constant(1, k0 * g)));
      cols = follow_modes(before.shapes, after.shapes, m.mass, cols, loose);
      before = after;
      for (size_t k = 0; k < gammas.size(); ++k) {
        if (std::abs(std::log(gammas[k]) - std::log(g)) > 1e-12) continue;
        for (int i = 0; i < 4; ++i) {
          ASSERT_TRUE(along[k][i].has_value()) << "gamma " << gammas[k] << " mode " << i + 1;
          const double ref =
              (after.frequency_hz(cols[i]) - meas.frequency_hz(i)) / meas.frequency_hz(i);
          EXPECT_NEAR(*along[k][i], ref, 1e-9) << "gamma " << gammas[k] << " mode " << i + 1;
        }
      }
    }
  }
  // At gamma 10 chain A's mode has moved above chain B's: measured mode 1 (chain A) errs high.
  EXPECT_GT(*along[4][0], 0.05);
  EXPECT_NEAR(*along[1][0], 0.0, 1e-9);  // gamma 1: the truth
}

}  // namespace
}  // namespace jointlab::correlate
