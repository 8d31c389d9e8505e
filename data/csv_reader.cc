#include "jointlab/data/csv_reader.h"

#include "jointlab/core/text.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <functional>
#include <optional>
#include <unordered_set>
#include <vector>

#include <csv.h>
#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/memory.h"

namespace jointlab::data {

const Channel* Record::find(const std::string& name) const {
  for (const Channel& c : channels) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

namespace {

// Parses a whole field as a double; nullopt if anything but a number is there.
std::optional<double> to_double(std::string_view s) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

// libcsv hands fields and row ends to C callbacks; this collects one row.
struct RowCollector {
  std::vector<std::string> fields;
  bool row_done = false;
  static void on_field(void* data, size_t len, void* self) {
    auto* r = static_cast<RowCollector*>(self);
    r->fields.emplace_back(data ? static_cast<const char*>(data) : "", data ? len : 0);
  }
  static void on_row(int, void* self) { static_cast<RowCollector*>(self)->row_done = true; }
};

// Splits one line into fields with libcsv (quotes handled by the library).
class LineSplitter {
 public:
  explicit LineSplitter(char delim) {
    csv_init(&parser_, CSV_APPEND_NULL);
    csv_set_delim(&parser_, static_cast<unsigned char>(delim));
  }
  ~LineSplitter() { csv_free(&parser_); }
  LineSplitter(const LineSplitter&) = delete;
  LineSplitter& operator=(const LineSplitter&) = delete;

  // Returns the fields of `line`; false if the line holds no row (blank).
  bool split(std::string_view line, std::vector<std::string>& out) {
    row_.fields.clear();
    row_.row_done = false;
    csv_parse(&parser_, line.data(), line.size(), RowCollector::on_field, RowCollector::on_row,
              &row_);
    csv_fini(&parser_, RowCollector::on_field, RowCollector::on_row, &row_);
    out.swap(row_.fields);
    return row_.row_done;
  }

 private:
  csv_parser parser_{};
  RowCollector row_;
};

char detect_delimiter(std::string_view header) {
  const char candidates[] = {',', ';', '\t'};
  char best = ',';
  long best_count = 0;
  for (char c : candidates) {
    const long n = std::count(header.begin(), header.end(), c);
    if (n > best_count) {
      best = c;
      best_count = n;
    }
  }
  return best;
}

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
  std::string_view field = trim(raw);
  ColumnSpec spec;
  std::string_view name = field;
  const auto open = field.find('[');
  if (open != std::string_view::npos) {
    const auto close = field.find(']', open);
    if (close == std::string_view::npos || !trim(field.substr(close + 1)).empty()) {
      throw InputError(where(file, line,
                             fmt::format("header '{}': unit must be written as "
                                         "'name [unit]'",
                                         shorten(field))));
    }
    name = trim(field.substr(0, open));
    spec.unit_text = std::string(trim(field.substr(open + 1, close - open - 1)));
  }
  if (name.empty())
    throw InputError(where(file, line, fmt::format("header '{}' has no name", shorten(field))));
  spec.name = std::string(name);
  if (lower(name) == "time") {
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
      throw InputError(where(file, line,
                             fmt::format("column '{}': unknown unit '{}' (known: m, "
                                         "mm, um, in, m/s, mm/s, in/s, m/s^2, mm/s^2, "
                                         "g, mg, N, kN, lbf)",
                                         shorten(spec.name), shorten(spec.unit_text))));
    }
  }
  return spec;
}

double parse_fs(const std::string& value, const std::string& file, long line) {
  std::string_view v = trim(value);
  const auto space = v.find_first_of(" \t");
  std::string_view number = v.substr(0, space);
  std::string_view rest = space == std::string_view::npos ? "" : trim(v.substr(space));
  const auto fs = to_double(number);
  if (!fs || !std::isfinite(*fs) || *fs <= 0 || !(rest.empty() || lower(rest) == "hz")) {
    throw InputError(where(
        file, line, fmt::format("fs '{}' is not a positive sample rate in Hz", shorten(value))));
  }
  return *fs;
}

}  // namespace

