// Structured meshes of flat strips: a grid of MITC4 shells in a plane z = const, or a line
// of Timoshenko beams along x.
//
// The shell grid has node (i, j) at (x_i, y_j, z), i along x, j along y, elements
// counter-clockwise about +z. The beam line has nodes at (x_i, y, z) with the section's
// local y along global y (so I_y bends the strip out of its plane, in z). Metres.
#pragma once

#include <vector>

#include "jointlab/model/fe/fe_model.h"

namespace jointlab::model::fe {

/// Node indices of a structured shell grid.
struct StripGrid {
  int nx = 0;              ///< Stations along x.
  int ny = 0;              ///< Stations along y.
  std::vector<int> nodes;  ///< Node index of (i, j) at i + nx·j.
  /// Node index at station (i, j).
  int node(int i, int j) const { return nodes[i + nx * j]; }
};

/// n + 1 equally spaced stations from a to b.
std::vector<double> uniform_stations(double a, double b, int n);

/// Adds a shell grid on the stations x × y at height z; stations strictly increasing.
StripGrid add_shell_strip(FeModel& model, const std::vector<double>& x,
                          const std::vector<double>& y, double z, const ShellSection& section);

/// Adds a line of beams through (x_i, y, z); returns the node indices in x order.
std::vector<int> add_beam_line(FeModel& model, const std::vector<double>& x, double y, double z,
                               const BeamSection& section);

}  // namespace jointlab::model::fe
