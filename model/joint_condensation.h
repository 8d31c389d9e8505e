// The static joint problem of a model condensed to its Iwan joint coordinates.
//
// Model: K_lin u - B^T h(B u) = f, with K_lin = K + every joint at linear stiffness
// (model_file.h), r = B u the n_J joint coordinates (row j of B is e_a - e_b, or e_a to
// ground; Iwan elements on the same pair of DOFs share one coordinate), and
// h_j(r) = sum over its elements of K_T r - F(r) >= 0 the softening (iwan.h).
// Rigid-body modes Phi_rb (K_lin Phi_rb = 0) are removed by Phi_rb^T M u = 0; since
// K_lin is a sum of positive semidefinite terms, B Phi_rb = 0, so joints never see them.
// With G the elastic flexibility (K_lin G f = f, Phi_rb^T M G f = 0 for Phi_rb^T f = 0),
//   r = B G f + C h(r),   C = B G B^T   (n_J x n_J, symmetric positive definite),
// equivalently the stationarity of the convex potential
//   Pi(r) = 1/2 r^T K_c r - r^T K_c r_f - sum_j H_j(r_j),   K_c = C^{-1},  r_f = B G f,
// H_j = int h_j, whose Hessian K_c - diag(h'_j) is the joint-condensed stiffness of the
// structure with the Iwan elements at their current tangent (>= 0: K_c - diag(K_T) is
// the condensed stiffness without the Iwan elements). A load past the largest the joints
// can carry leaves Pi unbounded below: no static solution exists.
// C is built once per model (one sparse Cholesky of K_lin with n_rb statically determinate
// DOFs clamped, see the constructor); each solve is a Newton iteration of size n_J with a
// line search on Pi.
// The deflection itself follows from r: u = G (f + B^T h(r)) and h(r) = K_c (r - r_f), so
//   u = Psi r + G f - Psi B G f,   Psi = G B^T K_c   (n x n_J, the constraint modes),
// Psi's column j the deflection of the unloaded structure when coordinate j moves by one and
// the others are held. Psi does not depend on the joints' stiffness (with every coordinate
// held the joints carry no deformation of their own): K_lin + B^T Delta B leaves K_c B G
// alone, since K_c gains Delta while B G loses exactly (I + C Delta)^-1 of itself.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "jointlab/model/iwan.h"
#include "jointlab/model/iwan_cycle.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"

namespace jointlab::model {

/// One joint coordinate r = u_a - u_b (u_a when b is ground) and the Iwan elements on it.
struct JointCoordinate {
  Eigen::Index a = 0;          ///< first DOF
  Eigen::Index b = kGround;    ///< second DOF or kGround
  std::vector<Iwan> elements;  ///< Iwan elements acting on this coordinate
};

/// Outcome of one static solve.
struct StaticSolve {
  bool converged = false;  ///< false: no equilibrium found (diverged or iteration limit)
  int iterations = 0;      ///< Newton iterations (Hessian factorizations)
};

/// The model condensed to its Iwan coordinates; built once, then solved at any load.
class JointCondensation {
 public:
  /// Computes the linear modes `modes` asks for (every mode by default; elastic_count = R
  /// for QSMA of mode R), the joint coordinates and C = B G B^T; InputError if the model
  /// has no Iwan element or its Iwan coordinates are linearly dependent.
  explicit JointCondensation(const Model& model, const ModesOptions& modes = {});
  /// From parts computed elsewhere (iwan_set_model.h): the joints give the coordinates and
  /// their laws (in the order the model constructor groups them), with the model's linear
  /// modes, K_c = C^{-1} and the constraint modes Psi (of any condensation of the same
  /// structure: Psi does not depend on the joints' stiffness; null: none); InputError as the
  /// model constructor, or if K_c is not positive definite.
  JointCondensation(const std::vector<Joint>& joints, LinearModes modes,
                    Eigen::MatrixXd condensed_stiffness,
                    std::shared_ptr<const Eigen::MatrixXd> constraint_modes = nullptr);

