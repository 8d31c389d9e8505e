// Output files that are either complete or absent.
//
// AtomicFile writes to "<path>.tmp-<random>" in the same directory and renames
// it over <path> on commit(); if destroyed uncommitted (an exception, an early
// return) the temporary is removed, so no half-written result is ever left.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace jointlab::data {

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
  /// Flushes, checks for write errors and renames into place; throws InputError on failure.
  void commit();

 private:
  std::filesystem::path path_;
  std::filesystem::path tmp_;
  std::ofstream out_;
  bool committed_ = false;
};

/// Writes `text` to `path` atomically.
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

}  // namespace jointlab::data
