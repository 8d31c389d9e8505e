// The QSMA curve as the CSV `jointlab qsma` writes (contract: force_amplitude,
// modal_amplitude, frequency_hz, damping_ratio, max_slip, ringdown_frequency_hz,
// ringdown_damping_ratio, then harmonic_damping_ratio), amplitude increasing, atomically.
#pragma once

#include <filesystem>
#include <vector>

#include "jointlab/data/table_writer.h"
#include "jointlab/model/qsma.h"

namespace jointlab::model {

/// The qsma command's columns of `curve`, named as in its CSV (the Python module returns them).
data::Table qsma_table(const std::vector<QsmaPoint>& curve);

/// Writes `curve` as the qsma command's CSV at `path` (atomically).
void write_qsma_csv(const std::filesystem::path& path, const std::vector<QsmaPoint>& curve);

}  // namespace jointlab::model
