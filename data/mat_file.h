// MATLAB .mat files (v5/v7 and v7.3) holding time histories, through matio.
//
// Mapping to a record (docs/mat.md):
//   - the variables are the fields of the one 1x1 struct in the file that has a `time` or
//     `fs` field (HammerImpact.mat: struct HIdata {time, acc1, acc2, acc3, units}), or the
//     file's top-level variables when one of them is named `time`, `t` or `fs`;
//   - time base: `fs` (scalar, Hz) and `t0` (scalar, s) when present, else the `time` (or
//     `t`) vector, which must increase uniformly; when both are given they must agree;
//   - every other real numeric vector of two or more elements is a channel, in file order,
//     named after its field or variable (or after the `channel_names` cell of strings);
//   - `units` (a char row "s, m/s^2" or a cell of strings): with a time vector, the first
//     entry is its unit (s or ms); then one entry for every channel, or one for all; an
//     empty entry means no unit. Samples are converted to SI (core/units.h);
//   - other numeric scalars and char rows go to the metadata; anything else is ignored.
// Integer and single-precision data are converted to double. The writer writes a struct
// `record` with fields fs, t0, time, one field per channel (MATLAB-safe names), units
// (SI, time first) and channel_names; v5 (compressed, "v7") or v7.3 (HDF5).
#pragma once

#include <filesystem>

#include "jointlab/data/record.h"

namespace jointlab::data {

/// MAT-file versions the writer can produce.
enum class MatVersion { kV5, kV73 };

/// Reads a .mat file into a record (mapping above); InputError ("file: field 'x': what") on
/// any defect.
Record read_mat(const std::filesystem::path& path);

/// Writes a record as a .mat file (struct `record`, mapping above), atomically.
void write_mat(const std::filesystem::path& path, const Record& record,
               MatVersion version = MatVersion::kV5);

/// True when the matio linked here can write and read v7.3 (HDF5) files.
bool mat_v73_supported();

}  // namespace jointlab::data
