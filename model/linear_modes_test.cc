#include "jointlab/model/linear_modes.h"

#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/tests/frame_element.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

using testing::Close;

// A free-free planar Euler-Bernoulli beam: DOFs (u, w, theta) per node, cubic Hermite
// bending, linear axial, consistent mass. Steel-like 1 m x 20 mm x 5 mm.
struct Beam {
  Eigen::SparseMatrix<double> M, K;
};
Beam free_beam(int elements) {
  const double L = 1.0, E = 2.0e11, rho = 7800.0, b = 0.02, h = 0.005;
  const double A = b * h, I = b * h * h * h / 12, le = L / elements;
  const int n = 3 * (elements + 1);
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(n, n), m = Eigen::MatrixXd::Zero(n, n);
  const testing::FrameElement f = testing::frame_element(E, A, I, rho, le);
  for (int e = 0; e < elements; ++e) {
    k.block<6, 6>(3 * e, 3 * e) += f.k;
    m.block<6, 6>(3 * e, 3 * e) += f.m;
  }
  return {m.sparseView(), k.sparseView()};
}

// Closed form of the free-free beam: omega_n = (beta_n L)^2 sqrt(E I / (rho A L^4)).
double beam_frequency_hz(int n) {
  const double betaL[] = {4.730040745, 7.853204624, 10.99560784};
  const double E = 2.0e11, rho = 7800.0, b = 0.02, h = 0.005;
  const double A = b * h, I = b * h * h * h / 12;
  return betaL[n] * betaL[n] * std::sqrt(E * I / (rho * A)) / (2 * std::numbers::pi);
}

TEST(LinearModes, FreeFreeBeamConvergesToTheClosedFormAtFourthOrder) {
  double previous[3] = {0, 0, 0};
  for (int elements : {8, 16, 32}) {
    const Beam beam = free_beam(elements);
    const LinearModes modes = linear_modes(beam.M, beam.K);
    // Axial translation, transverse translation, rotation.
    ASSERT_EQ(modes.rigid_count, 3) << elements;
    // The lowest elastic modes are bending (axial is ~100x stiffer).
    for (int i = 0; i < 3; ++i) {
      const double err =
          std::abs(modes.frequency_hz(3 + i) - beam_frequency_hz(i)) / beam_frequency_hz(i);
      if (elements > 8) {
        // Hermite cubics: the eigenvalue error falls as h^4; halving h divides it by ~16
        // (at least 12 allows for the pre-asymptotic range).
        EXPECT_GT(previous[i] / err, 12.0) << "mode " << i + 1 << ", " << elements;
      }
      previous[i] = err;
    }
  }
  // 32 elements: 1e-5 relative on the first three (measured ~1e-7 .. 3e-6).
  for (int i = 0; i < 3; ++i) EXPECT_GT(1e-5, previous[i]);
}

TEST(LinearModes, PairsSatisfyTheEigenproblemAndAreMassNormalised) {
  const Beam beam = free_beam(12);
  const LinearModes modes = linear_modes(beam.M, beam.K);
  const Eigen::MatrixXd K = Eigen::MatrixXd(beam.K), M = Eigen::MatrixXd(beam.M);
  const Eigen::MatrixXd& X = modes.shapes;
  // Residual of each pair relative to ||K X||: rounding level, 1e-9 allows for the
  // conditioning (omega_max^2 / omega_1^2 ~ 1e8). Rigid modes have omega^2 set to 0.
  const Eigen::MatrixXd R = K * X - M * X * modes.omega2.asDiagonal();
  EXPECT_LT(R.norm(), 1e-9 * (K * X).norm());
  EXPECT_LT((X.transpose() * M * X - Eigen::MatrixXd::Identity(X.cols(), X.cols())).norm(), 1e-10);
  for (int i = 1; i < modes.size(); ++i) EXPECT_LE(modes.omega2(i - 1), modes.omega2(i));
  for (int i = 0; i < modes.size(); ++i)
    EXPECT_GT(X.col(i).maxCoeff(), -X.col(i).minCoeff() - 1e-12);
}

TEST(LinearModes, TwoMassesOnSpringsAndCountOption) {
  // m1 = 1, m2 = 2 on springs k1 = 100 to ground and k2 = 50 between: omega^2 are the
  // roots of m1 m2 w^2 - (m1 k2 + m2 (k1 + k2)) w + k1 k2 = 0.
  Eigen::MatrixXd M(2, 2), K(2, 2);
  M << 1, 0, 0, 2;
  K << 150, -50, -50, 50;
  const double a = 2, b = -(1 * 50 + 2 * 150), c = 100 * 50;
  const double w1 = (-b - std::sqrt(b * b - 4 * a * c)) / (2 * a);
  ModesOptions one;
  one.count = 1;
  const LinearModes modes = linear_modes(M.sparseView(), K.sparseView(), one);
  ASSERT_EQ(modes.size(), 1);
  EXPECT_EQ(modes.rigid_count, 0);
  EXPECT_TRUE(Close(modes.omega2(0), w1, 1e-13));
  EXPECT_TRUE(Close(modes.frequency_hz(0), std::sqrt(w1) / (2 * std::numbers::pi), 1e-13));
}

TEST(LinearModes, IndefiniteStiffnessIsAnInputError) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Identity(2, 2), K(2, 2);
  K << 1, 0, 0, -1;
  EXPECT_THROW(linear_modes(M.sparseView(), K.sparseView()), InputError);
  EXPECT_NE((ModesOptions{-1, 1e-9}.error()), "");
  EXPECT_EQ(ModesOptions{}.error(), "");
}

