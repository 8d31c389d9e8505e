#include "jointlab/campaign/steps/numeric_table.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/data/backbone_table.h"
#include "jointlab/data/csv_lines.h"

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
  const NumericTable bt = read_numeric_table(path);
  BackboneFile file;
  correlate::Curve& cv = file.curve;
  cv.id = id;
  cv.group = group;
  const auto has = [&](const char* name) {
    return std::find(bt.names.begin(), bt.names.end(), name) != bt.names.end();
  };
  // The mode's own points: none marked in a column of data::is_point_mark.
  std::vector<const std::vector<double>*> marks;
  for (const std::string& name : bt.names) {
    if (data::is_point_mark(name)) marks.push_back(&bt.column(name, path));
  }
  std::vector<size_t> own;
  const size_t rows = bt.column("time_s", path).size();
  for (size_t i = 0; i < rows; ++i) {
    if (std::none_of(marks.begin(), marks.end(),
                     [&](const std::vector<double>* m) { return (*m)[i] != 0; }))
      own.push_back(i);
  }
  const auto pick = [&](const char* name) {
    const std::vector<double>& all = bt.column(name, path);
    Eigen::VectorXd out(static_cast<Eigen::Index>(own.size()));
    for (size_t k = 0; k < own.size(); ++k) out(static_cast<Eigen::Index>(k)) = all[own[k]];
    return out;
  };
  cv.time_s = pick("time_s");
  cv.amplitude = pick("amplitude");
  cv.frequency_hz = pick("frequency_hz");
  cv.damping = pick("damping_ratio");
  if (has("frequency_std_hz") && has("damping_std")) {
    file.frequency_std_hz = pick("frequency_std_hz");
    file.damping_std = pick("damping_std");
  }
  if (has("coverage_factor") && !own.empty()) {
    const std::vector<double>& k = bt.column("coverage_factor", path);
    double before = 0;
    for (const size_t i : own)
      before =
          data::coverage_factor_of_row(k[i], before, fmt::format("{:g}", k[i]), path.string(), 0);
    file.coverage_factor = before;
  }
  return file;
}

}  // namespace jointlab::campaign
