// The Iwan update on the usual campaign's shape: a few hits at rising force levels, each hit's
// backbone over its own amplitude range, the joint a little different in each hit (settling,
// re-tightening). Which parameters rest on one hit alone, how far the hits' joints scatter about
// one another, and the sigmas that allow for it.
#include "jointlab/correlate/iwan_update.h"

#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/correlate/iwan_update_test_fixtures.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/two_chain.h"

namespace jointlab::correlate {
namespace {

using iwan_test::box_around;
using iwan_test::FloorTruth;
using iwan_test::modal_backbone;

// One hit of the campaign: its amplitude range in units of the nominal joint's phi_max and its
// joint's F_S and K_T relative to the nominal's.
struct Hit {
  double lo, hi;  ///< amplitude range [phi_max]
  double fs = 1, kt = 1;
  double z = 0;  ///< the structure's own damping ratio in that hit
};

// The hits' backbones of the one-mode truth (F_S 0.5 N, K_T 4 % of the stiffness, chi -0.5, beta
// 0.5), 30 points each, 1e-4 frequency and 2 % damping noise stated as such (seeds seed + h),
// each of its own joint, named "hit h+1".
IwanTarget campaign(const std::vector<Hit>& hits, unsigned seed,
                    double chi = FloorTruth().iwan.chi) {
  const FloorTruth t;
  const double phi = model::Iwan(t.iwan).phi_max();
  IwanTarget target;
  for (size_t h = 0; h < hits.size(); ++h) {
    model::IwanParameters p = t.iwan;
    p.chi = chi;
    p.Fs *= hits[h].fs;
    p.Kt *= hits[h].kt;
    MeasuredBackbone b =
        modal_backbone(one_mode_structure(t.k0, p, hits[h].z), 30, hits[h].lo * phi,
                       hits[h].hi * phi, 1e-4, 0.02, seed + static_cast<unsigned>(h));
    b.source = "hit " + std::to_string(h + 1);
    target.curves.push_back(b);
  }
  return target;
}

// The fit from the start a little off the truth (F_S x1.3, K_T x0.9, chi -0.4, beta 0.7), one
// thread, the default budget; a model whose linear part is `stiffer` times the truth's, chi
// held within 0.01 of `held_chi` where given (models that are wrong), beta held at
// `held_beta` as --beta holds it where given, and beta's range ending at `beta_max` where given.
IwanUpdateSummary fit(const IwanTarget& target, double stiffer = 1,
                      std::optional<double> held_chi = std::nullopt,
                      std::optional<double> held_beta = std::nullopt,
                      std::optional<double> beta_max = std::nullopt) {
  const FloorTruth t;
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.threads = 1;
  o.fixed_beta = held_beta;
  if (beta_max) o.bounds.beta_max = *beta_max;
  model::IwanParameters near = t.near();
  if (held_chi) {
    near.chi = *held_chi;
    o.bounds.chi_min = *held_chi - 0.01;
    o.bounds.chi_max = *held_chi + 0.01;
  }
  const model::Model start =
      one_mode_structure(stiffer * t.k0, near, 0.0);  // the objective keeps it
  const IwanObjective obj(start, "j", {}, {target}, o);
  IwanUpdateSummary s;
  update_iwan(obj, o, &s);
  return s;
}

// The fit of fit() with the options and the start's Iwan parameters (F_S x1.3, K_T x0.9, chi
// -0.4, beta 0.7) as `adjust` leaves them.
IwanUpdateSummary fit_with(
    const IwanTarget& target,
    const std::function<void(IwanUpdateOptions&, model::IwanParameters&)>& adjust,
    double stiffer = 1) {
  const FloorTruth t;
  IwanUpdateOptions o;
  o.bounds = box_around(t.iwan);
  o.threads = 1;
  model::IwanParameters near = t.near();
  adjust(o, near);
  const model::Model start = one_mode_structure(stiffer * t.k0, near, 0.0);  // kept by obj
  const IwanObjective obj(start, "j", {}, {target}, o);
  IwanUpdateSummary s;
  update_iwan(obj, o, &s);
  return s;
}

// The z-score of parameter k (F_S, K_T, chi, beta) of s against the nominal truth.
double z_score(const IwanUpdateSummary& s, int k) {
  const FloorTruth t;
  const double truth[] = {t.iwan.Fs, t.iwan.Kt, t.iwan.chi, t.iwan.beta};
  const double found[] = {s.best.Fs, s.best.Kt, s.best.chi, s.best.beta};
  return k == 2 ? (found[k] - truth[k]) / (std::abs(found[k]) * s.relative_std(k))
                : std::log(found[k] / truth[k]) / s.relative_std(k);
}

// Three hits at rising levels, one each (1e-3-0.03, 0.03-0.3 and 0.3-2 phi_max): only the top one
// reaches past phi_max, so F_S and beta rest on it alone (the others carry under 1 % of their
// information: shares 1.000) and are that hit's joint's, here with F_S 3 % above the nominal
// (the middle hit's -1 %, K_T +0.5 %). Before, F_S came out +2.4 % +/- 0.30 % (z +7.8: the top
// hit's noise alone) with no word of the scatter, which no one hit shows (the Monte Carlo of
// such campaigns, F_S 2 % and K_T 1 % between hits, 10 seeds: 4 of the 5 stated F_S sigmas at
// |z| 4.0-7.6). Now F_S and beta state no sigma, and the note says why and gives that hit's
// noise alone as conditional. K_T and chi, which the lower hits share (0.70 and 0.84 of their
// information on the lowest), keep theirs, each within 3 of the nominal truth (a z-score over
// 3 is 1 in 370 for an honest sigma).
TEST(IwanCampaignShape, AParameterOnlyTheTopHitFixesRestsOnThatHitAndStatesNoSigma) {
  const IwanTarget target =
      campaign({{1e-3, 3e-2, 1.0, 1.0}, {3e-2, 0.3, 0.99, 1.005}, {0.3, 2.0, 1.03, 1.0}}, 40);
  const IwanUpdateSummary s = fit(target);
  const std::string r = s.report();
  SCOPED_TRACE(r);
  ASSERT_EQ(s.status, IwanUpdateStatus::kConverged);
  // The fit reads the top hit's F_S (+3 %), not the nominal's.
  EXPECT_NEAR(s.best.Fs / 0.5, 1.03, 0.01);
  for (const int k : {0, 3}) {
    EXPECT_EQ(s.sigma_reason(k), IwanSigmaReason::kOneHit) << k;
    EXPECT_EQ(s.relative_std(k), 0.0) << k;
    EXPECT_GT(s.one_curve_share[static_cast<size_t>(k)], 0.99) << k;
    EXPECT_EQ(s.one_curve_name[static_cast<size_t>(k)], "hit 3") << k;
  }
  EXPECT_NE(r.find("Fs 0.65 -> "), std::string::npos);
  EXPECT_NE(r.find("(no sigma: rests on one hit alone, below)"), std::string::npos);
  EXPECT_NE(r.find("note: Fs and beta rest on one hit alone, hit 3 (the other hits carry under "
                   "1 % of their information)"),
            std::string::npos);
  EXPECT_NE(r.find("That hit's noise alone gives Fs +/- "), std::string::npos);
  EXPECT_EQ(s.parameter_note(0),
            "no sigma: rests on one hit alone (its joint's scatter between hits unmeasured)");
  // What those sigmas allow for: the joint as it was in these hits.
  EXPECT_NE(r.find("note: the sigmas are of the joint as it was in the hits of these 3 curves: "
                   "how far the joint changes from hit to hit (settling, re-tightening) they "
                   "allow for only as far as the hits' curves disagree"),
            std::string::npos);
  // Hits that agree by chance cannot be told from an unchanged joint: the note says so plainly
  // rather than widening the sigma by a scatter no residual shows.
  EXPECT_NE(r.find("hits whose joints happen to agree with one another show none of it: no "
                   "statistic of these curves can tell them from hits of a joint that did not "
                   "change"),
            std::string::npos);
  // K_T and chi, shared by the hits, keep a sigma that covers the nominal truth.
  for (const int k : {1, 2}) {
    ASSERT_EQ(s.sigma_reason(k), IwanSigmaReason::kStated) << k;
    EXPECT_LT(s.one_curve_share[static_cast<size_t>(k)], 0.99) << k;
    EXPECT_LT(std::abs(z_score(s, k)), 3) << k;
  }
}

// The same three hits with the top one read at two channels (two curves of "hit 3", the same
// joint, each its own noise; two of its modes do the same): F_S and beta still rest on that hit
// alone. Before, the one-hit share was taken curve by curve, each of the two carried about half
// (F_S 0.48, beta 0.43), and F_S came out with a sigma of the top hit's noise, +/- 0.28 %, at
// z +9.5 against the joint's mean; one channel of it stated none. Required: as with one channel,
// F_S and beta state no sigma and name that hit, and the share is the hit's (over 0.99).
TEST(IwanCampaignShape, TwoChannelsOfTheTopHitAreStillOneHit) {
  IwanTarget target = campaign({{1e-3, 3e-2, 1.0, 1.0},
                                {3e-2, 0.3, 0.99, 1.005},
                                {0.3, 2.0, 1.03, 1.0},
                                {0.3, 2.0, 1.03, 1.0}},
                               40);
  target.curves[3].source = "hit 3";  // the top hit's second channel
  const IwanUpdateSummary s = fit(target);
  SCOPED_TRACE(s.report());
  ASSERT_EQ(s.status, IwanUpdateStatus::kConverged);
  for (const int k : {0, 3}) {
    EXPECT_EQ(s.sigma_reason(k), IwanSigmaReason::kOneHit) << k;
    EXPECT_EQ(s.relative_std(k), 0.0) << k;
    EXPECT_GT(s.one_curve_share[static_cast<size_t>(k)], 0.99) << k;
    EXPECT_EQ(s.one_curve_name[static_cast<size_t>(k)], "hit 3") << k;
  }
}

// Two hits (1e-3-0.1 and 0.1-2 phi_max), the low one's joint 1.5 % stiffer: K_T rests mostly on
// it (0.91 of its information), whose residuals the fit has taken up along K_T, and the plain
// cluster covariance needs three curves besides. Before, K_T came out +1.1 % +/- 0.22 % (z +5.1:
// the low hit's noise alone); the cluster covariance with each curve's residuals corrected for
// its own leverage (CR2) now states +/- 0.62 % (z +1.8; |z| < 3 asked, 1 in 370 for an honest
// sigma). The Monte Carlo of two such hits, K_T 1 % and F_S 2 % between them, 10 seeds: K_T
// |z| at most 7.8 and over 3 in 3 of 8 before, at most 2.7 now; with no scatter K_T's z-scores'
// RMS 1.11 and chi's 1.00.
TEST(IwanCampaignShape, KtMostlyFromTheLowHitAllowsForTheOtherHitsView) {
  const IwanTarget target = campaign({{1e-3, 0.1, 1.0, 1.015}, {0.1, 2.0, 1.0, 1.0}}, 60);
  const IwanUpdateSummary s = fit(target);
  const std::string r = s.report();
  SCOPED_TRACE(r);
  ASSERT_EQ(s.status, IwanUpdateStatus::kConverged);
  ASSERT_EQ(s.sigma_reason(1), IwanSigmaReason::kStated);
  EXPECT_GT(s.one_curve_share[1], 0.8);
  EXPECT_LT(std::abs(z_score(s, 1)), 3);
  EXPECT_EQ(s.sigma_reason(0), IwanSigmaReason::kOneHit);
}

// Three hits over the same amplitudes (1e-3-2 phi_max, one level struck three times), each hit's
// joint its own (F_S +4 %, -4 %, 0 and K_T -1.5 %, +1.5 %, 0 about the nominal): the curves
// disagree with one another, and that scatter explains most of the chi-square. One cluster per
// curve leaves Student's t 2 degrees of freedom, whose variance is infinite; before, no sigma was
// stated at all. Now each sigma is t's 95 % interval over 1.96 (2.2 times the cluster standard
// error), which assumes the offsets random scatter of one joint. Monte Carlo of such campaigns
// (F_S 2 % or 5 % and K_T 1 % or 2 % between three hits, 40 seeds each): of the 34 fits the
// scatter explained, every parameter within 1.96 sigma of the nominal truth (so coverage of the
// 95 % interval at least 95 %; it is conservative, the largest |z| 1.9). Here each |z| < 1.96
// asked.
TEST(IwanCampaignShape, ThreeScatteredHitsStateStudentsTIntervalOverTwoDegreesOfFreedom) {
  const IwanTarget target =
      campaign({{1e-3, 2.0, 1.04, 1.015}, {1e-3, 2.0, 0.96, 0.985}, {1e-3, 2.0, 1.0, 1.0}}, 80);
  const IwanUpdateSummary s = fit(target);
  const std::string r = s.report();
  SCOPED_TRACE(r);
  ASSERT_EQ(s.status, IwanUpdateStatus::kConverged);
  ASSERT_TRUE(s.evidence);
  EXPECT_EQ(s.evidence->curves, 3);
  EXPECT_TRUE(s.scatter_explains_misfit());
  EXPECT_NE(r.find("the sigmas allow for it (one cluster per hit, Student's t with 2 degrees "
                   "of freedom, whose variance is infinite: each sigma is its 95 % interval over "
                   "1.96"),
            std::string::npos);
  for (int k = 0; k < 4; ++k) {
    ASSERT_EQ(s.sigma_reason(k), IwanSigmaReason::kStated) << k;
    EXPECT_LT(std::abs(z_score(s, k)), 1.96) << k;
  }
  EXPECT_EQ(r.find("note: the sigmas are of the joint as it was"), std::string::npos);
}

// The same three scattered hits, each read at two channels (six curves, two per hit, each
// channel its own noise): the second channel says nothing of how the joint differs from hit to
// hit. Before, the clusters were the curves: five degrees of freedom and correlated scores gave
// sigmas 2.3-2.7 times narrower than one channel's (F_S +/- 1.95-2.27 % against 4.96-5.20 %, K_T
// 0.70-0.76 % against 1.72-2.01 %, 4 seeds). Now the clusters are the hits: F_S's and K_T's
// sigmas at least 0.8 times the one-channel fit's, Student's t over 2 degrees of freedom as for
// three curves, and every |z| < 1.96 as there.
TEST(IwanCampaignShape, TwoChannelsOfEachHitAreNoMoreHits) {
  const std::vector<Hit> hits = {
      {1e-3, 2.0, 1.04, 1.015}, {1e-3, 2.0, 0.96, 0.985}, {1e-3, 2.0, 1.0, 1.0}};
  const IwanUpdateSummary one = fit(campaign(hits, 80));
  IwanTarget both = campaign(hits, 80);
  const IwanTarget second = campaign(hits, 180);  // the other channel: its own noise
  for (const MeasuredBackbone& c : second.curves) both.curves.push_back(c);  // same sources
  const IwanUpdateSummary s = fit(both);
  const std::string r = s.report();
  SCOPED_TRACE(r);
  ASSERT_EQ(s.status, IwanUpdateStatus::kConverged);
  EXPECT_EQ(s.curves, 6);
  EXPECT_EQ(s.hits, 3);
  ASSERT_TRUE(s.scatter_explains_misfit());
  EXPECT_NE(r.find("one cluster per hit, Student's t with 2 degrees of freedom"),
            std::string::npos);
  for (int k = 0; k < 4; ++k) {
    ASSERT_EQ(s.sigma_reason(k), IwanSigmaReason::kStated) << k;
    // F_S and K_T, which the hits' joints scatter in, at least 0.8 times (seeds 80, 90, 100:
    // 0.94-1.09; clustered by curve 0.37-0.41); chi and beta, which noise rather than that
    // scatter sets, narrow with the second channel's points (0.65-0.80, about 1/sqrt 2).
    if (k < 2) {
      EXPECT_GT(s.relative_std(k), 0.8 * one.relative_std(k)) << k;
    }
    EXPECT_LT(std::abs(z_score(s, k)), 1.96) << k;
  }
}

// Scatter that reshapes the curves rather than offsetting them: three hits at rising levels from
// one floor (1e-3 to 0.1, 0.5 and 2 phi_max), the middle hit's joint F_S -5 % and K_T +1 % (off
// in opposite senses), the others nominal. The offsets between the curves explain only 37 % of
// the chi-square, and before, the fit ended "the model does not describe the data" with no
// cause and no sigma (so did 10 of 40 three-hit fits over one range at 5 % / 2 % random
// scatter, and 2-5 of 40 at rising levels). Where the curves overlap in amplitude, their own
// offsets and slopes about a common curve explain 44 % (a chi-square of 131 where the noise
// gives about 8) and the common curve gains what noise gives (27 over 22): the hits disagree
// with one another, data against data, which no model error does. Now the cause names the
// scatter, with that evidence and what to do, and the sigmas are Student's t's over the hits
// (t 2: |z| < 1.96 asked; measured +0.48 K_T, +0.56 chi; of 256 such z-scores in the Monte
// Carlo, 200 seeds, 248 within 1.96). Models wrong with the hits alike (the linear part 0.4 %
// stiff, chi held at -0.6 on chi -0.2 data) still say the model does not describe the data: their
// curves' own shapes explain 2 % and 0 % (at most 5 % over 40 seeds each).
TEST(IwanCampaignShape, ScatterThatReshapesTheCurvesIsNamedAndItsSigmasAllowForIt) {
  const std::vector<Hit> hits = {{1e-3, 0.1}, {1e-3, 0.5, 0.95, 1.01}, {1e-3, 2.0}};
  const IwanUpdateSummary s = fit(campaign(hits, 7));
  const std::string r = s.report();
  SCOPED_TRACE(r);
  ASSERT_EQ(s.status, IwanUpdateStatus::kConverged);
  ASSERT_TRUE(s.misfit());
  ASSERT_TRUE(s.evidence);
  EXPECT_LT(s.evidence->between_curves_share, 0.5);  // no offset rule
  EXPECT_TRUE(s.evidence->hits_differ_in_shape());
  EXPECT_GT(s.evidence->between_hits_share, 0.25);
  EXPECT_TRUE(s.scatter_explains_misfit());
  EXPECT_FALSE(s.misfit_sets_the_error());
  EXPECT_NE(r.find("the 3 curves disagree with one another by more than their stated noise: "
                   "where their amplitudes overlap they differ in shape"),
            std::string::npos);
  EXPECT_NE(r.find("A model error gives every hit the same residual at the same amplitude"),
            std::string::npos);
  EXPECT_NE(r.find("Fit each hit alone"), std::string::npos);
  EXPECT_NE(r.find("one cluster per hit, Student's t with 2 degrees of freedom"),
            std::string::npos);
  for (const int k : {1, 2}) {
    ASSERT_EQ(s.sigma_reason(k), IwanSigmaReason::kStated) << k;
    EXPECT_LT(std::abs(z_score(s, k)), 1.96) << k;
  }
  // The same campaign without scatter and a model that is wrong: still no scatter named.
  const IwanTarget alike = campaign({{1e-3, 0.1}, {1e-3, 0.5}, {1e-3, 2.0}}, 7);
  const IwanTarget soft = campaign({{1e-3, 0.1}, {1e-3, 0.5}, {1e-3, 2.0}}, 7, -0.2);
  for (const IwanUpdateSummary& wrong : {fit(alike, 1.004), fit(soft, 1, -0.6)}) {
    const std::string w = wrong.report();
    ASSERT_TRUE(wrong.evidence) << w;
    EXPECT_LT(wrong.evidence->between_hits_share, 0.05) << w;
    EXPECT_FALSE(wrong.evidence->hits_differ_in_shape()) << w;
    EXPECT_TRUE(wrong.misfit_sets_the_error()) << w;
    EXPECT_EQ(w.find("disagree with one another"), std::string::npos) << w;
    EXPECT_NE(w.find("WARNING: no sigma is stated: the model does not describe the data"),
              std::string::npos)
        << w;
  }
}

// Scatter between hits beside a model error the hits share: three hits whose joints scatter (F_S
// and K_T drawn 5 % and 2 % per hit) fitted by a model whose linear part is 0.4 % stiff. The
// offsets explain over half of the chi-square, and the offset rule named scatter and stated the
// cluster sigmas: over one range F_S -3.5 and K_T -3.0 of them off the nominal joint, at rising
// levels K_T -8.5 (Monte Carlo, seeds 0-199: 57 of 312 and 96 of 306 z-scores beyond 3). Each
// curve fitted alone (linearised) still keeps about 4 and 1.5-2 times the chi-square its noise
// gives (168 degrees of freedom: 1 +/- 0.11), and a common frequency curve gains F 3-15 over the
// rest's own scatter (its 1 % point is 2.4 at 11 and 67 degrees of freedom): no sigma is stated,
// and the cause says why. The thresholds (1 in 1000, 1 in 100) are the rule's; these campaigns
// sit far beyond them.
TEST(IwanCampaignShape, ScatterBesideAModelErrorStatesNoSigma) {
  const std::vector<std::vector<Hit>> campaigns = {
      {{1e-3, 2.0, 1.024, 0.974}, {1e-3, 2.0, 0.948, 0.990}, {1e-3, 2.0, 1.012, 1.022}},
      {{1e-3, 0.1, 1.086, 0.987}, {1e-3, 0.5, 1.096, 0.968}, {1e-3, 2.0, 1.011, 0.980}}};
  const unsigned seeds[] = {7, 2407};
  for (size_t c = 0; c < campaigns.size(); ++c) {
    const IwanUpdateSummary s = fit(campaign(campaigns[c], seeds[c]), 1.004);
    const std::string r = s.report();
    SCOPED_TRACE(r);
    ASSERT_EQ(s.status, IwanUpdateStatus::kConverged);
    ASSERT_TRUE(s.evidence);
    const MisfitEvidence& e = *s.evidence;
    EXPECT_GE(e.between_curves_share, 0.5);  // the offset rule's case
    EXPECT_GT(e.each_hit_chi2, 1.4 * e.each_hit_dof);
    EXPECT_GT(e.shared_frequency_f, 3.0);
    EXPECT_TRUE(e.model_misses_each_hit());
    EXPECT_FALSE(s.scatter_explains_misfit());
    EXPECT_TRUE(s.misfit_sets_the_error());
    for (int k = 0; k < 4; ++k) EXPECT_EQ(s.relative_std(k), 0.0) << k;
    EXPECT_NE(r.find("That is scatter between the hits, but not all of the misfit: each curve "
                     "fitted alone"),
              std::string::npos);
    EXPECT_EQ(r.find("the sigmas allow for it"), std::string::npos);
    EXPECT_NE(r.find("WARNING: no sigma is stated: the model does not describe the data"),
              std::string::npos);
  }
}

// A held parameter stays held in each curve's own fit. Three hits scattered in F_S and K_T (+2.4,
// -5.2, +1.2 % and -2.6, -1.0, +2.2 %) over one range, beta held at 0.35 (--beta) where the
// joint's is 0.5: a model error every hit shares. Each curve fitted alone with all four
// parameters freed (cb89e3c) took the held beta's error up in its own beta: a chi-square of 205
// over 168 and a common frequency curve's F of 1.61, so the offsets were named scatter between
// hits and the cluster sigmas stated as if beta were right (F_S +/- 5.6 %, K_T 3.1 %, chi 3.2 %).
// With beta held there too each curve keeps 718 over 171 (its 1 in 1000 point is about 230) and
// the common curve F 6.6 (its 1 in 100 point about 2.4): the model misses every hit, no sigma.
// Monte Carlo (100 seeds, 5 % / 2 % scatter): beta held at 0.35, fits stating sigmas 35 -> 0 over
// one range, 65 -> 17 at rising levels; at 0.25, 18 -> 0 at rising levels. The thresholds are
// the rule's; this campaign sits 3 and 2.7 times beyond them, so no rounding of a seed decides.
TEST(IwanCampaignShape, EachCurveAloneKeepsAHeldBetaHeld) {
  const IwanTarget target = campaign(
      {{1e-3, 2.0, 1.024, 0.974}, {1e-3, 2.0, 0.948, 0.990}, {1e-3, 2.0, 1.012, 1.022}}, 0);
  const IwanUpdateSummary s = fit(target, 1, std::nullopt, 0.35);
  const std::string r = s.report();
  SCOPED_TRACE(r);
  ASSERT_EQ(s.status, IwanUpdateStatus::kConverged);
  ASSERT_TRUE(s.evidence);
  const MisfitEvidence& e = *s.evidence;
  EXPECT_TRUE(e.each_hit_held[3]);
  EXPECT_FALSE(e.each_hit_held[0] || e.each_hit_held[1] || e.each_hit_held[2]);
  EXPECT_GE(e.between_curves_share, 0.5);  // the offset rule's case
  EXPECT_GT(e.each_hit_chi2, 1.4 * e.each_hit_dof);
  EXPECT_TRUE(e.model_misses_each_hit());
  EXPECT_FALSE(s.scatter_explains_misfit());
  for (int k = 0; k < 4; ++k) EXPECT_EQ(s.relative_std(k), 0.0) << k;
  EXPECT_NE(r.find("each curve fitted alone (linearised about this result, its own F_S, K_T and "
                   "chi, beta held as in the fit)"),
            std::string::npos);
}

// A parameter the fit pinned at a bound of its range is held there too: the campaign above with
// beta free in 0.01 to 0.35 (--beta-range) ends at beta 0.35, its upper bound. Before, each
// curve's own fit freed beta, took up the error every hit shares as --beta 0.35 did before
// 05cc406 (a chi-square of 206 over 168, F 1.64: scatter named and sigmas stated; with the
// range 0.1 to 0.35, 211 over 168, F 1.81, F_S +/- 6.8 % and beta +/- 63 % at its bound); now it
// keeps beta at the bound, as the fit did: 718 over 171, F 6.57, the model misses every hit, no
// sigma. The thresholds are the rule's (1 in 1000, 1 in 100), which that clears 3 and 2.7 times
// over.
TEST(IwanCampaignShape, EachCurveAloneKeepsABetaAtItsBoundThere) {
  const IwanTarget target = campaign(
      {{1e-3, 2.0, 1.024, 0.974}, {1e-3, 2.0, 0.948, 0.990}, {1e-3, 2.0, 1.012, 1.022}}, 0);
  const IwanUpdateSummary s = fit(target, 1, std::nullopt, std::nullopt, 0.35);
  const std::string r = s.report();
  SCOPED_TRACE(r);
  ASSERT_EQ(s.bound_side[3], 1);
  ASSERT_FALSE(s.held[3]);  // not held by the options or the fit: at its bound
  ASSERT_TRUE(s.evidence);
  const MisfitEvidence& e = *s.evidence;
  EXPECT_TRUE(e.each_hit_held[3]);
  EXPECT_FALSE(e.each_hit_held[0] || e.each_hit_held[1] || e.each_hit_held[2]);
  EXPECT_TRUE(e.model_misses_each_hit());
  EXPECT_FALSE(s.scatter_explains_misfit());
  for (int k = 0; k < 4; ++k) EXPECT_EQ(s.relative_std(k), 0.0) << k;
}

// A K_T held by --gamma at the joint's mean while it scatters between hits is no error the hits
// share. Three hits at rising levels (to 0.1, 0.5 and 2 phi_max), F_S -9.2, -6.7, -4.8 % and K_T
// -2.5, +1.7, +2.7 % off the nominal joint, gamma held at the nominal (--gamma 1, K_T = K_s).
// Before, each curve's own fit held K_T (05cc406) and kept each hit's K_T offset: a chi-square of
// 1757 over 172 and a common frequency curve's F of 3.8 over the rest's scatter, "the model misses
// every hit", no sigma. The curves' own K_T steps scatter about the held value (Student's t of
// their mean 0.36 over 2 degrees of freedom, chance 0.75; held where under 0.05), so K_T is freed
// there: 207 over 169 (its 1 in 1000 point is 1.36 times the degrees of freedom), F 0.88, the
// offsets are scatter, and chi's sigma (Student's t's over the hits) is stated, z -0.09 against
// the nominal joint (|z| < 1.96 asked). Beta held at 0.35 on a joint of 0.5 (the test above)
// moves every curve alike: t 18.9, chance 0.003, held. Monte Carlo (60 seeds a case, F_S and K_T
// scattered 5 % and 2 %): fits stating sigmas at rising levels 20 -> 28 (gamma at the nominal),
// 24 -> 38 (0.5 % off), 21 -> 31 (1 % off), 8 -> 17 (2 % off), 2 -> 6 (3 % off), over one range
// 26 -> 27 (nominal), 29 -> 29 (1 % off), 2 -> 4 (3 % off), every gained z within 0.32; gamma 2 %
// off without scatter and, with scatter, the linear part 0.4 % stiff state none before and after
// (0 of 60 each), --beta 0.35 and 0.25 as before (0 over one range; 7 and 0 at rising levels).
TEST(IwanCampaignShape, AGammaHeldAtTheMeanOfScatteredHitsIsScatterNotAModelError) {
  const IwanTarget target = campaign(
      {{1e-3, 0.1, 0.9076, 0.9747}, {1e-3, 0.5, 0.9331, 1.0170}, {1e-3, 2.0, 0.9525, 1.0272}}, 400);
  const FloorTruth t;
  const IwanUpdateSummary s = fit_with(target, [&](IwanUpdateOptions& o, model::IwanParameters& p) {
    p.Kt = t.iwan.Kt;
    o.fixed_gamma = 1;
  });
  const std::string r = s.report();
  SCOPED_TRACE(r);
  ASSERT_EQ(s.status, IwanUpdateStatus::kConverged);
  ASSERT_TRUE(s.held[1]);
  ASSERT_TRUE(s.evidence);
  const MisfitEvidence& e = *s.evidence;
  EXPECT_FALSE(e.each_hit_held[1]);                  // freed in each curve's own fit
  EXPECT_LT(e.each_hit_chi2, 1.3 * e.each_hit_dof);  // its 1 in 1000 point: 1.36 times
  EXPECT_FALSE(e.model_misses_each_hit());
  EXPECT_TRUE(s.scatter_explains_misfit());
  ASSERT_EQ(s.sigma_reason(2), IwanSigmaReason::kStated);
  EXPECT_LT(std::abs(z_score(s, 2)), 1.96);
}

// The structure's own damping, fitted (--linear-damping fit), is each curve's own in its fit
// alone, as the parameters the fit frees are. Three hits over one range, one joint, their own
// damping 3.96e-4, 6.12e-4 and 5.75e-4 (scattered 20 % about 5e-4). Before, held at the fit's Z
// there, each curve kept its damping offset: a chi-square of 1164 over 168 (its 1 in 1000 point
// is 1.36 times the degrees of freedom), and only the frequency's F (0.84) kept the rule from
// saying the model misses every hit; now 183 over 165. Monte Carlo (480 fits: Z scattered 0, 5,
// 10 or 20 % between three hits, F_S and K_T 0 or 5 % / 2 %, one range and rising levels): each
// curve's chi-square beyond its 1 in 1000 point in 214 fits before, 6 now; none refused by the
// rule before or now, and every stated sigma as before.
TEST(IwanCampaignShape, EachCurveAloneFitsItsOwnDampingWhereTheFitDoes) {
  const IwanTarget target = campaign(
      {{1e-3, 2.0, 1, 1, 3.96e-4}, {1e-3, 2.0, 1, 1, 6.12e-4}, {1e-3, 2.0, 1, 1, 5.75e-4}}, 0);
  const auto fit_z = [](IwanUpdateOptions& o, model::IwanParameters&) {
    o.fit_linear_damping = true;
  };
  const IwanUpdateSummary s = fit_with(target, fit_z);
  const std::string r = s.report();
  SCOPED_TRACE(r);
  ASSERT_EQ(s.status, IwanUpdateStatus::kConverged);
  ASSERT_TRUE(s.modal_ratio_fitted);
  ASSERT_TRUE(s.evidence);
  const MisfitEvidence& e = *s.evidence;
  EXPECT_TRUE(e.each_hit_own_damping);
  EXPECT_LT(e.each_hit_chi2, 1.3 * e.each_hit_dof);
  EXPECT_FALSE(e.model_misses_each_hit());
  // The same hits and a model whose linear part is 0.4 % stiff, an error every hit shares: each
  // curve alone still misses (568 over 165, F 6.5), no sigma, and the cause names what each
  // curve's own fit freed.
  const IwanUpdateSummary stiff = fit_with(target, fit_z, 1.004);
  const std::string w = stiff.report();
  ASSERT_TRUE(stiff.evidence) << w;
  EXPECT_TRUE(stiff.evidence->model_misses_each_hit()) << w;
  EXPECT_NE(w.find("each curve fitted alone (linearised about this result, its own F_S, K_T, chi, "
                   "beta and modal_ratio) still keeps a chi-square of"),
            std::string::npos)
      << w;
}

// A --beta held off the joint's, with nothing to scatter between hits: chi takes up its error.
// Three hits over one range (to 2 phi_max, past it), one joint (beta 0.5), beta held at 0.45.
// Before, no rule saw it (reduced chi-square 1.47, "a lower bound"): chi -0.4947 +/- 0.24 %,
// z 4.5 against the joint's -0.5; 3-6 sigma off in 39 of 39 such fits (40 seeds). Freed from the
// result, beta lowers the chi-square far beyond the 1 in 1000 point of one parameter (10.8 times
// the freed fit's reduced chi-square, 11.9 here): by 65.4, to beta 0.505; the sigmas given that
// beta are refused and the report says why. Held at the joint's 0.5 the drop is 0.50 and the sigmas
// stay (over 120 such fits without scatter: drops of 0.0-10.8, none refused; with F_S and K_T
// scattered 5 % / 2 %, 1 of 75).
TEST(IwanCampaignShape, AHeldBetaTheDataRejectStatesNoSigma) {
  const IwanTarget target = campaign({{1e-3, 2.0}, {1e-3, 2.0}, {1e-3, 2.0}}, 0);
  const IwanUpdateSummary off = fit(target, 1, std::nullopt, 0.45);
  SCOPED_TRACE(off.report());
  ASSERT_EQ(off.status, IwanUpdateStatus::kConverged);
  EXPECT_TRUE(off.held_beta_rejected());
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(off.sigma_reason(k), IwanSigmaReason::kHeldBetaRejected) << k;
    EXPECT_EQ(off.relative_std(k), 0.0) << k;
  }
  EXPECT_NE(off.report().find("reject beta = 0.45 as held (--beta)"), std::string::npos);
  const IwanUpdateSummary right = fit(target, 1, std::nullopt, 0.5);
  EXPECT_FALSE(right.held_beta_rejected());
  EXPECT_EQ(right.sigma_reason(2), IwanSigmaReason::kStated);
  EXPECT_LT(std::abs(z_score(right, 2)), 3.0);
}

}  // namespace
}  // namespace jointlab::correlate
