// Running the built jointlab command from tests.
#pragma once

#include <string>

namespace jointlab::testing {

/// Exit status and captured streams of one command run.
struct CommandResult {
  int status = -1;  ///< exit status (-1 if it did not exit normally)
  std::string out;  ///< standard output
  std::string err;  ///< standard error
};

/// Runs `$JOINTLAB_BINARY_DIR/bin/jointlab <args>` through the shell.
CommandResult run_jointlab(const std::string& args);

/// A fresh empty directory under the system temporary directory.
std::string scratch_dir(const std::string& name);

/// Writes `text` to `path`.
void write_text(const std::string& path, const std::string& text);

}  // namespace jointlab::testing
