#include "jointlab/data/atomic_file.h"

#include <random>
#include <system_error>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::data {

AtomicFile::AtomicFile(std::filesystem::path path) : path_(std::move(path)) {
  std::random_device rd;
  tmp_ = path_;
  tmp_ += fmt::format(".tmp-{:08x}", rd());
  out_.open(tmp_, std::ios::binary | std::ios::trunc);
  if (!out_) throw InputError(where(path_.string(), 0, "cannot create output file"));
  out_.precision(17);
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(tmp_, ec);
  }
}

void AtomicFile::commit() {
  out_.flush();
  const bool ok = static_cast<bool>(out_);
  out_.close();
  if (!ok) throw InputError(where(path_.string(), 0, "write failed (disk full?)"));
  std::error_code ec;
  std::filesystem::rename(tmp_, path_, ec);
  if (ec) throw InputError(where(path_.string(), 0, "cannot rename into place: " + ec.message()));
  committed_ = true;
}

void write_file_atomically(const std::filesystem::path& path, const std::string& text) {
  AtomicFile f(path);
  f.stream() << text;
  f.commit();
}

}  // namespace jointlab::data
