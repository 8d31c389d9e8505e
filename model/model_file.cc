#include "jointlab/model/model_file.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <toml++/toml.h>
#include <Eigen/SparseCholesky>

#include "jointlab/core/error.h"
#include "jointlab/core/memory.h"
#include "jointlab/data/csv_lines.h"
#include "jointlab/data/matrix_market.h"

namespace jointlab::model {
namespace {

namespace fs = std::filesystem;

long line_of(const toml::node& node) { return static_cast<long>(node.source().begin.line); }

// Everything read_model needs to name the place of a defect.
struct Context {
  std::string file;
  [[noreturn]] void fail(const toml::node& node, const std::string& message) const {
    throw InputError(where(file, line_of(node), message));
  }
  [[noreturn]] void fail(long line, const std::string& message) const {
    throw InputError(where(file, line, message));
  }
};

void reject_unknown_keys(const Context& ctx, const toml::table& table, const std::string& name,
                         const std::set<std::string>& known) {
  for (auto&& [key, value] : table) {
    if (!known.count(std::string(key.str()))) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      ctx.fail(value, fmt::format("{}: unknown key '{}' (expected {})", name, key.str(), list));
    }
  }
}

double number(const Context& ctx, const toml::node& node, const std::string& field) {
  const auto v = node.value<double>();
  if (!v || !(node.is_integer() || node.is_floating_point())) {
    ctx.fail(node, fmt::format("{} must be a number", field));
  }
  return *v;
}

void check_symmetric(const Context& ctx, long line, const std::string& field,
                     const std::string& name, const Eigen::SparseMatrix<double>& m) {
  const Eigen::SparseMatrix<double> t = m.transpose();
  const Eigen::SparseMatrix<double> d = m - t;
  double scale = 0;
  for (int k = 0; k < m.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(m, k); it; ++it) {
      scale = std::max(scale, std::abs(it.value()));
    }
  }
  for (int k = 0; k < d.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(d, k); it; ++it) {
      // Written and read with enough digits a symmetric matrix is exactly symmetric;
      // 1e-10 of the largest entry allows for files printed with ~11 digits.
      if (std::abs(it.value()) > 1e-10 * scale) {
        ctx.fail(line,
                 fmt::format("{}: '{}' is not symmetric: entry ({}, {}) = {} but ({}, {}) = {}",
                             field, name, it.row() + 1, it.col() + 1, m.coeff(it.row(), it.col()),
                             it.col() + 1, it.row() + 1, m.coeff(it.col(), it.row())));
      }
    }
  }
}

void check_square(const Context& ctx, long line, const std::string& field, const std::string& name,
                  const Eigen::SparseMatrix<double>& m) {
  if (m.rows() != m.cols()) {
    ctx.fail(line, fmt::format("{}: '{}' is {} x {}, not square", field, name, m.rows(), m.cols()));
  }
}

void check_positive_definite(const Context& ctx, long line, const std::string& field,
                             const std::string& name, const Eigen::SparseMatrix<double>& m) {
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(m);
  if (llt.info() != Eigen::Success) {
    ctx.fail(line,
             fmt::format("{}: '{}' is not positive definite (a mass matrix must be)", field, name));
  }
}

std::vector<std::string> read_labels(const Context& ctx, long line, const fs::path& path) {
  const auto text = data::read_text_file(path);
  if (!text) ctx.fail(line, fmt::format("matrices.dof_labels: cannot open '{}'", path.string()));
  std::vector<std::string> labels;
  std::set<std::string> seen;
  bool header = false;
  data::for_each_csv_line(*text, [&](std::vector<std::string> cells, long n) {
    if (cells.size() > 1 && cells.back().empty()) cells.pop_back();  // a trailing comma
    if (!header) {
      if (cells.size() != 2 || cells[0] != "node" || cells[1] != "component") {
        throw InputError(where(path.string(), n, "expected the header 'node,component'"));
      }
      header = true;
      return;
    }
    if (cells.size() != 2 || cells[0].empty() || cells[1].empty()) {
      throw InputError(where(path.string(), n, "expected 'node,component'"));
    }
    const std::string label = cells[0] + ":" + cells[1];
    if (!seen.insert(label).second) {
      throw InputError(where(path.string(), n, fmt::format("label '{}' appears twice", label)));
    }
    labels.push_back(label);
  });
  if (!header) throw InputError(where(path.string(), 0, "empty file, expected 'node,component'"));
  return labels;
}

