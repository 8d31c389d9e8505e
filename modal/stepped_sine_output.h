// Files written by `jointlab stepped-sine` (docs/stepped-sine.md).
//
// Per input file: DIR/<file stem>.backbone.csv, one row per level that gave a point,
// amplitude increasing, with columns
//   amplitude, frequency_hz, damping_ratio, frequency_std_hz, damping_std   (as `process`)
//   level, response_controlled, points, fit_rms, displacement_m, force_n, damping_direct
// and DIR/summary.json describing every level of every file (its fit, or why it gave no point).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "jointlab/data/stepped_sine.h"
#include "jointlab/data/table_writer.h"
#include "jointlab/modal/stepped_sine.h"

namespace jointlab::modal {

/// The tables of one file and the point each gave.
struct SteppedSineFileResult {
  std::string source;                          ///< the file
  std::vector<data::SteppedSineTable> tables;  ///< its levels
  std::vector<SineBackbonePoint> points;       ///< one per table
};

/// Reads a stepped-sine file (data/stepped_sine.h; `quantity`: what a response column without a
/// unit measures) and extracts every level's point: the response-controlled levels first,
/// whose modal constant then serves the force-controlled ones' energy balance. InputError on a
/// defective file.
SteppedSineFileResult extract_stepped_sine_file(const std::filesystem::path& file,
                                                std::optional<Quantity> quantity,
                                                const SteppedSineOptions& options);

/// Name of a file's backbone CSV: "<stem>.backbone.csv".
std::string sine_backbone_file_name(const std::string& source);

/// Number of usable points of a file.
int usable_points(const SteppedSineFileResult& result);

/// The rows of the file's backbone CSV: one per level that gave a point, amplitude increasing,
/// in the columns above (no row when no level gave a point).
data::Table sine_backbone_table(const SteppedSineFileResult& result);

/// Writes DIR/<stem>.backbone.csv, sine_backbone_table's rows (nothing when no level gave a
/// point).
void write_sine_backbone(const std::filesystem::path& dir, const SteppedSineFileResult& result);

/// Writes DIR/summary.json for all files.
void write_sine_summary(const std::filesystem::path& dir,
                        const std::vector<SteppedSineFileResult>& results,
                        const SteppedSineOptions& options);

}  // namespace jointlab::modal
