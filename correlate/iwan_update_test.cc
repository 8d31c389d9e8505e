#include "jointlab/correlate/iwan_update.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <optional>
#include <random>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/mode_tracking.h"
#include "jointlab/correlate/qsma_at.h"
#include "jointlab/correlate/two_chain.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/qsma.h"
#include "jointlab/tests/all_dof_newton.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::correlate {
namespace {

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
IwanBounds box_around(const TwoChainParameters& start) {
  return {start.Fs / 30, start.Fs * 30, 0.05, 2.0, -0.95, 0.0, 0.01, 100};
}

// The same box around an Iwan parameter set's F_S.
IwanBounds box_around(const model::IwanParameters& start) {
  return {start.Fs / 30, start.Fs * 30, 0.05, 2.0, -0.95, 0.0, 0.01, 100};
}

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

TEST(IwanUpdate, ObjectiveIsSmallAtTheTruthAndLargeAway) {
  Synthetic s;
  const model::Model m = two_chain_structure(s.truth);
  const IwanObjective obj(m, "rivet", s.sensors, {s.target}, {});
  const model::IwanParameters truth{20, 5e5, -0.5, 1.0};
  // Noise-only residuals: expected cost ~ 2 (two residuals per point of unit variance / N).
  EXPECT_LT(obj.cost(truth), 6.0);
  EXPECT_GT(obj.cost({40, 5e5, -0.5, 1.0}), 100.0);
  EXPECT_GT(obj.cost({20, 5.5e5, -0.5, 1.0}), 100.0);
}

// process and stepped-sine write expanded uncertainties, k sigma (k = 3): a curve whose std
// columns are 3 sigma with coverage_factor 3 costs what the same curve at one sigma does, at the
// truth (noise-only residuals, cost ~2) and away from it. Read as one sigma (k left at 1), the
// same numbers cost a ninth (the floors, 1e-5 in frequency and 1e-3 in damping of the values, lie
// far below these 5e-4 and 3 % std), and the cost ~2 of noise alone looked like 0.2.
TEST(IwanUpdate, ExpandedUncertaintiesAreWeighedAsOneSigma) {
  Synthetic s;
  const model::Model m = two_chain_structure(s.truth);
  IwanTarget expanded = s.target, misread = s.target;
  for (IwanTarget* t : {&expanded, &misread}) {
    for (MeasuredBackbone& c : t->curves) {
      c.frequency_std_hz *= 3;
      c.damping_std *= 3;
    }
  }
  for (MeasuredBackbone& c : expanded.curves) c.coverage_factor = 3;
  const IwanObjective one(m, "rivet", s.sensors, {s.target}, {}),
      three(m, "rivet", s.sensors, {expanded}, {}), wrong(m, "rivet", s.sensors, {misread}, {});
  for (const model::IwanParameters& p :
       {model::IwanParameters{20, 5e5, -0.5, 1.0}, model::IwanParameters{40, 5e5, -0.5, 1.0}}) {
    const double c1 = one.cost(p);
    EXPECT_NEAR(three.cost(p), c1, 1e-12 * c1) << p.Fs;
    EXPECT_NEAR(wrong.cost(p), c1 / 9, 1e-9 * c1) << p.Fs;
  }
  IwanTarget bad = s.target;
  bad.curves[0].coverage_factor = 0.5;
  EXPECT_NE(testing::input_error_of([&] {
              IwanObjective(m, "rivet", s.sensors, {bad}, {});
            }).find("coverage factor 0.5 is not a finite number >= 1"),
            std::string::npos);
}

// The fast evaluation (shared set-up, model/iwan_set_model.h; Newton, qsma_at.h) against
// the slow one (condensation from scratch, bracketing) at the same parameters, across the
// search box: the same residuals. They differ by the rounding of two dense eigen-solves and
// condensations (~1e-12 relative in frequency) and by the bracketing's 1e-10 in ln s (~1e-10
// in the columns); the residuals differ from the measured points by ~1e-4 of the frequency,
// which magnifies that to ~1e-10 relative in the cost: 1e-9 is the threshold.
TEST(IwanUpdate, SharedSetUpGivesTheResidualsFromScratch) {
  Synthetic s;
  const model::Model m = two_chain_structure(s.truth);
  const IwanObjective obj(m, "rivet", s.sensors, {s.target}, {});
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> a(static_cast<size_t>(obj.residual_count())), b(a.size());
  int compared = 0, undecided = 0;
  double worst = 0;
  for (int i = 0; i < 40; ++i) {
    const model::IwanParameters p{20 * std::exp(u(rng) * 2 - 1), 5e5 * std::exp(u(rng) * 2 - 1),
                                  -0.9 * u(rng), std::exp(u(rng) * 4 - 2)};
    const bool ok = obj.residuals(p, a.data());
    if (ok != obj.residuals_from_scratch(p, b.data())) {
      ++undecided;
      continue;
    }
    if (!ok) continue;
    ++compared;
    double ca = 0, cb = 0;
    for (size_t k = 0; k < a.size(); ++k) {
      ca += a[k] * a[k];
      cb += b[k] * b[k];
    }
    EXPECT_TRUE(testing::Close(ca, cb, 1e-9)) << i;
    worst = std::max(worst, std::abs(ca - cb) / cb);
  }
  RecordProperty("worst_relative_cost_difference", std::to_string(worst));
  // Parameters where the curve does not reach the data, or where mode 1 is chain B's (which
  // leaves the sensor still), are refused by both.
  EXPECT_EQ(undecided, 0);
  EXPECT_GE(compared, 15);
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

// Stated uncertainties below the floors are raised to them, and the report says how many.
TEST(IwanUpdate, UncertaintiesBelowTheFloorsAreSaid) {
  IwanTarget target;
  target.mode = 1;
  MeasuredBackbone c;
  c.modal = true;
  c.amplitude = Eigen::Vector3d(1e-6, 2e-6, 3e-6);
  c.frequency_hz = Eigen::Vector3d(100, 100, 100);
  c.damping_ratio = Eigen::Vector3d(1e-3, 1e-3, 1e-3);
  // sigma 1e-3 Hz (1e-5 f, below 1e-4 f), 3e-2 Hz (above), none; damping 1e-6 (0.1 %, below
  // 2 %) at every point.
  c.frequency_std_hz = Eigen::Vector3d(1e-3, 3e-2, 0);
  c.damping_std = Eigen::Vector3d(1e-6, 1e-6, 1e-6);
  target.curves = {c};
  TwoChainParameters p;
  p.iwan = true;
  const model::Model m = two_chain_structure(p);
  const IwanObjective obj(m, "rivet", {}, {target}, {});
  EXPECT_EQ(obj.floored_points(), Eigen::Vector3i(3, 1, 3));
  IwanUpdateSummary s;
  s.floored = obj.floored_points();
  s.frequency_floor = 1e-4;
  s.damping_floor = 0.02;
  EXPECT_NE(s.report().find("note: the stated uncertainties of 1 of 3 frequencies and 3 of 3 "
                            "dampings lie below the floors (0.0001 f, 0.02 zeta)"),
            std::string::npos)
      << s.report();
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

// Ring-down backbones of the truth in modal amplitude q (QSMA's ring-down pair plus Z), `points`
// log-spaced from q_lo to q_hi, with relative Gaussian noise of sd f_noise in frequency and
// z_noise in damping (the std columns say so), serially correlated along the points as AR(1)
// of coefficient rho (0: independent), frequency and damping apart.
MeasuredBackbone modal_backbone(const model::Model& truth, int points, double q_lo, double q_hi,
                                double f_noise, double z_noise, unsigned seed, double rho = 0) {
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

// The same curve ten times more densely: linear interpolation in ln q of every column.
MeasuredBackbone denser(const MeasuredBackbone& b, int factor) {
  const Eigen::Index n = b.amplitude.size(), m = (n - 1) * factor + 1;
  MeasuredBackbone d = sized_backbone(b.kind, b.sensor, m);
  d.modal = b.modal;
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Index k = std::min(i / factor, n - 2);
    const double w = static_cast<double>(i - k * factor) / factor;
    auto lerp = [&](const Eigen::VectorXd& v) { return (1 - w) * v(k) + w * v(k + 1); };
    d.amplitude(i) =
        std::exp((1 - w) * std::log(b.amplitude(k)) + w * std::log(b.amplitude(k + 1)));
    d.frequency_hz(i) = lerp(b.frequency_hz);
    d.damping_ratio(i) = lerp(b.damping_ratio);
    d.frequency_std_hz(i) = lerp(b.frequency_std_hz);
    d.damping_std(i) = lerp(b.damping_std);
  }
  return d;
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

// A measured amplitude on the fitted phi_max (a kink of the model, where minima like to sit):
// beta's sigma must not come out far below that of the same data with the point just past it
// (a Monte Carlo found 3-4 times too small a sigma in 7 of 40 fits, the central difference
// straddling the kink). Noiseless hits of the one-mode truth reaching 1.2 and 1.6 phi_max and a
// third exactly phi_max (or 1.001 phi_max), the fit started at the truth. Measured: 0.0126 on,
// 0.0121 past; with the central difference alone 0.00367 on, 3.3 times too small.
TEST(IwanUpdate, APointOnPhiMaxDoesNotShrinkBetasSigma) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  const auto beta_sigma = [&](double third_top) {
    IwanTarget target;
    for (const double top : {1.2 * phi, 1.6 * phi, third_top})
      target.curves.push_back(modal_backbone(truth, 30, 1e-8, top, 0, 0, 1));
    IwanUpdateOptions o;
    o.bounds = box_around(t.iwan);
    o.max_evaluations = 600;
    const IwanObjective obj(truth, "j", {}, {target}, o);
    IwanUpdateSummary s;
    const model::IwanParameters p = update_iwan(obj, o, &s);
    EXPECT_NEAR(p.beta, t.iwan.beta, 1e-3 * t.iwan.beta) << s.report();
    return s.relative_std(3);
  };
  const double on = beta_sigma(phi), past = beta_sigma(1.001 * phi);
  RecordProperty("beta_sigma_on_past", fmt::format("{} {}", on, past));
  std::printf("beta sigma with a point on phi_max %.3g, just past it %.3g\n", on, past);
  ASSERT_GT(past, 0);
  EXPECT_GT(on, 0.7 * past);
}

// A point a little past the fitted phi_max lies on the steep branch of the ring-down damping
// there, and its slope 1e-4 away pins phi_max as if that branch went on; a little further the
// point is back on the shallow branch, where the cost has another minimum about as low. Six
// points of the one-mode truth, three times apart in q, the fifth at 0.9 phi_max and the sixth
// at 2.7 phi_max (1e-4 frequency and 2 % damping noise, 20 seeds, start F_S x1.5, K_T x0.9, chi
// -0.4, beta 0.8): before the probe two sigmas out, seed 17 put F_S 5.8 % off with 0.61 % stated
// (z -9.5) and beta 23 % off with 4.2 % (z +5.4); now the largest |z| is 2.1 (F_S) and 2.5
// (beta), and a fit whose direction only the kink fixes states no sigma for it. Acceptance: every
// stated |z| below 3.5 (a sigma off by the old factor of 4 fails it; 30 honest fits pass with
// room), RMS z below 1.5 (30 seeds: 0.65-1.06 per parameter).
TEST(IwanUpdate, APointJustPastPhiMaxDoesNotPinItsSigma) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const model::Model start =
      one_mode_structure(t.k0, {t.iwan.Fs * 1.5, t.iwan.Kt * 0.9, -0.4, 0.8}, 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.threads = 1;
  const double truth_p[] = {t.iwan.Fs, t.iwan.Kt, t.iwan.chi, t.iwan.beta};
  double sum2 = 0;
  int stated = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    IwanTarget target;
    target.curves.push_back(modal_backbone(truth, 6, 0.9 * phi / 81, 2.7 * phi, 1e-4, 0.02, seed));
    const IwanObjective obj(start, "j", {}, {target}, o);
    IwanUpdateSummary s;
    const model::IwanParameters p = update_iwan(obj, o, &s);
    const double found[] = {p.Fs, p.Kt, p.chi, p.beta};
    for (int k = 0; k < 4; ++k) {
      if (!(s.relative_std(k) > 0)) continue;
      const double z = k == 2 ? (found[k] - truth_p[k]) / (std::abs(found[k]) * s.relative_std(k))
                              : (found[k] / truth_p[k] - 1) / s.relative_std(k);
      EXPECT_LT(std::abs(z), 3.5) << "seed " << seed << " parameter " << k << "\n" << s.report();
      sum2 += z * z;
      ++stated;
    }
  }
  ASSERT_GT(stated, 40);
  EXPECT_LT(std::sqrt(sum2 / stated), 1.5);
}

// Held (the default), Z is the model's: the truth's Z is used in every damping, so the truth
// scores as the noise does, and a fit from the truth's model stays there.
TEST(IwanUpdate, HeldLinearDampingIsTheModels) {
  const FloorTruth t;
  IwanUpdateOptions o = t.options();
  o.fit_linear_damping = false;
  const IwanObjective with(t.truth(), "j", {}, {t.target()}, o);
  EXPECT_EQ(with.linear_damping(t.iwan).value(), t.z);
  // Noise only: about 2 (two residuals of unit variance per point over N).
  EXPECT_LT(with.cost(t.iwan), 3.0);
  model::Model no_floor = t.truth();
  no_floor.modal_ratio = 0;
  const IwanObjective without(no_floor, "j", {}, {t.target()}, o);
  EXPECT_GT(without.cost(t.iwan), 10.0);
}

// The sigma does not shrink with sampling density (method.md section 2 point 5): the same
// noisy curve resampled ten times more densely gives each sigma within 30 % of the sparse
// fit's, where independent-point (Gauss-Newton) sigma would shrink by sqrt(10) = 3.2.
TEST(IwanUpdate, SigmaDoesNotDependOnTheSamplingDensity) {
  const FloorTruth t;
  const IwanTarget sparse = t.target(40, 1);
  IwanTarget dense = sparse;
  dense.curves[0] = denser(sparse.curves[0], 10);
  IwanUpdateSummary ss, sd;
  const model::Model start = t.start();
  IwanUpdateOptions o = t.options();
  o.max_evaluations = 3000;
  update_iwan(IwanObjective(start, "j", {}, {sparse}, o), o, &ss);
  update_iwan(IwanObjective(start, "j", {}, {dense}, o), o, &sd);
  std::printf("sparse:\n%sdense:\n%s", ss.report().c_str(), sd.report().c_str());
  for (int k = 0; k < 4; ++k) {
    ASSERT_GT(ss.relative_std(k), 0) << k;
    EXPECT_NEAR(sd.relative_std(k) / ss.relative_std(k), 1.0, 0.3) << k;
    RecordProperty("sigma_ratio_" + std::to_string(k),
                   std::to_string(sd.relative_std(k) / ss.relative_std(k)));
  }
  ASSERT_GT(ss.modal_ratio_std, 0);
  EXPECT_NEAR(sd.modal_ratio_std / ss.modal_ratio_std, 1.0, 0.3);
}

// Sigma under strongly correlated noise (method.md section 2 point 5): one 200-point curve of
// the one-mode truth up to twice phi_max whose noise (1e-4 f, 2 % zeta, stated as such) is
// AR(1) with rho 0.95 along the points (correlation time 39 points, about 5 independent points
// per frequency or damping sequence). Over 12 seeds the z-scores (error / stated sigma) of K_T
// and chi, pooled, must have a root mean square within 0.6-1.5: one sigma means one sigma, the
// upper limit with room for 24 draws (the RMS of 24 standard normals lies within 0.7-1.3 at
// 95 %), the lower one against a sigma inflated far past the spread. Measured: RMS 1.86 before
// the bias-corrected AR(1) covariance (HAC and tau from the residuals alone), 1.30 with it, 1.27
// with the floor taken last and t at n_eff - p.
TEST(IwanUpdate, SigmaHoldsUnderStronglyCorrelatedNoise) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const model::Model start = one_mode_structure(t.k0, t.near(), 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.max_evaluations = 600;
  double sum = 0;
  int count = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    IwanTarget target;
    target.curves.push_back(modal_backbone(truth, 200, 1e-8, 2 * phi, 1e-4, 0.02, seed, 0.95));
    const IwanObjective obj(start, "j", {}, {target}, o);
    IwanUpdateSummary s;
    const model::IwanParameters p = update_iwan(obj, o, &s);
    ASSERT_TRUE(s.improved) << s.report();
    ASSERT_GT(s.relative_std(1), 0) << s.report();
    ASSERT_GT(s.relative_std(2), 0) << s.report();
    const double z_kt = std::log(p.Kt / t.iwan.Kt) / s.relative_std(1);
    const double z_chi = (p.chi - t.iwan.chi) / (s.relative_std(2) * std::abs(p.chi));
    std::printf("seed %u: z K_T %+.2f, z chi %+.2f, effective points %.3g\n", seed, z_kt, z_chi,
                s.effective_points);
    sum += z_kt * z_kt + z_chi * z_chi;
    count += 2;
  }
  const double rms = std::sqrt(sum / count);
  RecordProperty("z_rms", std::to_string(rms));
  std::printf("RMS z of K_T and chi over 12 seeds: %.3g\n", rms);
  EXPECT_GT(rms, 0.6);
  EXPECT_LT(rms, 1.5);
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

// A fit that does not converge states no sigma and says so, whatever its chi-square: a budget of
// the 100 samples alone leaves no local solve, and the polish of the best sample (100 more
// evaluations) stops short of the tolerance. Before, such fits stated sigmas at the point the
// budget left them (the cantilever: chi 4.6 sigma off at reduced chi-square 0.68, no warning).
TEST(IwanUpdate, AFitThatDidNotConvergeStatesNoSigma) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  IwanTarget target;
  target.curves.push_back(modal_backbone(truth, 60, 1e-8, 2 * phi, 1e-4, 0.02, 3));
  const model::Model start =
      one_mode_structure(t.k0, {t.iwan.Fs * 3, t.iwan.Kt * 0.8, -0.3, 2.0}, 0.0);
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.max_evaluations = o.samples;
  const IwanObjective obj(start, "j", {}, {target}, o);
  IwanUpdateSummary s;
  update_iwan(obj, o, &s);
  SCOPED_TRACE(s.report());
  ASSERT_TRUE(s.improved);
  ASSERT_EQ(s.status, IwanUpdateStatus::kBudget);
  EXPECT_EQ(s.relative_std, Eigen::Vector4d::Zero());
  EXPECT_EQ(s.covariance, Eigen::Matrix4d::Zero());
  EXPECT_NE(s.report().find("Iwan update: not converged"), std::string::npos);
  EXPECT_NE(s.report().find("(no sigma: not converged)"), std::string::npos);
  EXPECT_NE(s.report().find("WARNING: the fit did not converge"), std::string::npos);
  EXPECT_NE(s.report().find("run again with a larger --evaluations (e.g. "), std::string::npos);
}

// slip_force_at_beta() gives the same element below phi_max: the same K_T, chi and R, hence the
// same virgin force at every displacement below both phi_max (the microslip family the report
// lists), and F_S itself at the set's own beta.
TEST(IwanUpdate, SlipForceAtAnotherBetaKeepsTheMicroslipElement) {
  const model::IwanParameters p{0.564065, 164.801, -0.2955, 1.0};
  EXPECT_NEAR(slip_force_at_beta(p, p.beta), p.Fs, 1e-12 * p.Fs);
  for (const double beta : {0.25, 0.6, 2.0}) {
    const model::IwanParameters q{slip_force_at_beta(p, beta), p.Kt, p.chi, beta};
    const model::Iwan a(p), b(q);
    EXPECT_NEAR(b.R() / a.R(), 1.0, 1e-12) << beta;
    const double top = std::min(a.phi_max(), b.phi_max());
    for (const double u : {1e-3 * top, 0.3 * top, 0.99 * top})
      EXPECT_NEAR(b.force(u) / a.force(u), 1.0, 1e-12) << beta << " " << u;
  }
  // The cantilever's microslip fit (beta held 1, F_S 0.564 N): at the truth's beta 0.6 the family
  // gives F_S 0.69 N (truth 0.7 N).
  EXPECT_NEAR(slip_force_at_beta(p, 0.6), 0.69, 0.01);
}

// Hits of the one-mode truth that disagree with one another: f.size() curves of `points` points
// from q = 1e-8 to (1.5 + step h) phi_max, 5e-4 frequency and 2 % damping noise (seeds seed + h),
// curve h's frequency times 1 + f[h] and damping times 1 + z[h], named "hit h+1".
IwanTarget offset_hits(const model::Model& truth, double phi, int points, double step,
                       unsigned seed, const std::vector<double>& f, const std::vector<double>& z) {
  IwanTarget tg;
  for (size_t h = 0; h < f.size(); ++h) {
    const double d = static_cast<double>(h);
    MeasuredBackbone b = modal_backbone(truth, points, 1e-8, (1.5 + step * d) * phi, 5e-4, 0.02,
                                        seed + static_cast<unsigned>(h));
    b.frequency_hz *= 1 + f[h];
    b.damping_ratio *= 1 + z[h];
    b.source = fmt::format("hit {}", h + 1);
    tg.curves.push_back(b);
  }
  return tg;
}

// Hit-to-hit scatter (the trial's H/o1): four curves of the one-mode truth, each with its own
// offset (+0.2 %, -0.2 %, 0, +0.1 % in frequency; +5 %, -5 %, 0, -2.5 % in damping) on 0.05 % and
// 2 % noise. The offsets between the curves explain most of the chi-square, and the report names
// that instead of a longer search: before, the same case said "the search spent its evaluation
// budget ...; run again with a larger --evaluations (e.g. 25492)" (at 3 000 evaluations), and,
// converged, named no cause. The same curves with every damping doubled disagree with the model,
// not with one another: the between-curve share stays small. Four curves, one cluster each,
// leave the cluster covariance 3 degrees of freedom (Student's t), so the sigmas are stated; three
// would leave 2 and state none (IwanUpdateReport.NoSigmaWhereTheMisfitNotTheNoiseSetsTheError).
// Measured: share 0.84 with the offsets (their span about the fitted curve 0.4 % and 10 %), 3e-5
// doubled; K_T 0.12 sigma from the truth (|z| < 3 asked: a sigma that allows for the scatter).
TEST(IwanUpdate, CurvesThatDisagreeWithOneAnotherAreNamedAsScatterBetweenHits) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  const auto target = [&](double z_factor, bool offsets) {
    IwanTarget tg = offsets ? offset_hits(truth, phi, 40, 0.5, 21, {2e-3, -2e-3, 0, 1e-3},
                                          {0.05, -0.05, 0, -0.025})
                            : offset_hits(truth, phi, 40, 0.5, 21, {0, 0, 0, 0}, {0, 0, 0, 0});
    for (MeasuredBackbone& b : tg.curves) {
      b.damping_ratio *= z_factor;
      b.damping_std *= z_factor;
    }
    return tg;
  };
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  const model::Model start = one_mode_structure(t.k0, t.near(), 0.0);
  const IwanObjective scattered(start, "j", {}, {target(1, true)}, o);
  IwanUpdateSummary s;
  update_iwan(scattered, o, &s);
  const std::string r = s.report();
  SCOPED_TRACE(r);
  RecordProperty("report", r);
  ASSERT_TRUE(s.misfit());
  ASSERT_TRUE(s.evidence);
  RecordProperty("share", std::to_string(s.evidence->between_curves_share));
  EXPECT_GT(s.evidence->between_curves_share, 0.5);
  EXPECT_EQ(s.evidence->curves, 4);
  EXPECT_EQ(s.evidence->apart_curve, "");  // random-looking offsets: no curve apart
  // The offsets about the fitted curve span about the planted 0.4 % and 10 %.
  EXPECT_NEAR(s.evidence->frequency_offsets(1) - s.evidence->frequency_offsets(0), 4e-3, 1e-3);
  EXPECT_NEAR(s.evidence->damping_offsets(1) - s.evidence->damping_offsets(0), 0.1, 0.03);
  EXPECT_NE(r.find("the 4 curves disagree with one another by more than their stated noise"),
            std::string::npos);
  EXPECT_NE(r.find("the sigmas allow for it (one cluster per curve, Student's t with 3 degrees "
                   "of freedom)"),
            std::string::npos);
  EXPECT_NE(r.find("(the scatter between the curves, above)"), std::string::npos);
  EXPECT_EQ(r.find("--evaluations"), std::string::npos);
  ASSERT_GT(s.relative_std(1), 0);
  const double z_kt = std::log(s.best.Kt / t.iwan.Kt) / s.relative_std(1);
  RecordProperty("z_Kt", std::to_string(z_kt));
  EXPECT_LT(std::abs(z_kt), 3);
  // Every damping doubled: the curves agree with one another, not with the model.
  const IwanObjective doubled(start, "j", {}, {target(2, false)}, o);
  const std::optional<MisfitEvidence> e = doubled.misfit_evidence(t.iwan, 0);
  ASSERT_TRUE(e);
  RecordProperty("share_doubled", std::to_string(e->between_curves_share));
  EXPECT_LT(e->between_curves_share, 0.1);
  // One curve: no between-curve evidence at all.
  IwanTarget one = target(1, true);
  one.curves.resize(1);
  const IwanObjective single(start, "j", {}, {one}, o);
  EXPECT_EQ(single.misfit_evidence(t.iwan, 0)->between_curves_share, 0.0);
}

