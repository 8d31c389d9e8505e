// Lowest modes of K φ = λ M φ (λ = ω² [rad²/s²]) for sparse symmetric K ⪰ 0, M ≻ 0.
//
// Shift-invert Lanczos (Spectra SymGEigsShiftSolver, GEigsMode::ShiftInvert): the operator
// (K − σM)⁻¹ M is applied with one CHOLMOD factorisation of K − σM. σ < 0 below every
// eigenvalue makes K − σM positive definite even for free-free structures (rigid-body
// modes λ = 0), so the eigenvalues nearest σ are the lowest ones. Eigenvectors are
// M-normalised (φᵀMφ = 1) and returned in ascending λ.
#pragma once

#include <functional>
#include <string>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "jointlab/model/sparse_cholesky.h"

namespace jointlab::model {

/// Settings of the shift-invert eigen-solve.
struct EigenOptions {
  int count = 10;             ///< Number of eigenpairs wanted (nearest the shift).
  double shift = 0;           ///< σ [rad²/s²]; K − σM must be positive definite.
  int subspace = 0;           ///< Lanczos basis size; 0 = max(2·count + 1, count + 20).
  double tolerance = 1e-10;   ///< Relative tolerance on the Ritz values.
  int max_iterations = 1000;  ///< Restarts allowed.
  /// Called before each application of (K − σM)⁻¹ (one per Lanczos step, a few ms on the
  /// riveted beam); it may throw to stop the solve (the Python module's Ctrl-C). May be empty.
  std::function<void()> interrupt;
  /// Empty when the options are usable, otherwise what is wrong.
  std::string validate() const;
};

/// How an eigen-solve ended.
enum class EigenStatus {
  kConverged,            ///< Every requested pair converged.
  kNotConverged,         ///< Spectra stopped before convergence.
  kFactorizationFailed,  ///< K − σM is not positive definite.
};

/// Outcome of an eigen-solve.
struct EigenSummary {
  EigenStatus status = EigenStatus::kNotConverged;  ///< Termination reason.
  int iterations = 0;                               ///< Restarts used.
  int converged = 0;                                ///< Pairs converged.
  std::string report;                               ///< One paragraph for people.
  /// True when status is kConverged.
  bool ok() const { return status == EigenStatus::kConverged; }
};

/// Eigenvalues (ascending) with M-normalised eigenvectors (columns).
struct EigenResult {
  Eigen::VectorXd eigenvalues;  ///< λ = ω² [rad²/s²], ascending.
  Eigen::MatrixXd vectors;      ///< φ, one column per eigenvalue, φᵀMφ = 1.
  EigenSummary summary;         ///< Status and report.
};

/// The `options.count` eigenpairs of K φ = λ M φ nearest options.shift.
EigenResult lowest_modes(const Eigen::SparseMatrix<double>& stiffness,
                         const Eigen::SparseMatrix<double>& mass, const EigenOptions& options);

/// Same, reusing a factorisation of K − σM with σ = options.shift.
EigenResult lowest_modes(const SparseCholesky& factor, const Eigen::SparseMatrix<double>& mass,
                         const EigenOptions& options);

/// Natural frequencies f = √λ / 2π [Hz]; eigenvalues below zero (round-off) give 0.
Eigen::VectorXd frequencies_hz(const Eigen::VectorXd& eigenvalues);

}  // namespace jointlab::model
