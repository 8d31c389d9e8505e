#include "jointlab/campaign/steps/numeric_table.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/data/csv_lines.h"
#include "jointlab/data/process_folder.h"

namespace jointlab::campaign {

namespace fs = std::filesystem;

const std::vector<double>& NumericTable::column(const std::string& name,
                                                const fs::path& file) const {
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return columns[i];
  throw InputError(
      fmt::format("{}: no column '{}' (delete the file to recompute it)", file.string(), name));
}

NumericTable read_numeric_table(const fs::path& path, bool allow_empty) {
  const auto text = data::read_text_file(path);
  if (!text) throw InputError(fmt::format("{}: cannot read", path.string()));
  NumericTable t;
  bool header = false;
  data::for_each_csv_line(*text, [&](const std::vector<std::string>& cells, long row) {
    if (!header) {
      t.names = cells;
      t.columns.resize(t.names.size());
      header = true;
      return;
    }
    if (cells.size() != t.columns.size())
      throw InputError(where(path.string(), row, "wrong number of cells"));
    for (size_t c = 0; c < cells.size(); ++c) {
      if (allow_empty && cells[c].empty()) {
        t.columns[c].push_back(std::numeric_limits<double>::quiet_NaN());
        continue;
      }
      const auto v = data::parse_double(cells[c]);
      if (!v || !std::isfinite(*v))
        throw InputError(where(path.string(), row,
                               "not a row of numbers (delete the file to "
                               "recompute it)"));
      t.columns[c].push_back(*v);
    }
  });
  if (!header) throw InputError(fmt::format("{}: empty", path.string()));
  return t;
}

BackboneFile read_backbone_file(const fs::path& path, const std::string& id,
                                const std::string& group) {
  // The one reader of process's backbone CSVs (data/, as update-iwan's --measured reads them).
  const data::BackboneTable t = data::read_process_backbone(path);
  if (t.time_s.size() != t.size())
    throw InputError(
        fmt::format("{}: no column 'time_s' (delete the file to recompute it)", path.string()));
  BackboneFile file;
  correlate::Curve& cv = file.curve;
  cv.id = id;
  cv.group = group;
  cv.time_s = t.time_s;
  cv.amplitude = t.amplitude;
  cv.frequency_hz = t.frequency_hz;
  cv.damping = t.damping_ratio;
  if (t.has_uncertainty) {
    file.frequency_std_hz = t.frequency_std_hz;
    file.damping_std = t.damping_std;
  }
  file.coverage_factor = t.coverage_factor;
  return file;
}

}  // namespace jointlab::campaign
