#include "jointlab/data/csv_reader.h"

#include "jointlab/core/text.h"
#include "jointlab/core/units.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <functional>
#include <new>
#include <optional>
#include <tuple>
#include <unordered_set>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/memory.h"
#include "jointlab/data/csv_lines.h"
#include "jointlab/data/names.h"

namespace jointlab::data {

const Channel* Record::find(const std::string& name) const {
  for (const Channel& c : channels) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

namespace {

bool looks_binary(std::string_view text) {
  const size_t n = std::min<size_t>(text.size(), 4096);
  size_t bad = 0;
  for (size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == 0) return true;
    if (c < 0x09 || (c > 0x0d && c < 0x20 && c != 0x1b)) ++bad;
  }
  return bad * 20 > n;  // more than 5 % control characters
}

struct ColumnSpec {
  std::string name;
  std::optional<Unit> unit;
  std::string unit_text;
  bool is_time = false;
  double time_scale = 1.0;
};

ColumnSpec parse_header_field(std::string_view raw, const std::string& file, long line) {
  ColumnSpec spec;
  std::tie(spec.name, spec.unit_text) = split_name_unit(raw, file, line);
  if (spec.name.empty())
    throw InputError(where(file, line, fmt::format("header '{}' has no name", shorten(trim(raw)))));
  // A unit in round brackets would stay part of the name, and the channel would have no unit:
  // 'acc1 (g)' with --quantity acceleration read g as m/s^2. Only a known unit is refused; a
  // name such as 'acc1 (x)' is a name, and so is 'force (in)' (input; inches are 'in' too).
  if (const auto round = split_round_brackets(spec.name); spec.unit_text.empty() && round) {
    const auto& [base, unit] = *round;
    const bool time_unit = lower(base) == "time" && (unit == "s" || unit == "ms");
    if (!base.empty() && unit != "in" && (time_unit || parse_unit(unit))) {
      throw InputError(where(
          file, line,
          fmt::format("column '{}': if '{}' is its unit, write it in square brackets, '{} [{}]' "
                      "(in round brackets it is read as part of the name, and the channel has no "
                      "unit); if it is part of the name, write the name without round brackets",
                      shorten(spec.name), shorten(unit), shorten(base), shorten(unit))));
    }
  }
  if (lower(spec.name) == "time") {
    spec.is_time = true;
    if (spec.unit_text.empty() || spec.unit_text == "s") {
      spec.time_scale = 1.0;
    } else if (spec.unit_text == "ms") {
      spec.time_scale = 1e-3;
    } else {
      throw InputError(
          where(file, line,
                fmt::format("time column unit '{}' is not s or ms", shorten(spec.unit_text))));
    }
    return spec;
  }
  if (!spec.unit_text.empty()) {
    spec.unit = parse_unit(spec.unit_text);
    if (!spec.unit) {
      throw InputError(
          where(file, line,
                fmt::format("column '{}': unknown unit '{}' (known: {})", shorten(spec.name),
                            shorten(spec.unit_text), known_units())));
    }
  }
  return spec;
}

double parse_fs(const std::string& value, const std::string& file, long line) {
  std::string_view v = trim(value);
  const auto space = v.find_first_of(" \t");
  std::string_view number = v.substr(0, space);
  std::string_view rest = space == std::string_view::npos ? "" : trim(v.substr(space));
  const auto fs = parse_double(number);
  if (!fs || !std::isfinite(*fs) || *fs <= 0 || !(rest.empty() || lower(rest) == "hz")) {
    throw InputError(where(
        file, line, fmt::format("fs '{}' is not a positive sample rate in Hz", shorten(value))));
  }
  return *fs;
}

// The sample rate given by "# fs:" and the line it is on.
struct FsLine {
  std::optional<double> fs;
  long line = 0;
};

// The columns of the header row.
struct Header {
  long line = 0;
  char delim = ',';
  std::vector<ColumnSpec> cols;
  int time_col = -1;
  // A trailing delimiter on the header allows one on every row (some exports end every line
  // with it); otherwise an empty last field is a missing value.
  bool trailing = false;
};

Header read_header(std::string_view line, long line_no, const std::string& name, bool have_fs) {
  Header h;
  h.line = line_no;
  h.delim = detect_delimiter(line);
  if (std::count(line.begin(), line.end(), '"') % 2 != 0) {
    throw InputError(where(name, line_no, "the header row has an unbalanced quote (\")"));
  }
  // Each raw field is unquoted or quoted whole: what is left of a quoted field followed by
  // more text (time,"" [m/s^2]) would become a name of stray quotes.
  bool quoted = false;
  size_t start = 0, field = 1;
  for (size_t i = 0; i <= line.size(); ++i) {
    if (i < line.size() && line[i] == '"') {
      quoted = !quoted;
      continue;
    }
    if (i < line.size() && (quoted || line[i] != h.delim)) continue;
    const std::string_view raw = trim(line.substr(start, i - start));
    if (raw.find('"') != std::string_view::npos &&
        !(raw.size() >= 2 && raw.front() == '"' && raw.back() == '"')) {
      throw InputError(where(name, line_no,
                             fmt::format("header field {} ({}) has a stray quote; quote whole "
                                         "fields (\"acc1 [g]\") or none",
                                         field, shorten(raw))));
    }
    start = i + 1;
    ++field;
  }
  std::vector<std::string> fields = CsvLineSplitter(h.delim).split(line);
  h.trailing = fields.size() > 1 && trim(fields.back()).empty();
  if (h.trailing) fields.pop_back();
  for (const std::string& f : fields) {
    h.cols.push_back(parse_header_field(f, name, h.line));
    if (h.cols.back().is_time) {
      if (h.time_col >= 0) throw InputError(where(name, h.line, "two 'time' columns"));
      h.time_col = static_cast<int>(h.cols.size()) - 1;
    }
  }
  std::unordered_set<std::string_view> seen;
  for (const ColumnSpec& c : h.cols) {
    if (!seen.insert(c.name).second) {
      throw InputError(
          where(name, h.line, fmt::format("two channels named '{}'", shorten(c.name))));
    }
  }
  std::vector<std::string> channels;
  for (size_t c = 0; c < h.cols.size(); ++c)
    if (static_cast<int>(c) != h.time_col) channels.push_back(h.cols[c].name);
  check_channel_names(channels, name, h.line);
  if (h.time_col < 0 && !have_fs) {
    throw InputError(where(name, h.line, "no 'time' column and no '# fs: <Hz>' line"));
  }
  if (h.cols.size() == (h.time_col >= 0 ? 1u : 0u)) {
    throw InputError(where(name, h.line, "no channel columns"));
  }
  return h;
}

// At most one row per remaining line (counted in 16 MB steps so `consumed` can drop them).
size_t max_rows_after(std::string_view text, size_t from,
                      const std::function<void(size_t)>& consumed) {
  size_t rows = 0;
  for (size_t at = from; at < text.size();) {
    const size_t chunk = std::min<size_t>(text.size() - at, size_t{1} << 24);
    rows += static_cast<size_t>(std::count(text.data() + at, text.data() + at + chunk, '\n'));
    at += chunk;
    consumed(at);
  }
  return rows + 1;  // a last line without a line end
}

// The data rows after the header: one column of values per header column.
class DataRows {
 public:
  DataRows(std::string_view text, const Header& header, const std::string& name, size_t data_start)
      : lines_(text), header_(header), name_(name), splitter_(header.delim) {
    lines_.seek(data_start, header.line);
    data_start_ = data_start;
  }

  // Reads every row into `values` (reserved by the caller); returns the row count.
  size_t read(std::vector<std::vector<double>>& values,
              const std::function<void(size_t)>& consumed) {
    const std::vector<ColumnSpec>& cols = header_.cols;
    std::string_view line;
    size_t n = 0;
    while (lines_.next(line)) {
      if (!is_row(line)) continue;
      if (header_.trailing && fields_.size() == cols.size() + 1 && trim(fields_.back()).empty())
        fields_.pop_back();
      if (fields_.size() != cols.size()) {
        throw InputError(
            where(name_, lines_.line_no(),
                  fmt::format("{} fields where the header has {}", fields_.size(), cols.size())));
      }
      for (size_t c = 0; c < cols.size(); ++c) values[c].push_back(value(c));
      ++n;
      if ((n & 0xffff) == 0) consumed(lines_.pos());
    }
    if (n < 2)
      throw InputError(
          where(name_, lines_.line_no(), fmt::format("{} data rows; need at least 2", n)));
    return n;
  }

  // The line of data row k, found again for a message (not kept: it would cost a column).
  long row_line(size_t k) {
    lines_.seek(data_start_, header_.line);
    std::string_view line;
    size_t row = 0;
    while (lines_.next(line)) {
      if (is_row(line) && row++ == k) break;
    }
    return lines_.line_no();
  }

 private:
  bool is_row(std::string_view l) { return !trim(l).empty() && splitter_.split(l, fields_); }

  double value(size_t c) const {
    const auto v = parse_double(fields_[c]);
    const std::string& col = header_.cols[c].name;
    if (!v) {
      throw InputError(where(name_, lines_.line_no(),
                             fmt::format("column '{}': '{}' is not a number", shorten(col),
                                         shorten(trim(fields_[c])))));
    }
    if (!std::isfinite(*v)) {
      throw InputError(where(name_, lines_.line_no(),
                             fmt::format("column '{}': {} sample (NaN and Inf "
                                         "are not allowed)",
                                         shorten(col), shorten(trim(fields_[c])))));
    }
    return *v;
  }

  TextLines lines_;
  const Header& header_;
  const std::string& name_;
  CsvLineSplitter splitter_;
  std::vector<std::string> fields_;
  size_t data_start_ = 0;
};

// Checks that the time column (in seconds) is uniform and sets rec.fs and rec.t0 from it.
void time_base_from_column(Record& rec, const std::vector<double>& t, const FsLine& fs_meta,
                           DataRows& rows) {
  const std::string& name = rec.source;
  const size_t n = t.size();
  for (size_t k = 1; k < n; ++k) {
    if (!(t[k] > t[k - 1])) {
      throw InputError(where(name, rows.row_line(k),
                             fmt::format("time {} does not increase (previous"
                                         " {})",
                                         t[k], t[k - 1])));
    }
  }
  // A step far from the typical one (a dropped or repeated sample) is named where it occurs.
  std::vector<double> steps(n - 1);
  for (size_t k = 1; k < n; ++k) steps[k - 1] = t[k] - t[k - 1];
  std::nth_element(steps.begin(), steps.begin() + (n - 1) / 2, steps.end());
  const double typical = steps[(n - 1) / 2];
  for (size_t k = 1; k < n; ++k) {
    if (std::abs(t[k] - t[k - 1] - typical) > 0.25 * typical) {
      throw InputError(where(name, rows.row_line(k),
                             fmt::format("time step is not uniform: {} s after {} s steps",
                                         t[k] - t[k - 1], typical)));
    }
  }
  const double dt = (t[n - 1] - t[0]) / static_cast<double>(n - 1);
  // Printed times are rounded; a tenth of a step is far above rounding and far
  // below a missing or repeated sample.
  for (size_t k = 0; k < n; ++k) {
    const double expected = t[0] + static_cast<double>(k) * dt;
    if (std::abs(t[k] - expected) > 0.1 * dt) {
      throw InputError(where(name, rows.row_line(k),
                             fmt::format("time step is not uniform: t = {} where {} was expected "
                                         "(dt = {})",
                                         t[k], expected, dt)));
    }
  }
  rec.fs = 1.0 / dt;
  rec.t0 = t[0];
  if (fs_meta.fs && std::abs(*fs_meta.fs - rec.fs) > 1e-3 * *fs_meta.fs) {
    throw InputError(where(name, fs_meta.line,
                           fmt::format("fs {} Hz disagrees with the time column "
                                       "({} Hz)",
                                       *fs_meta.fs, rec.fs)));
  }
}

// Sets rec.fs and rec.t0 from the "# fs:" and "# t0:" lines.
void time_base_from_metadata(Record& rec, double fs) {
  rec.fs = fs;
  rec.t0 = 0.0;
  if (auto it = rec.metadata.find("t0"); it != rec.metadata.end()) {
    const auto t0 = parse_double(it->second);
    if (!t0 || !std::isfinite(*t0)) throw InputError(where(rec.source, 0, "t0 is not a number"));
    rec.t0 = *t0;
  }
}

// Moves the value columns into SI channels, one at a time: peak = samples + 1 column.
void add_channels(Record& rec, const Header& header, std::vector<std::vector<double>>& values,
                  size_t n) {
  for (size_t c = 0; c < header.cols.size(); ++c) {
    if (static_cast<int>(c) == header.time_col) continue;
    const ColumnSpec& col = header.cols[c];
    Channel ch;
    ch.name = col.name;
    ch.unit = col.unit_text;
    if (col.unit) ch.quantity = col.unit->quantity;
    const double scale = col.unit ? col.unit->to_si : 1.0;
    ch.samples =
        Eigen::Map<const Eigen::VectorXd>(values[c].data(), static_cast<Eigen::Index>(n)) * scale;
    std::vector<double>().swap(values[c]);
    rec.channels.push_back(std::move(ch));
  }
}

}  // namespace

// The parser behind parse_csv and read_csv; `consumed(pos)` says the text before `pos` may be
// dropped from memory (read_csv's mapping reads such pages back from the file if needed).
Record parse_csv_text(std::string_view text, const std::string& name,
                      const std::function<void(size_t)>& consumed) {
  if (trim(text).empty()) throw InputError(where(name, 0, "empty file"));
  if (looks_binary(text)) throw InputError(where(name, 0, "binary data, not a CSV text file"));
  text = strip_bom(text);

  Record rec;
  rec.source = name;
  FsLine fs_meta;
  TextLines lines(text);
  const std::string_view header_row =
      read_preamble(lines, name, [&](const std::string& key, const std::string& value) {
        // The time base is stated once: a second "# fs:" or "# t0:" line is refused, not left
        // to silently win over the first.
        if ((key == "fs" || key == "t0") && rec.metadata.count(key)) {
          throw InputError(where(name, lines.line_no(),
                                 fmt::format("a second '# {}:' line ({}); state the time base once",
                                             key, shorten(value))));
        }
        rec.metadata[key] = value;
        if (key == "fs") fs_meta = {parse_fs(value, name, lines.line_no()), lines.line_no()};
      });
  const Header header = read_header(header_row, lines.line_no(), name, fs_meta.fs.has_value());

  // Price the samples before allocating: 8 bytes a value, reserved exactly so the columns
  // never grow by doubling.
  const size_t data_start = lines.pos();
  const size_t max_rows = max_rows_after(text, data_start, consumed);
  const size_t width = header.cols.size();
  check_memory(fmt::format("{}: {} rows x {} columns", name, max_rows, width),
               8.0 * static_cast<double>(max_rows) * static_cast<double>(width));
  std::vector<std::vector<double>> values(width);
  for (auto& v : values) v.reserve(max_rows);
  DataRows rows(text, header, name, data_start);
  const size_t n = rows.read(values, consumed);

  if (header.time_col >= 0) {
    std::vector<double>& t = values[static_cast<size_t>(header.time_col)];
    for (double& v : t) v *= header.cols[static_cast<size_t>(header.time_col)].time_scale;
    time_base_from_column(rec, t, fs_meta, rows);
  } else {
    time_base_from_metadata(rec, *fs_meta.fs);
  }
  add_channels(rec, header, values, n);
  return rec;
}

Record parse_csv(std::string_view text, const std::string& name) {
  return parse_csv_text(text, name, [](size_t) {});
}

Record read_csv(const std::filesystem::path& path) {
  // Mapped rather than read into a string: pages already parsed are dropped as the parser
  // moves on, so the text never costs memory on top of the samples.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(where(path.string(), 0, "cannot open file"));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw InputError(where(path.string(), 0, "not a regular file"));
  }
  const auto size = static_cast<size_t>(st.st_size);
  if (size == 0) {
    ::close(fd);
    return parse_csv("", path.string());
  }
  void* map = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
  const int error = errno;
  ::close(fd);
  // Out of address space (ulimit -v) mapping it is running out of memory: std::bad_alloc, which
  // the commands turn into their one line naming the file.
  if (map == MAP_FAILED && error == ENOMEM) throw std::bad_alloc();
  if (map == MAP_FAILED) throw InputError(where(path.string(), 0, "cannot read file"));
  struct Unmap {
    void* p;
    size_t n;
    ~Unmap() { ::munmap(p, n); }
  } unmap{map, size};
  ::madvise(map, size, MADV_SEQUENTIAL);
  const long page = ::sysconf(_SC_PAGESIZE);
  size_t dropped = 0;
  const auto consumed = [&](size_t pos) {
    const size_t upto = pos / static_cast<size_t>(page) * static_cast<size_t>(page);
    if (upto < dropped) dropped = 0;  // the parser went back for its next pass
    if (upto > dropped + (size_t{1} << 24)) {
      ::madvise(static_cast<char*>(map) + dropped, upto - dropped, MADV_DONTNEED);
      dropped = upto;
    }
  };
  return parse_csv_text(std::string_view(static_cast<const char*>(map), size), path.string(),
                        consumed);
}

}  // namespace jointlab::data
