// Measured data for updating, from a `jointlab process` output directory as
// data::read_process_run() reads its summary.json (data/process_folder.h): per file (hit) its
// bands k = 1, 2, ... with the reference channel, the linear frequency [Hz] and the operating
// shape, and one backbone CSV per channel and band (columns time_s, amplitude, frequency_hz,
// damping_ratio, frequency_std_hz, damping_std, ...; amplitude in the SI unit of its
// "amplitude_quantity"). Linear data: band k becomes one measured mode. Its frequency is the mean
// over the files that report a linear frequency for k (where they disagree and fall with the hit's
// level, the lowest-level files', with the uncertainty the spread shows: linear_spread()); its
// shape at the sensors (sensors.h, sensor order) is the operating shape of the file that measured
// most of the sensor channels (the first such file), 0 at sensors no file measured. A band
// no file gives a linear frequency for is left out.
//
// Backbones: band_outputs() names the backbone files of band k on the selected channels (several
// hits and channels give several curves; by default one channel for every hit, band_channel());
// the caller reads each (data::read_process_backbone, at the edge) and makes it a curve
// (measured_backbone). Nothing here opens a file (style.md 14).
#pragma once

#include <complex>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/data/backbone_table.h"
#include "jointlab/data/modes_table.h"
#include "jointlab/data/process_folder.h"
#include "jointlab/model/model_file.h"

