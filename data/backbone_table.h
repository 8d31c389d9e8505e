// A measured backbone as a plain table, from any source (docs/update-iwan.md, "--backbone"):
// one curve (one hit or test) per file, a lab's own tool, a script or a paper's table.
//
// CSV (comma, semicolon or tab; optional "# key: value" lines and blank lines before the header):
//     amplitude,frequency_hz,damping_ratio[,frequency_std_hz,damping_std]
// further columns ignored but for a `process` file's marks: a row whose `harmonic` or
// `exchange` cell is not 0 (not the mode's own frequency or damping) is skipped. Columns in
// any order. A column read may carry a unit in brackets, converted, never ignored:
//   amplitude [m], [mm/s], [g], ... (core/units.h): must measure the quantity the caller names
//     (none for a modal amplitude, which takes no unit), converted to SI;
//   frequency_hz, frequency_std_hz: [Hz] only;
//   damping_ratio, damping_std: [1] or [-] (a fraction), [%] (per cent: divided by 100).
// Any other unit is an InputError "file:line: column 'damping_ratio [x]': unit 'x' ..." naming
// what the column takes. Rows in any order; the table returned has them by increasing amplitude.
// Every amplitude, frequency [Hz] and damping ratio (a fraction) must be finite and > 0; the
// uncertainties, when present, finite and >= 0 (0: the caller's floor). Any defect is an
// InputError "file:line: what" naming the column.
// Tables written otherwise (docs/backbone-table.md): names are read case-blind and rows of empty
// cells (",,") skipped; everything else is refused with the fix named: a unit in round
// brackets, a lab's own column names, lines above the header without '#', decimal commas (never
// read as points nor as separators), while the two uncertainties are not both read, a column
// that looks like one (std, sigma, err, ...): ignored, the fit would use its floors unseen, and
// several hits in one file, told apart by a label column ('hit', 'test', 'run_id', ...) two of
// whose values hold two rows or more each, or by their order (each hit's rows running through its
// amplitudes one way, the next starting again at the other end): read as one curve, the scatter
// between the hits would pass for the model's misfit.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "jointlab/core/units.h"

namespace jointlab::data {

/// One backbone curve, amplitude increasing.
struct BackboneTable {
  std::string source;                ///< the file it was read from
  Eigen::VectorXd amplitude;         ///< a_j, > 0 (SI of the quantity named by the caller)
  Eigen::VectorXd frequency_hz;      ///< f_j [Hz], > 0
  Eigen::VectorXd damping_ratio;     ///< zeta_j, > 0
  Eigen::VectorXd frequency_std_hz;  ///< k sigma_f,j [Hz] >= 0 (all 0 without the column)
  Eigen::VectorXd damping_std;       ///< k sigma_z,j >= 0 (all 0 without the column)
  /// k of the std columns: a `coverage_factor` column's value (a `process` backbone's), else 1.
  double coverage_factor = 1.0;
  /// Whether the two std columns were read (else they are all 0: the caller's floors).
  bool has_uncertainty = false;
  /// A `process` backbone's time of each point after the record's start [s] (read_process_backbone;
  /// empty where the file has no time_s column, and for a plain table).
  Eigen::VectorXd time_s;
  /// The amplitude column's unit as its header gives it ("" where it gives none: SI).
  std::string amplitude_unit;
  /// A `process` backbone (its `coverage_factor` column) or a `stepped-sine` one
  /// (`response_controlled`): amplitudes in SI whatever the header says.
  bool written_by_jointlab = false;
  /// Number of points.
  Eigen::Index size() const { return amplitude.size(); }
  /// Whether its amplitudes were read in SI without a unit saying so (none in the header, and
  /// not a table jointlab wrote): a table in g or mm read so scales F_S by its factor.
  bool amplitude_unit_assumed() const { return amplitude_unit.empty() && !written_by_jointlab; }
};

/// Whether a backbone column marks points that are not the mode's own: a `process` backbone's
/// `harmonic` (a multiple of a stronger mode's frequency) and `exchange` (damping plus transfer
/// to another mode, which may be negative). Every backbone reader skips a row whose mark is not 0.
bool is_point_mark(std::string_view column);

/// One row's `coverage_factor` (k of a backbone file's expanded uncertainties, as `process`
/// writes it): `value` (NaN where the cell is no number) must be a finite number >= 1 and equal
/// `before`, the rows' value so far (0: none yet); returns it, else InputError "file:line:
/// coverage_factor 'cell' must be ..." (line 0: the file alone).
double coverage_factor_of_row(double value, double before, std::string_view cell,
                              const std::string& file, long line);

/// Reads a backbone table whose amplitude is of `quantity` (nullopt: a modal amplitude, which
/// takes no unit); InputError "file:line: what" on any defect (above), and when the file holds
/// fewer than two points.
BackboneTable read_backbone_table(const std::filesystem::path& path,
                                  std::optional<Quantity> quantity);

/// Reads each of `paths` (read_backbone_table), one curve each, in order; InputError when a file
/// is given twice ("a.csv: given twice: ...") or two files hold the same points (every amplitude,
/// frequency and damping equal to 1e-9: a copy of one hit's table): one hit counted as two
/// weighs its points twice, and the stated sigmas shrank by up to sqrt(2) (two hits each given
/// twice: K_T 0.073 % -> 0.050 %, its error then 3.9 sigma, not 2.7).
std::vector<BackboneTable> read_backbone_tables(const std::vector<std::filesystem::path>& paths,
                                                std::optional<Quantity> quantity);

}  // namespace jointlab::data
