#include "jointlab/model/joint_condensation.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>
#include <utility>

#include <fmt/format.h>

#include <Eigen/QR>

#include "jointlab/core/error.h"
#include "jointlab/model/sparse_cholesky.h"

namespace jointlab::model {

namespace {

// The ends of a joint coordinate for a message: "DOF 3 and ground", "DOFs 3 and 7" (0-based
// matrix indices).
std::string joint_ends(Eigen::Index a, Eigen::Index b) {
  return b == kGround ? fmt::format("DOF {} and ground", a) : fmt::format("DOFs {} and {}", a, b);
}

}  // namespace

double JointCondensation::Law::eval(double r, double& h, double& dh, double& energy) const {
  const double s = std::abs(r);
  const double sign = r < 0 ? -1.0 : 1.0;
  if (s >= phi_max) {
    h = sign * (Kt * s - Fs);
    dh = Kt;
    energy = Kt * s * s / 2 - e_max - Fs * (s - phi_max);
    return 0;
  }
  // Microslip: h = R s^(chi+2)/((chi+1)(chi+2)) written without the K_T s - F cancellation.
  const double p = s > 0 ? std::pow(s, chi1) : 0.0;
  h = sign * a2 * s * p;
  dh = a1 * p;
  energy = a3 * s * s * p;
  return p;
}

void JointCondensation::set_coordinates(const std::vector<Joint>& joints) {
  // Group Iwan elements by unordered pair of ends: one coordinate each. An element with
  // swapped ends sees -r, which leaves its energy (even) and generalized force unchanged.
  std::map<std::pair<Eigen::Index, Eigen::Index>, int> index;
  for (const Joint& joint : joints) {
    if (!joint.iwan) continue;
    std::pair<Eigen::Index, Eigen::Index> key{joint.a, kGround};
    if (joint.b != kGround) key = {std::min(joint.a, joint.b), std::max(joint.a, joint.b)};
    auto [it, fresh] = index.emplace(key, static_cast<int>(coords_.size()));
    if (fresh) coords_.push_back(JointCoordinate{key.first, key.second, {}});
    coords_[it->second].elements.push_back(*joint.iwan);
  }
  const int nj = size();
  laws_.resize(nj);
  cycles_.resize(nj);
  phi_max_.resize(nj);
  kt_ = Eigen::VectorXd::Zero(nj);
  phi_max_min_ = INFINITY;
  chi1_min_ = INFINITY;
  for (int j = 0; j < nj; ++j) {
    phi_max_(j) = 0;
    for (const Iwan& e : coords_[j].elements) {
      const double chi1 = e.chi() + 1, R = e.R();
      // The solver works with forces, displacements and energies of the element's own
      // scale: refuse parameters whose products leave double precision. Slips down to 1e-6
      // of phi_max raised to chi + 3 stay clear of underflow when phi_max >= 1e-90 m and
      // chi <= 0 (below it a cycle's dissipation rounds to zero and the damping with it); a
      // larger chi needs a larger phi_max for R = F_S (chi+1) / (phi_max^(chi+2) (beta + c)) to
      // stay finite, which the test of R checks.
      if (!(e.chi() <= kIwanCycleChiMax)) {
        throw InputError(fmt::format(
            "QSMA: the Iwan element between {} has chi = {:g}, above {:g}, the largest for which "
            "its first-harmonic slip integral is verified",
            joint_ends(coords_[j].a, coords_[j].b), e.chi(), kIwanCycleChiMax));
      }
      const double work = e.slip_force() * e.phi_max();
      if (!(e.phi_max() >= 1e-90) || !std::isfinite(e.phi_max()) || !std::isfinite(R) || !(R > 0) ||
          !std::isfinite(e.S()) || !std::isfinite(work) || !(work > 0)) {
        throw InputError(fmt::format(
            "QSMA: the Iwan element between {} (Fs = {:g}, Kt = {:g}, chi = {:g}) has phi_max "
            "= {:.3g} m, Fs phi_max = {:.3g} J and slider density R = {:.3g} (F_S (chi+1) / "
            "(phi_max^(chi+2) (beta + c))) beyond double precision; state the model in other "
            "units",
            joint_ends(coords_[j].a, coords_[j].b), e.slip_force(), e.stiffness(), e.chi(),
            e.phi_max(), work, R));
      }
      laws_[j].push_back({e.stiffness(), e.slip_force(), e.phi_max(), chi1, R / chi1,
                          R / (chi1 * (chi1 + 1)), R / (chi1 * (chi1 + 1) * (chi1 + 2)),
                          e.energy(e.phi_max())});
      cycles_[j].emplace_back(e);
      Law& law = laws_[j].back();
      const double j1 = cycles_[j].back().microslip_integral();
      law.k1_0 = R * std::pow(e.phi_max(), chi1) / chi1 + e.S();
      law.k1_p = R * (j1 - 1 / chi1);
      law.dk1_p = R * (chi1 * j1 - 1);
      kt_(j) += e.stiffness();
      phi_max_(j) = std::max(phi_max_(j), e.phi_max());
      phi_max_min_ = std::min(phi_max_min_, e.phi_max());
      chi1_min_ = std::min(chi1_min_, chi1);
    }
  }
}

JointCondensation::JointCondensation(const Model& model, const ModesOptions& modes_options) {
  if (model.iwan_count() == 0) {
    throw InputError("QSMA: the model has no Iwan joint (every joint is a linear spring)");
  }
  modes_ = linear_modes(model, modes_options);
  linear_damping_ = model.modal_ratio;
  set_coordinates(model.joints);
  const int nj = size();
  const Eigen::Index n = model.size();

  // B^T as a dense n x n_J matrix (n_J is small).
  Eigen::MatrixXd bt = Eigen::MatrixXd::Zero(n, nj);
  for (int j = 0; j < nj; ++j) {
    bt(coords_[j].a, j) = 1.0;
    if (coords_[j].b != kGround) bt(coords_[j].b, j) = -1.0;
  }
  joint_shapes_ = bt.transpose() * modes_.shapes;

  // G B^T with rigid-body motion suppressed by clamping n_rb statically determinate DOFs
  // (those where the rigid-body shapes are best conditioned, by QR with column pivoting):
  // a load orthogonal to the rigid-body modes (every column of B^T is) needs no reaction
  // there, so the clamped solution solves K_lin x = f exactly, up to a rigid motion the
  // joints do not see. One sparse Cholesky factorization (CHOLMOD).
  const Eigen::SparseMatrix<double> k_lin = model.linear_stiffness();
  std::vector<bool> clamped(static_cast<size_t>(n), false);
  if (modes_.rigid_count > 0) {
    const Eigen::MatrixXd rigid_t = modes_.shapes.leftCols(modes_.rigid_count).transpose();
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(rigid_t);
    for (int i = 0; i < modes_.rigid_count; ++i) {
      clamped[static_cast<size_t>(qr.colsPermutation().indices()(i))] = true;
    }
  }
  std::vector<Eigen::Triplet<double>> entries;
  for (int c = 0; c < k_lin.outerSize(); ++c) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(k_lin, c); it; ++it) {
      if (!clamped[static_cast<size_t>(it.row())] && !clamped[static_cast<size_t>(it.col())]) {
        entries.emplace_back(it.row(), it.col(), it.value());
      }
    }
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    if (clamped[static_cast<size_t>(i)]) entries.emplace_back(i, i, 1.0);
  }
  Eigen::SparseMatrix<double> k_clamped(n, n);
  k_clamped.setFromTriplets(entries.begin(), entries.end());
  SparseCholesky factor;
  if (!factor.factorize(k_clamped)) {
    throw InputError(
        "QSMA: the stiffness with joints at linear stiffness is not positive "
        "semidefinite");
  }
  Eigen::MatrixXd rhs = bt;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (clamped[static_cast<size_t>(i)]) rhs.row(i).setZero();
  }
  const Eigen::MatrixXd gbt = factor.solve(rhs);
  flexibility_ = bt.transpose() * gbt;
  // The solve's own error, measured by one step of iterative refinement with residuals
  // formed element by element (free of the cancellation a stiff joint brings to K_lin): a
  // joint far stiffer than the structure (a penalty spring) leaves error of order
  // cond(K_lin) eps in the soft flexibility the Iwan joints see. The step is not applied:
  // where C is ill-conditioned (closely spaced rivets) it moves C only within its rounding,
  // and C^-1 far more. Beyond 1e-6 of C the model is refused, not analysed.
  Eigen::MatrixXd residual(n, nj);
  for (int j = 0; j < nj; ++j) {
    residual.col(j) = rhs.col(j) - model.apply_linear_stiffness(gbt.col(j));
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    if (clamped[static_cast<size_t>(i)]) residual.row(i).setZero();
  }
  const double left = (bt.transpose() * factor.solve(residual)).cwiseAbs().maxCoeff() /
                      flexibility_.cwiseAbs().maxCoeff();
  if (flexibility_.allFinite() && !(left <= 1e-6)) {
    throw InputError(fmt::format(
        "QSMA: the joints' flexibility B K_lin^-1 B^T is resolved only to {:.1g} of itself: a "
        "joint or spring far stiffer than the structure (the stiffest is {:.3g} N/m) leaves "
        "K_lin too ill-conditioned; a penalty stiffness 1e6 times the structure's is rigid to "
        "6 digits",
        left, model.stiffest_joint()));
  }
  if (!flexibility_.allFinite()) {
    throw InputError(
        "QSMA: the joints' flexibility B K_lin^-1 B^T is not finite (stiffness entries beyond "
        "double precision); state the model in other units");
  }
  flexibility_ = 0.5 * (flexibility_ + flexibility_.transpose()).eval();
  const Eigen::LLT<Eigen::MatrixXd> cl(flexibility_);
  const Eigen::VectorXd d = flexibility_.diagonal();
  const double pivot_ratio =
      cl.info() == Eigen::Success
          ? (cl.matrixLLT().diagonal().array().square() / d.array()).minCoeff()
          : 0.0;
  // A pivot below 1e-10 of its diagonal entry means a coordinate is (numerically) a
  // combination of others: C has no usable inverse.
  if (!(pivot_ratio > 1e-10)) {
    throw InputError(
        "QSMA: the Iwan joint coordinates are linearly dependent (a loop of joints, or a "
        "joint whose ends cannot move relative to each other)");
  }
  stiffness_ = cl.solve(Eigen::MatrixXd::Identity(nj, nj));
  stiffness_ = 0.5 * (stiffness_ + stiffness_.transpose()).eval();
  // Psi = G B^T K_c: the clamped solutions less their rigid-body motion (Phi_rb^T M u = 0, the
  // constraint every static solution here meets; the modes are mass-normalised).
  Eigen::MatrixXd psi = gbt;
  if (modes_.rigid_count > 0) {
    const Eigen::MatrixXd rigid = modes_.shapes.leftCols(modes_.rigid_count);
    const Eigen::MatrixXd m_rigid = model.mass * rigid;
    psi -= rigid * (m_rigid.transpose() * gbt);
  }
  constraint_modes_ = std::make_shared<const Eigen::MatrixXd>(psi * stiffness_);
}

