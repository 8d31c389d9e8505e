// Reading back the numeric CSV tables a run writes (data/table_writer.h): a header of
// column names, then rows of finite numbers, for the cached hits; and a hit's backbone file of
// `process` as a curve (read by data::read_process_backbone).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/curve.h"

namespace jointlab::campaign {

/// A numeric CSV: column names and equally long columns.
struct NumericTable {
  std::vector<std::string> names;            ///< header row
  std::vector<std::vector<double>> columns;  ///< one per name
  /// The column called `name`; InputError naming `file` when there is none.
  const std::vector<double>& column(const std::string& name,
                                    const std::filesystem::path& file) const;
};

/// Reads a numeric CSV; InputError naming the file and row when a cell is not a finite number.
/// With allow_empty, an empty cell is an absent value (data::Table::add_optional) and reads as
/// NaN: the caller tests for it before any use.
NumericTable read_numeric_table(const std::filesystem::path& path, bool allow_empty = false);

/// A backbone file of `process`: the curve and each point's own uncertainty.
struct BackboneFile {
  correlate::Curve curve;            ///< time, amplitude, frequency and damping (no linear values)
  Eigen::VectorXd frequency_std_hz;  ///< per point, k sigma [Hz]; empty when the file has none
  Eigen::VectorXd damping_std;       ///< per point, k sigma; empty when the file has none
  double coverage_factor = 1.0;      ///< k: the file's coverage_factor column (none: 1)
};

/// Reads a backbone CSV of `process` (data::read_process_backbone: time_s, amplitude,
/// frequency_hz, damping_ratio and, when present, frequency_std_hz and damping_std) as a curve of
/// hit `id` in `group`. Points marked in a `harmonic` or `exchange` column (not the mode's own
/// frequency or damping) are left out.
BackboneFile read_backbone_file(const std::filesystem::path& path, const std::string& id,
                                const std::string& group);

}  // namespace jointlab::campaign
