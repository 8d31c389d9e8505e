// The folders `jointlab process` and `jointlab stepped-sine` write, as their summary.json
// describes them (modal/process_output.h, modal/stepped_sine_output.h): the files (hits) processed,
// each one's bands with their linear data and operating shape, and the backbone CSV of each
// channel and band. Read here, with the other readers, so that the updating (correlate/) computes
// on values and opens no JSON (style.md 14).
//
// DIR/summary.json lists per file its bands k = 1, 2, ... with the reference channel, the linear
// frequency [Hz] and the operating shape (complex amplitude per channel, any scaling, [m]), and its
// outputs: one backbone CSV per channel and band, amplitudes in the SI unit of
// "amplitude_quantity".
#pragma once

#include <complex>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "jointlab/core/units.h"
#include "jointlab/data/backbone_table.h"

namespace jointlab::data {

/// One band of one processed file, as summary.json describes it.
struct ProcessBand {
  std::string source;                  ///< the processed file
  int band = 0;                        ///< k, from 1
  std::string reference_channel;       ///< channel of the linear data
  double linear_frequency_hz = 0;      ///< 0 when the summary gives none
  double linear_frequency_std_hz = 0;  ///< its stated one-sigma uncertainty (0: none given)
  /// The lowest amplitude its linear fit read (linear_fit_amplitude_min; 0: none given)
  double linear_fit_amplitude_min = 0;
  std::vector<std::pair<std::string, std::complex<double>>> shape;  ///< channel, amplitude
};

/// One output (channel and band of one file) as summary.json describes it.
struct ProcessOutput {
  std::string source;   ///< the processed file
  std::string channel;  ///< channel name
  int band = 0;         ///< k, from 1
  std::string file;     ///< backbone CSV name in the directory; empty when none was written
};

/// The contents of a process output directory's summary.json.
struct ProcessRun {
  std::filesystem::path dir;                 ///< the directory
  Quantity amplitude = Quantity::kVelocity;  ///< backbone amplitude quantity
  std::vector<ProcessBand> bands;            ///< every file's bands
  std::vector<ProcessOutput> outputs;        ///< every file's outputs
  /// k of the *_std values (summary.json's coverage_factor: expanded, k sigma; absent: 1)
  double coverage_factor = 1.0;
};

/// Reads DIR/summary.json; InputError naming the file and the field (or line and byte), and
/// saying so when DIR is a `stepped-sine` output instead.
ProcessRun read_process_run(const std::filesystem::path& dir);

/// Reads one backbone CSV of `process` (columns by name: amplitude, frequency_hz,
/// damping_ratio, and where present time_s and the two std columns, both or neither; amplitudes
/// in SI): rows in the file's (time) order, those marked in a `harmonic` or `exchange` column
/// left out (not the mode's own frequency or damping), so that the table may hold no point; the
/// std columns' k from its `coverage_factor` column (none: 1). InputError naming the file and
/// line. A point's damping may be 0 or below (noise at the record's end), unlike a plain table's
/// (read_backbone_table).
BackboneTable read_process_backbone(const std::filesystem::path& path);

/// One file of a `jointlab stepped-sine` run and its backbone CSV.
struct SteppedSineOutput {
  std::string source;  ///< the stepped-sine file
  std::string file;    ///< backbone CSV name in the directory; empty when no level gave a point
};

/// The contents of a `jointlab stepped-sine` output directory's summary.json
/// (docs/stepped-sine.md): one backbone per file, one point per level.
struct SteppedSineRun {
  std::filesystem::path dir;                 ///< the directory
  Quantity amplitude = Quantity::kVelocity;  ///< backbone amplitude quantity
  std::vector<SteppedSineOutput> outputs;    ///< every file's backbone
  double coverage_factor = 1.0;  ///< k of the backbones' std columns (summary.json; absent: 1)
};

/// Reads DIR/summary.json of `jointlab stepped-sine`; InputError naming the file and the field,
/// and saying so when DIR is a `process` output instead.
SteppedSineRun read_stepped_sine_run(const std::filesystem::path& dir);

}  // namespace jointlab::data
