// Building blocks of the CSV readers: a line cursor, libcsv field splitting, number parsing
// and the "# key: value" lines before a header row.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace jointlab::data {

/// A whole field as a double (surrounding blanks and a leading '+' allowed); nullopt otherwise.
std::optional<double> parse_double(std::string_view field);

/// The delimiter of a header row: whichever of ',', ';' and tab occurs most (',' if none).
char detect_delimiter(std::string_view header);

/// The delimiter of a text's header row, its first line neither blank nor a '#' comment
/// (detect_delimiter; ',' if there is none).
char header_delimiter(std::string_view text);

/// `text` without a leading UTF-8 byte-order mark.
std::string_view strip_bom(std::string_view text);

/// Walks a text line by line: 1-based line numbers as editors show them, the CR of CRLF dropped.
class TextLines {
 public:
  /// A cursor before the first line of `text` (which must outlive the cursor).
  explicit TextLines(std::string_view text) : text_(text) {}
  /// Sets `line` to the next line; false at the end of the text.
  bool next(std::string_view& line);
  /// The number of the line `next` gave last (0 before the first).
  long line_no() const { return line_no_; }
  /// The offset of the text after the line `next` gave last.
  size_t pos() const { return pos_; }
  /// Moves the cursor back (or on) to offset `pos`, after line `line_no`.
  void seek(size_t pos, long line_no) { pos_ = pos, line_no_ = line_no; }
  /// The whole text.
  std::string_view text() const { return text_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  long line_no_ = 0;
};

/// Splits single CSV lines into fields with libcsv (quotes handled by the library).
class CsvLineSplitter {
 public:
  /// A splitter for fields separated by `delim`.
  explicit CsvLineSplitter(char delim = ',');
  ~CsvLineSplitter();
  CsvLineSplitter(const CsvLineSplitter&) = delete;
  CsvLineSplitter& operator=(const CsvLineSplitter&) = delete;
  /// Puts the fields of `line` in `out`; false if the line holds no row (blank).
  bool split(std::string_view line, std::vector<std::string>& out);
  /// The fields of `line` (none for a blank line).
  std::vector<std::string> split(std::string_view line);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Reads the blank and "# key: value" lines before a header row, handing each entry to
/// `on_entry` (key trimmed and lower-cased, value trimmed; `lines.line_no()` is its line);
/// returns the header row; InputError "file:line: no header row" if none.
std::string_view read_preamble(
    TextLines& lines, const std::string& file,
    const std::function<void(const std::string& key, const std::string& value)>& on_entry);

/// A header field "name [unit]" as its trimmed name and unit (empty when none); InputError
/// naming `file` and `line` when the brackets are malformed.
std::pair<std::string, std::string> split_name_unit(std::string_view field, const std::string& file,
                                                    long line);

/// A name ending in square brackets, "acc1 [g]", as the trimmed name before the first '[' and the
/// trimmed text inside ("acc1", "g"); none where it has no '[' or anything but blanks follows the
/// ']' that closes it.
std::optional<std::pair<std::string, std::string>> split_square_brackets(std::string_view name);

/// A name ending in round brackets, "acc1 (g)", as the trimmed name before them and the trimmed
/// text inside ("acc1", "g"); none where the name does not end so.
std::optional<std::pair<std::string, std::string>> split_round_brackets(std::string_view name);

/// Calls `on_line(cells, line)` for each line of a small CSV text that is neither blank nor a
/// '#' comment, its cells split at `delim` (libcsv quoting) and trimmed.
void for_each_csv_line(
    std::string_view text,
    const std::function<void(const std::vector<std::string>& cells, long line)>& on_line,
    char delim = ',');

/// Reads the small CSV file `path` as a header and its rows: `on_header(cells, line)` for its
/// first line that is neither blank nor a '#' comment, `on_row(cells, line)` for each later one,
/// after checking it has the header's width; returns whether a header was seen. With `detect` the
/// cells are split at whichever of ',', ';' and tab the header holds most (detect_delimiter), else
/// at ','. InputError "FILE: cannot open the <what>", and "FILE:LINE: k cells where the header has
/// n" (saying how to write a complex cell where an unquoted "(re,im)" split at its comma).
bool for_each_csv_row(
    const std::filesystem::path& path, const std::string& what,
    const std::function<void(const std::vector<std::string>& cells, long line)>& on_header,
    const std::function<void(const std::vector<std::string>& cells, long line)>& on_row,
    bool detect = false);

/// The whole content of a file; nullopt if it cannot be opened or read; InputError (as
/// require_regular_file) for what is not a regular file.
std::optional<std::string> read_text_file(const std::filesystem::path& path);

/// InputError "PATH: is a directory, not a file" (a FIFO, a device, a socket likewise) when
/// `path` exists and is not a regular file, before anything is read: a FIFO would block,
/// /dev/zero would fill memory, a directory would read as empty. A missing path passes (the
/// reader's own "cannot open" follows). First, InputError (require_committed, output_stage.h)
/// when `path` is an output that a killed commit may have left half old, half new.
void require_regular_file(const std::filesystem::path& path);

}  // namespace jointlab::data
