// Stepped-sine test tables: one table per excitation level (docs/stepped-sine-table.md).
//
// A stepped-sine test holds the structure at one level per sweep and steps the excitation
// frequency through a mode; each step gives the steady-state first harmonic of the force
// and of the response: the force amplitude |F| [N], the response amplitude |Y| in its
// quantity (displacement, velocity or acceleration; SI on reading) and the phase of the
// response relative to the force. The level is either the response amplitude (response
// control: |Y| held constant, the force follows) or the force amplitude (force control).
//
// CSV: optional "# key: value" lines (`control: response|force`, `level: ...`, `test: ...`),
// one header row with `frequency_hz` (or `frequency [Hz]`), `force [unit]`,
// `response [unit]` and `phase [deg|rad]`, optionally `level` (rows with one level value
// form one table, in order of first appearance) and `control` (`response`/`force` per
// row, constant within a level); comma, semicolon or tab delimited. Force and response are zero
// to peak: a header that says RMS or peak to peak ('response_rms [m/s^2]', 'force [N RMS]',
// 'response [mm/s] (pk-pk)') is refused with its factor (amplitude_measure.h).
// MATLAB (.mat, the Brake-Reuss layout): a struct whose fields are struct arrays named
// after their control (`ForceControl`, `ResponseControl`; any name containing "force" or
// "response"), each element one table with vectors `frequency`, `force`, `amplitude` (or
// `response`), `phase` and `units` ("Hz, N, m/s^2, rad": frequency, force, response and
// phase units in that order; an entry that says RMS or peak to peak is refused with its factor).
// Every defect is an InputError naming the file and the line or the field.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/core/units.h"

namespace jointlab::data {

/// What a stepped-sine sweep holds constant.
enum class SineControl { kResponse, kForce };

/// "response" or "force".
std::string control_name(SineControl c);

/// One sweep at one level, rows in increasing frequency.
struct SteppedSineTable {
  std::string source;                                    ///< file it came from
  std::string label;                                     ///< "level 20", "ResponseControl(3)", ...
  int index = 0;                                         ///< 1-based position in its file
  SineControl control = SineControl::kResponse;          ///< what was held constant
  Quantity response_quantity = Quantity::kAcceleration;  ///< what `response` measures
  Eigen::VectorXd frequency_hz;                          ///< excitation frequency [Hz], increasing
  Eigen::VectorXd force;                                 ///< force amplitude [N], > 0
  Eigen::VectorXd response;                              ///< response amplitude, SI, > 0
  Eigen::VectorXd phase_rad;                    ///< response phase relative to the force [rad]
  std::map<std::string, std::string> metadata;  ///< "# key: value" lines or .mat scalars

  /// Number of frequency steps.
  Eigen::Index size() const { return frequency_hz.size(); }
};

/// Reads every table of a stepped-sine file (CSV or .mat, recognised as read_record does);
/// `quantity` is what a response column without a unit measures (none: an error).
/// InputError ("file:line: what" or "file: field 'x': what") on any defect.
std::vector<SteppedSineTable> read_stepped_sine(const std::filesystem::path& path,
                                                std::optional<Quantity> quantity = {});

/// Parses stepped-sine CSV text as if read from a file named `name`.
std::vector<SteppedSineTable> parse_stepped_sine_csv(const std::string& text,
                                                     const std::string& name,
                                                     std::optional<Quantity> quantity = {});

/// Writes tables as one stepped-sine CSV (with `level` and `control` columns), atomically;
/// the response column in the SI unit of the first table's quantity, phase in degrees.
void write_stepped_sine_csv(const std::filesystem::path& path,
                            const std::vector<SteppedSineTable>& tables,
                            const std::vector<std::string>& comments = {});

}  // namespace jointlab::data
