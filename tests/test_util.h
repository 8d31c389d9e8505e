// One place for test tolerances: relative/absolute comparison with NaN made explicit.
//
// expect_close(actual, expected, rel, abs) passes when
//   |actual - expected| <= max(rel * |expected|, abs)
// and both are finite. A NaN never compares close to anything.
#pragma once

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"

namespace jointlab::testing {

/// True when a and b are finite and within max(rel*|b|, abs) of each other.
inline bool is_close(double a, double b, double rel, double abs = 0.0) {
  if (!std::isfinite(a) || !std::isfinite(b)) return false;
  return std::abs(a - b) <= std::max(rel * std::abs(b), abs);
}

/// gtest assertion form of is_close, with both values in the failure message.
inline ::testing::AssertionResult Close(double actual, double expected, double rel,
                                        double abs = 0.0) {
  if (is_close(actual, expected, rel, abs)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "actual " << actual << " vs expected " << expected << " (rel err "
         << (expected != 0 ? std::abs(actual - expected) / std::abs(expected) : INFINITY)
         << ", allowed rel " << rel << " abs " << abs << ")";
}

/// Relative error |a-b|/|b|.
inline double rel_err(double a, double b) { return std::abs(a - b) / std::abs(b); }

/// Runs f expecting an InputError with a one-line message; returns the message
/// (an empty string, and a test failure, when nothing or something else is thrown).
inline std::string input_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    return m;
  }
  ADD_FAILURE() << "no InputError";
  return "";
}

/// The whole content of the file at `path` ("" when it cannot be read).
inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// This process's folder under the system temporary folder, holding every scratch folder
/// its tests make; removed when the process ends (kept when JOINTLAB_KEEP_SCRATCH is set,
/// to look at after a failure). One per process: ctest runs the cases of one program side
/// by side, so a shared folder would be cleared under them.
inline const std::filesystem::path& scratch_root() {
  struct Root {
    pid_t owner = getpid();
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("jointlab-test-" + std::to_string(getpid()));
    Root() = default;
    Root(const Root&) = delete;
    Root& operator=(const Root&) = delete;
    // A forked child that exits normally runs this too: only the process that made the
    // folder removes it.
    ~Root() {
      std::error_code ec;
      if (getpid() == owner && !std::getenv("JOINTLAB_KEEP_SCRATCH"))
        std::filesystem::remove_all(path, ec);
    }
  };
  static const Root root;
  return root.path;
}

/// A temporary folder named after `folder` in scratch_root().
inline std::filesystem::path scratch_folder(const std::string& folder) {
  const std::filesystem::path dir = scratch_root() / folder;
  std::filesystem::create_directories(dir);
  return dir;
}

/// A path for a test's file `name` in scratch_folder(folder).
inline std::filesystem::path scratch_path(const std::string& folder, const std::string& name) {
  return scratch_folder(folder) / name;
}

/// scratch_path() with `text` written to it.
inline std::filesystem::path scratch_file(const std::string& folder, const std::string& name,
                                          const std::string& text) {
  const std::filesystem::path p = scratch_path(folder, name);
  std::ofstream(p) << text;
  return p;
}

/// The source tree root (set by CMake for every test).
inline std::string source_dir() {
  const char* s = std::getenv("JOINTLAB_SOURCE_DIR");
  return s ? s : ".";
}

/// The build tree root (set by CMake for every test).
inline std::string binary_dir() {
  const char* s = std::getenv("JOINTLAB_BINARY_DIR");
  return s ? s : ".";
}

}  // namespace jointlab::testing
