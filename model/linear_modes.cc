#include "jointlab/model/linear_modes.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <vector>

#include <Spectra/MatOp/SparseSymMatProd.h>
#include <Spectra/SymGEigsShiftSolver.h>
#include <fmt/format.h>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "jointlab/core/error.h"
#include "jointlab/model/sparse_cholesky.h"

namespace jointlab::model {

std::string ModesOptions::error() const {
  if (count < 0) return fmt::format("mode count {} must be >= 0", count);
  if (elastic_count < 0) return fmt::format("elastic mode count {} must be >= 0", elastic_count);
  if (!(rigid_tolerance > 0 && rigid_tolerance < 1)) {
    return fmt::format("rigid tolerance {} must be in (0, 1)", rigid_tolerance);
  }
  return "";
}

double LinearModes::frequency_hz(int i) const {
  return std::sqrt(std::max(omega2(i), 0.0)) / (2 * std::numbers::pi);
}

LinearModes linear_modes(const Eigen::SparseMatrix<double>& mass,
                         const Eigen::SparseMatrix<double>& stiffness,
                         const ModesOptions& options) {
  assert(options.error().empty());
  assert(mass.rows() == stiffness.rows() && mass.rows() == mass.cols());
  const Eigen::MatrixXd k = Eigen::MatrixXd(stiffness);
  const Eigen::MatrixXd m = Eigen::MatrixXd(mass);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(
      k, m, Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
  if (solver.info() != Eigen::Success) {
    throw InputError("linear modes: the mass matrix is not positive definite");
  }
  const Eigen::Index n = k.rows();
  const Eigen::VectorXd& lambda = solver.eigenvalues();
  const double lambda_max = std::max(std::abs(lambda(n - 1)), std::abs(lambda(0)));
  const double threshold = options.rigid_tolerance * lambda_max;
  if (lambda(0) < -threshold) {
    throw InputError(fmt::format(
        "linear modes: the stiffness matrix with joints at linear stiffness is not positive "
        "semidefinite (eigenvalue omega^2 = {:.6g} rad^2/s^2)",
        lambda(0)));
  }
  const Eigen::Index keep = options.count == 0 ? n : std::min<Eigen::Index>(options.count, n);
  LinearModes out;
  out.omega2 = lambda.head(keep);
  out.shapes = solver.eigenvectors().leftCols(keep);
  for (Eigen::Index i = 0; i < n && lambda(i) <= threshold; ++i) ++out.rigid_count;
  out.rigid_count = static_cast<int>(std::min<Eigen::Index>(out.rigid_count, keep));
  for (int i = 0; i < out.rigid_count; ++i) out.omega2(i) = 0.0;
  for (Eigen::Index i = 0; i < keep; ++i) {
    Eigen::Index at;
    out.shapes.col(i).cwiseAbs().maxCoeff(&at);
    if (out.shapes(at, i) < 0) out.shapes.col(i) *= -1.0;
  }
  return out;
}

namespace {

// max_i K_ii / M_ii: the largest omega^2 scale of a stiffness against the mass.
double diagonal_scale(const Eigen::SparseMatrix<double>& k, const Eigen::SparseMatrix<double>& m) {
  double s = 0;
  for (Eigen::Index i = 0; i < k.rows(); ++i) s = std::max(s, k.coeff(i, i) / m.coeff(i, i));
  return s;
}

// Strain energy of a shape summed element by element (linear_modes.h).
double strain_energy(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& phi) {
  double e = phi.dot(model.stiffness * phi);
  for (const Joint& j : model.joints) {
    const double d = phi(j.a) - (j.b == kGround ? 0.0 : phi(j.b));
    e += j.stiffness * d * d;
  }
  return e;
}

// Every mode, densely (Cholesky of M, symmetric eigenproblem).
LinearModes dense_modes(const Eigen::SparseMatrix<double>& mass,
                        const Eigen::SparseMatrix<double>& stiffness) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(
      Eigen::MatrixXd(stiffness), Eigen::MatrixXd(mass),
      Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
  if (solver.info() != Eigen::Success) {
    throw InputError("linear modes: the mass matrix is not positive definite");
  }
  return {solver.eigenvalues(), solver.eigenvectors(), 0};
}

// y = (K_lin - sigma M)^{-1} x for Spectra: one CHOLMOD factorization, then iterative
// refinement (two steps) with residuals formed element by element: a joint 1e12 times
// stiffer than the rest leaves rounding of order 1e-4 in the factorization's soft part.
class RefinedShiftInvert {
 public:
  using Scalar = double;
  RefinedShiftInvert(const Model& model, const SparseCholesky& factor, double shift)
      : model_(model), factor_(factor), shift_(shift) {}
  Eigen::Index rows() const { return factor_.size(); }
  Eigen::Index cols() const { return factor_.size(); }
  void set_shift(double) {}
  void perform_op(const double* x_in, double* y_out) const {
    const Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    Eigen::VectorXd y = factor_.solve(x);
    for (int it = 0; it < 2; ++it) {
      const Eigen::VectorXd r = x - model_.apply_linear_stiffness(y) + shift_ * (model_.mass * y);
      y += factor_.solve(r);
    }
    Eigen::Map<Eigen::VectorXd>(y_out, rows()) = y;
  }

 private:
  const Model& model_;
  const SparseCholesky& factor_;
  double shift_;
};

// The shift-invert operator with the M-orthonormal columns of v projected out, P A P with
// P = I - v v^T M, for Spectra (which hands it x = M w): its largest eigenvalues are those of
// the modes v does not hold.
class DeflatedShiftInvert {
 public:
  using Scalar = double;
  DeflatedShiftInvert(const RefinedShiftInvert& op, const Eigen::MatrixXd& v,
                      const Eigen::MatrixXd& mv)
      : op_(op), v_(v), mv_(mv) {}
  Eigen::Index rows() const { return op_.rows(); }
  Eigen::Index cols() const { return op_.cols(); }
  void set_shift(double) {}
  void perform_op(const double* x_in, double* y_out) const {
    const Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    const Eigen::VectorXd px = x - mv_ * (v_.transpose() * x);
    Eigen::Map<Eigen::VectorXd> y(y_out, rows());
    op_.perform_op(px.data(), y_out);
    y -= v_ * (mv_.transpose() * y);
  }

 private:
  const RefinedShiftInvert& op_;
  const Eigen::MatrixXd& v_;
  const Eigen::MatrixXd& mv_;
};

// The lowest `count` modes by shift-invert Lanczos (Spectra), M-normalised, ascending.
LinearModes sparse_modes(const Model& model, const Eigen::SparseMatrix<double>& k_lin, int count,
                         double shift) {
  const int n = static_cast<int>(model.size());
  const int nev = std::min(count, n - 1);
  const int ncv = std::min(n, std::max(2 * nev + 1, nev + 20));
  SparseCholesky factor;
  if (!factor.factorize(k_lin - shift * model.mass)) {
    throw InputError(
        "linear modes: the stiffness matrix with joints at linear stiffness is not positive "
        "semidefinite");
  }
  RefinedShiftInvert op(model, factor, shift);
  Spectra::SparseSymMatProd<double> bop(model.mass);
  Spectra::SymGEigsShiftSolver<RefinedShiftInvert, Spectra::SparseSymMatProd<double>,
                               Spectra::GEigsMode::ShiftInvert>
      solver(op, bop, nev, ncv, shift);
  solver.init();
  solver.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10);
  if (solver.info() != Spectra::CompInfo::Successful) {
    throw InputError(fmt::format(
        "linear modes: shift-invert Lanczos did not converge for the lowest {} modes", nev));
  }
  // Polish: three steps of subspace iteration with the refined operator (each shrinks a
  // vector's error by (lambda_i - sigma) / (lambda_{nev+1} - sigma); components along stiff
  // joint modes by far more), then Rayleigh-Ritz with K_lin applied element by element, so
  // that a rigid-body shape stretches no stiff joint beyond rounding.
  // The subspace steps only where a joint is far stiffer (1e6) than the structure at its
  // ends: elsewhere Lanczos' shapes are already accurate and the steps cost solves.
  bool stiff_joint = false;
  for (const Joint& j : model.joints) {
    double local = model.stiffness.coeff(j.a, j.a);
    if (j.b != kGround) local = std::max(local, model.stiffness.coeff(j.b, j.b));
    stiff_joint = stiff_joint || j.stiffness > 1e6 * local;
  }
  Eigen::MatrixXd v = solver.eigenvectors();
  for (int it = 0; stiff_joint && it < 3; ++it) {
    const Eigen::MatrixXd mv = model.mass * v;
    for (int k = 0; k < nev; ++k) op.perform_op(mv.col(k).data(), v.col(k).data());
    v = Eigen::HouseholderQR<Eigen::MatrixXd>(v).householderQ() * Eigen::MatrixXd::Identity(n, nev);
  }
  // Rayleigh-Ritz on the columns of v (K_lin applied element by element), M-normalised.
  const auto ritz = [&](const Eigen::MatrixXd& basis) {
    const Eigen::Index m = basis.cols();
    Eigen::MatrixXd kv(n, m);
    for (Eigen::Index k = 0; k < m; ++k) kv.col(k) = model.apply_linear_stiffness(basis.col(k));
    const Eigen::MatrixXd kr = basis.transpose() * kv,
                          mr = basis.transpose() * (model.mass * basis);
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> rr(0.5 * (kr + kr.transpose()),
                                                                       0.5 * (mr + mr.transpose()));
    if (rr.info() != Eigen::Success) {
      throw InputError("linear modes: the Rayleigh-Ritz step failed (mass not positive definite)");
    }
    LinearModes r;
    r.omega2 = rr.eigenvalues();
    r.shapes = basis * rr.eigenvectors();
    for (Eigen::Index k = 0; k < m; ++k) {
      r.shapes.col(k) /= std::sqrt(r.shapes.col(k).dot(model.mass * r.shapes.col(k)));
    }
    return r;
  };
  LinearModes out = ritz(v);
  // Lanczos from one start vector finds one vector of each eigenvalue in exact arithmetic: of a
  // repeated eigenvalue it may miss members, which rounding alone brings in. The six rigid-body
  // modes of a free structure are one such: a 6-rivet lap joint of two steel strips (107 DOFs)
  // came back with five of them, and QSMA of its first two modes refused the model as "not
  // positive semidefinite" (the clamping that removes rigid motion missed one). So the lowest
  // modes of the operator with the found ones projected out are computed too; any below the
  // highest found joins them, and the check repeats until none does.
  for (int pass = 0; pass < nev && n - nev >= 3; ++pass) {
    const Eigen::MatrixXd mv = model.mass * out.shapes;
    DeflatedShiftInvert deflated(op, out.shapes, mv);
    const int extra = std::min(2, n - nev - 1);
    Spectra::SymGEigsShiftSolver<DeflatedShiftInvert, Spectra::SparseSymMatProd<double>,
                                 Spectra::GEigsMode::ShiftInvert>
        check(deflated, bop, extra, std::min(n - nev, std::max(2 * extra + 1, extra + 20)), shift);
    check.init();
    check.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10);
    if (check.info() != Spectra::CompInfo::Successful) {
      throw InputError(fmt::format(
          "linear modes: shift-invert Lanczos did not converge for the lowest {} modes", nev));
    }
    const Eigen::MatrixXd w = check.eigenvectors();
    const double highest = out.omega2(nev - 1);
    const double tolerance = 1e-9 * std::max(std::abs(highest), std::abs(shift));
    bool missed = false;
    for (Eigen::Index k = 0; k < w.cols(); ++k) {
      const double lambda = strain_energy(model, w.col(k)) / w.col(k).dot(model.mass * w.col(k));
      missed = missed || lambda < highest - tolerance;
    }
    if (!missed) break;
    Eigen::MatrixXd basis(n, nev + w.cols());
    basis << out.shapes, w;
    LinearModes merged = ritz(basis);
    out.omega2 = merged.omega2.head(nev);
    out.shapes = merged.shapes.leftCols(nev);
  }
  return out;
}

}  // namespace

