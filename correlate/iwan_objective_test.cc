// The Iwan update's objective: residuals at the truth and away, their weights and floors, the
// fast evaluation against the slow one, held linear damping, bad input, and the slip force at
// another beta.
#include "jointlab/correlate/iwan_update.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/correlate/iwan_update_test_fixtures.h"
#include "jointlab/correlate/two_chain.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::correlate {
namespace {

using iwan_test::FloorTruth;
using iwan_test::Synthetic;

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

TEST(IwanUpdate, BadInputIsReported) {
  const model::Model m = two_chain_structure();
  Synthetic s;
  EXPECT_THROW(IwanObjective(m, "rivet", s.sensors, {s.target}, {}),
               InputError);  // no Iwan set in the linear model
  IwanUpdateOptions o;
  o.bounds.chi_min = -1.5;
  EXPECT_NE(o.error(), "");
}

}  // namespace
}  // namespace jointlab::correlate
