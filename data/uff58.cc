#include "jointlab/data/uff58.h"

#include "jointlab/core/text.h"
#include "jointlab/core/units.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/data/names.h"

namespace jointlab::data {
namespace {

bool is_none(std::string_view s) {
  s = trim(s);
  return s.empty() || s == "NONE" || s == "none" || s == "None";
}

// A line-by-line view of the file that also hands out raw byte ranges (58b).
class Cursor {
 public:
  explicit Cursor(std::string_view bytes) : bytes_(bytes) {}
  bool at_end() const { return pos_ >= bytes_.size(); }
  long line() const { return line_; }
  size_t remaining() const { return bytes_.size() - pos_; }
  // The next line without its end of line; false at end of file.
  bool next(std::string_view& out) {
    if (at_end()) return false;
    const size_t end = bytes_.find('\n', pos_);
    const size_t stop = end == std::string_view::npos ? bytes_.size() : end;
    out = bytes_.substr(pos_, stop - pos_);
    if (!out.empty() && out.back() == '\r') out.remove_suffix(1);
    pos_ = stop == bytes_.size() ? stop : stop + 1;
    ++line_;
    return true;
  }
  // The next n raw bytes (the caller checked n <= remaining()).
  std::string_view take(size_t n) {
    const std::string_view out = bytes_.substr(pos_, n);
    pos_ += n;
    return out;
  }

