// Writers of the uniform record: the contract's CSV, UFF 58 and MATLAB .mat.
//
// CSV as jointlab writes it (docs/csv.md): "# fs: <Hz>" and "# t0: <s>" lines, then the
// record's other metadata as "# key: value" lines, a header row "name [unit]" with the SI
// unit of each channel's quantity (no brackets when the channel has no quantity), and one
// row per sample, comma-delimited. Every number is printed in its shortest form that reads
// back to the same double, so read_csv(write_csv_record(r)) returns r's samples and fs
// bit for bit. UFF and .mat writers live beside their readers (uff58.h, mat_file.h);
// write_record picks one by extension.
#pragma once

#include <filesystem>
#include <string>

#include "jointlab/data/record.h"

namespace jointlab::data {

/// The CSV text write_csv_record writes; InputError (naming `name`) for a record it cannot
/// represent.
std::string format_csv_record(const Record& record, const std::string& name = "record");

/// Writes a record as a contract CSV file, atomically.
void write_csv_record(const std::filesystem::path& path, const Record& record);

/// Refuses (InputError naming the file), before any work, a path write_record could not
/// write: an extension naming no format, a folder, or a folder that does not exist.
void check_record_destination(const std::filesystem::path& path);

/// Writes a record in the format its extension names: .csv, .uff/.unv (ASCII 58), .mat (v5).
void write_record(const std::filesystem::path& path, const Record& record);

}  // namespace jointlab::data
