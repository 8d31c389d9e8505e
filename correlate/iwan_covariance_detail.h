// The Iwan update's covariance of the parameters at the result (internal): the HAC sandwich,
// Gauss-Newton, cluster-robust and AR(1) estimates, a kink's one-sided slopes, and Student's t
// for the effective independent points.
#pragma once

#include <array>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/iwan_coordinates_detail.h"
#include "jointlab/correlate/iwan_update.h"

namespace jointlab::correlate::iwan_detail {

/// The residuals' serial correlation as an AR(1) process along each curve (frequency and damping
/// apart), its lag-1 coefficient corrected for what the fit takes out (serial_noise()).
struct SerialNoise {
  double rho = 0;               ///< AR(1) coefficient of the noise, in [0, 0.999] (kMaxRho)
  double variance = 0;          ///< marginal variance of a normalised residual's noise
  double effective_points = 0;  ///< independent points the residuals amount to
  double amplitude_share = 0;   ///< amplitude_share() of the residuals
};

/// The degrees of freedom of the sigmas' Student's t: the effective independent points less the
/// parameters fitted to them (as a regression's n - p); 2 or fewer state no sigma.
inline double t_degrees_of_freedom(double effective_points, int fitted) {
  return effective_points - fitted;
}

/// What one hit alone tells of each parameter (covariance()): per parameter (F_S, K_T, chi,
/// beta) the largest share of its information that one hit's curves carry, 1 - (J^T J)^-1_kk /
/// (J^T J - J_c^T J_c)^-1_kk over the hits c (curves of one source, a hit's channels or modes,
/// taken together; 1 where the others leave it undetermined), and that hit's first curve
/// (0-based; -1 with fewer than two hits, or for a parameter not free). Where one
/// hit carries nearly all of a parameter's information the parameter is that hit's joint's, and
/// no spread of the hits about one another (the cluster covariance) shows how far the joint
/// scattered between hits.
struct CurveShares {
  std::array<double, 4> share{};               ///< the largest one-curve share, per parameter
  std::array<int, 4> curve{{-1, -1, -1, -1}};  ///< the curve that carries it
};

/// Covariance of x = (ln F_S, ln gamma, chi, ln beta[, Z]) at v and the structure's own damping z
/// (ln gamma and ln K_T differ by a constant), over the free parameters `free` (indices 0-3, and 4
/// for a fitted Z); empty when unknown. The larger, variance by variance, of
/// - the HAC sandwich H^-1 S H^-1, H = J^T J (hac_scores: robust to serially correlated
///   residuals along each curve), with its correlations;
/// - Gauss-Newton (J^T J)^-1 / N (residuals are normalised by sigma sqrt(N)) times the reduced
///   chi-square and the residuals' correlation time tau (N / tau independent points), at least
///   times 1 (the stated noise is a floor, never shrunk): steadier than the sandwich for a
///   parameter a few points decide (beta at the knee), and as independent of sampling density;
/// - with G >= 3 curves the cluster-robust H^-1 (G/(G-1) sum_c g_c g_c^T) H^-1, g_c = J_c^T r_c
///   over curve c's residuals: points along one hit's backbone share that hit's offset, so the
///   curves, not the points, are the independent samples;
/// - the parametric AR(1) covariance at the noise's bias-corrected coefficient (serial_noise(),
///   set in *noise): the HAC and tau read the residuals, from which the fit has taken the slow
///   part of the noise. A linearised Monte Carlo (400 seeds) of a 200-point curve of the
///   riveted beam with AR(1) noise: the z-scores' standard deviation for K_T and chi fell from
///   2.4 and 1.9 to 1.5 and 1.3 at rho 0.98 and from 1.4 and 1.3 to 1.1 and 1.0 at rho 0.9,
///   unchanged (0.9-1.0) for independent noise (full fits: docs/update-iwan.md).
/// The whole is then widened by nu / (nu - 2), the variance of Student's t with nu = n_eff - p
/// degrees of freedom (t_degrees_of_freedom()), n_eff the effective number of independent points
/// (Bayley & Hammersley 1946, J. R. Stat. Soc. Suppl. 8:184), p the parameters fitted to them: a
/// sigma estimated from a few effective points is itself uncertain. Where nu <= 2 that variance
/// is infinite and the covariance is empty (the caller says so from noise->effective_points).
/// The hit of each curve (objective.residual_curve()'s numbering, hits from 0) and the first
/// curve of each hit: curves of one source (one processed record or campaign hit: its channels,
/// or its modes) are one hit; a curve without a source is a hit of its own.
std::pair<std::vector<int>, std::vector<int>> curve_hits(const IwanObjective& objective);

Eigen::MatrixXd covariance(const IwanObjective& objective, const std::vector<int>& free,
                           const Vec4& v, double z, double* reduced_chi2, SerialNoise* noise,
                           std::array<bool, 4>* fixed_at_kink, CurveShares* shares = nullptr);

/// Widens cov (covariance()'s, Student's t over s.sigma_degrees_of_freedom already in it) to
/// Student's t over the hits less 1 where scatter between hits explains the misfit
/// (IwanUpdateSummary::scatter_explains_misfit()); never narrows it.
void widen_for_scatter(const IwanUpdateSummary& s, Eigen::MatrixXd& cov);

}  // namespace jointlab::correlate::iwan_detail
