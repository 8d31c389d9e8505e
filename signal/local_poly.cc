#include "jointlab/signal/local_poly.h"

#include <cassert>
#include <cmath>

#include <Eigen/Dense>

namespace jointlab::signal {

LocalFit fit_local(const Eigen::Ref<const Eigen::VectorXd>& y, double t_first, double dt,
                   double centre, double half_width, int degree, double correlation) {
  const Eigen::Index i0 = std::max<Eigen::Index>(
      0, static_cast<Eigen::Index>(std::ceil((centre - half_width - t_first) / dt)));
  const Eigen::Index i1 = std::min<Eigen::Index>(
      y.size() - 1, static_cast<Eigen::Index>(std::floor((centre + half_width - t_first) / dt)));
  const Eigen::Index n = i1 - i0 + 1;
  const int p = degree + 2;  // columns for the degree+1 fit
  assert(n >= degree + 3);

  Eigen::MatrixXd X(n, p);
  Eigen::VectorXd w(n), yy(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double tau = (t_first + static_cast<double>(i0 + i) * dt - centre) / half_width;
    const double u = std::max(0.0, 1.0 - tau * tau);
    w(i) = u * u;
    double pw = 1.0;
    for (int j = 0; j < p; ++j) {
      X(i, j) = pw;
      pw *= tau;
    }
    yy(i) = y(i0 + i);
  }
  LocalFit out;
  out.samples = static_cast<int>(n);

  const int q = degree + 1;
  const Eigen::MatrixXd Xq = X.leftCols(q);
  const Eigen::MatrixXd A = Xq.transpose() * w.asDiagonal() * Xq;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
  const Eigen::VectorXd beta = ldlt.solve(Xq.transpose() * (w.array() * yy.array()).matrix());
  const Eigen::VectorXd r = yy - Xq * beta;
  const double sw = w.sum();
  const double s2 = (w.array() * r.array().square()).sum() / sw;
  const Eigen::MatrixXd Ainv = ldlt.solve(Eigen::MatrixXd::Identity(q, q));
  const Eigen::MatrixXd meat = Xq.transpose() * w.array().square().matrix().asDiagonal() * Xq;
  const Eigen::MatrixXd cov = Ainv * meat * Ainv * (s2 * correlation);

  out.value = beta(0);
  out.slope = beta(1) / half_width;
  out.slope_std = std::sqrt(std::max(0.0, cov(1, 1))) / half_width;
  out.residual_rms = std::sqrt(s2);

  const Eigen::MatrixXd A2 = X.transpose() * w.asDiagonal() * X;
  const Eigen::VectorXd beta2 = A2.ldlt().solve(X.transpose() * (w.array() * yy.array()).matrix());
  out.slope_change = std::abs(beta2(1) - beta(1)) / half_width;
  return out;
}

}  // namespace jointlab::signal
