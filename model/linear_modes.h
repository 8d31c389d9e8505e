// Linear normal modes of a model with every joint at its linear stiffness.
//
// K_lin phi_i = omega_i^2 M phi_i with phi_i^T M phi_j = delta_ij (mass-normalised,
// phi in m per sqrt(kg)), omega in rad/s, frequencies f = omega / (2 pi) in Hz.
// Solved densely (Eigen's generalized self-adjoint solver: Cholesky of M, then a
// symmetric eigenproblem), which suits reduced models of up to a few thousand DOFs.
// Matrices only: a mode is rigid when omega^2 <= rigid_tolerance * omega_max^2: K_lin is
// positive semidefinite, so rigid-body modes come first and their computed omega^2 are
// rounding noise of order eps * omega_max^2.
// A model: rigid-body modes are decided on the structure's own scale, not on its stiffest
// joint (one stiff spring otherwise makes every mode below eps times its frequency look
// rigid). The strain energy of a mass-normalised shape, summed element by element,
//   e(phi) = phi^T K phi + sum_joints k (phi_a - phi_b)^2        (= omega^2 for exact phi),
// carries rounding of order eps * lambda_s, lambda_s = max_i K_ii / M_ii of the structure
// without its joints (of K_lin if the structure alone has no stiffness): a joint term only
// sees the error of phi_a - phi_b, squared. A leading mode is rigid when
// e(phi) <= rigid_tolerance * lambda_s. With count or elastic_count > 0 on a model of more than 100
// DOFs only the lowest modes are computed, by shift-invert Lanczos on a sparse Cholesky
// factorization of K_lin - sigma M (fe/sparse_eigen.h, sigma = -1e-6 lambda_s), then checked
// for members of a repeated eigenvalue (the rigid-body modes) Lanczos missed, by the same
// solve with the found modes projected out; otherwise every mode, densely. Each shape's
// largest-magnitude entry is positive.
#pragma once

#include <string>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "jointlab/model/model_file.h"

namespace jointlab::model {

/// Settings of linear_modes().
struct ModesOptions {
  int count = 0;                  ///< modes to keep, lowest first; 0 keeps all
  double rigid_tolerance = 1e-9;  ///< e(phi) / lambda_s (or omega^2 / omega_max^2) of a rigid mode
  int elastic_count = 0;  ///< model only: if > 0, keep the rigid-body modes and this many elastic

  /// What is wrong with these options, or "".
  std::string error() const;
};

/// Eigenvalues and mass-normalised shapes, ascending in frequency.
struct LinearModes {
  Eigen::VectorXd omega2;  ///< omega_i^2 [rad^2/s^2]; 0 for rigid modes
  Eigen::MatrixXd shapes;  ///< phi_i as columns, phi^T M phi = I
  int rigid_count = 0;     ///< the first rigid_count modes are rigid-body modes

  /// Number of modes kept.
  int size() const { return static_cast<int>(omega2.size()); }
  /// Natural frequency of mode i (0-based column) [Hz].
  double frequency_hz(int i) const;
  /// True if column i is a rigid-body mode.
  bool rigid(int i) const { return i < rigid_count; }
};

/// Solves K phi = omega^2 M phi (K positive semidefinite, M positive definite); InputError if K is
/// indefinite.
LinearModes linear_modes(const Eigen::SparseMatrix<double>& mass,
                         const Eigen::SparseMatrix<double>& stiffness,
                         const ModesOptions& options = {});

/// The lowest modes of a model with every joint at its linear stiffness, rigid-body modes
/// decided on the structure's own scale (above); InputError if K_lin is indefinite or the
/// eigen-solve fails.
LinearModes linear_modes(const Model& model, const ModesOptions& options = {});

}  // namespace jointlab::model
