#include "jointlab/data/matrix_market.h"

#include "jointlab/core/text.h"

#include <algorithm>
#include <cassert>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/memory.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/data/csv_lines.h"

namespace jointlab::data {
namespace {

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> tokens;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

// Reads a file line by line, skipping '%' comments and blank lines after the banner,
// and turns any defect into an InputError naming the file and line.
class Reader {
 public:
  explicit Reader(const std::filesystem::path& path) : path_(path.string()), in_(path) {
    if (!in_) throw InputError(where(path_, 0, "cannot open Matrix Market file"));
    std::error_code ec;
    bytes_ = std::filesystem::file_size(path, ec);
    if (ec) bytes_ = 0;
  }

  // Size of the file in bytes (bounds how many entries it can hold).
  std::uintmax_t bytes() const { return bytes_; }

  [[noreturn]] void fail(const std::string& message) const {
    throw InputError(where(path_, line_no_, message));
  }

  bool raw_line(std::string& line) {
    if (!std::getline(in_, line)) return false;
    ++line_no_;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  }

  // Next non-comment, non-blank line split into tokens; empty at end of file.
  std::vector<std::string_view> next() {
    while (raw_line(current_)) {
      const auto tokens = split(current_);
      if (tokens.empty() || tokens.front().front() == '%') continue;
      return tokens;
    }
    return {};
  }

  long index(std::string_view token, const char* what) const {
    long value = 0;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || ptr != token.data() + token.size()) {
      fail(fmt::format("{} '{}' is not an integer", what, shorten(token)));
    }
    return value;
  }

  double number(std::string_view token) const {
    // from_chars rejects a leading '+', which some writers emit.
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);
    double value = 0;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || ptr != token.data() + token.size()) {
      fail(fmt::format("value '{}' is not a number", shorten(token)));
    }
    if (!std::isfinite(value)) fail(fmt::format("value '{}' is not finite", shorten(token)));
    return value;
  }

  long line_no() const { return line_no_; }

 private:
  std::string path_;
  std::ifstream in_;
  std::string current_;
  std::uintmax_t bytes_ = 0;
  long line_no_ = 0;
};

}  // namespace

