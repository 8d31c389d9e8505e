#include "jointlab/data/stepped_sine.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <memory>
#include <numbers>
#include <numeric>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <matio.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/data/amplitude_measure.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/data/csv_lines.h"
#include "jointlab/data/mat_file.h"
#include "jointlab/data/mat_variable.h"
#include "jointlab/data/read_record.h"

namespace jointlab::data {

std::string control_name(SineControl c) {
  return c == SineControl::kResponse ? "response" : "force";
}

namespace {

constexpr Eigen::Index kMinRows = 5;

std::optional<SineControl> parse_control(std::string_view text) {
  const std::string t = lower(trim(text));
  if (t == "response" || t == "response-controlled" || t == "response controlled") {
    return SineControl::kResponse;
  }
  if (t == "force" || t == "force-controlled" || t == "force controlled")
    return SineControl::kForce;
  return std::nullopt;
}

// Phase unit factor to radians; nullopt if unknown.
std::optional<double> phase_factor(std::string_view unit) {
  const std::string u = lower(trim(unit));
  if (u == "rad") return 1.0;
  if (u == "deg" || u == "degree" || u == "degrees") return std::numbers::pi / 180.0;
  return std::nullopt;
}

// The raw columns of one table before checking.
struct Raw {
  std::string label;
  std::optional<SineControl> control;
  std::vector<double> f, force, response, phase;
  std::vector<long> lines;  // CSV line of each row (0 for .mat)
};

// Checks the values and sorts the rows by frequency; `field` names the place for messages.
SteppedSineTable finish(Raw raw, const std::string& file, const std::string& field,
                        SineControl control, Quantity quantity, double force_si, double response_si,
                        double phase_si) {
  auto fail = [&](long line, const std::string& what) {
    throw InputError(line > 0 ? where(file, line, what)
                              : where(file, 0, fmt::format("{}: {}", field, what)));
  };
  const size_t n = raw.f.size();
  if (static_cast<Eigen::Index>(n) < kMinRows) {
    fail(0, fmt::format("{} frequencies; a stepped-sine table needs at least {}", n, kMinRows));
  }
  for (size_t i = 0; i < n; ++i) {
    const long line = raw.lines.empty() ? 0 : raw.lines[i];
    const std::string at = line > 0 ? std::string() : fmt::format(" (row {})", i + 1);
    if (!std::isfinite(raw.f[i]) || raw.f[i] <= 0) {
      fail(line, fmt::format("frequency {} Hz is not positive{}", raw.f[i], at));
    }
    if (!std::isfinite(raw.force[i]) || raw.force[i] <= 0) {
      fail(line, fmt::format("force amplitude {} is not positive{}", raw.force[i], at));
    }
    if (!std::isfinite(raw.response[i]) || raw.response[i] <= 0) {
      fail(line, fmt::format("response amplitude {} is not positive{}", raw.response[i], at));
    }
    if (!std::isfinite(raw.phase[i])) fail(line, fmt::format("phase is not finite{}", at));
  }
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return raw.f[a] < raw.f[b]; });
  for (size_t k = 1; k < n; ++k) {
    if (raw.f[order[k]] == raw.f[order[k - 1]]) {
      const long line = raw.lines.empty() ? 0 : raw.lines[order[k]];
      fail(line, fmt::format("frequency {} Hz appears twice", raw.f[order[k]]));
    }
  }
  SteppedSineTable t;
  t.source = file;
  t.label = raw.label;
  t.control = control;
  t.response_quantity = quantity;
  t.frequency_hz.resize(static_cast<Eigen::Index>(n));
  t.force.resizeLike(t.frequency_hz);
  t.response.resizeLike(t.frequency_hz);
  t.phase_rad.resizeLike(t.frequency_hz);
  for (size_t k = 0; k < n; ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    t.frequency_hz(i) = raw.f[order[k]];
    t.force(i) = raw.force[order[k]] * force_si;
    t.response(i) = raw.response[order[k]] * response_si;
    t.phase_rad(i) = raw.phase[order[k]] * phase_si;
  }
  return t;
}

