#include "jointlab/correlate/mac.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>

#include "jointlab/tests/test_util.h"

namespace jointlab::correlate {
namespace {

TEST(Mac, InvariantToScaleAndPhaseAndBounded) {
  const Eigen::VectorXd y = (Eigen::VectorXd(4) << 1.0, -2.0, 0.5, 3.0).finished();
  const std::complex<double> c(0.3, -1.7);  // any complex scale of a real shape
  const Eigen::VectorXcd x = c * y.cast<std::complex<double>>();
  EXPECT_TRUE(testing::Close(mac(x, y), 1.0, 1e-14));
  EXPECT_TRUE(testing::Close(mac(Eigen::VectorXd(-5.0 * y), y), 1.0, 1e-14));
  const Eigen::VectorXd z = (Eigen::VectorXd(4) << 2.0, 1.0, 0.0, 0.0).finished();  // y.z = 0
  EXPECT_NEAR(mac(z, y), 0.0, 1e-15);
  // Independent truth: cos^2 of the angle between two vectors.
  const Eigen::VectorXd w = (Eigen::VectorXd(4) << 1.0, 1.0, 1.0, 1.0).finished();
  const double cos2 = std::pow(w.dot(y) / (w.norm() * y.norm()), 2);
  EXPECT_TRUE(testing::Close(mac(w, y), cos2, 1e-14));
  EXPECT_EQ(mac(Eigen::VectorXd::Zero(4), y), 0.0);
}

// A real shape times e^{i phi} (a real normal mode's residue at any phase) comes back as that
// shape up to sign, MPC 1, nothing left out: rounding alone, so 1e-14 relative.
TEST(Mac, ARealShapeAtAnyPhaseIsRealisedAsItselfWithMpcOne) {
  const Eigen::VectorXd y = (Eigen::VectorXd(5) << 0.3, -1.0, 0.02, 0.7, -0.45).finished();
  for (const double phi : {0.0, 0.4, 1.5707963267948966, 2.0, -2.9, 3.14159}) {
    const Eigen::VectorXcd x = std::polar(2.5, phi) * y.cast<std::complex<double>>();
    const RealisedShape r = realise(x);
    // The largest entry (-1.0) is made positive: -2.5 y.
    EXPECT_LT((r.shape + 2.5 * y).norm(), 1e-14 * y.norm()) << "phi " << phi;
    EXPECT_TRUE(testing::Close(r.mpc, 1.0, 1e-14)) << "phi " << phi;
    EXPECT_LT(r.imaginary_share, 1e-28) << "phi " << phi;
  }
}

// Known complex shapes, closed forms: x = (1, e^{i alpha}) has x^T x = 2 cos(alpha) e^{i alpha},
// so MPC = cos^2 alpha, the realised shape cos(alpha/2) (1, 1) and the part left out sin^2(alpha/2)
// of the whole; x = a + i b with a.b = 0 has l1 = |a|^2, l2 = |b|^2 and realises as a. Rounding
// alone: 1e-13.
TEST(Mac, AKnownComplexShapeHasItsClosedFormMpc) {
  for (const double alpha : {0.1, 0.5, 1.0, 1.3}) {
    const Eigen::Vector2cd x(1.0, std::polar(1.0, alpha));
    const RealisedShape r = realise(x);
    EXPECT_NEAR(r.mpc, std::pow(std::cos(alpha), 2), 1e-13) << alpha;
    EXPECT_NEAR(r.shape(0), std::cos(alpha / 2), 1e-13) << alpha;
    EXPECT_NEAR(r.shape(1), std::cos(alpha / 2), 1e-13) << alpha;
    EXPECT_NEAR(r.imaginary_share, std::pow(std::sin(alpha / 2), 2), 1e-13) << alpha;
  }
  const Eigen::Vector4d a(1.0, 2.0, -1.0, 0.5), b(0.5, 0.0, 0.5, 0.0);  // a.b = 0
  ASSERT_EQ(a.dot(b), 0.0);
  const Eigen::Vector4cd x =
      std::polar(1.0, 0.7) * (a.cast<std::complex<double>>() + std::complex<double>(0, 1) * b);
  const RealisedShape r = realise(x);
  const double l1 = a.squaredNorm(), l2 = b.squaredNorm();
  EXPECT_NEAR(r.mpc, std::pow((l1 - l2) / (l1 + l2), 2), 1e-13);  // 0.7347
  EXPECT_LT((r.shape - a).norm(), 1e-13);
  EXPECT_NEAR(r.imaginary_share, l2 / (l1 + l2), 1e-13);
  // Points spread evenly round the origin: MPC 0, and the entry left at quadrature stays an
  // entry (non-zero), never "not measured".
  const RealisedShape round = realise(Eigen::Vector2cd(1.0, std::complex<double>(0, 1)));
  EXPECT_EQ(round.mpc, 0.0);
  EXPECT_NE(round.shape(1), 0.0);
  EXPECT_EQ(realise(Eigen::Vector2cd::Zero()).mpc, 1.0);
}

TEST(Mac, PairingIsOneToOneWithThresholdAndReportsUnpaired) {
  // Measured 0 looks like model 2, measured 1 like model 0, measured 2 like nothing.
  Eigen::MatrixXd m(3, 4);
  m << 0.10, 0.05, 0.97, 0.20,  //
      0.91, 0.30, 0.40, 0.02,   //
      0.20, 0.35, 0.30, 0.10;
  const Pairing p = pair_modes(m, 0.6);
  ASSERT_EQ(p.pairs.size(), 2u);
  EXPECT_EQ(p.model_for(0), 2);
  EXPECT_EQ(p.model_for(1), 0);
  EXPECT_EQ(p.model_for(2), -1);
  EXPECT_EQ(p.unpaired_measured, std::vector<int>{2});
  EXPECT_EQ(p.unpaired_model, (std::vector<int>{1, 3}));
}

TEST(Mac, PairingGivesEachModelModeOnce) {
  // Both measured modes resemble model 0 most; the better one gets it, the other its runner-up.
  Eigen::MatrixXd m(2, 2);
  m << 0.95, 0.70,  //
      0.90, 0.20;
  const Pairing p = pair_modes(m, 0.1);
  EXPECT_EQ(p.model_for(0), 0);
  EXPECT_EQ(p.model_for(1), 1);
}

// pair_by_rules on hand-made MAC matrices: what each rule does, one at a time.
struct RulesCase {
  Eigen::MatrixXd mac;
  Eigen::VectorXd f_test, f_model, norm2;
  std::vector<bool> shape;
  RulePairing run(const PairingRules& r = {}) const {
    return pair_by_rules(mac, f_test, shape, f_model, norm2, r);
  }
};

TEST(PairByRules, AModeInvisibleAtTheSensorsIsNeverPairedByMac) {
  // Model mode 0 has no motion at the sensors (rounding-level norm, so its MAC is noise: here
  // 1.0); model mode 1 is the visible one with MAC 0.9.
  RulesCase c{Eigen::MatrixXd(1, 2),
              Eigen::VectorXd::Constant(1, 100.0),
              (Eigen::VectorXd(2) << 100.0, 105.0).finished(),
              (Eigen::VectorXd(2) << 1e-30, 1.0).finished(),
              {true}};
  c.mac << 1.0, 0.9;
  const RulePairing p = c.run();
  EXPECT_EQ(p.pairing.model_for(0), 1);
  EXPECT_EQ(p.hidden, std::vector<int>{0});
  EXPECT_TRUE(p.ambiguity.empty());
}

TEST(PairByRules, EveryGuessedPairIsRecordedNotTheFirstAlone) {
  // Two test modes without a shape (100 and 200 Hz), each between two model modes as close in
  // frequency (99/101 and 198/202 Hz): both pairs are guesses, and both are recorded with their
  // candidates, so that a caller can try each combination (before, only the first was).
  RulesCase c{Eigen::MatrixXd::Ones(2, 4),
              (Eigen::VectorXd(2) << 100.0, 200.0).finished(),
              (Eigen::VectorXd(4) << 99.0, 101.0, 198.0, 202.0).finished(),
              Eigen::VectorXd::Ones(4),
              {false, false}};
  const RulePairing p = c.run();
  ASSERT_EQ(p.ties.size(), 2u) << p.ambiguity;
  std::vector<int> measured{p.ties[0].measured, p.ties[1].measured};
  std::sort(measured.begin(), measured.end());
  EXPECT_EQ(measured, (std::vector<int>{0, 1}));
  for (const PairingTie& t : p.ties) {
    std::vector<int> cand = t.candidates;
    std::sort(cand.begin(), cand.end());
    EXPECT_EQ(cand, t.measured == 0 ? (std::vector<int>{0, 1}) : (std::vector<int>{2, 3}));
    EXPECT_EQ(p.pairing.model_for(t.measured), t.candidates.front());
  }
  EXPECT_NE(p.ambiguity.find("test mode 1"), std::string::npos) << p.ambiguity;
  EXPECT_NE(p.ambiguity.find("test mode 2"), std::string::npos) << p.ambiguity;
  // Named by the table's own numbers where it has them (modes 3 and 5 of a campaign whose
  // modes 1, 2 and 4 were not measured), not by their rows.
  const RulePairing named =
      pair_by_rules(c.mac, c.f_test, c.shape, c.f_model, c.norm2, PairingRules{}, {"3", "5"});
  EXPECT_NE(named.ambiguity.find("test mode 3 (100 Hz"), std::string::npos) << named.ambiguity;
  EXPECT_NE(named.ambiguity.find("test mode 5 (200 Hz"), std::string::npos) << named.ambiguity;
  EXPECT_EQ(named.ambiguity.find("test mode 1"), std::string::npos) << named.ambiguity;
}

TEST(PairByRules, ModesAlikeAtTheSensorsAreToldApartByFrequency) {
  // Two model modes with MAC 0.99 and 0.97 (within tie_mac): the one at 101 Hz, not the one at
  // 160 Hz, pairs with the 100 Hz test mode, although its MAC is the lower.
  RulesCase c{Eigen::MatrixXd(1, 2),
              Eigen::VectorXd::Constant(1, 100.0),
              (Eigen::VectorXd(2) << 130.0, 101.0).finished(),
              Eigen::VectorXd::Ones(2),
              {true}};
  c.mac << 0.99, 0.97;
  RulePairing p = c.run();
  EXPECT_EQ(p.pairing.model_for(0), 1);
  EXPECT_TRUE(p.ambiguity.empty());
  // As close in frequency (99 and 101 Hz): the pairing says it cannot decide, and between which.
  c.f_model << 99.0, 101.0;
  p = c.run();
  EXPECT_NE(p.ambiguity.find("test mode 1"), std::string::npos) << p.ambiguity;
  ASSERT_EQ(p.ties.size(), 1u);
  EXPECT_EQ(p.ties[0].measured, 0);
  EXPECT_EQ(p.ties[0].candidates.size(), 2u);
  // The frequency window removes a far mode before MAC is looked at: 300 Hz is outside +-50 %.
  c.f_model << 300.0, 101.0;
  c.mac << 1.0, 0.7;
  EXPECT_EQ(c.run().pairing.model_for(0), 1);
  PairingRules no_window;
  no_window.frequency_window = 0;
  EXPECT_EQ(c.run(no_window).pairing.model_for(0), 0);
}

TEST(PairByRules, AModeWithoutAShapePairsByFrequencyWithinTheWindow) {
  RulesCase c{Eigen::MatrixXd::Zero(2, 3),
              (Eigen::VectorXd(2) << 100.0, 400.0).finished(),
              (Eigen::VectorXd(3) << 90.0, 120.0, 1000.0).finished(),
              Eigen::VectorXd::Ones(3),
              {false, false}};
  const RulePairing p = c.run();
  EXPECT_EQ(p.pairing.model_for(0), 0);
  EXPECT_EQ(p.pairing.model_for(1), -1);  // 1000 Hz is 150 % away: unpaired, not forced
  EXPECT_EQ(p.pairing.unpaired_measured, std::vector<int>{1});
}

TEST(PairByRules, ModesWithAShapePairBeforeThoseWithout) {
  // The two-chain structure at three sensors (two on chain A, one on chain B), started with ka
  // four times and kb a third of the truth: test mode 1 (57.9 Hz, chain A) has MAC 0.99 with
  // model mode 2 (66.2 Hz, chain A's first mode there); test mode 2 (59.9 Hz, chain B) is seen at
  // one sensor only and pairs by frequency. Paired first (as if its missing MAC were 1), it took
  // model mode 2, the nearest in frequency, and test mode 1 was left unpaired: the fit then moved
  // ka to 6.8e5 (truth 5e5). A shape's MAC is the stronger evidence: it pairs first, and the mode
  // without one takes the nearest of the model modes left, model mode 1 (41.2 Hz, chain B).
  RulesCase c{Eigen::MatrixXd::Zero(2, 3),
              (Eigen::VectorXd(2) << 57.9, 59.9).finished(),
              (Eigen::VectorXd(3) << 41.2, 66.2, 205.5).finished(),
              Eigen::VectorXd::Ones(3),
              {true, false}};
  c.mac << 0.0, 0.99, 0.52;
  const RulePairing p = c.run();
  EXPECT_EQ(p.pairing.model_for(0), 1);
  EXPECT_EQ(p.pairing.model_for(1), 0);
  EXPECT_TRUE(p.pairing.unpaired_measured.empty());
}

}  // namespace
}  // namespace jointlab::correlate