JointCondensation::JointCondensation(const std::vector<Joint>& joints, LinearModes modes,
                                     Eigen::MatrixXd condensed_stiffness,
                                     std::shared_ptr<const Eigen::MatrixXd> constraint_modes)
    : modes_(std::move(modes)),
      stiffness_(std::move(condensed_stiffness)),
      constraint_modes_(std::move(constraint_modes)) {
  if (!constraint_modes_) constraint_modes_ = std::make_shared<const Eigen::MatrixXd>();
  set_coordinates(joints);
  assert(stiffness_.rows() == size() && stiffness_.cols() == size());
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(size(), modes_.shapes.rows());
  for (int j = 0; j < size(); ++j) {
    b(j, coords_[j].a) = 1.0;
    if (coords_[j].b != kGround) b(j, coords_[j].b) = -1.0;
  }
  joint_shapes_ = b * modes_.shapes;
  const Eigen::LLT<Eigen::MatrixXd> llt(stiffness_);
  if (llt.info() != Eigen::Success) {
    throw InputError("QSMA: the joint-condensed stiffness is not positive definite");
  }
  flexibility_ = llt.solve(Eigen::MatrixXd::Identity(size(), size()));
  flexibility_ = 0.5 * (flexibility_ + flexibility_.transpose()).eval();
}