// ---------------------------------------------------------------------------------------------
// CSV

// The fields of one line; an empty last field (a trailing delimiter) is dropped.
std::vector<std::string> split_fields(CsvLineSplitter& splitter, std::string_view line) {
  std::vector<std::string> fields = splitter.split(line);
  if (fields.size() > 1 && trim(fields.back()).empty()) fields.pop_back();
  return fields;
}

// Where the columns of a stepped-sine CSV are and the SI factors of their units.
struct CsvColumns {
  long line = 0;
  std::vector<std::string> header;
  int f = -1, force = -1, response = -1, phase = -1, level = -1, control = -1;
  double force_si = 1, response_si = 1, phase_si = 1;
  Quantity response_quantity = Quantity::kAcceleration;
};

// The response or the force amplitude a header name other than theirs means ("resp...",
// "amp...", "acc...", "vel...", "disp...": the response; "force...": the force); "" for neither.
std::string amplitude_meant(std::string_view name) {
  for (const std::string& w : header_words(name)) {
    if (w.starts_with("resp") || w.starts_with("amp") || w.starts_with("acc") ||
        w.starts_with("vel") || w.starts_with("disp"))
      return "response";
    if (w.starts_with("force")) return "force";
  }
  return {};
}

// The fix of column `meant` ("response" or "force") measured as `measure` (amplitude_measure()):
// both are read zero to peak; the response's is the backbone's amplitude, whose factor F_S takes.
std::string fix_of(const std::string& meant, const std::string& measure) {
  return meant == "response"
             ? measure_fix(measure)
             : measure_factor(measure) + " (a force amplitude is read zero to peak)";
}

// InputError for a `column` whose bracketed unit also says how it was measured ('[m/s^2 RMS]'):
// the factor, then the header without it.
void refuse_unit_measure(const std::string& column, const std::string& unit,
                         const std::string& file, long line) {
  if (const std::optional<UnitMeasure> m = unit_measure(unit)) {
    throw InputError(where(
        file, line,
        fmt::format("column '{} [{}]': '{}' says how it was measured, not a unit: {}, then write "
                    "'{}{}'",
                    column, printable(unit), printable(m->written), fix_of(column, m->measure),
                    column,
                    m->rest.empty() ? std::string() : fmt::format(" [{}]", printable(m->rest)))));
  }
}

// InputError for a level label that says it was measured RMS or peak to peak ('# level: 1.414
// m/s^2 RMS'): the sweep's force and response columns were likely written so, and read zero to
// peak as every amplitude is, F_S came out 0.707 (RMS) or 2 times the truth without a word.
void refuse_measured_level(const std::string& label, const std::string& file, long line) {
  const std::optional<UnitMeasure> m = unit_measure(label);
  if (!m) return;
  const bool rms = m->measure == "RMS";
  throw InputError(where(
      file, line,
      fmt::format("level '{}' says it was measured {}, but force and response are read zero to "
                  "peak: where their columns hold {} values, {} (read as they are, F_S comes out "
                  "{} the truth); then, or where they are zero to peak already, write the level "
                  "without '{}'",
                  printable(label), m->measure, m->measure,
                  rms ? "multiply them by sqrt(2) = 1.4142" : "halve them",
                  rms ? "0.707 times" : "twice", printable(m->written))));
}

double force_unit(const std::string& unit, const std::string& file, long line) {
  if (unit.empty()) return 1.0;
  const auto u = parse_unit(unit);
  if (!u) refuse_unit_measure("force", unit, file, line);
  if (!u || u->quantity != Quantity::kForce) {
    throw InputError(where(
        file, line,
        fmt::format("column 'force': '{}' is not a force unit (N, kN, lbf)", printable(unit))));
  }
  return u->to_si;
}