// A joint end: a 0-based index, a "node:component" label, or (when allowed) "ground".
Eigen::Index joint_end(const Context& ctx, const toml::node& node, const std::string& field,
                       Eigen::Index size, const std::map<std::string, Eigen::Index>& labels,
                       bool allow_ground) {
  if (node.is_integer()) {
    const long v = *node.value<long>();
    if (v < 0 || v >= size) {
      ctx.fail(node, fmt::format("{} = {} is out of range 0..{}", field, v, size - 1));
    }
    return v;
  }
  if (node.is_string()) {
    const std::string s = *node.value<std::string>();
    if (s == "ground") {
      if (!allow_ground) ctx.fail(node, fmt::format("{} cannot be \"ground\" (use b)", field));
      return kGround;
    }
    if (labels.empty()) {
      ctx.fail(node, fmt::format("{} = \"{}\": a \"node:component\" label needs "
                                 "matrices.dof_labels",
                                 field, s));
    }
    const auto it = labels.find(s);
    if (it == labels.end()) {
      ctx.fail(node, fmt::format("{} = \"{}\" is not a label of matrices.dof_labels", field, s));
    }
    return it->second;
  }
  ctx.fail(node, fmt::format("{} must be a 0-based index, a \"node:component\" label{}", field,
                             allow_ground ? " or \"ground\"" : ""));
}

}  // namespace

int Model::iwan_count() const {
  return static_cast<int>(std::count_if(joints.begin(), joints.end(),
                                        [](const Joint& j) { return j.iwan.has_value(); }));
}

Eigen::SparseMatrix<double> Model::linear_stiffness() const {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<size_t>(stiffness.nonZeros()) + 4 * joints.size());
  for (int k = 0; k < stiffness.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(stiffness, k); it; ++it) {
      t.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
    }
  }
  for (const Joint& j : joints) {
    const int a = static_cast<int>(j.a);
    t.emplace_back(a, a, j.stiffness);
    if (j.b != kGround) {
      const int b = static_cast<int>(j.b);
      t.emplace_back(b, b, j.stiffness);
      t.emplace_back(a, b, -j.stiffness);
      t.emplace_back(b, a, -j.stiffness);
    }
  }
  Eigen::SparseMatrix<double> k(stiffness.rows(), stiffness.cols());
  k.setFromTriplets(t.begin(), t.end());
  return k;
}

Eigen::VectorXd Model::apply_linear_stiffness(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  assert(x.size() == size());
  Eigen::VectorXd y = stiffness * x;
  for (const Joint& j : joints) {
    const double f = j.stiffness * (x(j.a) - (j.b == kGround ? 0.0 : x(j.b)));
    y(j.a) += f;
    if (j.b != kGround) y(j.b) -= f;
  }
  return y;
}

double Model::stiffest_joint() const {
  double k = 0;
  for (const Joint& j : joints) k = std::max(k, j.stiffness);
  return k;
}

void validate_model(const Model& model, const std::string& source) {
  const Context ctx{source};
  check_square(ctx, 0, "mass", "M", model.mass);
  check_square(ctx, 0, "stiffness", "K", model.stiffness);
  if (model.stiffness.rows() != model.mass.rows()) {
    ctx.fail(0L, fmt::format("stiffness is {} x {} but mass is {} x {}", model.stiffness.rows(),
                             model.stiffness.cols(), model.mass.rows(), model.mass.cols()));
  }
  check_symmetric(ctx, 0, "mass", "M", model.mass);
  check_symmetric(ctx, 0, "stiffness", "K", model.stiffness);
  check_positive_definite(ctx, 0, "mass", "M", model.mass);
  for (size_t i = 0; i < model.joints.size(); ++i) {
    const Joint& j = model.joints[i];
    if (j.a < 0 || j.a >= model.size() || j.b < kGround || j.b >= model.size() || j.a == j.b) {
      ctx.fail(0L, fmt::format("joint {}: ends ({}, {}) are invalid", i + 1, j.a, j.b));
    }
    if (!(j.stiffness > 0)) ctx.fail(0L, fmt::format("joint {}: stiffness must be > 0", i + 1));
  }
  if (!std::isfinite(model.modal_ratio) || !(model.modal_ratio >= 0 && model.modal_ratio < 1)) {
    ctx.fail(0L,
             fmt::format("modal_ratio {} must be a damping ratio, 0 <= Z < 1", model.modal_ratio));
  }
}

