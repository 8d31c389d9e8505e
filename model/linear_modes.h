// Linear normal modes of a model with every joint at its linear stiffness.
//
// K_lin phi_i = omega_i^2 M phi_i with phi_i^T M phi_j = delta_ij (mass-normalised,
// phi in m per sqrt(kg)), omega in rad/s, frequencies f = omega / (2 pi) in Hz.
// Solved densely (Eigen's generalized self-adjoint solver: Cholesky of M, then a
// symmetric eigenproblem), which suits reduced models of up to a few thousand DOFs.
// A mode is rigid when omega^2 <= rigid_tolerance * omega_max^2: K_lin is positive
// semidefinite, so rigid-body modes come first and their computed omega^2 are rounding
// noise of order eps * omega_max^2. Each shape's largest-magnitude entry is positive.
#pragma once

#include <string>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace jointlab::model {

/// Settings of linear_modes().
struct ModesOptions {
  int count = 0;                  ///< modes to keep, lowest first; 0 keeps all
  double rigid_tolerance = 1e-9;  ///< omega^2 / omega_max^2 below which a mode is rigid

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

}  // namespace jointlab::model
