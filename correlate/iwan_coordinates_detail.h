// The Iwan update's search coordinates (internal): the search vector v = (F_S, gamma, chi, beta),
// K_T = gamma K_s; the coordinates x = (ln F_S, ln gamma, chi, ln beta) the local solve, the
// covariance and the linear part's sensitivity work in; the search box of the options, held
// parameters at their values; and the central differences of the residuals in x.
#pragma once

#include <array>
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/iwan_update.h"

namespace jointlab::correlate::iwan_detail {

/// The search vector v = (F_S, gamma, chi, beta).
using Vec4 = Eigen::Vector4d;

/// The parameters of search vector v (K_T = gamma K_s).
inline model::IwanParameters to_params(const Vec4& v, double Ks) {
  return {v(0), v(1) * Ks, v(2), v(3)};
}

/// A search box: the lower and upper corner of v.
struct Box {
  Vec4 lo, hi;
};

/// Which of (F_S, gamma, chi, beta) the options hold at a given value.
inline std::array<bool, 4> held_parameters(const IwanUpdateOptions& o) {
  return {false, o.fixed_gamma > 0, false, o.fixed_beta.has_value()};
}

/// The search box of the options, held parameters at their values.
inline Box initial_box(const IwanUpdateOptions& o) {
  const IwanBounds& b = o.bounds;
  Box box{Vec4(b.Fs_min, b.gamma_min, b.chi_min, b.beta_min),
          Vec4(b.Fs_max, b.gamma_max, b.chi_max, b.beta_max)};
  if (o.fixed_gamma > 0) box.lo(1) = box.hi(1) = o.fixed_gamma;
  if (o.fixed_beta) box.lo(3) = box.hi(3) = *o.fixed_beta;
  return box;
}

/// x = (ln F_S, ln gamma, chi, ln beta).
inline Vec4 to_x(const Vec4& v) {
  return Vec4(std::log(v(0)), std::log(v(1)), v(2), std::log(v(3)));
}
inline Vec4 to_v(const double* x) {
  return Vec4(std::exp(x[0]), std::exp(x[1]), x[2], std::exp(x[3]));
}

/// The residuals at x +/- h along each free parameter in turn (x = (ln F_S, ln gamma, chi,
/// ln beta), h = 1e-4, as the local solve; Z, index 4, linearly at h = 1e-6), handed to
/// column(j, h, r_plus, r_minus); false where the model cannot be evaluated at one of them. The
/// covariance's slopes and the linear part's sensitivity take the same steps.
template <typename Column>
bool central_differences(const IwanObjective& objective, const std::vector<int>& free,
                         const Vec4& v, double z, Column&& column) {
  const double Ks = objective.reference_stiffness();
  Eigen::VectorXd rp(objective.residual_count()), rm(objective.residual_count());
  const Vec4 x0 = to_x(v);
  for (int j = 0; j < static_cast<int>(free.size()); ++j) {
    const double h = free[j] == 4 ? 1e-6 : 1e-4;
    Vec4 xp = x0, xm = x0;
    double zp = z, zm = z;
    if (free[j] == 4) {
      zp += h, zm -= h;
    } else {
      xp(free[j]) += h, xm(free[j]) -= h;
    }
    if (!objective.residuals_at(to_params(to_v(xp.data()), Ks), zp, rp.data()) ||
        !objective.residuals_at(to_params(to_v(xm.data()), Ks), zm, rm.data()))
      return false;
    column(j, h, rp, rm);
  }
  return true;
}

}  // namespace jointlab::correlate::iwan_detail
