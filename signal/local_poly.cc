#include "jointlab/signal/local_poly.h"

#include <array>
#include <cassert>
#include <cmath>

#include <Eigen/Dense>

namespace jointlab::signal {

namespace {

// Fits K series that share one grid and window: the powers, weights, normal
// matrices and their factorisations are computed once for all of them.
// P = degree + 2 columns is a compile-time size, so the small matrix algebra
// below is unrolled fixed-size Eigen code.
template <int K, int P>
std::array<LocalFit, K> fit_local_series(const std::array<const Eigen::VectorXd*, K>& ys,
                                         double t_first, double dt, double centre,
                                         double half_width, double correlation,
                                         Eigen::Index stride) {
  constexpr int p = P;
  constexpr int q = P - 1;
  using MatP = Eigen::Matrix<double, P, P>;
  using MatQ = Eigen::Matrix<double, q, q>;
  using VecP = Eigen::Matrix<double, P, 1>;
  using VecQ = Eigen::Matrix<double, q, 1>;
  const Eigen::Index size = ys[0]->size();
  const Eigen::Index i0 = std::max<Eigen::Index>(
      0, static_cast<Eigen::Index>(std::ceil((centre - half_width - t_first) / dt)));
  const Eigen::Index i1 = std::min<Eigen::Index>(
      size - 1, static_cast<Eigen::Index>(std::floor((centre + half_width - t_first) / dt)));
  assert(stride >= 1);
  const Eigen::Index n = (i1 - i0) / stride + 1;
  assert(n >= P + 1);

  // Normal equations from power sums: (X'WX)_jk = sum w tau^(j+k), likewise
  // X'W^2X and X'Wy. Scalar loops with no heap traffic: this runs thousands of
  // times per backbone.
  double s1[2 * P] = {}, s2w[2 * P] = {}, sy[K][P] = {};
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index idx = i0 + i * stride;
    const double tau = (t_first + static_cast<double>(idx) * dt - centre) / half_width;
    const double u = std::max(0.0, 1.0 - tau * tau);
    const double w = u * u;
    double wy[K];
    for (int k = 0; k < K; ++k) wy[k] = w * (*ys[k])(idx);
    double pw = 1.0;
    for (int m = 0; m < 2 * p - 1; ++m) {
      s1[m] += w * pw;
      s2w[m] += w * w * pw;
      if (m < p) {
        for (int k = 0; k < K; ++k) sy[k][m] += wy[k] * pw;
      }
      pw *= tau;
    }
  }
  MatP A, M;
  for (int j = 0; j < p; ++j) {
    for (int c = 0; c < p; ++c) {
      A(j, c) = s1[j + c];
      M(j, c) = s2w[j + c];
    }
  }
  const Eigen::LDLT<MatQ> ldlt(A.template topLeftCorner<q, q>());
  const Eigen::LDLT<MatP> ldlt2(A);
  const MatQ Ainv = ldlt.solve(MatQ::Identity());
  const MatQ sandwich = Ainv * M.template topLeftCorner<q, q>() * Ainv;

  std::array<VecQ, K> beta;
  for (int k = 0; k < K; ++k) beta[k] = ldlt.solve(Eigen::Map<const VecQ>(sy[k]));
  // Weighted residual sums of squares from a second pass (numerically safer
  // than expanding y'Wy - beta'X'Wy for nearly exact fits).
  double sw = 0, swr2[K] = {};
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index idx = i0 + i * stride;
    const double tau = (t_first + static_cast<double>(idx) * dt - centre) / half_width;
    const double u = std::max(0.0, 1.0 - tau * tau);
    const double w = u * u;
    sw += w;
    for (int k = 0; k < K; ++k) {
      double fit = 0, pw = 1.0;
      for (int j = 0; j < q; ++j) {
        fit += beta[k](j) * pw;
        pw *= tau;
      }
      const double r = (*ys[k])(idx)-fit;
      swr2[k] += w * r * r;
    }
  }
  std::array<LocalFit, K> out;
  for (int k = 0; k < K; ++k) {
    const double s2 = swr2[k] / sw;
    const double scale = s2 * correlation;
    LocalFit& f = out[k];
    f.samples = static_cast<int>(n);
    f.value = beta[k](0);
    f.value_std = std::sqrt(std::max(0.0, sandwich(0, 0) * scale));
    f.slope = beta[k](1) / half_width;
    f.slope_std = std::sqrt(std::max(0.0, sandwich(1, 1) * scale)) / half_width;
    f.residual_rms = std::sqrt(s2);
    const VecP beta2 = ldlt2.solve(Eigen::Map<const VecP>(sy[k]));
    f.slope_change = std::abs(beta2(1) - beta[k](1)) / half_width;
    f.value_change = std::abs(beta2(0) - beta[k](0));
  }
  return out;
}

// Runtime degree -> compile-time column count.
template <int K>
std::array<LocalFit, K> dispatch(const std::array<const Eigen::VectorXd*, K>& ys, double t_first,
                                 double dt, double centre, double half_width, int degree,
                                 double correlation, Eigen::Index stride) {
  switch (degree) {
    case 1:
      return fit_local_series<K, 3>(ys, t_first, dt, centre, half_width, correlation, stride);
    case 2:
      return fit_local_series<K, 4>(ys, t_first, dt, centre, half_width, correlation, stride);
    case 3:
      return fit_local_series<K, 5>(ys, t_first, dt, centre, half_width, correlation, stride);
    case 4:
      return fit_local_series<K, 6>(ys, t_first, dt, centre, half_width, correlation, stride);
    case 5:
      return fit_local_series<K, 7>(ys, t_first, dt, centre, half_width, correlation, stride);
    default:
      assert(false && "degree must be 1 to 5");
      return {};
  }
}

}  // namespace

LocalFit fit_local(const Eigen::Ref<const Eigen::VectorXd>& y, double t_first, double dt,
                   double centre, double half_width, int degree, double correlation,
                   Eigen::Index stride) {
  const Eigen::VectorXd copy = y;
  return dispatch<1>({&copy}, t_first, dt, centre, half_width, degree, correlation, stride)[0];
}

std::array<LocalFit, 2> fit_local_pair(const Eigen::VectorXd& y1, const Eigen::VectorXd& y2,
                                       double t_first, double dt, double centre, double half_width,
                                       int degree, double correlation, Eigen::Index stride) {
  assert(y1.size() == y2.size());
  return dispatch<2>({&y1, &y2}, t_first, dt, centre, half_width, degree, correlation, stride);
}

}  // namespace jointlab::signal
