// The frame shared by the summary.json files of `process` and `stepped-sine`.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>

#include "jointlab/core/units.h"
#include "jointlab/data/json_writer.h"

namespace jointlab::modal {

/// Writes the keys amplitude_quantity, amplitude_unit and coverage_factor, in that order.
void write_amplitude_keys(data::JsonWriter& j, Quantity amplitude, double coverage_factor);

/// Writes DIR/summary.json: one object holding the keys `header` writes, then "files", an
/// array of `files` objects whose keys `file(j, i)` writes for file i.
void write_summary_json(const std::filesystem::path& dir,
                        const std::function<void(data::JsonWriter&)>& header, std::size_t files,
                        const std::function<void(data::JsonWriter&, std::size_t)>& file);

}  // namespace jointlab::modal
