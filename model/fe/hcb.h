// Hurty/Craig–Bampton reduction of sparse K, M onto boundary DOFs and fixed-interface modes.
//
// Partition the DOFs into boundary b (kept) and interior i. With Φ the lowest m
// fixed-interface modes (K_ii Φ = M_ii Φ Λ, ΦᵀM_iiΦ = I) and the constraint modes
// Ψ = −K_ii⁻¹ K_ib,   u_i = Φ q + Ψ u_b, and the reduced coordinates are ordered
// x = (u_b, q):
//   K_r = [K_bb + K_bi Ψ, 0; 0, Λ],
//   M_r = [M_bb + ΨᵀM_ib + M_biΨ + ΨᵀM_iiΨ, (M_iiΨ + M_ib)ᵀΦ; Φᵀ(M_iiΨ + M_ib), I].
// One CHOLMOD factorisation of K_ii serves both the shift-invert eigen-solve (σ = 0) and
// Ψ. Free-free structures are fine as long as the boundary restrains every part (K_ii
// positive definite): the constraint modes then carry the rigid-body motion exactly.
// Units: those of K and M (SI: N/m, kg); q is M-normalised [√kg·m].
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace jointlab::model::fe {

/// Settings of a Craig–Bampton reduction.
struct HcbOptions {
  int fixed_interface_modes = 20;  ///< m, number of fixed-interface modes kept (≥ 0).
  double tolerance = 1e-10;        ///< Eigen-solve tolerance.
  /// Called with a short message before each long step (may be empty).
  std::function<void(const std::string&)> progress;
  /// Called at each step of the fixed-interface eigen-solve (EigenOptions::interrupt) and before
  /// the constraint modes' solve and the projection; it may throw to stop the reduction. May be
  /// empty.
  std::function<void()> interrupt;
  /// Empty when the options are usable, otherwise what is wrong.
  std::string validate() const;
};

/// How a reduction ended.
enum class HcbStatus {
  kSuccess,                      ///< Reduced matrices are valid.
  kInteriorNotPositiveDefinite,  ///< K_ii singular: the boundary leaves a part free.
  kEigenNotConverged,            ///< The fixed-interface eigen-solve did not converge.
};

/// Outcome of a reduction.
struct HcbSummary {
  HcbStatus status = HcbStatus::kSuccess;  ///< Termination reason.
  int boundary_dofs = 0;                   ///< Number of boundary DOFs kept.
  int interior_dofs = 0;                   ///< Number of interior DOFs eliminated.
  int modes = 0;                           ///< Fixed-interface modes kept.
  std::string report;                      ///< One paragraph for people.
  /// True when status is kSuccess.
  bool ok() const { return status == HcbStatus::kSuccess; }
};

/// Reduced matrices on x = (u_b, q).
struct HcbReduction {
  Eigen::SparseMatrix<double> stiffness;  ///< K_r (order b + m).
  Eigen::SparseMatrix<double> mass;       ///< M_r (order b + m).
  std::vector<int> boundary;              ///< Full index of each boundary DOF, in x order.
  Eigen::VectorXd interface_eigenvalues;  ///< Λ = ω² of the fixed-interface modes.
  HcbSummary summary;                     ///< Status and report.
};

/// Reduces K, M (both triangles stored, symmetric) keeping `boundary` (distinct indices,
/// their order is kept) and options.fixed_interface_modes fixed-interface modes.
HcbReduction reduce_hcb(const Eigen::SparseMatrix<double>& stiffness,
                        const Eigen::SparseMatrix<double>& mass, const std::vector<int>& boundary,
                        const HcbOptions& options);

}  // namespace jointlab::model::fe
