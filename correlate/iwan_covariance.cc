// The Iwan update's covariance of the parameters at the result: serial correlation along the
// curves (HAC, AR(1) noise corrected for what the fit absorbs), clusters per curve, a kink's
// one-sided slopes, and Student's t for the effective independent points.
#include "jointlab/correlate/iwan_covariance_detail.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "jointlab/correlate/iwan_coordinates_detail.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/noise_limits.h"

namespace jointlab::correlate::iwan_detail {
namespace {

// The points of each curve (the index of each point's frequency residual; its damping residual
// follows), ordered by amplitude: the order serial correlation runs in.
std::vector<std::vector<int>> points_by_amplitude(const IwanObjective& objective) {
  const std::vector<int>& curve = objective.residual_curve();
  const std::vector<double>& amp = objective.residual_amplitude();
  const int m = static_cast<int>(curve.size());
  std::vector<std::vector<int>> out;
  for (int begin = 0; begin < m;) {
    int end = begin;
    while (end < m && curve[end] == curve[begin]) ++end;
    std::vector<int>& points = out.emplace_back();
    for (int i = begin; i < end; i += 2) points.push_back(i);
    std::stable_sort(points.begin(), points.end(), [&](int a, int b) { return amp[a] < amp[b]; });
    begin = end;
  }
  return out;
}

// The bandwidth L of hac_scores() and residual_correlation_time() for a curve of n points whose
// residuals have the pooled lag-1 autocorrelation rho: a tenth of the points (a fixed share of
// the amplitude range, the same for the same curve sampled more densely), or Andrews' (1991)
// AR(1) plug-in 1.1447 (alpha n)^(1/3), alpha = 4 rho^2 / ((1 - rho)^2 (1 + rho)^2), where that
// is longer (rho at most 0.97, L at most n / 2): ten lags of noise correlated with rho 0.8 along
// 30 points outlast a tenth of them, and chi's stated sigma came out 0.64 of its spread.
int hac_lags(int n, double rho) {
  const double r = std::clamp(rho, 0.0, 0.97);
  const double alpha = 4 * r * r / ((1 - r) * (1 - r) * (1 + r) * (1 + r));
  const int andrews = static_cast<int>(std::ceil(1.1447 * std::cbrt(alpha * n)));
  return std::max(std::max(1, static_cast<int>(std::ceil(n / 10.0))), std::min(andrews, n / 2));
}

// The pooled lag-1 autocorrelation of the frequency and damping residuals along each curve
// ordered by amplitude.
double lag_one_correlation(const std::vector<std::vector<int>>& curves, const Eigen::VectorXd& r) {
  double c0 = 0, c1 = 0;
  for (const std::vector<int>& points : curves) {
    const int n = static_cast<int>(points.size());
    for (int part = 0; part < 2; ++part) {
      for (int t = 0; t < n; ++t) c0 += r(points[t] + part) * r(points[t] + part);
      for (int t = 1; t < n; ++t) c1 += r(points[t] + part) * r(points[t - 1] + part);
    }
  }
  return c0 > 0 ? c1 / c0 : 0.0;
}

// Each curve's points ordered by amplitude (points_by_amplitude) and its bandwidth (hac_lags at
// the residuals' pooled lag-1 autocorrelation): made once for the residuals at the result, for
// every Jacobian that covariance() weighs with them.
struct SerialOrder {
  std::vector<std::vector<int>> curves;
  std::vector<int> lags;  // per curve
};

SerialOrder serial_order(const IwanObjective& objective, const Eigen::VectorXd& r) {
  SerialOrder out{points_by_amplitude(objective), {}};
  const double rho = lag_one_correlation(out.curves, r);
  for (const std::vector<int>& points : out.curves)
    out.lags.push_back(hac_lags(static_cast<int>(points.size()), rho));
  return out;
}

// Newey-West (HAC) estimate of S = Var(sum of scores) for residuals r with Jacobian J: each
// curve's points ordered by amplitude, the score of a point g_t = J_t^T r_t over its frequency
// and damping residuals, S = sum over curves of sum_t g_t g_t^T + sum_{l=1..L} w_l (g_t g_{t-l}^T
// + g_{t-l} g_t^T), Bartlett weights w_l = 1 - l / (L + 1), L the curve's hac_lags(): at least
// a tenth of its points, a fixed share of the amplitude range, so the same curve sampled ten
// times more densely covers the same correlation length and gives the same S, where the points of
// a curve come from overlapping local fits and model-form error runs in long waves (method.md
// section 2 point 5).
Eigen::MatrixXd hac_scores(const SerialOrder& order, const Eigen::MatrixXd& J,
                           const Eigen::VectorXd& r) {
  const Eigen::Index nf = J.cols();
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(nf, nf);
  for (size_t c = 0; c < order.curves.size(); ++c) {
    const std::vector<int>& points = order.curves[c];
    const int n = static_cast<int>(points.size());
    Eigen::MatrixXd g(nf, n);
    for (int t = 0; t < n; ++t) {
      const int i = points[t];
      g.col(t) = J.row(i).transpose() * r(i) + J.row(i + 1).transpose() * r(i + 1);
    }
    const int lags = order.lags[c];
    S += g * g.transpose();
    for (int l = 1; l <= lags && l < n; ++l) {
      const double w = 1.0 - l / (lags + 1.0);
      const Eigen::MatrixXd G = g.rightCols(n - l) * g.leftCols(n - l).transpose();
      S += w * (G + G.transpose());
    }
  }
  return S;
}

// Integrated autocorrelation time of the residuals along the curves, tau = 1 + 2 sum_{l=1..L}
// w_l rho_l (Bartlett weights and the bandwidth of hac_scores), rho_l the lag-l autocorrelation
// of the frequency and of the damping residuals of each curve ordered by amplitude, pooled: N /
// tau is the effective number of independent points. The same curve sampled ten times more
// densely has tau about ten times larger, so Gauss-Newton times tau does not depend on density.
double residual_correlation_time(const SerialOrder& order, const Eigen::VectorXd& r) {
  double c0 = 0, sum = 0;
  for (size_t c = 0; c < order.curves.size(); ++c) {
    const std::vector<int>& points = order.curves[c];
    const int n = static_cast<int>(points.size());
    const int lags = order.lags[c];
    for (int part = 0; part < 2; ++part) {  // frequency, damping
      for (int t = 0; t < n; ++t) c0 += r(points[t] + part) * r(points[t] + part);
      for (int l = 1; l <= lags && l < n; ++l) {
        double c = 0;
        for (int t = l; t < n; ++t) c += r(points[t] + part) * r(points[t - l] + part);
        sum += 2 * (1.0 - l / (lags + 1.0)) * c;
      }
    }
  }
  return c0 > 0 ? 1 + sum / c0 : 1.0;
}

constexpr double kMaxRho = 0.999;

// Sigma(rho) X for the AR(1) correlation Sigma_ij = rho^|i-j| within each sequence (a curve's
// frequency residuals, or its damping residuals, ordered by amplitude) and 0 across them: a
// forward and a backward recursion, O(rows) per column.
Eigen::MatrixXd ar1_times(const SerialOrder& order, const Eigen::MatrixXd& X, double rho) {
  Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(X.rows(), X.cols());
  for (const std::vector<int>& points : order.curves) {
    const int n = static_cast<int>(points.size());
    for (int part = 0; part < 2; ++part) {
      Eigen::RowVectorXd acc = Eigen::RowVectorXd::Zero(X.cols());
      for (int t = 0; t < n; ++t) {  // sum_{s <= t} rho^(t-s) x_s
        acc = rho * acc + X.row(points[t] + part);
        Y.row(points[t] + part) += acc;
      }
      acc.setZero();
      for (int t = n - 1; t >= 0; --t) {  // sum_{s > t} rho^(s-t) x_s
        Y.row(points[t] + part) += rho * acc;
        acc = rho * acc + X.row(points[t] + part);
      }
    }
  }
  return Y;
}

// W X for the Bartlett weights of hac_scores(): W_ij = 1 - |i-j| / (L+1) within a sequence for
// |i-j| <= L (the curve's bandwidth), else 0; r^T W r / r^T r is residual_correlation_time().
Eigen::MatrixXd bartlett_times(const SerialOrder& order, const Eigen::MatrixXd& X) {
  Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(X.rows(), X.cols());
  for (size_t c = 0; c < order.curves.size(); ++c) {
    const std::vector<int>& points = order.curves[c];
    const int n = static_cast<int>(points.size()), lags = order.lags[c];
    for (int part = 0; part < 2; ++part) {
      for (int t = 0; t < n; ++t) {
        const int i = points[t] + part;
        Y.row(i) += X.row(i);
        for (int l = 1; l <= lags && l <= t; ++l) {
          const int j = points[t - l] + part;
          const double w = 1.0 - l / (lags + 1.0);
          Y.row(i) += w * X.row(j);
          Y.row(j) += w * X.row(i);
        }
      }
    }
  }
  return Y;
}

// trace(W Sigma(rho)) = sum over sequences of n + 2 sum_{l=1..L} w_l rho^l (n - l).
double bartlett_ar1_trace(const SerialOrder& order, double rho) {
  double sum = 0;
  for (size_t c = 0; c < order.curves.size(); ++c) {
    const int n = static_cast<int>(order.curves[c].size()), lags = order.lags[c];
    double s = n, power = 1;
    for (int l = 1; l <= lags && l < n; ++l) {
      power *= rho;
      s += 2 * (1.0 - l / (lags + 1.0)) * power * (n - l);
    }
    sum += 2 * s;  // frequency and damping
  }
  return sum;
}

// The noise behind residuals r = (I - P) e at the result, P the projection onto the columns of
// J, taken as an AR(1) process of coefficient rho and variance s2 along each sequence:
// E[r r^T] = s2 M(rho), M = (I - P) Sigma(rho) (I - P). The fit absorbs the slow part of the
// noise, so the residuals' correlation time tau (residual_correlation_time(), r^T W r / r^T r)
// understates the noise's: on a 200-point curve with noise of rho 0.98 (correlation time 99)
// the residuals gave tau 25 and a lag-1 coefficient 0.953, and the sigmas of K_T and chi came out
// about half their spread. rho is instead the coefficient whose expected statistic under the
// fit's projection equals the observed one, tr(W M(rho)) / tr(M(rho)) = tau: indirect
// inference (Gourieroux, Monfort & Renault 1993, J. Appl. Econometrics 8:S85), the
// bias correction of Andrews (1993, Econometrica 61:139) for the AR(1) coefficient of
// regression residuals, here on the Bartlett statistic rather than lag 1, so that a curve
// interpolated between fewer independent points (lag-1 correlation near 1, correlation gone
// after the interpolation's span) is read by its correlation time, not its lag-1 coefficient.
// s2 = r^T r / tr(M(rho)) (unbiased under the model; the Gauss-Newton estimate keeps the stated
// noise as a floor). The effective number of independent points is that of the mean of each
// sequence, n^2 / (1^T Sigma 1) (Bayley & Hammersley 1946, J. R. Stat. Soc. Suppl. 8:184),
// summed: n (1 - rho) / (1 + rho) for long sequences, at least 1 per sequence.
// With Q an orthonormal basis of J and C = Q^T Sigma Q: tr(M) = m - tr(C) and tr(W M) =
// tr(W Sigma) - 2 tr((Sigma Q)^T W Q) + tr(Q^T W Q C), each O(m) per column.
SerialNoise serial_noise(const SerialOrder& order, const Eigen::MatrixXd& J,
                         const Eigen::VectorXd& r, double tau) {
  SerialNoise out;
  const Eigen::Index m = J.rows();
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(J).householderQ() *
                            Eigen::MatrixXd::Identity(m, J.cols());
  const Eigen::MatrixXd WQ = bartlett_times(order, Q);
  const Eigen::MatrixXd QWQ = Q.transpose() * WQ;
  // The expected statistic tr(W M) / tr(M) at rho, and tr(M).
  const auto expected = [&](double rho) {
    const Eigen::MatrixXd SQ = ar1_times(order, Q, rho);
    const Eigen::MatrixXd C = Q.transpose() * SQ;
    const double trace_m = static_cast<double>(m) - C.trace();
    const double trace_wm =
        bartlett_ar1_trace(order, rho) - 2 * SQ.cwiseProduct(WQ).sum() + QWQ.cwiseProduct(C).sum();
    return std::pair<double, double>(trace_m > 0 ? trace_wm / trace_m : 0.0, trace_m);
  };
  double lo = 0, hi = kMaxRho;
  if (expected(lo).first >= tau) {
    hi = 0;
  } else if (expected(hi).first <= tau) {
    lo = kMaxRho;
  } else {
    for (int it = 0; it < 50; ++it) {
      const double mid = 0.5 * (lo + hi);
      (expected(mid).first < tau ? lo : hi) = mid;
    }
  }
  out.rho = 0.5 * (lo + hi);
  const double trace_m = expected(out.rho).second;
  out.variance = trace_m > 0 ? r.squaredNorm() / trace_m : 0.0;
  const Eigen::VectorXd sums = ar1_times(order, Eigen::VectorXd::Ones(m), out.rho);
  for (const std::vector<int>& points : order.curves) {
    const double n = static_cast<double>(points.size());
    for (int part = 0; part < 2; ++part) {
      double total = 0;  // 1^T Sigma 1 over the sequence
      for (const int i : points) total += sums(i + part);
      out.effective_points += total > 0 ? n * n / total : 0.0;
    }
  }
  return out;
}

// The largest share of r^T r that one third of the points holds, each curve's points (in order of
// amplitude) cut in thirds and the thirds pooled over curves: about 1/3 for residuals spread
// evenly over the amplitudes, as noise is; a model's misfit gathers where the model bends wrong.
double amplitude_share(const SerialOrder& order, const Eigen::VectorXd& r) {
  double third[3] = {0, 0, 0};
  for (const std::vector<int>& points : order.curves) {
    const size_t n = points.size();
    for (size_t t = 0; t < n; ++t) {
      const int i = points[t];
      third[std::min<size_t>(2, 3 * t / n)] += r(i) * r(i) + r(i + 1) * r(i + 1);
    }
  }
  const double total = third[0] + third[1] + third[2];
  return total > 0 ? std::max({third[0], third[1], third[2]}) / total : 0.0;
}

// The cluster-robust covariance with each curve's residuals corrected for what the fit takes of
// them (CR2, Bell & McCaffrey 2002): H^-1 (sum_c a_c a_c^T) H^-1, a_c = J_c^T (I - P_cc)^(-1/2)
// r_c, P_cc = J_c H^-1 J_c^T the curve's own leverage. A curve that carries most of a
// parameter's information has had its residuals fitted away along it (its plain score J_c^T r_c
// is near 0 there), so the plain cluster covariance cannot see how far that hit's joint differs
// from the others'; the correction gives it back, and under independent noise the estimate is
// unbiased (the delete-one-curve jackknife, CR3, raised chi's variance 2.5-fold there: three
// hits at rising levels, no scatter, chi's z-scores' RMS 0.54 against 0.86). With J_c = U S
// V^T (thin SVD) and M = S V^T H^-1 V S, a_c = V S (I - M)^(-1/2) U^T r_c; M's eigenvalues are
// capped at 0.99 (a curve with all of a direction's information: that parameter rests on one
// curve, CurveShares, and states no sigma). The clusters are the hits (cluster: each residual's),
// not the curves: two channels or modes of one hit share its joint.
Eigen::MatrixXd curve_cr2(const std::vector<int>& cluster, int n_clusters, const Eigen::MatrixXd& J,
                          const Eigen::VectorXd& r, const Eigen::MatrixXd& Hi) {
  const int nf = static_cast<int>(J.cols());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(nf, n_clusters);
  for (int c = 0; c < n_clusters; ++c) {
    std::vector<int> rows;
    for (int i = 0; i < static_cast<int>(J.rows()); ++i)
      if (cluster[static_cast<size_t>(i)] == c) rows.push_back(i);
    Eigen::MatrixXd Jc(static_cast<Eigen::Index>(rows.size()), nf);
    Eigen::VectorXd rc(static_cast<Eigen::Index>(rows.size()));
    for (size_t i = 0; i < rows.size(); ++i) {
      Jc.row(static_cast<Eigen::Index>(i)) = J.row(rows[i]);
      rc(static_cast<Eigen::Index>(i)) = r(rows[i]);
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Jc, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::MatrixXd VS = svd.matrixV() * svd.singularValues().asDiagonal();
    const Eigen::MatrixXd M = VS.transpose() * Hi * VS;
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
    Eigen::VectorXd f(eig.eigenvalues().size());
    for (Eigen::Index e = 0; e < f.size(); ++e)
      f(e) = 1 / std::sqrt(1 - std::clamp(eig.eigenvalues()(e), 0.0, 0.99));
    const Eigen::MatrixXd root =
        eig.eigenvectors() * f.asDiagonal() * eig.eigenvectors().transpose();
    a.col(c) = VS * (root * (svd.matrixU().transpose() * rc));
  }
  return Hi * (a * a.transpose()) * Hi;
}

// The covariance of covariance() (below) from one Jacobian J of the residuals r; none when J^T J
// is singular.
std::optional<Eigen::MatrixXd> sandwich(const IwanObjective& objective, const SerialOrder& order,
                                        const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                                        double n_points, double reduced_chi2, double tau,
                                        const SerialNoise& noise,
                                        const Eigen::MatrixXd* pseudo_inverse = nullptr) {
  const Eigen::MatrixXd H = J.transpose() * J;
  Eigen::MatrixXd Hi;
  if (pseudo_inverse) {
    Hi = *pseudo_inverse;
  } else {
    Eigen::FullPivLU<Eigen::MatrixXd> lu(H);
    if (!lu.isInvertible()) return std::nullopt;
    Hi = lu.inverse();
  }
  const Eigen::MatrixXd gauss_newton = Hi / n_points * std::max(1.0, reduced_chi2 * tau);
  // The parametric AR(1) covariance s2 H^-1 J^T Sigma(rho) J H^-1 at the bias-corrected rho
  // (serial_noise()).
  const Eigen::MatrixXd ar1 =
      noise.variance * Hi * (J.transpose() * ar1_times(order, J, noise.rho)) * Hi;
  Eigen::MatrixXd robust = Hi * hac_scores(order, J, r) * Hi;
  // One cluster per hit (curve_hits()): the hits' joints, not the curves, are the independent
  // samples. Three hits read at two channels each gave six curves and sigmas 2.3-2.7 times
  // narrower (F_S +/- 1.95-2.27 % against 4.96-5.20 % from one channel of the same hits).
  const std::vector<int>& curve = objective.residual_curve();
  const int nf = static_cast<int>(J.cols()), m = static_cast<int>(J.rows());
  std::vector<int> hit_of(curve.size());
  int n_hits = 0;
  if (!curve.empty()) {
    const std::vector<int> hit = curve_hits(objective).first;
    const bool matched = curve.back() + 1 == static_cast<int>(hit.size());
    for (size_t i = 0; i < curve.size(); ++i)
      hit_of[i] = matched ? hit[static_cast<size_t>(curve[i])] : curve[i];
    n_hits = *std::max_element(hit_of.begin(), hit_of.end()) + 1;
  }
  if (n_hits >= 3) {
    Eigen::MatrixXd g = Eigen::MatrixXd::Zero(nf, n_hits);
    for (int i = 0; i < m; ++i)
      g.col(hit_of[static_cast<size_t>(i)]) += J.row(i).transpose() * r(i);
    const Eigen::MatrixXd cluster = Hi * (g * g.transpose() * (n_hits / (n_hits - 1.0))) * Hi;
    // Few curves estimate the scatter between them poorly (G - 1 degrees of freedom): the
    // cluster-robust correlations, each variance the larger of the two.
    Eigen::VectorXd d(nf);
    bool usable = true;
    for (int k = 0; k < nf; ++k) {
      usable = usable && cluster(k, k) > 0;
      d(k) = cluster(k, k) > 0 ? std::sqrt(std::max(1.0, robust(k, k) / cluster(k, k))) : 0.0;
    }
    if (usable) robust = d.asDiagonal() * cluster * d.asDiagonal();
  }
  if (n_hits >= 2) {
    // Each hit's joint as the others read it: the cluster covariance with each hit's
    // residuals corrected for its own leverage (curve_cr2()).
    const Eigen::MatrixXd cr2 = curve_cr2(hit_of, n_hits, J, r, Hi);
    for (int k = 0; k < nf; ++k) {
      if (!(robust(k, k) > 0) || !(cr2(k, k) > robust(k, k)) || !std::isfinite(cr2(k, k))) continue;
      const double f = std::sqrt(cr2(k, k) / robust(k, k));
      robust.row(k) *= f;
      robust.col(k) *= f;
    }
  }
  Eigen::VectorXd d(nf);
  for (int k = 0; k < nf; ++k) {
    const double floor = std::max(gauss_newton(k, k), ar1(k, k));
    d(k) = robust(k, k) > 0 ? std::sqrt(std::max(1.0, floor / robust(k, k))) : 0.0;
  }
  Eigen::MatrixXd cov = d.asDiagonal() * robust * d.asDiagonal();
  for (int k = 0; k < nf; ++k)
    if (!(robust(k, k) > 0)) cov(k, k) = std::max(gauss_newton(k, k), ar1(k, k));
  return cov;
}

// The residuals at the result and what every sandwich() over them shares (covariance()).
struct Residuals {
  const IwanObjective& objective;
  const SerialOrder& order;
  const Eigen::VectorXd& r;
  double n_points, reduced_chi2, tau;
};

// The central covariance with each variance raised to a one-sided estimate's (slopes Jf, Jb).
// At a kink of the model (a measured amplitude at phi_max, where the cost's minimum likes to
// sit) the one-sided slopes differ and the central one overstates what the data say: each
// variance is the largest of the central and the two one-sided estimates (7 of 40 three-hit
// fits had phi_max within 2.5e-5 of a measured amplitude in ln q and stated beta's sigma
// 3-4 times too small). Elsewhere the three agree to O(h).
Eigen::MatrixXd widen_at_one_sided(const Residuals& res, const Eigen::MatrixXd& central,
                                   const Eigen::MatrixXd& Jf, const Eigen::MatrixXd& Jb,
                                   const SerialNoise& without_floor) {
  const int nf = static_cast<int>(central.cols());
  Eigen::MatrixXd cov = central;
  for (const Eigen::MatrixXd* one_sided : {&Jf, &Jb}) {
    const std::optional<Eigen::MatrixXd> c =
        sandwich(res.objective, res.order, *one_sided, res.r, res.n_points, res.reduced_chi2,
                 res.tau, without_floor);
    if (!c) continue;
    // Only where a sigma differs by more than 10 %: elsewhere the O(h) differences of the
    // one-sided slopes are no kink and leave the result as it was.
    Eigen::VectorXd d = Eigen::VectorXd::Ones(nf);
    for (int k = 0; k < nf; ++k)
      if (cov(k, k) > 0 && (*c)(k, k) > 1.21 * cov(k, k)) d(k) = std::sqrt((*c)(k, k) / cov(k, k));
    cov = d.asDiagonal() * cov * d.asDiagonal();
  }
  return cov;
}

// Marks the residuals (at_kink) whose secants two stated sigmas (`total`) each way along a free
// Iwan parameter show a kink on one side (covariance()); true when it marked any.
bool mark_kink_rows(const IwanObjective& objective, const std::vector<int>& free, const Vec4& v,
                    double z, const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                    const Eigen::MatrixXd& total, std::vector<bool>& at_kink) {
  const int m = static_cast<int>(J.rows()), nf = static_cast<int>(J.cols());
  const double Ks = objective.reference_stiffness();
  const Vec4 x0 = to_x(v);
  std::vector<double> rp(m), rm(m);
  bool more = false;
  for (int j = 0; j < nf; ++j) {
    if (free[j] == 4) continue;  // Z enters linearly: no kink
    // Only a sigma up to 15 % is probed: a wider one is no pin, and over steps past 30 % in
    // ln (F_S, gamma, beta) or 0.3 in chi the secants of smooth residuals part too (the lap
    // joint's mode 2, whose joint barely moves, stated 26-95 % and was then called fixed at a
    // kink). The six-point table's kink showed at beta's step, 12 %.
    const double h = 2 * std::sqrt(std::max(total(j, j), 0.0));
    if (!(h > 1e-3) || h > 0.3) continue;
    Vec4 xp = x0, xm = x0;
    xp(free[j]) += h;
    xm(free[j]) -= h;
    if (!objective.residuals_at(to_params(to_v(xp.data()), Ks), z, rp.data()) ||
        !objective.residuals_at(to_params(to_v(xm.data()), Ks), z, rm.data())) {
      continue;
    }
    const double scale = J.col(j).cwiseAbs().maxCoeff();
    for (int i = 0; i < m; ++i) {
      const double forward = (rp[i] - r(i)) / h, backward = (r(i) - rm[i]) / h;
      const double larger = std::max(std::abs(forward), std::abs(backward));
      // A kink on one side: that side's secant leaves the slope at the result while the other
      // keeps it; a smooth residual's curvature moves both about equally, one up, one down
      // (chi of a barely slipping one-mode joint, stepped 0.12, was taken for a kink).
      const double off_f = std::abs(forward - J(i, j)), off_b = std::abs(backward - J(i, j));
      const bool one_sided = std::min(off_f, off_b) < 0.3 * std::max(off_f, off_b);
      if (!at_kink[i] && larger > 0.05 * scale && std::abs(forward - backward) > 0.5 * larger &&
          one_sided) {
        at_kink[i] = true;
        more = true;
      }
    }
  }
  return more;
}

// The covariance without the rows at a kink (J's rows where at_kink) raises each variance of cov
// where larger; the parameters along a direction only those rows fix have no sigma
// (fixed_at_kink). False where that covariance cannot be formed.
bool widen_without_kink_rows(const Residuals& res, const Eigen::MatrixXd& J,
                             const std::vector<bool>& at_kink, const SerialNoise& without_floor,
                             const std::vector<int>& free, Eigen::MatrixXd& cov,
                             std::array<bool, 4>* fixed_at_kink) {
  const int m = static_cast<int>(J.rows()), nf = static_cast<int>(J.cols());
  Eigen::MatrixXd Jk = J;
  for (int i = 0; i < m; ++i)
    if (at_kink[i]) Jk.row(i).setZero();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Jk.transpose() * Jk);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  Eigen::MatrixXd pinv = Eigen::MatrixXd::Zero(nf, nf);
  std::vector<bool> undetermined(static_cast<size_t>(nf), false);
  for (int e = 0; e < nf; ++e) {
    const Eigen::VectorXd u = eig.eigenvectors().col(e);
    if (lambda(e) > 1e-10 * lambda(nf - 1)) {
      pinv += u * u.transpose() / lambda(e);
    } else {
      for (int k = 0; k < nf; ++k) undetermined[k] = undetermined[k] || std::abs(u(k)) > 0.05;
    }
  }
  const std::optional<Eigen::MatrixXd> c =
      sandwich(res.objective, res.order, Jk, res.r, res.n_points, res.reduced_chi2, res.tau,
               without_floor, &pinv);
  if (!c || !c->allFinite()) return false;
  Eigen::VectorXd d = Eigen::VectorXd::Ones(nf);
  for (int k = 0; k < nf; ++k) {
    if (undetermined[k] && free[k] < 4) (*fixed_at_kink)[free[k]] = true;
    if (!undetermined[k] && cov(k, k) > 0 && (*c)(k, k) > cov(k, k))
      d(k) = std::sqrt((*c)(k, k) / cov(k, k));
  }
  cov = d.asDiagonal() * cov * d.asDiagonal();
  return true;
}

// CurveShares of the Jacobian J over `free` (rows of curve objective.residual_curve()), by hit
// (curve_hits(): the top hit read at two channels carries F_S as one curve of it does). The
// information matrices are scaled to a unit diagonal and inverted by their eigenvalues, so that
// a flat direction of the rest (microslip hits alone fix F_S and beta only together) leaves
// undetermined only the parameters along it, not K_T and chi beside them.
CurveShares curve_shares(const IwanObjective& objective, const std::vector<int>& free,
                         const Eigen::MatrixXd& J) {
  CurveShares out;
  const std::vector<int>& curve = objective.residual_curve();
  const auto [hit, first] = curve_hits(objective);
  const int n_hits = static_cast<int>(first.size()), nf = static_cast<int>(J.cols());
  if (n_hits < 2 || curve.empty() || curve.back() + 1 != static_cast<int>(hit.size())) return out;
  const Eigen::MatrixXd H0 = J.transpose() * J;
  if (!(H0.diagonal().minCoeff() > 0)) return out;
  const Eigen::VectorXd scale = H0.diagonal().cwiseSqrt().cwiseInverse();
  // The diagonal of the inverse of a scaled information matrix; +inf where a direction with
  // (next to) no information has a share of parameter k.
  const auto variances = [&](const Eigen::MatrixXd& H) {
    const Eigen::MatrixXd Hs = scale.asDiagonal() * H * scale.asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Hs);
    const Eigen::VectorXd& l = eig.eigenvalues();
    const double floor = 1e-12 * std::max(l.maxCoeff(), 0.0);
    Eigen::VectorXd v = Eigen::VectorXd::Zero(nf);
    for (int j = 0; j < nf; ++j) {
      for (int k = 0; k < nf; ++k) {
        const double w = eig.eigenvectors()(k, j) * eig.eigenvectors()(k, j);
        if (w < 1e-12) continue;
        v(k) = l(j) > floor ? v(k) + w / l(j) : INFINITY;
      }
    }
    return v;
  };
  const Eigen::VectorXd whole = variances(H0);
  for (int h = 0; h < n_hits; ++h) {
    Eigen::MatrixXd Hc = Eigen::MatrixXd::Zero(nf, nf);
    for (int i = 0; i < static_cast<int>(J.rows()); ++i)
      if (hit[static_cast<size_t>(curve[i])] == h) Hc += J.row(i).transpose() * J.row(i);
    const Eigen::VectorXd rest = variances(H0 - Hc);
    for (int k = 0; k < nf; ++k) {
      if (free[k] >= 4 || !std::isfinite(whole(k))) continue;
      // The rest's marginal information on parameter k over the whole's (none: undetermined).
      const double kept =
          std::isfinite(rest(k)) && rest(k) > 0 ? std::min(1.0, whole(k) / rest(k)) : 0.0;
      const size_t p = static_cast<size_t>(free[k]);
      if (1 - kept > out.share[p]) {
        out.share[p] = 1 - kept;
        out.curve[p] = first[static_cast<size_t>(h)];
      }
    }
  }
  return out;
}

}  // namespace

