// The Iwan update's linear-part sensitivity (internal): how far an error of the rest of the model
// moves the parameters at a converged result, which no residual shows where K_T takes it up.
#pragma once

#include <vector>

#include "jointlab/correlate/iwan_coordinates_detail.h"
#include "jointlab/correlate/iwan_update.h"

namespace jointlab::correlate::iwan_detail {

/// IwanUpdateSummary::linear_part_sensitivity and frequency_per_stiffness at the result v (the
/// search's parameters) and z, over the free parameters `free` (indices 0-3, 4 for a fitted Z):
/// at the minimum the cost's gradient J^T r stays 0 as the structure's stiffness K moves by a
/// factor e^s, so dx/ds = -(J^T J)^-1 J^T dr/ds (Gauss-Newton: the residuals' second derivatives,
/// of the order of the residuals, left out), J and dr/ds central differences (steps 1e-4 in x, as
/// the covariance, and 1e-4 in s); divided by d ln f_R / ds, mode R the first target's, at the
/// result's K_T. False where a residual or mode cannot be evaluated or J^T J is singular.
bool linear_part_sensitivity(const IwanObjective& objective, const std::vector<int>& free,
                             const Vec4& v, double z, IwanUpdateSummary& s);

}  // namespace jointlab::correlate::iwan_detail
