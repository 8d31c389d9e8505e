// The paper's figures of a linear update (Figures 2-4), drawn from its summary.
//
//   history.png    the objective (log) and every stiffness (log) against iteration: Figure 2
//                  and Table 1;
//   sweeps.png     one panel per set: each paired mode's frequency error [%] as the set alone
//                  moves by the sweep's factors, the mode followed by its shape, the result
//                  marked: Figure 3;
//   mac_start.png  the MAC at the start and at the result, test and model frequencies on the
//   mac.png        axes, the pairs framed: Figure 4.
#pragma once

#include <filesystem>

#include "jointlab/correlate/linear_update.h"

namespace jointlab::campaign {

/// Writes history.png, sweeps.png, mac_start.png and mac.png of `summary` into `dir`.
void write_linear_figures(const correlate::LinearUpdateSummary& summary,
                          const std::filesystem::path& dir);

}  // namespace jointlab::campaign
