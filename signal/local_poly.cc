#include "jointlab/signal/local_poly.h"

#include <cassert>
#include <cmath>

#include <Eigen/Dense>

namespace jointlab::signal {

namespace {
constexpr int kMaxColumns = 8;
using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxColumns, kMaxColumns>;
using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxColumns, 1>;
}  // namespace

LocalFit fit_local(const Eigen::Ref<const Eigen::VectorXd>& y, double t_first, double dt,
                   double centre, double half_width, int degree, double correlation,
                   Eigen::Index stride) {
  const Eigen::Index i0 = std::max<Eigen::Index>(
      0, static_cast<Eigen::Index>(std::ceil((centre - half_width - t_first) / dt)));
  const Eigen::Index i1 = std::min<Eigen::Index>(
      y.size() - 1, static_cast<Eigen::Index>(std::floor((centre + half_width - t_first) / dt)));
  assert(stride >= 1);
  const Eigen::Index n = (i1 - i0) / stride + 1;
  const int p = degree + 2;  // columns for the degree+1 fit
  assert(n >= degree + 3 && p <= kMaxColumns);

  // Normal equations from power sums: (X'WX)_jk = sum w tau^(j+k), likewise
  // X'W^2X and X'Wy. Scalar loops with no heap traffic: this runs thousands of
  // times per backbone.
  double s1[2 * kMaxColumns] = {}, s2w[2 * kMaxColumns] = {}, sy[kMaxColumns] = {};
  for (Eigen::Index i = 0; i < n; ++i) {
    const double tau = (t_first + static_cast<double>(i0 + i * stride) * dt - centre) / half_width;
    const double u = std::max(0.0, 1.0 - tau * tau);
    const double w = u * u;
    const double wy = w * y(i0 + i * stride);
    double pw = 1.0;
    for (int m = 0; m < 2 * p - 1; ++m) {
      s1[m] += w * pw;
      s2w[m] += w * w * pw;
      if (m < p) sy[m] += wy * pw;
      pw *= tau;
    }
  }
  Small A(p, p), M(p, p);
  SmallVec rhs(p);
  for (int j = 0; j < p; ++j) {
    rhs(j) = sy[j];
    for (int k = 0; k < p; ++k) {
      A(j, k) = s1[j + k];
      M(j, k) = s2w[j + k];
    }
  }
  LocalFit out;
  out.samples = static_cast<int>(n);

  const int q = degree + 1;
  const Small Aq = A.topLeftCorner(q, q);
  const Eigen::LDLT<Small> ldlt(Aq);
  const SmallVec beta = ldlt.solve(rhs.head(q));
  // Weighted residual sum of squares from a second pass (numerically safer than
  // expanding y'Wy - beta'X'Wy for nearly exact fits).
  double sw = 0, swr2 = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double tau = (t_first + static_cast<double>(i0 + i * stride) * dt - centre) / half_width;
    const double u = std::max(0.0, 1.0 - tau * tau);
    const double w = u * u;
    double fit = 0, pw = 1.0;
    for (int j = 0; j < q; ++j) {
      fit += beta(j) * pw;
      pw *= tau;
    }
    const double r = y(i0 + i * stride) - fit;
    sw += w;
    swr2 += w * r * r;
  }
  const double s2 = swr2 / sw;
  const Small Ainv = ldlt.solve(Small::Identity(q, q));
  const Small cov = Ainv * M.topLeftCorner(q, q) * Ainv * (s2 * correlation);

  out.value = beta(0);
  out.value_std = std::sqrt(std::max(0.0, cov(0, 0)));
  out.slope = beta(1) / half_width;
  out.slope_std = std::sqrt(std::max(0.0, cov(1, 1))) / half_width;
  out.residual_rms = std::sqrt(s2);

  const SmallVec beta2 = Eigen::LDLT<Small>(A).solve(rhs);
  out.slope_change = std::abs(beta2(1) - beta(1)) / half_width;
  out.value_change = std::abs(beta2(0) - beta(0));
  return out;
}

}  // namespace jointlab::signal
