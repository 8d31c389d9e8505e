#include "jointlab/model/fe/strip_mesh.h"

#include <cassert>

namespace jointlab::model::fe {

std::vector<double> uniform_stations(double a, double b, int n) {
  assert(n >= 1);
  std::vector<double> s(n + 1);
  for (int i = 0; i <= n; ++i) s[i] = a + (b - a) * i / n;
  return s;
}

StripGrid add_shell_strip(FeModel& model, const std::vector<double>& x,
                          const std::vector<double>& y, double z, const ShellSection& section) {
  StripGrid g;
  g.nx = static_cast<int>(x.size());
  g.ny = static_cast<int>(y.size());
  assert(g.nx >= 2 && g.ny >= 2);
  g.nodes.resize(g.nx * g.ny);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) g.nodes[i + g.nx * j] = model.add_node({x[i], y[j], z});
  for (int j = 0; j + 1 < g.ny; ++j)
    for (int i = 0; i + 1 < g.nx; ++i)
      model.add_shell({g.node(i, j), g.node(i + 1, j), g.node(i + 1, j + 1), g.node(i, j + 1)},
                      section);
  return g;
}

std::vector<int> add_beam_line(FeModel& model, const std::vector<double>& x, double y, double z,
                               const BeamSection& section) {
  std::vector<int> nodes;
  for (double xi : x) nodes.push_back(model.add_node({xi, y, z}));
  for (std::size_t i = 0; i + 1 < nodes.size(); ++i)
    model.add_beam(nodes[i], nodes[i + 1], Eigen::Vector3d::UnitY(), section);
  return nodes;
}

}  // namespace jointlab::model::fe
