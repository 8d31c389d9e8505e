#include "jointlab/data/record_writer.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/data/mat_file.h"
#include "jointlab/data/uff58.h"

namespace jointlab::data {
namespace {

// A header field: quoted (libcsv rules) when it holds the delimiter or a quote.
std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

bool printable_line(const std::string& s) { return s.find_first_of("\r\n") == std::string::npos; }

}  // namespace

std::string format_csv_record(const Record& record, const std::string& name) {
  check_writable(record, name);
  const Eigen::Index n = record.size();
  std::string out = fmt::format("# fs: {}\n# t0: {}\n", record.fs, record.t0);
  for (const auto& [key, value] : record.metadata) {
    const std::string k = lower(key);
    if (k == "fs" || k == "t0" || k.empty() || k.find(':') != std::string::npos ||
        k.find('#') != std::string::npos || !printable_line(k) || !printable_line(value)) {
      continue;
    }
    out += fmt::format("# {}: {}\n", key, value);
  }
  for (size_t c = 0; c < record.channels.size(); ++c) {
    const Channel& ch = record.channels[c];
    const auto first = ch.name.find_first_not_of(" \t");
    const auto last = ch.name.find_last_not_of(" \t");
    if (first != 0 || last + 1 != ch.name.size() ||
        ch.name.find_first_of("[]\r\n\t;") != std::string::npos || lower(ch.name) == "time" ||
        ch.name.front() == '#') {
      throw InputError(where(name, 0,
                             fmt::format("channel name '{}' cannot be a CSV header (no "
                                         "brackets, tab, semicolon, line break, leading"
                                         " '#' or outer blanks; not 'time')",
                                         ch.name)));
    }
    if (!ch.samples.allFinite()) {
      throw InputError(where(name, 0, fmt::format("channel '{}' holds NaN or Inf", ch.name)));
    }
    const std::string header =
        ch.quantity ? fmt::format("{} [{}]", ch.name, si_unit(*ch.quantity)) : ch.name;
    if (c) out += ',';
    out += csv_field(header);
  }
  out += '\n';
  for (Eigen::Index k = 0; k < n; ++k) {
    for (size_t c = 0; c < record.channels.size(); ++c) {
      if (c) out += ',';
      out += fmt::format("{}", record.channels[c].samples[k]);
    }
    out += '\n';
  }
  return out;
}

void write_csv_record(const std::filesystem::path& path, const Record& record) {
  write_file_atomically(path, format_csv_record(record, path.string()));
}

namespace {

enum class RecordFormat { kCsv, kUff, kMat };

// The format `path`'s extension names; InputError naming the file otherwise.
RecordFormat record_format(const std::filesystem::path& path) {
  const std::string ext = lower(path.extension().string());
  if (ext == ".csv" || ext == ".txt") return RecordFormat::kCsv;
  if (ext == ".uff" || ext == ".unv" || ext == ".uf") return RecordFormat::kUff;
  if (ext == ".mat") return RecordFormat::kMat;
  throw InputError(where(path.string(), 0,
                         fmt::format("cannot tell the format to write from "
                                     "extension '{}' (.csv, .uff, .mat)",
                                     ext)));
}

}  // namespace

void check_record_destination(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    throw InputError(
        where(path.string(), 0, "is a folder: give a file name to write the record to"));
  }
  record_format(path);
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec)) {
    throw InputError(
        where(path.string(), 0,
              fmt::format("the folder '{}' does not exist: create it first", dir.string())));
  }
}

void write_record(const std::filesystem::path& path, const Record& record) {
  switch (record_format(path)) {
    case RecordFormat::kCsv:
      return write_csv_record(path, record);
    case RecordFormat::kUff:
      return write_uff58(path, record, false);
    case RecordFormat::kMat:
      return write_mat(path, record);
  }
}

}  // namespace jointlab::data
