// Reader of the contract's CSV test files (one file per hit).
//
// Layout: optional leading "# key: value" lines (metadata: fs, test, level, ...),
// one header row, then one row per sample. A column named "time" (seconds, or
// "time [ms]") gives the time base unless "# fs: <Hz>" does; every other column
// is a channel whose header may carry a unit in brackets ("acc1 [g]"). The
// delimiter (comma, semicolon or tab) is detected from the header row.
// Samples are converted to SI on reading. Any defect is an InputError naming
// the file and line.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "jointlab/data/record.h"

namespace jointlab::data {

/// Reads a CSV test file; throws InputError ("file:line: what") on any defect.
Record read_csv(const std::filesystem::path& path);

/// Parses CSV text as if read from a file named `name` (used by read_csv and fuzzing).
Record parse_csv(std::string_view text, const std::string& name);

}  // namespace jointlab::data
