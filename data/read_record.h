// One entry point for every test-file format jointlab reads.
//
// The format is recognised from the content first, then from the extension:
//   - "MATLAB 5.0 MAT-file" header (v5/v7) or an HDF5 signature at byte 512 (v7.3) -> MATLAB
//     (mat_file.h);
//   - a first non-blank line "-1" followed by a dataset number -> UFF dataset 58 (uff58.h);
//   - otherwise by extension: .csv .txt .tsv -> CSV (csv_reader.h); .uff .unv .uf -> UFF;
//     .mat -> MATLAB.
// Anything else is an InputError naming the file. Every reader returns the same Record:
// named channels, SI samples, one uniform time base (record.h).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

#include "jointlab/data/record.h"

namespace jointlab::data {

/// The file formats read_record recognises.
enum class FileFormat { kCsv, kUff58, kMat };

/// Recognises the format of `path` from its first bytes and its extension; InputError if
/// none fits.
FileFormat detect_format(const std::filesystem::path& path);

/// Reads a test file of any supported format into a record; InputError on any defect.
Record read_record(const std::filesystem::path& path);

/// What to say when reading or processing the record `path` ran out of memory (std::bad_alloc):
/// one line naming the file, its size on disk and how many files were read at once (`at_once`),
/// and what to do. `process` and `run` both say it.
std::string out_of_memory_message(const std::filesystem::path& path, size_t at_once);

}  // namespace jointlab::data