// A curve unlike the others is no scatter between hits. The case of two joint sets (a bolt pair
// at each end, rivets at mid-span; pairs of hits at three levels at mid-span and one hit at
// x = 0.375 m, where mode 2 slips the same joints): the off-span hit's damping stood +94 %
// above the fitted curve, the others within -3.5 to +2.3 %, and one cluster per curve read that
// as random scatter: K_T +/- 0.24 % at z +7.1, F_S at beta 1 +/- 5.8 % at z -10. Here: six curves
// of the one-mode truth, five with random-looking offsets (+/-0.1 %, +/-0.05 %, 0 in frequency;
// +/-3 %, +/-1.5 %, 0 in damping) and the sixth's damping +60 % (another mode slipping the joint
// in that hit). misfit_evidence() sets it apart (t 25 at the truth; the 1 % point with Bonferroni
// over 12 tries is 9.0 at 4 degrees of freedom, and more than 13 is asked) and names it; the five
// alone, or all six without its offset, set none apart. The fit then states no sigma and names
// the curve. Before, the fit stated K_T's and chi's sigmas from the cluster covariance.
TEST(IwanUpdate, ACurveApartFromTheOthersIsNoScatterAndStatesNoSigma) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  const auto target = [&](int curves, double apart) {
    std::vector<double> f{1e-3, -1e-3, 0, 5e-4, -5e-4, 0}, z{0.03, -0.03, 0, 0.015, -0.015, apart};
    f.resize(static_cast<size_t>(curves));
    z.resize(static_cast<size_t>(curves));
    return offset_hits(truth, phi, 30, 0.2, 41, f, z);
  };
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  const model::Model start = one_mode_structure(t.k0, t.near(), 0.0);
  const IwanObjective apart(start, "j", {}, {target(6, 0.6)}, o);
  const std::optional<MisfitEvidence> e = apart.misfit_evidence(t.iwan, 0);
  ASSERT_TRUE(e);
  RecordProperty("t_apart", std::to_string(e->apart_t));
  EXPECT_EQ(e->apart_curve, "hit 6");
  EXPECT_TRUE(e->apart_in_damping);
  EXPECT_EQ(e->apart_points, 30);
  EXPECT_GT(e->apart_t, 13);
  for (const IwanTarget& honest : {target(5, 0), target(6, 0)}) {
    const IwanObjective scatter(start, "j", {}, {honest}, o);
    const std::optional<MisfitEvidence> h = scatter.misfit_evidence(t.iwan, 0);
    ASSERT_TRUE(h);
    EXPECT_EQ(h->apart_curve, "") << h->apart_t;
  }
  IwanUpdateSummary s;
  update_iwan(apart, o, &s);
  const std::string r = s.report();
  SCOPED_TRACE(r);
  RecordProperty("report", r);
  ASSERT_TRUE(s.evidence);
  EXPECT_EQ(s.evidence->apart_curve, "hit 6");
  EXPECT_TRUE(s.misfit_sets_the_error());
  EXPECT_FALSE(s.scatter_explains_misfit());
  EXPECT_EQ(s.relative_std(1), 0);
  EXPECT_EQ(s.relative_std(2), 0);
  EXPECT_NE(r.find("But hit 6 (30 points, amplitude"), std::string::npos);
  EXPECT_NE(r.find("lies apart from the others (damping +"), std::string::npos);
  EXPECT_EQ(r.find("the sigmas allow for it (one cluster per curve"), std::string::npos);
}