 private:
  std::string_view bytes_;
  size_t pos_ = 0;
  long line_ = 0;
};

// Appends every number of a text line to `out` (Fortran E fields, possibly run
// together); returns the offending token when something else is there.
std::optional<std::string> scan_numbers(std::string_view line, std::vector<double>& out) {
  size_t i = 0;
  while (i < line.size()) {
    const char c = line[i];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
      ++i;
      continue;
    }
    size_t start = i;
    if (c == '+') ++start;
    double v = 0;
    const auto [ptr, ec] = std::from_chars(line.data() + start, line.data() + line.size(), v);
    if (ec != std::errc() || ptr == line.data() + start) {
      const size_t end = line.find_first_of(" \t", i);
      return std::string(line.substr(i, end == std::string_view::npos ? end : end - i));
    }
    out.push_back(v);
    i = static_cast<size_t>(ptr - line.data());
  }
  return std::nullopt;
}

std::optional<long> to_long(std::string_view s) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  long v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

// Fixed-width field [start, start + width) of a card image; shorter lines give "".
std::string_view column(std::string_view line, size_t start, size_t width) {
  if (start >= line.size()) return {};
  return line.substr(start, width);
}

const char* function_type_name(long type) {
  switch (type) {
    case 0:
      return "general";
    case 1:
      return "time response";
    case 2:
      return "auto spectrum";
    case 3:
      return "cross spectrum";
    case 4:
      return "frequency response function";
    case 5:
      return "transmissibility";
    case 6:
      return "coherence";
    case 7:
      return "auto correlation";
    case 8:
      return "cross correlation";
    case 9:
      return "power spectral density";
    case 10:
      return "energy spectral density";
    case 11:
      return "probability density function";
    case 12:
      return "spectrum";
    case 18:
      return "mode indicator function";
    case 24:
      return "shock response spectrum";
    default:
      return "not a time history";
  }
}

const char* direction_name(long dir) {
  switch (dir) {
    case 1:
      return "+X";
    case 2:
      return "+Y";
    case 3:
      return "+Z";
    case 4:
      return "+RX";
    case 5:
      return "+RY";
    case 6:
      return "+RZ";
    case -1:
      return "-X";
    case -2:
      return "-Y";
    case -3:
      return "-Z";
    case -4:
      return "-RX";
    case -5:
      return "-RY";
    case -6:
      return "-RZ";
    default:
      return "";
  }
}

std::optional<Quantity> quantity_of_data_type(long type) {
  switch (type) {
    case 8:
      return Quantity::kDisplacement;
    case 11:
      return Quantity::kVelocity;
    case 12:
      return Quantity::kAcceleration;
    case 9:   // reaction force
    case 13:  // excitation force
      return Quantity::kForce;
    default:
      return std::nullopt;
  }
}

long data_type_of_quantity(Quantity q) {
  switch (q) {
    case Quantity::kDisplacement:
      return 8;
    case Quantity::kVelocity:
      return 11;
    case Quantity::kAcceleration:
      return 12;
    case Quantity::kForce:
      return 13;
  }
  return 0;
}

struct AxisRecord {
  long data_type = 0;
  std::string label;
  std::string unit;  // as written, "" when NONE
};

AxisRecord parse_axis(std::string_view line, const std::string& file, long line_no, int record) {
  // Format(I10,3I5,2(1X,A20)); the unit label runs to the end of the line (it may hold
  // multi-byte characters such as "m/s²").
  AxisRecord a;
  const auto type = to_long(column(line, 0, 10));
  if (!type) {
    throw InputError(where(file, line_no,
                           fmt::format("record {}: specific data type '{}' is not "
                                       "an integer",
                                       record, printable(trim(column(line, 0, 10))))));
  }
  a.data_type = *type;
  a.label = std::string(trim(column(line, 26, 20)));
  const std::string_view unit = trim(column(line, 47, std::string_view::npos));
  if (!is_none(unit)) a.unit = std::string(unit);
  return a;
}

struct Dataset {
  long line = 0;  // line of the dataset number
  bool binary = false;
  std::string id[5];
  long function_type = 0;
  std::string entity;
  long node = 0;
  long direction = 0;
  long ordinate_type = 0;
  long n = 0;
  bool even = true;
  double x0 = 0;
  double dx = 0;
  AxisRecord abscissa, ordinate;
  std::vector<double> values;     // the ordinates
  std::vector<double> abscissae;  // uneven spacing only
};

struct BinaryHeader {
  long byte_order = 1;    // 1 little endian, 2 big endian
  long float_format = 2;  // 2 IEEE 754
  long ascii_lines = 0;
  long bytes = 0;
};

// Dataset line of a binary dataset: Format(I6,1A1,I6,I6,I12,I12,I6,I6,I12,I12).
BinaryHeader parse_binary_header(std::string_view line, const std::string& file, long line_no) {
  std::vector<double> v;
  const std::string_view head = trim(line);
  const std::string_view rest = head.substr(head.find_first_of("bB") + 1);
  if (scan_numbers(rest, v) || v.size() < 4) {
    throw InputError(where(file, line_no,
                           "binary dataset line: expected byte order, floating "
                           "point format, number of ASCII lines and of bytes"));
  }
  for (size_t i = 0; i < 4; ++i) {
    if (v[i] != std::floor(v[i]) || std::abs(v[i]) > 9e15) {
      throw InputError(where(file, line_no, "binary dataset line: field is not an integer"));
    }
  }
  return BinaryHeader{static_cast<long>(v[0]), static_cast<long>(v[1]), static_cast<long>(v[2]),
                      static_cast<long>(v[3])};
}

// Reads the eleven header records of a dataset 58.
void parse_header(Cursor& cur, Dataset& ds, const std::string& file) {
  std::string_view line;
  long lines[12] = {};
  std::string_view rec[12];
  for (int r = 1; r <= 11; ++r) {
    if (!cur.next(line)) {
      throw InputError(where(file, cur.line(),
                             fmt::format("dataset 58 starting at line {} ends "
                                         "inside its header (record {} missing)",
                                         ds.line, r)));
    }
    rec[r] = line;
    lines[r] = cur.line();
  }
  for (int r = 0; r < 5; ++r) ds.id[r] = std::string(trim(rec[r + 1]));

  // Record 6: Format(2(I5,I10),2(1X,10A1,I10,I4)).
  const std::string_view r6 = rec[6];
  const auto ftype = to_long(column(r6, 0, 5));
  if (!ftype) {
    throw InputError(where(file, lines[6],
                           fmt::format("record 6: function type '{}' is not an "
                                       "integer",
                                       printable(trim(column(r6, 0, 5))))));
  }
  ds.function_type = *ftype;
  ds.entity = std::string(trim(column(r6, 31, 10)));
  const std::string_view node_text = trim(column(r6, 41, 10));
  const std::string_view dir_text = trim(column(r6, 51, 4));
  const auto node = node_text.empty() ? std::optional<long>(0) : to_long(node_text);
  const auto dir = dir_text.empty() ? std::optional<long>(0) : to_long(dir_text);
  if (!node || !dir) {
    throw InputError(where(file, lines[6],
                           fmt::format("record 6: response node '{}' or direction "
                                       "'{}' is not an integer",
                                       printable(node_text), printable(dir_text))));
  }
  ds.node = *node;
  ds.direction = *dir;

  // Record 7: Format(3I10,3E13.5); read as free-format numbers.
  std::vector<double> v;
  if (auto bad = scan_numbers(rec[7], v)) {
    throw InputError(
        where(file, lines[7], fmt::format("record 7: '{}' is not a number", printable(*bad))));
  }
  if (v.size() < 5) {
    throw InputError(where(file, lines[7],
                           fmt::format("record 7: {} fields, expected 6 (data "
                                       "type, points, spacing, minimum, increment,"
                                       " z)",
                                       v.size())));
  }
  for (int i = 0; i < 3; ++i) {
    if (v[i] != std::floor(v[i]) || std::abs(v[i]) > 9e15) {
      throw InputError(where(file, lines[7],
                             fmt::format("record 7: field {} ({}) is not an "
                                         "integer",
                                         i + 1, v[i])));
    }
  }
  ds.ordinate_type = static_cast<long>(v[0]);
  ds.n = static_cast<long>(v[1]);
  ds.even = v[2] == 1;
  ds.x0 = v[3];
  ds.dx = v[4];

  ds.abscissa = parse_axis(rec[8], file, lines[8], 8);
  ds.ordinate = parse_axis(rec[9], file, lines[9], 9);

  // What jointlab accepts, checked before any data is read.
  const bool time_abscissa = ds.abscissa.data_type == 17 || ds.abscissa.unit == "s";
  if (!(ds.function_type == 1 || (ds.function_type == 0 && time_abscissa))) {
    throw InputError(where(file, lines[6],
                           fmt::format("record 6: function type {} ({}) is not a "
                                       "time response (type 1); jointlab reads "
                                       "time histories only",
                                       ds.function_type, function_type_name(ds.function_type))));
  }
  if (ds.ordinate_type == 5 || ds.ordinate_type == 6) {
    throw InputError(where(file, lines[7],
                           fmt::format("record 7: complex ordinate data (type {}) "
                                       "is not a time history",
                                       ds.ordinate_type)));
  }
  if (ds.ordinate_type != 2 && ds.ordinate_type != 4) {
    throw InputError(where(file, lines[7],
                           fmt::format("record 7: ordinate data type {} is not 2 "
                                       "(real single) or 4 (real double)",
                                       ds.ordinate_type)));
  }
  if (v[2] != 0 && v[2] != 1) {
    throw InputError(where(file, lines[7],
                           fmt::format("record 7: abscissa spacing {} is not 0 "
                                       "(uneven) or 1 (even)",
                                       v[2])));
  }
  if (ds.n < 2) {
    throw InputError(
        where(file, lines[7], fmt::format("record 7: {} points; need at least 2", ds.n)));
  }
  if (ds.even) {
    if (!std::isfinite(ds.x0) || !std::isfinite(ds.dx)) {
      throw InputError(where(file, lines[7],
                             "record 7: abscissa minimum or increment is not "
                             "finite"));
    }
    if (!(ds.dx > 0)) {
      throw InputError(where(file, lines[7],
                             fmt::format("record 7: abscissa increment {} is not "
                                         "positive (no sampling rate)",
                                         ds.dx)));
    }
  }
  if (ds.abscissa.data_type != 17 && ds.abscissa.data_type != 0 && ds.abscissa.data_type != 1) {
    throw InputError(where(file, lines[8],
                           fmt::format("record 8: abscissa specific data type {} "
                                       "is not time (17)",
                                       ds.abscissa.data_type)));
  }
  double time_scale = 1.0;
  if (ds.abscissa.unit == "ms") {
    time_scale = 1e-3;
  } else if (!ds.abscissa.unit.empty() && ds.abscissa.unit != "s" && ds.abscissa.unit != "sec") {
    throw InputError(where(file, lines[8],
                           fmt::format("record 8: abscissa unit '{}' is not a "
                                       "time unit (s or ms)",
                                       printable(ds.abscissa.unit))));
  }
  ds.x0 *= time_scale;
  ds.dx *= time_scale;
}

double load_value(std::string_view bytes, size_t index, size_t size, bool big_endian) {
  unsigned char b[8];
  std::memcpy(b, bytes.data() + index * size, size);
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + size);
  if (size == 4) {
    float f;
    std::memcpy(&f, b, 4);
    return f;
  }
  double d;
  std::memcpy(&d, b, 8);
  return d;
}

