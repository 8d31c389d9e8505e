#include "jointlab/data/read_record.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/data/csv_lines.h"
#include "jointlab/data/csv_reader.h"
#include "jointlab/data/mat_file.h"
#include "jointlab/data/uff58.h"

namespace jointlab::data {
namespace {

std::string lower_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// True when the text opens like a UFF file: blank lines, "-1", then a dataset number.
bool looks_like_uff(const std::string& head) {
  size_t pos = 0;
  int stage = 0;
  while (pos < head.size() && stage < 2) {
    const size_t end = head.find('\n', pos);
    const std::string line =
        head.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
    pos = end == std::string::npos ? head.size() : end + 1;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    const auto last = line.find_last_not_of(" \t\r");
    const std::string t = line.substr(first, last - first + 1);
    if (stage == 0) {
      if (t != "-1") return false;
      stage = 1;
    } else {
      // "58", "58b ...", "151", "2411": digits, optionally a 'b', then anything.
      size_t i = 0;
      while (i < t.size() && std::isdigit(static_cast<unsigned char>(t[i]))) ++i;
      return i > 0 && (i == t.size() || t[i] == ' ' || t[i] == 'b' || t[i] == 'B');
    }
  }
  return false;
}

}  // namespace

FileFormat detect_format(const std::filesystem::path& path) {
  require_regular_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where(path.string(), 0, "cannot open file"));
  std::string head(1024, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));

  if (head.rfind("MATLAB 5.0 MAT-file", 0) == 0 || head.rfind("MATLAB 7.3 MAT-file", 0) == 0) {
    return FileFormat::kMat;
  }
  if (head.size() >= 520 && head.compare(512, 8, "\x89HDF\r\n\x1a\n") == 0) return FileFormat::kMat;
  if (looks_like_uff(head)) return FileFormat::kUff58;

  const std::string ext = lower_extension(path);
  if (ext == ".csv" || ext == ".txt" || ext == ".tsv") return FileFormat::kCsv;
  if (ext == ".uff" || ext == ".unv" || ext == ".uf") return FileFormat::kUff58;
  if (ext == ".mat") return FileFormat::kMat;
  throw InputError(where(path.string(), 0,
                         fmt::format("unknown file format (extension '{}'; "
                                     "jointlab reads CSV (.csv, .txt, .tsv), "
                                     "UFF 58 (.uff, .unv, .uf) and MATLAB "
                                     ".mat)",
                                     ext)));
}

Record read_record(const std::filesystem::path& path) {
  switch (detect_format(path)) {
    case FileFormat::kCsv:
      return read_csv(path);
    case FileFormat::kUff58:
      return read_uff58(path);
    case FileFormat::kMat:
      return read_mat(path);
  }
  throw InputError(where(path.string(), 0, "unknown file format"));
}

std::string out_of_memory_message(const std::filesystem::path& path, size_t at_once) {
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  return where(path.string(), 0,
               fmt::format("out of memory while reading and processing this record ({:.3g} MB on "
                           "disk, {} file(s) at once); give it alone with --threads 1, or a "
                           "shorter record",
                           ec ? 0.0 : static_cast<double>(bytes) / 1e6, at_once));
}

}  // namespace jointlab::data