// The parser behind parse_csv and read_csv; `consumed(pos)` says the text before `pos` may be
// dropped from memory (read_csv's mapping reads such pages back from the file if needed).
Record parse_csv_text(std::string_view text, const std::string& name,
                      const std::function<void(size_t)>& consumed) {
  if (trim(text).empty()) throw InputError(where(name, 0, "empty file"));
  if (looks_binary(text)) throw InputError(where(name, 0, "binary data, not a CSV text file"));
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 BOM

  Record rec;
  rec.source = name;
  std::optional<double> fs_meta;
  long fs_line = 0;

  // Walk the text line by line; `line_no` is 1-based as editors show it.
  size_t pos = 0;
  long line_no = 0;
  auto next_line = [&](std::string_view& line) {
    if (pos >= text.size()) return false;
    const size_t end = text.find('\n', pos);
    const size_t stop = end == std::string_view::npos ? text.size() : end;
    line = text.substr(pos, stop - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = stop + 1;
    ++line_no;
    return true;
  };

  // Metadata comments and blank lines before the header.
  std::string_view line;
  bool have_header = false;
  while (next_line(line)) {
    const std::string_view t = trim(line);
    if (t.empty()) continue;
    if (t.front() == '#') {
      const std::string_view body = trim(t.substr(1));
      const auto colon = body.find(':');
      if (colon != std::string_view::npos) {
        const std::string key = lower(trim(body.substr(0, colon)));
        const std::string value(trim(body.substr(colon + 1)));
        if (!key.empty()) {
          rec.metadata[key] = value;
          if (key == "fs") {
            fs_meta = parse_fs(value, name, line_no);
            fs_line = line_no;
          }
        }
      }
      continue;
    }
    have_header = true;
    break;
  }
  if (!have_header) throw InputError(where(name, line_no, "no header row"));

  const long header_line = line_no;
  const char delim = detect_delimiter(line);
  LineSplitter splitter(delim);
  std::vector<std::string> fields;
  splitter.split(line, fields);
  // A trailing delimiter on the header allows one on every row (some exports end every line
  // with it); otherwise an empty last field is a missing value.
  const bool trailing = fields.size() > 1 && trim(fields.back()).empty();
  if (trailing) fields.pop_back();

  std::vector<ColumnSpec> cols;
  int time_col = -1;
  for (const std::string& f : fields) {
    cols.push_back(parse_header_field(f, name, header_line));
    if (cols.back().is_time) {
      if (time_col >= 0) throw InputError(where(name, header_line, "two 'time' columns"));
      time_col = static_cast<int>(cols.size()) - 1;
    }
  }
  std::unordered_set<std::string_view> seen;
  for (const ColumnSpec& c : cols) {
    if (!seen.insert(c.name).second) {
      throw InputError(
          where(name, header_line, fmt::format("two channels named '{}'", shorten(c.name))));
    }
  }
  if (time_col < 0 && !fs_meta) {
    throw InputError(where(name, header_line, "no 'time' column and no '# fs: <Hz>' line"));
  }
  if (cols.size() == (time_col >= 0 ? 1u : 0u)) {
    throw InputError(where(name, header_line, "no channel columns"));
  }

  // Price the samples before allocating: at most one row per remaining line, 8 bytes a
  // value, reserved exactly so the columns never grow by doubling.
  const size_t data_start = pos;
  size_t max_rows = 0;
  for (size_t at = data_start; at < text.size();) {
    const size_t chunk = std::min<size_t>(text.size() - at, size_t{1} << 24);
    max_rows += static_cast<size_t>(std::count(text.data() + at, text.data() + at + chunk, '\n'));
    at += chunk;
    consumed(at);
  }
  ++max_rows;  // a last line without a line end
  check_memory(fmt::format("{}: {} rows x {} columns", name, max_rows, cols.size()),
               8.0 * static_cast<double>(max_rows) * static_cast<double>(cols.size()));
  std::vector<std::vector<double>> values(cols.size());
  for (auto& v : values) v.reserve(max_rows);
  const auto is_row = [&](std::string_view l) {
    return !trim(l).empty() && splitter.split(l, fields);
  };
  size_t n = 0;
  while (next_line(line)) {
    if (!is_row(line)) continue;
    if (trailing && fields.size() == cols.size() + 1 && trim(fields.back()).empty())
      fields.pop_back();
    if (fields.size() != cols.size()) {
      throw InputError(
          where(name, line_no,
                fmt::format("{} fields where the header has {}", fields.size(), cols.size())));
    }
    for (size_t c = 0; c < cols.size(); ++c) {
      const auto v = to_double(fields[c]);
      if (!v) {
        throw InputError(where(name, line_no,
                               fmt::format("column '{}': '{}' is not a number",
                                           shorten(cols[c].name), shorten(trim(fields[c])))));
      }
      if (!std::isfinite(*v)) {
        throw InputError(where(name, line_no,
                               fmt::format("column '{}': {} sample (NaN and Inf "
                                           "are not allowed)",
                                           shorten(cols[c].name), shorten(trim(fields[c])))));
      }
      values[c].push_back(*v);
    }
    ++n;
    if ((n & 0xffff) == 0) consumed(pos);
  }
  if (n < 2)
    throw InputError(where(name, line_no, fmt::format("{} data rows; need at least 2", n)));
  // The line of data row k, found again for a message (not kept: it would cost a column).
  const auto row_line = [&](size_t k) {
    pos = data_start;
    line_no = header_line;
    size_t row = 0;
    while (next_line(line)) {
      if (is_row(line) && row++ == k) break;
    }
    return line_no;
  };

  if (time_col >= 0) {
    std::vector<double>& t = values[time_col];
    for (double& v : t) v *= cols[time_col].time_scale;
    for (size_t k = 1; k < n; ++k) {
      if (!(t[k] > t[k - 1])) {
        throw InputError(where(name, row_line(k),
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
        throw InputError(where(name, row_line(k),
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
        throw InputError(where(name, row_line(k),
                               fmt::format("time step is not uniform: t = {} where {} was expected "
                                           "(dt = {})",
                                           t[k], expected, dt)));
      }
    }
    rec.fs = 1.0 / dt;
    rec.t0 = t[0];
    if (fs_meta && std::abs(*fs_meta - rec.fs) > 1e-3 * *fs_meta) {
      throw InputError(where(name, fs_line,
                             fmt::format("fs {} Hz disagrees with the time column "
                                         "({} Hz)",
                                         *fs_meta, rec.fs)));
    }
  } else {
    rec.fs = *fs_meta;
    rec.t0 = 0.0;
    if (auto it = rec.metadata.find("t0"); it != rec.metadata.end()) {
      const auto t0 = to_double(it->second);
      if (!t0 || !std::isfinite(*t0)) throw InputError(where(name, 0, "t0 is not a number"));
      rec.t0 = *t0;
    }
  }

  for (size_t c = 0; c < cols.size(); ++c) {
    if (static_cast<int>(c) == time_col) continue;
    Channel ch;
    ch.name = cols[c].name;
    ch.unit = cols[c].unit_text;
    if (cols[c].unit) ch.quantity = cols[c].unit->quantity;
    const double scale = cols[c].unit ? cols[c].unit->to_si : 1.0;
    ch.samples =
        Eigen::Map<const Eigen::VectorXd>(values[c].data(), static_cast<Eigen::Index>(n)) * scale;
    std::vector<double>().swap(values[c]);  // one column at a time: peak = samples + 1 column
    rec.channels.push_back(std::move(ch));
  }
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
  ::close(fd);
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
