// `jointlab build-model`: riveted beam description → full FE model → Craig–Bampton model
// directory in the contract's format (M.mtx, K.mtx, dofs.csv, model.toml).
//
// Reduced coordinates x = (u_b, q): first the boundary DOFs (the rivet reference nodes of
// strip 1 then strip 2, six components each, then the sensors' requested components), then
// the fixed-interface modal coordinates q (M-normalised, √kg·m). dofs.csv labels them
// `node,component`: reference node of rivet r on strip s → node 1000·s + r, sensors → their
// label, components 1..6 = x, y, z, rx, ry, rz [m, rad]; modal coordinate k → node 0,
// component k (1-based). K and M [N/m, kg] are the structure WITHOUT the joints; model.toml
// adds the six joint elements of each rivet between its two reference nodes:
// x and y → [iwan.rivet], z → spring.kz, rx and ry → spring.rxy, rz → spring.rz.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "jointlab/model/fe/riveted_beam.h"

namespace jointlab::model::fe {

/// Settings of build_reduced_model.
struct BuildOptions {
  /// Called with a short message before each long step (may be empty).
  std::function<void(const std::string&)> progress;
  /// Called often during the reduction (HcbOptions::interrupt); it may throw to stop the build
  /// (the Python module's Ctrl-C). May be empty.
  std::function<void()> interrupt;
};

/// A `node,component` label of one reduced DOF.
struct DofLabel {
  int node = 0;       ///< Node label (0 for modal coordinates).
  int component = 0;  ///< 1..6, or the mode number for node 0.
};

/// One joint element of the reduced model between reduced indices a and b.
struct ReducedJoint {
  int a = 0;            ///< Strip-1 reference DOF (0-based reduced index).
  int b = 0;            ///< Strip-2 reference DOF.
  std::string element;  ///< "iwan.rivet", "spring.kz", "spring.rxy" or "spring.rz".
  std::string comment;  ///< "rivet 3 x" and the like.
};

/// How the build ended, with sizes and timings.
struct BuildSummary {
  bool ok = false;               ///< False when the reduction failed (see report).
  int full_dofs = 0;             ///< Independent DOFs of the full FE model.
  int boundary_dofs = 0;         ///< Boundary DOFs kept.
  int modes = 0;                 ///< Fixed-interface modes kept.
  int elements = 0;              ///< Finite elements.
  double seconds_assembly = 0;   ///< Generating and assembling the full model.
  double seconds_reduction = 0;  ///< Craig–Bampton reduction.
  std::string report;            ///< One paragraph for people.
};

/// The reduced riveted beam, ready to write.
struct ReducedModel {
  Eigen::SparseMatrix<double> stiffness;     ///< Reduced K without joints [N/m, N, N·m].
  Eigen::SparseMatrix<double> mass;          ///< Reduced M [kg, kg·m, kg·m²].
  std::vector<DofLabel> labels;              ///< One per reduced DOF.
  std::vector<ReducedJoint> joints;          ///< Six per rivet.
  RivetedBeamDescription description;        ///< Joint parameters and provenance.
  Eigen::VectorXd interface_frequencies_hz;  ///< Fixed-interface natural frequencies.
  BuildSummary summary;                      ///< Status, sizes, timings.
};

/// Generates, assembles and reduces the riveted beam of a validated description.
ReducedModel build_reduced_model(const RivetedBeamDescription& d, const BuildOptions& options);

/// K + Σ k·[1 −1; −1 1] over the joints at their linear stiffness (K_T for Iwan elements);
/// `index(node, component 1..6)` maps a reference node DOF to a matrix index.
Eigen::SparseMatrix<double> with_joints(const Eigen::SparseMatrix<double>& k,
                                        const std::vector<RivetJoint>& joints,
                                        const RivetedBeamDescription& d,
                                        const std::function<int(int, int)>& index);

/// Same for the reduced model's joints.
Eigen::SparseMatrix<double> with_joints(const ReducedModel& m);

/// Natural frequencies [Hz] of the reduced model with every joint at its linear stiffness,
/// ascending (rigid-body modes near 0); a dense solve of the small reduced problem.
Eigen::VectorXd reduced_frequencies_hz(const ReducedModel& m);

/// The lowest n elastic natural frequencies [Hz] of the full (unreduced) model with every joint
/// at its linear stiffness: what the reduction approximates (a sparse shift-invert solve).
Eigen::VectorXd full_elastic_frequencies_hz(const RivetedBeamDescription& d, int n);

/// Writes M.mtx, K.mtx, dofs.csv and model.toml into dir (created if missing), together or
/// not at all (data/output_stage.h); InputError when the directory cannot be written.
void write_model_directory(const std::filesystem::path& dir, const ReducedModel& m);

}  // namespace jointlab::model::fe
