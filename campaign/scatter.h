// Scatter between tests: several backbones (one per hit) of one mode, summarised on a
// log-spaced amplitude grid (method.md section 1, "Scatter between tests").
//
// Grid: bin edges a_k = 10^(k / n_d) for integer k (n_d = bins_per_decade), spanning the
// amplitudes of every curve, so that two campaigns with the same n_d share their edges.
// A curve's value in a bin is the mean of its points with a_k <= amplitude < a_(k+1).
// Per bin, over the n curves that reach it (n >= min_curves), of frequency and damping:
//   mean  m = (1/n) sum x_h,   standard deviation  s = sqrt(sum (x_h - m)^2 / (n - 1)),
//   confidence interval of the mean  m -/+ t_((1+c)/2, n-1) s / sqrt(n)   (Student t,
//   c = confidence, 0.95 by default).
// Hits that stand out: per hit, its mean relative deviation from the per-bin median over
// the bins it shares with at least two other curves, d_h = mean_b (x_h,b - med_b) / med_b,
// for frequency and for damping, and its linear frequency and damping relative to their
// medians. Each is turned into a robust z-score over the hits,
//   z_h = (d_h - median(d)) / max(1.4826 MAD(d), floor),
// MAD the median absolute deviation (1.4826 MAD estimates the standard deviation of
// Gaussian data; the floor keeps hits that agree to within the processing's own accuracy
// from being called outliers). A hit with any |z| > outlier_threshold is flagged; with
// exclude_outliers the bins and the linear spread leave flagged hits out (they stay listed).
// Units: amplitude as given (SI of the amplitude quantity), frequency in Hz, damping ratio
// as a fraction.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/correlate/curve.h"

namespace jointlab::campaign {

using correlate::Curve;

/// Settings of summarize_scatter().
struct ScatterOptions {
  int bins_per_decade = 5;         ///< bins per factor of ten in amplitude
  double confidence = 0.95;        ///< two-sided confidence level of the interval, in (0, 1)
  int min_curves = 2;              ///< bins reached by fewer curves are left out (>= 2)
  double outlier_threshold = 3.5;  ///< |robust z| above which a hit is flagged
  double frequency_floor = 2e-4;   ///< smallest robust spread of relative frequency deviations
  double damping_floor = 0.02;     ///< smallest robust spread of relative damping deviations
  bool exclude_outliers = true;    ///< leave flagged hits out of bins and linear spread
  /// Empty if usable, else what is wrong.
  std::string check() const;
};

/// Mean, standard deviation and confidence interval of one quantity over curves.
struct Statistic {
  int count = 0;       ///< values described
  double mean = 0;     ///< arithmetic mean
  double std = 0;      ///< sample standard deviation (n - 1); meaningless when n < 2
  double ci_low = 0;   ///< lower end of the confidence interval of the mean (n >= 2)
  double ci_high = 0;  ///< upper end of the confidence interval of the mean (n >= 2)
  /// Whether std and the interval exist: one value has no spread (not a spread of 0).
  bool has_spread() const { return count >= 2; }
};

/// One amplitude bin.
struct ScatterBin {
  double amplitude_low = 0;     ///< lower edge [SI]
  double amplitude_high = 0;    ///< upper edge [SI]
  double amplitude_center = 0;  ///< geometric centre sqrt(low * high) [SI]
  int curves = 0;               ///< curves counted in this bin
  int flagged = 0;              ///< flagged curves reaching the bin (left out if excluded)
  Statistic frequency_hz;       ///< natural frequency over the curves [Hz]
  Statistic damping;            ///< damping ratio over the curves
};

/// How one hit compares with the others.
struct HitDeviation {
  std::string id;                  ///< the hit
  std::string group;               ///< its group
  int bins = 0;                    ///< bins used for its deviations
  double frequency_deviation = 0;  ///< mean relative deviation from the bin medians
  double damping_deviation = 0;    ///< mean relative deviation from the bin medians
  double frequency_z = 0;          ///< robust z of frequency_deviation
  double damping_z = 0;            ///< robust z of damping_deviation
  bool has_linear = false;         ///< linear values present
  double linear_frequency_hz = 0;  ///< the hit's linear frequency [Hz]
  double linear_damping = 0;       ///< the hit's linear damping ratio
  double linear_frequency_z = 0;   ///< robust z of the linear frequency
  double linear_damping_z = 0;     ///< robust z of the linear damping
  bool outlier = false;            ///< any |z| above the threshold
  std::string reason;              ///< which z flagged it ("" when not flagged)
};

/// The scatter summary of one mode.
struct ScatterSummary {
  std::vector<ScatterBin> bins;    ///< amplitude increasing
  std::vector<HitDeviation> hits;  ///< in the order of the curves given
  int linear_count = 0;            ///< hits in the linear statistics
  Statistic linear_frequency_hz;   ///< spread of the hits' linear frequency [Hz]
  Statistic linear_damping;        ///< spread of the hits' linear damping ratio
  ScatterOptions options;          ///< the settings used
  /// Number of flagged hits.
  int outliers() const;
  /// A short paragraph for a person: bins, amplitude range, flagged hits, linear spread.
  std::string report() const;
};

/// Quantile t_(p, dof) of Student's t distribution (Boost.Math); InputError unless 0 < p < 1
/// and dof >= 1.
double student_t_quantile(double p, int dof);

/// Mean, standard deviation and confidence interval at `confidence` of the values.
Statistic describe(const std::vector<double>& values, double confidence);

/// Summarises the curves of one mode; InputError for options that do not check.
ScatterSummary summarize_scatter(const std::vector<Curve>& curves, const ScatterOptions& options);

/// Writes the bins as CSV (amplitude_low, amplitude_high, amplitude_center, curves, flagged,
/// frequency_mean_hz, frequency_std_hz, frequency_ci_low_hz, frequency_ci_high_hz,
/// damping_mean, damping_std, damping_ci_low, damping_ci_high), atomically.
void write_scatter_bins_csv(const std::filesystem::path& path, const ScatterSummary& s);

/// Writes the hits as CSV (hit, group, bins, deviations, z-scores, linear values, outlier,
/// reason), atomically.
void write_scatter_hits_csv(const std::filesystem::path& path, const ScatterSummary& s);

/// Writes the whole summary (settings, bins, hits, linear spread) as JSON, atomically;
/// `mode` names the mode in the file.
void write_scatter_json(const std::filesystem::path& path, const std::string& mode,
                        const ScatterSummary& s);

}  // namespace jointlab::campaign
