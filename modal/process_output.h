// Files written by `jointlab process`.
//
// Per channel and band: DIR/<file stem>.<channel>.band<k>.csv with columns
//   time_s, amplitude, frequency_hz, damping_ratio, frequency_std_hz, damping_std,
//   damped_frequency_hz, decay_rate_1_per_s, displacement_m, snr, window_s, harmonic,
//   exchange, coverage_factor
// (the first six fixed by the contract). DIR/summary.json describes every
// output: file, channel, band, span kept, noise floor, linear frequency and
// damping, and each band's complex amplitudes (operating shape) per channel.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "jointlab/data/table_writer.h"
#include "jointlab/modal/process.h"

namespace jointlab::modal {

/// Name of the backbone CSV of one channel and band: "<stem>.<channel>.band<k>.csv", stem and
/// channel as data::file_name_part gives them (summary.json names the file the same).
std::string backbone_file_name(const std::string& source, const std::string& channel, int band);

/// The columns of one backbone CSV, named as in the file (the Python module returns them).
data::Table backbone_table(const Backbone& backbone, const RingdownOptions& options);

/// Writes the backbone CSVs of `result` into `dir` (no file for a channel-band without a span);
/// InputError if a name would be longer than data::kMaxFileNameBytes.
void write_backbones(const std::filesystem::path& dir, const RecordResult& result,
                     const RingdownOptions& options);

/// Writes DIR/summary.json for all processed records.
void write_summary(const std::filesystem::path& dir, const std::vector<RecordResult>& results,
                   const ProcessOptions& options);

}  // namespace jointlab::modal
