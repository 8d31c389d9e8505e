#include "jointlab/data/backbone_table.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/core/units.h"
#include "jointlab/data/csv_lines.h"

namespace jointlab::data {

namespace fs = std::filesystem;

bool is_point_mark(std::string_view column) { return column == "harmonic" || column == "exchange"; }

namespace {

// The columns read: the three required, then the two optional uncertainties.
constexpr std::array<const char*, 5> kNames = {"amplitude", "frequency_hz", "damping_ratio",
                                               "frequency_std_hz", "damping_std"};

// The factor a value of column k (amplitude, frequency_hz, damping_ratio, frequency_std_hz,
// damping_std) in `unit` takes to the table's units; InputError naming the file, the column and
// the unit when the column does not take it: a unit is converted or refused, never ignored.
double unit_scale(size_t k, const std::string& unit, std::optional<Quantity> quantity,
                  const std::string& file, long line) {
  const auto refuse = [&](const std::string& why) {
    return InputError(
        where(file, line, fmt::format("column '{} [{}]': {}", kNames[k], shorten(unit), why)));
  };
  if (k == 1 || k == 3) {  // frequencies
    if (lower(unit) == "hz") return 1.0;
    throw refuse(
        fmt::format("unit '{}' refused: {} is in Hz ([Hz] or no unit)", shorten(unit), kNames[k]));
  }
  if (k == 2 || k == 4) {  // damping ratios
    if (unit == "1" || unit == "-") return 1.0;
    if (unit == "%") return 0.01;
    throw refuse(fmt::format(
        "unit '{}' refused: {} is a fraction (no unit, [1] or [-]) or in per cent ([%])",
        shorten(unit), kNames[k]));
  }
  if (!quantity) {
    throw refuse(fmt::format(
        "unit '{}' refused: a modal amplitude (--amplitude modal) takes no unit; a measured one "
        "needs --amplitude displacement, velocity or acceleration with --dof",
        shorten(unit)));
  }
  const std::string name = quantity_name(*quantity);
  const std::optional<Unit> u = parse_unit(unit);
  if (!u) {
    throw refuse(fmt::format("unknown unit '{}' (the amplitude is a {}, SI unit {})", shorten(unit),
                             name, si_unit(*quantity)));
  }
  if (u->quantity != *quantity) {
    throw refuse(
        fmt::format("unit '{}' measures {}, the amplitude is a {} (--amplitude {}, SI "
                    "unit {})",
                    shorten(unit), quantity_name(u->quantity), name, name, si_unit(*quantity)));
  }
  return u->to_si;
}

}  // namespace

double coverage_factor_of_row(double value, double before, std::string_view cell,
                              const std::string& file, long line) {
  if (!(value >= 1) || !std::isfinite(value) || (before > 0 && value != before)) {
    throw InputError(where(file, line,
                           fmt::format("coverage_factor '{}' must be a finite number >= 1, the "
                                       "same on every row",
                                       cell)));
  }
  return value;
}

BackboneTable read_backbone_table(const fs::path& path, std::optional<Quantity> quantity) {
  const std::string file = path.string();
  const auto text = read_text_file(path);
  if (!text) throw InputError(where(file, 0, "cannot open the backbone table"));
  TextLines lines(strip_bom(*text));
  const std::string_view header = read_preamble(lines, file, [](const auto&, const auto&) {});
  const long header_line = lines.line_no();
  const char delim = detect_delimiter(header);
  CsvLineSplitter splitter(delim);
  std::array<int, 5> col;
  col.fill(-1);
  std::array<double, 5> scale;  // value in the file's unit -> the table's (SI, Hz, a fraction)
  scale.fill(1.0);
  std::vector<size_t> marks;  // columns of is_point_mark: their marked rows are skipped
  int coverage_col = -1;      // a `process` backbone's coverage_factor: k of the std columns
  double coverage = 0;        // its value (0: none read yet)
  const std::vector<std::string> fields = splitter.split(header);
  std::string amplitude_unit;
  bool ours = false;
  for (size_t i = 0; i < fields.size(); ++i) {
    const auto [name, unit] = split_name_unit(fields[i], file, header_line);
    if (is_point_mark(name)) marks.push_back(i);
    if (name == "coverage_factor") coverage_col = static_cast<int>(i);
    if (name == "coverage_factor" || name == "response_controlled") ours = true;
    for (size_t k = 0; k < kNames.size(); ++k) {
      if (name != kNames[k]) continue;
      if (col[k] >= 0) {
        throw InputError(where(file, header_line, fmt::format("column '{}' appears twice", name)));
      }
      col[k] = static_cast<int>(i);
      if (!unit.empty()) scale[k] = unit_scale(k, unit, quantity, file, header_line);
      if (k == 0) amplitude_unit = unit;
    }
  }
  for (size_t k = 0; k < 3; ++k) {
    if (col[k] < 0) {
      throw InputError(
          where(file, header_line,
                fmt::format("no column '{}': a backbone table has the header "
                            "amplitude,frequency_hz,damping_ratio[,frequency_std_hz,damping_std]",
                            kNames[k])));
    }
  }
  if ((col[3] < 0) != (col[4] < 0)) {
    throw InputError(
        where(file, header_line, "give both frequency_std_hz and damping_std, or neither"));
  }
  const size_t needed = static_cast<size_t>(*std::max_element(col.begin(), col.end())) + 1;
  std::array<std::vector<double>, 5> values;
  std::vector<std::string> cells;
  std::string_view line;
  while (lines.next(line)) {
    const std::string_view trimmed =
        line.substr(std::min(line.find_first_not_of(" \t"), line.size()));
    if (trimmed.empty() || trimmed.front() == '#') continue;
    if (!splitter.split(line, cells)) continue;
    const long n = lines.line_no();
    if (cells.size() < needed) {
      throw InputError(where(
          file, n, fmt::format("{} cells, the header needs at least {}", cells.size(), needed)));
    }
    const bool marked = std::any_of(marks.begin(), marks.end(), [&](size_t c) {
      if (c >= cells.size()) return false;
      const auto v = parse_double(cells[c]);
      return v && *v != 0;
    });
    if (marked) continue;
    if (coverage_col >= 0 && static_cast<size_t>(coverage_col) < cells.size()) {
      const std::string& cell = cells[static_cast<size_t>(coverage_col)];
      coverage = coverage_factor_of_row(parse_double(cell).value_or(NAN), coverage, cell, file, n);
    }
    for (size_t k = 0; k < kNames.size(); ++k) {
      if (col[k] < 0) continue;
      const std::string& cell = cells[static_cast<size_t>(col[k])];
      const auto v = parse_double(cell);
      const bool uncertainty = k >= 3;
      if (!v || !std::isfinite(*v) || (uncertainty ? !(*v >= 0) : !(*v > 0))) {
        throw InputError(where(file, n,
                               fmt::format("{} '{}' must be a finite number {}", kNames[k], cell,
                                           uncertainty ? ">= 0" : "> 0")));
      }
      // A damping ratio of 1 or more is no ring-down (critical damping): per cent read as a
      // fraction (a table of 0.05-4.85 % ran to a fit with an RMS damping error of 99 %).
      if (k == 2 && *v * scale[k] >= 1) {
        throw InputError(
            where(file, n,
                  fmt::format("damping_ratio '{}' is not a fraction below 1; per cent? write the "
                              "header as 'damping_ratio [%]'",
                              cell)));
      }
      values[k].push_back(*v * scale[k]);
    }
  }
  const size_t points = values[0].size();
  if (points < 2) {
    throw InputError(where(
        file, 0, fmt::format("a backbone needs at least two points, the table has {}", points)));
  }
  std::vector<size_t> order(points);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return values[0][a] < values[0][b]; });
  BackboneTable t;
  t.source = file;
  t.amplitude_unit = amplitude_unit;
  t.written_by_jointlab = ours;
  if (coverage > 0) t.coverage_factor = coverage;
  Eigen::VectorXd* out[] = {&t.amplitude, &t.frequency_hz, &t.damping_ratio, &t.frequency_std_hz,
                            &t.damping_std};
  for (size_t k = 0; k < kNames.size(); ++k) {
    out[k]->setZero(static_cast<Eigen::Index>(points));
    if (values[k].empty()) continue;
    for (size_t i = 0; i < points; ++i)
      (*out[k])(static_cast<Eigen::Index>(i)) = values[k][order[i]];
  }
  return t;
}

}  // namespace jointlab::data
