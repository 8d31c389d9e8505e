#include "jointlab/correlate/shape_checks.h"

#include <cmath>
#include <complex>
#include <numbers>

#include <gtest/gtest.h>

namespace jointlab::correlate {
namespace {

// A pinned-pinned string's modes sin(k pi x), k = 1..5, at sensors x = 0.1, 0.3, ..., 0.9, with
// frequencies 10 x 4^(k-1) Hz: no other mode lies within the default window (0.5) of any.
struct StringModes {
  Eigen::MatrixXd at = Eigen::MatrixXd(5, 5);
  Eigen::VectorXd f = Eigen::VectorXd(5);
  StringModes() {
    for (int k = 1; k <= 5; ++k) {
      f(k - 1) = 10.0 * std::pow(4.0, k - 1);
      for (int s = 0; s < 5; ++s) at(s, k - 1) = std::sin(k * std::numbers::pi * (0.1 + 0.2 * s));
    }
  }
};

TEST(ChannelSigns, NamesTheOneChannelMountedTheOtherWayRound) {
  const StringModes m;
  // The measured shapes are the model's with a phase of 0.3 rad and channel 0 reversed.
  Eigen::MatrixXcd measured = std::polar(2.0, 0.3) * m.at.cast<std::complex<double>>();
  measured.row(0) *= -1.0;
  const SignCheck c = check_channel_signs(measured, m.f, m.at, m.f, {}, 0.5);
  EXPECT_EQ(c.channels, std::vector<int>{0});
  EXPECT_EQ(c.counted, 5);
  EXPECT_EQ(c.matched_reversed, 5);
  EXPECT_NEAR(c.mean_mac_reversed, 1.0, 1e-12);
  // As given, mode k's MAC with its own model mode is (|y|^2 - 2 y_0^2)^2 / |y|^4 (the one
  // entry y_0 reversed): 0.853, 0.523, 0.227, 0.077, 0.36 (|y|^2 = 2.5, and 5 for k = 5); the
  // other model modes lie outside the window. None reaches 0.9.
  double mean = 0;
  for (int k = 0; k < 5; ++k) {
    const double n2 = m.at.col(k).squaredNorm(), y0 = m.at(0, k);
    mean += std::pow(n2 - 2 * y0 * y0, 2) / (n2 * n2) / 5;
  }
  EXPECT_EQ(c.matched, 0);
  EXPECT_NEAR(c.mean_mac, mean, 1e-12);
}

TEST(ChannelSigns, NamesTwoChannelsMountedTheOtherWayRound) {
  const StringModes m;
  Eigen::MatrixXcd measured = m.at.cast<std::complex<double>>();
  measured.row(1) *= -1.0;
  measured.row(3) *= -1.0;
  const SignCheck c = check_channel_signs(measured, m.f, m.at, m.f, {}, 0.5);
  EXPECT_EQ(c.channels, (std::vector<int>{1, 3}));
  EXPECT_EQ(c.matched_reversed, 5);
  EXPECT_LE(c.matched, 3);
}

TEST(ChannelSigns, RightSignsNameNoChannel) {
  const StringModes m;
  const Eigen::MatrixXcd measured = m.at.cast<std::complex<double>>();
  const SignCheck c = check_channel_signs(measured, m.f, m.at, m.f, {}, 0.5);
  EXPECT_TRUE(c.channels.empty());
  EXPECT_EQ(c.matched, 5);
}

TEST(ChannelSigns, TwoSensorsAreNotEnoughToJudge) {
  // At two sensors reversing one only swaps which of two shapes a mode looks like: no mode is
  // counted, and no channel named, whatever the signs.
  const StringModes m;
  Eigen::MatrixXcd measured = m.at.topRows(2).cast<std::complex<double>>();
  measured.row(0) *= -1.0;
  const SignCheck c = check_channel_signs(measured, m.f, m.at.topRows(2), m.f, {}, 0.5);
  EXPECT_EQ(c.counted, 0);
  EXPECT_TRUE(c.channels.empty());
}

TEST(PhaselessShapes, MagnitudesAreNamed) {
  const StringModes m;
  const std::vector<std::string> ids = {"3", "4", "5", "6", "7"};
  // Magnitudes, with a common phase (a complex scale keeps every entry in phase).
  const Eigen::MatrixXcd magnitudes =
      std::polar(1.0, 0.3) * m.at.cwiseAbs().cast<std::complex<double>>();
  const std::string why = phaseless_shapes(magnitudes, m.f, m.at, m.f, ids, 0.5);
  EXPECT_NE(why.find("the shapes of measured modes 4, 5, 6, 7 have one phase"), std::string::npos)
      << why;
  // Mode 1 of the string keeps one sign at every sensor; modes 2-5 change it.
  EXPECT_NE(why.find("model modes 2 (40 Hz), 3 (160 Hz), 4 (640 Hz), 5 (2560 Hz)"),
            std::string::npos)
      << why;
  const Eigen::MatrixXcd signed_shapes = std::polar(1.0, 0.3) * m.at.cast<std::complex<double>>();
  EXPECT_EQ(phaseless_shapes(signed_shapes, m.f, m.at, m.f, ids, 0.5), "");
}

TEST(PhaselessShapes, ModesThatKeepOneSignAreNotMagnitudes) {
  // Two modes that keep one sign at every sensor, as their model modes do (a first bending
  // mode seen between its nodes): nothing to say.
  Eigen::MatrixXd at(3, 2);
  at << 1.0, 0.2, 0.8, 0.5, 0.6, 1.0;
  const Eigen::Vector2d f(10, 40);
  EXPECT_EQ(phaseless_shapes(at.cast<std::complex<double>>(), f, at, f, {"1", "2"}, 0.5), "");
}

}  // namespace
}  // namespace jointlab::correlate
