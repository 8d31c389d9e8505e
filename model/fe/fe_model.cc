#include "jointlab/model/fe/fe_model.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>

#include <fmt/format.h>
#include <Eigen/Dense>

#include "jointlab/core/error.h"
#include "jointlab/model/fe/couplings.h"

namespace jointlab::model::fe {
namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

void scatter(Triplets& k, Triplets& m, const ElementMatrices& e, const std::vector<int>& nodes) {
  const int n = static_cast<int>(e.stiffness.rows());
  std::vector<int> map(n);
  for (int i = 0; i < n; ++i) map[i] = 6 * nodes[i / 6] + i % 6;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (e.stiffness(i, j) != 0) k.emplace_back(map[i], map[j], e.stiffness(i, j));
      if (e.mass(i, j) != 0) m.emplace_back(map[i], map[j], e.mass(i, j));
    }
}

// One dependent DOF as a combination of other full DOFs.
struct Dependency {
  std::vector<std::pair<int, double>> terms;
};

}  // namespace

int FeModel::add_node(const Eigen::Vector3d& x) {
  nodes_.push_back(x);
  keep_.push_back(0);
  return node_count() - 1;
}

void FeModel::add_beam(int a, int b, const Eigen::Vector3d& y_axis, const BeamSection& section) {
  assert(a >= 0 && a < node_count() && b >= 0 && b < node_count() && a != b);
  beams_.push_back({a, b, y_axis, section});
}

void FeModel::add_shell(const std::array<int, 4>& nodes, const ShellSection& section) {
  assert(
      std::all_of(nodes.begin(), nodes.end(), [&](int n) { return n >= 0 && n < node_count(); }));
  shells_.push_back({nodes, section});
}

void FeModel::add_distributing_coupling(int reference, const std::vector<int>& patch) {
  assert(reference >= 0 && reference < node_count());
  couplings_.push_back({reference, patch});
}

void FeModel::add_rigid_link(int master, int slave) {
  assert(master >= 0 && master < node_count() && slave >= 0 && slave < node_count());
  links_.push_back({master, slave});
}

void FeModel::keep_independent(int node) {
  assert(node >= 0 && node < node_count());
  keep_[node] = 1;
}

std::vector<int> FeModel::nodes_within(const Eigen::Vector3d& centre, double radius,
                                       const std::vector<int>& candidates) const {
  std::vector<int> out;
  const auto test = [&](int i) {
    if ((nodes_[i] - centre).norm() <= radius) out.push_back(i);
  };
  if (candidates.empty()) {
    for (int i = 0; i < node_count(); ++i) test(i);
  } else {
    for (int i : candidates) test(i);
  }
  return out;
}

