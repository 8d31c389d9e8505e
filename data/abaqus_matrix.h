// Abaqus matrix output (*MATRIX GENERATE + *MATRIX OUTPUT) read into sparse M and K.
//
// Two text layouts, one entry per line, comma (or blank) separated:
//   FORMAT=MATRIX INPUT (default): "row node, row DOF, column node, column DOF, value";
//   FORMAT=COORDINATE:             "row, column, value" (1-based equation numbers).
// Lines starting with '*' (keywords, "**" comments) and blank lines are skipped. A
// symmetric matrix may be stored as its lower triangle, its upper triangle or in full;
// the full matrix is rebuilt from a triangle, and a full one must be symmetric. Each
// matrix index has a label (node, component): the node number and the DOF number (1-3
// translations, 4-6 rotations, ...) of the MATRIX INPUT layout, or (equation number, 0)
// for the COORDINATE layout, which carries no node numbers. Indices are ordered by
// label (node, then component). Values are taken as written, in the model's own
// consistent units (jointlab expects SI: N/m, kg). See docs/abaqus-matrix.md.
#pragma once

#include <compare>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/SparseCore>

namespace jointlab::data {

/// The node and component (DOF number; 0 when unknown) of one matrix index.
struct DofLabel {
  long node = 0;      ///< node number (equation number in the COORDINATE layout)
  int component = 0;  ///< Abaqus DOF number, 0 in the COORDINATE layout
  /// Ordered by node, then component.
  auto operator<=>(const DofLabel&) const = default;
};

/// One matrix read from an Abaqus .mtx file, with the label of every index.
struct AbaqusMatrix {
  Eigen::SparseMatrix<double> matrix;  ///< full symmetric matrix
  std::vector<DofLabel> dofs;          ///< label of each row/column, ascending
};

/// Mass and stiffness on one common, labelled set of indices.
struct AbaqusModel {
  Eigen::SparseMatrix<double> mass;       ///< M, full symmetric
  Eigen::SparseMatrix<double> stiffness;  ///< K, full symmetric
  std::vector<DofLabel> dofs;             ///< label of each index (union of both files)
};

/// Reads one Abaqus matrix file; InputError ("file:line: what") on any defect.
AbaqusMatrix read_abaqus_matrix(const std::filesystem::path& path);

/// Parses Abaqus matrix text as if read from a file named `name` (used by fuzzing).
AbaqusMatrix parse_abaqus_matrix(std::string_view text, const std::string& name);

/// Reads M and K files and puts both on the union of their labelled indices.
AbaqusModel read_abaqus_model(const std::filesystem::path& mass,
                              const std::filesystem::path& stiffness);

}  // namespace jointlab::data
