// Output files that are either complete or absent.
//
// AtomicFile writes to "<path>.tmp-<random>" in the same directory and renames
// it over <path> on commit(); if destroyed uncommitted (an exception, an early
// return) the temporary is removed, so no half-written result is ever left.
// A temporary is claimed (an advisory lock) while its writer lives, so the
// temporaries a killed run left behind are told apart from a running one's and
// removed by the next writer of the same file (or remove_stale_temporaries).
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace jointlab::data {

/// Holds an advisory lock on a file created for a running writer (a temporary or a staging
/// folder); remove_stale_temporaries spares what is claimed.
class TemporaryClaim {
 public:
  TemporaryClaim() = default;
  /// Creates the file `path` (which must not exist; a folder when `folder`) and claims it;
  /// throws InputError if it cannot be created.
  explicit TemporaryClaim(const std::filesystem::path& path, bool folder = false);
  ~TemporaryClaim();
  TemporaryClaim(TemporaryClaim&& other) noexcept;
  TemporaryClaim& operator=(TemporaryClaim&& other) noexcept;
  TemporaryClaim(const TemporaryClaim&) = delete;
  TemporaryClaim& operator=(const TemporaryClaim&) = delete;
  /// Releases the claim (the file stays).
  void release();

 private:
  int fd_ = -1;
};

/// A new unclaimed name "<dir>/<prefix><8 hex digits><suffix>" (random).
std::filesystem::path temporary_name(const std::filesystem::path& dir, const std::string& prefix,
                                     const std::string& suffix = "");

/// True for a name a writer gives its temporaries: "...tmp-XXXXXXXX" with an optional
/// extension, or a staging folder ".<command>.stage-XXXXXXXX".
bool is_temporary_name(const std::string& file_name);

/// Removes the unclaimed temporaries (left by killed runs) in `dir` whose names start
/// with `prefix` (every temporary when empty); a claimed one belongs to a running writer.
void remove_stale_temporaries(const std::filesystem::path& dir, const std::string& prefix = "");

/// A file written under a temporary name and renamed into place on commit().
class AtomicFile {
 public:
  /// Opens a temporary beside `path`; throws InputError if it cannot be created.
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// The stream to write to.
  std::ofstream& stream() { return out_; }
  /// Flushes and closes, checks every write and the close, and renames into place; throws
  /// InputError on failure (the temporary is removed, nothing is moved into place).
  void commit();

 private:
  std::filesystem::path path_;
  std::filesystem::path tmp_;
  TemporaryClaim claim_;
  std::ofstream out_;
  bool committed_ = false;
};

/// Writes `text` to `path` atomically.
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace jointlab::data