Eigen::VectorXd JointCondensation::joint_motion(const Eigen::Ref<const Eigen::VectorXd>& u) const {
  Eigen::VectorXd r(size());
  for (int j = 0; j < size(); ++j) {
    r(j) = u(coords_[j].a) - (coords_[j].b == kGround ? 0.0 : u(coords_[j].b));
  }
  return r;
}

void JointCondensation::evaluate(const Eigen::VectorXd& r, Eigen::VectorXd& h, Eigen::VectorXd& dh,
                                 double& energy) const {
  energy = 0;
  for (int j = 0; j < size(); ++j) {
    h(j) = 0;
    dh(j) = 0;
    for (const Law& law : laws_[j]) {
      double hj, dhj, ej;
      law.eval(r(j), hj, dhj, ej);
      h(j) += hj;
      dh(j) += dhj;
      energy += ej;
    }
  }
}

Eigen::VectorXd JointCondensation::softening(const Eigen::Ref<const Eigen::VectorXd>& r) const {
  Eigen::VectorXd h(size()), dh(size());
  double energy;
  evaluate(r, h, dh, energy);
  return h;
}

Eigen::VectorXd JointCondensation::softening_tangent(
    const Eigen::Ref<const Eigen::VectorXd>& r) const {
  Eigen::VectorXd h(size()), dh(size());
  double energy;
  evaluate(r, h, dh, energy);
  return dh;
}

