#include "jointlab/modal/stepped_sine.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <ceres/ceres.h>
#include <fmt/format.h>
#include <Eigen/Dense>

#include "jointlab/core/error.h"
#include "jointlab/core/median.h"

namespace jointlab::modal {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr int kParams = 8;  // nu_n, zeta, q (re, im), r0 (re, im), r1 (re, im)

// The normalised model h(nu) = q / d(nu) + r0 + r1 (nu - 1), nu = w / w_c, split into real
// and imaginary parts; templated so ceres::Jet gives its exact Jacobian.
struct ModelResidual {
  double nu, h_re, h_im, weight;
  bool viscous;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    const T a = x[0] * x[0] - T(nu * nu);
    const T b = viscous ? T(2.0) * x[1] * x[0] * T(nu) : T(2.0) * x[1] * x[0] * x[0];
    const T den = a * a + b * b;
    const T m_re = (x[2] * a + x[3] * b) / den + x[4] + x[6] * T(nu - 1.0);
    const T m_im = (x[3] * a - x[2] * b) / den + x[5] + x[7] * T(nu - 1.0);
    r[0] = (m_re - T(h_re)) * T(weight);
    r[1] = (m_im - T(h_im)) * T(weight);
    return true;
  }
};

// Linear least squares for q, r0, r1 at fixed (nu_n, zeta): the grid search's inner step.
double linear_fit(const Eigen::VectorXd& nu, const Eigen::VectorXcd& h, double nu_n, double zeta,
                  bool viscous, int terms, Eigen::VectorXcd& coef) {
  const Eigen::Index m = nu.size();
  Eigen::MatrixXcd a(m, 1 + terms);
  for (Eigen::Index k = 0; k < m; ++k) {
    const double b = viscous ? 2 * zeta * nu_n * nu(k) : 2 * zeta * nu_n * nu_n;
    a(k, 0) = 1.0 / std::complex<double>(nu_n * nu_n - nu(k) * nu(k), b);
    if (terms >= 1) a(k, 1) = 1.0;
    if (terms >= 2) a(k, 2) = nu(k) - 1.0;
  }
  // Relative weighting, as in the nonlinear fit.
  const Eigen::VectorXd w = h.cwiseAbs().cwiseInverse();
  a = w.asDiagonal() * a;
  const Eigen::VectorXcd b = w.asDiagonal() * h;
  coef = a.colPivHouseholderQr().solve(b);
  return (a * coef - b).squaredNorm();
}

double interpolate(const Eigen::VectorXd& x, const Eigen::VectorXd& y, double at) {
  const Eigen::Index n = x.size();
  if (at <= x(0)) return y(0);
  if (at >= x(n - 1)) return y(n - 1);
  Eigen::Index k = 0;
  while (k + 2 < n && x(k + 1) < at) ++k;
  const double t = (at - x(k)) / (x(k + 1) - x(k));
  return y(k) + t * (y(k + 1) - y(k));
}

}  // namespace

std::string SteppedSineOptions::check() const {
  if (residual_terms < 0 || residual_terms > 2) return "residual terms must be 0, 1 or 2";
  if (!(coverage_factor >= 1 && coverage_factor <= 10)) return "coverage factor must be in [1, 10]";
  if (amplitude == Quantity::kForce)
    return "the amplitude must be a displacement, velocity or acceleration";
  if (max_iterations < 1) return "max iterations must be >= 1";
  return "";
}

std::string SineBackbonePoint::report() const {
  if (status != SineStatus::kOk) return "no backbone point: " + message;
  return fmt::format(
      "{}-controlled: f = {:.5f} Hz +/- {:.2g}, zeta = {:.4g} % +/- {:.2g} %{} at amplitude {:.4g} "
      "(fit misfit {:.2g} %){}",
      data::control_name(control), frequency_hz, frequency_std_hz, 100 * damping_ratio,
      100 * damping_std,
      damping_direct ? ""
      : own_modal_constant
          ? " (energy balance with this sweep's own modal constant)"
          : " (energy balance with the response-controlled levels' modal constant)",
      amplitude, 100 * fit.rms, message.empty() ? "" : "; " + message);
}

Eigen::VectorXcd receptance(const data::SteppedSineTable& t) {
  const int p = derivative_order(t.response_quantity);
  Eigen::VectorXcd h(t.size());
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    const std::complex<double> iw(0.0, kTwoPi * t.frequency_hz(k));
    h(k) = std::polar(t.response(k), t.phase_rad(k)) / (t.force(k) * std::pow(iw, p));
  }
  return h;
}