// Reads the data section of a dataset 58 into ds.values (and ds.abscissae if uneven).
void parse_data(Cursor& cur, Dataset& ds, const BinaryHeader* bin, const std::string& file) {
  const size_t per_point = ds.even ? 1 : 2;
  const auto total = static_cast<unsigned long>(ds.n) * per_point;
  std::vector<double> raw;
  long data_line = cur.line() + 1;
  std::vector<long> value_lines;  // ASCII: the line of every 6th value, for messages
  if (bin) {
    const size_t size = ds.ordinate_type == 2 ? 4 : 8;
    if (static_cast<unsigned long>(ds.n) > cur.remaining() / size / per_point) {
      throw InputError(where(file, data_line,
                             fmt::format("dataset 58b declares {} points but only "
                                         "{} bytes follow (truncated file?)",
                                         ds.n, cur.remaining())));
    }
    if (static_cast<unsigned long>(bin->bytes) != total * size) {
      throw InputError(where(file, ds.line,
                             fmt::format("dataset 58b: {} bytes declared, {} points"
                                         " of {} bytes need {}",
                                         bin->bytes, ds.n, size, total * size)));
    }
    const std::string_view block = cur.take(total * size);
    raw.resize(total);
    for (size_t i = 0; i < total; ++i) raw[i] = load_value(block, i, size, bin->byte_order == 2);
    // The end of line after the data, if any, then the closing "-1".
    std::string_view line;
    bool closed = false;
    while (cur.next(line)) {
      if (trim(line).empty()) continue;
      if (trim(line) == "-1") {
        closed = true;
        break;
      }
      throw InputError(where(file, cur.line(),
                             fmt::format("dataset 58b: unexpected '{}' after "
                                         "{} data bytes (expected -1)",
                                         printable(trim(line)), bin->bytes)));
    }
    (void)closed;  // a file may end right after the data
  } else {
    // At least two characters per value; refuse a declared size the file cannot hold.
    if (total > cur.remaining() / 2 + 1) {
      throw InputError(where(file, data_line,
                             fmt::format("dataset 58 declares {} points but only "
                                         "{} bytes follow (truncated file?)",
                                         ds.n, cur.remaining())));
    }
    raw.reserve(total);
    std::string_view line;
    bool closed = false;
    while (cur.next(line)) {
      if (trim(line) == "-1") {
        closed = true;
        break;
      }
      const size_t before = raw.size();
      if (auto bad = scan_numbers(line, raw)) {
        throw InputError(
            where(file, cur.line(), fmt::format("'{}' is not a number", printable(*bad))));
      }
      if (raw.size() > total) {
        throw InputError(where(file, cur.line(),
                               fmt::format("more values than the {} points "
                                           "declared in record 7 (line {})",
                                           ds.n, ds.line + 7)));
      }
      for (size_t k = before; k < raw.size(); ++k) {
        if (!std::isfinite(raw[k])) {
          throw InputError(where(file, cur.line(),
                                 fmt::format("value {} is {} (NaN and Inf are "
                                             "not allowed)",
                                             k + 1, raw[k])));
        }
      }
      value_lines.push_back(cur.line());
    }
    if (raw.size() < total) {
      throw InputError(where(file, cur.line(),
                             fmt::format("dataset 58 starting at line {} is "
                                         "truncated: {} of {} values",
                                         ds.line, raw.size(), total)));
    }
    (void)closed;
  }
  for (size_t k = 0; k < raw.size(); ++k) {
    if (!std::isfinite(raw[k])) {
      throw InputError(where(file, data_line,
                             fmt::format("dataset 58b: value {} is {} (NaN and "
                                         "Inf are not allowed)",
                                         k + 1, raw[k])));
    }
  }
  if (ds.even) {
    ds.values = std::move(raw);
    return;
  }
  // Uneven spacing: (abscissa, ordinate) pairs, accepted when the abscissa is uniform.
  const size_t n = static_cast<size_t>(ds.n);
  ds.values.resize(n);
  ds.abscissae.resize(n);
  for (size_t k = 0; k < n; ++k) {
    ds.abscissae[k] = raw[2 * k];
    ds.values[k] = raw[2 * k + 1];
  }
  const std::vector<double>& t = ds.abscissae;
  for (size_t k = 1; k < n; ++k) {
    if (!(t[k] > t[k - 1])) {
      throw InputError(where(file, data_line,
                             fmt::format("uneven abscissa: point {} at t = {} "
                                         "does not increase (previous {})",
                                         k + 1, t[k], t[k - 1])));
    }
  }
  const double dt = (t[n - 1] - t[0]) / static_cast<double>(n - 1);
  for (size_t k = 0; k < n; ++k) {
    const double expected = t[0] + static_cast<double>(k) * dt;
    if (std::abs(t[k] - expected) > 0.1 * dt) {
      throw InputError(where(file, data_line,
                             fmt::format("uneven abscissa: point {} at t = {} "
                                         "where {} was expected; jointlab needs "
                                         "a uniform time base",
                                         k + 1, t[k], expected)));
    }
  }
  if (!(dt > 0) || !std::isfinite(dt) || !std::isfinite(1.0 / dt)) {
    throw InputError(where(file, data_line, "uneven abscissa: no usable sampling interval"));
  }
  ds.x0 = t[0];
  ds.dx = dt;
}