void response_unit(CsvColumns& cols, const std::string& unit, std::optional<Quantity> quantity,
                   const std::string& file) {
  if (unit.empty()) {
    if (!quantity) {
      throw InputError(where(file, cols.line,
                             "column 'response' has no unit: write e.g. 'response [m/s^2]' "
                             "(or give --quantity)"));
    }
    cols.response_quantity = *quantity;
    return;
  }
  const auto u = parse_unit(unit);
  if (!u) refuse_unit_measure("response", unit, file, cols.line);
  if (!u || u->quantity == Quantity::kForce) {
    throw InputError(where(file, cols.line,
                           fmt::format("column 'response': '{}' is not a displacement, "
                                       "velocity or acceleration unit (m, mm, m/s, m/s^2, g, ...)",
                                       printable(unit))));
  }
  cols.response_quantity = u->quantity;
  cols.response_si = u->to_si;
}

double phase_unit(const std::string& unit, const std::string& file, long line) {
  const auto f = phase_factor(unit);
  if (!f) {
    throw InputError(where(file, line,
                           fmt::format("column 'phase': unit '{}' is not deg or rad (write "
                                       "'phase [deg]' or 'phase [rad]')",
                                       printable(unit))));
  }
  return *f;
}

CsvColumns read_columns(std::vector<std::string> header, long line, const std::string& file,
                        std::optional<Quantity> quantity) {
  CsvColumns cols;
  cols.line = line;
  cols.header = std::move(header);
  // The fix of a response or force column named as measured RMS or peak to peak ('response_rms
  // [m/s^2]'), for the refusal of its column missing: renamed alone, it was read zero to peak
  // and F_S came out 0.707 (RMS) or 2 (peak to peak) times the truth.
  std::map<std::string, std::string> measured;
  for (size_t i = 0; i < cols.header.size(); ++i) {
    // A measure after the unit ('response [m/s^2] (RMS)'): split_name_unit would say only that
    // the unit goes in square brackets.
    if (const std::optional<MeasureAfterUnit> m = measure_after_unit(cols.header[i])) {
      const std::string meant = amplitude_meant(m->name);
      if (!meant.empty()) {
        throw InputError(where(file, line,
                               fmt::format("column {} '{}': {}, then write '{} [{}]'", i + 1,
                                           printable(trim(cols.header[i])),
                                           fix_of(meant, m->measure), meant, printable(m->unit))));
      }
    }
    auto [name, unit] = split_name_unit(cols.header[i], file, line);
    const std::string col = lower(name);
    auto take = [&](int& slot) {
      if (slot >= 0) throw InputError(where(file, line, fmt::format("two '{}' columns", col)));
      slot = static_cast<int>(i);
    };
    if ((col == "frequency_hz" || col == "frequency") &&
        (lower(unit) == "hz" || (col == "frequency_hz" && unit.empty()))) {
      take(cols.f);
    } else if (col == "frequency" || col == "frequency_hz") {
      // (`frequency_hz [rad/s]` was read as Hz: a frequency 2 pi too high, and no word.)
      throw InputError(where(file, line,
                             fmt::format("column '{}': unit '{}' is not Hz (write 'frequency_hz' "
                                         "or 'frequency [Hz]')",
                                         col, printable(unit))));
    } else if (col == "force") {
      take(cols.force);
      cols.force_si = force_unit(unit, file, line);
    } else if (col == "response") {
      take(cols.response);
      response_unit(cols, unit, quantity, file);
    } else if (col == "phase") {
      take(cols.phase);
      cols.phase_si = phase_unit(unit, file, line);
    } else if (col == "level") {
      take(cols.level);
    } else if (col == "control") {
      take(cols.control);
    } else if (const std::string measure = amplitude_measure(col + " " + unit); !measure.empty()) {
      const std::string meant = amplitude_meant(col);
      // The unit without the measure ('Force RMS (N)', 'resp [g rms]', 'Response (g RMS)'): told
      // "rename it 'response'", values in g were read as m/s^2 (with --quantity) or refused.
      std::string suggested_unit = unit_without_measure(unit);
      if (const auto round = split_round_brackets(name); unit.empty() && round)
        suggested_unit = unit_without_measure(round->second);
      if (!meant.empty() && !measured.contains(meant)) {
        measured[meant] = fmt::format(
            "column {} '{}': {}, then rename it '{}{}'", i + 1, printable(trim(cols.header[i])),
            fix_of(meant, measure), meant,
            parse_unit(suggested_unit) ? fmt::format(" [{}]", suggested_unit) : std::string());
      }
    }
  }
  // Each missing column that a measured one stands for, with its fix (both where both are).
  std::vector<std::string> fixes;
  for (const auto& [c, meant] : {std::pair{cols.force, "force"}, {cols.response, "response"}}) {
    if (c < 0 && measured.contains(meant)) fixes.push_back(measured.at(meant));
  }
  if (!fixes.empty())
    throw InputError(where(file, line, fmt::format("{}", fmt::join(fixes, "; "))));
  const std::pair<int, const char*> required[] = {{cols.f, "frequency_hz"},
                                                  {cols.force, "force"},
                                                  {cols.response, "response"},
                                                  {cols.phase, "phase"}};
  for (const auto& [c, what] : required) {
    if (c < 0) {
      throw InputError(where(file, line,
                             fmt::format("no '{}' column (need frequency_hz, force [N], "
                                         "response [unit], phase [deg|rad])",
                                         what)));
    }
  }
  return cols;
}

