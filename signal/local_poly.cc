#include "jointlab/signal/local_poly.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

#include <Eigen/Dense>

namespace jointlab::signal {

namespace {

// Fits K series that share one grid and window: the powers, weights, normal
// matrices and their factorisations are computed once for all of them.
// Q = degree + 1 columns is a compile-time size, so the small matrix algebra
// below is unrolled fixed-size Eigen code. The model-error estimates refit at
// degree + 1 for the value and degree + 2 for the slope: in a symmetric window
// the slope at the centre is set by the odd powers alone, so adding one even
// power leaves it unchanged and says nothing about its bias.
template <int K, int Q>
std::array<LocalFit, K> fit_local_series(const std::array<const Eigen::VectorXd*, K>& ys,
                                         double t_first, double dt, double centre,
                                         double half_width, double correlation, Eigen::Index stride,
                                         double offset) {
  constexpr int q = Q;      // columns of the fit
  constexpr int p = Q + 2;  // columns of the largest refit
  using VecQ = Eigen::Matrix<double, q, 1>;
  using MatQ = Eigen::Matrix<double, q, q>;
  using VecQ1 = Eigen::Matrix<double, q + 1, 1>;
  using MatP = Eigen::Matrix<double, p, p>;
  using VecP = Eigen::Matrix<double, p, 1>;
  const Eigen::Index size = ys[0]->size();
  const Eigen::Index i0 = std::max<Eigen::Index>(
      0, static_cast<Eigen::Index>(std::ceil((centre - half_width - t_first) / dt)));
  const Eigen::Index i1 = std::min<Eigen::Index>(
      size - 1, static_cast<Eigen::Index>(std::floor((centre + half_width - t_first) / dt)));
  assert(stride >= 1);
  const Eigen::Index n = (i1 - i0) / stride + 1;
  assert(n >= p);
  const double inv_h = 1.0 / half_width;
  const auto tau_of = [&](Eigen::Index i) {
    return (t_first + static_cast<double>(i0 + i * stride) * dt - centre) * inv_h;
  };

  // Normal equations from power sums: (X'WX)_jk = sum w tau^(j+k), likewise X'W^2X and
  // X'Wy. Two samples at a time in one SSE2 register pair (GCC vector extension), and
  // passes with few enough running sums to stay in registers: one pass over all 30 sums,
  // one sample at a time, spilled them and waited on each power's multiply.
  using V2 = double __attribute__((vector_size(16)));
  const auto pair_at = [n](Eigen::Index i, auto value) {  // samples i, i + 1 (0 past n)
    const V2 v = {value(i), i + 1 < n ? value(i + 1) : 0.0};
    return v;
  };
  const auto weight = [&](Eigen::Index i) {
    const double tau = tau_of(i);
    const double u = std::max(0.0, 1.0 - tau * tau);
    return u * u;
  };
  double s1[2 * p - 1], s2w[2 * q - 1], sy[K][p];
  {
    V2 acc[2 * p - 1] = {};
    for (Eigen::Index i = 0; i < n; i += 2) {
      const V2 tau = pair_at(i, tau_of);
      V2 pw = pair_at(i, weight);
      for (int m = 0; m < 2 * p - 1; ++m) {
        acc[m] += pw;
        pw *= tau;
      }
    }
    for (int m = 0; m < 2 * p - 1; ++m) s1[m] = acc[m][0] + acc[m][1];
  }
  // w^2 tau^m = w tau^m (1 - tau^2)^2: the sums of X'W^2X are those of X'WX combined (the
  // highest, m + 4 = 2p - 2, is there), no pass of their own.
  for (int m = 0; m < 2 * q - 1; ++m) s2w[m] = s1[m] - 2 * s1[m + 2] + s1[m + 4];
  // Two series a pass: more running sums would spill.
  for (int k0 = 0; k0 < K; k0 += 2) {
    const int k1 = std::min(K, k0 + 2);
    V2 acc[K][p] = {};
    for (Eigen::Index i = 0; i < n; i += 2) {
      const V2 tau = pair_at(i, tau_of);
      const V2 w = pair_at(i, weight);
      V2 pw[K];
      for (int k = k0; k < k1; ++k) {
        pw[k] = w * pair_at(i, [&](Eigen::Index j) { return (*ys[k])(i0 + j * stride); });
      }
      for (int m = 0; m < p; ++m) {
        for (int k = k0; k < k1; ++k) {
          acc[k][m] += pw[k];
          pw[k] *= tau;
        }
      }
    }
    for (int k = k0; k < k1; ++k)
      for (int m = 0; m < p; ++m) sy[k][m] = acc[k][m][0] + acc[k][m][1];
  }
  // One Cholesky factor of the largest normal matrix holds those of the smaller fits in its
  // leading blocks (no pivoting: the weighted power sums of a window of at least p samples
  // are positive definite). Where rounding makes it fail, the pivoted LDLT decides.
  MatP A;
  for (int j = 0; j < p; ++j) {
    for (int c = 0; c < p; ++c) A(j, c) = s1[j + c];
  }
  MatQ M;
  for (int j = 0; j < q; ++j) {
    for (int c = 0; c < q; ++c) M(j, c) = s2w[j + c];
  }
  const Eigen::LLT<MatP> llt(A);
  // Solves the leading r x r block's system for b.
  const auto solve = [&](auto b) {
    constexpr int r = decltype(b)::RowsAtCompileTime;
    if (llt.info() == Eigen::Success) {
      const auto L = llt.matrixLLT().template topLeftCorner<r, r>();
      L.template triangularView<Eigen::Lower>().solveInPlace(b);
      L.template triangularView<Eigen::Lower>().transpose().solveInPlace(b);
      return b;
    }
    using Mat = Eigen::Matrix<double, r, r>;
    return decltype(b)(Eigen::LDLT<Mat>(A.template topLeftCorner<r, r>()).solve(b));
  };
  // Value and slope at tau0 = offset: g_v' beta and g_s' beta / h.
  const auto basis = [offset](auto& gv, auto& gs) {
    gv.setZero();
    gs.setZero();
    double pw = 1.0;
    for (int j = 0; j < gv.size(); ++j) {
      gv(j) = pw;
      if (j + 1 < gv.size()) gs(j + 1) = (j + 1) * pw;
      pw *= offset;
    }
  };
  VecQ gv, gs;
  VecQ1 gv1, gs1;
  VecP gv2, gs2;
  basis(gv, gs);
  basis(gv1, gs1);
  basis(gv2, gs2);
  // Sandwich quadratic forms g' A^-1 M A^-1 g from one solve per g.
  const VecQ av = solve(gv), as = solve(gs);
  const double var_value = av.dot(M * av), var_slope = as.dot(M * as);

  std::array<VecQ, K> beta;
  for (int k = 0; k < K; ++k) beta[k] = solve(VecQ(Eigen::Map<const VecQ>(sy[k])));
  // Weighted residual sums of squares from a pass of their own (numerically safer than
  // expanding y'Wy - beta'X'Wy for nearly exact fits), two samples at a time like the sums
  // (the pair past an odd count has weight 0).
  V2 sum_w = {}, sum_wr2[K] = {};
  for (Eigen::Index i = 0; i < n; i += 2) {
    const V2 tau = pair_at(i, tau_of);
    const V2 w = pair_at(i, weight);
    sum_w += w;
    for (int k = 0; k < K; ++k) {
      V2 fit = {beta[k](q - 1), beta[k](q - 1)};
      for (int j = q - 2; j >= 0; --j) fit = fit * tau + beta[k](j);
      const V2 r = pair_at(i, [&](Eigen::Index l) { return (*ys[k])(i0 + l * stride); }) - fit;
      sum_wr2[k] += w * r * r;
    }
  }
  const double sw = sum_w[0] + sum_w[1];
  double swr2[K];
  for (int k = 0; k < K; ++k) swr2[k] = sum_wr2[k][0] + sum_wr2[k][1];
  std::array<LocalFit, K> out;
  for (int k = 0; k < K; ++k) {
    const double s2 = swr2[k] / sw;
    const double scale = s2 * correlation;
    LocalFit& f = out[k];
    f.samples = static_cast<int>(n);
    f.value = gv.dot(beta[k]);
    f.value_std = std::sqrt(std::max(0.0, var_value * scale));
    f.slope = gs.dot(beta[k]) / half_width;
    f.slope_std = std::sqrt(std::max(0.0, var_slope * scale)) / half_width;
    f.residual_rms = std::sqrt(s2);
    const VecQ1 beta1 = solve(VecQ1(Eigen::Map<const VecQ1>(sy[k])));
    const VecP beta2 = solve(VecP(Eigen::Map<const VecP>(sy[k])));
    f.slope_change = std::abs(gs2.dot(beta2) - gs.dot(beta[k])) / half_width;
    f.value_change = std::abs(gv1.dot(beta1) - f.value);
  }
  return out;
}

// Runtime degree -> compile-time column count.
template <int K>
std::array<LocalFit, K> dispatch(const std::array<const Eigen::VectorXd*, K>& ys, double t_first,
                                 double dt, double centre, double half_width, int degree,
                                 double correlation, Eigen::Index stride, double offset) {
  // fit_local_series for Q = degree + 1 columns, degree 1 to 5.
  constexpr std::array fits{&fit_local_series<K, 2>, &fit_local_series<K, 3>,
                            &fit_local_series<K, 4>, &fit_local_series<K, 5>,
                            &fit_local_series<K, 6>};
  if (degree < 1 || degree > static_cast<int>(fits.size())) {
    assert(false && "degree must be 1 to 5");
    return {};
  }
  return fits[static_cast<size_t>(degree - 1)](ys, t_first, dt, centre, half_width, correlation,
                                               stride, offset);
}

}  // namespace

LocalFit fit_local(const Eigen::Ref<const Eigen::VectorXd>& y, double t_first, double dt,
                   double centre, double half_width, int degree, double correlation,
                   Eigen::Index stride, double offset) {
  assert(std::abs(offset) <= 1.0);
  const Eigen::VectorXd copy = y;
  return dispatch<1>({&copy}, t_first, dt, centre, half_width, degree, correlation, stride,
                     offset)[0];
}

std::array<LocalFit, 2> fit_local_pair(const Eigen::VectorXd& y1, const Eigen::VectorXd& y2,
                                       double t_first, double dt, double centre, double half_width,
                                       int degree, double correlation, Eigen::Index stride,
                                       double offset) {
  assert(y1.size() == y2.size());
  assert(std::abs(offset) <= 1.0);
  return dispatch<2>({&y1, &y2}, t_first, dt, centre, half_width, degree, correlation, stride,
                     offset);
}

std::array<LocalFit, 4> fit_local_quad(const std::array<const Eigen::VectorXd*, 4>& ys,
                                       double t_first, double dt, double centre, double half_width,
                                       int degree, double correlation, Eigen::Index stride,
                                       double offset) {
  assert(std::all_of(ys.begin(), ys.end(),
                     [&](const Eigen::VectorXd* y) { return y->size() == ys[0]->size(); }));
  assert(std::abs(offset) <= 1.0);
  return dispatch<4>(ys, t_first, dt, centre, half_width, degree, correlation, stride, offset);
}

}  // namespace jointlab::signal