SineFit fit_single_mode(const Eigen::Ref<const Eigen::VectorXd>& frequency_hz,
                        const Eigen::Ref<const Eigen::VectorXcd>& h_in,
                        const SteppedSineOptions& options) {
  if (const std::string why = options.check(); !why.empty()) throw InputError(why);
  const Eigen::Index m = frequency_hz.size();
  assert(h_in.size() == m && m >= 2);
  const bool viscous = options.damping == SineDamping::kViscous;
  const int terms = options.residual_terms;
  const int active = 4 + 2 * terms;
  SineFit fit;
  if (2 * m <= active) return fit;  // not converged: too few steps for the model

  // Normalise: nu = f / f_c, h scaled to a peak of 1.
  const double f_c = 0.5 * (frequency_hz.minCoeff() + frequency_hz.maxCoeff());
  const double scale = 1.0 / h_in.cwiseAbs().maxCoeff();
  const Eigen::VectorXd nu = frequency_hz / f_c;
  const Eigen::VectorXcd h = h_in * scale;

  // Start: the best (nu_n, zeta) on a grid over the band, q and residuals linear in between.
  double best = INFINITY;
  double x[kParams] = {1, 0.01, 0, 0, 0, 0, 0, 0};
  Eigen::VectorXcd coef;
  const double lo = nu.minCoeff(), hi = nu.maxCoeff();
  for (int i = 0; i <= 80; ++i) {
    const double nu_n = lo + (hi - lo) * i / 80.0;
    for (int j = 0; j <= 27; ++j) {
      const double zeta = 1e-5 * std::pow(10.0, 4.5 * j / 27.0);
      const double cost = linear_fit(nu, h, nu_n, zeta, viscous, terms, coef);
      if (cost < best) {
        best = cost;
        x[0] = nu_n, x[1] = zeta;
        x[2] = coef(0).real(), x[3] = coef(0).imag();
        x[4] = terms >= 1 ? coef(1).real() : 0, x[5] = terms >= 1 ? coef(1).imag() : 0;
        x[6] = terms >= 2 ? coef(2).real() : 0, x[7] = terms >= 2 ? coef(2).imag() : 0;
      }
    }
  }

  ceres::Problem problem;
  for (Eigen::Index k = 0; k < m; ++k) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<ModelResidual, 2, kParams>(
            new ModelResidual{nu(k), h(k).real(), h(k).imag(), 1.0 / std::abs(h(k)), viscous}),
        nullptr, x);
  }
  if (terms < 2) {
    std::vector<int> fixed = {6, 7};
    if (terms < 1) fixed = {4, 5, 6, 7};
    problem.SetManifold(x, new ceres::SubsetManifold(kParams, fixed));
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.function_tolerance = 1e-15;
  so.parameter_tolerance = 1e-14;
  so.gradient_tolerance = 1e-16;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary cs;
  ceres::Solve(so, &problem, &cs);
  fit.iterations = static_cast<int>(cs.iterations.size());
  fit.converged = cs.termination_type == ceres::CONVERGENCE;

  // Exact Jacobian at the solution; covariance of the active parameters.
  using Jet = ceres::Jet<double, kParams>;
  Jet xj[kParams];
  for (int i = 0; i < kParams; ++i) xj[i] = Jet(x[i], i);
  Eigen::MatrixXd jac(2 * m, active);
  double rss = 0, hss = 0;
  for (Eigen::Index k = 0; k < m; ++k) {
    Jet r[2];
    ModelResidual{nu(k), h(k).real(), h(k).imag(), 1.0 / std::abs(h(k)), viscous}(xj, r);
    for (int c = 0; c < 2; ++c) {
      jac.row(2 * k + c) = r[c].v.head(active).transpose();
      rss += r[c].a * r[c].a;
    }
  }
  hss = static_cast<double>(m);
  const double s2 = rss / static_cast<double>(2 * m - active);
  const Eigen::MatrixXd jtj = jac.transpose() * jac;
  Eigen::FullPivLU<Eigen::MatrixXd> lu(jtj);
  if (!lu.isInvertible()) fit.converged = false;
  const Eigen::MatrixXd cov = lu.isInvertible() ? Eigen::MatrixXd(s2 * lu.inverse())
                                                : Eigen::MatrixXd::Zero(active, active);

  fit.frequency_hz = x[0] * f_c;
  fit.damping_ratio = x[1];
  fit.frequency_sigma_hz = std::sqrt(std::max(cov(0, 0), 0.0)) * f_c;
  fit.damping_sigma = std::sqrt(std::max(cov(1, 1), 0.0));
  const double wc2 = std::pow(kTwoPi * f_c, 2);
  fit.modal_constant = std::complex<double>(x[2], x[3]) * wc2 / scale;
  const double q2 = x[2] * x[2] + x[3] * x[3];
  const double var_q =
      (x[2] * x[2] * cov(2, 2) + 2 * x[2] * x[3] * cov(2, 3) + x[3] * x[3] * cov(3, 3)) /
      std::max(q2, 1e-300);
  fit.modal_constant_rel_sigma = std::sqrt(std::max(var_q, 0.0) / std::max(q2, 1e-300));
  fit.residual0 = std::complex<double>(x[4], x[5]) / scale;
  fit.residual1 = std::complex<double>(x[6], x[7]) / scale;
  fit.rms = std::sqrt(rss / std::max(hss, 1e-300));
  if (!std::isfinite(fit.frequency_hz) || !std::isfinite(fit.damping_ratio) ||
      !std::isfinite(fit.frequency_sigma_hz) || !std::isfinite(fit.damping_sigma)) {
    fit.converged = false;
  }
  return fit;
}