TEST(IwanUpdate, BadInputIsReported) {
  const model::Model m = two_chain_structure();
  Synthetic s;
  EXPECT_THROW(IwanObjective(m, "rivet", s.sensors, {s.target}, {}),
               InputError);  // no Iwan set in the linear model
  IwanUpdateOptions o;
  o.bounds.chi_min = -1.5;
  EXPECT_NE(o.error(), "");
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

// The report notes a Kt moved far from its start (more than 25 %): a backbone 5 % below an
// un-updated model moved it -38 % (beta +46 %, chi 8.6 sigma off) within the noise and without
// a word. A move of 20 % (the example's start 1e7 to its truth 1.2e7) is not noted, nor a held
// Kt.
// A mode that leaves the joint still: a 50 Hz mass on a spring beside a second mass held by
// the Iwan joint (177 Hz), the two uncoupled (as a beam's first mode left its two rivets at
// 1e-13 m of slip). Its measured backbone (flat: 50 Hz, damping 1e-3, 1e-4 and 2 % noise) is the
// structure's own damping alone; no Iwan parameters change it, so no candidate improves on the
// start. Before, both fits below ended "the result is the start. Widen the bounds or give a
// better start." (with Z fitted, Fs and chi "the start"; with Z held, no cause named at a
// damping error of 100 %: the model's damping, exactly 0, gave no ratio). Now: with Z fitted,
// no slip and a mode that hardly moves the joint; with Z held, that and the structure's own
// damping.
TEST(IwanUpdateReport, AModeThatHardlyMovesTheJointIsSaidSoNotSentToWiderBounds) {
  const double k0 = std::pow(2 * M_PI * 50.0, 2), kc = 0.0;
  const double kt = 0.04 * std::pow(2 * M_PI * 177.0, 2);
  model::Model m;
  m.mass.resize(2, 2);
  m.mass.insert(0, 0) = 1.0;
  m.mass.insert(1, 1) = 1.0;
  m.stiffness.resize(2, 2);
  m.stiffness.insert(0, 0) = k0 + kc;
  m.stiffness.insert(1, 1) = 0.96 * std::pow(2 * M_PI * 177.0, 2) + kc;
  m.stiffness.insert(0, 1) = -kc;
  m.stiffness.insert(1, 0) = -kc;
  m.joints.push_back(model::Joint{1, model::kGround, "iwan.j", kt,
                                  model::Iwan(model::IwanParameters{0.5, kt, -0.5, 0.5})});
  MeasuredBackbone b = sized_backbone(BackboneKind::kRingdown, 0, 30);
  b.modal = true;
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 30; ++i) {
    b.amplitude(i) = 1e-6 * std::pow(100.0, i / 29.0);
    b.frequency_hz(i) = 50.0 * (1 + 1e-4 * n(rng));
    b.damping_ratio(i) = 1e-3 * (1 + 0.02 * n(rng));
    b.frequency_std_hz(i) = 50.0 * 1e-4;
    b.damping_std(i) = 1e-3 * 0.02;
  }
  IwanTarget t;
  t.curves.push_back(b);
  for (const bool fit_z : {true, false}) {
    IwanUpdateOptions o;
    o.bounds = default_iwan_bounds({0.5, kt, -0.5, 0.5});
    o.fit_linear_damping = fit_z;
    o.max_evaluations = 300;
    o.threads = 1;
    const IwanObjective obj(m, "j", {}, {t}, o);
    IwanUpdateSummary s;
    update_iwan(obj, o, &s);
    const std::string r = s.report();
    std::printf("%s", r.c_str());
    ASSERT_TRUE(s.joint_hardly_moved()) << r;
    EXPECT_EQ(r.find("Widen the bounds"), std::string::npos) << r;
    if (fit_z) {
      EXPECT_TRUE(s.no_slip_seen()) << r;
      EXPECT_NE(r.find("this mode hardly moves the joint"), std::string::npos) << r;
      EXPECT_EQ(s.parameter_note(0), "not identified: no slip in the data") << r;
      EXPECT_EQ(s.parameter_note(2), "not identified: no slip in the data") << r;
    } else {
      EXPECT_NE(r.find("The measured modes hardly move the joint here"), std::string::npos) << r;
      EXPECT_NE(r.find("That is the structure's own damping, which the model lacks (modal_ratio "
                       "0, held): this mode hardly moves the joint"),
                std::string::npos)
          << r;
    }
  }
}

// A parameter at a bound that the data hardly fix (its stated sigma over half its value) ended
// there along what they leave free: mode 2 of a lap joint whose joint barely moves put gamma at
// its upper bound 2 +/- 78 % (the truth 1.6) and was told "the best fit may lie outside the
// range, widen it". Now the line says so and that a wider range moves it, not the fit; with a
// sigma of 20 % the old advice stands.
TEST(IwanUpdateReport, ABoundOfAParameterTheDataHardlyFixIsNoCallToWidenIt) {
  IwanUpdateSummary s;
  s.status = IwanUpdateStatus::kConverged;
  s.improved = true;
  s.start = {30, 5e6, -0.5, 1};
  s.best = {8.58, 1e7, -0.71, 0.59};
  s.reference_stiffness = 5e6;
  s.relative_std << 0.26, 0.78, 0.78, 0.95;
  s.effective_points = 60;
  s.sigma_degrees_of_freedom = 56;
  s.at_bounds = {"gamma (Kt/Ks) at its upper bound 2"};
  s.bound_side = {0, 1, 0, 0, 0};
  std::string r = s.report();
  EXPECT_NE(r.find("WARNING: gamma (Kt/Ks) at its upper bound 2: the data hardly fix it (+/- 78 "
                   "%), so it ended there along what they leave free; a wider range moves it, "
                   "not the fit"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find("widen it"), std::string::npos) << r;
  s.relative_std(1) = 0.2;
  r = s.report();
  EXPECT_NE(r.find("gamma (Kt/Ks) at its upper bound 2: the best fit may lie outside the range, "
                   "widen it"),
            std::string::npos)
      << r;
}

TEST(IwanUpdateReport, AKtMovedFarFromItsStartIsNoted) {
  IwanUpdateSummary s;
  s.status = IwanUpdateStatus::kConverged;
  s.start = {50, 1e7, -0.5, 1};
  s.best = {33.6, 6.16e6, -0.34, 1.46};
  EXPECT_NE(s.report().find("note: Kt moved from 1e+07 to 6.16e+06 N/m (-38 %)"), std::string::npos)
      << s.report();
  EXPECT_NE(s.report().find("first (update-linear)"), std::string::npos) << s.report();
  // After the linear update the start is its K_T: the note does not send the user back to it
  // (before, it did, while the "linear part:" line said the linear update was done).
  s.linear_part_updated = true;
  EXPECT_NE(s.report().find("note: Kt moved from 1e+07 to 6.16e+06 N/m (-38 %): away from the "
                            "model's, whose linear frequencies match the measured ones"),
            std::string::npos)
      << s.report();
  EXPECT_EQ(s.report().find("update-linear"), std::string::npos) << s.report();
  s.linear_part_updated = false;
  s.best.Kt = 1.2e7;
  EXPECT_EQ(s.report().find("Kt moved"), std::string::npos) << s.report();
  s.best.Kt = 6.16e6;
  s.held[1] = true;
  EXPECT_EQ(s.report().find("Kt moved"), std::string::npos) << s.report();
}

// misfit_evidence() on data the truth explains and on the same data misread. Two-chain truth,
// one mode-1 backbone (0.05 % frequency and 3 % damping noise), evaluated at the truth: as mode 1
// its linear limit lies within ten times its noise and no other mode is nearer; as mode 3 (the
// next mode that moves the sensor) mode 1 is named; with the dampings 100 times larger (per cent
// read as a fraction) the measured damping is a median 100 times the model's (to the 3 % noise).
TEST(IwanUpdate, MisfitEvidenceNamesTheNearerModeAndTheDampingFactor) {
  Synthetic s;
  const model::Model m = two_chain_structure(s.truth);
  const model::IwanParameters truth{20, 5e5, -0.5, 1.0};
  const auto evidence = [&](int mode, double damping_scale) {
    IwanTarget t = s.target;
    t.mode = mode;
    for (MeasuredBackbone& c : t.curves) {
      c.damping_ratio *= damping_scale;
      c.damping_std *= damping_scale;
    }
    const IwanObjective obj(m, "rivet", s.sensors, {t}, {});
    return obj.misfit_evidence(truth, 0);
  };
  const std::optional<MisfitEvidence> right = evidence(1, 1);
  ASSERT_TRUE(right);
  EXPECT_EQ(right->mode, 1);
  EXPECT_EQ(right->nearer_mode, 0);
  EXPECT_LT(std::abs(right->low_frequency_error), 10 * right->low_frequency_noise);
  EXPECT_NEAR(right->damping_factor, 1, 0.05);
  // Mode 3 (201.7 Hz, the next mode that moves the sensor) for data of mode 1 (57.9 Hz).
  const std::optional<MisfitEvidence> wrong = evidence(3, 1);
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->mode, 3);
  EXPECT_EQ(wrong->nearer_mode, 1);
  EXPECT_GT(wrong->low_frequency_error, 1.0);  // 201.7 Hz against 57.9 Hz
  const std::optional<MisfitEvidence> percent = evidence(1, 100);
  ASSERT_TRUE(percent);
  EXPECT_NEAR(percent->damping_factor, 100, 5);
}

// A summary of a fit that ended as `status` after `evaluations` QSMA evaluations, over
// `residuals` residuals at reduced chi-square `chi2`: the report's wording, no fit run.
IwanUpdateSummary reported_fit(IwanUpdateStatus status, int evaluations, size_t residuals,
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
MisfitEvidence mode_one_evidence(double low_hz, double noise, double mode_hz, double damping_factor,
                                 double damping_max) {
  MisfitEvidence e;
  e.mode = 1;
  e.low_frequency_hz = low_hz;
  e.low_frequency_noise = noise;
  e.mode_hz = mode_hz;
  e.damping_factor = damping_factor;
  e.damping_max = damping_max;
  return e;
}

// A misfit whose residuals show a likelier cause names it instead of "widen it" or "a larger
// --evaluations" (the trial's cases, their numbers): a wrong --mode (mode-1 data fitted as mode
// 2), a linear-limit frequency off with K_T held (data 5 % below the model, --gamma 1), per-cent
// damping read as a fraction. Where the evidence shows none of these the old advice stays. (Of a
// converged fit: one that did not converge names none as a finding, below.)
TEST(IwanUpdateReport, AMisfitNamesItsLikelierCauseInsteadOfAWiderRangeOrMoreEvaluations) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 3054, 80, 881);
  s.at_bounds = {"chi at its lower bound -0.95"};
  // The model's damping above the measured (factor 0.36): no unit error to name.
  MisfitEvidence e = mode_one_evidence(115.768, 5.3e-4, 120.504, 0.36, 0.02);
  e.low_frequency_error = 0.0116;  // 22 times the noise
  const std::string widen = "widen it", longer = "larger --evaluations";
  // No evidence: the search is the suspect, as before.
  EXPECT_NE(s.report().find(widen), std::string::npos) << s.report();
  EXPECT_NE(s.report().find(longer), std::string::npos) << s.report();
  // The linear limit 1.16 % off with K_T held: update-linear.
  s.held[1] = true;
  s.evidence = e;
  std::string r = s.report();
  EXPECT_NE(r.find("misses the measured low-amplitude frequency 115.768 Hz by +1.16 % (22 times "
                   "its noise) with Kt held"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("update-linear first"), std::string::npos) << r;
  EXPECT_EQ(r.find(widen), std::string::npos) << r;
  EXPECT_EQ(r.find(longer), std::string::npos) << r;
  // Within ten times its noise the linear limit says nothing.
  s.evidence->low_frequency_error = 4e-3;
  EXPECT_EQ(s.report().find("update-linear first"), std::string::npos) << s.report();
  // Another mode of the model far nearer the measured frequency: the mode.
  s.held[1] = false;
  s.evidence->mode = 2;
  s.evidence->low_frequency_hz = 121.849;
  s.evidence->low_frequency_error = 0.527;
  s.evidence->mode_hz = 284.327;
  s.evidence->nearer_mode = 1;
  s.evidence->nearer_mode_hz = 120.504;
  r = s.report();
  EXPECT_NE(r.find("is -57.1 % off the model's mode 2 (284.327 Hz, linear, as given) but +1.12 % "
                   "off its mode 1 (120.504 Hz): the backbone looks like mode 1's; check --mode"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find(widen), std::string::npos) << r;
  // The frequencies fit, the damping lies 14.6 times above the model's, every value below 1:
  // per cent read as a fraction.
  s.evidence = e;
  s.evidence->low_frequency_error = 1e-4;
  s.evidence->damping_factor = 14.6;
  s.evidence->damping_max = 0.0349;
  r = s.report();
  EXPECT_NE(r.find("a median 14.6 times above the fitted model's"), std::string::npos) << r;
  EXPECT_NE(r.find("(damping_ratio [%])"), std::string::npos) << r;
  EXPECT_EQ(r.find(longer), std::string::npos) << r;
  // A damping of 1 or more is no plausible per cent read as a fraction: nothing named.
  s.evidence->damping_max = 1.5;
  EXPECT_EQ(s.report().find("damping_ratio [%]"), std::string::npos) << s.report();
  EXPECT_NE(s.report().find(widen), std::string::npos) << s.report();
  // Without a misfit nothing is named, whatever the evidence.
  s.evidence->damping_max = 0.0349;
  s.reduced_chi2 = 1.1;
  EXPECT_EQ(s.report().find("damping_ratio [%]"), std::string::npos) << s.report();
}

// A fit that did not converge stopped where its evaluations ran out, so its residuals are not a
// best fit's: the causes read off them are no findings (an unconverged fit was told "a loss
// factor (eta = 2 zeta) given as the damping ratio" at a damping factor of 1.85, and to mend
// that first). The report says the fit did not converge and asks for more evaluations; what
// the residuals would suggest is said only as that, qualified. A wrong --mode, which rests on
// the model as given and not on the fit, is still named.
TEST(IwanUpdateReport, AFitThatDidNotConvergeNamesNoCauseAsAFinding) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 1500, 120, 40);
  MisfitEvidence e = mode_one_evidence(13.34, 2e-3, 13.35, 1.85, 0.2);
  e.low_frequency_error = 1e-4;
  s.evidence = e;
  const std::string loss = "a loss factor (eta = 2 zeta) given as the damping ratio";
  // Converged: the factor 1.85 is named as the likelier cause (the test can tell the two apart).
  ASSERT_NE(s.misfit_cause().find(loss), std::string::npos) << s.report();
  EXPECT_EQ(s.tentative_cause(), "");
  // Not converged: no cause, the advice is the longer search, the heuristic only qualified.
  s.status = IwanUpdateStatus::kBudget;
  EXPECT_EQ(s.misfit_cause(), "");
  EXPECT_NE(s.tentative_cause().find(loss), std::string::npos);
  const std::string r = s.report();
  EXPECT_EQ(r.find("the residuals point at the data or the model"), std::string::npos) << r;
  EXPECT_EQ(r.find("mend the cause named above first"), std::string::npos) << r;
  EXPECT_NE(r.find("the fit did not converge"), std::string::npos) << r;
  EXPECT_NE(r.find("run again with a larger --evaluations (e.g. 6000)"), std::string::npos) << r;
  EXPECT_NE(r.find("no finding while the fit has not converged"), std::string::npos) << r;
  // The wrong mode, read off the model as given, is named whether or not the fit converged.
  s.evidence->mode = 2;
  s.evidence->low_frequency_hz = 13.34;
  s.evidence->low_frequency_error = 0.5;
  s.evidence->mode_hz = 40.1;
  s.evidence->nearer_mode = 1;
  s.evidence->nearer_mode_hz = 13.35;
  EXPECT_NE(s.misfit_cause().find("check --mode"), std::string::npos) << s.report();
}

// K_T held and data 0.5 % below the model's linear frequency (--gamma 1): chi runs to its bound,
// its microslip softening the whole curve nearly evenly, so the fitted curve meets the low data
// and the linear limit check (against the fitted curve) sees nothing; the report said "widen
// it" and "--evaluations". Now the cause is the linear part: mode R's linear frequency at the
// held K_T against the measured low-amplitude frequency, beyond three times its noise. Without
// chi at a bound, or with K_T free, or within the noise, that is not said.
TEST(IwanUpdateReport, ChiAtItsBoundWithKtHeldNamesTheLinearFrequency) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 1500, 120, 12);
  s.held[1] = true;
  s.at_bounds = {"chi at its lower bound -0.95"};
  s.bound_side[2] = -1;
  MisfitEvidence e = mode_one_evidence(13.2672, 2e-4, 13.3339, 1.1, 0.2);
  e.low_frequency_error = 8e-4;  // the fitted curve meets the low data within 10 x the noise
  e.linear_hz = 13.3339;         // 0.503 % above the data
  s.evidence = e;
  std::string r = s.report();
  EXPECT_NE(r.find("with Kt held, mode 1's linear frequency 13.3339 Hz (the curve's "
                   "zero-amplitude limit) lies +0.503 % off the measured low-amplitude frequency "
                   "13.2672 Hz (25 times its noise), and chi ran to its lower bound"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("update-linear first"), std::string::npos) << r;
  EXPECT_EQ(r.find("widen it"), std::string::npos) << r;
  EXPECT_EQ(r.find("--evaluations"), std::string::npos) << r;
  const std::string named = "mode 1's linear frequency";
  s.bound_side[2] = 0;  // chi inside its range, the fitted curve meeting the low data (1 sigma)
  s.evidence->low_frequency_error = 2e-4;
  EXPECT_EQ(s.misfit_cause().find(named), std::string::npos);
  s.evidence->low_frequency_error = 8e-4;
  s.bound_side[2] = -1;
  s.held[1] = false;  // K_T free: it would move the linear limit itself
  EXPECT_EQ(s.misfit_cause().find(named), std::string::npos);
  s.held[1] = true;
  s.evidence->linear_hz = 13.2672 * (1 + 5e-4);  // within three times the noise, and 0.1 %
  EXPECT_EQ(s.misfit_cause().find(named), std::string::npos);
}

