#include "jointlab/model/fe/hcb.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "jointlab/model/fe/fe_model.h"
#include "jointlab/model/fe/strip_mesh.h"
#include "jointlab/model/sparse_eigen.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model::fe {
namespace {

using jointlab::testing::Close;
using jointlab::testing::rel_err;

// A free-free shell strip (L = 0.3 m) and its boundary: all DOFs of three nodes.
struct Fixture {
  FeModel model;
  AssembledModel a;
  std::vector<int> boundary;
  Fixture() {
    const ShellSection s{70e9, 0.33, 2700, 0.002, 1e-3};
    const StripGrid g = add_shell_strip(model, uniform_stations(0, 0.3, 30),
                                        uniform_stations(-0.01, 0.01, 2), 0, s);
    a = model.assemble();
    for (int i : {5, 15, 25})
      for (int c = 0; c < 6; ++c) boundary.push_back(a.dof(g.node(i, 1), c));
  }
};

Eigen::VectorXd dense_eigenvalues(const Eigen::SparseMatrix<double>& k,
                                  const Eigen::SparseMatrix<double>& m) {
  return Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(k),
                                                                   Eigen::MatrixXd(m))
      .eigenvalues();
}

TEST(Hcb, AllFixedInterfaceModesReproduceTheFullModelExactly) {
  // With every interior mode kept the transformation is square and invertible: the
  // reduced eigenvalues are the full ones, to the round-off of two dense generalized
  // solves, ~ε·cond(M) ≈ 1e-16 × 1e10 (the shell's small drilling inertia) → 1e-6.
  Fixture f;
  HcbOptions o;
  o.fixed_interface_modes = 100000;
  const HcbReduction r = reduce_hcb(f.a.stiffness, f.a.mass, f.boundary, o);
  ASSERT_TRUE(r.summary.ok()) << r.summary.report;
  ASSERT_EQ(r.stiffness.rows(), f.a.size());
  const Eigen::VectorXd full = dense_eigenvalues(f.a.stiffness, f.a.mass);
  const Eigen::VectorXd red = dense_eigenvalues(r.stiffness, r.mass);
  for (int k = 6; k < 30; ++k) EXPECT_TRUE(Close(red(k), full(k), 1e-6)) << k;
}

TEST(Hcb, ConvergesFromAboveAsModesAreAddedAndKeepsRigidBodyModes) {
  Fixture f;
  EigenOptions eo;
  eo.count = 16;
  eo.shift = -1.0;
  const EigenResult full = lowest_modes(f.a.stiffness, f.a.mass, eo);
  ASSERT_TRUE(full.summary.ok());
  double previous = INFINITY;
  for (int m : {2, 5, 10, 20, 40}) {
    HcbOptions o;
    o.fixed_interface_modes = m;
    const HcbReduction r = reduce_hcb(f.a.stiffness, f.a.mass, f.boundary, o);
    ASSERT_TRUE(r.summary.ok()) << r.summary.report;
    EXPECT_EQ(r.summary.modes, m);
    const Eigen::VectorXd red = dense_eigenvalues(r.stiffness, r.mass);
    // Free-free: the constraint modes carry rigid motion exactly, so six zero eigenvalues
    // (|λ| below 1e-6 of the first elastic one: round-off of the reduction).
    for (int k = 0; k < 6; ++k) EXPECT_LT(std::abs(red(k)), 1e-6 * red(6)) << m;
    double worst = 0;
    for (int k = 6; k < 16; ++k) {
      // Rayleigh–Ritz: a reduced eigenvalue is an upper bound of the full one (allowing
      // 1e-9 relative for the round-off of both solves).
      EXPECT_GT(red(k), full.eigenvalues(k) * (1 - 1e-9)) << "m " << m << " mode " << k;
      worst = std::max(worst, rel_err(red(k), full.eigenvalues(k)));
    }
    EXPECT_LT(worst, previous) << m;  // more fixed-interface modes, better
    previous = worst;
  }
  // 40 modes for 10 elastic modes of a 3-node interface: well inside 0.1 % in frequency.
  EXPECT_LT(std::sqrt(1 + previous) - 1, 1e-3);
}

TEST(Hcb, TheInterruptHookIsCalledAtEachEigenSolveStepAndAThrowStopsTheReduction) {
  // The hook runs before each operator application of the Lanczos solve (the only long step
  // without a checkpoint: 6 s of the riveted beam's 7 s build on a busy machine), so a caller's
  // Ctrl-C is seen within one step. 20 fixed-interface modes take at least the basis size,
  // max(2 m + 1, m + 20) = 41 applications, plus the check before the constraint modes; the
  // reduction's matrices are the same with the hook as without (bit for bit: it computes
  // nothing). A throw from the hook ends the reduction with that exception.
  Fixture f;
  HcbOptions o;
  o.fixed_interface_modes = 20;
  const HcbReduction plain = reduce_hcb(f.a.stiffness, f.a.mass, f.boundary, o);
  int calls = 0;
  o.interrupt = [&calls] { ++calls; };
  const HcbReduction hooked = reduce_hcb(f.a.stiffness, f.a.mass, f.boundary, o);
  ASSERT_TRUE(hooked.summary.ok()) << hooked.summary.report;
  EXPECT_GE(calls, 42);
  EXPECT_TRUE(Eigen::MatrixXd(hooked.stiffness) == Eigen::MatrixXd(plain.stiffness));
  EXPECT_TRUE(Eigen::MatrixXd(hooked.mass) == Eigen::MatrixXd(plain.mass));
  struct Stop {};
  int left = 5;
  o.interrupt = [&left] {
    if (--left == 0) throw Stop{};
  };
  EXPECT_THROW(reduce_hcb(f.a.stiffness, f.a.mass, f.boundary, o), Stop);
  EXPECT_EQ(left, 0);
}

TEST(Hcb, ReportsABoundaryThatLeavesAPartFree) {
  // Two disconnected strips, boundary only on the first: K_ii is singular.
  FeModel model;
  const ShellSection s{70e9, 0.33, 2700, 0.002, 1e-3};
  const StripGrid g1 =
      add_shell_strip(model, uniform_stations(0, 0.1, 5), uniform_stations(0, 0.02, 1), 0, s);
  add_shell_strip(model, uniform_stations(0, 0.1, 5), uniform_stations(0, 0.02, 1), 0.01, s);
  const AssembledModel a = model.assemble();
  std::vector<int> boundary;
  for (int c = 0; c < 6; ++c) boundary.push_back(a.dof(g1.node(2, 0), c));
  const HcbReduction r = reduce_hcb(a.stiffness, a.mass, boundary, HcbOptions{});
  EXPECT_EQ(r.summary.status, HcbStatus::kInteriorNotPositiveDefinite);
  EXPECT_FALSE(r.summary.report.empty());
}

}  // namespace
}  // namespace jointlab::model::fe