// The free beam as a model file would give it, with joint springs added.
Model beam_model(int elements, const std::vector<Joint>& joints) {
  const Beam beam = free_beam(elements);
  Model model;
  model.mass = beam.M;
  model.stiffness = beam.K;
  model.joints = joints;
  return model;
}

TEST(LinearModes, AStiffSpringLeavesTheRigidBodyModesAndTheBendingModesAlone) {
  // A 1e20 N/m spring on the axial DOFs of the beam's two ends leaves its three rigid-body
  // modes (axial and transverse translation, rotation about the centroid, none stretches
  // it) and its bending modes exactly as they were. On the matrices alone omega_max^2 is
  // ~1e24 and every bending mode falls under 1e-9 of it; on the structure's own scale
  // (strain energy element by element) they stay elastic. A dense solve of every mode
  // cannot resolve them at all (its absolute rounding eps omega_max^2 ~ 1e8 exceeds
  // omega_1^2 ~ 3e4): the lowest modes by shift-invert Lanczos on CHOLMOD can.
  const int elements = 40, last = 3 * elements;  // 123 DOFs: the sparse path with a count
  const Model plain = beam_model(elements, {});
  const Model stiff = beam_model(elements, {{0, last, "spring.axial", 1e20, std::nullopt}});
  const LinearModes matrices_only = linear_modes(stiff.mass, stiff.linear_stiffness());
  EXPECT_GT(matrices_only.rigid_count, 3);  // the old rule: bending modes called rigid
  const LinearModes reference = linear_modes(plain);
  ASSERT_EQ(reference.rigid_count, 3);
  ModesOptions o;
  o.count = 8;
  const LinearModes modes = linear_modes(stiff, o);
  ASSERT_EQ(modes.rigid_count, 3);
  // The first three bending modes: Lanczos converges to 1e-10; 1e-8 allows for the
  // factorization of K_lin - sigma M with its 1e20 entries.
  for (int i = 3; i < 6; ++i) {
    EXPECT_TRUE(Close(modes.omega2(i), reference.omega2(i), 1e-8)) << i;
  }
}

TEST(LinearModes, ShiftInvertLanczosAgreesWithTheDenseSolve) {
  // Two methods on one model: the lowest 10 modes of a 123-DOF free beam with a grounded
  // spring (no rigid axial translation left): eigenvalues to 1e-9, shapes to 1e-6 (the
  // Ritz vectors' accuracy is the square root of the values').
  const Model model = beam_model(40, {{0, kGround, "spring.ground", 1e5, std::nullopt}});
  const LinearModes dense = linear_modes(model);
  ModesOptions o;
  o.count = 10;
  const LinearModes sparse = linear_modes(model, o);
  ASSERT_EQ(sparse.size(), 10);
  EXPECT_EQ(sparse.rigid_count, 2);
  EXPECT_EQ(dense.rigid_count, 2);
  for (int i = sparse.rigid_count; i < 10; ++i) {
    EXPECT_TRUE(Close(sparse.omega2(i), dense.omega2(i), 1e-9)) << i;
    EXPECT_TRUE(
        Close(std::abs(sparse.shapes.col(i).dot(model.mass * dense.shapes.col(i))), 1.0, 1e-6))
        << i;
  }
  ModesOptions elastic;
  elastic.elastic_count = 4;
  const LinearModes four = linear_modes(model, elastic);
  EXPECT_EQ(four.size(), 6);
  EXPECT_TRUE(Close(four.omega2(5), dense.omega2(5), 1e-9));
}

TEST(LinearModes, ShiftInvertLanczosFindsEveryMemberOfARepeatedEigenvalue) {
  // Two identical free beams side by side, unjoined (246 DOFs): every eigenvalue twice, the
  // three rigid-body modes of each beam six times over. Lanczos from one start vector finds
  // one vector of each eigenvalue in exact arithmetic; before the deflated check it came back
  // with fewer rigid-body modes than the structure has (a lap joint of two strips lost one
  // of its six, and QSMA refused the model). The sparse path must give what the dense one
  // does: 6 rigid-body modes, then each bending frequency twice, to 1e-9 as above.
  const Beam one = free_beam(40);
  const Eigen::Index n = one.M.rows();
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(2 * n, 2 * n), k = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  m.topLeftCorner(n, n) = m.bottomRightCorner(n, n) = Eigen::MatrixXd(one.M);
  k.topLeftCorner(n, n) = k.bottomRightCorner(n, n) = Eigen::MatrixXd(one.K);
  Model model;
  model.mass = m.sparseView();
  model.stiffness = k.sparseView();
  const LinearModes dense = linear_modes(model);
  ASSERT_EQ(dense.rigid_count, 6);
  for (int elastic : {1, 2, 4}) {
    ModesOptions o;
    o.elastic_count = elastic;
    const LinearModes sparse = linear_modes(model, o);
    ASSERT_EQ(sparse.rigid_count, 6) << elastic;
    ASSERT_EQ(sparse.size(), 6 + elastic) << elastic;
    for (int i = 6; i < sparse.size(); ++i) {
      EXPECT_TRUE(Close(sparse.omega2(i), dense.omega2(i), 1e-9)) << elastic << " " << i;
    }
  }
}

}  // namespace
}  // namespace jointlab::model
