// A finite-element model: nodes with six DOFs, beam and shell elements, couplings;
// assembled into sparse stiffness and mass on the independent DOFs.
//
// Full DOF numbering: 6·node + c, c = 0..5 for (u_x, u_y, u_z, θ_x, θ_y, θ_z) [m, rad].
// Couplings (couplings.h) make some DOFs dependent, u_d = G u_i; assembly eliminates them
// with the transformation u_full = T u, so K = Tᵀ K_full T and M = Tᵀ M_full T [N/m, kg].
// A distributing coupling's dependent DOFs are six translations of its patch chosen by
// column-pivoted QR of G (the reference node stays independent, so it can be a boundary
// DOF); a rigid link's dependent DOFs are the slave's six. A DOF can be dependent in one
// constraint only and constraints do not chain (InputError otherwise).
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "jointlab/model/fe/beam_element.h"
#include "jointlab/model/fe/shell_element.h"

namespace jointlab::model::fe {

/// Sparse K and M on the independent DOFs and the map from full DOFs to them.
struct AssembledModel {
  Eigen::SparseMatrix<double> stiffness;       ///< K = Tᵀ K_full T [N/m, N, N·m].
  Eigen::SparseMatrix<double> mass;            ///< M = Tᵀ M_full T [kg, kg·m, kg·m²].
  Eigen::SparseMatrix<double> transformation;  ///< T: u_full (6 per node) = T u.
  std::vector<int> index;  ///< Full DOF 6·node + c → independent index, or −1 if dependent.

  /// Independent index of (node, component 0..5); −1 when that DOF is dependent.
  int dof(int node, int component) const { return index[6 * node + component]; }
  /// Number of independent DOFs.
  int size() const { return static_cast<int>(stiffness.rows()); }
};

/// Nodes, elements and couplings of one structure; assemble() builds the matrices.
class FeModel {
 public:
  /// Adds a node at x [m]; returns its index.
  int add_node(const Eigen::Vector3d& x);
  /// Adds a Timoshenko beam between nodes a and b (y_axis fixes the section's local y).
  void add_beam(int a, int b, const Eigen::Vector3d& y_axis, const BeamSection& section);
  /// Adds a flat MITC4 shell on four nodes, counter-clockwise about its normal.
  void add_shell(const std::array<int, 4>& nodes, const ShellSection& section);
  /// Ties `reference` to the translations of `patch` by a uniform distributing coupling.
  void add_distributing_coupling(int reference, const std::vector<int>& patch);
  /// Ties all six DOFs of `slave` rigidly to `master`.
  void add_rigid_link(int master, int slave);
  /// Keeps every DOF of `node` independent (a sensor or boundary node inside a patch).
  void keep_independent(int node);

  /// Indices of `candidates` within `radius` [m] of `centre` (all nodes when empty).
  std::vector<int> nodes_within(const Eigen::Vector3d& centre, double radius,
                                const std::vector<int>& candidates) const;
  /// Number of nodes.
  int node_count() const { return static_cast<int>(nodes_.size()); }
  /// Position of node i [m].
  const Eigen::Vector3d& node(int i) const { return nodes_[i]; }
  /// Number of beam plus shell elements.
  int element_count() const { return static_cast<int>(beams_.size() + shells_.size()); }

  /// Assembles K and M with every coupling eliminated; InputError on inconsistent couplings.
  AssembledModel assemble() const;

 private:
  struct Beam {
    int a, b;
    Eigen::Vector3d y_axis;
    BeamSection section;
  };
  struct Shell {
    std::array<int, 4> nodes;
    ShellSection section;
  };
  struct Coupling {
    int reference;
    std::vector<int> patch;
  };
  struct Link {
    int master, slave;
  };
  std::vector<Eigen::Vector3d> nodes_;
  std::vector<Beam> beams_;
  std::vector<Shell> shells_;
  std::vector<Coupling> couplings_;
  std::vector<Link> links_;
  std::vector<char> keep_;
};

}  // namespace jointlab::model::fe