AssembledModel FeModel::assemble() const {
  const int n_full = 6 * node_count();
  Triplets kt, mt;
  kt.reserve(beams_.size() * 144 + shells_.size() * 400);
  mt.reserve(beams_.size() * 144 + shells_.size() * 400);
  for (const Beam& b : beams_)
    scatter(kt, mt, beam_element(nodes_[b.a], nodes_[b.b], b.y_axis, b.section), {b.a, b.b});
  for (const Shell& s : shells_) {
    const std::array<Eigen::Vector3d, 4> x = {nodes_[s.nodes[0]], nodes_[s.nodes[1]],
                                              nodes_[s.nodes[2]], nodes_[s.nodes[3]]};
    scatter(kt, mt, shell_element(x, s.section), {s.nodes[0], s.nodes[1], s.nodes[2], s.nodes[3]});
  }
  Eigen::SparseMatrix<double> k_full(n_full, n_full), m_full(n_full, n_full);
  k_full.setFromTriplets(kt.begin(), kt.end());
  m_full.setFromTriplets(mt.begin(), mt.end());
  kt.clear();
  mt.clear();

  // Nodes that must stay independent: kept nodes, references and masters.
  std::vector<char> fixed_node = keep_;
  for (const Coupling& c : couplings_) fixed_node[c.reference] = 1;
  for (const Link& l : links_) fixed_node[l.master] = 1;

  std::map<int, Dependency> dependent;
  const auto make_dependent = [&](int d, Dependency dep) {
    if (!dependent.emplace(d, std::move(dep)).second)
      throw InputError(
          fmt::format("node {} component {} is tied by two couplings", d / 6, d % 6 + 1));
  };
  for (const Link& l : links_) {
    if (fixed_node[l.slave])
      throw InputError(fmt::format(
          "rigid link slave node {} is also a reference, master or kept node", l.slave));
    const Eigen::Matrix<double, 6, 6> g = rigid_link_matrix(nodes_[l.master], nodes_[l.slave]);
    for (int i = 0; i < 6; ++i) {
      Dependency dep;
      for (int j = 0; j < 6; ++j)
        if (g(i, j) != 0) dep.terms.emplace_back(6 * l.master + j, g(i, j));
      make_dependent(6 * l.slave + i, std::move(dep));
    }
  }
  for (const Coupling& c : couplings_) {
    std::vector<Eigen::Vector3d> x;
    for (int p : c.patch) x.push_back(nodes_[p]);
    Eigen::MatrixXd g;
    try {
      g = distributing_coupling_matrix(nodes_[c.reference], x);
    } catch (const InputError& e) {
      throw InputError(fmt::format("coupling of reference node {}: {}", c.reference, e.what()));
    }
    // Candidate dependent columns: translations of patch nodes free to be eliminated.
    std::vector<int> allowed;
    for (int i = 0; i < static_cast<int>(c.patch.size()); ++i)
      if (!fixed_node[c.patch[i]] && !dependent.count(6 * c.patch[i]))
        for (int k = 0; k < 3; ++k) allowed.push_back(3 * i + k);
    Eigen::MatrixXd ga(6, allowed.size());
    for (int j = 0; j < static_cast<int>(allowed.size()); ++j) ga.col(j) = g.col(allowed[j]);
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(ga);
    const Eigen::MatrixXd r = qr.matrixR().template triangularView<Eigen::Upper>();
    if (allowed.size() < 6 || std::abs(r(5, 5)) <= 1e-9 * std::abs(r(0, 0)))
      throw InputError(fmt::format(
          "coupling of reference node {}: too few free patch nodes to carry the coupling",
          c.reference));
    std::vector<int> dep_cols(6);
    std::vector<char> is_dep(g.cols(), 0);
    for (int k = 0; k < 6; ++k) {
      dep_cols[k] = allowed[qr.colsPermutation().indices()(k)];
      is_dep[dep_cols[k]] = 1;
    }
    Eigen::Matrix<double, 6, 6> gd;
    for (int k = 0; k < 6; ++k) gd.col(k) = g.col(dep_cols[k]);
    const Eigen::Matrix<double, 6, 6> gd_inv = gd.inverse();
    // u_dep = Gd⁻¹ (u_ref − Σ_other G_j u_j).
    const auto full_dof = [&](int col) { return 6 * c.patch[col / 3] + col % 3; };
    for (int k = 0; k < 6; ++k) {
      Dependency dep;
      for (int j = 0; j < 6; ++j) dep.terms.emplace_back(6 * c.reference + j, gd_inv(k, j));
      for (int col = 0; col < g.cols(); ++col) {
        if (is_dep[col]) continue;
        const double v = -gd_inv.row(k).dot(g.col(col));
        if (v != 0) dep.terms.emplace_back(full_dof(col), v);
      }
      make_dependent(full_dof(dep_cols[k]), std::move(dep));
    }
  }
  for (const auto& [d, dep] : dependent)
    for (const auto& [j, v] : dep.terms)
      if (dependent.count(j))
        throw InputError(fmt::format(
            "couplings chain: node {} component {} depends on a DOF that is itself tied", d / 6,
            d % 6 + 1));

  AssembledModel out;
  out.index.assign(n_full, -1);
  int n_ind = 0;
  for (int i = 0; i < n_full; ++i)
    if (!dependent.count(i)) out.index[i] = n_ind++;
  Triplets tt;
  tt.reserve(n_full + 40 * dependent.size());
  for (int i = 0; i < n_full; ++i) {
    if (out.index[i] >= 0) {
      tt.emplace_back(i, out.index[i], 1.0);
    } else {
      for (const auto& [j, v] : dependent.at(i).terms) tt.emplace_back(i, out.index[j], v);
    }
  }
  out.transformation.resize(n_full, n_ind);
  out.transformation.setFromTriplets(tt.begin(), tt.end());
  const Eigen::SparseMatrix<double> tt_t = out.transformation.transpose();
  out.stiffness = tt_t * (k_full * out.transformation);
  out.mass = tt_t * (m_full * out.transformation);
  // Exact symmetry (the products above are symmetric only to round-off).
  out.stiffness = 0.5 * (out.stiffness + Eigen::SparseMatrix<double>(out.stiffness.transpose()));
  out.mass = 0.5 * (out.mass + Eigen::SparseMatrix<double>(out.mass.transpose()));
  out.stiffness.prune(0.0);
  out.mass.prune(0.0);
  return out;
}

}  // namespace jointlab::model::fe