LinearModes linear_modes(const Model& model, const ModesOptions& options) {
  if (const std::string e = options.error(); !e.empty()) {
    throw InputError(fmt::format("linear modes: {}", e));
  }
  const Eigen::SparseMatrix<double> k_lin = model.linear_stiffness();
  double scale = diagonal_scale(model.stiffness, model.mass);
  if (!(scale > 0)) scale = diagonal_scale(k_lin, model.mass);
  if (!std::isfinite(scale)) {
    throw InputError("linear modes: the stiffness or mass has entries that overflow");
  }
  // A joint more than 1e16 times stiffer than the structure's stiffest diagonal entry: the
  // structure's own stiffness falls below rounding in that joint's rows of K_lin.
  const Eigen::VectorXd structure_diagonal = model.stiffness.diagonal();
  const double structure_max =
      structure_diagonal.size() > 0 ? structure_diagonal.cwiseAbs().maxCoeff() : 0.0;
  for (const Joint& j : model.joints) {
    if (structure_max > 0 && j.stiffness > 1e16 * structure_max) {
      throw InputError(fmt::format(
          "linear modes: joint '{}' has stiffness {:.3g} N/m, more than 1e16 times the "
          "structure's stiffest diagonal entry ({:.3g} N/m): the structure falls below "
          "double precision beside it; a penalty stiffness 1e6 times the structure's is rigid "
          "to 6 digits",
          j.element, j.stiffness, structure_max));
    }
  }
  const double threshold = options.rigid_tolerance * scale;
  const auto rigid_count = [&](const LinearModes& m) {
    int n = 0;
    while (n < m.size() && strain_energy(model, m.shapes.col(n)) <= threshold) ++n;
    return n;
  };
  const Eigen::Index n = model.size();
  LinearModes out;
  const int elastic = options.elastic_count;
  bool found = false;
  if ((options.count > 0 || elastic > 0) && n > 100) {
    // Rigid-body modes come first: ask for more until enough modes are elastic; past half
    // the model a dense solve is cheaper.
    for (int ask = elastic > 0 ? elastic + 12 : options.count; 2 * ask < n; ask *= 2) {
      out = sparse_modes(model, k_lin, ask, -1e-6 * scale);
      out.rigid_count = rigid_count(out);
      if (out.size() - out.rigid_count >= elastic) {
        found = true;
        break;
      }
    }
  }
  if (!found) {
    out = dense_modes(model.mass, k_lin);
    out.rigid_count = rigid_count(out);
  }
  // Each eigenvalue as the Rayleigh quotient summed element by element: second order in
  // the shape's error and free of the cancellation a stiff joint brings to phi^T K_lin phi.
  for (int i = 0; i < out.size(); ++i) out.omega2(i) = strain_energy(model, out.shapes.col(i));
  // Indefinite: a shape with negative strain energy beyond rounding.
  if (out.size() > 0 && out.omega2.minCoeff() < -threshold) {
    throw InputError(fmt::format(
        "linear modes: the stiffness matrix with joints at linear stiffness is not positive "
        "semidefinite (eigenvalue omega^2 = {:.6g} rad^2/s^2)",
        out.omega2.minCoeff()));
  }
  // Rayleigh quotients out of order (beyond rounding of the reduced problem) or not finite:
  // the solve lost the structure to rounding, as a joint far stiffer than the structure can
  // make it. Refused rather than reported as modes.
  for (int i = 1; i < out.size(); ++i) {
    if (!std::isfinite(out.omega2(i)) ||
        out.omega2(i) < out.omega2(i - 1) * (1 - 1e-6) - threshold) {
      throw InputError(fmt::format(
          "linear modes: the modes are not resolved (omega^2 of mode {} is {:.6g} rad^2/s^2, "
          "below the {:.6g} of the one before): the stiffest joint ({:.3g} N/m) leaves K_lin "
          "too ill-conditioned; a penalty stiffness 1e6 times the structure's is rigid to 6 "
          "digits",
          i + 1, out.omega2(i), out.omega2(i - 1), model.stiffest_joint()));
    }
  }
  int keep = out.size();
  if (elastic > 0) {
    keep = std::min(out.size(), out.rigid_count + elastic);
  } else if (options.count > 0) {
    keep = std::min(out.size(), options.count);
  }
  out.omega2.conservativeResize(keep);
  out.shapes.conservativeResize(Eigen::NoChange, keep);
  out.rigid_count = std::min(out.rigid_count, keep);
  for (int i = 0; i < out.rigid_count; ++i) out.omega2(i) = 0.0;
  for (int i = 0; i < keep; ++i) {
    Eigen::Index at;
    out.shapes.col(i).cwiseAbs().maxCoeff(&at);
    if (out.shapes(at, i) < 0) out.shapes.col(i) *= -1.0;
  }
  return out;
}

}  // namespace jointlab::model
