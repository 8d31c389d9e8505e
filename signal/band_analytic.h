// The analytic signal of one frequency band, computed in the frequency domain.
//
// For a real record x (n samples at fs, zero-padded to N >= n with one-sided
// spectrum X[k], see fft.h) and a band [lo, hi] Hz, the band's analytic signal is
//   z(t) = (1/N) sum_k 2 G(f_k) H(f_k) X[k] exp(2 pi i f_k t),   f_k = k fs / N > 0,
// i.e. the Hilbert transform (negative frequencies zeroed, positive doubled) of
// the zero-phase band-passed signal. G is the band gain: a box [lo + w/2, hi - w/2]
// convolved with a Gaussian of standard deviation w/4 (w = taper * (hi - lo)), so
// G = 0.98 at lo + w and at hi - w, 0.023 at lo and hi, and ~0 a further w/2 out.
// Gaussian edges give a kernel sinc(t) exp(-2 pi^2 (w/4)^2 t^2) in time: the
// filter's transients die out within about 2/w seconds instead of trailing off
// as a power law (as raised-cosine or brick-wall edges do). G is real, so the
// filter has zero phase. H = (2 pi i f)^(-order) integrates
// (order > 0) or differentiates (order < 0) in the same pass, e.g. order 2 turns
// acceleration into displacement.
//
// Only the band's bins are non-zero, so z is evaluated exactly (trigonometric
// interpolation) on a coarse grid t_j = j dt by a short inverse FFT of the bins
// shifted down by a carrier f_c:  z(t_j) = b_j exp(2 pi i f_c t_j).
// Time t is measured from the record's first sample.
#pragma once

#include <array>
#include <complex>
#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "jointlab/signal/fft.h"

namespace jointlab::signal {

/// A frequency band [lo, hi] in Hz, 0 < lo < hi.
struct Band {
  double lo = 0.0;  ///< lower edge [Hz]
  double hi = 0.0;  ///< upper edge [Hz]
};

/// Settings of the band analytic signal.
struct BandOptions {
  double taper = 0.25;     ///< edge transition width w as a fraction of the band width
  int order = 0;           ///< integrations (>0) or differentiations (<0) applied in the band
  double oversample = 8;   ///< coarse-grid rate as a multiple of the band width
  bool full_rate = false;  ///< evaluate at every sample (dt = 1/fs, carrier 0) instead
};

/// The band's analytic signal on a coarse grid: z(t_j) = baseband_j exp(2 pi i carrier_hz t_j).
struct BandSignal {
  double dt = 0.0;                  ///< coarse grid step [s]
  double carrier_hz = 0.0;          ///< frequency shifted out of `baseband` [Hz]
  Eigen::VectorXcd baseband;        ///< samples covering the record (padding dropped)
  double noise_bandwidth_hz = 0.0;  ///< integral of G(f)^2 over f > 0 [Hz]
};

/// Band gain G(f): a box of [lo + w/2, hi - w/2] smoothed by a Gaussian of std w/4.
double band_gain(const Band& band, double taper, double f);

/// G continued to the complex frequency f = f_r + i d, 0 <= d <= 5 w/4: the factor by
/// which the band passes exp(2 pi i f t), a sinusoid of frequency f_r decaying at 2 pi d.
std::complex<double> band_gain(const Band& band, double taper, std::complex<double> f);

/// The bins of one band's analytic signal: where each non-zero bin k of the spectrum goes
/// in the shifted spectrum and its factor 2 G(f_k) H(f_k) (band_analytic).
struct BandWeights {
  Eigen::Index m = 0;                        ///< coarse-grid (inverse transform) size
  Eigen::Index k_c = 0;                      ///< carrier bin
  std::vector<Eigen::Index> bin, index;      ///< spectrum bin k and its place in the shift
  std::vector<std::complex<double>> factor;  ///< 2 G(f_k) H(f_k)
  double noise_bandwidth_hz = 0.0;           ///< integral of G(f)^2 over f > 0 [Hz]
};

/// The values made for the last `Kept` keys, the oldest replaced first.
template <typename Value, size_t Kept>
class RecentValues {
 public:
  /// The value made by `make` for `key`, made only if it is not kept.
  template <typename Make>
  const Value& get(const std::array<double, 8>& key, Make make) {
    for (auto& [k, v] : kept_)
      if (k == key) return v;
    if (kept_.size() < Kept) {
      kept_.emplace_back(key, make());
      return kept_.back().second;
    }
    auto& slot = kept_[next_++ % Kept];
    slot = {key, make()};
    return slot.second;
  }

 private:
  std::vector<std::pair<std::array<double, 8>, Value>> kept_;
  size_t next_ = 0;
};

/// Reusable FFT plans keyed by transform size, the last few filter gains computed and the
/// last few bands' weights (every channel of a record shares them); one workspace per thread.
class FftCache {
 public:
  /// The Fft of length n, created on first use.
  Fft& get(Eigen::Index n);
  /// The workspace of this one's i-th helper thread, created on first use and kept with this
  /// one (its plans then serve every record the helper works on).
  FftCache& helper(size_t i);
  /// The weights made by `make` for `key`, kept for the last few keys.
  template <typename Make>
  const BandWeights& band_weights(const std::array<double, 8>& key, Make make) {
    return weights_.get(key, make);
  }
  /// The gain vector made by `make` for `key`, kept for the last few keys (a record's
  /// low-pass and its bands' gains on the gain correction's grids alternate).
  template <typename Make>
  const Eigen::VectorXd& gain(const std::array<double, 8>& key, Make make) {
    return gains_.get(key, make);
  }

 private:
  std::map<Eigen::Index, std::pair<Fft, std::uint64_t>> ffts_;  // and when last asked for
  std::uint64_t clock_ = 0;
  std::vector<std::unique_ptr<FftCache>> helpers_;
  RecentValues<Eigen::VectorXd, 4> gains_;
  RecentValues<BandWeights, 8> weights_;  // bands and their superharmonic bands
};

/// Analytic signal of `band` from the one-sided spectrum of an n-sample record padded to n_fft
/// (bins past spectrum's size, at most n_fft / 2 + 1, taken as zero).
BandSignal band_analytic(const Eigen::Ref<const Eigen::VectorXcd>& spectrum, Eigen::Index n_record,
                         Eigen::Index n_fft, double fs, const Band& band,
                         const BandOptions& options, FftCache& cache);

}  // namespace jointlab::signal