void JointCondensation::softening(const Eigen::Ref<const Eigen::VectorXd>& r, Eigen::VectorXd& h,
                                  Eigen::VectorXd& dh) const {
  h.resize(size());
  dh.resize(size());
  double energy;
  evaluate(r, h, dh, energy);
}

void JointCondensation::softening_and_harmonic(const Eigen::Ref<const Eigen::VectorXd>& r,
                                               Eigen::VectorXd& h, Eigen::VectorXd& dh,
                                               Eigen::VectorXd& k1, Eigen::VectorXd& dk1) const {
  const int nj = size();
  h.resize(nj);
  dh.resize(nj);
  k1.resize(nj);
  dk1.resize(nj);
  for (int j = 0; j < nj; ++j) {
    h(j) = dh(j) = k1(j) = dk1(j) = 0;
    const double s = std::abs(r(j));
    const double sign = r(j) < 0 ? -1.0 : 1.0;
    for (size_t e = 0; e < laws_[j].size(); ++e) {
      const Law& law = laws_[j][e];
      double hj, dhj, ej;
      const double p = law.eval(r(j), hj, dhj, ej);
      h(j) += hj;
      dh(j) += dhj;
      if (s >= law.phi_max) {  // past the closed form of k_1: the cycle's own integral
        double slope;
        k1(j) += cycles_[j][e].first_harmonic_stiffness(r(j), &slope);
        dk1(j) += slope;
      } else {
        k1(j) += law.k1_0 + law.k1_p * p;
        if (s > 0) dk1(j) += sign * law.dk1_p * p / s;
      }
    }
  }
}

Eigen::VectorXd JointCondensation::first_harmonic_stiffness(
    const Eigen::Ref<const Eigen::VectorXd>& r) const {
  Eigen::VectorXd k = Eigen::VectorXd::Zero(size());
  for (int j = 0; j < size(); ++j) {
    for (const IwanCycle& c : cycles_[j]) k(j) += c.first_harmonic_stiffness(r(j));
  }
  return k;
}

double JointCondensation::turning_point_energy(const Eigen::Ref<const Eigen::VectorXd>& r) const {
  double e = 0;
  for (int j = 0; j < size(); ++j) {
    for (const IwanCycle& c : cycles_[j]) e += c.turning_point_energy(r(j));
  }
  return e;
}

