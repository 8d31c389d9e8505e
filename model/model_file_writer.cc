#include "jointlab/model/model_file_writer.h"

#include <cassert>
#include <cmath>
#include <fstream>
#include <map>
#include <set>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/data/matrix_market.h"

namespace jointlab::model {
namespace {

namespace fs = std::filesystem;

// Shortest round-trip text of x as a TOML float ("5e+05" -> "500000.0" stays a float).

bool bare_key(const std::string& k) {
  if (k.empty()) return false;
  for (char c : k) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  }
  return true;
}

// A TOML basic string with the characters TOML requires escaped.
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\u{:04x}", static_cast<unsigned>(c));
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string key(const std::string& k) { return bare_key(k) ? k : quoted(k); }

// The element name after its "iwan." or "spring." prefix.
std::string suffix(const std::string& element, const std::string& prefix) {
  const std::string s = element.substr(prefix.size());
  if (s.empty()) throw InputError(fmt::format("model file: element '{}' has no name", element));
  return s;
}

std::string end_text(const Model& model, Eigen::Index i) {
  if (i == kGround) return "\"ground\"";
  if (!model.dof_labels.empty()) return quoted(model.dof_labels[static_cast<size_t>(i)]);
  return fmt::format("{}", i);
}

// `target` as written in a file in `dir`: relative when it can be, absolute otherwise.
std::string path_from(const fs::path& dir, const fs::path& target) {
  const fs::path abs = fs::absolute(target).lexically_normal();
  const fs::path rel = abs.lexically_relative(fs::absolute(dir).lexically_normal());
  return (rel.empty() ? abs : rel).generic_string();
}

}  // namespace

std::string toml_float(double x) {
  if (!std::isfinite(x)) throw std::logic_error("model file writer: non-finite number");
  std::string s = fmt::format("{}", x);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

std::string model_file_text(const Model& model, const std::string& mass_path,
                            const std::string& stiffness_path, const std::string& labels_path,
                            const ModelFileComments& comments) {
  assert(comments.joints.empty() || comments.joints.size() == model.joints.size());
  std::string t;
  for (const std::string& line : comments.header) t += "# " + line + "\n";
  if (comments.header.empty()) t += "# Written by jointlab.\n";
  t += "[matrices]\n";
  t += fmt::format("mass = {}\nstiffness = {}\n", quoted(mass_path), quoted(stiffness_path));
  if (!model.dof_labels.empty()) t += fmt::format("dof_labels = {}\n", quoted(labels_path));
  std::map<std::string, const Joint*> iwans, springs;  // first joint of each element name
  for (const Joint& j : model.joints) {
    if (j.iwan) {
      if (!j.element.starts_with("iwan."))
        throw InputError(
            fmt::format("model file: Iwan element '{}' must be named iwan.<name>", j.element));
      iwans.emplace(j.element, &j);
    } else {
      if (!j.element.starts_with("spring."))
        throw InputError(
            fmt::format("model file: spring '{}' must be named spring.<name>", j.element));
      springs.emplace(j.element, &j);
    }
  }
  for (const auto& [name, j] : iwans) {
    const Iwan& w = *j->iwan;
    t += fmt::format("\n[iwan.{}]\nFs = {}\nKt = {}\nchi = {}\nbeta = {}\n",
                     key(suffix(name, "iwan.")), toml_float(w.slip_force()),
                     toml_float(w.stiffness()), toml_float(w.chi()), toml_float(w.beta()));
  }
  if (!springs.empty()) {
    t += "\n[spring]\n";
    for (const auto& [name, j] : springs) {
      t += fmt::format("{} = {}\n", key(suffix(name, "spring.")), toml_float(j->stiffness));
    }
  }
  if (model.modal_ratio != 0) {
    t += fmt::format("\n[damping]\nmodal_ratio = {}\n", toml_float(model.modal_ratio));
  }
  for (size_t i = 0; i < model.joints.size(); ++i) {
    const Joint& j = model.joints[i];
    const std::string note =
        comments.joints.empty() || comments.joints[i].empty() ? "" : "  # " + comments.joints[i];
    t += fmt::format("\n[[joint]]{}\na = {}\nb = {}\nelement = {}\n", note, end_text(model, j.a),
                     end_text(model, j.b), quoted(j.element));
  }
  return t;
}

void write_model_file(const fs::path& path, const Model& model, const ModelFileMatrices& files,
                      const ModelFileComments& comments) {
  const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  auto matrix = [&](const fs::path& given, const char* name,
                    const Eigen::SparseMatrix<double>& m) -> std::string {
    if (!given.empty()) return path_from(dir, given);
    data::write_matrix_market(dir / name, m, true);
    return name;
  };
  const std::string mass = matrix(files.mass, "mass.mtx", model.mass);
  const std::string stiffness = matrix(files.stiffness, "stiffness.mtx", model.stiffness);
  std::string labels;
  if (!model.dof_labels.empty()) {
    if (!files.dof_labels.empty()) {
      labels = path_from(dir, files.dof_labels);
    } else {
      labels = "dof_labels.csv";
      std::string text = "node,component\n";
      for (const std::string& l : model.dof_labels) {
        const size_t colon = l.rfind(':');
        if (colon == std::string::npos)
          throw InputError(fmt::format("model file: DOF label '{}' is not node:component", l));
        text += l.substr(0, colon) + "," + l.substr(colon + 1) + "\n";
      }
      data::write_file_atomically(dir / labels, text);
    }
  }
  data::write_file_atomically(path, model_file_text(model, mass, stiffness, labels, comments));
}

}  // namespace jointlab::model
