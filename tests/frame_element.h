// Test-only reference element: the planar Euler-Bernoulli frame element, DOFs
// (u, w, theta) at each of its two nodes, linear axial and cubic Hermite bending
// shape functions, consistent mass (the textbook matrices, independent of model/fe), and two
// stacked beams made of it.
#pragma once

#include <Eigen/Dense>

namespace jointlab::testing {

/// Stiffness and consistent mass of one element, DOF order (u1, w1, theta1, u2, w2, theta2).
struct FrameElement {
  Eigen::Matrix<double, 6, 6> k;  ///< stiffness [N/m, N, N m]
  Eigen::Matrix<double, 6, 6> m;  ///< consistent mass [kg, kg m, kg m^2]
};

/// The element of length `le` [m]: modulus E [Pa], area A [m^2], second moment I [m^4],
/// density rho [kg/m^3].
inline FrameElement frame_element(double E, double A, double I, double rho, double le) {
  FrameElement f;
  f.k.setZero();
  f.m.setZero();
  const double ka = E * A / le, ma = rho * A * le, c = E * I / (le * le * le), l = le;
  f.k(0, 0) = f.k(3, 3) = ka;
  f.k(0, 3) = f.k(3, 0) = -ka;
  f.m(0, 0) = f.m(3, 3) = ma / 3;
  f.m(0, 3) = f.m(3, 0) = ma / 6;
  const int d[4] = {1, 2, 4, 5};
  const double kb[4][4] = {{12, 6 * l, -12, 6 * l},
                           {6 * l, 4 * l * l, -6 * l, 2 * l * l},
                           {-12, -6 * l, 12, -6 * l},
                           {6 * l, 2 * l * l, -6 * l, 4 * l * l}};
  const double mb[4][4] = {{156, 22 * l, 54, -13 * l},
                           {22 * l, 4 * l * l, 13 * l, -3 * l * l},
                           {54, 13 * l, 156, -22 * l},
                           {-13 * l, -3 * l * l, -22 * l, 4 * l * l}};
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      f.k(d[i], d[j]) += c * kb[i][j];
      f.m(d[i], d[j]) += ma / 420 * mb[i][j];
    }
  }
  return f;
}

/// Two stacked free-free planar beams, each 0.6 m of aluminium 25 mm x 5 mm in `elements`
/// frame elements, not joined: DOFs (u, w, theta) per node, u the axial displacement of the
/// beam's contact face, a rigid offset e from its centroid (u_centroid = u_face + e theta);
/// the bottom beam's nodes first, then the top beam's.
struct StackedBeams {
  Eigen::MatrixXd K;  ///< stiffness
  Eigen::MatrixXd M;  ///< consistent mass
  int nodes = 0;      ///< nodes per beam
  int per_beam = 0;   ///< DOFs per beam: 3 nodes
};

/// The stacked beams of `elements` elements each.
inline StackedBeams stacked_beam_matrices(int elements) {
  const double L = 0.6, E = 70e9, rho = 2700, b = 0.025, h = 0.005;
  const double A = b * h, I = b * h * h * h / 12, le = L / elements;
  StackedBeams s;
  s.nodes = elements + 1;
  s.per_beam = 3 * s.nodes;
  const int n = 2 * s.per_beam;
  s.K = Eigen::MatrixXd::Zero(n, n);
  s.M = Eigen::MatrixXd::Zero(n, n);
  const FrameElement fe = frame_element(E, A, I, rho, le);
  for (int beam = 0; beam < 2; ++beam) {
    const double e = beam == 0 ? h / 2 : -h / 2;  // bottom beam's face is above its centroid
    for (int el = 0; el < elements; ++el) {
      // Centroid DOFs from face DOFs: u_c = u + e theta (theta = dw/dx, u_c - z theta).
      Eigen::MatrixXd T = Eigen::MatrixXd::Identity(6, 6);
      T(0, 2) = T(3, 5) = e;
      const Eigen::MatrixXd kf = T.transpose() * fe.k * T, mf = T.transpose() * fe.m * T;
      const int o = beam * s.per_beam + 3 * el;
      s.K.block(o, o, 6, 6) += kf;
      s.M.block(o, o, 6, 6) += mf;
    }
  }
  return s;
}

}  // namespace jointlab::testing