namespace jointlab::correlate {

/// One file's (hit's) linear frequency of a mode: the backbone's straight-line fit at the lowest
/// amplitude it read, not an extrapolation to zero amplitude.
struct LinearReading {
  std::string source;       ///< the file or hit
  double frequency_hz = 0;  ///< its linear frequency [Hz]
  double std_hz = 0;        ///< its stated one-sigma uncertainty [Hz] (0: not stated)
  double level = 0;         ///< the lowest amplitude it was read at [SI] (0: unknown)
};

/// What the readings of one mode say about its linear frequency.
struct LinearSpread {
  double frequency_hz = 0;  ///< the value to fit (0: no reading)
  /// The relative one-sigma uncertainty the readings show (0: one reading, or they agree within
  /// their stated uncertainties)
  double relative_std = 0;
  bool falls_with_level = false;  ///< the frequency falls as the level rises (joint slips)
  std::string note;  ///< the warning, where relative_std exceeds the update's (else "")
};

/// The linear frequency of mode `mode` (a name for the note) from its readings. Where they
/// disagree by more than their stated uncertainties allow (their chi-square over the mean
/// beyond its 3-sigma point; unstated: they disagree) the relative uncertainty is their
/// standard deviation over the mean. Where besides they fall as the level rises (a straight
/// line in ln level with a slope below 0 by more than 3 of its sigmas, levels a factor 2 apart
/// or more), the joint still slips at the lowest amplitudes read: every reading is below the
/// linear frequency, and the relative uncertainty is their range over the value. Where that
/// uncertainty exceeds `frequency_std` (the update's), the value is the mean of the lowest-level
/// readings (levels within a factor 2 of the lowest) where they fall with level, else the mean
/// of all, and `note` says so, naming the readings and their levels (in `unit`); elsewhere the
/// value is the mean of all.
LinearSpread linear_spread(const std::string& mode, const std::vector<LinearReading>& readings,
                           double frequency_std, const std::string& unit = "");

/// Linear modal data per band at the sensors; `bands` (if given) receives the band number of
/// each measured mode. Each band's frequency and its uncertainty are linear_spread()'s over
/// the files that give one (against `frequency_std`, the update's); its note goes to the
/// warnings. InputError when no band has a linear frequency or no sensor channel appears in
/// any operating shape.
MeasuredModes measured_modes(const data::ProcessRun& run, const std::vector<Sensor>& sensors,
                             std::vector<int>* bands = nullptr,
                             double frequency_std = LinearUpdateOptions{}.frequency_std);

/// A backbone of `kind` measured at sensor index `sensor` with `points` points, all zero.
MeasuredBackbone sized_backbone(BackboneKind kind, int sensor, Eigen::Index points);

/// A backbone table (data/backbone_table.h, read at the edge) as a measured ring-down backbone:
/// at sensor index `sensor`, or of the modal amplitude q when `sensor` is negative.
MeasuredBackbone measured_backbone(const data::BackboneTable& table, int sensor);

/// Backbone tables as curves (measured_backbone at `sensor`), and the files among them whose
/// amplitude header gives no unit (SI assumed; jointlab's own backbones, SI, are not named).
struct BackboneCurves {
  std::vector<MeasuredBackbone> curves;  ///< one per table, in order
  std::vector<std::string> unitless;     ///< tables read without an amplitude unit
};
/// The tables (data::read_backbone_tables, read at the edge) as curves at `sensor`.
BackboneCurves backbone_curves(const std::vector<data::BackboneTable>& tables, int sensor);

/// The channel a band's backbones are read at where none is chosen, and a note where the hits'
/// reference channels differ or a hit has no backbone at that channel.
struct BandChannel {
  std::string channel;  ///< "" when no hit's reference channel of the band is a sensor
  std::string note;     ///< which channel was taken over which, and the hits it leaves out
};

/// Where no channel is chosen, every hit of band `band` is read at one channel, so that their
/// curves share one amplitude (the hits' scatter summary compares them point by point): of the
/// sensors that are some hit's reference channel, the one with a backbone in the most hits,
/// then the one most hits name, then the first in the sensors file.
BandChannel band_channel(const data::ProcessRun& run, const std::vector<Sensor>& sensors, int band);

/// One backbone file of a process run, with the index of its channel's sensor.
struct BandOutput {
  const data::ProcessOutput* output = nullptr;  ///< the file (in the run it was taken from)
  int sensor = -1;                              ///< its channel's sensor
};

/// The backbone files of band `band` on the selected channels (empty: band_channel's, its note
/// in `note`), in the run's order; InputError when a selected channel is not a sensor or no
/// backbone is found.
std::vector<BandOutput> band_outputs(const data::ProcessRun& run,
                                     const std::vector<Sensor>& sensors, int band,
                                     const std::vector<std::string>& channels,
                                     std::string* note = nullptr);

/// Below this MPC (mac.h) a complex shape of a modes table is realised with a warning: 0.9,
/// the usual floor for a normal mode of a lightly damped structure (two equal entries 18 deg
/// apart in phase).
inline constexpr double kMpcPoor = 0.9;
/// Below this MPC a complex shape of a modes table is refused: 0.5, two equal entries 45 deg
/// apart in phase, the imaginary part left out holding 15 % of the shape or more.
inline constexpr double kMpcRefused = 0.5;

/// The channel names of `sensors`, in order: what data::read_modes_table() reads the shape
/// columns against.
std::vector<std::string> channels_of(const std::vector<Sensor>& sensors);

/// Measured linear modes from a modes table (data/modes_table.h, read at the edge against
/// channels_of(sensors)): each complex shape realised (mac.h realise(): the real part at the
/// phase that maximises it): with MPC below kMpcRefused InputError "file:line:" naming the mode,
/// below kMpcPoor the MeasuredModes' warnings name it and its MPC. A mode without any shape entry
/// is paired by frequency alone (linear_update.h).
MeasuredModes measured_modes(const data::ModesTable& table, const std::vector<Sensor>& sensors);

/// The measured column MAC-paired (mac.h) with elastic mode `mode` of the model at its linear
/// stiffness, or -1 when that mode pairs with none.
int measured_mode_of(const model::Model& model, const std::vector<Sensor>& sensors,
                     const MeasuredModes& measured, int mode, double mac_threshold);

/// How a measured mode's shape matches a model mode at the sensors.
struct ModeShapeMatch {
  double mac = 0;       ///< MAC of the measured shape with the asked model mode
  int best_mode = 0;    ///< the elastic model mode (1-based) of highest MAC
  double best_mac = 0;  ///< its MAC
  /// Where the MAC with `mode` is below 0.6 and the shape has entries at three sensors or more:
  /// the one or two sensors whose reversal raises it the most, when that reaches 0.9 (a sign
  /// the sensors file may have wrong); empty otherwise.
  std::vector<int> reversed;
  double reversed_mac = 0;  ///< the MAC with `mode` with `reversed` reversed
};

/// The MAC at the sensors of measured column `column` against elastic mode `mode` (1-based) of
/// the model at its linear stiffness, and the elastic mode it matches best.
ModeShapeMatch mode_shape_match(const model::Model& model, const std::vector<Sensor>& sensors,
                                const MeasuredModes& measured, int column, int mode);

/// The report's line on what a backbone table's amplitudes were read as: mode `mode`'s QSMA modal
/// amplitude q (quantity "modal"; `defaulted`: no amplitude quantity given), else `quantity` at
/// the model DOF `dof_name` (given as `dof`). A sensor's displacement read as modal scales F_S by
/// the shape's value there and fits as well (a 2.65 times F_S, reduced chi-square 0.027), so only
/// the report can say it. Measured amplitudes are zero to peak; `unitless` names the tables
/// whose amplitude header gives no unit (SI assumed: g or mm read so scale F_S and pass every
/// check; BackboneCurves::unitless), none for none.
std::string amplitude_reading(int mode, const std::string& quantity, bool defaulted,
                              const std::string& dof_name, const std::string& dof,
                              const std::vector<std::string>& unitless = {});

/// The tables among `unitless` (files whose amplitude header gives no unit) read in the SI unit
/// of `quantity` ("velocity": m/s): "a.csv, b.csv give no unit in the amplitude header, so m/s
/// is assumed (...)", as update-iwan's and run's reports say it; "" for none.
std::string unitless_amplitudes(const std::vector<std::string>& unitless,
                                const std::string& quantity);

}  // namespace jointlab::correlate