std::string channel_name(const Dataset& ds, size_t index) {
  if (ds.node >= 1 && ds.direction != 0 && *direction_name(ds.direction)) {
    return fmt::format("{}{}", ds.node, direction_name(ds.direction));
  }
  if (!is_none(ds.entity)) return ds.entity;
  if (!is_none(ds.id[0])) return ds.id[0];
  return fmt::format("ch{}", index + 1);
}

Channel make_channel(const Dataset& ds, size_t index, const std::string& file) {
  Channel ch;
  ch.name = channel_name(ds, index);
  const auto type_q = quantity_of_data_type(ds.ordinate.data_type);
  const std::string& label = ds.ordinate.unit;
  const auto unit = label.empty() ? std::nullopt : parse_unit(label);
  double scale = 1.0;
  const long line9 = ds.line + 9;
  if (unit) {
    if (type_q && *type_q != unit->quantity) {
      throw InputError(where(file, line9,
                             fmt::format("record 9: unit '{}' measures {} but the "
                                         "specific data type {} is {}",
                                         label, quantity_name(unit->quantity),
                                         ds.ordinate.data_type, quantity_name(*type_q))));
    }
    ch.quantity = unit->quantity;
    scale = unit->to_si;
  } else if (type_q) {
    if (!label.empty()) {
      throw InputError(where(file, line9,
                             fmt::format("record 9: unknown {} unit '{}' (known: {})",
                                         quantity_name(*type_q), printable(label), known_units())));
    }
    ch.quantity = type_q;  // unlabelled: SI, as the unit exponents say nothing of scale
  }
  ch.unit = label;
  ch.samples = Eigen::Map<const Eigen::VectorXd>(ds.values.data(),
                                                 static_cast<Eigen::Index>(ds.values.size())) *
               scale;
  return ch;
}

}  // namespace