// Every decision on a parameter's sigma is made once (sigma_reason()) and read the same in the
// report's parameter line and in the note parameters.csv and Python carry; relative_std is
// nonzero exactly where a sigma is stated. Before, the report and parameter_note() decided
// apart: a fit of 3 points (6 residuals for 4 parameters) said "(sigma unknown)" in the report
// and nothing in parameters.csv's note; data without slip kept F_S's and chi's sigmas in
// relative_std (parameters.csv, Python) while the report called them not identified; a fitted
// modal_ratio's note was empty wherever its sigma was unknown.
TEST(IwanUpdateReport, EverySigmaDecisionReadsTheSameInTheReportAndTheNotes) {
  const auto fitted = [] {
    IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 900, 80, 1.0);
    s.start = {1, 5e4, -0.3, 1};
    s.best = {0.5, 5e4, -0.5, 0.5};
    s.relative_std = Eigen::Vector4d(0.01, 0.002, 0.005, 0.03);
    s.covariance.diagonal() = Eigen::Vector4d(1e-4, 4e-6, 6e-6, 9e-4);
    s.effective_points = 80;
    s.sigma_degrees_of_freedom = 76;
    s.top_slip = 2, s.phi_max = 1;  // the data reach macroslip
    return s;
  }();
  // Too few independent points: no covariance, and the count said in both.
  IwanUpdateSummary few = fitted;
  few.residuals = 6;
  few.relative_std.setZero();
  few.covariance.setZero();
  few.effective_points = 2.4;
  few.sigma_degrees_of_freedom = -1.6;
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(few.sigma_reason(k), IwanSigmaReason::kTooFewPoints);
    EXPECT_EQ(few.parameter_note(k), "sigma unknown: too few independent points (2.4)");
  }
  EXPECT_NE(few.report().find("Fs 1 -> 0.5 N (sigma unknown: too few independent points, below)"),
            std::string::npos)
      << few.report();
  // Data without slip (Z fitted, the constant backbone as good): F_S, chi and beta not
  // identified, their sigmas cleared; K_T and Z are the result with theirs.
  IwanUpdateSummary flat = fitted;
  flat.modal_ratio_fitted = true;
  flat.modal_ratio = 3e-3;
  flat.modal_ratio_std = 1e-5;
  flat.final_cost = flat.constant_cost = 2.3;
  flat.clear_unstated_sigmas();
  for (int k : {0, 2, 3}) {
    EXPECT_EQ(flat.sigma_reason(k), IwanSigmaReason::kNoSlip);
    EXPECT_EQ(flat.relative_std(k), 0.0) << k;
    EXPECT_EQ(flat.parameter_note(k), "not identified: no slip in the data");
  }
  EXPECT_EQ(flat.relative_std(1), 0.002);
  EXPECT_EQ(flat.parameter_note(1), "");
  EXPECT_EQ(flat.modal_ratio_std, 1e-5);
  EXPECT_EQ(flat.parameter_note(4), "");
  EXPECT_NE(flat.report().find("Fs 1 -> 0.5 N (not identified: no slip in the data, below)"),
            std::string::npos)
      << flat.report();
  // A fitted Z without a sigma: the note says why, as the report does.
  IwanUpdateSummary z = few;
  z.modal_ratio_fitted = true;
  z.modal_ratio = 3e-3;
  EXPECT_EQ(z.parameter_note(4), "sigma unknown: too few independent points (2.4)");
  EXPECT_NE(z.report().find("0 -> 0.003 (sigma unknown: too few independent points, below)"),
            std::string::npos)
      << z.report();
  z.status = IwanUpdateStatus::kBudget;
  EXPECT_EQ(z.parameter_note(4), "no sigma: not converged");
  // F_S and beta fixed only by the slopes of points at phi_max (the kink probe): no sigma, in
  // the notes, the report's words and its note line alike; K_T and chi keep theirs.
  IwanUpdateSummary kink = fitted;
  kink.fixed_at_kink = {true, false, false, true};
  kink.clear_unstated_sigmas();
  for (int k : {0, 3}) {
    EXPECT_EQ(kink.sigma_reason(k), IwanSigmaReason::kAtKink);
    EXPECT_EQ(kink.relative_std(k), 0.0) << k;
    EXPECT_EQ(kink.parameter_note(k),
              "sigma unknown: fixed only by points at phi_max, from one side");
  }
  EXPECT_EQ(kink.relative_std(1), 0.002);
  EXPECT_EQ(kink.parameter_note(2), "");
  EXPECT_NE(kink.report().find("Fs 1 -> 0.5 N (sigma unknown: fixed only by points at phi_max, "
                               "from one side, below)"),
            std::string::npos)
      << kink.report();
  EXPECT_NE(kink.report().find("note: Fs and beta are fixed only by the slopes of points at "
                               "phi_max"),
            std::string::npos)
      << kink.report();
}

// Backbones that lie past phi_max at every amplitude fix F_S (the plateau) but show K_T, chi and
// beta, which shape the joint below phi_max, only weakly. The one-mode truth's table from 2.7 to
// 27 phi_max (40 points, 1e-4 / 2 % noise, the numbers below from its command run): F_S -0.13 %
// +/- 0.53 %, K_T +100 % at the top of its range with a sigma of 2.8e4 %, and the report said
// "widen it" and "Kt moved ... update-linear first"; another seed's fit stopped short and was
// told "run again with a larger --evaluations (e.g. 18340)", which, run, ended at the same cost
// (1.971) with chi at its bound and no sigma. Now the slip line says the data are past phi_max
// throughout, the bounds of K_T, chi and beta say a wider range moves them, not the fit, and no
// longer search or linear update is advised for them.
TEST(IwanUpdateReport, DataPastPhiMaxThroughoutSayKtChiAndBetaShowWeakly) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 4403, 80, 0.728);
  s.start = {1, 49472.8, -0.3, 1};
  s.best = {0.499367, 98927.7, -0.9034, 0.2831};
  s.relative_std = Eigen::Vector4d(0.0053, 283, 47, 339);
  s.effective_points = 80;
  s.sigma_degrees_of_freedom = 76;
  s.bottom_slip = 5e-5, s.top_slip = 5e-4, s.phi_max = 1.74e-5;
  s.at_bounds = {"gamma (Kt/Ks) 1.99964, near its upper bound 2"};
  s.bound_side[1] = 1;
  ASSERT_TRUE(s.macroslip_only());
  std::string r = s.report();
  EXPECT_NE(r.find("macroslip only: every measured amplitude lies past phi_max"), std::string::npos)
      << r;
  EXPECT_NE(r.find("WARNING: gamma (Kt/Ks) 1.99964, near its upper bound 2: the data lie past "
                   "phi_max at every amplitude (below)"),
            std::string::npos)
      << r;
  for (const char* not_said : {"widen it", "update-linear", "--evaluations"})
    EXPECT_EQ(r.find(not_said), std::string::npos) << not_said << ": " << r;
  // Not converged: the longer search is no cure for K_T, chi and beta.
  s.status = IwanUpdateStatus::kBudget;
  s.relative_std.setZero();
  s.at_bounds = {"chi at its upper bound 0"};
  s.bound_side = {0, 0, 1, 0, 0};
  r = s.report();
  EXPECT_NE(r.find("WARNING: the fit did not converge"), std::string::npos) << r;
  EXPECT_EQ(r.find("run again with a larger --evaluations"), std::string::npos) << r;
  EXPECT_EQ(r.find("widen it"), std::string::npos) << r;
  // Data that reach below phi_max: as before.
  s.bottom_slip = 1e-8;
  EXPECT_FALSE(s.macroslip_only());
  EXPECT_NE(s.report().find("run again with a larger --evaluations"), std::string::npos);
}

// Three points (6 residuals) for four parameters leave two degrees of freedom even if every
// residual were independent: too few points, which the report says as such. Before, it said
// "the residuals run in long waves along the curves (serial correlation 0.782 ...)", a
// correlation read off 3 points, and sent the user after waves (the one-mode truth's 3-point
// table to 2 phi_max: the numbers below). Where the points are enough and their correlation
// leaves too few, the waves are still named.
TEST(IwanUpdateReport, TooFewPointsAreNamedAsSuchNotAsWaves) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 2699, 6, 0.0132);
  s.start = {1, 49472.8, -0.3, 1};
  s.best = {0.502379, 49357.8, -0.4915, 0.5148};
  s.noise_correlation = 0.782;
  s.effective_points = 2.4;
  s.sigma_degrees_of_freedom = 2.4 - 4;
  std::string r = s.report();
  EXPECT_NE(r.find("WARNING: 3 points (6 residuals) leave 2 beyond the 4 parameters fitted even if "
                   "independent: too few to state a sigma (more than 2 needed); more points, or "
                   "more curves, would give one"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find("long waves"), std::string::npos) << r;
  s.residuals = 80;
  s.effective_points = 5.4;
  s.sigma_degrees_of_freedom = 1.4;
  r = s.report();
  EXPECT_NE(r.find("the residuals run in long waves along the curves"), std::string::npos) << r;
}

// Frequency noise ten times the stated (1.5e-3 relative, stated as 1.5e-4; damping 3 % as
// stated) on a 60-point backbone of the one-mode truth (a unit mass on a spring with an Iwan
// joint to ground), fitted from the truth: reduced chi-square 48, the model does not describe
// the data within their stated noise, but the residuals are uncorrelated from point to point
// (serial correlation 0) and spread evenly over the amplitudes (largest third's share 0.39), as
// noise is, and a note says the stated uncertainties may be about sqrt(reduced chi-square) = 6.9
// times too small. The control: the same data of a chi -0.2 joint fitted with chi held near -0.6
// (the model wrong): reduced chi-square 281, residuals running in waves (serial correlation
// 0.98), and no such note. Over seeds 1-16 the same held (the numbers at the report's note).
TEST(IwanUpdate, WhiteResidualsOfAMisfitNoteThatTheStatedNoiseMayBeTooSmall) {
  const FloorTruth t;
  const auto fit = [&](double chi_data, std::optional<double> chi_held) {
    model::IwanParameters truth = t.iwan;
    truth.chi = chi_data;
    IwanTarget target;
    target.mode = 1;
    MeasuredBackbone b = modal_backbone(one_mode_structure(t.k0, truth), 60, 1e-8,
                                        2 * model::Iwan(truth).phi_max(), 1.5e-3, 0.03, 5);
    b.frequency_std_hz *= 0.1;  // 1.5e-4 stated
    target.curves = {b};
    IwanUpdateOptions o = t.options();
    o.fit_linear_damping = false;
    o.max_evaluations = 1500;
    model::IwanParameters start = truth;
    if (chi_held) {  // a range of +/- 0.01 about it: the bounds need chi_min < chi_max
      start.chi = *chi_held;
      o.bounds.chi_min = *chi_held - 0.01;
      o.bounds.chi_max = *chi_held + 0.01;
    }
    const model::Model m = one_mode_structure(t.k0, start);  // the objective keeps a reference
    const IwanObjective obj(m, "j", {}, {target}, o);
    IwanUpdateSummary s;
    update_iwan(obj, o, &s);
    return s;
  };
  const std::string note = "the residuals are uncorrelated from point to point";
  const IwanUpdateSummary noise = fit(t.iwan.chi, std::nullopt);
  std::printf("%s", noise.report().c_str());
  EXPECT_TRUE(noise.misfit()) << noise.report();
  EXPECT_LT(noise.noise_correlation, 0.3) << noise.report();
  EXPECT_NE(noise.report().find(note), std::string::npos) << noise.report();
  EXPECT_NE(noise.report().find(fmt::format("sqrt(reduced chi-square) = {:.2g} times too small",
                                            std::sqrt(noise.reduced_chi2))),
            std::string::npos)
      << noise.report();
  const IwanUpdateSummary wrong = fit(-0.2, -0.6);
  std::printf("%s", wrong.report().c_str());
  EXPECT_TRUE(wrong.misfit()) << wrong.report();
  EXPECT_EQ(wrong.report().find(note), std::string::npos) << wrong.report();
}

// The note that the stated noise may be too small needs both: residuals uncorrelated from point
// to point (serial correlation below 0.3) and spread evenly over the amplitudes (the largest
// third's share of the chi-square within 3 standard deviations of 1/3: for 120 residuals, 60
// points, below 1/3 + 3 sqrt((2/9) / 31) = 0.587); and a misfit to begin with.
TEST(IwanUpdateReport, WhiteEvenResidualsOfAMisfitAloneNoteTheStatedNoise) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 1500, 120, 47.8);
  s.effective_points = 100;
  s.sigma_degrees_of_freedom = 96;
  s.noise_correlation = 0.05;
  s.amplitude_share = 0.39;
  const std::string note =
      "the stated uncertainties may be about sqrt(reduced chi-square) = 6.9 "
      "times too small";
  EXPECT_NE(s.report().find(note), std::string::npos) << s.report();
  s.amplitude_share = 0.6;  // a misfit gathered at some amplitudes
  EXPECT_EQ(s.report().find("uncorrelated from point to point"), std::string::npos) << s.report();
  s.amplitude_share = 0.39;
  s.noise_correlation = 0.35;  // waves
  EXPECT_EQ(s.report().find("uncorrelated from point to point"), std::string::npos) << s.report();
  s.noise_correlation = 0.05;
  s.reduced_chi2 = 1.2;  // within 1 + 3 sqrt(2 / 120) = 1.39: no misfit
  EXPECT_EQ(s.report().find("uncorrelated from point to point"), std::string::npos) << s.report();
}

// Uncertainties stated 10 times the noise (the one-mode truth's 40-point table, 1e-4 / 2 % noise
// stated as 1e-3 / 20 %): reduced chi-square 0.0074, and the sigmas, which never shrink the
// stated noise, came out about 9 times too wide (every z-score within 0.15 over 6 seeds) while
// the report said only that the model describes the data. Now a note says the scatter is 0.086
// times the stated uncertainties. Not within 3 of the chi-square's standard deviations of 1
// (here 1 - 3 sqrt(2 / 80) = 0.53), and not where floors raised the uncertainties (their note).
TEST(IwanUpdateReport, UncertaintiesStatedFarAboveTheScatterAreNoted) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 3000, 80, 0.00738);
  s.relative_std = Eigen::Vector4d(0.05, 0.01, 0.03, 0.2);
  const std::string said = "the residuals scatter about 0.086 times the stated uncertainties";
  EXPECT_NE(s.report().find(said), std::string::npos) << s.report();
  s.reduced_chi2 = 0.6;
  EXPECT_EQ(s.report().find("scatter about"), std::string::npos) << s.report();
  // The example campaign's fit: 978 residuals serially correlated into 18.3 independent points,
  // reduced chi-square 0.669, common over 18 points (3 of its standard deviations reach 1 - 0.99);
  // against the count's limit, 0.86, it was called far below 1.
  s.residuals = 978;
  s.effective_points = 18.3;
  s.reduced_chi2 = 0.669;
  EXPECT_EQ(s.report().find("scatter about"), std::string::npos) << s.report();
  s.reduced_chi2 = 0.00738;
  EXPECT_NE(s.report().find("scatter about"), std::string::npos) << s.report();
  s.floored = Eigen::Vector3i(40, 0, 12);
  EXPECT_EQ(s.report().find("scatter about"), std::string::npos) << s.report();
}

