#include "jointlab/model/fe/beam_element.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "jointlab/model/fe/fe_model.h"
#include "jointlab/model/fe/strip_mesh.h"
#include "jointlab/model/sparse_eigen.h"
#include "jointlab/tests/free_modes.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model::fe {
namespace {

using jointlab::testing::Close;
using jointlab::testing::rel_err;

constexpr double kPi = 3.14159265358979323846;
// Free-free Euler–Bernoulli beam: β_n L for the first five elastic bending modes.
constexpr double kBetaL[5] = {4.7300408, 7.8532046, 10.9956078, 14.1371655, 17.2787596};

BeamSection aluminium_strip() {
  return rectangular_section(70e9, 0.33, 2700, 0.02, 0.002);  // 20 mm × 2 mm
}

TEST(BeamElement, SymmetricWithExactlySixRigidBodyModes) {
  const ElementMatrices e =
      beam_element({0.1, -0.2, 0.3}, {0.4, 0.2, 0.1}, {0, 0, 1}, aluminium_strip());
  EXPECT_LT((e.stiffness - e.stiffness.transpose()).norm(), 1e-12 * e.stiffness.norm());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> k(e.stiffness);
  const double kmax = k.eigenvalues().maxCoeff();
  // Six zero eigenvalues (rigid motion in 3D), to round-off of the largest (1e-10 relative:
  // double precision times the ~1e6 spread of axial vs. bending terms); the seventh is a
  // genuine deformation mode, far above that.
  for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(k.eigenvalues()(i)), 1e-10 * kmax) << i;
  EXPECT_GT(k.eigenvalues()(6), 1e-8 * kmax);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> m(e.mass);
  EXPECT_GT(m.eigenvalues().minCoeff(), 0.0);
  // Total mass: a unit rigid translation carries ρAL.
  Eigen::VectorXd ux = Eigen::VectorXd::Zero(12);
  ux(0) = ux(6) = 1;
  const BeamSection s = aluminium_strip();
  const double length = (Eigen::Vector3d(0.4, 0.2, 0.1) - Eigen::Vector3d(0.1, -0.2, 0.3)).norm();
  EXPECT_TRUE(Close(ux.dot(e.mass * ux), s.density * s.area * length, 1e-12));
}

TEST(BeamElement, CantileverTipDeflectionIsExactTimoshenko) {
  // One element is exact for a tip load: δ = PL³/(3EI) + PL/(κGA). A stocky beam makes
  // the shear term 10 % of the total, so a wrong Φ would show.
  const BeamSection s = rectangular_section(200e9, 0.3, 7800, 0.05, 0.08);
  const double l = 0.3, p = 1000;
  const ElementMatrices e = beam_element({0, 0, 0}, {l, 0, 0}, {0, 1, 0}, s);
  const Eigen::MatrixXd kff = e.stiffness.bottomRightCorner(6, 6);  // node 1 clamped
  Eigen::VectorXd f = Eigen::VectorXd::Zero(6);
  f(2) = p;  // z load: bends about local y with I_y
  const Eigen::VectorXd u = kff.ldlt().solve(f);
  const double expected = p * l * l * l / (3 * s.youngs_modulus * s.inertia_y) +
                          p * l / (s.shear_coefficient * s.shear_modulus * s.area);
  EXPECT_TRUE(Close(u(2), expected, 1e-10));
  f.setZero();
  f(1) = p;  // y load: bends about local z with I_z
  const Eigen::VectorXd v = kff.ldlt().solve(f);
  EXPECT_TRUE(Close(v(1),
                    p * l * l * l / (3 * s.youngs_modulus * s.inertia_z) +
                        p * l / (s.shear_coefficient * s.shear_modulus * s.area),
                    1e-10));
}

// Lowest five out-of-plane (z) bending frequencies of a free-free strip of `n` beams.
std::vector<double> free_free_bending(int n, double length) {
  FeModel model;
  add_beam_line(model, uniform_stations(0, length, n), 0, 0, aluminium_strip());
  const AssembledModel a = model.assemble();
  const EigenResult r = jointlab::testing::free_modes(a.stiffness, a.mass, 24);
  const Eigen::VectorXd f = frequencies_hz(r.eigenvalues);
  std::vector<double> out;
  for (int k = 0; k < f.size() && out.size() < 5; ++k) {
    if (f(k) < 1.0) continue;  // rigid
    const Eigen::VectorXd& v = r.vectors.col(k);
    double uz = 0, all = 0;
    for (int node = 0; node < model.node_count(); ++node) {
      uz += v(6 * node + 2) * v(6 * node + 2);
      all += v.segment<3>(6 * node).squaredNorm();
    }
    if (uz > 0.99 * all && all > 1e-12 * v.squaredNorm()) out.push_back(f(k));
  }
  return out;
}

double euler_bernoulli(int mode, double length) {
  const BeamSection s = aluminium_strip();
  const double bl = kBetaL[mode];
  return bl * bl / (2 * kPi * length * length) *
         std::sqrt(s.youngs_modulus * s.inertia_y / (s.density * s.area));
}

TEST(BeamElement, FreeFreeBeamMatchesEulerBernoulliAndConverges) {
  const double length = 0.5;  // L/t = 250: shear and rotary inertia shift mode 5 by ~0.1 %
  std::vector<double> previous_error(5, INFINITY);
  for (int n : {8, 16, 32, 64}) {
    const std::vector<double> f = free_free_bending(n, length);
    ASSERT_EQ(f.size(), 5u) << n << " elements";
    for (int k = 0; k < 5; ++k) {
      const double err = rel_err(f[k], euler_bernoulli(k, length));
      // Refinement must lower the error until it reaches the Timoshenko–Euler-Bernoulli
      // model difference (~(β r)², below 2e-3 here), which no mesh removes.
      if (previous_error[k] > 3e-3) {
        EXPECT_LT(err, previous_error[k]) << "mode " << k + 1 << ", " << n << " elements";
      }
      previous_error[k] = err;
    }
  }
  // Acceptance: the fine mesh within 0.5 % of the closed form for all five modes.
  const std::vector<double> f = free_free_bending(64, length);
  for (int k = 0; k < 5; ++k) {
    EXPECT_TRUE(Close(f[k], euler_bernoulli(k, length), 5e-3)) << "mode " << k + 1;
    RecordProperty("mode" + std::to_string(k + 1) + "_rel_err",
                   std::to_string(rel_err(f[k], euler_bernoulli(k, length))));
  }
}

}  // namespace
}  // namespace jointlab::model::fe
