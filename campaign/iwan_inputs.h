// The measured side of `update-iwan` and `compare`: a `process` folder with its sensors (and
// stepped-sine folders), or plain backbone tables (data/backbone_table.h) of a modal amplitude or
// of a quantity at a model DOF, turned into the Iwan update's targets (campaign/iwan_targets.h
// for a process folder, as `run` builds them). Argument handling only: the readers and the
// targets are library code. The command line (update-iwan, compare) and the Python module
// read them here.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"

namespace jointlab::campaign {

/// The options naming the measured backbones.
struct IwanInputArgs {
  std::string model, measured, sensors;
  std::vector<std::string> modes, channels, stepped_sine;
  std::vector<std::string> backbones;  ///< --backbone tables
  std::string amplitude, dof;          ///< --amplitude, --dof (of the --backbone tables)
  std::string stepped_sine_channel;
  int stepped_sine_mode = 0;
};

/// A `--mode R[:BAND]` of a process folder: the band whose measured shape must look like model
/// mode R (checked against the updated model).
struct BandOfMode {
  std::string spec;  ///< as given ("1:2")
  int mode = 0;      ///< elastic model mode R
  int band = 0;      ///< the measured band
  int column = -1;   ///< its column in IwanInputs::measured
};

/// The measured backbones as targets.
struct IwanInputs {
  std::vector<correlate::Sensor> sensors;      ///< the sensors (one DOF for --dof, none: modal)
  std::vector<correlate::IwanTarget> targets;  ///< the fitted modes' targets
  correlate::AmplitudeQuantity amplitude = correlate::AmplitudeQuantity::kVelocity;
  bool modal = false;                                ///< amplitudes are modal (q)
  std::optional<correlate::MeasuredModes> measured;  ///< the measured linear modes (process)
  std::string data_name;                             ///< for messages
  std::string amplitude_note;     ///< --backbone: what the amplitudes were read as, for the report
  std::vector<BandOfMode> bands;  ///< each process --mode's band
  std::string slip_screen;  ///< several process modes: per mode, the points the slip screen left
  /// Which channel the hits were read at where their reference channels differ, and which hits
  /// the scatter summary left out as outliers; for the report.
  std::vector<std::string> curve_notes;
};

/// Reads the measured side named by `a` against model `m`; InputError prefixed by `command`.
IwanInputs read_iwan_inputs(const model::Model& m, const IwanInputArgs& a,
                            const std::string& command);

/// One line for each process --mode whose band's measured shape does not look like that mode of
/// the `updated` model at the sensors (MAC below the pairing's 0.6): the band, or the sensors
/// file, may belong to another mode. Empty for backbone tables.
std::vector<std::string> band_shape_warnings(const model::Model& updated, const IwanInputs& in);

/// Per Iwan set (named as in the model file, "iwan.<name>", in the order first met), its share
/// of elastic mode `mode`'s joint dissipation per cycle in `m` as given at modal amplitude `q`:
/// each Iwan element slipping |B phi_R| q, as the linear mode moves it (model::Iwan's Masing
/// dissipation, past phi_max too). Shares sum to 1; empty where the mode slips no Iwan element.
/// `linear`: m's linear modes (model::linear_modes of its linear stiffness).
std::vector<std::pair<std::string, double>> iwan_set_shares(const model::Model& m,
                                                            const model::LinearModes& linear,
                                                            int mode, double q);

/// One line for each target whose joint dissipation in `m` as given comes mostly from Iwan sets
/// other than `set` over its measured amplitudes (the fitted set's share below one half at the
/// lowest and the highest, read as modal amplitudes through the linear mode's shape at each
/// curve's sensor): the fit then moves `set` to take up what the held sets' values miss, and
/// its residuals, sigmas and advice read that misfit as this set's. `option` is how the advice
/// names the set to fit, "{}" standing for it ("--set {}"; run: "sets = [\"{}\"] in
/// [update.iwan]").
std::vector<std::string> set_share_warnings(const model::Model& m, const std::string& set,
                                            const std::vector<correlate::Sensor>& sensors,
                                            const std::vector<correlate::IwanTarget>& targets,
                                            correlate::AmplitudeQuantity amplitude,
                                            const std::string& option);

/// update-iwan's report as the command prints it and the Python module returns it: the fit's
/// (IwanUpdateSummary::report()), what the amplitudes were read as, the bands' shapes in the
/// `updated` model (band_shape_warnings), the sets that carry the modes' joint dissipation in
/// the `given` one (set_share_warnings, the advice naming a set as `set_option`) and the Pareto
/// front's lines (pareto_report). `warnings` (if given) receives the band-shape and set-share
/// lines as they stand in it.
std::string update_iwan_report(const correlate::IwanUpdateSummary& s, const model::Model& given,
                               const model::Model& updated, const std::string& set,
                               const IwanInputs& in,
                               const std::vector<correlate::ParetoPoint>& front,
                               const std::string& set_option = "--set {}",
                               std::vector<std::string>* warnings = nullptr);

/// True when every target has a measured linear frequency and mode R of `m` (joints at K_T) lies
/// within `tolerance` (relative) of it: the model's linear part matches the measured linear
/// frequencies (update-linear's result), which update-iwan states
/// (IwanUpdateOptions::linear_part_updated) instead of sending to update-linear. The default is
/// three times update-linear's frequency uncertainty (0.1 %): its result with degrees of freedom
/// left misses a mode by about that (one set fitted to two modes of the example beam: 0.02 %,
/// which 1e-4 called not updated, and update-iwan sent the user back to update-linear).
bool linear_part_matches(const model::Model& m, const std::vector<correlate::IwanTarget>& targets,
                         double tolerance = 3e-3);

}  // namespace jointlab::campaign
