#include "jointlab/data/modes_table.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <complex>
#include <optional>
#include <string_view>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/data/csv_lines.h"

namespace jointlab::data {
namespace {

// The index of `channel` in `channels`, or -1.
int find_channel(const std::vector<std::string>& channels, const std::string& channel) {
  const auto it = std::find(channels.begin(), channels.end(), channel);
  return it == channels.end() ? -1 : static_cast<int>(it - channels.begin());
}

// What a shape column of a modes table holds: a whole entry (real or complex), or the real or
// imaginary part of one; kMagnitudeOrPhase (row -1) names a sensor's magnitude or phase column.
// kModalParameter (row -1) a column of what other tools export beside the shapes (damping,
// MPC, MPD, modal mass), which the linear update does not use and which is left out.
constexpr int kWhole = 0, kRealPart = 1, kImaginaryPart = 2, kMagnitudeOrPhase = 4,
              kModalParameter = 8;
struct TableColumn {
  int row = -1;        // sensor index, -1: none
  int part = kWhole;   // kWhole, kRealPart, kImaginaryPart or kMagnitudeOrPhase
  std::string header;  // as written
  std::string base;    // the sensor channel, for parts
};

// Whether a modes-table column headed `header` (not a sensor channel) holds a modal parameter
// other tools export beside the shapes: damping (a ratio or in %), zeta, MPC, MPD, MCF, MOV or
// the modal mass, any case, a unit in brackets or after a blank or '_' allowed ("Damping [%]",
// "damping_ratio", "MPC (%)", "Modal mass").
bool modal_parameter_column(const std::string& header) {
  const std::string h(trim(lower(header.substr(0, header.find_first_of("[(")))));
  const auto begins = [&](std::string_view w) {
    return h.rfind(w, 0) == 0 &&
           (h.size() == w.size() || h[w.size()] == '_' || h[w.size()] == ' ' || h[w.size()] == '.');
  };
  for (const std::string_view w :
       {"damping", "damping_ratio", "damping ratio", "zeta", "mpc", "mpd", "mcf", "mov"})
    if (begins(w)) return true;
  return h == "modal_mass" || h == "modal mass";
}

// The column headed `header`: a channel, or one with a suffix _re/_im (also _real/_imag, any
// case, after '_', '.' or ' '), or a modal parameter's (left out).
TableColumn table_column(const std::vector<std::string>& channels, const std::string& header) {
  TableColumn out;
  out.header = header;
  out.row = find_channel(channels, header);
  if (out.row >= 0) return out;
  if (modal_parameter_column(header)) {
    out.part = kModalParameter;
    return out;
  }
  const size_t cut = header.find_last_of("_. ");
  if (cut == std::string::npos || cut == 0) return out;
  const std::string suffix = lower(header.substr(cut + 1));
  out.base = std::string(trim(std::string_view(header).substr(0, cut)));
  const int row = find_channel(channels, out.base);
  if (row < 0) return out;
  if (suffix == "re" || suffix == "real") {
    out.row = row, out.part = kRealPart;
  } else if (suffix == "im" || suffix == "imag") {
    out.row = row, out.part = kImaginaryPart;
  } else if (suffix == "mag" || suffix == "abs" || suffix == "amp" || suffix == "phase" ||
             suffix == "deg" || suffix == "arg") {
    out.part = kMagnitudeOrPhase;
  }
  return out;
}

// `cell` with its commas written as decimal points, where that reads as a number (a decimal
// comma of a European export names itself in the message); none otherwise.
std::optional<std::string> with_decimal_point(const std::string& cell) {
  std::string point = cell;
  std::replace(point.begin(), point.end(), ',', '.');
  if (point == cell || !parse_double(point)) return std::nullopt;
  return point;
}

// A cell as a complex number: a real number, a+bi or a-bj (blanks allowed, i or j, optionally
// in round brackets, "bi" alone imaginary), or (a,b); nothing else, and finite parts only.
std::optional<std::complex<double>> complex_cell(const std::string& cell) {
  std::string t;
  for (const char ch : cell)
    if (!std::isspace(static_cast<unsigned char>(ch))) t += ch;
  if (t.size() >= 2 && t.front() == '(' && t.back() == ')') t = t.substr(1, t.size() - 2);
  const auto real = [](std::string_view x) -> std::optional<double> {
    const std::optional<double> v = parse_double(x);
    if (!v || !std::isfinite(*v)) return std::nullopt;
    return v;
  };
  if (const size_t comma = t.find(','); comma != std::string::npos) {
    if (cell.find('(') == std::string::npos) return std::nullopt;  // "0,5": a decimal comma?
    const auto re = real(std::string_view(t).substr(0, comma));
    const auto im = real(std::string_view(t).substr(comma + 1));
    if (!re || !im) return std::nullopt;
    return std::complex<double>(*re, *im);
  }
  if (t.empty()) return std::nullopt;
  const char last = static_cast<char>(std::tolower(static_cast<unsigned char>(t.back())));
  if (last != 'i' && last != 'j') {
    const auto re = real(t);
    if (!re) return std::nullopt;
    return std::complex<double>(*re, 0.0);
  }
  const std::string_view body = std::string_view(t).substr(0, t.size() - 1);
  // The imaginary part starts at the last sign that is neither first nor an exponent's.
  size_t split = std::string_view::npos;
  for (size_t k = body.size(); k-- > 1;) {
    if ((body[k] == '+' || body[k] == '-') && body[k - 1] != 'e' && body[k - 1] != 'E') {
      split = k;
      break;
    }
  }
  const std::string_view re_text = split == std::string_view::npos ? "" : body.substr(0, split);
  const std::string_view im_text = split == std::string_view::npos ? body : body.substr(split);
  std::optional<double> re = re_text.empty() ? std::optional<double>(0.0) : real(re_text);
  std::optional<double> im = im_text.empty() || im_text == "+" ? std::optional<double>(1.0)
                             : im_text == "-"                  ? std::optional<double>(-1.0)
                                                               : real(im_text);
  if (!re || !im) return std::nullopt;
  return std::complex<double>(*re, *im);
}

// The sensors' channels, for a message: "z1, z2, z3" (the first 8, then how many more).
std::string channel_list(const std::vector<std::string>& channels) {
  std::vector<std::string> names;
  for (size_t i = 0; i < channels.size() && i < 8; ++i) names.push_back(channels[i]);
  if (channels.size() > 8) names.push_back(fmt::format("and {} more", channels.size() - 8));
  return fmt::format("{} channel{}: {}", channels.size(), channels.size() == 1 ? "" : "s",
                     fmt::join(names, ", "));
}

// The factor to Hz of a modes table's frequency column `cell` (column 2 of line n of `name`):
// `frequency_hz`, or a frequency named as test-modal tools write it (frequency, freq, f, fn,
// natural frequency, eigenfrequency; any case) with its unit in Hz or kHz given in brackets
// ([Hz], (kHz)) or after '_' (f_Hz, Frequency_kHz); 0 where the cell names no frequency. A
// frequency without a unit, or in any other, is refused naming the column; rad/s says to give Hz.
double frequency_column_scale(const std::string& name, long n, const std::string& cell) {
  const std::string f = lower(cell);
  const auto refuse = [&](const std::string& why) {
    return InputError(where(name, n, fmt::format("column 2 '{}': {}", printable(cell), why)));
  };
  if (f.find("rad") != std::string::npos || f.find("omega") != std::string::npos)
    throw refuse(
        "frequencies are read in Hz only, under frequency_hz: give them so (rad/s "
        "divided by 2 pi)");
  std::string base = f, unit, written;  // written: the unit as the cell gives it
  if (cell.find_first_of("[(") != std::string::npos) {
    // "Frequency [Hz]" or "Freq (Hz)" (data/csv_lines' splits); brackets that do not close the
    // cell name no frequency.
    const auto split = cell.find('[') != std::string::npos ? split_square_brackets(cell)
                                                           : split_round_brackets(cell);
    if (!split) return 0;
    base = lower(split->first);
    written = split->second;
    unit = lower(written);
  } else {
    for (const char* u : {"hz", "khz"})
      if (const std::string tail = std::string("_") + u; base.ends_with(tail)) {
        base.erase(base.size() - tail.size());
        unit = u;
      }
  }
  if (base == "frequency_hz") {  // frequency_hz [Hz]; in another unit, not frequency_hz
    if (unit == "hz") return 1;
    throw refuse(fmt::format("unit '{}' refused: frequency_hz is in Hz ([Hz] or no unit)",
                             printable(written)));
  }
  const std::vector<std::string> names = {"frequency",         "freq",          "f", "fn", "f_n",
                                          "natural frequency", "eigenfrequency"};
  if (std::find(names.begin(), names.end(), base) == names.end()) return 0;
  if (unit == "hz") return 1;
  if (unit == "khz") return 1e3;
  if (unit.empty())
    throw refuse(
        "a frequency needs its unit: write frequency_hz, or the unit in brackets ('Frequency "
        "[Hz]', 'Frequency [kHz]')");
  throw refuse(
      fmt::format("unit '{}' is not read: give the frequencies in Hz (frequency_hz) or kHz",
                  printable(written)));
}

// Whether a modes table's header cell names the mode column: `mode` in any case, or as test-modal
// tools write it, `Mode #`, `Mode No.`, `Mode number`, `mode_nr` (blanks, `_` and `.` aside).
// Before, `Mode #` was refused as "column 1 'Mode #' is not 'mode'".
bool mode_column(const std::string& cell) {
  std::string k;
  for (const char c : lower(cell))
    if (c != ' ' && c != '\t' && c != '_' && c != '.') k += c;
  return k == "mode" || k == "mode#" || k == "modeno" || k == "modenr" || k == "modenumber";
}

// The shape columns of a modes table from its header `cells` (line n of `name`), after the
// mode and frequency columns that must begin it (`to_hz` receives the frequency column's factor
// to Hz): each a sensor channel (or its real or imaginary part), none twice, every part beside
// its other part.
std::vector<TableColumn> modes_table_columns(const std::string& name,
                                             const std::vector<std::string>& channels,
                                             const std::vector<std::string>& cells, long n,
                                             double& to_hz) {
  std::vector<TableColumn> columns;
  to_hz = cells.size() >= 2 && mode_column(cells[0])
              ? (cells[1] == "frequency_hz" ? 1 : frequency_column_scale(name, n, cells[1]))
              : 0;
  if (to_hz == 0) {
    // What was found, as written, and where: a swapped pair says to swap it.
    std::string found;
    for (size_t c = 0; c < std::min<size_t>(cells.size(), 2); ++c) {
      if (c > 0) found += ',';
      found += printable(cells[c]);
    }
    const bool swapped =
        cells.size() >= 2 && mode_column(cells[1]) && (cells[0] == "frequency_hz" || [&] {
          try {
            return frequency_column_scale(name, n, cells[0]) > 0;
          } catch (const InputError&) {
            return false;
          }
        }());
    // update-linear's own modes.csv (measured,frequency_hz,model_mode,...) pairs the modes of a
    // past update; it holds no shapes to pair a new one with.
    const bool update_output =
        cells.size() >= 3 && cells[0] == "measured" && cells[2] == "model_mode";
    throw InputError(where(
        name, n,
        fmt::format("the header must begin with mode,frequency_hz (or a frequency with its unit, "
                    "'Frequency [Hz]'); it begins '{}'{}",
                    found,
                    update_output
                        ? ": this is the modes.csv update-linear writes (measured against model "
                          "modes), not a modes table; give --measured DIR or a table of mode, "
                          "frequency_hz and one shape column per sensor"
                    : swapped ? ": put the mode column first"
                    : cells.empty() || !mode_column(cells[0])
                        ? fmt::format(", column 1 '{}' is not 'mode'",
                                      cells.empty() ? "" : printable(cells[0]))
                        : fmt::format(", column 2 '{}' names no frequency",
                                      cells.size() < 2 ? "" : printable(cells[1])))));
  }
  for (size_t c = 2; c < cells.size(); ++c) {
    const TableColumn col = table_column(channels, cells[c]);
    if (col.part == kModalParameter) {
      columns.push_back(col);
      continue;
    }
    if (col.row < 0) {
      throw InputError(where(
          name, n,
          col.part == kMagnitudeOrPhase
              ? fmt::format("column '{}': magnitude or phase columns are not read; give the "
                            "real and imaginary parts ({}_re, {}_im) or complex cells (0.1+0.2i)",
                            cells[c], col.base, col.base)
              : fmt::format("column '{}' is not a sensor channel (the sensors file has {}); a "
                            "modes table's columns are mode, frequency_hz, one per channel (or "
                            "its _re and _im parts), and damping, MPC, MPD or modal mass "
                            "columns, which are left out: rename or remove it",
                            cells[c], channel_list(channels))));
    }
    for (const TableColumn& other : columns) {
      if (other.part != kModalParameter && other.row == col.row &&
          (other.part == col.part || other.part == kWhole || col.part == kWhole)) {
        throw InputError(where(name, n,
                               fmt::format("column '{}': sensor channel {} twice", cells[c],
                                           channels[static_cast<size_t>(col.row)])));
      }
    }
    columns.push_back(col);
  }
  for (const TableColumn& col : columns) {
    if (col.part != kRealPart && col.part != kImaginaryPart) continue;
    const bool paired = std::any_of(columns.begin(), columns.end(), [&](const TableColumn& o) {
      return o.row == col.row && o.part == kRealPart + kImaginaryPart - col.part;
    });
    if (!paired) {
      throw InputError(where(name, n,
                             fmt::format("column '{}' has no {} part beside it ({}_{})", col.header,
                                         col.part == kRealPart ? "imaginary" : "real", col.base,
                                         col.part == kRealPart ? "im" : "re")));
    }
  }
  return columns;
}

// The shape of one modes-table row (`cells`, line n of `name`) at the sensors, complex, 0 where
// a sensor has no entry; a sensor with one part of two given is refused. `number` reads cell c.
template <class Number>
Eigen::VectorXcd row_shape(const std::string& name, const std::vector<std::string>& channels,
                           const std::vector<TableColumn>& columns,
                           const std::vector<std::string>& cells, long n, const Number& number) {
  const auto n_s = static_cast<Eigen::Index>(channels.size());
  Eigen::VectorXcd v = Eigen::VectorXcd::Zero(n_s);
  std::vector<char> given(channels.size(), 0);  // per sensor: parts given (1 real, 2 imaginary)
  for (size_t c = 2; c < cells.size(); ++c) {
    const TableColumn& col = columns[c - 2];
    const std::string& cell = cells[c];
    if (cell.empty() || col.part == kModalParameter) continue;
    if (col.part == kWhole) {
      const std::optional<std::complex<double>> z = complex_cell(cell);
      if (!z) {
        const std::optional<std::string> point = with_decimal_point(cell);
        throw InputError(
            where(name, n,
                  point ? fmt::format("shape entry '{}' of column '{}' is not a number (a decimal "
                                      "comma: write {} with a decimal point; ';' or tab may still "
                                      "separate the cells)",
                                      cell, col.header, *point)
                        : fmt::format("shape entry '{}' of column '{}' is not a number (real, or "
                                      "complex as 0.1+0.2i, 0.1-0.2j or (0.1,0.2))",
                                      cell, col.header)));
      }
      v(col.row) = *z;
      given[static_cast<size_t>(col.row)] = 3;
      continue;
    }
    const double x = number(c, "shape entry");
    if (col.part == kRealPart)
      v(col.row).real(x);
    else
      v(col.row).imag(x);
    given[static_cast<size_t>(col.row)] |= static_cast<char>(col.part);
  }
  for (const TableColumn& col : columns) {
    if (col.part == kModalParameter) continue;
    const char g = given[static_cast<size_t>(col.row)];
    if (col.part != kWhole && g != 0 && g != 3) {
      throw InputError(where(
          name, n,
          fmt::format("sensor {}: its {} part is given and its {} part empty: give both or "
                      "neither (neither: not measured)",
                      channels[static_cast<size_t>(col.row)], g == kRealPart ? "real" : "imaginary",
                      g == kRealPart ? "imaginary" : "real")));
    }
  }
  return v;
}

}  // namespace

ModesTable read_modes_table(const std::filesystem::path& path,
                            const std::vector<std::string>& channels) {
  ModesTable out;
  out.source = path.string();
  const std::string& name = out.source;
  std::vector<TableColumn> columns;  // what each shape column holds
  std::vector<double> freq;
  std::vector<Eigen::VectorXcd> shape;
  double to_hz = 1;  // the frequency column's unit: Hz or kHz
  const auto on_header = [&](const std::vector<std::string>& cells, long n) {
    columns = modes_table_columns(name, channels, cells, n, to_hz);
  };
  const auto on_row = [&](const std::vector<std::string>& cells, long n) {
    auto number = [&](size_t c, const char* what) {
      const std::optional<double> x = parse_double(cells[c]);
      if (!x || !std::isfinite(*x)) {
        // A decimal comma (a European export): say so where a point would read.
        const std::optional<std::string> point = with_decimal_point(cells[c]);
        throw InputError(where(
            name, n,
            fmt::format("{} '{}' is not a number{}", what, cells[c],
                        point ? fmt::format(" (a decimal comma: write {} with a decimal point; "
                                            "';' or tab may still separate the cells)",
                                            *point)
                              : "")));
      }
      return *x;
    };
    const double mode = number(0, "mode");
    if (mode != std::floor(mode) || mode < 1) {
      throw InputError(where(name, n, fmt::format("mode '{}' must be an integer >= 1", cells[0])));
    }
    for (int m : out.modes) {
      if (m == static_cast<int>(mode)) {
        throw InputError(where(name, n, fmt::format("mode {} twice", m)));
      }
    }
    const double f = to_hz * number(1, "frequency_hz");
    if (!(f > 0)) throw InputError(where(name, n, "frequency_hz must be > 0"));
    shape.push_back(row_shape(name, channels, columns, cells, n, number));
    out.modes.push_back(static_cast<int>(mode));
    out.lines.push_back(n);
    freq.push_back(f);
  };
  for_each_csv_row(path, "modes table", on_header, on_row, /*detect=*/true);
  if (freq.empty()) throw InputError(fmt::format("{}: no mode in the table", name));
  const auto count = static_cast<Eigen::Index>(freq.size());
  out.frequency_hz = Eigen::Map<const Eigen::VectorXd>(freq.data(), count);
  out.shapes.resize(static_cast<Eigen::Index>(channels.size()), count);
  for (Eigen::Index i = 0; i < count; ++i) out.shapes.col(i) = shape[static_cast<size_t>(i)];
  return out;
}

}  // namespace jointlab::data
