#include "jointlab/correlate/mode_tracking.h"

#include <cmath>

#include <gtest/gtest.h>

#include "jointlab/correlate/two_chain.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::correlate {
namespace {

// The fraction of a mass-normalised shape's kinetic energy on chain A (indices 0..n-1).
double on_chain_a(const Eigen::VectorXd& phi, const Eigen::SparseMatrix<double>& mass, int n) {
  const Eigen::VectorXd mp = mass * phi;
  return phi.head(n).dot(mp.head(n)) / phi.dot(mp);
}

// The two chains are uncoupled, so raising ka moves chain A's first mode (57.9 Hz) through
// chain B's (59.9 Hz, unchanged): a true crossing. Followed by shape, the mode must stay on
// chain A (energy fraction 1 to rounding) and end one place higher in frequency order, at the
// frequency of the model at the end (exact: the same eigen-solve).
TEST(ModeTracking, FollowsAModeThroughACrossing) {
  TwoChainParameters a;
  model::Model m = two_chain_structure(a);
  const auto stiffness = [&](double s) {
    model::Model at = m;
    for (model::Joint& j : at.joints)
      if (j.element == "spring.ka") j.stiffness = 5e5 * std::pow(10.0, s);  // 5e5 -> 5e6
    return at.linear_stiffness();
  };
  const ElasticModes start = elastic_modes(m.mass, stiffness(0));
  ASSERT_GT(on_chain_a(start.shapes.col(0), m.mass, a.n), 0.999);  // mode 1 is chain A's
  ASSERT_LT(on_chain_a(start.shapes.col(1), m.mass, a.n), 1e-3);   // mode 2 is chain B's
  const auto f = follow_path(stiffness, m.mass, start, {0, 1}, TrackingOptions{});
  ASSERT_TRUE(f.has_value());
  const ElasticModes end = elastic_modes(m.mass, stiffness(1));
  EXPECT_GT(end.frequency_hz(1), start.frequency_hz(1) * (1 - 1e-12));
  EXPECT_EQ(f->columns[1], 0);  // chain B's mode is now the lowest
  ASSERT_GE(f->columns[0], 1);
  EXPECT_GT(on_chain_a(f->modes.shapes.col(f->columns[0]), m.mass, a.n), 0.999);
  EXPECT_TRUE(
      testing::Close(f->modes.frequency_hz(f->columns[0]), end.frequency_hz(f->columns[0]), 1e-12));
  // Pairing by frequency order would have kept index 0: chain B's mode.
  EXPECT_LT(on_chain_a(end.shapes.col(0), m.mass, a.n), 1e-3);
}

// A shape that splits equally between two new shapes (MAC_M 0.5 each) cannot be followed; a
// tracked entry of -1 stays -1.
TEST(ModeTracking, RefusesAContinuationItCannotTell) {
  Eigen::SparseMatrix<double> mass(2, 2);
  mass.setIdentity();
  Eigen::MatrixXd before = Eigen::MatrixXd::Identity(2, 2);
  Eigen::MatrixXd after(2, 2);
  after << 1, 1, 1, -1;
  after /= std::sqrt(2.0);
  std::vector<double> mac;
  const std::vector<int> cols = follow_modes(before, after, mass, {0, -1}, {}, &mac);
  EXPECT_EQ(cols[0], -1);
  EXPECT_EQ(cols[1], -1);
  EXPECT_NEAR(mac[0], 0.5, 1e-15);
  // Turned by a small angle, the continuation is clear: MAC_M cos^2(0.1) = 0.990.
  after << std::cos(0.1), -std::sin(0.1), std::sin(0.1), std::cos(0.1);
  const std::vector<int> ok = follow_modes(before, after, mass, {1, 0}, {}, &mac);
  EXPECT_EQ(ok[0], 1);
  EXPECT_EQ(ok[1], 0);
  EXPECT_NEAR(mac[0], std::pow(std::cos(0.1), 2), 1e-15);
}

// Two unit masses, each grounded (ka, kb = 2) and coupled by 0.01: with ka 1 < kb 2 mode 1 moves
// mass 1, with ka 3 mode 1 moves mass 2. A pairing of a measured mode with mode 1 at ka 1 and
// one with mode 2 at ka 3 pair it with the same mode (mass 1's, MAC_M above 0.99), mode 1 at
// both with two different ones (MAC_M below 1e-3): the update compared mode numbers, so it took
// the first for two pairings ("cannot be decided", the example beam's sixth bending mode as model
// modes 9 and 10) and the second for one.
TEST(ModeTracking, SamePartnersComparesShapesNotModeNumbers) {
  Eigen::SparseMatrix<double> mass(2, 2);
  mass.insert(0, 0) = 1.0;
  mass.insert(1, 1) = 1.0;
  const auto modes = [&](double ka, double coupling = 0.01) {
    Eigen::SparseMatrix<double> k(2, 2);
    k.insert(0, 0) = ka + coupling;
    k.insert(1, 1) = 2 + coupling;
    k.insert(0, 1) = -coupling;
    k.insert(1, 0) = -coupling;
    return elastic_modes(mass, k);
  };
  const ElasticModes a = modes(1.0), b = modes(3.0);
  ASSERT_GT(std::abs(a.shapes(0, 0)), 0.99);  // mode 1 moves mass 1 at ka 1
  ASSERT_GT(std::abs(b.shapes(1, 0)), 0.99);  // and mass 2 at ka 3
  EXPECT_TRUE(same_partners(mass, a, {0}, b, {1}));
  EXPECT_FALSE(same_partners(mass, a, {0}, b, {0}));
  EXPECT_TRUE(same_partners(mass, a, {0, -1}, b, {1, -1}));
  EXPECT_FALSE(same_partners(mass, a, {0, -1}, b, {1, 0}));
  // Coupled by 1e-4, ka 2 -/+ 5e-4: the two modes 1.4e-4 apart in frequency and mode 1 moving
  // mass 1 at the first point, mass 2 at the second (MAC_M 0.14 between them): one eigenspace
  // to the data, the same partner within a cluster of 1e-3, not within 1e-5.
  const ElasticModes c = modes(2.0 - 5e-4, 1e-4), d = modes(2.0 + 5e-4, 1e-4);
  ASSERT_LT(d.frequency_hz(1) / d.frequency_hz(0) - 1, 1e-3);
  EXPECT_TRUE(same_partners(mass, c, {0}, d, {0}));
  EXPECT_FALSE(same_partners(mass, c, {0}, d, {0}, 0.5, 1e-5));
}

}  // namespace
}  // namespace jointlab::correlate
