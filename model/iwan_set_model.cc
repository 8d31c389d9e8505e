#include "jointlab/model/iwan_set_model.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include <fmt/format.h>

#include <Eigen/Cholesky>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"

namespace jointlab::model {
namespace {

constexpr int kMaxIterations = 30;    // Rayleigh quotient steps per mode
constexpr double kSeparation = 1e-8;  // relative distance of the inertia checks
// Relative change of the Rayleigh quotient that ends the iteration: the quotient's error is
// the square of the vector's, so the step that changed it by this much left a vector
// error of ~1e-7, which the cubic convergence has taken to rounding in that same step.
constexpr double kSettled = 1e-14;

// The capacitance S(sigma) = diag(1/d) + U (Lambda - sigma)^-1 U^T, factorised.
Eigen::LDLT<Eigen::MatrixXd> capacitance(const Eigen::MatrixXd& u, const Eigen::VectorXd& d,
                                         const Eigen::VectorXd& lambda, double sigma) {
  const Eigen::VectorXd inv = (lambda.array() - sigma).inverse().matrix();
  // The lower triangle only (what LDLT reads): half the product.
  const Eigen::MatrixXd w = u * inv.asDiagonal();
  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(u.rows(), u.rows());
  s.triangularView<Eigen::Lower>() = w * u.transpose();
  s.diagonal() += d.cwiseInverse();
  return Eigen::LDLT<Eigen::MatrixXd>(s);
}

// Number of eigenvalues of A = Lambda + U^T diag(d) U below sigma; -1 if undecided (sigma on
// an eigenvalue of Lambda, or S(sigma) singular).
int count_below(const Eigen::MatrixXd& u, const Eigen::VectorXd& d, const Eigen::VectorXd& lambda,
                double sigma) {
  int below = 0;
  for (Eigen::Index i = 0; i < lambda.size(); ++i) {
    if (lambda(i) == sigma) return -1;
    below += lambda(i) < sigma;
  }
  const Eigen::LDLT<Eigen::MatrixXd> s = capacitance(u, d, lambda, sigma);
  if (s.info() != Eigen::Success) return -1;
  const Eigen::VectorXd pivots = s.vectorD();
  for (Eigen::Index i = 0; i < pivots.size(); ++i) {
    if (!(pivots(i) != 0) || !std::isfinite(pivots(i))) return -1;
    below += pivots(i) > 0;
  }
  for (Eigen::Index i = 0; i < d.size(); ++i) below -= d(i) > 0;
  return below;
}

}  // namespace

IwanSetModel::IwanSetModel(const Model& model, const std::string& set, int elastic_count)
    : joints_(model.joints),
      set_(set),
      modal_ratio_(model.modal_ratio),
      elastic_count_(elastic_count) {
  ModesOptions one;
  one.elastic_count = 1;
  const JointCondensation base(model, one);
  stiffness_ = base.condensed_stiffness();
  constraint_modes_ = base.shared_constraint_modes();
  std::map<std::pair<Eigen::Index, Eigen::Index>, int> index;
  for (int j = 0; j < base.size(); ++j)
    index[{base.coordinates()[j].a, base.coordinates()[j].b}] = j;
  bool found = false;
  for (const Joint& joint : joints_) {
    int c = -1;
    if (joint.iwan && joint.element == set_) {
      std::pair<Eigen::Index, Eigen::Index> key{joint.a, kGround};
      if (joint.b != kGround) key = {std::min(joint.a, joint.b), std::max(joint.a, joint.b)};
      c = index.at(key);
      found = true;
    }
    coordinate_.push_back(c);
  }
  if (!found) throw InputError(fmt::format("no Iwan element of the model belongs to '{}'", set_));
  modes_ = linear_modes(model);
  const int rigid = modes_.rigid_count;
  if (elastic_count_ < 1 || elastic_count_ > modes_.size() - rigid) {
    throw InputError(fmt::format("mode {} does not exist: the model has {}", elastic_count_,
                                 counted(modes_.size() - rigid, "elastic mode")));
  }
  lambda_ = modes_.omega2.tail(modes_.size() - rigid);
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(base.size(), model.size());
  for (int j = 0; j < base.size(); ++j) {
    b(j, base.coordinates()[j].a) = 1.0;
    if (base.coordinates()[j].b != kGround) b(j, base.coordinates()[j].b) = -1.0;
  }
  u_ = b * modes_.shapes.rightCols(modes_.size() - rigid);
}

namespace {

// (A - sigma)^-1 x by Woodbury: z - L^-1 U^T S^-1 U z, z = L^-1 x, L = Lambda - sigma; empty
// when S is singular or the result is not finite (sigma on an eigenvalue).
Eigen::VectorXd shifted_solve(const Eigen::MatrixXd& u, const Eigen::VectorXd& d,
                              const Eigen::VectorXd& lambda, double sigma,
                              const Eigen::VectorXd& x) {
  const Eigen::VectorXd inv = (lambda.array() - sigma).inverse().matrix();
  const Eigen::VectorXd z = inv.cwiseProduct(x);
  const Eigen::LDLT<Eigen::MatrixXd> s = capacitance(u, d, lambda, sigma);
  if (s.info() != Eigen::Success) return {};
  Eigen::VectorXd y = z - inv.cwiseProduct(u.transpose() * s.solve(u * z));
  const double norm = y.norm();
  if (!(norm > 0) || !std::isfinite(norm)) return {};
  return y / norm;
}

}  // namespace

bool IwanSetModel::mode(int k, const Eigen::MatrixXd& u, const Eigen::VectorXd& d,
                        Eigen::VectorXd& x, double& lambda) const {
  const Eigen::Index ne = lambda_.size();
  const auto quotient = [&](const Eigen::VectorXd& v) {
    return v.dot(lambda_.cwiseProduct(v)) + (u * v).dot(d.cwiseProduct(u * v));
  };
  // Rayleigh quotient iteration from x; true when the pair found is the k-th.
  const auto iterate = [&](double sigma) {
    for (int it = 0; it < kMaxIterations; ++it) {
      const Eigen::VectorXd y = shifted_solve(u, d, lambda_, sigma, x);
      if (y.size() == 0) break;  // sigma is an eigenvalue to rounding: x is its vector
      x = y;
      const double next = quotient(x);
      const bool settled = std::abs(next - sigma) <= kSettled * std::abs(next);
      sigma = next;
      if (settled && it > 0) break;
    }
    lambda = sigma;
    if (!(lambda > 0) || !x.allFinite()) return false;
    const double gap = kSeparation * lambda;
    return count_below(u, d, lambda_, lambda - gap) == k &&
           count_below(u, d, lambda_, lambda + gap) == k + 1;
  };
  x = Eigen::VectorXd::Unit(ne, k);
  if (iterate(quotient(x))) return true;
  // The model's k-th mode led to another: bracket the k-th eigenvalue by its count (Weyl:
  // within Lambda_k + [min(d, 0), max(d, 0)] |U|_F^2), bisect it to 1e-6, then two steps of
  // inverse iteration at the bracket's centre and the quotient iteration from there.
  const double spread = u.squaredNorm();
  double lo = lambda_(k) + std::min(d.minCoeff(), 0.0) * spread;
  double hi = lambda_(k) + std::max(d.maxCoeff(), 0.0) * spread;
  lo = std::max(lo, 1e-300);
  for (int it = 0; it < 200 && hi - lo > 1e-6 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    const int below = count_below(u, d, lambda_, mid);
    if (below < 0) return false;
    (below <= k ? lo : hi) = mid;
  }
  const double centre = 0.5 * (lo + hi);
  x = Eigen::VectorXd::Ones(ne).normalized();
  for (int it = 0; it < 2; ++it) {
    const Eigen::VectorXd y = shifted_solve(u, d, lambda_, centre, x);
    if (y.size() == 0) return false;
    x = y;
  }
  return iterate(quotient(x));
}

std::optional<JointCondensation> IwanSetModel::at(const IwanParameters& p) const {
  std::vector<Joint> joints = joints_;
  Eigen::VectorXd d = Eigen::VectorXd::Zero(stiffness_.rows());
  for (size_t i = 0; i < joints.size(); ++i) {
    if (coordinate_[i] < 0) continue;
    d(coordinate_[i]) += p.Kt - joints[i].stiffness;
    joints[i].stiffness = p.Kt;
    joints[i].iwan = Iwan(p);
  }
  Eigen::MatrixXd kc = stiffness_;
  kc.diagonal() += d;

  const int rigid = modes_.rigid_count;
  LinearModes modes;
  modes.rigid_count = rigid;
  modes.omega2 = modes_.omega2.head(rigid + elastic_count_);
  modes.shapes = modes_.shapes.leftCols(rigid + elastic_count_);
  std::vector<Eigen::Index> active;
  for (Eigen::Index j = 0; j < d.size(); ++j)
    if (d(j) != 0) active.push_back(j);
  if (!active.empty()) {
    const Eigen::MatrixXd u = u_(active, Eigen::all);
    const Eigen::VectorXd da = d(active);
    for (int k = 0; k < elastic_count_; ++k) {
      Eigen::VectorXd x;
      double lambda = 0;
      if (!mode(k, u, da, x, lambda)) return std::nullopt;
      modes.omega2(rigid + k) = lambda;
      Eigen::VectorXd phi = modes_.shapes.rightCols(lambda_.size()) * x;
      Eigen::Index at;
      phi.cwiseAbs().maxCoeff(&at);
      if (phi(at) < 0) phi = -phi;
      modes.shapes.col(rigid + k) = phi;
    }
  }
  JointCondensation out(joints, std::move(modes), std::move(kc), constraint_modes_);
  out.set_linear_damping(modal_ratio_);
  return out;
}

}  // namespace jointlab::model