Model read_model(const fs::path& path) {
  const Context ctx{path.string()};
  data::require_regular_file(path);
  toml::table doc;
  try {
    doc = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    if (!fs::exists(path)) ctx.fail(0L, "cannot open model file");
    ctx.fail(static_cast<long>(e.source().begin.line),
             fmt::format("TOML syntax: {}", e.description()));
  }
  reject_unknown_keys(ctx, doc, "model file", {"matrices", "iwan", "spring", "damping", "joint"});

  // [matrices]
  const toml::table* mats = doc["matrices"].as_table();
  if (!mats) ctx.fail(0L, "missing table [matrices] (mass and stiffness)");
  reject_unknown_keys(ctx, *mats, "matrices", {"mass", "stiffness", "dof_labels"});
  const fs::path dir = path.parent_path();
  auto file_field = [&](const char* key, bool required) -> std::optional<fs::path> {
    const toml::node* node = mats->get(key);
    if (!node) {
      if (required) ctx.fail(line_of(*mats), fmt::format("matrices.{} is missing", key));
      return std::nullopt;
    }
    if (!node->is_string()) ctx.fail(*node, fmt::format("matrices.{} must be a file name", key));
    const fs::path p(*node->value<std::string>());
    return p.is_absolute() ? p : dir / p;
  };
  auto field_line = [&](const char* key) { return line_of(*mats->get(key)); };

  Model model;
  const fs::path mass_path = *file_field("mass", true);
  const fs::path stiff_path = *file_field("stiffness", true);
  // Every command solves the model dense (about six n x n double matrices at once), so the
  // matrices are refused at the size line when those would not fit in memory_limit().
  const auto max_dofs = static_cast<long>(std::sqrt(memory_limit() / 48));
  model.mass = data::read_matrix_market(mass_path, max_dofs);
  model.stiffness = data::read_matrix_market(stiff_path, max_dofs);
  const std::string mass_name = mass_path.filename().string();
  const std::string stiff_name = stiff_path.filename().string();
  check_square(ctx, field_line("mass"), "matrices.mass", mass_name, model.mass);
  check_square(ctx, field_line("stiffness"), "matrices.stiffness", stiff_name, model.stiffness);
  if (model.stiffness.rows() != model.mass.rows()) {
    ctx.fail(field_line("stiffness"),
             fmt::format("matrices.stiffness: '{}' is {} x {} but the mass matrix is {} x {}",
                         stiff_name, model.stiffness.rows(), model.stiffness.cols(),
                         model.mass.rows(), model.mass.cols()));
  }
  check_symmetric(ctx, field_line("mass"), "matrices.mass", mass_name, model.mass);
  check_symmetric(ctx, field_line("stiffness"), "matrices.stiffness", stiff_name, model.stiffness);
  check_positive_definite(ctx, field_line("mass"), "matrices.mass", mass_name, model.mass);
  const Eigen::Index n = model.size();

  std::map<std::string, Eigen::Index> label_index;
  if (const auto labels_path = file_field("dof_labels", false)) {
    model.dof_labels = read_labels(ctx, field_line("dof_labels"), *labels_path);
    if (static_cast<Eigen::Index>(model.dof_labels.size()) != n) {
      ctx.fail(field_line("dof_labels"),
               fmt::format("matrices.dof_labels: '{}' has {} rows but the matrices have {} DOFs",
                           labels_path->filename().string(), model.dof_labels.size(), n));
    }
    for (Eigen::Index i = 0; i < n; ++i) label_index[model.dof_labels[i]] = i;
  }

  // [iwan.<name>] and [spring]
  std::map<std::string, Iwan> iwans;
  std::map<std::string, double> springs;
  if (const toml::node* node = doc.get("iwan")) {
    const toml::table* t = node->as_table();
    if (!t) ctx.fail(*node, "iwan must be a table of named parameter sets ([iwan.<name>])");
    for (auto&& [key, value] : *t) {
      const std::string name = "iwan." + std::string(key.str());
      const toml::table* set = value.as_table();
      if (!set) ctx.fail(value, fmt::format("{} must be a table with Fs, Kt, chi, beta", name));
      reject_unknown_keys(ctx, *set, name, {"Fs", "Kt", "chi", "beta"});
      IwanParameters p;
      double* fields[] = {&p.Fs, &p.Kt, &p.chi, &p.beta};
      const char* names[] = {"Fs", "Kt", "chi", "beta"};
      for (int i = 0; i < 4; ++i) {
        const toml::node* f = set->get(names[i]);
        if (!f) ctx.fail(value, fmt::format("{}.{} is missing", name, names[i]));
        *fields[i] = number(ctx, *f, name + "." + names[i]);
      }
      const std::string error = iwan_parameter_error(p);
      if (!error.empty()) {
        // Point at the offending field: the error starts with its name.
        const std::string field = error.substr(0, error.find(' '));
        ctx.fail(*set->get(field), fmt::format("{}: {}", name, error));
      }
      iwans.emplace(name, Iwan(p));
    }
  }
  if (const toml::node* node = doc.get("spring")) {
    const toml::table* t = node->as_table();
    if (!t) ctx.fail(*node, "spring must be a table of named stiffnesses");
    for (auto&& [key, value] : *t) {
      const std::string name = "spring." + std::string(key.str());
      const double k = number(ctx, value, name);
      if (!(k > 0) || !std::isfinite(k))
        ctx.fail(value, fmt::format("{} = {} must be {}> 0", name, k,
                                    std::isfinite(k) ? "" : "a finite number "));
      springs.emplace(name, k);
    }
  }

  // [damping]
  if (const toml::node* node = doc.get("damping")) {
    const toml::table* t = node->as_table();
    if (!t) ctx.fail(*node, "damping must be a table ([damping] with modal_ratio)");
    reject_unknown_keys(ctx, *t, "damping", {"modal_ratio"});
    if (const toml::node* z = t->get("modal_ratio")) {
      const double v = number(ctx, *z, "damping.modal_ratio");
      if (!std::isfinite(v) || !(v >= 0 && v < 1)) {
        ctx.fail(*z, fmt::format("damping.modal_ratio = {} must be a damping ratio, 0 <= Z < 1 "
                                 "(a fraction, not percent)",
                                 v));
      }
      model.modal_ratio = v;
    }
  }

  // [[joint]]
  if (const toml::node* node = doc.get("joint")) {
    const toml::array* joints = node->as_array();
    if (!joints) ctx.fail(*node, "joint must be an array of tables ([[joint]])");
    int index = 0;
    for (const toml::node& item : *joints) {
      ++index;
      const std::string name = fmt::format("joint {}", index);
      const toml::table* t = item.as_table();
      if (!t) ctx.fail(item, fmt::format("{} must be a table", name));
      reject_unknown_keys(ctx, *t, name, {"a", "b", "element"});
      for (const char* key : {"a", "b", "element"}) {
        if (!t->get(key)) ctx.fail(item, fmt::format("{}: '{}' is missing", name, key));
      }
      Joint joint;
      joint.a = joint_end(ctx, *t->get("a"), name + ": a", n, label_index, false);
      joint.b = joint_end(ctx, *t->get("b"), name + ": b", n, label_index, true);
      if (joint.a == joint.b)
        ctx.fail(*t->get("b"), fmt::format("{}: a and b are the same DOF", name));
      const toml::node& element = *t->get("element");
      if (!element.is_string()) ctx.fail(element, fmt::format("{}: element must be a name", name));
      joint.element = *element.value<std::string>();
      if (const auto it = iwans.find(joint.element); it != iwans.end()) {
        joint.iwan = it->second;
        joint.stiffness = it->second.stiffness();
      } else if (const auto s = springs.find(joint.element); s != springs.end()) {
        joint.stiffness = s->second;
      } else {
        std::string known;
        for (const auto& [k, v] : iwans) known += (known.empty() ? "" : ", ") + k;
        for (const auto& [k, v] : springs) known += (known.empty() ? "" : ", ") + k;
        ctx.fail(element, fmt::format("{}: unknown element '{}' (defined: {})", name, joint.element,
                                      known.empty() ? "none" : known));
      }
      model.joints.push_back(std::move(joint));
    }
  }
  return model;
}

std::string missing_label_hint(const Model& model, const std::string& label) {
  // Name the labels the node has: a component the node lacks (x at a sensor that measures z)
  // is the likely slip, and the fix is one of those.
  const std::string node = label.substr(0, label.find(':'));
  std::vector<std::string> same;
  for (const std::string& l : model.dof_labels) {
    if (l.substr(0, l.find(':')) == node) same.push_back(l);
  }
  if (same.empty()) {
    return fmt::format(
        ": it has no node {} (a label is \"node:component\", as in the model's dof_labels file)",
        node);
  }
  constexpr size_t kShown = 6;
  const auto shown = same.begin() + static_cast<std::ptrdiff_t>(std::min(same.size(), kShown));
  return fmt::format(": node {} has {}{}{}", node, same.size() == 1 ? "only " : "",
                     fmt::join(same.begin(), shown, ", "),
                     same.size() > kShown ? fmt::format(" and {} more", same.size() - kShown) : "");
}

}  // namespace jointlab::model