  /// The linear modes computed (rigid-body modes first) with joints at linear stiffness.
  const LinearModes& modes() const { return modes_; }
  /// Number of elastic modes computed.
  int elastic_count() const { return modes_.size() - modes_.rigid_count; }
  /// The joint coordinates (n_J of them).
  const std::vector<JointCoordinate>& coordinates() const { return coords_; }
  /// Number of joint coordinates n_J.
  int size() const { return static_cast<int>(coords_.size()); }
  /// C = B G B^T, the elastic flexibility seen by the joint coordinates [m/N].
  const Eigen::MatrixXd& flexibility() const { return flexibility_; }
  /// K_c = C^{-1}, the joint-condensed linear stiffness [N/m].
  const Eigen::MatrixXd& condensed_stiffness() const { return stiffness_; }
  /// Psi = G B^T K_c (n x n_J, rigid-body motion removed: Phi_rb^T M Psi = 0): the static
  /// deflection u = Psi r + G f - Psi B G f of a solution r under load f (above); empty when
  /// the parts constructor was given none.
  const Eigen::MatrixXd& constraint_modes() const { return *constraint_modes_; }
  /// Psi shared, for a condensation of the same structure at other joint stiffness.
  const std::shared_ptr<const Eigen::MatrixXd>& shared_constraint_modes() const {
    return constraint_modes_;
  }
  /// B Phi: the joint coordinates of every mode shape (n_J x n).
  const Eigen::MatrixXd& joint_shapes() const { return joint_shapes_; }
  /// B u for a vector of matrix DOFs.
  Eigen::VectorXd joint_motion(const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// Macroslip displacement of coordinate j: the largest phi_max of its elements [m].
  double phi_max(int j) const { return phi_max_(j); }
  /// The smallest phi_max over every element [m].
  double smallest_phi_max() const { return phi_max_min_; }
  /// Smallest chi + 1 over every element (slowest microslip power law).
  double smallest_chi_plus_one() const { return chi1_min_; }

  /// The structure's own modal damping ratio Z (Model::modal_ratio), added to every QSMA
  /// damping column (qsma.h); 0 by default and for the parts constructor.
  double linear_damping() const { return linear_damping_; }
  /// Sets Z (0 <= Z < 1, checked by the caller).
  void set_linear_damping(double z) { linear_damping_ = z; }

  /// Linear (zero-load) stiffness of coordinate j: the sum of its elements' K_T [N/m].
  double linear_stiffness(int j) const { return kt_(j); }

  /// Softening h_j(r_j) of every coordinate [N].
  Eigen::VectorXd softening(const Eigen::Ref<const Eigen::VectorXd>& r) const;
  /// Its derivative h'_j(r_j) in [0, K_T] [N/m].
  Eigen::VectorXd softening_tangent(const Eigen::Ref<const Eigen::VectorXd>& r) const;
  /// The softening h and its derivative h' together (one evaluation of the laws).
  void softening(const Eigen::Ref<const Eigen::VectorXd>& r, Eigen::VectorXd& h,
                 Eigen::VectorXd& dh) const;
  /// In-phase first-harmonic stiffness of each coordinate in a steady cycle of amplitude
  /// |r_j| (iwan_cycle.h), summed over its elements [N/m].
  Eigen::VectorXd first_harmonic_stiffness(const Eigen::Ref<const Eigen::VectorXd>& r) const;
  /// h, h' and the first-harmonic stiffness k_1 with its slope dk_1/dr together: one power
  /// per element below phi_max (the laws share |r|^(chi+1)).
  void softening_and_harmonic(const Eigen::Ref<const Eigen::VectorXd>& r, Eigen::VectorXd& h,
                              Eigen::VectorXd& dh, Eigen::VectorXd& k1, Eigen::VectorXd& dk1) const;
  /// Energy the Iwan elements store at the turning point of cycles of amplitudes |r| [J].
  double turning_point_energy(const Eigen::Ref<const Eigen::VectorXd>& r) const;
  /// dr/dalpha = (K_c - diag h'(r))^{-1} g at r (Cholesky, or LDLT: finite also at a limit
  /// point where the Hessian is only semidefinite); empty when it is singular.
  Eigen::VectorXd tangent(const Eigen::Ref<const Eigen::VectorXd>& g,
                          const Eigen::Ref<const Eigen::VectorXd>& r) const;
  /// Energy dissipated in one Masing cycle with joint amplitudes |r| [J].
  double dissipation(const Eigen::Ref<const Eigen::VectorXd>& r) const;
  /// True when every Iwan element is at or past its phi_max.
  bool full_macroslip(const Eigen::Ref<const Eigen::VectorXd>& r) const;

  /// Solves K_c r - h(r) = alpha * g from the guess in r (on return: the solution when
  /// converged). When tangent is given it receives dr/dalpha = (K_c - diag h')^{-1} g from
  /// the last factorization (a continuation predictor). A solve whose coordinates grow
  /// past `runaway` is stopped as diverged.
  StaticSolve solve(const Eigen::Ref<const Eigen::VectorXd>& g, double alpha, Eigen::VectorXd& r,
                    double runaway, int max_iterations, Eigen::VectorXd* tangent = nullptr) const;

 private:
  // One element's law with its constants precomputed (one pow per evaluation).
  struct Law {
    double Kt, Fs, phi_max, chi1, a1, a2, a3, e_max;
    // Below phi_max, k_1 = k1_0 + k1_p |r|^chi1 and dk_1/d|r| = dk1_p |r|^chi1 / |r|.
    double k1_0 = 0, k1_p = 0, dk1_p = 0;
    // h, h' and the stored energy at r; returns |r|^chi1 below phi_max (0 beyond), the power
    // the microslip terms of h, h' and k_1 share.
    double eval(double r, double& h, double& dh, double& energy) const;
  };
  // Groups the Iwan elements of `joints` into coordinates with their laws.
  void set_coordinates(const std::vector<Joint>& joints);
  void evaluate(const Eigen::VectorXd& r, Eigen::VectorXd& h, Eigen::VectorXd& dh,
                double& energy) const;

  LinearModes modes_;
  std::vector<JointCoordinate> coords_;
  std::vector<std::vector<Law>> laws_;
  std::vector<std::vector<IwanCycle>> cycles_;
  Eigen::MatrixXd flexibility_, stiffness_, joint_shapes_;
  std::shared_ptr<const Eigen::MatrixXd> constraint_modes_;  // Psi (never null); shared by copies
  Eigen::VectorXd phi_max_, kt_;
  double phi_max_min_ = 0, chi1_min_ = 1;
  double linear_damping_ = 0;
};

}  // namespace jointlab::model
