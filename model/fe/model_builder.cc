#include "jointlab/model/fe/model_builder.h"

#include <cassert>
#include <chrono>
#include <map>

#include <fmt/format.h>
#include <Eigen/Dense>

#include "jointlab/core/error.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/data/matrix_market.h"
#include "jointlab/data/output_stage.h"
#include "jointlab/model/fe/hcb.h"
#include "jointlab/model/model_file_writer.h"
#include "jointlab/model/sparse_eigen.h"

namespace jointlab::model::fe {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

const char* component_name(int c) {
  static const char* const names[6] = {"x", "y", "z", "rx", "ry", "rz"};
  return names[c - 1];
}

void add_spring(std::vector<Eigen::Triplet<double>>& t, int a, int b, double k) {
  t.emplace_back(a, a, k);
  t.emplace_back(b, b, k);
  t.emplace_back(a, b, -k);
  t.emplace_back(b, a, -k);
}

}  // namespace

Eigen::SparseMatrix<double> with_joints(const Eigen::SparseMatrix<double>& k,
                                        const std::vector<RivetJoint>& joints,
                                        const RivetedBeamDescription& d,
                                        const std::function<int(int, int)>& index) {
  std::vector<Eigen::Triplet<double>> t;
  for (const RivetJoint& j : joints)
    add_spring(t, index(j.node_a, j.component), index(j.node_b, j.component),
               joint_stiffness(d, j.element));
  Eigen::SparseMatrix<double> s(k.rows(), k.cols());
  s.setFromTriplets(t.begin(), t.end());
  return k + s;
}

Eigen::SparseMatrix<double> with_joints(const ReducedModel& m) {
  std::vector<Eigen::Triplet<double>> t;
  for (const ReducedJoint& j : m.joints)
    add_spring(t, j.a, j.b, joint_stiffness(m.description, j.element));
  Eigen::SparseMatrix<double> s(m.stiffness.rows(), m.stiffness.cols());
  s.setFromTriplets(t.begin(), t.end());
  return m.stiffness + s;
}

ReducedModel build_reduced_model(const RivetedBeamDescription& d, const BuildOptions& options) {
  const auto say = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  ReducedModel out;
  out.description = d;
  const Clock::time_point t0 = Clock::now();
  say(fmt::format("generating the {} model ({} rivets, element size {} m)",
                  d.shell ? "shell" : "beam", d.rivets.size(), d.element_size));
  const RivetedBeam beam = build_riveted_beam(d);
  say(fmt::format("assembling {} elements, {} nodes", beam.fe.element_count(),
                  beam.fe.node_count()));
  AssembledModel a;
  try {
    a = beam.fe.assemble();
  } catch (const InputError& e) {
    throw InputError(where(d.source, 0, e.what()));
  }
  out.summary.seconds_assembly = seconds_since(t0);
  out.summary.full_dofs = a.size();
  out.summary.elements = beam.fe.element_count();

  // Boundary DOFs in output order, with their labels.
  std::vector<int> boundary;
  std::map<std::pair<int, int>, int> reduced_index;  // (fe node, component) → reduced index
  for (const LabelledNode& n : beam.boundary)
    for (int c : n.components) {
      const int i = a.dof(n.node, c - 1);
      assert(i >= 0);
      reduced_index[{n.node, c}] = static_cast<int>(boundary.size());
      boundary.push_back(i);
      out.labels.push_back({n.label, c});
    }
  const Clock::time_point t1 = Clock::now();
  HcbOptions ho;
  ho.fixed_interface_modes = d.fixed_interface_modes;
  ho.progress = options.progress;
  ho.interrupt = options.interrupt;
  const HcbReduction r = reduce_hcb(a.stiffness, a.mass, boundary, ho);
  out.summary.seconds_reduction = seconds_since(t1);
  out.summary.boundary_dofs = static_cast<int>(boundary.size());
  if (!r.summary.ok()) {
    out.summary.ok = false;
    out.summary.report = r.summary.report;
    return out;
  }
  out.summary.modes = r.summary.modes;
  out.stiffness = r.stiffness;
  out.mass = r.mass;
  out.interface_frequencies_hz = frequencies_hz(r.interface_eigenvalues);
  for (int k = 1; k <= r.summary.modes; ++k) out.labels.push_back({0, k});
  for (const RivetJoint& j : beam.joints)
    out.joints.push_back({reduced_index.at({j.node_a, j.component}),
                          reduced_index.at({j.node_b, j.component}), j.element,
                          fmt::format("rivet {} {}", j.rivet, component_name(j.component))});
  out.summary.ok = true;
  out.summary.report =
      fmt::format("{} model: {} elements, {} DOFs, assembled in {:.2f} s; {}; reduced in {:.2f} s",
                  d.shell ? "shell" : "beam", out.summary.elements, out.summary.full_dofs,
                  out.summary.seconds_assembly, r.summary.report, out.summary.seconds_reduction);
  return out;
}

