#include "jointlab/correlate/sensors.h"

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/data/csv_lines.h"

namespace jointlab::correlate {
namespace {

// Where the component of label `d` ("node:component") is written as a direction, "z", "-z",
// "+Y", "-3" or "rx", what to write instead: " (a component is a number, 1-6 for x, y, z, rx,
// ry, rz, and a channel that reads against it has sign -1: give 9001:3 and sign -1)", the label
// only where `labels` has it; else "".
std::string direction_hint(const std::string& d, const std::vector<std::string>& labels) {
  const size_t colon = d.rfind(':');
  std::string c = lower(d.substr(colon + 1));
  bool reversed = false;
  if (!c.empty() && (c[0] == '-' || c[0] == '+')) reversed = c[0] == '-', c.erase(0, 1);
  const std::vector<std::string> names = {"x", "y", "z", "rx", "ry", "rz"};
  int k = 0;
  for (int i = 0; i < 6; ++i)
    if (c == names[static_cast<size_t>(i)] || c == std::to_string(i + 1)) k = i + 1;
  if (k == 0 || (!reversed && c == std::to_string(k))) return "";
  const std::string label = fmt::format("{}:{}", d.substr(0, colon), k);
  const bool exists = std::find(labels.begin(), labels.end(), label) != labels.end();
  return fmt::format(
      " (a component is a number, 1-6 for x, y, z, rx, ry, rz, and a channel that reads against "
      "it has sign -1{})",
      exists ? fmt::format(": give {}{}", label, reversed ? " and sign -1" : "") : "");
}

}  // namespace

std::vector<Sensor> parse_sensors(const std::string& text, const std::string& name,
                                  const model::Model& model) {
  std::vector<Sensor> out;
  std::set<std::string> seen;
  bool header = false;
  data::for_each_csv_line(text, [&](std::vector<std::string> cells, long n) {
    if (cells.size() > 1 && cells.back().empty()) cells.pop_back();  // a trailing comma
    if (!header) {
      if (cells.size() < 2 || cells.size() > 3 || cells[0] != "channel" || cells[1] != "dof" ||
          (cells.size() == 3 && cells[2] != "sign")) {
        throw InputError(where(name, n, "expected the header 'channel,dof[,sign]'"));
      }
      header = true;
      return;
    }
    if (cells.size() < 2 || cells.size() > 3 || cells[0].empty() || cells[1].empty()) {
      throw InputError(where(name, n, "expected 'channel,dof[,sign]'"));
    }
    Sensor s;
    s.channel = cells[0];
    if (!seen.insert(s.channel).second) {
      throw InputError(where(name, n, fmt::format("channel '{}' appears twice", s.channel)));
    }
    const std::string& d = cells[1];
    if (d.find(':') != std::string::npos) {
      if (model.dof_labels.empty()) {
        throw InputError(where(name, n,
                               fmt::format("dof '{}': a \"node:component\" label needs the "
                                           "model's matrices.dof_labels (or give a 0-based index)",
                                           d)));
      }
      const auto it = std::find(model.dof_labels.begin(), model.dof_labels.end(), d);
      if (it == model.dof_labels.end()) {
        throw InputError(where(
            name, n,
            fmt::format("dof '{}' is not a label of the model's dof_labels{}{}", d,
                        model::missing_label_hint(model, d), direction_hint(d, model.dof_labels))));
      }
      s.dof = it - model.dof_labels.begin();
    } else {
      size_t used = 0;
      long v = -1;
      try {
        v = std::stol(d, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != d.size() || v < 0 || v >= model.size()) {
        throw InputError(
            where(name, n,
                  fmt::format("dof '{}' must be an index 0..{} or a node:component label", d,
                              model.size() - 1)));
      }
      s.dof = v;
    }
    if (cells.size() == 3 && !cells[2].empty()) {
      if (cells[2] == "1" || cells[2] == "+1") {
        s.sign = 1.0;
      } else if (cells[2] == "-1") {
        s.sign = -1.0;
      } else {
        throw InputError(where(name, n, fmt::format("sign '{}' must be 1 or -1", cells[2])));
      }
    }
    out.push_back(s);
  });
  if (!header) throw InputError(where(name, 0, "empty file, expected 'channel,dof[,sign]'"));
  if (out.empty()) throw InputError(where(name, 0, "no sensors"));
  return out;
}

std::vector<Sensor> read_sensors(const std::filesystem::path& path, const model::Model& model) {
  const auto text = data::read_text_file(path);
  if (!text) throw InputError(where(path.string(), 0, "cannot open the sensors file"));
  return parse_sensors(*text, path.string(), model);
}

Eigen::MatrixXd shapes_at_sensors(const std::vector<Sensor>& sensors,
                                  const Eigen::Ref<const Eigen::MatrixXd>& shapes) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(sensors.size()), shapes.cols());
  for (size_t i = 0; i < sensors.size(); ++i) {
    out.row(static_cast<Eigen::Index>(i)) = sensors[i].sign * shapes.row(sensors[i].dof);
  }
  return out;
}

int find_sensor(const std::vector<Sensor>& sensors, const std::string& channel) {
  for (size_t i = 0; i < sensors.size(); ++i) {
    if (sensors[i].channel == channel) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace jointlab::correlate
