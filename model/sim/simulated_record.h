// A simulated impact ring-down as a test record (contract: "Test files"), the input of
// `jointlab process`.
//
// Channels: the sensors' accelerations in m/s^2 (unit "[m/s^2]"), named after their DOF:
// acc_<node>_<component> for a label "node:c" (c = 1..6 written x, y, z, rx, ry, rz, other
// components as given), acc_<index> without labels; optionally the hammer force
// "hammer [N]". Metadata ("# key: value"): model, impact_dof, force_N, pulse_s,
// pulse_start_s, substeps, dt_s, noise, seed, energy_closure (the writer adds fs and t0).
// Noise: independent white Gaussian samples added to each channel, standard deviation
// noise * max|channel| (its noise-free peak), from a std::mt19937_64 seeded with `seed`.
#pragma once

#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "jointlab/data/record.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/sim/ringdown_simulation.h"

namespace jointlab::model {

/// A 0-based index ("12") or a "node:component" label ("9001:3") of the model's DOFs;
/// InputError naming `what` (the argument) when it is neither.
Eigen::Index resolve_dof(const Model& model, const std::string& text, const std::string& what);

/// The DOF's label when the model has labels, else its index ("9001:3", "12").
std::string dof_name(const Model& model, Eigen::Index dof);

/// The channel name of a sensor DOF ("acc_9001_z", "acc_12").
std::string sensor_channel_name(const Model& model, Eigen::Index dof);

/// How a simulated response becomes a test record.
struct RecordOptions {
  std::string model_name;      ///< the "# model:" metadata (the model file as given)
  double noise = 0;            ///< noise standard deviation / channel peak, >= 0
  std::uint64_t seed = 1;      ///< noise generator seed
  bool include_force = false;  ///< also write the hammer force channel

  /// What is wrong with these options, or "".
  std::string error() const;
};

/// InputError if two of `sensors` are one channel (checked before a simulation runs).
void check_sensors(const Model& model, const std::vector<Eigen::Index>& sensors);

/// The record of a simulated ring-down; InputError for bad options or duplicate sensors.
data::Record make_simulated_record(const Model& model, const SimulationOptions& simulation,
                                   const SimulatedResponse& response,
                                   const SimulationSummary& summary, const RecordOptions& options);

}  // namespace jointlab::model