// K_T held and data 0.5 % below the model's linear frequency with 5e-4 frequency noise, chi
// inside its range: the joint cannot soften the curve that much at the lowest amplitudes, so the
// fitted curve misses the low data by about the offset itself, +0.497 % here, just under the ten
// times the noise linear_limit_off() asks (the riveted beam's mode 1 held at K_T = 1.2e7 N/m,
// one 40-point microslip table: reduced chi-square 51.7 and no cause named; before, the K_T-held
// rule asked for chi at a bound). The linear frequency 0.5 % off (10 times the noise, beyond the
// rule's 3 times and 0.1 %) with the fitted curve still above the low data by more than 3 times
// its noise on the same side is the linear part's error. Data above the linear frequency (which
// no Iwan joint reaches: it only softens) are named alike.
TEST(IwanUpdateReport, KtHeldWithChiInsideItsRangeNamesTheLinearFrequency) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 872, 80, 51.7);
  s.held[1] = true;
  MisfitEvidence e = mode_one_evidence(121.310, 5e-4, 121.925, 1.0, 0.004);
  e.low_frequency_error = 4.97e-3;
  e.linear_hz = 121.925;
  s.evidence = e;
  const std::string r = s.report();
  EXPECT_NE(r.find("with Kt held, mode 1's linear frequency 121.925 Hz (the curve's "
                   "zero-amplitude limit) lies +0.507 % off the measured low-amplitude frequency "
                   "121.31 Hz (10 times its noise), and the fitted curve still misses the "
                   "low-amplitude data by +0.497 % (10 times its noise)"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("error of the linear part"), std::string::npos) << r;
  EXPECT_NE(r.find("update-linear first"), std::string::npos) << r;
  // Data above the linear frequency: the fitted curve below them.
  s.evidence->low_frequency_hz = 122.53;
  s.evidence->low_frequency_error = -5.13e-3;
  EXPECT_NE(s.misfit_cause().find("lies -0.494 % off the measured low-amplitude frequency 122.53 "
                                  "Hz (10 times its noise)"),
            std::string::npos)
      << s.misfit_cause();
  // The fitted curve meets the low data (within 3 times the noise): the joint softening it there
  // may be the truth, and the misfit has another cause.
  s.evidence->low_frequency_hz = 121.310;
  s.evidence->low_frequency_error = 1.2e-3;
  EXPECT_EQ(s.misfit_cause().find("linear frequency"), std::string::npos) << s.misfit_cause();
  // K_T free: it would move the linear limit itself.
  s.evidence->low_frequency_error = 4.97e-3;
  s.held[1] = false;
  EXPECT_EQ(s.misfit_cause().find("mode 1's linear frequency"), std::string::npos)
      << s.misfit_cause();
}

// K_T at a bound short of the measured low-amplitude frequency: that frequency pressed it there,
// and the line says so instead of "a wider range would not cure that" (a wider range does move
// K_T onto the data: it takes up the linear part's error). The numbers are the command's on a
// one-mode table 1.5 % above the model (UpdateCli.IwanKtAtABoundNamesTheLinearLimitThatPressedIt).
// Where the model as given (gamma 1) matches the measured frequency, the range stopped the fit:
// widen it, and neither "update-linear" nor "a larger --evaluations" is said. The plain line stays
// where it is true: another parameter at a bound, or K_T at the bound the miss does not point to.
TEST(IwanUpdateReport, AKtBoundNamesTheLinearLimitThatPressedIt) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 3064, 120, 386);
  s.at_bounds = {"gamma (Kt/Ks) at its upper bound 2"};
  s.bound_side[1] = 1;
  // The model as given 1.85 % below the data.
  MisfitEvidence e = mode_one_evidence(179.611, 1e-4, 176.291, 1.1, 0.004);
  e.low_frequency_error = -0.00298;  // the fitted linear limit below the data
  s.evidence = e;
  const std::string plain = "the misfit below pressed it there; a wider range would not cure that";
  std::string r = s.report();
  EXPECT_NE(r.find("WARNING: gamma (Kt/Ks) at its upper bound 2: the measured low-amplitude "
                   "frequency pressed it there, beyond the linear limit Kt reaches in its range "
                   "(below); a wider range would let Kt take up the linear part's error rather "
                   "than fit the joint"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("misses the measured low-amplitude frequency 179.611 Hz by -0.298 % (30 times "
                   "its noise) with Kt at its upper bound, and mode 1 of the model as given (Kt = "
                   "Ks, 176.291 Hz) by -1.85 %: the model's linear part does not match the "
                   "measured mode; update-linear first"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find(plain), std::string::npos) << r;
  EXPECT_EQ(r.find("Kt alone cannot bring it there"), std::string::npos) << r;
  // At the lower bound with the linear limit below the data, the miss is not what pressed K_T
  // down: the plain line.
  s.at_bounds = {"gamma (Kt/Ks) at its lower bound 0.05"};
  s.bound_side[1] = -1;
  r = s.report();
  EXPECT_NE(r.find("at its lower bound 0.05: " + plain), std::string::npos) << r;
  // The model as given matches the measured frequency: the range stopped K_T short of it.
  s.at_bounds = {"gamma (Kt/Ks) at its upper bound 0.9"};
  s.bound_side[1] = 1;
  s.evidence->mode_hz = 179.65;
  s.status = IwanUpdateStatus::kBudget;
  r = s.report();
  EXPECT_NE(r.find("at its upper bound 0.9: the best fit may lie outside the range, widen it"),
            std::string::npos)
      << r;
  for (const char* not_said : {"update-linear", "larger --evaluations", "would not cure"})
    EXPECT_EQ(r.find(not_said), std::string::npos) << not_said << ": " << r;
  // Another parameter at its bound with K_T held and the linear limit off, the fit converged:
  // the plain line.
  s.status = IwanUpdateStatus::kConverged;
  s.held[1] = true;
  s.bound_side[1] = 0;
  s.bound_side[2] = -1;
  s.at_bounds = {"chi at its lower bound -0.95"};
  s.evidence->mode_hz = 176.291;
  r = s.report();
  EXPECT_NE(r.find("chi at its lower bound -0.95: " + plain), std::string::npos) << r;
  EXPECT_NE(r.find("with Kt held: the model's linear part"), std::string::npos) << r;
}

// A joint that barely slips: the floor truth's mode read far below phi_max (q from 1e-13 to
// 2e-12 m, 3e-8 phi_max at most), where the joint's microslip damping is below 1 % of the floor
// Z and the frequency shift below 1e-6, with 1e-4 frequency and 2 % damping noise: the data
// are a constant backbone. With Z fitted the fit ends at the constant's cost, F_S and chi at
// their upper bounds; before, the report said "widen it" of both and "run again with a larger
// --evaluations". Now no_slip_seen() holds, F_S and chi are "not identified", and neither
// advice is given; Z comes back within 3 % (three sigma of the mean of 30 points of 2 % noise
// is 1.1 %, and the bias of the neglected joint damping below 1 %). Its control: the hits
// past phi_max (FitsTheStructuresOwnDampingWithTheJoint) see slip.
TEST(IwanUpdate, ABackboneWithoutSlipSaysSoInsteadOfWideningTheRange) {
  const FloorTruth t;
  IwanTarget target;
  target.curves.push_back(modal_backbone(t.truth(), 30, 1e-13, 2e-12, 1e-4, 0.02, 5));
  const model::Model start = t.start();  // the objective keeps a reference to it
  const IwanObjective obj(start, "j", {}, {target}, t.options());
  IwanUpdateSummary s;
  update_iwan(obj, t.options(), &s);
  const std::string r = s.report();
  std::printf("%s", r.c_str());
  ASSERT_TRUE(s.improved) << r;
  EXPECT_TRUE(s.no_slip_seen()) << r;
  EXPECT_NE(r.find("no slip in these data"), std::string::npos) << r;
  EXPECT_NE(r.find("Fs 1.5 -> "), std::string::npos) << r;
  EXPECT_NE(r.find("(not identified: no slip in the data, below)"), std::string::npos) << r;
  for (const char* not_said : {"widen it", "larger --evaluations"})
    EXPECT_EQ(r.find(not_said), std::string::npos) << not_said << ": " << r;
  EXPECT_LT(std::abs(s.modal_ratio / t.z - 1), 0.03) << r;
  // The slipping hits of the floor truth: slip seen.
  IwanUpdateSummary slipping;
  const IwanObjective with_slip(start, "j", {}, {t.target(20)}, t.options());
  update_iwan(with_slip, t.options(), &slipping);
  EXPECT_FALSE(slipping.no_slip_seen()) << slipping.report();
  EXPECT_EQ(slipping.report().find("no slip"), std::string::npos) << slipping.report();
}

// The structure's own damping missing from a model whose Z is held: measured damping that stays
// at least half its median down to the lowest amplitudes, far above the model's there, is named
// as that (fit Z, or set it), not as a per-cent column; a joint's rise from a low start, as a
// per-cent column keeps, is still named per cent. The evidence is the flat 0.3 % table's of a
// trial (a riveted beam's mode 1, modal_ratio 0): median damping 3.16 times the fitted model's,
// 0.003 at the lowest amplitudes against the model's 0.000817 there.
TEST(IwanUpdateReport, FlatDampingAboveAModelWithoutItsOwnDampingNamesThatDamping) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kBudget, 3002, 30, 903);
  s.at_bounds = {"chi at its lower bound -0.95"};
  MisfitEvidence e = mode_one_evidence(120.48, 1e-4, 120.48, 3.16, 0.0031);
  e.low_damping = 0.003;
  e.low_model_damping = 0.000817;
  e.median_damping = 0.00299;
  s.evidence = e;
  std::string r = s.report();
  EXPECT_NE(r.find("the measured damping stays near 0.003 down to the lowest amplitudes"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("--linear-damping fit"), std::string::npos) << r;
  EXPECT_EQ(r.find("damping_ratio [%]"), std::string::npos) << r;
  // A per-cent column: 0.005 at the lowest amplitudes, rising to a median 0.015.
  s.evidence->damping_factor = 14.6;
  s.evidence->damping_max = 0.0349;
  s.evidence->low_damping = 0.005;
  s.evidence->median_damping = 0.015;
  r = s.report();
  EXPECT_NE(r.find("(damping_ratio [%])"), std::string::npos) << r;
  EXPECT_EQ(r.find("--linear-damping fit"), std::string::npos) << r;
  // Z fitted already: the linear damping is not what is missing.
  s.evidence->low_damping = 0.003;
  s.evidence->median_damping = 0.00299;
  s.modal_ratio_fitted = true;
  EXPECT_EQ(s.report().find("--linear-damping fit"), std::string::npos) << s.report();
}

// A ring-down backbone of `truth` whose joint also carries another mode's slip, as in a hit where
// a second mode of the same joint still rings: each point's frequency and damping are QSMA's at
// q + q_other, recorded at q (`points` log-spaced from q_lo to q_hi), with independent relative
// noise f_noise and z_noise, stated as such. q_other = 0 is the truth's own backbone.
MeasuredBackbone backbone_with_other_slip(const model::Model& truth, int points, double q_lo,
                                          double q_hi, double q_other, double f_noise,
                                          double z_noise, unsigned seed) {
  const model::JointCondensation jc(truth);
  std::vector<double> q(static_cast<size_t>(points)), slipped(q.size());
  for (size_t i = 0; i < q.size(); ++i) {
    q[i] = q_lo * std::pow(q_hi / q_lo, static_cast<double>(i) / (points - 1.0));
    slipped[i] = q[i] + q_other;
  }
  const std::vector<QsmaAtPoint> at =
      qsma_at(jc, 1, 0, slipped, AmplitudeFrequency::kFirstHarmonic);
  EXPECT_EQ(at.size(), q.size());
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  MeasuredBackbone b = sized_backbone(BackboneKind::kRingdown, 0, points);
  b.modal = true;
  for (int i = 0; i < points; ++i) {
    const model::QsmaPoint& p = at[static_cast<size_t>(i)].point;
    b.amplitude(i) = q[static_cast<size_t>(i)];
    b.frequency_hz(i) = p.ringdown_frequency_hz * (1 + f_noise * n(rng));
    b.damping_ratio(i) = p.ringdown_damping_ratio * (1 + z_noise * n(rng));
    b.frequency_std_hz(i) = f_noise * p.ringdown_frequency_hz;
    b.damping_std(i) = z_noise * p.ringdown_damping_ratio;
  }
  return b;
}

// The misfit tests' three hits of the one-mode truth: 40 points each (or `points`) from q = 1e-8
// to 1.5, 2 and 2.5 phi_max, another mode adding q_other to the joint's slip, 1e-4 frequency and
// 2 % damping noise (seeds 100-102).
IwanTarget three_hits_with_other_slip(const model::Model& truth, double phi, double q_other,
                                      int points = 40) {
  IwanTarget target;
  for (int h = 0; h < 3; ++h)
    target.curves.push_back(backbone_with_other_slip(truth, points, 1e-8, (1.5 + 0.5 * h) * phi,
                                                     q_other, 1e-4, 0.02, 100 + h));
  return target;
}

