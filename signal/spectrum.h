// Amplitude spectrum of a record and its strongest peaks.
//
// The spectrum is one-sided and Hann-windowed, scaled so that a sinusoid
// A cos(2 pi f0 t) on a bin shows a peak of height A at f0 (amplitude, not
// power: |X_w[k]| * 2 / sum(w)). A record is zero-padded to a fast FFT size.
#pragma once

#include <complex>
#include <vector>

#include <Eigen/Core>

#include "jointlab/signal/band_analytic.h"

namespace jointlab::signal {

/// One-sided amplitude spectrum: frequency [Hz] and amplitude [unit of the record].
struct AmplitudeSpectrum {
  Eigen::VectorXd frequency_hz;  ///< bin frequencies
  Eigen::VectorXd amplitude;     ///< Hann-windowed sinusoid amplitude per bin
};

/// Hann-windowed amplitude spectrum of x sampled at fs (mean removed).
AmplitudeSpectrum amplitude_spectrum(const Eigen::Ref<const Eigen::VectorXd>& x, double fs,
                                     FftCache& cache);

/// Indices of the `count` most prominent local maxima, at least `min_distance` bins apart,
/// ignoring maxima whose prominence is below `min_prominence` times the highest peak;
/// returned most prominent first (fewer when fewer peaks exist).
std::vector<Eigen::Index> prominent_peaks(const Eigen::Ref<const Eigen::VectorXd>& amplitude,
                                          int count, Eigen::Index min_distance,
                                          double min_prominence = 1e-3);

/// Indices of the `count` highest local maxima, at least `min_distance` bins apart,
/// ignoring maxima whose prominence is below `min_prominence` times the highest peak;
/// returned in ascending index order (fewer when fewer peaks exist).
std::vector<Eigen::Index> strongest_peaks(const Eigen::Ref<const Eigen::VectorXd>& amplitude,
                                          int count, Eigen::Index min_distance,
                                          double min_prominence = 1e-3);

/// Zero-phase low-pass: gain 1 up to f_pass, a Gaussian edge (standard deviation
/// (f_stop - f_pass) / 4, gain 0.5 midway), ~0 beyond f_stop. x is zero-padded
/// to twice its length so the record does not wrap onto itself.
Eigen::VectorXd lowpass(const Eigen::Ref<const Eigen::VectorXd>& x, double fs, double f_pass,
                        double f_stop, FftCache& cache);

/// lowpass() in place, for records too long to copy: `data` holds fast_size(2 n) / 2 + 1
/// complex values; x's n samples in its first n doubles become the low-passed samples (the
/// same numbers as lowpass() up to rounding); the rest is overwritten.
void lowpass_in_place(std::complex<double>* data, Eigen::Index n, double fs, double f_pass,
                      double f_stop, FftCache& cache);

/// lowpass_in_place() on an nfft-point transform (nfft >= n; `data` holds nfft / 2 + 1
/// complex values): the record is padded to nfft only, so each end leaks onto the other
/// through the filter's kernel at nfft - n samples and more (a long record's caller pads by
/// what the kernel needs to die out and drops the ends).
void lowpass_in_place(std::complex<double>* data, Eigen::Index n, Eigen::Index nfft, double fs,
                      double f_pass, double f_stop, FftCache& cache);

/// Frequency-domain integration (order > 0) or differentiation (order < 0) of x,
/// with everything below f_min [Hz] removed (integration has no DC). x is zero-padded
/// to twice its length so the record does not wrap onto itself.
Eigen::VectorXd integrate(const Eigen::Ref<const Eigen::VectorXd>& x, double fs, int order,
                          double f_min, FftCache& cache);

}  // namespace jointlab::signal