// One data row into its level's table; new levels are added in order of first appearance.
void add_row(const std::vector<std::string>& cells, long line, const CsvColumns& cols,
             const std::string& file, const std::map<std::string, std::string>& metadata,
             std::vector<Raw>& raws, std::vector<std::string>& level_keys) {
  const auto cell = [&](int c) -> const std::string& { return cells[static_cast<size_t>(c)]; };
  auto number = [&](int c) {
    const auto v = parse_double(cell(c));
    if (!v || !std::isfinite(*v)) {
      throw InputError(where(
          file, line,
          fmt::format("column '{}': '{}' is not a finite number",
                      printable(trim(cols.header[static_cast<size_t>(c)])), printable(cell(c)))));
    }
    return *v;
  };
  const std::string key = cols.level >= 0 ? std::string(trim(cell(cols.level))) : "";
  if (cols.level >= 0 && key.empty()) throw InputError(where(file, line, "empty level"));
  const size_t k = std::find(level_keys.begin(), level_keys.end(), key) - level_keys.begin();
  if (k == level_keys.size()) {
    if (cols.level >= 0) refuse_measured_level(key, file, line);
    level_keys.push_back(key);
    raws.emplace_back();
    const auto file_level = metadata.find("level");
    raws.back().label = cols.level >= 0                ? "level " + key
                        : file_level != metadata.end() ? "level " + file_level->second
                                                       : "level 1";
  }
  Raw& r = raws[k];
  if (cols.control >= 0) {
    const auto c = parse_control(cell(cols.control));
    if (!c) {
      throw InputError(where(
          file, line,
          fmt::format("control '{}' is not 'response' or 'force'", printable(cell(cols.control)))));
    }
    if (r.control && *r.control != *c) {
      throw InputError(
          where(file, line, fmt::format("{} changes control within the level", r.label)));
    }
    r.control = c;
  }
  r.f.push_back(number(cols.f));
  r.force.push_back(number(cols.force));
  r.response.push_back(number(cols.response));
  r.phase.push_back(number(cols.phase));
  r.lines.push_back(line);
}

}  // namespace