// Where the model does not describe the data and the residuals are no noise, the misfit, not the
// noise, sets the parameters' error: no sigma is stated, and the report says why. The one-mode
// truth (F_S 0.5 N, K_T 4 % of the stiffness, chi -0.5, beta 0.5), three 40-point hits to 1.5, 2
// and 2.5 phi_max (1e-4 frequency and 2 % damping noise), started off (F_S x1.3, K_T x0.9, chi
// -0.4, beta 0.7), fitted three ways:
// - the truth's model: the honest control, every sigma stated and every |z| below 3 (measured
//   -0.4, -0.5, +1.0, -1.7; over seeds 1-8 of this set-up none above 2.1);
// - the model's linear part 0.4 % stiffer than the data's (frequency +0.2 %), K_T free: K_T takes
//   it up, F_S -20 % (the trial's campaign: -21 % with 1.6 % stated, z -13), reduced chi-square
//   4.3, serial correlation 0.33, a third of the amplitudes holding 83 % of the chi-square;
//   before, F_S -20.1 % +/- 1.4 % (z -16.5), K_T -9.6 % +/- 0.17 % (z -61), beta
//   -23 % +/- 5.4 % (z -4.8);
// - another mode adding 0.1 phi_max to the joint's slip at every point: reduced chi-square 168,
//   serial correlation 0.93; before, chi -86 % with 6.1 % stated (z -7.6).
TEST(IwanUpdate, AMisfitWhoseResidualsAreNoNoiseStatesNoSigma) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const double phi = model::Iwan(t.iwan).phi_max();
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.threads = 1;
  const model::IwanParameters start = t.near();
  const auto fit = [&](double k0_model, double q_other, model::IwanParameters* p) {
    const IwanTarget target = three_hits_with_other_slip(truth, phi, q_other);
    const model::Model m = one_mode_structure(k0_model, start);  // the objective keeps it
    const IwanObjective obj(m, "j", {}, {target}, o);
    IwanUpdateSummary s;
    *p = update_iwan(obj, o, &s);
    return s;
  };
  model::IwanParameters p;
  const IwanUpdateSummary honest = fit(t.k0, 0, &p);
  const double truth_p[] = {t.iwan.Fs, t.iwan.Kt, t.iwan.chi, t.iwan.beta};
  const double found[] = {p.Fs, p.Kt, p.chi, p.beta};
  EXPECT_FALSE(honest.misfit_sets_the_error()) << honest.report();
  for (int k = 0; k < 4; ++k) {
    ASSERT_EQ(honest.sigma_reason(k), IwanSigmaReason::kStated) << k << "\n" << honest.report();
    const double z = k == 2
                         ? (found[k] - truth_p[k]) / (std::abs(found[k]) * honest.relative_std(k))
                         : std::log(found[k] / truth_p[k]) / honest.relative_std(k);
    EXPECT_LT(std::abs(z), 3) << k << "\n" << honest.report();
  }
  for (const auto& [k0_model, q_other] :
       {std::pair(t.k0 * 1.004, 0.0), std::pair(t.k0, 0.1 * phi)}) {
    const IwanUpdateSummary s = fit(k0_model, q_other, &p);
    const std::string r = s.report();
    std::printf("%s", r.c_str());
    ASSERT_EQ(s.status, IwanUpdateStatus::kConverged) << r;
    EXPECT_TRUE(s.misfit_sets_the_error()) << r;
    EXPECT_GT(std::abs(p.Fs / t.iwan.Fs - 1) + std::abs(p.chi / t.iwan.chi - 1), 0.15) << r;
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(s.relative_std(k), 0.0) << k << "\n" << r;
      EXPECT_NE(s.sigma_reason(k), IwanSigmaReason::kStated) << k << "\n" << r;
    }
    EXPECT_EQ(s.sigma_reason(2), IwanSigmaReason::kModelMisfit) << r;
    EXPECT_EQ(s.parameter_note(2), "no sigma: the model does not describe the data");
    EXPECT_NE(r.find("(no sigma: the model does not describe the data, below)"), std::string::npos)
        << r;
    EXPECT_NE(r.find("WARNING: no sigma is stated: the model does not describe the data"),
              std::string::npos)
        << r;
  }
}

