// Result tables of the updating commands (update-linear, update-iwan) as CSV text: values, which
// the commands write (data::write_file_atomically, at the edge; correlate/ opens no file).
//
// parameters.csv, one row per parameter:
//   linear: name,initial,final,relative_std,sensitivity,identifiable,smallest_within_tolerance
//     (relative_std empty where none is stated; identifiable 0 for a flat parameter and for
//     sets acting together, ParameterReport::identifiable(); smallest_within_tolerance empty
//     unless the tolerance formulation lowered it);
//   Iwan:   name,initial,final,relative_std,identifiable,held,at_bound  for Fs [N], Kt [N/m],
//     chi, beta, gamma = K_T / K_s and, when fitted, modal_ratio (relative_std from the
//     covariance of iwan_update.h, empty where held or unknown; identifiable 1 when
//     0 < relative_std <= identifiable_std (for chi, its sigma <= identifiable_std (1 + chi), the
//     damping's slope over ln amplitude) and, for Fs and beta, the data reach macroslip;
//     held 1 for a parameter the options held; at_bound "lower" or "upper" for a parameter the
//     fit left at a bound of its search range, else empty).
// history.csv: linear  iteration,objective,<set>...  (iteration 0: the start; every set's
//                      stiffness after each iteration, then each feasible step of the
//                      smallest rule);
//              Iwan    evaluation,objective,best.
// modes.csv (linear): measured,frequency_hz,model_mode,model_frequency_hz,error,mac per
//   measured mode (error relative, model columns empty when unpaired).
// mac.csv (linear): measured,model1,...: the MAC matrix at the result (model modes up to 1.5x
//   the highest measured frequency, and two past the highest paired one).
// sweeps.csv (linear): set,factor,stiffness,rms_error,error1,...: the one-at-a-time sweeps.
// pareto.csv (Iwan, --pareto): gamma,Fs,Kt,chi,beta,linear_error,backbone_cost,dominated,
//   linear_error1,...: every measured linear mode's relative error (empty: unpaired).
// Numbers print with 10 significant digits; a non-finite number is a bug upstream and
// throws std::logic_error (never written as NaN).
#pragma once

#include <string>
#include <vector>

#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/linear_update.h"

namespace jointlab::correlate {

/// The linear update's parameters.csv.
std::string linear_parameters_csv(const LinearUpdateSummary& s);

/// The linear update's history.csv.
std::string linear_history_csv(const LinearUpdateSummary& s);

/// The linear update's modes.csv (per-mode frequency errors).
std::string linear_modes_csv(const LinearUpdateSummary& s);

/// Model columns mac.csv shows: two past the highest paired model mode, and every model mode up
/// to 1.5 times the highest measured frequency.
int mac_columns(const LinearUpdateSummary& s);

/// The linear update's mac.csv (the MAC matrix at the result).
std::string mac_matrix_csv(const LinearUpdateSummary& s);

/// The linear update's sweeps.csv (one-at-a-time sweeps, every mode's error).
std::string linear_sweeps_csv(const LinearUpdateSummary& s);

/// One row of the Iwan update's parameters.csv.
struct IwanParameterRow {
  std::string name;           ///< Fs, Kt, chi, beta, gamma or modal_ratio
  double initial = 0;         ///< at the start
  double final = 0;           ///< at the result
  double relative_std = -1;   ///< relative one-sigma uncertainty; < 0: none stated
  bool identifiable = false;  ///< 0 < relative_std <= identifiable_std, and separately identified
  bool held = false;          ///< held as the options asked
  int at_bound = 0;           ///< -1: at the lower bound of its range, +1: upper, 0: inside
  std::string note;           ///< IwanUpdateSummary::parameter_note()
};

/// The rows of the Iwan update's parameters.csv: Fs, Kt, chi, beta, modal_ratio when fitted, then
/// gamma (K_T / K_s, when known; last since 79f1138); a parameter is identifiable when its relative
/// standard deviation is known and at most identifiable_std (chi: its sigma at most
/// identifiable_std times 1 + chi, the slope it gives the damping) and, for Fs and beta, the data
/// reach macroslip. The file and the Python module's result both read them.
std::vector<IwanParameterRow> iwan_parameter_rows(const IwanUpdateSummary& s,
                                                  double identifiable_std = 0.5);

/// The Iwan update's parameters.csv (iwan_parameter_rows()).
std::string iwan_parameters_csv(const IwanUpdateSummary& s, double identifiable_std = 0.5);

/// The Iwan update's history.csv.
std::string iwan_history_csv(const IwanUpdateSummary& s);

/// The Pareto front as pareto.csv.
std::string pareto_csv(const std::vector<ParetoPoint>& front);

}  // namespace jointlab::correlate