std::vector<SteppedSineTable> parse_stepped_sine_csv(const std::string& text_in,
                                                     const std::string& name,
                                                     std::optional<Quantity> quantity) {
  const std::string_view text = strip_bom(text_in);
  if (trim(text).empty()) throw InputError(where(name, 0, "empty file"));
  if (text.find('\0') != std::string_view::npos) {
    throw InputError(where(name, 0, "binary data, not a CSV text file"));
  }
  std::map<std::string, std::string> metadata;
  std::optional<SineControl> file_control;
  TextLines lines(text);
  const std::string_view header_row =
      read_preamble(lines, name, [&](const std::string& key, const std::string& value) {
        metadata[key] = value;
        if (key == "level") refuse_measured_level(value, name, lines.line_no());
        if (key != "control") return;
        file_control = parse_control(value);
        if (!file_control) {
          throw InputError(
              where(name, lines.line_no(),
                    fmt::format("control '{}' is not 'response' or 'force'", printable(value))));
        }
      });
  CsvLineSplitter splitter(detect_delimiter(header_row));
  const CsvColumns cols =
      read_columns(split_fields(splitter, header_row), lines.line_no(), name, quantity);

  // Rows, grouped by level in order of first appearance.
  std::vector<Raw> raws;
  std::vector<std::string> level_keys;
  std::string_view line;
  while (lines.next(line)) {
    const std::string_view t = trim(line);
    if (t.empty() || t.front() == '#') continue;
    const std::vector<std::string> cells = split_fields(splitter, line);
    if (cells.size() != cols.header.size()) {
      throw InputError(where(
          name, lines.line_no(),
          fmt::format("{} fields where the header has {}", cells.size(), cols.header.size())));
    }
    add_row(cells, lines.line_no(), cols, name, metadata, raws, level_keys);
  }
  if (raws.empty()) throw InputError(where(name, lines.line_no(), "no data rows"));
  std::vector<SteppedSineTable> out;
  for (size_t k = 0; k < raws.size(); ++k) {
    const std::optional<SineControl> control = raws[k].control ? raws[k].control : file_control;
    if (!control) {
      throw InputError(where(name, cols.line,
                             "control not given: add '# control: response' (or force) or a "
                             "'control' column"));
    }
    const std::string label = raws[k].label;
    out.push_back(finish(std::move(raws[k]), name, label, *control, cols.response_quantity,
                         cols.force_si, cols.response_si, cols.phase_si));
    out.back().index = static_cast<int>(k) + 1;
    out.back().metadata = metadata;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// MATLAB

namespace {

struct MatCloser {
  void operator()(mat_t* m) const { Mat_Close(m); }
};
struct VarFreer {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};

size_t element_count(const matvar_t* v) { return mat_element_count(v).value_or(0); }

// A real double (or single) vector field; InputError naming it otherwise.
std::vector<double> vector_field(const matvar_t* v, const std::string& file,
                                 const std::string& field) {
  const size_t n = element_count(v);
  const bool vec = v && v->rank == 2 && (v->dims[0] == 1 || v->dims[1] == 1);
  const bool ok_class = v && (v->class_type == MAT_C_DOUBLE || v->class_type == MAT_C_SINGLE);
  if (!vec || !ok_class || v->isComplex || !v->data ||
      v->nbytes < n * (v->class_type == MAT_C_DOUBLE ? sizeof(double) : sizeof(float))) {
    throw InputError(where(file, 0, fmt::format("field '{}' is not a real numeric vector", field)));
  }
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i) {
    out[i] = v->class_type == MAT_C_DOUBLE ? static_cast<const double*>(v->data)[i]
                                           : static_cast<const float*>(v->data)[i];
  }
  return out;
}

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.emplace_back(trim(item));
  return out;
}

matvar_t* field_of(matvar_t* st, const char* name, size_t index) {
  const unsigned nf = Mat_VarGetNumberOfFields(st);
  char* const* names = Mat_VarGetStructFieldnames(st);
  for (unsigned i = 0; names && i < nf; ++i) {
    if (names[i] && lower(names[i]) == name) return Mat_VarGetStructFieldByIndex(st, i, index);
  }
  return nullptr;
}

// Whether a struct array holds stepped-sine tables (frequency, force, phase fields).
bool is_table_array(matvar_t* v) {
  if (!v || v->class_type != MAT_C_STRUCT || element_count(v) == 0) return false;
  return field_of(v, "frequency", 0) && field_of(v, "force", 0) && field_of(v, "phase", 0);
}

void read_table_array(matvar_t* arr, const std::string& path_name, const std::string& file,
                      std::vector<SteppedSineTable>& out) {
  const std::string l = lower(path_name);
  const bool resp = l.find("response") != std::string::npos;
  const bool force = l.find("force") != std::string::npos;
  const size_t n = element_count(arr);
  for (size_t e = 0; e < n; ++e) {
    const std::string base = fmt::format("{}({})", path_name, e + 1);
    std::optional<SineControl> control;
    if (auto c = mat_char_text(field_of(arr, "control", e))) control = parse_control(*c);
    if (!control && resp != force) control = resp ? SineControl::kResponse : SineControl::kForce;
    if (!control) {
      throw InputError(where(file, 0,
                             fmt::format("field '{}': cannot tell response from force control "
                                         "(name the array ...ResponseControl or ...ForceControl, "
                                         "or give a 'control' field)",
                                         base)));
    }
    Raw raw;
    raw.label = base;
    raw.f = vector_field(field_of(arr, "frequency", e), file, base + ".frequency");
    raw.force = vector_field(field_of(arr, "force", e), file, base + ".force");
    matvar_t* resp_var = field_of(arr, "amplitude", e);
    std::string resp_name = "amplitude";
    if (!resp_var) resp_var = field_of(arr, "response", e), resp_name = "response";
    if (!resp_var) {
      throw InputError(
          where(file, 0, fmt::format("field '{}' has no 'amplitude' or 'response'", base)));
    }
    raw.response = vector_field(resp_var, file, base + "." + resp_name);
    raw.phase = vector_field(field_of(arr, "phase", e), file, base + ".phase");
    if (raw.force.size() != raw.f.size() || raw.response.size() != raw.f.size() ||
        raw.phase.size() != raw.f.size()) {
      throw InputError(where(file, 0,
                             fmt::format("field '{}': frequency, force, {} and phase differ in "
                                         "length ({}, {}, {}, {})",
                                         base, resp_name, raw.f.size(), raw.force.size(),
                                         raw.response.size(), raw.phase.size())));
    }
    const auto units_text = mat_char_text(field_of(arr, "units", e));
    if (!units_text) {
      throw InputError(where(file, 0,
                             fmt::format("field '{}.units' missing or not text (expected e.g. "
                                         "'Hz, N, m/s^2, rad')",
                                         base)));
    }
    const std::vector<std::string> units = split_commas(*units_text);
    auto bad_units = [&](const std::string& what) {
      throw InputError(
          where(file, 0, fmt::format("field '{}.units' ('{}'): {}", base, *units_text, what)));
    };
    if (units.size() != 4) bad_units("expected 4 entries: frequency, force, response, phase");
    if (lower(units[0]) != "hz") bad_units("frequency unit is not Hz");
    // A unit that also says how its values were measured ('m/s^2 RMS'): the factor, on the field.
    const std::pair<size_t, std::string> measured[] = {{1, "force"}, {2, resp_name}};
    for (const auto& [k, field] : measured) {
      if (parse_unit(units[k])) continue;
      if (const std::optional<UnitMeasure> m = unit_measure(units[k])) {
        bad_units(fmt::format("'{}' says how '{}.{}' was measured, not a unit: {}, then write {}",
                              m->written, base, field,
                              fix_of(k == 1 ? "force" : "response", m->measure),
                              !m->rest.empty() ? fmt::format("'{}'", m->rest)
                              : k == 1         ? std::string("its unit alone ('N', 'kN', 'lbf')")
                                       : std::string("its unit alone ('m/s^2', 'g', ...)")));
      }
    }
    const auto fu = parse_unit(units[1]);
    if (!fu || fu->quantity != Quantity::kForce) bad_units("second entry is not a force unit");
    const auto ru = parse_unit(units[2]);
    if (!ru || ru->quantity == Quantity::kForce) bad_units("third entry is not a motion unit");
    const auto pu = phase_factor(units[3]);
    if (!pu) bad_units("fourth entry is not deg or rad");
    SteppedSineTable t =
        finish(std::move(raw), file, base, *control, ru->quantity, fu->to_si, ru->to_si, *pu);
    t.index = static_cast<int>(out.size()) + 1;
    t.metadata["format"] = "mat";
    out.push_back(std::move(t));
  }
}

void walk(matvar_t* v, const std::string& path_name, const std::string& file, int depth,
          std::vector<SteppedSineTable>& out) {
  if (!v || v->class_type != MAT_C_STRUCT || depth > 4) return;
  if (is_table_array(v)) {
    read_table_array(v, path_name, file, out);
    return;
  }
  if (element_count(v) != 1) return;
  const unsigned nf = Mat_VarGetNumberOfFields(v);
  char* const* names = Mat_VarGetStructFieldnames(v);
  for (unsigned i = 0; names && i < nf; ++i) {
    if (!names[i]) continue;
    walk(Mat_VarGetStructFieldByIndex(v, i, 0), path_name + "." + names[i], file, depth + 1, out);
  }
}

std::vector<SteppedSineTable> read_mat_tables(const std::filesystem::path& path) {
  const std::string file = path.string();
  // The record reader first checks that the file's structure holds together (matio itself
  // may crash on a damaged file); a file without time histories passes that check and is
  // then refused for what it lacks, which is no defect here.
  try {
    (void)read_mat(path);
  } catch (const InputError& e) {
    const std::string m = e.what();
    if (m.find("no time histories found") == std::string::npos &&
        m.find("no channel") == std::string::npos) {
      throw;
    }
  }
  std::unique_ptr<mat_t, MatCloser> mat(Mat_Open(file.c_str(), MAT_ACC_RDONLY));
  if (!mat) throw InputError(where(file, 0, "not a MATLAB .mat file that matio can open"));
  std::vector<SteppedSineTable> out;
  while (true) {
    std::unique_ptr<matvar_t, VarFreer> v(Mat_VarReadNext(mat.get()));
    if (!v) break;
    if (v->name) walk(v.get(), v->name, file, 0, out);
  }
  if (out.empty()) {
    throw InputError(where(file, 0,
                           "no stepped-sine tables: expected a struct array with fields "
                           "frequency, force, amplitude, phase, units (e.g. "
                           "FRdata.ResponseControl)"));
  }
  return out;
}

}  // namespace

