// Test-only reference element: the planar Euler-Bernoulli frame element, DOFs
// (u, w, theta) at each of its two nodes, linear axial and cubic Hermite bending
// shape functions, consistent mass (the textbook matrices, independent of model/fe).
#pragma once

#include <Eigen/Core>

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

}  // namespace jointlab::testing
