#include "jointlab/data/csv_lines.h"

#include <algorithm>
#include <charconv>
#include <fstream>
#include <sstream>

#include <csv.h>
#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/data/output_stage.h"

namespace jointlab::data {

std::optional<double> parse_double(std::string_view s) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

char detect_delimiter(std::string_view header) {
  char best = ',';
  long best_count = 0;
  for (char c : {',', ';', '\t'}) {
    const long n = std::count(header.begin(), header.end(), c);
    if (n > best_count) best = c, best_count = n;
  }
  return best;
}

char header_delimiter(std::string_view text) {
  TextLines lines(strip_bom(text));
  for (std::string_view line; lines.next(line);)
    if (const std::string_view t = trim(line); !t.empty() && t.front() != '#')
      return detect_delimiter(t);
  return ',';
}

std::string_view strip_bom(std::string_view text) {
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  return text;
}

bool TextLines::next(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  const size_t end = text_.find('\n', pos_);
  const size_t stop = end == std::string_view::npos ? text_.size() : end;
  line = text_.substr(pos_, stop - pos_);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos_ = stop + 1;
  ++line_no_;
  return true;
}

// libcsv hands fields and row ends to C callbacks; this collects one row.
struct CsvLineSplitter::Impl {
  csv_parser parser{};
  std::vector<std::string> fields;
  bool row_done = false;
  static void on_field(void* data, size_t len, void* self) {
    static_cast<Impl*>(self)->fields.emplace_back(data ? static_cast<const char*>(data) : "",
                                                  data ? len : 0);
  }
  static void on_row(int, void* self) { static_cast<Impl*>(self)->row_done = true; }
};

CsvLineSplitter::CsvLineSplitter(char delim) : impl_(std::make_unique<Impl>()) {
  csv_init(&impl_->parser, CSV_APPEND_NULL);
  csv_set_delim(&impl_->parser, static_cast<unsigned char>(delim));
}

CsvLineSplitter::~CsvLineSplitter() { csv_free(&impl_->parser); }

bool CsvLineSplitter::split(std::string_view line, std::vector<std::string>& out) {
  Impl& p = *impl_;
  p.fields.clear();
  p.row_done = false;
  csv_parse(&p.parser, line.data(), line.size(), Impl::on_field, Impl::on_row, &p);
  csv_fini(&p.parser, Impl::on_field, Impl::on_row, &p);
  out.swap(p.fields);
  return p.row_done;
}

std::vector<std::string> CsvLineSplitter::split(std::string_view line) {
  std::vector<std::string> out;
  split(line, out);
  return out;
}

std::string_view read_preamble(
    TextLines& lines, const std::string& file,
    const std::function<void(const std::string& key, const std::string& value)>& on_entry) {
  std::string_view line;
  while (lines.next(line)) {
    const std::string_view t = trim(line);
    if (t.empty()) continue;
    if (t.front() != '#') return line;
    const std::string_view body = trim(t.substr(1));
    const auto colon = body.find(':');
    if (colon == std::string_view::npos) continue;
    const std::string key = lower(trim(body.substr(0, colon)));
    if (!key.empty()) on_entry(key, std::string(trim(body.substr(colon + 1))));
  }
  throw InputError(where(file, lines.line_no(), "no header row"));
}

std::pair<std::string, std::string> split_name_unit(std::string_view field, const std::string& file,
                                                    long line) {
  field = trim(field);
  if (field.find('[') == std::string_view::npos) return {std::string(field), ""};
  if (auto split = split_square_brackets(field)) return *std::move(split);
  throw InputError(
      where(file, line,
            fmt::format("header '{}': unit must be written as 'name [unit]'", shorten(field))));
}

std::optional<std::pair<std::string, std::string>> split_square_brackets(std::string_view name) {
  const auto open = name.find('[');
  if (open == std::string_view::npos) return std::nullopt;
  const auto close = name.find(']', open);
  if (close == std::string_view::npos || !trim(name.substr(close + 1)).empty()) return std::nullopt;
  return std::pair{std::string(trim(name.substr(0, open))),
                   std::string(trim(name.substr(open + 1, close - open - 1)))};
}

std::optional<std::pair<std::string, std::string>> split_round_brackets(std::string_view name) {
  const auto open = name.rfind('(');
  if (open == std::string_view::npos || name.empty() || name.back() != ')') return std::nullopt;
  return std::pair{std::string(trim(name.substr(0, open))),
                   std::string(trim(name.substr(open + 1, name.size() - open - 2)))};
}

void for_each_csv_line(
    std::string_view text,
    const std::function<void(const std::vector<std::string>& cells, long line)>& on_line,
    char delim) {
  TextLines lines(strip_bom(text));
  CsvLineSplitter splitter(delim);
  std::vector<std::string> cells;
  std::string_view line;
  while (lines.next(line)) {
    const std::string_view t = trim(line);
    if (t.empty() || t.front() == '#') continue;
    splitter.split(t, cells);
    for (std::string& c : cells) c = std::string(trim(c));
    on_line(cells, lines.line_no());
  }
}

bool for_each_csv_row(
    const std::filesystem::path& path, const std::string& what,
    const std::function<void(const std::vector<std::string>& cells, long line)>& on_header,
    const std::function<void(const std::vector<std::string>& cells, long line)>& on_row,
    bool detect) {
  const std::string name = path.string();
  const auto text = read_text_file(path);
  if (!text) throw InputError(fmt::format("{}: cannot open the {}", name, what));
  const char delim = detect ? header_delimiter(*text) : ',';
  bool header = false;
  size_t width = 0;
  for_each_csv_line(
      *text,
      [&](const std::vector<std::string>& cells, long n) {
        if (!header) {
          on_header(cells, n);
          header = true;
          width = cells.size();
          return;
        }
        if (cells.size() != width) {
          // "(0.1,0.2)" unquoted in a comma-separated file is split in two.
          const bool split_pair =
              delim == ',' && std::any_of(cells.begin(), cells.end(), [](const std::string& c) {
                return !c.empty() && c.front() == '(' && c.back() != ')';
              });
          throw InputError(where(
              name, n,
              fmt::format("{} cells where the header has {}{}", cells.size(), width,
                          split_pair ? " (a complex cell written (re,im) splits at its comma in "
                                       "a comma-separated file: quote it, \"(0.1,0.2)\", or "
                                       "write 0.1+0.2i)"
                                     : "")));
        }
        on_row(cells, n);
      },
      delim);
  return header;
}

void require_regular_file(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  // Every reader comes here first: an output a killed commit may have left mixed is refused.
  require_committed(path);
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);  // follows symbolic links
  if (ec || !fs::exists(st) || fs::is_regular_file(st)) return;
  const char* kind = fs::is_directory(st)        ? "a directory"
                     : fs::is_fifo(st)           ? "a FIFO (named pipe)"
                     : fs::is_character_file(st) ? "a character device"
                     : fs::is_block_file(st)     ? "a block device"
                     : fs::is_socket(st)         ? "a socket"
                                                 : "not a regular file";
  throw InputError(where(path.string(), 0, fmt::format("is {}, not a file; give a file", kind)));
}

std::optional<std::string> read_text_file(const std::filesystem::path& path) {
  require_regular_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return std::nullopt;
  return std::move(ss).str();
}

}  // namespace jointlab::data
