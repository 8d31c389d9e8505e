// A reduced structural model with joints, as read from a model file (TOML; see
// docs/model-file.md and the contract).
//
// Equation of motion: M u'' + K u + sum_j f_j(u) = F, u the matrix DOFs (m, rad),
// M [kg] and K [N/m] symmetric, M positive definite, K the structure WITHOUT its joints.
// A joint element acts on the relative displacement r = u_a - u_b (r = u_a when b is
// ground) with a force f(r) along (e_a - e_b): a linear spring f = k r, or an Iwan
// element f = F(r) (iwan.h). At linear stiffness k (spring k, Iwan K_T) a joint adds
// k [1 -1; -1 1] to K at rows/columns (a, b), or k at (a, a) to ground (method.md Eq. 4).
// Matrix indices are 0-based.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/SparseCore>

#include "jointlab/model/iwan.h"

namespace jointlab::model {

/// The index used for a joint end attached to the ground.
inline constexpr Eigen::Index kGround = -1;

/// One joint element between matrix indices a and b (or a and the ground).
struct Joint {
  Eigen::Index a = 0;        ///< first end, 0-based matrix index
  Eigen::Index b = kGround;  ///< second end, 0-based matrix index, or kGround
  std::string element;       ///< the element's name in the file ("iwan.rivet", "spring.kz")
  double stiffness = 0;      ///< linear stiffness: spring k or Iwan K_T [N/m]
  std::optional<Iwan> iwan;  ///< the Iwan element, absent for a linear spring
};

/// A structure (M, K without joints) and its joints.
struct Model {
  Eigen::SparseMatrix<double> mass;       ///< M [kg], symmetric positive definite
  Eigen::SparseMatrix<double> stiffness;  ///< K [N/m] without joints, symmetric
  std::vector<Joint> joints;              ///< every joint element
  std::vector<std::string> dof_labels;    ///< "node:component" per index, or empty
  /// The structure's own linear (viscous) damping: the damping ratio Z of every elastic mode
  /// ([damping] modal_ratio; 0 <= Z < 1, 0 when the file has none). It adds to the joints'
  /// damping in every QSMA damping column (method.md section 2, point 4).
  double modal_ratio = 0;

  /// Number of matrix DOFs.
  Eigen::Index size() const { return mass.rows(); }
  /// Number of Iwan elements among the joints.
  int iwan_count() const;
  /// K plus every joint at its linear stiffness (Eq. 4).
  Eigen::SparseMatrix<double> linear_stiffness() const;
  /// K_lin x formed element by element (K x, then k (x_a - x_b) per joint): free of the
  /// cancellation a joint far stiffer than the structure brings to the assembled matrix.
  Eigen::VectorXd apply_linear_stiffness(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// The largest joint stiffness (spring k or Iwan K_T) [N/m]; 0 without joints.
  double stiffest_joint() const;
};

/// Reads a model file and the matrices it names; InputError naming file and field or line.
Model read_model(const std::filesystem::path& path);

/// Checks a model built in code (sizes, symmetry, positive mass, joint indices); InputError.
void validate_model(const Model& model, const std::string& source = "model");

/// What a "node:component" label the model lacks should have been, for a message: ": node 9001
/// has only 9001:3", or ": it has no node 9001 ...".
std::string missing_label_hint(const Model& model, const std::string& label);

}  // namespace jointlab::model
