// The Iwan update's misfit evidence and the causes it names: scatter between hits, a curve
// apart, white residuals, no slip, the linear part's effect, the structure's own damping
// against another mode's slip, and the low end's damping rise.
#include "jointlab/correlate/iwan_update.h"

#include <cmath>
#include <cstdio>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/correlate/iwan_update_test_fixtures.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/qsma_at.h"
#include "jointlab/correlate/two_chain.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/qsma.h"

namespace jointlab::correlate {
namespace {

using iwan_test::box_around;
using iwan_test::FloorTruth;
using iwan_test::modal_backbone;
using iwan_test::Synthetic;

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
  EXPECT_NE(r.find("the sigmas allow for it (one cluster per hit, Student's t with 3 degrees "
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
// above the fitted curve, the others within -3.5 to +2.3 %, and one cluster per hit read that
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
  EXPECT_EQ(r.find("the sigmas allow for it (one cluster per hit"), std::string::npos);
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

// The curves' own shapes compare curves at the same amplitude: the same modal amplitude reads
// larger at a sensor that moves more, so curves of two sensors would put one model error at
// two places in ln amplitude, where it could read as their own shapes. Two-chain truth, one
// hit read at a5 and at a3 (velocity, 30 points each, 5e-4 / 3 % noise), each sensor's curve
// twice (another noise seed), evaluated at chi -0.3 (the truth's -0.5: a model error every hit
// shares). Each sensor's pair is compared alone: 2 degrees of freedom per pair and quantity
// (8), not the 12 of the four curves together, and the common curve is each pair's (44). Here
// the common curve's chi-square (3.4e4) rules scatter out either way (the shapes' share 0.0003
// by pairs, 0.0005 together); the grouping guards the case where it would not.
TEST(IwanUpdate, CurvesOfTwoSensorsAreComparedEachWithItsOwn) {
  Synthetic syn;
  const std::vector<Sensor> sensors{{"a5", 5, -1.0}, {"a3", 3, -1.0}};
  const model::Model m = two_chain_structure(syn.truth);
  IwanTarget target;
  target.mode = 1;
  for (const int sensor : {0, 1, 0, 1})
    target.curves.push_back(synthetic_backbone(m, 1, sensors, sensor, AmplitudeQuantity::kVelocity,
                                               30, 2.0, 5e-4, 0.03,
                                               static_cast<unsigned>(7 + target.curves.size())));
  IwanUpdateOptions o;
  o.bounds = box_around(syn.truth);
  o.amplitude = AmplitudeQuantity::kVelocity;
  const IwanObjective obj(m, "rivet", sensors, {target}, o);
  model::IwanParameters wrong = obj.initial();
  wrong.chi = -0.3;
  const std::optional<MisfitEvidence> e = obj.misfit_evidence(wrong, 0);
  ASSERT_TRUE(e);
  RecordProperty("between_hits_share", std::to_string(e->between_hits_share));
  EXPECT_EQ(e->between_hits_dof, 8);
  EXPECT_EQ(e->common_dof, 44);
  EXPECT_LT(e->between_hits_share, 0.05);
  EXPECT_FALSE(e->hits_differ_in_shape());
}

}  // namespace
}  // namespace jointlab::correlate