std::vector<SteppedSineTable> read_stepped_sine(const std::filesystem::path& path,
                                                std::optional<Quantity> quantity) {
  const FileFormat format = detect_format(path);
  if (format == FileFormat::kMat) return read_mat_tables(path);
  if (format != FileFormat::kCsv) {
    throw InputError(
        where(path.string(), 0, "stepped-sine tables are read from CSV or .mat files"));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where(path.string(), 0, "cannot open file"));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_stepped_sine_csv(text, path.string(), quantity);
}

void write_stepped_sine_csv(const std::filesystem::path& path,
                            const std::vector<SteppedSineTable>& tables,
                            const std::vector<std::string>& comments) {
  if (tables.empty()) throw InputError(where(path.string(), 0, "no table to write"));
  const Quantity q = tables.front().response_quantity;
  for (const SteppedSineTable& t : tables) {
    if (t.response_quantity != q) {
      throw InputError(where(path.string(), 0,
                             "tables measure different response quantities; write them apart"));
    }
  }
  std::string text;
  for (const std::string& c : comments) text += "# " + c + "\n";
  text +=
      fmt::format("level,control,frequency_hz,force [N],response [{}],phase [deg]\n", si_unit(q));
  for (const SteppedSineTable& t : tables) {
    for (Eigen::Index i = 0; i < t.size(); ++i) {
      text += fmt::format("{},{},{:.10g},{:.10g},{:.10g},{:.10g}\n", t.index,
                          control_name(t.control), t.frequency_hz(i), t.force(i), t.response(i),
                          t.phase_rad(i) * 180.0 / std::numbers::pi);
    }
  }
  write_file_atomically(path, text);
}

}  // namespace jointlab::data
