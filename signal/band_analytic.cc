#include "jointlab/signal/band_analytic.h"

#include <cassert>
#include <cmath>
#include <numbers>

namespace jointlab::signal {

double band_gain(const Band& band, double taper, double f) {
  const double w = taper * (band.hi - band.lo);
  if (w <= 0) return (f > band.lo && f < band.hi) ? 1.0 : 0.0;
  const double s = std::sqrt(2.0) * w / 4.0;
  const double g =
      0.5 * (std::erf((f - band.lo - 0.5 * w) / s) - std::erf((f - band.hi + 0.5 * w) / s));
  return g < 1e-12 ? 0.0 : g;
}

Fft& FftCache::get(Eigen::Index n) {
  auto it = ffts_.find(n);
  if (it == ffts_.end()) it = ffts_.emplace(n, Fft(n)).first;
  return it->second;
}

BandSignal band_analytic(const Eigen::Ref<const Eigen::VectorXcd>& spectrum, Eigen::Index n_record,
                         Eigen::Index n_fft, double fs, const Band& band,
                         const BandOptions& options, FftCache& cache) {
  assert(spectrum.size() == n_fft / 2 + 1);
  assert(band.lo > 0 && band.hi > band.lo && band.hi <= fs / 2);
  const double df = fs / static_cast<double>(n_fft);
  // The Gaussian edges reach below 1e-12 within 1.75 w of the nominal edges.
  const double reach = 1.75 * options.taper * (band.hi - band.lo);
  const Eigen::Index k_lo =
      std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::floor((band.lo - reach) / df)));
  const Eigen::Index k_hi = std::min<Eigen::Index>(
      static_cast<Eigen::Index>(std::ceil((band.hi + reach) / df)), n_fft / 2);
  const Eigen::Index width = k_hi - k_lo + 1;
  const Eigen::Index m =
      options.full_rate ? n_fft
                        : fast_size(std::max<Eigen::Index>(
                              16, static_cast<Eigen::Index>(
                                      std::ceil(options.oversample * static_cast<double>(width)))));
  const Eigen::Index k_c = options.full_rate ? 0 : (k_lo + k_hi) / 2;

  Eigen::VectorXcd shifted = Eigen::VectorXcd::Zero(m);
  double noise_bw = 0.0;
  for (Eigen::Index k = k_lo; k <= k_hi; ++k) {
    const double f = static_cast<double>(k) * df;
    const double g = band_gain(band, options.taper, f);
    if (g == 0.0) continue;
    noise_bw += g * g * df;
    // (i w)^(-order) by repeated multiplication (std::pow on complex is costly).
    std::complex<double> h = 1.0;
    const std::complex<double> iw(0.0, 2.0 * std::numbers::pi * f);
    for (int o = 0; o < std::abs(options.order); ++o) h *= iw;
    if (options.order > 0) h = 1.0 / h;
    const Eigen::Index idx = ((k - k_c) % m + m) % m;
    shifted(idx) = 2.0 * g * h * spectrum(k);
  }
  Eigen::VectorXcd b = cache.get(m).inverse_complex(shifted);
  b *= static_cast<double>(m) / static_cast<double>(n_fft);

  BandSignal out;
  out.dt = static_cast<double>(n_fft) / (fs * static_cast<double>(m));
  out.carrier_hz = static_cast<double>(k_c) * df;
  out.noise_bandwidth_hz = noise_bw;
  const double duration = static_cast<double>(n_record - 1) / fs;
  const Eigen::Index keep = std::min<Eigen::Index>(
      m, static_cast<Eigen::Index>(std::floor(duration / out.dt + 1e-9)) + 1);
  out.baseband = b.head(keep);
  return out;
}

}  // namespace jointlab::signal