Record parse_uff58(std::string_view bytes, const std::string& name) {
  Cursor cur(bytes);
  std::vector<Dataset> sets;
  std::string_view line;
  while (cur.next(line)) {
    if (trim(line).empty()) continue;
    if (trim(line) != "-1") {
      throw InputError(where(name, cur.line(),
                             fmt::format("expected '-1' opening a dataset, found "
                                         "'{}'",
                                         printable(trim(line)))));
    }
    // The dataset number, "58" or "58b" followed by the binary layout.
    if (!cur.next(line)) break;
    const long id_line = cur.line();
    const std::string_view head = trim(line);
    const std::string_view number = head.substr(0, head.find_first_of(" \t"));
    const bool binary = !number.empty() && (number.back() == 'b' || number.back() == 'B');
    const auto id = to_long(binary ? number.substr(0, number.size() - 1) : number);
    if (!id) {
      throw InputError(where(
          name, id_line, fmt::format("dataset number '{}' is not an integer", printable(number))));
    }
    BinaryHeader bin;
    if (binary) bin = parse_binary_header(line, name, id_line);
    if (*id != 58) {
      // Another dataset: skip it (by its declared layout when binary).
      if (binary) {
        if (bin.ascii_lines < 0 || bin.bytes < 0) {
          throw InputError(where(name, id_line, "binary dataset: negative size"));
        }
        for (long k = 0; k < bin.ascii_lines; ++k) {
          if (!cur.next(line)) throw InputError(where(name, cur.line(), "truncated dataset"));
        }
        if (static_cast<unsigned long>(bin.bytes) > cur.remaining()) {
          throw InputError(where(name, id_line,
                                 fmt::format("dataset {}b declares {} bytes but "
                                             "only {} follow",
                                             *id, bin.bytes, cur.remaining())));
        }
        cur.take(static_cast<size_t>(bin.bytes));
      }
      while (cur.next(line) && trim(line) != "-1") {
      }
      continue;
    }
    Dataset ds;
    ds.line = id_line;
    ds.binary = binary;
    if (binary) {
      if (bin.ascii_lines != 11) {
        throw InputError(where(name, id_line,
                               fmt::format("dataset 58b: {} ASCII header lines "
                                           "declared, expected 11",
                                           bin.ascii_lines)));
      }
      if (bin.byte_order != 1 && bin.byte_order != 2) {
        throw InputError(where(name, id_line,
                               fmt::format("dataset 58b: byte order {} is not 1 "
                                           "(little endian) or 2 (big endian)",
                                           bin.byte_order)));
      }
      if (bin.float_format != 2) {
        throw InputError(where(name, id_line,
                               fmt::format("dataset 58b: floating-point format {} "
                                           "is not 2 (IEEE 754)",
                                           bin.float_format)));
      }
      if (bin.bytes < 0) throw InputError(where(name, id_line, "dataset 58b: negative byte count"));
    }
    parse_header(cur, ds, name);
    parse_data(cur, ds, binary ? &bin : nullptr, name);
    sets.push_back(std::move(ds));
  }
  if (sets.empty()) {
    throw InputError(where(name, 0,
                           bytes.empty() ? "empty file"
                                         : "no dataset 58 (time history) in this UFF "
                                           "file"));
  }

  Record rec;
  rec.source = name;
  const Dataset& first = sets.front();
  rec.fs = 1.0 / first.dx;
  rec.t0 = first.x0;
  if (!std::isfinite(rec.fs)) {
    throw InputError(where(name, first.line + 7,
                           "record 7: abscissa increment gives no finite "
                           "sampling rate"));
  }
  rec.metadata["format"] = first.binary ? "uff58b" : "uff58";
  if (!is_none(first.id[2])) rec.metadata["date"] = first.id[2];
  for (size_t i = 0; i < sets.size(); ++i) {
    const Dataset& ds = sets[i];
    if (ds.n != first.n || std::abs(ds.dx - first.dx) > 1e-6 * first.dx ||
        std::abs(ds.x0 - first.x0) > 1e-3 * first.dx) {
      throw InputError(where(name, ds.line,
                             fmt::format("dataset 58 #{}: time base ({} points, t0 "
                                         "= {} s, dt = {} s) differs from dataset "
                                         "#1 ({} points, t0 = {} s, dt = {} s); a "
                                         "record needs one time base",
                                         i + 1, ds.n, ds.x0, ds.dx, first.n, first.x0, first.dx)));
    }
    Channel ch = make_channel(ds, i, name);
    if (rec.find(ch.name)) {
      throw InputError(
          where(name, ds.line,
                fmt::format("dataset 58 #{}: two channels named '{}'", i + 1, printable(ch.name))));
    }
    rec.metadata[fmt::format("{}.node", ch.name)] = std::to_string(ds.node);
    rec.metadata[fmt::format("{}.direction", ch.name)] =
        *direction_name(ds.direction) ? direction_name(ds.direction) : "scalar";
    rec.channels.push_back(std::move(ch));
  }
  std::vector<std::string> names;
  for (const Channel& ch : rec.channels) names.push_back(ch.name);
  check_channel_names(names, name);
  return rec;
}

