#include "jointlab/correlate/mac.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace jointlab::correlate
