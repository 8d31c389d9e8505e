// The Iwan update's linear-part sensitivity: dx/ds = -(J^T J)^-1 J^T dr/ds at the minimum, per
// relative error of mode R's linear frequency.
#include "jointlab/correlate/iwan_sensitivity_detail.h"

#include <cmath>

#include <Eigen/Dense>

#include "jointlab/core/error.h"
#include "jointlab/correlate/iwan_coordinates_detail.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/model/linear_modes.h"

namespace jointlab::correlate::iwan_detail {

bool linear_part_sensitivity(const IwanObjective& objective, const std::vector<int>& free,
                             const Vec4& v, double z, IwanUpdateSummary& s) {
  const int m = objective.residual_count(), nf = static_cast<int>(free.size());
  if (nf == 0 || objective.targets().empty()) return false;
  const double Ks = objective.reference_stiffness();
  const model::IwanParameters p = to_params(v, Ks);
  Eigen::MatrixXd J(m, nf);
  Eigen::VectorXd rp(m), rm(m), dr(m);
  if (!central_differences(
          objective, free, v, z,
          [&](int j, double h, const Eigen::VectorXd& plus, const Eigen::VectorXd& minus) {
            J.col(j) = (plus - minus) / (2 * h);
          }))
    return false;
  const double hs = 1e-4;
  if (!objective.residuals_with_structure_stiffness(p, z, std::exp(hs), rp.data()) ||
      !objective.residuals_with_structure_stiffness(p, z, std::exp(-hs), rm.data())) {
    return false;
  }
  dr = (rp - rm) / (2 * hs);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J);
  if (qr.rank() < nf) return false;
  const Eigen::VectorXd dx = -qr.solve(dr);
  // Mode R's linear frequency at the result's K_T, K scaled each way.
  const int mode = objective.targets().front().mode;
  double ln_f[2];
  for (int side = 0; side < 2; ++side) {
    model::Model mk = objective.apply(p);
    mk.stiffness *= std::exp(side == 0 ? hs : -hs);
    try {
      const model::LinearModes modes = model::linear_modes(mk.mass, mk.linear_stiffness());
      const int col = modes.rigid_count + mode - 1;
      if (col >= modes.size() || !(modes.frequency_hz(col) > 0)) return false;
      ln_f[side] = std::log(modes.frequency_hz(col));
    } catch (const InputError&) {
      return false;
    }
  }
  const double df = (ln_f[0] - ln_f[1]) / (2 * hs);
  if (!(std::abs(df) > 1e-12) || !dx.allFinite()) return false;
  s.linear_part_sensitivity.setZero();
  for (int j = 0; j < nf; ++j) {
    if (free[j] == 4) continue;
    const double per_f = dx(j) / df;
    s.linear_part_sensitivity(free[j]) = free[j] != 2         ? per_f
                                         : std::abs(v(2)) > 0 ? per_f / std::abs(v(2))
                                                              : 0.0;
  }
  s.sensitivity_mode = mode;
  s.frequency_per_stiffness = df;
  return true;
}

}  // namespace jointlab::correlate::iwan_detail
