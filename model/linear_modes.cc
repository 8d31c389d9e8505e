#include "jointlab/model/linear_modes.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "jointlab/core/error.h"

namespace jointlab::model {

std::string ModesOptions::error() const {
  if (count < 0) return fmt::format("mode count {} must be >= 0", count);
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

}  // namespace jointlab::model
