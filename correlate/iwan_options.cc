// The settings of the Iwan update: the default search box and what is wrong with a set of options.
#include "jointlab/correlate/iwan_options.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

namespace jointlab::correlate {

IwanBounds default_iwan_bounds(const model::IwanParameters& start) {
  IwanBounds b;
  b.Fs_min = start.Fs / 30;
  b.Fs_max = start.Fs * 30;
  b.gamma_min = 0.05;
  b.gamma_max = 2;
  // A start outside -0.95:0 (a model file may hold any chi > -1) widens the range to hold it,
  // so that the search starts where the model is rather than from a box without its start.
  b.chi_min = std::min(-0.95, start.chi);
  b.chi_max = std::max(0.0, start.chi);
  b.beta_min = 0.01;
  b.beta_max = 100;
  return b;
}

std::string IwanUpdateOptions::error() const {
  const IwanBounds& b = bounds;
  if (!(b.Fs_min > 0 && b.Fs_min < b.Fs_max)) return "bounds: 0 < Fs_min < Fs_max";
  if (!(b.gamma_min > 0 && b.gamma_min < b.gamma_max)) return "bounds: 0 < gamma_min < gamma_max";
  if (!(b.chi_min > -1 && b.chi_min < b.chi_max)) return "bounds: -1 < chi_min < chi_max";
  if (!(b.beta_min > 0 && b.beta_min < b.beta_max)) return "bounds: 0 < beta_min < beta_max";
  if (!(fixed_gamma >= 0)) return "fixed_gamma must be >= 0";
  if (fixed_beta && !(*fixed_beta >= 0 && std::isfinite(*fixed_beta)))
    return "fixed_beta must be a finite number >= 0";
  if (samples < 2) return "samples must be >= 2";
  if (!(contraction > 0 && contraction < 1)) return "contraction must be in (0, 1)";
  if (max_evaluations < samples) {
    return fmt::format(
        "the evaluation budget (--evaluations, max_evaluations) {} must be at least the samples "
        "of one round ({})",
        max_evaluations, samples);
  }
  if (fit_linear_damping && !(linear_damping_max > 0 && linear_damping_max < 1))
    return "linear_damping_max must be in (0, 1)";
  if (local_starts < 1) return "local_starts must be >= 1";
  if (threads < 0) return "threads must be >= 0 (0: every core)";
  if (!(frequency_floor > 0) || !(damping_floor > 0)) return "floors must be > 0";
  return "";
}

}  // namespace jointlab::correlate
