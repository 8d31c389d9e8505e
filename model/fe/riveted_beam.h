// The riveted beam: two identical strips stacked and joined by rivets, as a finite-element
// model (MITC4 shells, or Timoshenko beams for fast checks) with one coupling per rivet
// per strip, described by a TOML file (docs/model-description.md).
//
// Geometry (SI, metres): strip 1 spans x ∈ [0, L], y ∈ [−b/2, b/2] with its mid-surface at
// z = 0; strip 2 spans x ∈ [L − overlap, 2L − overlap] with its mid-surface at z = t (the
// strips touch at the interface z = t/2). Rivets sit in the overlap at (x_r, y_r); by
// default `count` rivets alternate between the rows y = ±row_offset at x_r = L − overlap +
// (r − ½)·overlap/count (two staggered rows). Each rivet r has one reference node per strip
// s at (x_r, y_r, t/2), labelled 1000·s + r: in the shell model tied by a distributing
// coupling to the strip's nodes within coupling_radius of the rivet; in the beam model a
// rigid link from the reference node to the beam node at x_r (the strip's centre line).
// The two reference nodes of a rivet coincide, so the rivet's six joint elements (x, y,
// z, rx, ry, rz) have zero length and pass rigid-body motion exactly.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/model/fe/fe_model.h"
#include "jointlab/model/iwan.h"

namespace jointlab::model::fe {

/// A requested measurement point: its DOFs become boundary DOFs of the reduction.
struct SensorDescription {
  int label = 0;                ///< Node label in dofs.csv (unique, not a rivet label).
  int strip = 1;                ///< Strip 1 or 2.
  double x = 0, y = 0;          ///< Position on the strip [m] (global x, y).
  std::vector<int> components;  ///< 1..6 = x, y, z, rx, ry, rz.
};

/// A named Iwan set of some of the rivets (`[[joint_set]]`): their x and y elements become
/// "iwan.<name>" with these parameters; the other rivets keep "iwan.rivet" and [joints].
struct JointSetDescription {
  std::string name;         ///< Set name (a word, not "rivet").
  std::vector<int> rivets;  ///< Its rivets, 1-based, as numbered in dofs.csv.
  double kt = 0;            ///< Iwan K_T [N/m].
  double fs = 0;            ///< Iwan slip force F_S [N].
  double chi = 0;           ///< Iwan exponent χ.
  double beta = 0;          ///< Iwan macroslip weight β.
};

/// Everything the riveted beam generator needs (see docs/model-description.md).
struct RivetedBeamDescription {
  std::string source = "description";           ///< File name, for messages.
  double length = 0.5;                          ///< Strip length L [m].
  double width = 0.0254;                        ///< Strip width b [m].
  double thickness = 0.003175;                  ///< Strip thickness t [m].
  double overlap = 0.5;                         ///< Length of the lapped region [m] (≤ L).
  double youngs_modulus = 69e9;                 ///< E [Pa].
  double poissons_ratio = 0.33;                 ///< ν.
  double density = 2700;                        ///< ρ [kg/m³].
  bool shell = true;                            ///< Shell (MITC4) model, else beam model.
  double element_size = 0.0025;                 ///< Target element edge [m].
  std::vector<Eigen::Vector2d> rivets;          ///< Rivet positions (x, y) [m].
  double coupling_radius = 0.004;               ///< Patch radius of the distributing couplings [m].
  double kt = 1e7;                              ///< Iwan K_T = k_x = k_y of each rivet [N/m].
  double fs = 50;                               ///< Iwan slip force F_S [N].
  double chi = -0.5;                            ///< Iwan exponent χ.
  double beta = 1.0;                            ///< Iwan macroslip weight β.
  double kz = 1e8;                              ///< Normal spring [N/m].
  double rxy = 1e3;                             ///< Bending (rx, ry) springs [N·m/rad].
  double rz = 1e2;                              ///< Twisting (rz) spring [N·m/rad].
  std::vector<SensorDescription> sensors;       ///< Measurement points.
  std::vector<JointSetDescription> joint_sets;  ///< Rivets with Iwan sets of their own.
  int fixed_interface_modes = 60;               ///< Fixed-interface modes kept by the reduction.
};

/// `count` rivets in two staggered rows at y = ±row_offset along the overlap.
std::vector<Eigen::Vector2d> staggered_rivets(double length, double overlap, int count,
                                              double row_offset);

/// The default description: 24 rivets in two staggered rows, a sensor at each end.
RivetedBeamDescription default_riveted_beam();

/// Reads a TOML description; unset fields keep default_riveted_beam()'s values. InputError
/// naming the file, line and field on any defect.
RivetedBeamDescription read_riveted_beam_description(const std::filesystem::path& path);

/// Checks the ranges and the geometry (rivets inside the overlap, labels unique, …);
/// InputError naming the field.
void validate(const RivetedBeamDescription& d);

/// A node whose DOFs are kept in the reduction, with its dofs.csv label.
struct LabelledNode {
  int node = 0;                 ///< FeModel node index.
  int label = 0;                ///< dofs.csv node label.
  std::vector<int> components;  ///< Kept components 1..6.
};

/// One joint element between two reference nodes of a rivet.
struct RivetJoint {
  int rivet = 0;        ///< Rivet number 1..n.
  int node_a = 0;       ///< Strip-1 reference node (FeModel index).
  int node_b = 0;       ///< Strip-2 reference node.
  int component = 1;    ///< 1..6 = x, y, z, rx, ry, rz.
  std::string element;  ///< "iwan.rivet", "spring.kz", "spring.rxy" or "spring.rz".
};

/// The generated finite-element model and what the reduction keeps.
struct RivetedBeam {
  FeModel fe;                          ///< Nodes, elements, couplings.
  std::vector<LabelledNode> boundary;  ///< Rivet reference nodes (strip 1, strip 2), sensors.
  std::vector<RivetJoint> joints;      ///< Six per rivet.
};

/// Builds the model of a validated description.
RivetedBeam build_riveted_beam(const RivetedBeamDescription& d);

/// The linear stiffness of a joint element name under d (K_T for an Iwan element).
double joint_stiffness(const RivetedBeamDescription& d, const std::string& element);

/// The Iwan parameters of element "iwan.rivet" or "iwan.<joint set>" under d.
IwanParameters joint_iwan(const RivetedBeamDescription& d, const std::string& element);

}  // namespace jointlab::model::fe
