// The all-DOF QSMA reference shared by the tests and the benchmark: Newton on
//   K_lin u - B^T h(B u) = alpha M phi,   Phi_rb^T M u = 0
// by Lagrange multipliers, a dense LU of the bordered tangent and backtracking on the
// potential energy: what an obvious full-size implementation (a NumPy script) does, and
// independent of the joint condensation (no flexibility, no Schur step).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"

namespace jointlab::testing {

/// QSMA of one mode solved on every DOF of the model.
class AllDofNewton {
 public:
  /// Sets up mode `column` (0-based, rigid-body modes first) of `model`, at u = 0.
  AllDofNewton(const model::Model& model, const model::LinearModes& modes, int column)
      : k_(Eigen::MatrixXd(model.linear_stiffness())), m_(Eigen::MatrixXd(model.mass)) {
    for (const model::Joint& j : model.joints) {
      if (j.iwan) joints_.push_back(j);
    }
    rb_ = m_ * modes.shapes.leftCols(modes.rigid_count);
    load_ = m_ * modes.shapes.col(column);
    phi_ = modes.shapes.col(column);
    u_ = Eigen::VectorXd::Zero(k_.rows());
  }

  /// Solves at alpha from the current state; false if Newton does not converge.
  bool solve(double alpha) {
    const Eigen::Index n = k_.rows(), nr = rb_.cols();
    Eigen::VectorXd u = u_;
    for (int it = 0; it < 400; ++it) {
      Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + nr, n + nr);
      a.topLeftCorner(n, n) = k_;
      a.topRightCorner(n, nr) = rb_;
      a.bottomLeftCorner(nr, n) = rb_.transpose();
      const Eigen::VectorXd res = residual(u, alpha, &a);
      // Converged at 1e-12 of the forces involved, or when a Newton step changes u by
      // less than 1e-13 (rounding in K u of the stiff beams limits the residual).
      const double scale = alpha * load_.norm() + (k_.cwiseAbs() * u.cwiseAbs()).norm();
      if (res.norm() <= 1e-12 * scale) {
        u_ = u;
        return true;
      }
      const Eigen::VectorXd step = a.partialPivLu().solve(-res);
      if (step.head(n).lpNorm<Eigen::Infinity>() <= 1e-13 * u.lpNorm<Eigen::Infinity>()) {
        u_ = u + step.head(n);
        return true;
      }
      // Backtracking on the potential energy (the force balance is its gradient).
      const double pi0 = potential(u, alpha), slope = res.head(n).dot(step.head(n));
      // Step control: a step at most |u| (a near-singular tangent past the
      // rivets' slip points otherwise throws the iterate far away), then backtracking.
      const double len = step.head(n).lpNorm<Eigen::Infinity>();
      double t = std::min(1.0, std::max(u.lpNorm<Eigen::Infinity>(), 1e-9) / len);
      Eigen::VectorXd trial;
      for (int k = 0; k < 100; ++k, t /= 2) {
        trial = u + t * step.head(n);
        // Steps below 1e-6 of |u| are in Newton's quadratic range, where differences of
        // the potential are rounding noise: take them as they are.
        if (potential(trial, alpha) <= pi0 + 1e-4 * t * slope ||
            t * step.head(n).lpNorm<Eigen::Infinity>() <= 1e-6 * u.lpNorm<Eigen::Infinity>()) {
          break;
        }
      }
      u = trial;
      if (!u.allFinite() || u.lpNorm<Eigen::Infinity>() > 1e3) return false;  // ran away
    }
    return false;
  }

  /// Solves at each level in turn from u = 0, each from the previous solution scaled in
  /// proportion (a predictor); returns how many levels converged.
  int run(const std::vector<double>& alphas) {
    u_.setZero();
    double previous = 0;
    int converged = 0;
    for (double alpha : alphas) {
      if (previous > 0) u_ *= alpha / previous;
      converged += solve(alpha) ? 1 : 0;
      previous = alpha;
    }
    return converged;
  }

  /// Modal amplitude q = phi^T M u of the current state.
  double q() const { return phi_.dot(m_ * u_); }
  /// The current displacements.
  const Eigen::VectorXd& u() const { return u_; }
  /// Sets the current state (a predictor for the next solve).
  void set(const Eigen::VectorXd& u) { u_ = u; }
  /// Every Iwan element past its phi_max.
  bool full_macroslip() const {
    for (const model::Joint& j : joints_) {
      if (std::abs(u_(j.a) - u_(j.b)) < j.iwan->phi_max()) return false;
    }
    return true;
  }

 private:
  double potential(const Eigen::VectorXd& u, double alpha) const {
    double pi = 0.5 * u.dot(k_ * u) - alpha * load_.dot(u);
    for (const model::Joint& j : joints_) pi -= j.iwan->softening_energy(u(j.a) - u(j.b));
    return pi;
  }

  // Residual of force balance and constraints; with `a`, adds -B^T h' B to its K block.
  Eigen::VectorXd residual(const Eigen::VectorXd& u, double alpha, Eigen::MatrixXd* a) const {
    const Eigen::Index n = k_.rows(), nr = rb_.cols();
    Eigen::VectorXd res(n + nr);
    res.head(n) = k_ * u - alpha * load_;
    res.tail(nr) = rb_.transpose() * u;
    for (const model::Joint& j : joints_) {
      const double r = u(j.a) - u(j.b);
      const double h = j.iwan->softening(r), dh = j.iwan->softening_tangent(r);
      res(j.a) -= h;
      res(j.b) += h;
      if (a) {
        (*a)(j.a, j.a) -= dh;
        (*a)(j.b, j.b) -= dh;
        (*a)(j.a, j.b) += dh;
        (*a)(j.b, j.a) += dh;
      }
    }
    return res;
  }

  Eigen::MatrixXd k_, m_, rb_;
  Eigen::VectorXd load_, phi_, u_;
  std::vector<model::Joint> joints_;
};

}  // namespace jointlab::testing