Eigen::VectorXd reduced_frequencies_hz(const ReducedModel& m) {
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(
      Eigen::MatrixXd(with_joints(m)), Eigen::MatrixXd(m.mass), Eigen::EigenvaluesOnly);
  return frequencies_hz(es.eigenvalues());
}

Eigen::VectorXd full_elastic_frequencies_hz(const RivetedBeamDescription& d, int n) {
  const RivetedBeam b = build_riveted_beam(d);
  const AssembledModel a = b.fe.assemble();
  const Eigen::SparseMatrix<double> k =
      with_joints(a.stiffness, b.joints, d, [&](int node, int c) { return a.dof(node, c - 1); });
  EigenOptions o;
  o.count = n + 6;
  o.shift = -1.0;
  const EigenResult r = lowest_modes(k, a.mass, o);
  if (!r.summary.ok()) throw InputError("full model eigenvalues: " + r.summary.report);
  return frequencies_hz(r.eigenvalues.tail(n));
}

void write_model_directory(const std::filesystem::path& out, const ReducedModel& m) {
  // The four files appear together, replacing a previous model as a set.
  data::OutputStage stage(out, "build-model", [](const std::string& name) {
    return name == "M.mtx" || name == "K.mtx" || name == "dofs.csv" || name == "model.toml";
  });
  const std::filesystem::path& dir = stage.path();
  data::write_matrix_market(dir / "M.mtx", m.mass, true);
  data::write_matrix_market(dir / "K.mtx", m.stiffness, true);
  std::string csv = "node,component\n";
  for (const DofLabel& l : m.labels) csv += fmt::format("{},{}\n", l.node, l.component);
  data::write_file_atomically(dir / "dofs.csv", csv);

  // The model file itself is written by the one model-file writer (model_file_writer.h).
  const RivetedBeamDescription& d = m.description;
  Model model;
  model.mass = m.mass;
  model.stiffness = m.stiffness;
  for (const DofLabel& l : m.labels)
    model.dof_labels.push_back(fmt::format("{}:{}", l.node, l.component));
  ModelFileComments comments;
  comments.header = {
      "Riveted beam reduced by Hurty/Craig-Bampton (jointlab build-model).",
      "Description: " + d.source,
      fmt::format("Full {} model: {} elements, {} DOFs. Reduced: {} DOFs = {} boundary + {} "
                  "fixed-interface modes.",
                  d.shell ? "shell" : "beam", m.summary.elements, m.summary.full_dofs,
                  m.stiffness.rows(), m.summary.boundary_dofs, m.summary.modes),
      "dofs.csv labels: node 1000*s + r = reference node of rivet r on strip s (components",
      "1..6 = x, y, z, rx, ry, rz); other nonzero nodes = sensors; node 0 = modal coordinate",
      "(component = mode number). K is the structure WITHOUT its joints.",
      d.joint_sets.empty()
          ? "iwan.rivet: x and y of every rivet; spring.kz: z [N/m]; spring.rxy: rx and ry, "
            "spring.rz:"
          : "iwan.<set>: x and y of the rivets of each [[joint_set]], iwan.rivet: of the others;",
      d.joint_sets.empty() ? "rz [N*m/rad]."
                           : "spring.kz: z [N/m]; spring.rxy: rx and ry, spring.rz: rz [N*m/rad]."};
  for (const ReducedJoint& j : m.joints) {
    Joint joint;
    joint.a = j.a;
    joint.b = j.b;
    joint.element = j.element;
    joint.stiffness = joint_stiffness(d, j.element);
    if (j.element.starts_with("iwan.")) joint.iwan = Iwan(joint_iwan(d, j.element));
    model.joints.push_back(std::move(joint));
    comments.joints.push_back(j.comment);
  }
  write_model_file(dir / "model.toml", model, {dir / "M.mtx", dir / "K.mtx", dir / "dofs.csv"},
                   comments);
  stage.commit();
}

}  // namespace jointlab::model::fe
