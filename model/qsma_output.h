// The QSMA curve as the CSV `jointlab qsma` writes (contract: force_amplitude,
// modal_amplitude, frequency_hz, damping_ratio, max_slip, ringdown_frequency_hz,
// ringdown_damping_ratio, then harmonic_damping_ratio), amplitude increasing, atomically.
#pragma once

#include <filesystem>
#include <vector>

#include "jointlab/model/qsma.h"

namespace jointlab::model {

/// Writes `curve` as the qsma command's CSV at `path` (atomically).
void write_qsma_csv(const std::filesystem::path& path, const std::vector<QsmaPoint>& curve);

}  // namespace jointlab::model
