#include "jointlab/data/sensors_file.h"

#include <optional>
#include <set>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/data/csv_lines.h"

namespace jointlab::data {

SensorsFile parse_sensors_file(const std::string& text, const std::string& name) {
  SensorsFile out;
  out.source = name;
  std::set<std::string> seen;
  bool header = false;
  // Delimited as the modes table is: ',', ';' or tab, the header's most frequent.
  const char delim = header_delimiter(text);
  for_each_csv_line(
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
        SensorRow r;
        r.channel = cells[0];
        r.dof = cells[1];
        r.line = n;
        if (!seen.insert(r.channel).second) {
          throw InputError(where(name, n, fmt::format("channel '{}' appears twice", r.channel)));
        }
        if (cells.size() == 3 && !cells[2].empty()) {
          const std::optional<double> v = parse_double(cells[2]);
          if (v && (*v == 1 || *v == -1)) {
            r.sign = *v;
          } else {
            throw InputError(where(name, n,
                                   fmt::format("sign '{}' must be 1 or -1{}", printable(cells[2]),
                                               cells[2] == "-"   ? ": give -1"
                                               : cells[2] == "+" ? ": give 1"
                                                                 : "")));
          }
        }
        out.rows.push_back(std::move(r));
      },
      delim);
  if (!header) throw InputError(where(name, 0, "empty file, expected 'channel,dof[,sign]'"));
  if (out.rows.empty()) throw InputError(where(name, 0, "no sensors"));
  return out;
}

SensorsFile read_sensors_file(const std::filesystem::path& path) {
  const auto text = read_text_file(path);
  if (!text) throw InputError(where(path.string(), 0, "cannot open the sensors file"));
  return parse_sensors_file(*text, path.string());
}

}  // namespace jointlab::data
