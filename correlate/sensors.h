// Sensors: which model DOF each measured channel sees, with its sign.
//
// A sensor i reads s_i * u[d_i]: the model DOF d_i (0-based matrix index, a translation in m
// or a rotation in rad) along the channel's measuring direction, with s_i = +1 when the
// channel's positive direction is the DOF's positive direction and -1 when opposite.
// The model shape of mode m at the sensors is therefore Phi_s(i, m) = s_i phi_m[d_i].
//
// The sensors file (channel,dof[,sign]) is read by data/sensors_file.h; sensors_of() resolves
// its DOFs against a model.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/data/sensors_file.h"
#include "jointlab/model/model_file.h"

namespace jointlab::correlate {

/// One measured channel and the model DOF it sees.
struct Sensor {
  std::string channel;   ///< channel name as in the test files
  Eigen::Index dof = 0;  ///< 0-based model matrix index
  double sign = 1.0;     ///< +1 or -1: the channel reads sign * u[dof]
};

/// The sensors of a sensors file (data/sensors_file.h, read at the edge) against a model: each
/// row's dof resolved (labels through model.dof_labels, with the fix named where a label is
/// written as other tools write it); InputError naming the file and line.
std::vector<Sensor> sensors_of(const data::SensorsFile& file, const model::Model& model);

/// Phi_s(i, m) = s_i shapes(d_i, m): model shapes (one column per mode) at the sensors.
Eigen::MatrixXd shapes_at_sensors(const std::vector<Sensor>& sensors,
                                  const Eigen::Ref<const Eigen::MatrixXd>& shapes);

/// Index of the sensor named `channel`, or -1.
int find_sensor(const std::vector<Sensor>& sensors, const std::string& channel);

}  // namespace jointlab::correlate