Record read_uff58(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where(path.string(), 0, "cannot open file"));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(where(path.string(), 0, "read error"));
  return parse_uff58(bytes, path.string());
}

// ---------------------------------------------------------------------------------------------
// Writer

namespace {

// A Fortran E field of `width` characters with as many decimals (up to `max_decimals`) as
// leave one leading blank, so free-format and fixed-format readers both see it.
std::string e_field(double v, int width, int max_decimals) {
  for (int d = max_decimals; d >= 1; --d) {
    std::string s = fmt::format("{:.{}E}", v, d);
    if (static_cast<int>(s.size()) < width) return fmt::format("{:>{}}", s, width);
  }
  return fmt::format(" {:.1E}", v);
}

// "<node><dir>" ("1+Z") back to node and direction code; nullopt for other names.
std::optional<std::pair<long, long>> node_direction(const std::string& name) {
  size_t i = 0;
  while (i < name.size() && std::isdigit(static_cast<unsigned char>(name[i]))) ++i;
  if (i == 0 || i > 9) return std::nullopt;
  const std::string_view dir = std::string_view(name).substr(i);
  for (long d = -6; d <= 6; ++d) {
    if (d != 0 && dir == direction_name(d)) return std::make_pair(std::stol(name.substr(0, i)), d);
  }
  return std::nullopt;
}

std::string axis_line(long type, int length_exp, int force_exp, const std::string& label,
                      const std::string& unit) {
  return fmt::format("{:>10}{:>5}{:>5}{:>5} {:<20} {:<20}\n", type, length_exp, force_exp, 0,
                     label.substr(0, 20), unit.substr(0, 20));
}

}  // namespace