Eigen::SparseMatrix<double> read_matrix_market(const std::filesystem::path& path,
                                               long max_dimension) {
  require_regular_file(path);
  Reader reader(path);
  std::string banner;
  if (!reader.raw_line(banner)) reader.fail("empty file, expected a %%MatrixMarket banner");
  const auto head = split(banner);
  if (head.size() != 5 || lower(head[0]) != "%%matrixmarket") {
    reader.fail(
        "expected banner '%%MatrixMarket matrix <coordinate|array> real <general|symmetric>'");
  }
  if (lower(head[1]) != "matrix")
    reader.fail(fmt::format("object '{}' is not 'matrix'", shorten(head[1])));
  const std::string format = lower(head[2]);
  const std::string field = lower(head[3]);
  const std::string symmetry = lower(head[4]);
  if (format != "coordinate" && format != "array") {
    reader.fail(fmt::format("format '{}' is neither 'coordinate' nor 'array'", shorten(head[2])));
  }
  if (field != "real" && field != "double" && field != "integer") {
    reader.fail(fmt::format("field '{}' is not supported (only real matrices)", shorten(head[3])));
  }
  if (symmetry != "general" && symmetry != "symmetric") {
    reader.fail(
        fmt::format("symmetry '{}' is not supported (general or symmetric)", shorten(head[4])));
  }
  const bool symmetric = symmetry == "symmetric";
  const bool coordinate = format == "coordinate";

  auto size = reader.next();
  if (size.empty()) reader.fail("missing size line");
  if (size.size() != (coordinate ? 3u : 2u)) {
    reader.fail(coordinate ? "size line must be 'rows cols entries'"
                           : "size line must be 'rows cols'");
  }
  const long rows = reader.index(size[0], "row count");
  const long cols = reader.index(size[1], "column count");
  if (rows <= 0 || cols <= 0) reader.fail("matrix dimensions must be positive");
  if (symmetric && rows != cols) {
    reader.fail(fmt::format("symmetric matrix must be square, got {} x {}", rows, cols));
  }
  // Sizes are checked against what they cost before anything is allocated: the dimensions
  // against the caller's limit (and Eigen's int indices), the entries against what the
  // file's bytes can hold ("i j v" is at least 6 bytes, an array value 2) and the memory.
  const long dim_limit = std::min<long>(max_dimension, std::numeric_limits<int>::max() - 1);
  if (rows > dim_limit || cols > dim_limit) {
    reader.fail(fmt::format("size {} x {} exceeds the limit of {} rows and columns", rows, cols,
                            dim_limit));
  }
  const double room = static_cast<double>(reader.bytes());

  std::vector<Eigen::Triplet<double>> triplets;
  auto add = [&](long i, long j, double v) {  // 0-based
    triplets.emplace_back(static_cast<int>(i), static_cast<int>(j), v);
    if (symmetric && i != j) triplets.emplace_back(static_cast<int>(j), static_cast<int>(i), v);
  };

  if (coordinate) {
    const long entries = reader.index(size[2], "entry count");
    if (entries < 0) reader.fail("entry count must not be negative");
    if (static_cast<double>(entries) > room / 6) {
      reader.fail(fmt::format("size line declares {} entries; the file's {} bytes hold at most {}",
                              entries, reader.bytes(), static_cast<long>(room / 6)));
    }
    check_memory(fmt::format("{}: {} x {} with {} entries", path.string(), rows, cols, entries),
                 4.0 * cols + (symmetric ? 2 : 1) * 28.0 * static_cast<double>(entries));
    triplets.reserve(static_cast<size_t>(symmetric ? 2 * entries : entries));
    for (long k = 0; k < entries; ++k) {
      const auto t = reader.next();
      if (t.empty()) {
        reader.fail(fmt::format("file ends after {} of {} entries", k, entries));
      }
      if (t.size() != 3) reader.fail("entry line must be 'row col value'");
      const long i = reader.index(t[0], "row index");
      const long j = reader.index(t[1], "column index");
      if (i < 1 || i > rows) reader.fail(fmt::format("row index {} out of range 1..{}", i, rows));
      if (j < 1 || j > cols) {
        reader.fail(fmt::format("column index {} out of range 1..{}", j, cols));
      }
      if (symmetric && i < j) {
        reader.fail(
            fmt::format("entry ({}, {}) above the diagonal in a symmetric file "
                        "(only the lower triangle is stored)",
                        i, j));
      }
      add(i - 1, j - 1, reader.number(t[2]));
    }
  } else {
    const double values = symmetric ? 0.5 * static_cast<double>(rows) * (rows + 1.0)
                                    : static_cast<double>(rows) * static_cast<double>(cols);
    if (values > room / 2) {
      reader.fail(
          fmt::format("size {} x {} needs {:.0f} values; the file's {} bytes hold at most {}", rows,
                      cols, values, reader.bytes(), static_cast<long>(room / 2)));
    }
    for (long j = 0; j < cols; ++j) {
      for (long i = symmetric ? j : 0; i < rows; ++i) {
        const auto t = reader.next();
        if (t.empty()) reader.fail("file ends before every array value is read");
        if (t.size() != 1) reader.fail("array format has one value per line");
        const double v = reader.number(t[0]);
        if (v != 0.0) add(i, j, v);
      }
    }
  }
  if (!reader.next().empty()) reader.fail("more entries than the size line announces");

  Eigen::SparseMatrix<double> m(rows, cols);
  m.setFromTriplets(triplets.begin(), triplets.end());  // sums duplicates
  m.makeCompressed();
  return m;
}

void write_matrix_market(const std::filesystem::path& path, const Eigen::SparseMatrix<double>& m,
                         bool symmetric) {
  assert(!symmetric || m.rows() == m.cols());
  std::string body;
  long count = 0;
  for (int j = 0; j < m.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(m, j); it; ++it) {
      if (symmetric && it.row() < it.col()) continue;
      body += fmt::format("{} {} {:.17g}\n", it.row() + 1, it.col() + 1, it.value());
      ++count;
    }
  }
  std::string text = fmt::format("%%MatrixMarket matrix coordinate real {}\n",
                                 symmetric ? "symmetric" : "general");
  text += fmt::format("{} {} {}\n", m.rows(), m.cols(), count);
  text += body;
  write_file_atomically(path, text);
}

}  // namespace jointlab::data
