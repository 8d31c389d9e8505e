#include "jointlab/correlate/sensors.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
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

std::vector<Sensor> parse_sensors(const std::string& text, const std::string& name,
                                  const model::Model& model) {
  std::vector<Sensor> out;
  std::set<std::string> seen;
  bool header = false;
  // Delimited as the modes table is: ',', ';' or tab, the header's most frequent.
  char delim = ',';
  data::TextLines lines(data::strip_bom(text));
  for (std::string_view line; lines.next(line);)
    if (const std::string_view h = trim(line); !h.empty() && h.front() != '#') {
      delim = data::detect_delimiter(h);
      break;
    }
  data::for_each_csv_line(
      text,
      [&](std::vector<std::string> cells, long n) {
        if (cells.size() > 1 && cells.back().empty()) cells.pop_back();  // a trailing comma
        if (!header) {
          if (cells.size() < 2 || cells.size() > 3 || lower(cells[0]) != "channel" ||
              lower(cells[1]) != "dof" || (cells.size() == 3 && lower(cells[2]) != "sign")) {
            std::string seen_header;
            for (size_t i = 0; i < cells.size(); ++i) {
              if (i > 0) seen_header += ',';
              seen_header += printable(cells[i]);
            }
            throw InputError(where(name, n,
                                   fmt::format("expected the header 'channel,dof[,sign]' (',', "
                                               "';' or tab between the cells), found '{}'",
                                               shorten(seen_header))));
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
            throw InputError(
                where(name, n,
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
        if (cells.size() == 3 && !cells[2].empty()) {
          const std::optional<double> v = data::parse_double(cells[2]);
          if (v && (*v == 1 || *v == -1)) {
            s.sign = *v;
          } else {
            throw InputError(where(name, n,
                                   fmt::format("sign '{}' must be 1 or -1{}", printable(cells[2]),
                                               cells[2] == "-"   ? ": give -1"
                                               : cells[2] == "+" ? ": give 1"
                                                                 : "")));
          }
        }
        out.push_back(s);
      },
      delim);
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
