// Element matrices shared by the finite elements of model/fe.
//
// Every element returns its stiffness K [N/m, N, N·m/rad] and consistent mass M [kg, kg·m,
// kg·m²] in GLOBAL coordinates, ordered node by node with six DOFs per node:
// (u_x, u_y, u_z, θ_x, θ_y, θ_z), translations in m, right-handed rotations in rad.
#pragma once

#include <Eigen/Core>

namespace jointlab::model::fe {

/// Stiffness and consistent mass of one element in global coordinates, 6 DOFs per node.
struct ElementMatrices {
  Eigen::MatrixXd stiffness;  ///< K, symmetric positive semi-definite.
  Eigen::MatrixXd mass;       ///< M, symmetric positive definite.
};

/// Local element matrices (N DOFs, every 3-vector in the local axes e1, e2, e3) turned to
/// global axes: K = T^T K_local T with T = diag(R, ..., R) and R's rows the local unit axes.
template <int N>
ElementMatrices to_global(const Eigen::Matrix<double, N, N>& k_local,
                          const Eigen::Matrix<double, N, N>& m_local, const Eigen::Vector3d& e1,
                          const Eigen::Vector3d& e2, const Eigen::Vector3d& e3) {
  static_assert(N % 3 == 0, "element DOFs come in 3-vectors");
  Eigen::Matrix3d r;
  r.row(0) = e1;
  r.row(1) = e2;
  r.row(2) = e3;
  Eigen::Matrix<double, N, N> t = Eigen::Matrix<double, N, N>::Zero();
  for (int blk = 0; blk < N / 3; ++blk) t.template block<3, 3>(3 * blk, 3 * blk) = r;
  ElementMatrices out;
  out.stiffness = t.transpose() * k_local * t;
  out.mass = t.transpose() * m_local * t;
  return out;
}

}  // namespace jointlab::model::fe
