// A sensors file (docs/sensors.md) as written: which model DOF each measured channel sees.
//
// CSV (',', ';' or tab, the header's most frequent; '#' comment lines allowed):
//     channel,dof[,sign]
//     acc1,1001:3,1
//     acc2,57,-1
// `dof` is a 0-based matrix index or a "node:component" label of the model's dof_labels (resolved
// against a model in correlate/sensors.h); `sign` is 1 or -1 (default 1). Channel names are
// unique. Read here, with the other readers, so that the updating computes on values.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace jointlab::data {

/// One row of a sensors file.
struct SensorRow {
  std::string channel;  ///< channel name as in the test files
  std::string dof;      ///< the model DOF as written: an index or a "node:component" label
  double sign = 1.0;    ///< +1 or -1: the channel reads sign * u[dof]
  long line = 0;        ///< its line in the file (for messages)
};

/// A sensors file's rows, in order.
struct SensorsFile {
  std::string source;           ///< the file it was read from
  std::vector<SensorRow> rows;  ///< at least one
};

/// Parses sensors text as if read from a file named `name`; InputError "name:line: what".
SensorsFile parse_sensors_file(const std::string& text, const std::string& name);

/// Reads a sensors file; InputError naming the file and line.
SensorsFile read_sensors_file(const std::filesystem::path& path);

}  // namespace jointlab::data
