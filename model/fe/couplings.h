// Kinematic couplings: distributing (RBE3-type) and rigid (RBE2-type).
//
// Distributing coupling, uniform weights: the reference node at x_r moves with the
// least-squares rigid-body fit of the patch's translations. With the patch centroid x̄,
// r_i = x_i − x̄, d = x_r − x̄ and A = Σ (|r_i|² I − r_i r_iᵀ) (n patch nodes):
//   θ_r = A⁻¹ Σ r_i × u_i,      u_r = (1/n) Σ u_i + θ_r × d.
// Patch rotations do not enter. Rigid-body motion of the patch gives exactly that motion
// at the reference node, so the coupling transmits it exactly. A needs ≥ 3 non-collinear
// nodes. Rigid link: u_s = u_m + θ_m × (x_s − x_m), θ_s = θ_m.
// Both are linear constraints u_dependent = G u_independent, applied in FeModel by
// elimination (a transformation u = T u_independent, K ← TᵀKT, M ← TᵀMT), which is exact
// and keeps K positive semi-definite. DOF order per node (u_x, u_y, u_z, θ_x, θ_y, θ_z).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace jointlab::model::fe {

/// G (6 × 3n) with (u_r, θ_r) = G (u_1, …, u_n), the patch translations stacked node by
/// node; throws InputError when the patch has fewer than 3 nodes or is collinear.
Eigen::MatrixXd distributing_coupling_matrix(const Eigen::Vector3d& reference,
                                             const std::vector<Eigen::Vector3d>& patch);

/// G (6 × 6) with (u_s, θ_s) = G (u_m, θ_m) for a rigid link from master to slave.
Eigen::Matrix<double, 6, 6> rigid_link_matrix(const Eigen::Vector3d& master,
                                              const Eigen::Vector3d& slave);

/// The skew matrix [v]× with [v]× w = v × w.
Eigen::Matrix3d skew(const Eigen::Vector3d& v);

}  // namespace jointlab::model::fe