// The rule behind it (IwanUpdateSummary::misfit_sets_the_error()), on a summary: the numbers of
// the linear part 0.4 % off above (240 residuals, reduced chi-square 4.27, 124 effective points,
// serial correlation 0.33, largest third 0.83) withhold every sigma, in the words, the notes and
// relative_std alike. Each sigma stays where the misfit is not the model's: white residuals
// spread evenly (noise stated too small: the note says so; serial correlation 0.05, share 0.39,
// below 1/3 + 3 sqrt((2/9) / 61) = 0.514); scatter between three curves explaining 70 % of the
// chi-square (one cluster per curve); or a reduced chi-square of 1.35, a misfit by the count
// (1 + 3 sqrt(2 / 240) = 1.27) but within what serially correlated noise of 124 effective points
// reaches (1 + 3 sqrt(2 / 124) = 1.38).
TEST(IwanUpdateReport, NoSigmaWhereTheMisfitNotTheNoiseSetsTheError) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 1500, 240, 4.27);
  s.start = {0.65, 5e4, -0.4, 0.7};
  s.best = {0.4, 4.5e4, -0.5, 0.5};
  s.relative_std = Eigen::Vector4d(0.021, 0.0056, 0.013, 0.15);
  s.effective_points = 124;
  s.sigma_degrees_of_freedom = 120;
  s.noise_correlation = 0.33;
  s.amplitude_share = 0.83;
  s.top_slip = 2, s.phi_max = 1;  // the data reach macroslip
  const IwanUpdateSummary before = s;
  s.clear_unstated_sigmas();
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(s.sigma_reason(k), IwanSigmaReason::kModelMisfit) << k;
    EXPECT_EQ(s.relative_std(k), 0.0) << k;
    EXPECT_EQ(s.parameter_note(k), "no sigma: the model does not describe the data") << k;
  }
  const std::string r = s.report();
  EXPECT_NE(r.find("Fs 0.65 -> 0.4 N (no sigma: the model does not describe the data, below)"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("WARNING: no sigma is stated: the model does not describe the data (reduced "
                   "chi-square 4.27, beyond the 1.38 the noise reaches over the 124 independent "
                   "points) and the residuals are no noise (they run in waves, serial correlation "
                   "0.33 from one point to the next, and one third of the amplitudes holds 83 % "
                   "of the chi-square)"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find("are a lower bound"), std::string::npos) << r;
  // White residuals spread evenly: the stated noise may be too small; the sigmas stand.
  IwanUpdateSummary white = before;
  white.noise_correlation = 0.05;
  white.amplitude_share = 0.39;
  white.clear_unstated_sigmas();
  EXPECT_FALSE(white.misfit_sets_the_error());
  EXPECT_EQ(white.sigma_reason(0), IwanSigmaReason::kStated);
  EXPECT_EQ(white.relative_std(0), 0.021);
  EXPECT_NE(white.report().find("uncorrelated from point to point"), std::string::npos);
  EXPECT_EQ(white.report().find("no sigma is stated"), std::string::npos);
  // Scatter between four curves: the cluster-robust covariance allows for it (Student's t with
  // 3 degrees of freedom).
  IwanUpdateSummary scatter = before;
  MisfitEvidence e = mode_one_evidence(177.0, 1e-4, 177.0, 1.0, 0.03);
  e.curves = 4;
  e.between_curves_share = 0.7;
  scatter.evidence = e;
  EXPECT_TRUE(scatter.scatter_explains_misfit());
  EXPECT_FALSE(scatter.misfit_sets_the_error());
  EXPECT_EQ(scatter.sigma_reason(1), IwanSigmaReason::kStated);
  // A curve apart from the others: its offset follows that hit, no random scatter; no sigma.
  scatter.evidence->apart_curve = "node_15N_h1";
  EXPECT_TRUE(scatter.misfit_sets_the_error());
  scatter.evidence->apart_curve.clear();
  // Three: the cluster covariance's 2 degrees of freedom give Student's t no finite variance
  // (before, three curves stated a sigma); two: no cluster covariance. No sigma either way.
  for (const int curves : {3, 2}) {
    scatter.evidence->curves = curves;
    EXPECT_TRUE(scatter.misfit_sets_the_error()) << curves;
  }
  // Within what 124 effective points of correlated noise reach.
  IwanUpdateSummary near = before;
  near.reduced_chi2 = 1.35;
  EXPECT_TRUE(near.misfit());
  EXPECT_FALSE(near.misfit_sets_the_error());
  EXPECT_EQ(near.sigma_reason(2), IwanSigmaReason::kStated);
}

// An error of the rest of the model that K_T takes up leaves no trace in the residuals (the model's
// structure stiffness 0.1 % above the data's: reduced chi-square 1.31, K_T -2.4 % and F_S -5 %
// at 27 and 17 of their sigmas, and nothing said), so the report states how far such an error
// moves each parameter, per 0.1 % of mode R's linear frequency, computed at the result
// (IwanUpdateSummary::linear_part_sensitivity), and the accuracy of that frequency each sigma
// needs. Checked against a second method, the refit on the model with K 0.1 % stiffer: the
// one-mode truth's three 40-point hits (1e-4 / 2 % noise, seeds 100-102) give -50.0 and -111 per
// unit of ln f_R for K_T and F_S (K_T's is the algebra of the linear frequency: -k0 / (K_T
// d ln f / d ln K), -24 / 0.48), and the refit moves them by 1.013 and 0.939 times that times
// the frequency's 0.048 %. The rate is the tangent: across +-0.1 % it changes by 2.6 % (K_T) and
// 4 % (F_S) (at +-0.01 % the refits agree within 0.5 %), so K_T within 3 % and F_S within 10 %.
// Beta's rate changes by 25 % across the step (its refit 1.43 times the tangent): not checked.
TEST(IwanUpdate, TheLinearPartsEffectOnTheParametersIsStatedAndMatchesARefit) {
  const FloorTruth t;
  const model::Model truth = one_mode_structure(t.k0, t.iwan, 0.0);
  const IwanTarget target = three_hits_with_other_slip(truth, model::Iwan(t.iwan).phi_max(), 0);
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.threads = 1;
  const model::IwanParameters start = t.near();
  const auto fit = [&](double k0, model::IwanParameters* p) {
    const model::Model m = one_mode_structure(k0, start);  // the objective keeps it
    const IwanObjective obj(m, "j", {}, {target}, o);
    IwanUpdateSummary s;
    *p = update_iwan(obj, o, &s);
    return s;
  };
  model::IwanParameters right, stiffer;
  const IwanUpdateSummary s = fit(t.k0, &right);
  const IwanUpdateSummary off = fit(t.k0 * 1.001, &stiffer);
  ASSERT_EQ(s.status, IwanUpdateStatus::kConverged) << s.report();
  ASSERT_EQ(off.status, IwanUpdateStatus::kConverged) << off.report();
  EXPECT_EQ(s.sensitivity_mode, 1);
  // d ln f / d ln k0 of the one-mode model: k0 / (2 (k0 + K_T)).
  EXPECT_NEAR(s.frequency_per_stiffness, t.k0 / (2 * (t.k0 + right.Kt)), 1e-4);
  const double dlnf = std::log(1.001) * s.frequency_per_stiffness;
  EXPECT_NEAR(std::log(stiffer.Kt / right.Kt) / (s.linear_part_sensitivity(1) * dlnf), 1, 0.03)
      << s.report();
  EXPECT_NEAR(std::log(stiffer.Fs / right.Fs) / (s.linear_part_sensitivity(0) * dlnf), 1, 0.10)
      << s.report();
  // Both move by many of their sigmas, with nothing in the residuals: the report says so.
  EXPECT_FALSE(off.misfit_sets_the_error()) << off.report();
  EXPECT_GT(std::abs(std::log(stiffer.Kt / right.Kt)) / s.relative_std(1), 10) << s.report();
  EXPECT_NEAR(s.linear_part_tolerance(1),
              s.relative_std(1) / std::abs(s.linear_part_sensitivity(1)), 1e-12);
  const std::string r = off.report();
  EXPECT_NE(r.find("linear part: a 0.1 % error in mode 1's linear frequency from the rest of the "
                   "model (its stiffness without the joints 0.208 % off) moves Kt by -5.1 %"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("Kt takes the frequency up; the sigmas hold only where that frequency is "
                   "right to 0.00"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("(update-linear)"), std::string::npos) << r;
  // After a linear update (run's linear step) the rates stand without sending there again.
  IwanUpdateSummary updated = off;
  updated.linear_part_updated = true;
  EXPECT_EQ(updated.report().find("(update-linear)"), std::string::npos) << updated.report();
  EXPECT_NE(updated.report().find("the model's linear frequencies match the measured ones"),
            std::string::npos);
  // A rate of next to nothing (a one-mode fit's chi: -1.2e-08 % per 0.1 %) is said so, and the
  // tolerance it gives (4e+06 %, a sigma the linear part does not limit) is left out.
  IwanUpdateSummary flat = off;
  flat.linear_part_sensitivity(2) = 1e-7 * (flat.best.chi < 0 ? -1 : 1);
  const std::string line = flat.report().substr(flat.report().find("linear part:"));
  EXPECT_NE(line.find("chi by less than 0.001 %"), std::string::npos) << line;
  EXPECT_EQ(line.substr(0, line.find('\n')).find("(chi)"), std::string::npos) << line;
}

// A misfit whose linear limit misses the low data with K_T free names the damping that pulled it
// there, not the linear part, and tells the structure's own damping from another mode's slip by
// the measured frequency's low end. The one-mode truth and start of the test above (three
// 40-point hits to 1.5, 2 and 2.5 phi_max, 1e-4 / 2 % noise, seeds 100-102), fitted four ways:
// - the data with the structure's own damping 5e-4, the model without it (held, the default):
//   K_T rose to x1.32 and chi to -0.84 to buy damping at the low end, the fitted curve +0.21 %
//   above the low data (21 times the noise), the measured damping there 23 % above the model's,
//   and the measured frequency still softening there (5.2 % of the curve's softening between its
//   lowest and second fifth of amplitudes; seeds 100-400 of this set-up 4.0-5.3 %);
// - another mode adding 0.1 and 0.3 phi_max to the joint's slip: the same fit's signature (K_T
//   x1.65 and at its bound, +0.28 % and +0.35 %, damping 26 % and 94 % above), the frequency flat
//   at the low end (0.87 % and 0.66 %; seeds 100-400 -0.2 to 1.7 %);
// - the model's linear part 1 % stiffer with K_T held at the truth's: the linear limit 0.51 %
//   above the data (51 times the noise), chi at its bound: update-linear first, as before (with
//   K_T free, 0.4 % or 1 % stiffer, K_T takes it up and no cause is named, before and after).
// Before, the first three were told "the model's linear part does not match the measured mode;
// update-linear first". The low end only leans (the test below): both causes are named, with the
// refit that decides, and the lean follows the share. The threshold of 2.5 % lies a factor 2
// above the flat cases and below the softening one here, so one seed each decides the lean.
TEST(IwanUpdate, ALinearLimitMissedForDampingNamesTheOwnDampingOrAnotherModesSlip) {
  const FloorTruth t;
  const double phi = model::Iwan(t.iwan).phi_max();
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.threads = 1;
  const model::IwanParameters start = t.near();
  const auto fit = [&](double z_data, double q_other, double k0_model, double gamma) {
    const model::Model truth = one_mode_structure(t.k0, t.iwan, z_data);
    const IwanTarget target = three_hits_with_other_slip(truth, phi, q_other);
    model::IwanParameters p0 = start;
    IwanUpdateOptions oo = o;
    if (gamma > 0) p0.Kt = t.iwan.Kt, oo.fixed_gamma = gamma;
    const model::Model m = one_mode_structure(k0_model, p0);  // the objective keeps it
    const IwanObjective obj(m, "j", {}, {target}, oo);
    IwanUpdateSummary s;
    update_iwan(obj, oo, &s);
    return s;
  };
  const std::string own = "the structure's own damping (roughly constant in amplitude)";
  const std::string other = "another mode slipping the same joint in these hits";
  const std::string linear = "update-linear first";
  const std::string refit = "Refit with --linear-damping fit";
  {
    const IwanUpdateSummary s = fit(5e-4, 0, t.k0, 0);
    const std::string r = s.report();
    ASSERT_TRUE(s.evidence) << r;
    EXPECT_GT(s.evidence->low_softening_share, 0.04) << r;
    EXPECT_NE(r.find("which is no error of the linear part"), std::string::npos) << r;
    EXPECT_NE(r.find("leans toward the structure's own damping"), std::string::npos) << r;
    EXPECT_NE(r.find(refit), std::string::npos) << r;
    EXPECT_EQ(r.find(linear), std::string::npos) << r;
  }
  for (double q : {0.1 * phi, 0.3 * phi}) {
    const IwanUpdateSummary s = fit(0, q, t.k0, 0);
    const std::string r = s.report();
    ASSERT_TRUE(s.evidence) << r;
    EXPECT_LT(s.evidence->low_softening_share, 0.0125) << r;
    EXPECT_NE(r.find("leans toward another mode's slip"), std::string::npos) << r;
    EXPECT_NE(r.find("screen the hits with the other modes' backbones"), std::string::npos) << r;
    EXPECT_NE(r.find(refit), std::string::npos) << r;
    EXPECT_EQ(r.find(linear), std::string::npos) << r;
  }
  {
    const IwanUpdateSummary s = fit(0, 0, t.k0 * 1.01, 1.0);
    const std::string r = s.report();
    EXPECT_NE(r.find("with Kt held, mode 1's linear frequency"), std::string::npos) << r;
    EXPECT_NE(r.find(linear), std::string::npos) << r;
    EXPECT_EQ(r.find(own), std::string::npos) << r;
    EXPECT_EQ(r.find(other), std::string::npos) << r;
  }
}

// The same causes with K_T held (--gamma 1), where the held-K_T and flat-damping rules read the
// low end: the one-mode truth and hits of the test above (seeds 100-102), K_T held at the
// truth's unless said.
// - the structure's own damping 5e-4 missing: the measured damping at the low end 3.9 times the
//   model's, its median factor 1.65 under the 1.7 asked before, and no cause was named; the
//   frequency softening there (5.2 %) names it now;
// - another mode adding 0.1 phi_max: the measured low-amplitude frequency 0.29 % below the held
//   linear limit and flat (0.87 %), the damping there 3.2 times the model's; before, "an error
//   of the linear part ... update-linear first (or free Kt)";
// - the same with K_T held 10 % low (linear limit within 0.1 % of the low data): the damping
//   there 5.6 times the model's at a median factor of 1.74; before, "a loss factor ... halve it"
//   (and before the softening share guarded it, "the structure's own damping").
// Seeds 100-200 of each gave the same line; the share's margin is that of the test above.
TEST(IwanUpdate, KtHeldOwnDampingAndAnotherModesSlipAreNamedByTheLowEnd) {
  const FloorTruth t;
  const double phi = model::Iwan(t.iwan).phi_max();
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.threads = 1;
  o.fixed_gamma = 1;
  const auto report = [&](double z_data, double q_other, double kt_scale) {
    const model::Model truth = one_mode_structure(t.k0, t.iwan, z_data);
    const IwanTarget target = three_hits_with_other_slip(truth, phi, q_other);
    const model::Model m =
        one_mode_structure(t.k0, {t.iwan.Fs * 1.3, t.iwan.Kt * kt_scale, -0.4, 0.7});
    const IwanObjective obj(m, "j", {}, {target}, o);
    IwanUpdateSummary s;
    update_iwan(obj, o, &s);
    return s.report();
  };
  const std::string other = "as where another mode slipping the same joint in these hits";
  std::string r = report(5e-4, 0, 1.0);
  EXPECT_NE(r.find("not the joint's. That is the structure's own damping"), std::string::npos) << r;
  EXPECT_NE(r.find("leans toward the structure's own damping"), std::string::npos) << r;
  EXPECT_EQ(r.find(other), std::string::npos) << r;
  r = report(0, 0.1 * phi, 1.0);
  EXPECT_NE(r.find("with Kt held, the measured low-amplitude frequency"), std::string::npos) << r;
  EXPECT_NE(r.find(other), std::string::npos) << r;
  EXPECT_EQ(r.find("update-linear first"), std::string::npos) << r;
  EXPECT_EQ(r.find("--linear-damping fit"), std::string::npos) << r;
  r = report(0, 0.1 * phi, 0.9);
  EXPECT_NE(r.find("leans toward another mode's slip"), std::string::npos) << r;
  EXPECT_EQ(r.find("a loss factor"), std::string::npos) << r;
}

// The frequency's low end leans between the structure's own damping and another mode's slip but
// does not decide, so a misfit of either names both, with the refit that tells them apart. On the
// one-mode truth's three hits (1e-4 / 2 % noise, K_T free, model without its own damping):
// - a joint nearly linear in amplitude (chi -0.05) with own damping 5e-4, 40 points a curve over
//   3.5 decades: the low end reads 0.56 % (flat), and it was named another mode's slip alone
//   ("Strike so that the fitted mode dominates"); with --linear-damping fit these data fit at a
//   reduced chi-square of 1.09 (Z 4.97e-4), so the own damping is what is missing;
// - chi -0.5 with own damping, 8 points a curve (too few to read the low end): named "the model's
//   linear part does not match the measured mode; update-linear first" (the linear part is the
//   truth's), as were own damping and another mode's slip at every chi from -0.05 to -0.9.
// Elsewhere the lean went wrong too (another mode adding 0.1 phi_max over 2.5 decades read 3.5 %
// for chi -0.5 and 5.0 % for chi -0.9, softening: named own damping alone); the sweep is in
// docs/update-iwan.md.
TEST(IwanUpdate, TheLowEndLeansButDoesNotDecideBetweenOwnDampingAndAnotherModesSlip) {
  const FloorTruth t;
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.threads = 1;
  const auto report = [&](double chi, int points) {
    model::IwanParameters joint = t.iwan;
    joint.chi = chi;
    const model::Model truth = one_mode_structure(t.k0, joint, 5e-4);
    const IwanTarget target =
        three_hits_with_other_slip(truth, model::Iwan(joint).phi_max(), 0, points);
    const model::Model m = one_mode_structure(t.k0, {joint.Fs * 1.3, joint.Kt * 0.9, -0.4, 0.7});
    const IwanObjective obj(m, "j", {}, {target}, o);
    IwanUpdateSummary s;
    update_iwan(obj, o, &s);
    return s.report();
  };
  const std::string both =
      "That is the structure's own damping (roughly constant in amplitude), which the model lacks "
      "(modal_ratio 0, held), or another mode slipping the same joint in these hits";
  std::string r = report(-0.05, 40);
  EXPECT_NE(r.find(both), std::string::npos) << r;
  EXPECT_NE(r.find("leans toward another mode's slip, but does not decide"), std::string::npos)
      << r;
  EXPECT_NE(r.find("Refit with --linear-damping fit"), std::string::npos) << r;
  r = report(-0.5, 8);
  EXPECT_NE(r.find(both), std::string::npos) << r;
  EXPECT_NE(r.find("leans neither way here (fewer than 10 points a curve"), std::string::npos) << r;
  EXPECT_EQ(r.find("update-linear first"), std::string::npos) << r;
}

// The fit of the riveted beam's three 40-point velocity hits read as the modal amplitude (the
// command's numbers): F_S at its upper bound 1500 N, the residuals in long waves.
IwanUpdateSummary velocity_read_as_modal() {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 4854, 240, 3.23e6);
  s.best = {1500, 9.08345e6, -0.949783, 1};
  s.at_bounds = {"Fs at its upper bound 1500 N"};
  s.bound_side[0] = 1;
  s.noise_correlation = 0.999;
  s.effective_points = 6.08;
  s.sigma_degrees_of_freedom = 3.08;
  s.amplitude_share = 0.475;
  s.bottom_slip = 6.64e-5;
  s.top_slip = 0.0118;
  s.phi_max = 3.15e-4;
  MisfitEvidence e = mode_one_evidence(149.668, 1e-4, 0, 0.2, 0.116);
  e.targets = 1;
  e.low_frequency_error = -0.153246;
  e.linear_hz = 138.921;
  e.low_softening_share = 0.054;
  s.evidence = e;
  return s;
}

// Velocity tables read as the modal amplitude (the default; the riveted beam's three 40-point
// hits, truth F_S 30 N): F_S ran to its upper bound 1500 N and the fitted joint still slipped at
// the lowest measured amplitude (0.21 phi_max), its curve there 8.8 % below its own linear limit
// and 15.3 % below the data. A factor on the amplitudes is one on F_S, so the cause is the
// amplitudes' quantity or unit; before, "the structure's own damping" was named and, with it
// fitted, "no slip in these data ... do not change with amplitude" (the gain over the constant
// backbone, 6.389e6 against 6.41e6, divided by a reduced chi-square of 3.25e6). The numbers are
// the command's; each check is on words, none on a tolerance.
TEST(IwanUpdateReport, AmplitudesReadAsTheWrongQuantityNameTheirUnitNotNoSlip) {
  IwanUpdateSummary s = velocity_read_as_modal();
  s.evidence->low_damping = 6.77e-4;
  s.evidence->low_model_damping = 3.82e-3;
  s.evidence->median_damping = 3.38e-3;
  const std::string quantity = "these amplitudes are larger than the quantity they are read as";
  std::string r = s.report();
  EXPECT_NE(r.find("Fs ran to its upper bound 1500 N and still the fitted joint slips at the "
                   "lowest measured amplitudes (0.21 phi_max there, 37 phi_max at the highest)"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find(quantity), std::string::npos) << r;
  EXPECT_NE(r.find("Fs at its upper bound 1500 N: the amplitudes pressed it there (below); a "
                   "wider range would let Fs take up their factor"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find("the structure's own damping"), std::string::npos) << r;
  // With Z fitted, no better than the constant backbone: the misfit runs in waves, so the gain
  // scaled by the reduced chi-square tests nothing, and no "no slip" is said.
  s.modal_ratio_fitted = true;
  s.final_cost = 6.389e6;
  s.constant_cost = 6.41e6;
  s.reduced_chi2 = 3.25e6;
  EXPECT_FALSE(s.no_slip_seen());
  r = s.report();
  EXPECT_EQ(r.find("no slip"), std::string::npos) << r;
  EXPECT_NE(r.find(quantity), std::string::npos) << r;
  // The same gain with residuals like noise (white, even over the amplitudes), or with offsets
  // between the curves that the constant shares, is still read as no slip.
  IwanUpdateSummary white = s;
  white.noise_correlation = 0.05;
  white.amplitude_share = 0.34;
  EXPECT_TRUE(white.no_slip_seen()) << white.report();
  IwanUpdateSummary offsets = s;
  offsets.evidence->between_curves_share = 0.6;
  offsets.evidence->curves = 3;
  EXPECT_TRUE(offsets.no_slip_seen()) << offsets.report();
  // Fs inside its range, or the fitted curve at its own linear limit at the lowest amplitudes
  // (the joint stuck there): not the amplitudes.
  s.modal_ratio_fitted = false;
  s.bound_side[0] = 0;
  s.at_bounds.clear();
  EXPECT_EQ(s.report().find(quantity), std::string::npos) << s.report();
  s.bound_side[0] = 1;
  s.at_bounds = {"Fs at its upper bound 1500 N"};
  s.evidence->linear_hz = 149.668 * (1 - 0.153246);
  EXPECT_EQ(s.report().find(quantity), std::string::npos) << s.report();
}

// Damping columns in another unit, named beside the cause the residuals point at, as the fit
// cannot tell them apart (the riveted beam's three hits, the command's numbers): a per-cent
// column without a unit over the microslip range, 0.0636 at the lowest amplitudes against the
// model's 0.00143 (44 times, every value below 1), and a loss factor over 2.5 decades, the
// measured damping a median 1.69 times the fitted model's with K_T raised toward it. Before,
// both were told only "the structure's own damping" (or another mode's slip).
TEST(IwanUpdateReport, DampingInAnotherUnitIsNamedBesideTheMissingDamping) {
  const std::string own = "That is the structure's own damping";
  const std::string per_cent = "a damping column in per cent read as a fraction";
  const std::string loss = "a loss factor (eta = 2 zeta) given as the damping ratio";
  // Per cent: the damping flat at the low end, the joint hardly moved at the fit.
  IwanUpdateSummary p = reported_fit(IwanUpdateStatus::kConverged, 2939, 84, 1260);
  p.best = {1500, 1.62068e7, -0.8125, 1};
  p.top_slip = 1.28e-7;
  p.phi_max = 1.6e-4;
  MisfitEvidence e = mode_one_evidence(149.684, 1e-4, 0, 62.6, 0.184);
  e.targets = 1;
  e.low_frequency_error = 5.05e-4;
  e.low_damping = 0.0636;
  e.low_model_damping = 0.00143;
  e.median_damping = 0.104;
  e.low_softening_share = 0.058;
  p.evidence = e;
  std::string r = p.report();
  EXPECT_NE(r.find(own), std::string::npos) << r;
  EXPECT_NE(r.find("Or, every measured damping lying below 1 and 44.5 times the model's at the "
                   "lowest amplitudes, " +
                   per_cent),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("(damping_ratio [%])"), std::string::npos) << r;
  // A value of 1 or more is no per cent; 3.7 times (the flat 0.3 % table's) is the own damping's.
  p.evidence->damping_max = 1.2;
  EXPECT_EQ(p.report().find(per_cent), std::string::npos) << p.report();
  p.evidence->damping_max = 0.184;
  p.evidence->low_damping = 3.7 * 0.00143;
  p.evidence->median_damping = 0.006;
  EXPECT_EQ(p.report().find(per_cent), std::string::npos) << p.report();
  // Loss factor: K_T raised toward the damping at the low end, the linear limit 0.139 % off.
  IwanUpdateSummary l = reported_fit(IwanUpdateStatus::kConverged, 2352, 240, 263);
  MisfitEvidence le = mode_one_evidence(149.668, 1e-4, 0, 1.69, 0.233);
  le.targets = 1;
  le.low_frequency_error = 1.389e-3;
  le.linear_hz = 150.359;
  le.low_damping = 0.00135;
  le.low_model_damping = 0.000984;
  le.median_damping = 0.00675;
  le.low_softening_share = 0.054;
  l.evidence = le;
  r = l.report();
  EXPECT_NE(r.find(own), std::string::npos) << r;
  EXPECT_NE(
      r.find("Or, the measured damping lying a median 1.69 times the fitted model's, " + loss),
      std::string::npos)
      << r;
  // A median factor near 1 (the fit took the damping up) or far above 2: no loss factor.
  for (const double factor : {1.2, 3.0}) {
    l.evidence->damping_factor = factor;
    EXPECT_EQ(l.report().find(loss), std::string::npos) << factor << ": " << l.report();
  }
}

// A 6-point curve fitted with its residuals independent (serial correlation 0): the note said
// "serially correlated along the curves (0 from one point to the next)". The points are few,
// not waves; at a correlation of 0.1 or more the waves are still named.
TEST(IwanUpdateReport, FewIndependentPointsAreNotCalledSeriallyCorrelated) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 2419, 12, 7.01);
  s.effective_points = 12;
  s.sigma_degrees_of_freedom = 8;
  s.amplitude_share = 0.6;
  s.relative_std = Eigen::Vector4d::Constant(0.01);
  std::string r = s.report();
  EXPECT_NE(r.find("note: the 12 residuals (6 points) are few, each independent of the next "
                   "(serial correlation 0, corrected for what the fit absorbs): they amount to "
                   "12 independent points"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find("serially correlated"), std::string::npos) << r;
  // Too few for a sigma, nearly independent (8 residuals at 0.09 amount to 6.68, 5 parameters
  // fitted): no "long waves".
  s.residuals = 8;
  s.noise_correlation = 0.09;
  s.effective_points = 6.68;
  s.sigma_degrees_of_freedom = 1.68;
  r = s.report();
  EXPECT_EQ(r.find("long waves"), std::string::npos) << r;
  EXPECT_NE(r.find("WARNING: the 8 residuals (4 points), each independent of the next (serial "
                   "correlation 0.09, corrected for what the fit absorbs), amount to 6.7 "
                   "independent points, too few to state a sigma"),
            std::string::npos)
      << r;
  // Correlated: the waves.
  s.effective_points = 12;
  s.sigma_degrees_of_freedom = 8;
  s.residuals = 36;
  s.noise_correlation = 0.5;
  EXPECT_NE(s.report().find("serially correlated along the curves (0.5 from one point"),
            std::string::npos)
      << s.report();
}

// Displacement tables of the riveted beam (truth F_S 30 N) 1000 times too small (m given the
// unit mm, say): F_S ran to its lower bound 1.67 N, the fitted joint reached 0.018 phi_max at the
// highest amplitude, the fitted curve there 4.15 % above the data (415 times their noise) and
// 0.88 % below them at the lowest. A factor on the amplitudes is one on F_S, so the amplitudes'
// scale is named; before, "the structure's own damping" or another mode's slip, and F_S's bound
// "a wider range would not cure that" (--fs-range 1e-4:100 fits F_S 0.02999 N at a reduced
// chi-square of 1.11). The numbers are the command's; each check is on words.
TEST(IwanUpdateReport, AmplitudesReadTooSmallNameTheirScale) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 2172, 240, 1.4e4);
  s.best = {1.66667, 1.55912e7, -0.8387, 1};
  s.held[3] = true;  // by the fit: microslip only
  s.beta_hold = IwanBetaHold::kMicroslip;
  s.at_bounds = {"Fs at its lower bound 1.66667 N"};
  s.bound_side[0] = -1;
  s.noise_correlation = 0.837;
  s.effective_points = 24.8;
  s.sigma_degrees_of_freedom = 21.8;
  s.amplitude_share = 0.78;
  s.bottom_slip = 2.68e-11;
  s.top_slip = 3.44e-9;
  s.phi_max = 1.88e-7;
  MisfitEvidence e = mode_one_evidence(149.666, 1e-4, 0, 1.35, 0.03);
  e.targets = 1;
  e.low_frequency_error = -0.00879;
  e.linear_hz = 150.805;
  e.high_frequency_hz = 141.188;
  e.high_frequency_error = 0.041456;
  e.high_frequency_noise = 1e-4;
  e.low_damping = 6.81e-4;
  e.low_model_damping = 1.67e-3;
  e.median_damping = 3e-3;
  e.low_softening_share = 0.054;
  s.evidence = e;
  const std::string smaller = "these amplitudes are smaller than the quantity they are read as";
  std::string r = s.report();
  EXPECT_NE(r.find("Fs ran to its lower bound 1.667 N and still the fitted curve at the highest "
                   "measured amplitudes lies +4.15 % off the measured frequency 141.188 Hz there "
                   "(415 times its noise), while at the lowest it lies -0.879 % off"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find(smaller), std::string::npos) << r;
  EXPECT_NE(r.find("Fs at its lower bound 1.66667 N: the amplitudes pressed it there (below); a "
                   "wider range would let Fs take up their factor"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find("the structure's own damping"), std::string::npos) << r;
  EXPECT_EQ(r.find("would not cure that"), std::string::npos) << r;
  // The fitted curve within ten times the noise of the data at the top (1e-3 here), or above
  // them by as much at both ends (a linear part too stiff), or F_S inside its range or held:
  // not the amplitudes.
  IwanUpdateSummary c = s;
  c.evidence->high_frequency_error = 9e-4;
  EXPECT_EQ(c.report().find(smaller), std::string::npos) << c.report();
  c = s;
  c.evidence->low_frequency_error = 0.0410;
  EXPECT_EQ(c.report().find(smaller), std::string::npos) << c.report();
  c = s;
  c.bound_side[0] = 0;
  c.at_bounds.clear();
  EXPECT_EQ(c.report().find(smaller), std::string::npos) << c.report();
  c = s;
  c.held[0] = true;
  EXPECT_EQ(c.report().find(smaller), std::string::npos) << c.report();
  // At the upper bound the larger-amplitude rule alone applies (the curve above the data at the
  // top says nothing of amplitudes read too large).
  c = s;
  c.bound_side[0] = 1;
  c.at_bounds = {"Fs at its upper bound 1500 N"};
  EXPECT_EQ(c.report().find(smaller), std::string::npos) << c.report();
}

// Velocity tables read as the modal amplitude (the riveted beam, the command's numbers; Z held and
// fitted): beta freed lost to beta held (6.426e6 against 6.389e6) and the report said "run again
// with a larger --evaluations (e.g. 19416)", which cannot help while the amplitudes are read as
// another quantity; and the note on the serially correlated residuals said "the sigmas allow for
// it (Student's t, 3.08 degrees of freedom)" above "no sigma is stated".
TEST(IwanUpdateReport, ANamedCauseComesBeforeALongerSearchForBetaAndNoSigmaIsAllowedFor) {
  IwanUpdateSummary s = velocity_read_as_modal();
  s.held[3] = true;
  s.beta_hold = IwanBetaHold::kFreeFitNoBetter;
  s.free_fit_cost = 6.426e6;
  s.final_cost = 6.389e6;
  const std::string longer = "larger --evaluations";
  const std::string allow = "the sigmas allow for it (Student's t";
  std::string r = s.report();
  EXPECT_NE(r.find("these amplitudes are larger than the quantity they are read as"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("with beta held at its start 1: beta is not fitted and has no sigma, and the "
                   "other parameters hold at that beta; mend the cause named above first"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find(longer), std::string::npos) << r;
  EXPECT_NE(r.find("the 240 residuals amount to 6.08 independent points; no sigma is stated, so "
                   "none rests on these few"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find(allow), std::string::npos) << r;
  // No cause named (no evidence): the search is the suspect, and the longer search is advised;
  // with sigmas stated they allow for the few points.
  s.evidence.reset();
  s.relative_std = Eigen::Vector4d::Constant(0.01);
  r = s.report();
  EXPECT_NE(r.find("run again with a larger --evaluations (e.g. 19416)"), std::string::npos) << r;
  EXPECT_NE(r.find(allow + ", 3.08 degrees of freedom) but rest on these few"), std::string::npos)
      << r;
}

// A per-cent damping column on the riveted beam's microslip tables (the command's numbers): F_S
// ran to its upper bound 1500 N, where the fitted joint slips 8e-4 phi_max at the highest
// amplitude. The cause line said "this mode hardly moves the joint", which the bound, not the
// mode's shape, made so, and F_S's bound "a wider range would not cure that", where nothing holds
// F_S (--fs-range 1:1e7 moved it to 23751 N at cost 2430 -> 2423).
TEST(IwanUpdateReport, AJointSetAsideAtTheSlipForcesBoundIsNotAModeThatHardlyMovesIt) {
  IwanUpdateSummary p = reported_fit(IwanUpdateStatus::kConverged, 2939, 84, 1260);
  p.best = {1500, 1.62068e7, -0.8125, 1};
  p.held[3] = true;  // by the fit: microslip only
  p.beta_hold = IwanBetaHold::kMicroslip;
  p.bottom_slip = 2.6e-8;
  p.top_slip = 1.28e-7;
  p.phi_max = 1.6e-4;
  p.final_cost = 2430;
  MisfitEvidence e = mode_one_evidence(149.684, 1e-4, 0, 62.6, 0.184);
  e.targets = 1;
  e.low_frequency_error = 5.05e-4;
  e.linear_hz = 151.640;
  e.low_damping = 0.0636;
  e.low_model_damping = 0.00143;
  e.median_damping = 0.104;
  e.low_softening_share = 0.058;
  p.evidence = e;
  const std::string hardly = "this mode hardly moves the joint";
  // F_S inside its range: the mode's shape leaves the joint still, as before.
  ASSERT_NE(p.report().find(hardly), std::string::npos) << p.report();
  p.at_bounds = {"Fs at its upper bound 1500 N"};
  p.bound_side[0] = 1;
  const std::string r = p.report();
  EXPECT_EQ(r.find(hardly), std::string::npos) << r;
  EXPECT_NE(r.find("That is the structure's own damping (roughly constant in amplitude)"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("a damping column in per cent read as a fraction"), std::string::npos) << r;
  EXPECT_NE(r.find("Fs at its upper bound 1500 N: there the fitted joint hardly slips (0.0008 "
                   "phi_max at the highest amplitude): the misfit below set the joint aside, so "
                   "nothing in these data holds Fs; a wider range moves it, not the fit"),
            std::string::npos)
      << r;
  EXPECT_EQ(r.find("would not cure that"), std::string::npos) << r;
}

// The low end's damping rise against its frequency drop (MisfitEvidence::low_rise_ratio), read
// off the data alone: on the ring-down definitions an Iwan joint's damping and relative frequency
// drop in microslip both go as the slip amplitude to the power chi + 1, so their increments keep
// 4 / (pi (chi + 2) (chi + 3) G(chi)), G = int_0^1 x^chi (1 - (theta - sin theta cos theta) / pi)
// dx with cos theta = 1 - 2x (method.md's first-harmonic slider): 0.250 at chi -0.5, 0.326 at
// -0.3, at most 4 / (3 pi) = 0.424 at chi 0; the structure's own damping (5e-4 here), constant,
// drops out. QSMA's ring-down values of the one-mode truth, noise-free over three 40-point hits
// from 1e-8 to 1.5-2.5 phi_max, read 0.0611, 0.164, 0.2505, 0.3260, 0.3605, 0.3933, 0.4245 at chi
// -0.9, -0.7, -0.5, -0.3, -0.2, -0.1, 0 (the closed form 0.0601, 0.163, 0.2500, 0.3257, 0.3603,
// 0.3931, 0.4244). Here: three 40-point microslip hits (1e-2 to 0.5 phi_max, the probe's 1e-4
// frequency and 2 % damping noise): the truth at chi -0.5 and -0.3 reads below the limit, the
// chi -0.3 dampings doubled (a loss factor) above it, the chi -0.5 ones a hundred times (per
// cent) far above; another mode adding 0.1 phi_max to the joint's slip shifts the slip of both
// alike and stays below (measured: 0.254, 0.320, 0.639 at 3.7 standard deviations above, 25.4,
// 0.298). Tolerances: the ratio's noise over 8-point fifths (0.06 allowed on the truth's, 0.12 on
// the doubled, 5 on per cent); the excess is in standard deviations, 3 the rule's threshold.
TEST(IwanUpdate, TheLowEndsDampingRiseAgainstItsDropBoundsAJoints) {
  const FloorTruth t;
  const auto evidence = [&](double chi, double q_other, double scale) {
    const model::IwanParameters p{t.iwan.Fs, t.iwan.Kt, chi, t.iwan.beta};
    const model::Model truth = one_mode_structure(t.k0, p, t.z);
    const double phi = model::Iwan(p).phi_max();
    IwanTarget target;
    for (int h = 0; h < 3; ++h) {
      target.curves.push_back(backbone_with_other_slip(truth, 40, 1e-2 * phi, 0.5 * phi,
                                                       q_other * phi, 1e-4, 0.02, 100 + h));
      target.curves.back().damping_ratio *= scale;
      target.curves.back().damping_std *= scale;
    }
    const IwanObjective obj(truth, "j", {}, {target}, {});
    const std::optional<MisfitEvidence> e = obj.misfit_evidence(p, t.z);
    EXPECT_TRUE(e);
    return e.value_or(MisfitEvidence{});
  };
  const MisfitEvidence own = evidence(-0.5, 0, 1);
  EXPECT_NEAR(own.low_rise_ratio, 0.250, 0.06);
  EXPECT_LT(own.low_rise_excess, 3);
  const MisfitEvidence flatter = evidence(-0.3, 0, 1);
  EXPECT_NEAR(flatter.low_rise_ratio, 0.326, 0.06);
  EXPECT_LT(flatter.low_rise_excess, 3);
  const MisfitEvidence loss = evidence(-0.3, 0, 2);
  EXPECT_NEAR(loss.low_rise_ratio, 0.652, 0.12);
  EXPECT_GT(loss.low_rise_excess, 3);
  const MisfitEvidence per_cent = evidence(-0.5, 0, 100);
  EXPECT_NEAR(per_cent.low_rise_ratio, 25, 5);
  EXPECT_GT(per_cent.low_rise_excess, 3);
  const MisfitEvidence other = evidence(-0.5, 0.1, 1);
  EXPECT_LT(other.low_rise_excess, 3);
}

// The riveted beam's loss factor on 14-point microslip tables (the command's numbers): the fit
// took the doubling up almost whole (a median factor of 1.08, K_T raised, the linear limit
// +0.104 % off) and the report named only the structure's own damping or another mode's slip.
// The damping rises 0.86 times the frequency's relative drop from the lowest to the second fifth,
// 4.3 standard deviations above 4 / (3 pi), which no Iwan joint with chi <= 0 exceeds in microslip
// and the constant own damping does not change: a damping column in another unit is named
// beside. Not where the excess is within 3 standard deviations, the fitted chi above 0, the two
// fifths not in microslip at the fit, or the median factor names the loss factor already.
TEST(IwanUpdateReport, ADampingRiseNoJointGivesNamesTheDampingsUnit) {
  IwanUpdateSummary s = reported_fit(IwanUpdateStatus::kConverged, 1078, 84, 48.6);
  s.best = {21.9948, 1.54205e7, -0.4729, 1};
  s.held[3] = true;  // by the fit: microslip only
  s.beta_hold = IwanBetaHold::kMicroslip;
  s.noise_correlation = 0.841;
  s.effective_points = 11.6;
  s.sigma_degrees_of_freedom = 8.59;
  s.amplitude_share = 0.5;
  s.bottom_slip = 2.59e-8;
  s.top_slip = 1.28e-7;
  s.phi_max = 2.12e-6;
  MisfitEvidence e = mode_one_evidence(149.684, 1e-4, 0, 1.084, 0.00367);
  e.targets = 1;
  e.low_frequency_error = 1.042e-3;
  e.linear_hz = 150.566;
  e.low_damping = 1.272e-3;
  e.low_model_damping = 1.295e-3;
  e.median_damping = 2.086e-3;
  e.low_softening_share = 0.0576;
  e.low_rise_ratio = 0.860;
  e.low_rise_excess = 4.31;
  e.low_rise_span = 1.438;
  s.evidence = e;
  const std::string unit = "Or a damping column in another unit";
  std::string r = s.report();
  EXPECT_NE(r.find("That is the structure's own damping"), std::string::npos) << r;
  EXPECT_NE(r.find(unit + ": from the lowest to the second fifth of amplitudes the measured "
                          "damping rises 0.86 times the measured frequency's relative drop, 4.3 "
                          "standard deviations above the 0.42 that no Iwan joint with chi at or "
                          "below 0 exceeds in microslip"),
            std::string::npos)
      << r;
  EXPECT_NE(r.find("a loss factor (eta = 2 zeta) given as the damping ratio doubles it"),
            std::string::npos)
      << r;
  IwanUpdateSummary c = s;
  c.evidence->low_rise_excess = 2.9;
  EXPECT_EQ(c.report().find(unit), std::string::npos) << c.report();
  c = s;
  c.best.chi = 0.1;
  EXPECT_EQ(c.report().find(unit), std::string::npos) << c.report();
  c = s;
  c.evidence->low_rise_span = 0.5 * 2.12e-6 / 2.59e-8;
  EXPECT_EQ(c.report().find(unit), std::string::npos) << c.report();
  c = s;
  c.evidence->damping_factor = 1.69;
  EXPECT_EQ(c.report().find(unit), std::string::npos) << c.report();
  EXPECT_NE(c.report().find("Or, the measured damping lying a median 1.69 times"),
            std::string::npos)
      << c.report();
}

}  // namespace
}  // namespace jointlab::correlate
