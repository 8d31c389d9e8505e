#include "jointlab/model/sparse_eigen.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numeric>

#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymGEigsShiftSolver.h>
#include <fmt/format.h>
#include <Eigen/Dense>

namespace jointlab::model {
namespace {

// y = (K − σM)⁻¹ x through a prepared factorisation; the shift is fixed at construction.
class ShiftInvertOp {
 public:
  using Scalar = double;
  ShiftInvertOp(const SparseCholesky& factor, double shift, const std::function<void()>& interrupt)
      : factor_(factor), shift_(shift), interrupt_(interrupt) {}
  Eigen::Index rows() const { return factor_.size(); }
  Eigen::Index cols() const { return factor_.size(); }
  void set_shift(double sigma) {
    assert(sigma == shift_);
    (void)sigma;
  }
  void perform_op(const double* x_in, double* y_out) const {
    if (interrupt_) interrupt_();
    const Eigen::MatrixXd x = Eigen::Map<const Eigen::VectorXd>(x_in, rows());
    Eigen::Map<Eigen::VectorXd>(y_out, rows()) = factor_.solve(x);
  }

 private:
  const SparseCholesky& factor_;
  double shift_;
  const std::function<void()>& interrupt_;
};

EigenResult sorted(const Eigen::VectorXd& values, const Eigen::MatrixXd& vectors,
                   const Eigen::SparseMatrix<double>& mass) {
  std::vector<int> order(values.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return values(a) < values(b); });
  EigenResult r;
  r.eigenvalues.resize(values.size());
  r.vectors.resize(vectors.rows(), values.size());
  for (int k = 0; k < static_cast<int>(order.size()); ++k) {
    r.eigenvalues(k) = values(order[k]);
    Eigen::VectorXd v = vectors.col(order[k]);
    v /= std::sqrt(v.dot(mass * v));
    r.vectors.col(k) = v;
  }
  return r;
}

}  // namespace

std::string EigenOptions::validate() const {
  if (count < 1) return "count must be at least 1";
  if (subspace != 0 && subspace <= count) return "subspace must exceed count";
  if (!(tolerance > 0)) return "tolerance must be positive";
  if (max_iterations < 1) return "max_iterations must be at least 1";
  return "";
}

EigenResult lowest_modes(const Eigen::SparseMatrix<double>& stiffness,
                         const Eigen::SparseMatrix<double>& mass, const EigenOptions& options) {
  SparseCholesky factor;
  const Eigen::SparseMatrix<double> shifted = stiffness - options.shift * mass;
  if (!factor.factorize(shifted)) {
    EigenResult r;
    r.summary.status = EigenStatus::kFactorizationFailed;
    r.summary.report = fmt::format(
        "K - sigma M is not positive definite (sigma = {:g}); lower the shift", options.shift);
    return r;
  }
  return lowest_modes(factor, mass, options);
}

EigenResult lowest_modes(const SparseCholesky& factor, const Eigen::SparseMatrix<double>& mass,
                         const EigenOptions& options) {
  assert(options.validate().empty());
  const int n = static_cast<int>(mass.rows());
  assert(factor.size() == n);
  const int nev = std::min(options.count, n);
  int ncv = options.subspace > 0 ? options.subspace : std::max(2 * nev + 1, nev + 20);
  ncv = std::min(ncv, n);
  if (nev >= ncv) {
    // Too small for Lanczos: solve densely, K − σM = L Lᵀ recovered as its inverse's inverse.
    const Eigen::MatrixXd a_inv = factor.solve(Eigen::MatrixXd::Identity(n, n));
    const Eigen::MatrixXd a = a_inv.inverse();
    const Eigen::MatrixXd m = Eigen::MatrixXd(mass);
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (a + a.transpose()),
                                                                       m);
    EigenResult r = sorted(es.eigenvalues().head(nev).array() + options.shift,
                           es.eigenvectors().leftCols(nev), mass);
    r.summary.status = EigenStatus::kConverged;
    r.summary.converged = nev;
    r.summary.report = fmt::format("dense generalized eigen-solve of order {}", n);
    return r;
  }
  ShiftInvertOp op(factor, options.shift, options.interrupt);
  Spectra::SparseSymMatProd<double> bop(mass);
  Spectra::SymGEigsShiftSolver<ShiftInvertOp, Spectra::SparseSymMatProd<double>,
                               Spectra::GEigsMode::ShiftInvert>
      solver(op, bop, nev, ncv, options.shift);
  solver.init();
  const int nconv = static_cast<int>(
      solver.compute(Spectra::SortRule::LargestMagn, options.max_iterations, options.tolerance));
  EigenResult r;
  if (solver.info() == Spectra::CompInfo::Successful) {
    r = sorted(solver.eigenvalues(), solver.eigenvectors(), mass);
    r.summary.status = EigenStatus::kConverged;
  } else {
    r.summary.status = EigenStatus::kNotConverged;
  }
  r.summary.iterations = static_cast<int>(solver.num_iterations());
  r.summary.converged = nconv;
  r.summary.report = fmt::format(
      "shift-invert Lanczos, order {}, shift {:g}: {} of {} eigenpairs converged in {} restarts "
      "(basis {}, tolerance {:g})",
      n, options.shift, nconv, nev, r.summary.iterations, ncv, options.tolerance);
  return r;
}

Eigen::VectorXd frequencies_hz(const Eigen::VectorXd& eigenvalues) {
  return eigenvalues.unaryExpr(
      [](double l) { return l > 0 ? std::sqrt(l) / (2 * 3.14159265358979323846) : 0.0; });
}

}  // namespace jointlab::model
