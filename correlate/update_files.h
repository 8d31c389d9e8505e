// Result files of the updating commands (update-linear, update-iwan), written atomically.
//
// parameters.csv, one row per parameter:
//   linear: name,initial,final,relative_std,sensitivity,identifiable,smallest_within_tolerance
//     (relative_std 0 and identifiable 0 for a flat parameter; smallest_within_tolerance 0
//     unless the tolerance formulation lowered it);
//   Iwan:   name,initial,final,relative_std,identifiable  for Fs [N], Kt [N/m], chi, beta
//     (relative_std from the Gauss-Newton covariance, 0 where unknown; identifiable 1 when
//     0 < relative_std <= identifiable_std).
// history.csv: linear  iteration,objective  (iteration 0: the start);
//              Iwan    evaluation,objective,best.
// pareto.csv (Iwan, --pareto): gamma,Fs,Kt,chi,beta,linear_error,backbone_cost,dominated.
// Numbers print with 10 significant digits; a non-finite number is a bug upstream and
// throws std::logic_error (never written as NaN).
#pragma once

#include <filesystem>
#include <vector>

#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/linear_update.h"

namespace jointlab::correlate {

/// Writes the linear update's parameters.csv.
void write_linear_parameters(const std::filesystem::path& path, const LinearUpdateSummary& s);

/// Writes the linear update's history.csv.
void write_linear_history(const std::filesystem::path& path, const LinearUpdateSummary& s);

/// Writes the Iwan update's parameters.csv; a parameter is identifiable when its relative
/// standard deviation is known and at most identifiable_std.
void write_iwan_parameters(const std::filesystem::path& path, const IwanUpdateSummary& s,
                           double identifiable_std = 0.5);

/// Writes the Iwan update's history.csv.
void write_iwan_history(const std::filesystem::path& path, const IwanUpdateSummary& s);

/// Writes the Pareto front as pareto.csv.
void write_pareto(const std::filesystem::path& path, const std::vector<ParetoPoint>& front);

}  // namespace jointlab::correlate
