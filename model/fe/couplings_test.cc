#include "jointlab/model/fe/couplings.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "jointlab/core/error.h"
#include "jointlab/model/fe/fe_model.h"
#include "jointlab/model/fe/strip_mesh.h"
#include "jointlab/model/sparse_eigen.h"
#include "jointlab/tests/free_modes.h"

namespace jointlab::model::fe {
namespace {

using Vector6 = Eigen::Matrix<double, 6, 1>;

std::vector<Eigen::Vector3d> disc_patch() {
  // Seven nodes of a plane patch (a hexagon and its centre), then tilted out of the xy plane.
  std::vector<Eigen::Vector3d> p = {{0, 0, 0}};
  for (int k = 0; k < 6; ++k) p.emplace_back(std::cos(k * 1.047), std::sin(k * 1.047) * 0.8, 0);
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  for (auto& x : p) x = r * x * 0.004 + Eigen::Vector3d(0.1, 0.02, -0.01);
  return p;
}

TEST(DistributingCoupling, PassesRigidBodyMotionExactly) {
  const std::vector<Eigen::Vector3d> patch = disc_patch();
  const Eigen::Vector3d ref = patch[0] + Eigen::Vector3d(0.001, -0.002, 0.0015);  // offset
  const Eigen::MatrixXd g = distributing_coupling_matrix(ref, patch);
  ASSERT_EQ(g.rows(), 6);
  ASSERT_EQ(g.cols(), 3 * static_cast<int>(patch.size()));
  const Eigen::Vector3d a(1e-3, -2e-3, 5e-4), w(0.3, -0.1, 0.7);
  Eigen::VectorXd u(g.cols());
  for (std::size_t i = 0; i < patch.size(); ++i) u.segment<3>(3 * i) = a + w.cross(patch[i]);
  const Vector6 ur = g * u;
  // The reference node moves with the same rigid motion: exact up to round-off (1e-13
  // relative to the largest displacement, a few hundred ulps of a 6 × 21 product).
  EXPECT_LT((ur.head<3>() - (a + w.cross(ref))).norm(), 1e-13 * u.cwiseAbs().maxCoeff());
  EXPECT_LT((ur.tail<3>() - w).norm(), 1e-12 * w.norm());
}

TEST(DistributingCoupling, ReferenceTranslationIsThePatchAverage) {
  // With the reference at the centroid, translation = mean of the patch translations
  // for any (not only rigid) patch motion: the "distributing uniform" definition.
  const std::vector<Eigen::Vector3d> patch = disc_patch();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : patch) centroid += p / patch.size();
  const Eigen::MatrixXd g = distributing_coupling_matrix(centroid, patch);
  const Eigen::VectorXd u = Eigen::VectorXd::Random(g.cols());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < patch.size(); ++i) mean += u.segment<3>(3 * i) / patch.size();
  EXPECT_LT(((g * u).head<3>() - mean).norm(), 1e-13);
}

TEST(DistributingCoupling, RejectsDegeneratePatches) {
  EXPECT_THROW(distributing_coupling_matrix({0, 0, 0}, {{0, 0, 0}, {1, 0, 0}}), InputError);
  EXPECT_THROW(distributing_coupling_matrix({0, 0, 0}, {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}),
               InputError);
}

TEST(RigidLink, MovesTheSlaveRigidly) {
  const Eigen::Vector3d m(0.1, 0.2, 0.3), s(0.4, -0.1, 0.35);
  const Eigen::Matrix<double, 6, 6> g = rigid_link_matrix(m, s);
  const Eigen::Vector3d a(1, 2, 3), w(-0.2, 0.5, 0.1);
  Vector6 um;
  um << a + w.cross(m), w;
  const Vector6 us = g * um;
  EXPECT_LT((us.head<3>() - (a + w.cross(s))).norm(), 1e-14 * a.norm());
  EXPECT_LT((us.tail<3>() - w).norm(), 1e-15);
}

// Count of eigenvalues with f below 0.1 Hz among the lowest 12 (shift below zero). Round-off
// puts rigid-body eigenvalues near 1e-16 λ_max ≈ 1e-4 rad²/s² (f ~ 1e-3 Hz), not at 0.
int rigid_modes(const AssembledModel& a) {
  const EigenResult r = jointlab::testing::free_modes(a.stiffness, a.mass, 12);
  const Eigen::VectorXd f = frequencies_hz(r.eigenvalues);
  int n = 0;
  for (int k = 0; k < f.size(); ++k) n += f(k) < 0.1;
  // The first elastic mode of these strips is above 10 Hz: a clear gap, no ambiguity.
  EXPECT_GT(f(n), 10.0);
  return n;
}

TEST(Couplings, CoupledStripKeepsSixRigidBodyModesAndTheReferenceFollowsIt) {
  FeModel model;
  const ShellSection s{70e9, 0.33, 2700, 0.002, 1e-3};
  const StripGrid g =
      add_shell_strip(model, uniform_stations(0, 0.2, 40), uniform_stations(-0.01, 0.01, 4), 0, s);
  // Two distributing couplings (reference nodes 1 mm above the plane) and a rigid link.
  std::vector<int> refs;
  for (double x : {0.05, 0.15}) {
    const int ref = model.add_node({x, 0.003, 0.001});
    model.add_distributing_coupling(ref, model.nodes_within({x, 0.003, 0}, 0.006, g.nodes));
    refs.push_back(ref);
  }
  const int tip = model.add_node({0.21, 0, 0});
  model.add_rigid_link(g.node(40, 2), tip);
  const AssembledModel a = model.assemble();
  EXPECT_EQ(rigid_modes(a), 6);
  // A rigid motion imposed on the independent DOFs of the strip nodes moves the reference
  // nodes by the same rigid motion: T maps rigid to rigid.
  const Eigen::Vector3d t(1e-3, 2e-3, -1e-3), w(0.01, -0.02, 0.03);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(a.size());
  for (int n = 0; n < model.node_count(); ++n) {
    Vector6 un;
    un << t + w.cross(model.node(n)), w;
    for (int c = 0; c < 6; ++c)
      if (a.dof(n, c) >= 0) u(a.dof(n, c)) = un(c);
  }
  const Eigen::VectorXd full = a.transformation * u;
  for (int n = 0; n < model.node_count(); ++n) {
    Vector6 un;
    un << t + w.cross(model.node(n)), w;
    EXPECT_LT((full.segment<6>(6 * n) - un).norm(), 1e-14) << "node " << n;
  }
  // The reference nodes are independent (usable as boundary DOFs); the link's slave is not.
  for (int r : refs)
    for (int c = 0; c < 6; ++c) EXPECT_GE(a.dof(r, c), 0);
  EXPECT_LT(a.dof(tip, 0), 0);
}

TEST(Couplings, SlaveOfTwoLinksIsRejected) {
  FeModel model;
  const int a = model.add_node({0, 0, 0}), b = model.add_node({1, 0, 0}),
            c = model.add_node({2, 0, 0});
  model.add_rigid_link(a, c);
  model.add_rigid_link(b, c);
  EXPECT_THROW(model.assemble(), InputError);
}

}  // namespace
}  // namespace jointlab::model::fe