ModalConstant response_modal_constant(const std::vector<SineBackbonePoint>& points) {
  std::vector<double> q;
  double rel = 0;
  for (const SineBackbonePoint& p : points) {
    if (p.status != SineStatus::kOk || p.control != data::SineControl::kResponse) continue;
    q.push_back(std::abs(p.fit.modal_constant));
    rel = std::max(rel, p.fit.modal_constant_rel_sigma);
  }
  if (q.empty()) return {};
  const double middle = median(q);
  // The spread between levels is part of |Q|'s uncertainty.
  double spread = 0;
  for (double v : q) spread = std::max(spread, std::abs(v / middle - 1));
  return {middle, std::max(rel, q.size() > 1 ? spread / 2 : 0.0)};
}

SineBackbonePoint extract_backbone_point(const data::SteppedSineTable& t,
                                         const SteppedSineOptions& options,
                                         const ModalConstant& modal_constant) {
  if (const std::string why = options.check(); !why.empty()) throw InputError(why);
  SineBackbonePoint pt;
  pt.control = t.control;
  const Eigen::VectorXcd h = receptance(t);
  pt.fit = fit_single_mode(t.frequency_hz, h, options);
  const SineFit& fit = pt.fit;
  const double k = options.coverage_factor;
  const int p = derivative_order(t.response_quantity);
  const int out = derivative_order(options.amplitude);
  const double f_lo = t.frequency_hz(0), f_hi = t.frequency_hz(t.size() - 1);
  if (!(fit.frequency_hz > f_lo && fit.frequency_hz < f_hi)) {
    pt.status = SineStatus::kNoResonance;
    pt.message = fmt::format(
        "the fitted natural frequency {:.5g} Hz lies outside the sweep ({:.5g} to {:.5g} Hz)",
        fit.frequency_hz, f_lo, f_hi);
    return pt;
  }
  if (!fit.converged) {
    pt.status = SineStatus::kFitFailed;
    pt.message =
        fmt::format("the single-mode fit did not converge ({} iterations)", fit.iterations);
    return pt;
  }
  if (!(fit.damping_ratio > 0)) {
    pt.status = SineStatus::kFitFailed;
    pt.message =
        "the fit needs negative damping: the phase rises through resonance, so the table's "
        "phase has the opposite sign convention (negate it)";
    return pt;
  }

  if (t.control == data::SineControl::kResponse) {
    const double w = kTwoPi * fit.frequency_hz;
    const double y = interpolate(t.frequency_hz, t.response, fit.frequency_hz);
    pt.displacement_m = y / std::pow(w, p);
    pt.amplitude = pt.displacement_m * std::pow(w, out);
    pt.force_n = interpolate(t.frequency_hz, t.force, fit.frequency_hz);
    pt.frequency_hz = fit.frequency_hz;
    pt.damping_ratio = fit.damping_ratio;
    pt.frequency_std_hz = k * fit.frequency_sigma_hz;
    pt.damping_std = k * fit.damping_sigma;
    pt.damping_direct = true;
    pt.status = SineStatus::kOk;
    const double spread = (t.response.maxCoeff() - t.response.minCoeff()) / t.response.mean();
    if (spread > 0.05) {
      pt.message =
          fmt::format("the response amplitude varies by {:.1f} % over the sweep", 100 * spread);
    }
    return pt;
  }

  // Force control: the phase resonance, arg(H / Q) = -pi/2 with Q's phase rounded to 0 or pi.
  const double alpha =
      std::round(std::arg(fit.modal_constant) / std::numbers::pi) * std::numbers::pi;
  const Eigen::Index n = t.size();
  Eigen::VectorXd theta(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    theta(i) = std::arg(h(i) * std::polar(1.0, -alpha));
    if (i > 0) {
      while (theta(i) - theta(i - 1) > std::numbers::pi) theta(i) -= kTwoPi;
      while (theta(i) - theta(i - 1) < -std::numbers::pi) theta(i) += kTwoPi;
    }
  }
  // Shift the unwrapped phase so that it starts in (-pi, pi].
  const double shift = kTwoPi * std::round(theta(0) / kTwoPi);
  theta.array() -= shift;
  const double target = -std::numbers::pi / 2;
  Eigen::Index best = -1;
  double best_y = -1, best_f = 0;
  for (Eigen::Index i = 0; i + 1 < n; ++i) {
    const double a = theta(i) - target, b = theta(i + 1) - target;
    if (!(a >= 0 && b < 0)) continue;
    const double f = t.frequency_hz(i) + a / (a - b) * (t.frequency_hz(i + 1) - t.frequency_hz(i));
    const double y = interpolate(t.frequency_hz, t.response, f);
    if (y > best_y) best = i, best_y = y, best_f = f;
  }
  if (best < 0) {
    pt.status = SineStatus::kNoResonance;
    pt.message = "the response never passes through quadrature with the force in this sweep";
    return pt;
  }
  const double w = kTwoPi * best_f;
  pt.frequency_hz = best_f;
  pt.displacement_m = best_y / std::pow(w, p);
  pt.amplitude = pt.displacement_m * std::pow(w, out);
  pt.force_n = interpolate(t.frequency_hz, t.force, best_f);
  pt.own_modal_constant = !(modal_constant.magnitude > 0);
  const double q_abs =
      pt.own_modal_constant ? std::abs(fit.modal_constant) : modal_constant.magnitude;
  const double q_rel =
      pt.own_modal_constant ? fit.modal_constant_rel_sigma : modal_constant.rel_sigma;
  pt.damping_ratio = q_abs * pt.force_n / (2 * w * w * pt.displacement_m);
  pt.damping_direct = false;

  // Frequency uncertainty: the phase noise about a local quadratic through the crossing
  // (three steps each side) over the phase slope, combined with the difference between the
  // linear and the quadratic crossing (the interpolation error).
  const Eigen::Index i0 = std::max<Eigen::Index>(0, best - 2);
  const Eigen::Index i1 = std::min<Eigen::Index>(n - 1, best + 3);
  const Eigen::Index nl = i1 - i0 + 1;
  double sigma_theta = 0, f_quad = best_f;
  const double slope =
      (theta(best + 1) - theta(best)) / (t.frequency_hz(best + 1) - t.frequency_hz(best));
  if (nl >= 4) {
    Eigen::MatrixXd a(nl, 3);
    Eigen::VectorXd y(nl);
    for (Eigen::Index i = 0; i < nl; ++i) {
      const double df = t.frequency_hz(i0 + i) - best_f;
      a(i, 0) = 1, a(i, 1) = df, a(i, 2) = df * df;
      y(i) = theta(i0 + i) - target;
    }
    const Eigen::Vector3d c = a.colPivHouseholderQr().solve(y);
    sigma_theta = std::sqrt((a * c - y).squaredNorm() / static_cast<double>(nl - 3));
    // Root of c0 + c1 d + c2 d^2 nearest d = 0 (one Newton step from the linear crossing).
    if (std::abs(c(1)) > 0) f_quad = best_f - c(0) / c(1);
  }
  const double sigma_f = std::hypot(sigma_theta / std::abs(slope), f_quad - best_f);
  pt.frequency_std_hz = k * sigma_f;
  pt.damping_std = k * pt.damping_ratio * std::hypot(q_rel, sigma_theta);
  if (pt.own_modal_constant) {
    pt.message = "damping from the sweep's own modal constant (no response-controlled level)";
  }
  pt.status = SineStatus::kOk;
  return pt;
}

}  // namespace jointlab::modal