Eigen::VectorXd JointCondensation::tangent(const Eigen::Ref<const Eigen::VectorXd>& g,
                                           const Eigen::Ref<const Eigen::VectorXd>& r) const {
  Eigen::MatrixXd hessian = stiffness_;
  hessian.diagonal() -= softening_tangent(r);
  // Cholesky where the Hessian is positive definite (everywhere but at a limit point), a few
  // times faster than LDLT; LDLT where it is only semidefinite.
  const Eigen::LLT<Eigen::MatrixXd> llt(hessian);
  if (llt.info() == Eigen::Success) {
    Eigen::VectorXd t = llt.solve(g);
    if (t.allFinite()) return t;
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(hessian);
  if (ldlt.info() != Eigen::Success) return {};
  Eigen::VectorXd t = ldlt.solve(g);
  if (!t.allFinite()) return {};
  return t;
}

double JointCondensation::dissipation(const Eigen::Ref<const Eigen::VectorXd>& r) const {
  double d = 0;
  for (int j = 0; j < size(); ++j) {
    for (const Iwan& e : coords_[j].elements) d += e.dissipation(std::abs(r(j)));
  }
  return d;
}

bool JointCondensation::full_macroslip(const Eigen::Ref<const Eigen::VectorXd>& r) const {
  for (int j = 0; j < size(); ++j) {
    if (std::abs(r(j)) < phi_max_(j)) return false;
  }
  return true;
}

StaticSolve JointCondensation::solve(const Eigen::Ref<const Eigen::VectorXd>& g, double alpha,
                                     Eigen::VectorXd& r, double runaway, int max_iterations,
                                     Eigen::VectorXd* tangent) const {
  const int nj = size();
  assert(g.size() == nj && r.size() == nj);
  Eigen::VectorXd h(nj), dh(nj), kr(nj), grad(nj), step(nj), trial(nj), kt(nj);
  Eigen::MatrixXd hessian(nj, nj);
  Eigen::LLT<Eigen::MatrixXd> llt(nj);
  const Eigen::VectorXd load = alpha * g;
  const double kscale = stiffness_.diagonal().maxCoeff();
  double energy;

  auto potential = [&](const Eigen::VectorXd& x, Eigen::VectorXd& kx) {
    evaluate(x, h, dh, energy);
    kx.noalias() = stiffness_ * x;
    return 0.5 * x.dot(kx) - x.dot(load) - energy;
  };

  StaticSolve out;
  double pi = potential(r, kr);
  for (out.iterations = 0; out.iterations < max_iterations;) {
    grad = kr - load - h;
    const double scale =
        load.lpNorm<Eigen::Infinity>() + kr.lpNorm<Eigen::Infinity>() + h.lpNorm<Eigen::Infinity>();
    // Converged when the force balance holds to 1e-12 of the forces involved.
    if (grad.lpNorm<Eigen::Infinity>() <= 1e-12 * scale) {
      out.converged = true;
      break;
    }
    hessian = stiffness_;
    hessian.diagonal() -= dh;
    llt.compute(hessian);
    // The Hessian is positive semidefinite; it is singular only where the structure has
    // lost stiffness (Iwan elements in macroslip). A tiny shift then gives a direction
    // that the line search either accepts (no equilibrium: the solve runs away) or cuts.
    for (double shift = 1e-12 * kscale; llt.info() != Eigen::Success && shift < kscale;
         shift *= 1e3) {
      hessian.diagonal().array() += shift;
      llt.compute(hessian);
    }
    ++out.iterations;
    if (llt.info() != Eigen::Success) return out;
    step = -llt.solve(grad);
    const double slope = grad.dot(step);
    const double step_norm = step.lpNorm<Eigen::Infinity>();
    const double r_norm = r.lpNorm<Eigen::Infinity>();
    double t = 1;
    double pi_trial = 0;
    for (int halving = 0; halving < 80; ++halving, t *= 0.5) {
      trial = r + t * step;
      pi_trial = potential(trial, kt);
      // Armijo decrease; a step below 1e-6 of |r| is inside Newton's quadratic range,
      // where Pi differences are rounding noise, and is taken as it is.
      if (pi_trial <= pi + 1e-4 * t * slope || t * step_norm <= 1e-6 * r_norm) break;
    }
    r = trial;
    kr = kt;
    pi = pi_trial;
    if (!r.allFinite() || r.lpNorm<Eigen::Infinity>() > runaway) return out;
    if (t * step_norm <= 1e-15 * r_norm) {  // stagnation: accept only a small residual
      grad = kr - load - h;
      out.converged = grad.lpNorm<Eigen::Infinity>() <= 1e-9 * scale;
      break;
    }
  }
  // llt holds a factorization only when an iteration ran: ask it nothing otherwise.
  if (tangent && out.iterations > 0 && llt.info() == Eigen::Success) *tangent = llt.solve(g);
  if (tangent && out.iterations == 0) {
    hessian = stiffness_;
    hessian.diagonal() -= dh;  // dh is h'(r): the potential was last evaluated at r
    llt.compute(hessian);
    *tangent = llt.info() == Eigen::Success ? Eigen::VectorXd(llt.solve(g)) : Eigen::VectorXd();
  }
  return out;
}

}  // namespace jointlab::model
