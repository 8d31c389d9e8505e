#include "jointlab/data/atomic_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <random>
#include <regex>
#include <system_error>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::data {

namespace fs = std::filesystem;

TemporaryClaim::TemporaryClaim(const fs::path& path, bool folder) {
  if (folder) {
    if (::mkdir(path.c_str(), 0777) != 0)
      throw InputError(where(path.string(), 0, fmt::format("cannot create: {}", strerror(errno))));
    fd_ = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  } else {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  }
  if (fd_ < 0)
    throw InputError(where(path.string(), 0, fmt::format("cannot create: {}", strerror(errno))));
  // A cleaner that opened the new file before this lock may have taken it for stale; then the
  // path no longer names this file and the claim fails rather than write into nothing.
  struct stat mine {
  }, named{};
  if (::flock(fd_, LOCK_EX) != 0 || ::fstat(fd_, &mine) != 0 || ::stat(path.c_str(), &named) != 0 ||
      mine.st_ino != named.st_ino || mine.st_dev != named.st_dev) {
    release();
    throw InputError(where(path.string(), 0, "cannot claim the temporary (removed meanwhile)"));
  }
}

TemporaryClaim::~TemporaryClaim() { release(); }

TemporaryClaim::TemporaryClaim(TemporaryClaim&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }

TemporaryClaim& TemporaryClaim::operator=(TemporaryClaim&& other) noexcept {
  if (this != &other) {
    release();
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

void TemporaryClaim::release() {
  if (fd_ >= 0) ::close(fd_);  // closing drops the lock
  fd_ = -1;
}

fs::path temporary_name(const fs::path& dir, const std::string& prefix, const std::string& suffix) {
  static thread_local std::mt19937 gen{std::random_device{}()};
  for (;;) {
    fs::path p = dir / fmt::format("{}{:08x}{}", prefix, gen(), suffix);
    std::error_code ec;
    if (!fs::exists(fs::symlink_status(p, ec))) return p;
  }
}

bool is_temporary_name(const std::string& file_name) {
  static const std::regex pattern(R"((.*\.tmp-|^\..*\.stage-)[0-9a-f]{8}(\.[A-Za-z0-9]+)?)");
  return std::regex_match(file_name, pattern);
}

void remove_stale_temporaries(const fs::path& dir, const std::string& prefix) {
  std::error_code ec;
  for (fs::directory_iterator it(dir.empty() ? fs::path(".") : dir, ec), end; !ec && it != end;
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0 || !is_temporary_name(name)) continue;
    const int fd = ::open(it->path().c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) {  // nobody holds it: its writer is gone
      std::error_code rm;
      fs::remove_all(it->path(), rm);
    }
    ::close(fd);
  }
}

namespace {

// The path a message names: a file in a staging folder by the name it will have.
std::string shown(const fs::path& path) {
  const fs::path dir = path.parent_path();
  if (!dir.empty() && is_temporary_name(dir.filename().string()))
    return (dir.parent_path() / path.filename()).string();
  return path.string();
}

}  // namespace

AtomicFile::AtomicFile(fs::path path) : path_(std::move(path)) {
  const fs::path dir = path_.has_parent_path() ? path_.parent_path() : fs::path(".");
  const std::string prefix = path_.filename().string() + ".tmp-";
  // Said of the file asked for, not of the temporary a missing folder would fail to create.
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw InputError(where(shown(path_), 0,
                           fmt::format("cannot create output file: no folder {}", dir.string())));
  }
  remove_stale_temporaries(dir, prefix);
  tmp_ = temporary_name(dir, prefix);
  claim_ = TemporaryClaim(tmp_);
  out_.open(tmp_, std::ios::binary | std::ios::trunc);
  if (!out_) {
    fs::remove(tmp_, ec);
    throw InputError(where(shown(path_), 0, "cannot create output file"));
  }
  out_.precision(17);
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    fs::remove(tmp_, ec);
  }
}

void AtomicFile::commit() {
  out_.flush();
  bool ok = static_cast<bool>(out_);
  out_.close();  // a failed close (the last buffered write) sets failbit
  ok = ok && static_cast<bool>(out_);
  if (!ok) {
    std::error_code ec;
    fs::remove(tmp_, ec);
    throw InputError(where(shown(path_), 0, "write failed (disk full?)"));
  }
  std::error_code ec;
  fs::rename(tmp_, path_, ec);
  if (ec) {
    std::error_code rm;
    fs::remove(tmp_, rm);
    throw InputError(where(shown(path_), 0, "cannot rename into place: " + ec.message()));
  }
  committed_ = true;
  claim_.release();
}

void write_file_atomically(const fs::path& path, const std::string& text) {
  AtomicFile f(path);
  f.stream() << text;
  f.commit();
}

}  // namespace jointlab::data
