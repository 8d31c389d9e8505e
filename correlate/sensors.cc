#include "jointlab/correlate/sensors.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/data/csv_lines.h"

namespace jointlab::correlate {
namespace {

// Where label `d` ("node:component") is a label of `labels` written as other tools write it,
// what to write instead, else "": a direction ("z", "+Y", "Tz", "rx"), a sign before or after the
// component ("-z", "+3", "3+", "z-"), a component not written as a plain number ("03", "3.0") or
// blanks inside ("9001: 3"). " (a component is a number, 1-6 for x, y, z, rx, ry, rz, and a
// channel that reads against it has sign -1: give 9001:3 and sign -1)", the label only where
// `labels` has it.
std::string direction_hint(const std::string& d, const std::vector<std::string>& labels) {
  const size_t colon = d.rfind(':');
  const std::string node(trim(d.substr(0, colon)));
  std::string c(trim(lower(d.substr(colon + 1))));
  bool reversed = false, sign = false;
  for (const bool front : {true, false}) {
    if (c.empty()) break;
    const char s = front ? c.front() : c.back();
    if (s != '-' && s != '+') continue;
    sign = true;
    reversed = reversed != (s == '-');
    if (front)
      c.erase(c.begin());
    else
      c.pop_back();
    c = std::string(trim(c));
  }
  const std::vector<std::string> names = {"x", "y", "z", "rx", "ry", "rz"};
  int k = 0;
  bool named = false;
  for (int i = 0; i < 6; ++i) {
    const std::string& n = names[static_cast<size_t>(i)];
    if (c == n || (i < 3 && c == "t" + n)) k = i + 1, named = true;
  }
  if (k == 0) {
    const std::optional<double> v = data::parse_double(c);
    if (v && *v >= 1 && *v <= 6 && *v == std::floor(*v) && c.find_first_of("eE") == c.npos)
      k = static_cast<int>(*v);
  }
  const bool blanks = d.find_first_of(" \t") != std::string::npos;
  const std::string label = fmt::format("{}:{}", node, k);
  if (k == 0 || label == d) return "";
  std::string why = named  ? "a component is a number, 1-6 for x, y, z, rx, ry, rz, and a channel "
                             "that reads against it has sign -1"
                    : sign ? "a component is a number 1-6 without a sign, and a channel that "
                             "reads against it has sign -1"
                    : !blanks ? "a component is a whole number 1-6 as written in dof_labels"
                              : "";
  if (blanks) why = why.empty() ? "a label has no blanks" : "a label has no blanks, " + why;
  const bool exists = std::find(labels.begin(), labels.end(), label) != labels.end();
  return fmt::format(
      " ({}{})", why,
      exists ? fmt::format(": give {}{}", label, reversed ? " and sign -1" : "") : "");
}

}  // namespace

std::vector<Sensor> sensors_of(const data::SensorsFile& file, const model::Model& model) {
  std::vector<Sensor> out;
  const std::string& name = file.source;
  for (const data::SensorRow& row : file.rows) {
    const long n = row.line;
    Sensor s;
    s.channel = row.channel;
    s.sign = row.sign;
    const std::string& d = row.dof;
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
            fmt::format(
                "dof '{}' is not a label of the model's dof_labels{}{}", d,
                model::missing_label_hint(
                    model, std::string(trim(d.substr(0, d.find(':')))) + d.substr(d.find(':'))),
                direction_hint(d, model.dof_labels))));
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
    out.push_back(s);
  }
  return out;
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
