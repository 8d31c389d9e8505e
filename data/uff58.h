// Universal File Format dataset 58 (function at a nodal DOF): time histories.
//
// A UFF file is a sequence of datasets, each between two lines holding "-1" in
// columns 1-6. Dataset 58 has eleven header records (five ID lines; record 6:
// function type, response entity, node and direction; record 7: ordinate data
// type, number of points, abscissa spacing, minimum and increment; records 8-11:
// abscissa, ordinate numerator and denominator, z axis, each with a specific data
// type, unit exponents, a label and a unit label) and then the data, either as
// text (ASCII "58") or as raw IEEE 754 numbers ("58b": byte order and number of
// bytes given on the dataset line). Other datasets in the file are skipped.
//
// jointlab reads only time responses (function type 1, or 0 with a time
// abscissa) with real ordinates (types 2 and 4); every dataset 58 of a file
// becomes one channel and all must share one time base (same number of points,
// t0 = abscissa minimum, dt = abscissa increment; fs = 1/dt). A channel is named
// "<node><dir>" ("1+Z", "12-RX") when it has a node and a direction, else after
// its response entity name, else after ID line 1. Its quantity and SI factor come
// from the record 9 unit label (parse_unit) and the specific data type (8
// displacement, 11 velocity, 12 acceleration, 9 and 13 force); an unlabelled
// channel of a known type is taken as SI; one of another type (pressure, ...)
// keeps its samples and unit text with no quantity. The writer emits one dataset
// per channel: SI units, float64 values (ASCII 4E20.12, or 58b little-endian).
// See docs/uff58.md.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "jointlab/data/record.h"

namespace jointlab::data {

/// Reads every dataset 58/58b of a UFF file into one record; InputError ("file:line: what") on
/// any defect.
Record read_uff58(const std::filesystem::path& path);

/// Parses UFF bytes as if read from a file named `name` (used by read_uff58 and fuzzing).
Record parse_uff58(std::string_view bytes, const std::string& name);

/// The UFF file write_uff58 writes: one dataset 58 (ASCII) or 58b (binary) per channel.
std::string format_uff58(const Record& record, bool binary, const std::string& name = "record");

/// Writes a record as UFF datasets 58 (binary = false) or 58b (binary = true), atomically.
void write_uff58(const std::filesystem::path& path, const Record& record, bool binary);

}  // namespace jointlab::data
