// The Iwan fit as `update-iwan`, the Python module's update_iwan() and `run` make it: the search
// box from the user's LO:HI ranges over the default (correlate::default_iwan_bounds), the
// options checked, frequencies no parameter set can reach refused with the numbers, beta held
// first and freed where the data reach macroslip, and a fit that could evaluate no parameter
// set refused rather than returned as a result. One place, so that the three give the same
// parameters and the same refusals for the same backbones and settings.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "jointlab/correlate/iwan_update.h"
#include "jointlab/model/iwan.h"

namespace jointlab::campaign {

/// A LO:HI search range given by the user.
using IwanRange = std::optional<std::pair<double, double>>;

/// The LO:HI search ranges of the Iwan parameters as update-iwan's options name them (absent:
/// the default box of correlate::default_iwan_bounds).
struct IwanRanges {
  IwanRange fs = std::nullopt;     ///< --fs-range, F_S [N]
  IwanRange gamma = std::nullopt;  ///< --gamma-range, K_T / K_s
  IwanRange chi = std::nullopt;    ///< --chi-range
  IwanRange beta = std::nullopt;   ///< --beta-range

  /// InputError naming the option ("--chi-range -1:0.5: need LO < HI with both chi > -1") for
  /// a range outside its parameter's domain (model::iwan_parameter_domain), and for
  /// a beta range that reaches 0 (beta is searched on a log scale).
  void check() const;

  /// The search box: these ranges over the default around the starting parameters `start`.
  correlate::IwanBounds bounds(const model::IwanParameters& start) const;
};

/// The fit `run` and `update-iwan` both make: beta held first (at options.fixed_beta, else
/// at the objective's start), then, when that fit puts the top of the data past phi_max and
/// beta is not held by the options, freed for a second fit; the better of the two, with the
/// evaluations and the history of both (the second's evaluations numbered on from the first's).
/// `say` (may be empty) hears the first fit's report before the second.
correlate::IwanUpdateSummary fit_iwan(const correlate::IwanObjective& objective,
                                      const correlate::IwanUpdateOptions& options,
                                      const std::function<void(const std::string&)>& say);

/// fit_iwan() in the box `ranges` gives, refused (InputError starting with `command`, then
/// `data_name` where the data are at fault and it is not empty) where the options are
/// inconsistent, where the measured frequencies lie outside what any parameter set in the box
/// reaches (correlate::unreachable_frequencies), and where no parameter set in the box gives a
/// QSMA curve over the measured amplitudes. `ranges` is checked first.
correlate::IwanUpdateSummary checked_fit_iwan(const correlate::IwanObjective& objective,
                                              correlate::IwanUpdateOptions options,
                                              const IwanRanges& ranges, const std::string& command,
                                              const std::string& data_name,
                                              const std::function<void(const std::string&)>& say);

/// An Iwan fit's progress callback (IwanUpdateOptions::progress) that calls `line` at the first
/// evaluation at or past each multiple of `every` (the local solves' count steps over some: a
/// test on exact multiples of 250 said nothing in a 423-evaluation fit) and `between` (may be
/// empty) at the others; a count that starts again (the fit with beta freed) starts again.
std::function<void(int, double)> progress_every(int every, std::function<void(int, double)> line,
                                                std::function<void()> between = {});

/// The report's lines of a Pareto front (correlate::pareto_front), as update-iwan prints them and
/// the Python module returns them: per gamma the parameters, the linear error and the backbone
/// cost, then each measured mode's linear error; "" for an empty front.
std::string pareto_report(const std::vector<correlate::ParetoPoint>& front);

}  // namespace jointlab::campaign
