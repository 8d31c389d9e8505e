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

}  // namespace jointlab::model::fe
