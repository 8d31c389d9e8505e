// The condensed model (joint_condensation.h) of a structure as the parameters of one Iwan set
// vary: set up once, then at any parameters by an update of rank n_J.
//
// With every element e of the set at K_T instead of its stiffness k_e in the model,
//   K_lin(K_T) = K_lin,0 + B^T Delta B,   Delta = diag(d_j),  d_j = sum_e on j (K_T - k_e),
// B the Iwan coordinates (F_S, chi and beta leave K_lin alone). Then, exactly:
// - condensation: C^{-1} = C_0^{-1} + Delta (Woodbury's identity on C = B K_lin^-1 B^T), so
//   K_c(K_T) = K_c,0 + Delta: no new factorisation of the structure.
// - modes: in the model's modal coordinates (every mode once, densely: Phi_0^T K_lin,0 Phi_0 =
//   Lambda, Phi_0^T M Phi_0 = I) K_lin(K_T) is A = Lambda + U^T Delta U, U = B Phi_0 (elastic
//   columns; B Phi_rb = 0, so the rigid-body modes stay). Elastic mode k comes from Rayleigh
//   quotient iteration started at the model's mode k; each step solves (A - sigma) y = x with
//   the capacitance S(sigma) = Delta^-1 + U (Lambda - sigma)^-1 U^T (coordinates with d_j != 0
//   only), O(N n_J^2) instead of O(N^3) for a new eigen-solve. The converged pair is checked by
//   Sylvester's law of inertia: A has nu(Lambda - sigma) + pi(S(sigma)) - pi(Delta) eigenvalues
//   below sigma (Haynsworth's inertia additivity on [[Lambda - sigma, U^T], [U, -Delta^-1]]),
//   which must be k - 1 just below the eigenvalue and k just above it.
// - deflection: the constraint modes Psi = G B^T K_c do not change (joint_condensation.h), so
//   every condensation shares the model's.
// When that check fails (two modes within 1e-8 of each other, a mode that crossed another and
// is not found from its start) at() returns nothing: the caller builds the condensation from
// scratch.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/model/iwan.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"

namespace jointlab::model {

/// A model whose Iwan set `set` varies, set up once for its condensation at any parameters.
class IwanSetModel {
 public:
  /// Every linear mode of `model` (dense) and its condensation; condensations from at() keep
  /// the rigid-body modes and `elastic_count` elastic modes. InputError as JointCondensation,
  /// or if no Iwan element of the model belongs to `set`.
  IwanSetModel(const Model& model, const std::string& set, int elastic_count);

  /// The condensation with every element of the set at p (stiffness K_T = p.Kt); nothing when
  /// a mode cannot be vouched for (above). InputError as JointCondensation for parameters
  /// beyond double precision.
  std::optional<JointCondensation> at(const IwanParameters& p) const;

  /// Elastic modes of each condensation.
  int elastic_count() const { return elastic_count_; }

 private:
  // Elastic mode k (0-based) of A into x (elastic modal coordinates) and lambda; false when
  // it cannot be vouched for.
  bool mode(int k, const Eigen::MatrixXd& u, const Eigen::VectorXd& d, Eigen::VectorXd& x,
            double& lambda) const;

  std::vector<Joint> joints_;
  std::string set_;
  double modal_ratio_ = 0;       // the model's own damping, carried into every condensation
  std::vector<int> coordinate_;  // per joint: its Iwan coordinate (-1: not of the set)
  int elastic_count_ = 0;
  LinearModes modes_;                                        // every mode of the model
  Eigen::VectorXd lambda_;                                   // elastic omega^2 of the model
  Eigen::MatrixXd u_;                                        // B Phi_0, elastic columns (n_J x N_e)
  Eigen::MatrixXd stiffness_;                                // K_c,0
  std::shared_ptr<const Eigen::MatrixXd> constraint_modes_;  // Psi, the same at every K_T
};

}  // namespace jointlab::model
