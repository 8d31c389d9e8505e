// Sparse Cholesky factorisation A = L Lᵀ of a symmetric positive definite matrix (CHOLMOD).
//
// A is given with both triangles (only the lower one is read). The factor is computed once
// and reused for many right-hand sides: the fixed-interface eigen-solve and the constraint
// modes of a Craig–Bampton reduction share one factorisation of K_ii. CHOLMOD stays behind
// this interface (its headers are private to the model library).
#pragma once

#include <memory>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace jointlab::model {

/// A CHOLMOD factorisation of a sparse symmetric positive definite matrix.
class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(SparseCholesky&&) noexcept;
  SparseCholesky& operator=(SparseCholesky&&) noexcept;

  /// Factorises A; false when A is not (numerically) positive definite.
  bool factorize(const Eigen::SparseMatrix<double>& a);
  /// X = A⁻¹ B for a dense B (one column per right-hand side); requires a successful factorize.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  /// Order of the factorised matrix (0 before factorize).
  Eigen::Index size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace jointlab::model
