#include "jointlab/correlate/mode_interference.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace jointlab::correlate {
namespace {

Curve decaying(double a0, double sigma, double f_hz, double t0, double t1, int n) {
  Curve c;
  c.time_s = Eigen::VectorXd::LinSpaced(n, t0, t1);
  c.amplitude = (a0 * (-sigma * c.time_s.array()).exp()).matrix();
  c.frequency_hz = Eigen::VectorXd::Constant(n, f_hz);
  c.damping = Eigen::VectorXd::Constant(n, sigma / (2 * std::numbers::pi * f_hz));
  return c;
}

TEST(ModeInterference, ShareIsTheOtherModesSlipProjectedOnThisOnes) {
  // Two joints. Mode 1 slips them 1 and 2 per unit q, mode 2 slips 3 and 0.5;
  // sensor scales 2 and 5. share_1 = (u1 . u2) q2 / (|u1|^2 q1), exactly, where
  // both are measured; beyond mode 2's span its amplitude continues with its decay
  // rate (closed form here, since the curves are exact exponentials).
  std::vector<ModeSlip> modes(2);
  modes[0].unit_slip = Eigen::Vector2d(1.0, 2.0);
  modes[0].sensor_scale = 2.0;
  modes[1].unit_slip = Eigen::Vector2d(3.0, 0.5);
  modes[1].sensor_scale = 5.0;
  const Curve c1 = decaying(0.1, 0.5, 120, 0.1, 2.0, 40);
  const Curve c2 = decaying(0.3, 6.0, 500, 0.2, 0.6, 20);
  const std::vector<const Curve*> both{&c1, &c2};
  const Eigen::VectorXd share = slip_share(modes, both, 0);
  ASSERT_EQ(share.size(), c1.time_s.size());
  for (Eigen::Index i = 0; i < share.size(); ++i) {
    const double t = c1.time_s(i);
    const double q1 = 0.1 * std::exp(-0.5 * t) / 2.0, q2 = 0.3 * std::exp(-6.0 * t) / 5.0;
    const double expected = (1.0 * 3.0 + 2.0 * 0.5) * q2 / (5.0 * q1);
    EXPECT_NEAR(share(i), expected, 1e-9 * expected + 1e-15) << "t " << t;
  }
  // A mode not measured in the hit adds nothing.
  const std::vector<const Curve*> alone{&c1, nullptr};
  EXPECT_EQ(slip_share(modes, alone, 0).cwiseAbs().maxCoeff(), 0.0);
}

TEST(ModeInterference, ModeSlipReadsTheIwanJointsOfTheShape) {
  // Three DOFs, one Iwan joint between 0 and 2 and one to ground at 1, a linear
  // spring between 0 and 1 (ignored). Unit slips are |phi_0 - phi_2| and |phi_1|;
  // the sensor scale at DOF 1 for velocity is |phi_1| omega.
  model::Model m;
  model::Joint iwan_pair, iwan_ground, spring;
  iwan_pair.a = 0;
  iwan_pair.b = 2;
  iwan_pair.iwan = model::Iwan(model::IwanParameters{10.0, 1e6, -0.5, 1.0});
  iwan_ground.a = 1;
  iwan_ground.iwan = model::Iwan(model::IwanParameters{10.0, 1e6, -0.5, 1.0});
  spring.a = 0;
  spring.b = 1;
  m.joints = {iwan_pair, iwan_ground, spring};
  model::LinearModes lm;
  lm.rigid_count = 1;
  lm.omega2 = Eigen::Vector2d(0.0, 400.0);
  lm.shapes.resize(3, 2);
  lm.shapes << 0.5, 0.3, 0.5, -0.7, 0.5, 0.1;
  const ModeSlip s = mode_slip(m, lm, 1, 1, 1);
  ASSERT_EQ(s.unit_slip.size(), 2);
  EXPECT_DOUBLE_EQ(s.unit_slip(0), 0.2);
  EXPECT_DOUBLE_EQ(s.unit_slip(1), 0.7);
  EXPECT_DOUBLE_EQ(s.sensor_scale, 0.7 * 20.0);
}

}  // namespace
}  // namespace jointlab::correlate