std::pair<std::vector<int>, std::vector<int>> curve_hits(const IwanObjective& objective) {
  std::vector<int> hit, first;
  std::map<std::string, int> by_source;
  for (const IwanTarget& t : objective.targets()) {
    for (const MeasuredBackbone& c : t.curves) {
      const int next = static_cast<int>(first.size());
      const int h = c.source.empty() ? next : by_source.emplace(c.source, next).first->second;
      if (h == next) first.push_back(static_cast<int>(hit.size()));
      hit.push_back(h);
    }
  }
  return {hit, first};
}

Eigen::MatrixXd covariance(const IwanObjective& objective, const std::vector<int>& free,
                           const Vec4& v, double z, double* reduced_chi2, SerialNoise* noise,
                           std::array<bool, 4>* fixed_at_kink, CurveShares* shares) {
  fixed_at_kink->fill(false);
  const int m = objective.residual_count(), nf = static_cast<int>(free.size());
  const double Ks = objective.reference_stiffness();
  Eigen::MatrixXd J(m, nf), Jf(m, nf), Jb(m, nf);
  Eigen::VectorXd r(m);
  if (!objective.residuals_at(to_params(v, Ks), z, r.data())) return {};
  const double n_points = m / 2.0;
  *reduced_chi2 = r.squaredNorm() * n_points / std::max(1, m - nf);
  // Central slopes, and the one-sided ones for a kink (below).
  if (!central_differences(
          objective, free, v, z,
          [&](int j, double h, const Eigen::VectorXd& rp, const Eigen::VectorXd& rm) {
            J.col(j) = (rp - rm) / (2 * h);
            Jf.col(j) = (rp - r) / h;
            Jb.col(j) = (r - rm) / h;
          }))
    return {};
  if (shares) *shares = curve_shares(objective, free, J);
  const SerialOrder order = serial_order(objective, r);
  const double tau = residual_correlation_time(order, r);
  *noise = serial_noise(order, J, r, tau);
  noise->amplitude_share = amplitude_share(order, r);
  // The HAC, cluster and Gauss-Newton estimates first, each widened at a kink (below), and the
  // AR(1) floor last: taken inside, a floor that raised the central variance toward a
  // one-sided one could stop that widening and leave a sigma 9 % below what it was without it.
  SerialNoise without_floor = *noise;
  without_floor.variance = 0;
  const Residuals res{objective, order, r, n_points, *reduced_chi2, tau};
  const std::optional<Eigen::MatrixXd> central =
      sandwich(objective, order, J, r, n_points, *reduced_chi2, tau, without_floor);
  if (!central) return {};
  Eigen::MatrixXd cov = widen_at_one_sided(res, *central, Jf, Jb, without_floor);
  const std::optional<double> t =
      student_t_variance(t_degrees_of_freedom(noise->effective_points, nf));
  if (!t) return {};
  // The AR(1) floor, then Student's t: the covariance as stated.
  const auto stated = [&](Eigen::MatrixXd c) -> Eigen::MatrixXd {
    if (const std::optional<Eigen::MatrixXd> floored =
            sandwich(objective, order, J, r, n_points, *reduced_chi2, tau, *noise)) {
      Eigen::VectorXd d = Eigen::VectorXd::Ones(nf);
      for (int k = 0; k < nf; ++k)
        if (c(k, k) > 0 && (*floored)(k, k) > c(k, k)) d(k) = std::sqrt((*floored)(k, k) / c(k, k));
      c = d.asDiagonal() * c * d.asDiagonal();
    }
    return c * *t;
  };
  // A kink within the stated interval. The slopes above are taken 1e-4 from the result; a point
  // whose slip sits a little past phi_max (0.4 % on the lap joint's six-point table below) lies
  // on the steep branch of the damping there, and its slope pins phi_max as if that branch went
  // on, while 0.4 % away the point is back on the shallow branch: the cost then has another
  // minimum, about as low, beyond the slope's reach. So each free Iwan parameter is moved by two
  // of the sigmas as stated, each way; a residual whose two secants differ by more than half
  // the larger, one of them keeping the slope at the result (a smooth one's curvature moves
  // both, about equally) has its information at a kink, and the covariance without those rows'
  // slopes is the larger where larger (repeated at the wider sigmas, at most three times). The
  // six-point table of mode 1 of a 6-rivet steel lap joint up to 2.7 phi_max: F_S 5.4 % off with
  // 0.74 % stated (z -7.3, the point at the kink alone pinning phi_max; the profile of the cost
  // puts one sigma near 3 %); without that point's slope 2.2 %. Where the rows at a kink alone fix
  // a direction (J^T J without them singular), the parameters along it have no sigma
  // (fixed_at_kink) and the others theirs from the pseudo-inverse, which leaves that direction out.
  std::vector<bool> at_kink(static_cast<size_t>(m), false);
  for (int pass = 0; pass < 3; ++pass) {
    const Eigen::MatrixXd total = stated(cov);
    if (!total.allFinite()) return {};
    if (!mark_kink_rows(objective, free, v, z, J, r, total, at_kink)) break;
    if (!widen_without_kink_rows(res, J, at_kink, without_floor, free, cov, fixed_at_kink))
      return {};
  }
  cov = stated(cov);
  if (!cov.allFinite()) return {};
  return cov;
}

}  // namespace jointlab::correlate::iwan_detail
