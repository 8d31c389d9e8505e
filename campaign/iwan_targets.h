// The measured targets of an Iwan update, built one way for `jointlab run` and
// `jointlab update-iwan` (docs/update-iwan.md, docs/run.md).
//
// Per mode, its measured backbones (one per hit and channel) become one IwanTarget:
// - Hits flagged by the mode's scatter summary (scatter.h) are left out when the summary's
//   options exclude outliers, as they are left out of its bins.
// - Each point weighs by the scatter between hits in its amplitude bin (the bin's standard
//   deviation of frequency and of damping) where the bin holds at least three curves; in bins
//   of fewer (a standard deviation from two values has one degree of freedom and can fall far
//   below either hit's own noise) by the point's own uncertainty as `process` reports it.
//   Where neither is known, 0 leaves the update's floor (correlate/iwan_update.h).
// - In a fitted mode, points where the other modes of the same hit still slip the joints
//   are left out: share_k(t) > max_slip_share (correlate/mode_interference.h), the other
//   modes' slip from their backbones of the same hit, through the starting model's mode
//   shapes. A mode that is not fitted keeps every point (its cost is only reported).
// - Stepped-sine backbones (ModeBackbones::kinds) keep every point: a steady state at one
//   level excites the one mode.
// A backbone left with fewer than two points is dropped; a mode with no backbone gives no
// target.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "jointlab/campaign/scatter.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/correlate/sensors.h"
#include "jointlab/model/model_file.h"

namespace jointlab::campaign {

/// The measured backbones of one mode.
struct ModeBackbones {
  std::string name;                ///< the mode's name, for messages
  int model_mode = 0;              ///< elastic model mode R (1-based); 0: none (no target)
  bool fitted = true;              ///< the update fits it (else only its cost is reported)
  double linear_frequency_hz = 0;  ///< measured linear frequency (0: unknown)
  std::vector<Curve> curves;       ///< backbones; Curve::id names the hit
  std::vector<int> sensors;        ///< per curve: its sensor index
  std::vector<correlate::BackboneKind> kinds;     ///< per curve (empty or no entry: ring-down)
  std::vector<Eigen::VectorXd> frequency_std_hz;  ///< per curve: each point's own k sigma_f [Hz]
                                                  ///< (process's; empty vector or entry: none)
  std::vector<Eigen::VectorXd> damping_std;       ///< per curve: each point's own k sigma_z
  /// Per curve: k of its own std, as written (process and stepped-sine: 3 by default; a table
  /// without a coverage_factor column: 1); no entry: 1. The fit weighs by std / k.
  std::vector<double> coverage;
  ScatterSummary scatter;  ///< the scatter summary of `curves`
  /// Backbone tables: which of them give no amplitude unit (SI assumed), for the report; "" none.
  std::string amplitude_note;
  /// process runs read at one channel where the hits' reference channels differ, or with a hit
  /// without a backbone there (correlate::band_channel's note); "" otherwise.
  std::string channel_note;
};

/// Settings of iwan_targets().
struct IwanTargetOptions {
  /// Other modes' largest share of the joint slip a fitted point may carry: at 5 % the
  /// excess damping it causes (about half the share in the example campaign) stays below the
  /// hit-to-hit scatter of the damping.
  double max_slip_share = 0.05;
  correlate::AmplitudeQuantity amplitude =
      correlate::AmplitudeQuantity::kVelocity;  ///< of the curves
};

/// The targets of one update.
struct IwanTargets {
  std::vector<correlate::IwanTarget> fitted;                    ///< the fitted modes' targets
  std::vector<std::pair<size_t, correlate::IwanTarget>> every;  ///< (mode index, target), all
  Eigen::Index screened = 0;  ///< points left out where other modes slip the joints
  /// Per mode (the order of `modes`): points it had and points the slip screen left out.
  std::vector<std::pair<Eigen::Index, Eigen::Index>> points_screened;
  /// Per mode (the order of `modes`): the hits whose backbone the slip screen left with fewer
  /// than two points, so that the fit leaves them out.
  std::vector<std::vector<std::string>> hits_screened_out;
  /// "; every point but at most one of L5_hit1 and L5_hit2 ..., so those hits are left out of
  /// the fit" for mode `k`, "" where the screen left every hit in.
  std::string hits_screened_out_text(size_t k) const;
  /// One line per fitted mode with a screen: "mode 1:1: 12 of 480 points left out ...".
  std::string screen_report(const std::vector<ModeBackbones>& modes) const;
  /// Where no fitted target is left because the slip screen (at `max_slip_share`) left out every
  /// point of every fitted mode: why, with the points per mode and what to do; "" otherwise.
  std::string screened_out(const std::vector<ModeBackbones>& modes, double max_slip_share) const;
  size_t curves() const;  ///< backbones over the fitted targets
};

/// Builds the targets of `modes` against `model` (the model the update starts from) with the
/// sensors' DOFs; InputError when a mode or sensor index is out of range.
IwanTargets iwan_targets(const model::Model& model, const std::vector<correlate::Sensor>& sensors,
                         const std::vector<ModeBackbones>& modes, const IwanTargetOptions& options);

/// The backbones of band `band` (from 1) of a `process` run on the selected channels (empty:
/// each file's reference channel of the band), one curve per file and channel with its
/// time, and their scatter summary with `scatter`; InputError when a selected channel is not a
/// sensor or no backbone is found.
ModeBackbones process_run_backbones(const data::ProcessRun& run,
                                    const std::vector<correlate::Sensor>& sensors, int band,
                                    const std::vector<std::string>& channels,
                                    const ScatterOptions& scatter);

/// The backbones of a `stepped-sine` run (one curve per file, no time), all measured at sensor
/// index `sensor`, of kind stepped sine, and their scatter summary with `scatter`; InputError
/// when no file gave a backbone.
ModeBackbones stepped_sine_run_backbones(const data::SteppedSineRun& run, int sensor,
                                         const ScatterOptions& scatter);

}  // namespace jointlab::campaign