std::string format_uff58(const Record& record, bool binary, const std::string& name) {
  check_writable(record, name);
  const Eigen::Index n = record.size();
  std::string out;
  const std::string date = record.metadata.count("date") ? record.metadata.at("date") : "NONE";
  for (size_t c = 0; c < record.channels.size(); ++c) {
    const Channel& ch = record.channels[c];
    if (!ch.samples.allFinite()) {
      throw InputError(where(name, 0, fmt::format("channel '{}' holds NaN or Inf", ch.name)));
    }
    if (ch.name.empty() || ch.name.size() > 80 ||
        ch.name.find_first_of("\r\n") != std::string::npos || trim(ch.name) != ch.name ||
        is_none(ch.name)) {
      throw InputError(where(name, 0,
                             fmt::format("channel name '{}' cannot be written to UFF "
                                         "(1-80 characters, no line break, no leading or"
                                         " trailing blank, not NONE)",
                                         ch.name)));
    }
    const auto nd = node_direction(ch.name);
    const long node = nd ? nd->first : 0;
    const long dir = nd ? nd->second : 0;
    const std::string entity = !nd && ch.name.size() <= 10 ? ch.name : "NONE";
    std::string unit;
    long type = 0;
    int length_exp = 0, force_exp = 0;
    if (ch.quantity) {
      unit = si_unit(*ch.quantity);
      type = data_type_of_quantity(*ch.quantity);
      length_exp = *ch.quantity == Quantity::kForce ? 0 : 1;
      force_exp = *ch.quantity == Quantity::kForce ? 1 : 0;
    } else {
      unit = ch.unit.empty() ? "NONE" : ch.unit;
    }
    const size_t bytes = static_cast<size_t>(n) * 8;
    out += "    -1\n";
    if (binary) {
      out += fmt::format("{:>6}b{:>6}{:>6}{:>12}{:>12}{:>6}{:>6}{:>12}{:>12}\n", 58, 1, 2, 11,
                         bytes, 0, 0, 0, 0);
    } else {
      out += "    58\n";
    }
    out += ch.name + "\n";
    out += "NONE\n";
    out += (date.find_first_of("\r\n") == std::string::npos ? date : "NONE") + "\n";
    out += "NONE\nNONE\n";
    out += fmt::format("{:>5}{:>10}{:>5}{:>10} {:<10}{:>10}{:>4} {:<10}{:>10}{:>4}\n", 1, c + 1, 0,
                       0, entity, node, dir, "NONE", 0, 0);
    out += fmt::format("{:>10}{:>10}{:>10}{}{}{}\n", 4, n, 1, e_field(record.t0, 13, 6),
                       e_field(1.0 / record.fs, 13, 6), e_field(0.0, 13, 5));
    out += axis_line(17, 0, 0, "Time", "s");
    out += axis_line(type, length_exp, force_exp, ch.name, unit);
    out += axis_line(0, 0, 0, "NONE", "NONE");
    out += axis_line(0, 0, 0, "NONE", "NONE");
    if (binary) {
      const size_t start = out.size();
      out.resize(start + bytes);
      for (Eigen::Index k = 0; k < n; ++k) {
        double v = ch.samples[k];
        unsigned char b[8];
        std::memcpy(b, &v, 8);
        if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + 8);
        std::memcpy(out.data() + start + static_cast<size_t>(k) * 8, b, 8);
      }
      out += "\n";
    } else {
      for (Eigen::Index k = 0; k < n; ++k) {
        out += fmt::format("{:20.12E}", ch.samples[k]);
        if (k % 4 == 3 || k == n - 1) out += "\n";
      }
    }
    out += "    -1\n";
  }
  return out;
}

void write_uff58(const std::filesystem::path& path, const Record& record, bool binary) {
  write_file_atomically(path, format_uff58(record, binary, path.string()));
}

}  // namespace jointlab::data
