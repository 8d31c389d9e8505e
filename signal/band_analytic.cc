#include "jointlab/signal/band_analytic.h"

#include <cassert>
#include <cmath>
#include <cstdint>
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

namespace {

// Standard normal CDF at x + i y: Phi(x) plus the integral of the density up the
// vertical path from x to x + i y (8-point Gauss-Legendre per panel of height 0.5;
// the density exp(-(x + i t)^2 / 2) turns by at most x / 2 rad per panel).
std::complex<double> normal_cdf(double x, double y) {
  const double real = 0.5 * std::erfc(-x / std::sqrt(2.0));
  if (y == 0.0 || x * x - y * y > 80.0) return real;  // the path adds below 4e-18
  static constexpr double kNode[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                      0.9602898564975363};
  static constexpr double kWeight[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                        0.1012285362903763};
  const int panels = static_cast<int>(std::ceil(std::abs(y) / 0.5));
  const double h = y / panels;
  std::complex<double> sum = 0.0;
  for (int p = 0; p < panels; ++p) {
    const double mid = (p + 0.5) * h;
    for (int k = 0; k < 4; ++k) {
      for (const double s : {-1.0, 1.0}) {
        const double t = mid + s * kNode[k] * h / 2;
        sum += kWeight[k] * std::exp(std::complex<double>(-(x * x - t * t) / 2, -x * t));
      }
    }
  }
  return real + std::complex<double>(0.0, 1.0) * sum * (h / 2) / std::sqrt(2 * std::numbers::pi);
}

}  // namespace

std::complex<double> band_gain(const Band& band, double taper, std::complex<double> f) {
  const double w = taper * (band.hi - band.lo);
  assert(w > 0 && f.imag() >= 0 && f.imag() <= 1.25 * w);
  const double sd = w / 4;  // the Gaussian's standard deviation
  const double y = f.imag() / sd;
  return normal_cdf((f.real() - band.lo - 0.5 * w) / sd, y) -
         normal_cdf((f.real() - band.hi + 0.5 * w) / sd, y);
}

Fft& FftCache::get(Eigen::Index n) {
  // Every record's channels bring sizes of their own (their impacts differ): the least
  // recently used size goes once kSizesKept are held, so a long campaign's workspace does not
  // grow with every hit. The last sizes asked for stay, so a reference a caller holds while it
  // asks for one more size remains valid.
  constexpr size_t kSizesKept = 16;
  ++clock_;
  auto it = ffts_.find(n);
  if (it == ffts_.end()) {
    if (ffts_.size() >= kSizesKept) {
      auto oldest = ffts_.begin();
      for (auto k = ffts_.begin(); k != ffts_.end(); ++k)
        if (k->second.second < oldest->second.second) oldest = k;
      ffts_.erase(oldest);
    }
    it = ffts_.emplace(n, std::pair<Fft, std::uint64_t>(Fft(n), 0)).first;
  }
  it->second.second = clock_;
  return it->second.first;
}

FftCache& FftCache::helper(size_t i) {
  while (helpers_.size() <= i) helpers_.push_back(std::make_unique<FftCache>());
  return *helpers_[i];
}

namespace {

// The band's bins and their factors for a spectrum of n_fft bins at fs.
BandWeights band_weights(Eigen::Index n_fft, double fs, const Band& band,
                         const BandOptions& options) {
  const double df = fs / static_cast<double>(n_fft);
  // The Gaussian edges reach below 1e-12 within 1.75 w of the nominal edges.
  const double reach = 1.75 * options.taper * (band.hi - band.lo);
  const Eigen::Index k_lo =
      std::max<Eigen::Index>(1, static_cast<Eigen::Index>(std::floor((band.lo - reach) / df)));
  const Eigen::Index k_hi = std::min<Eigen::Index>(
      static_cast<Eigen::Index>(std::ceil((band.hi + reach) / df)), n_fft / 2);
  const Eigen::Index width = k_hi - k_lo + 1;
  BandWeights w;
  w.m = options.full_rate ? n_fft
                          : fast_size(std::max<Eigen::Index>(
                                16, static_cast<Eigen::Index>(std::ceil(
                                        options.oversample * static_cast<double>(width)))));
  w.k_c = options.full_rate ? 0 : (k_lo + k_hi) / 2;
  for (Eigen::Index k = k_lo; k <= k_hi; ++k) {
    const double f = static_cast<double>(k) * df;
    const double g = band_gain(band, options.taper, f);
    if (g == 0.0) continue;
    w.noise_bandwidth_hz += g * g * df;
    // (i w)^(-order) by repeated multiplication (std::pow on complex is costly).
    std::complex<double> h = 1.0;
    const std::complex<double> iw(0.0, 2.0 * std::numbers::pi * f);
    for (int o = 0; o < std::abs(options.order); ++o) h *= iw;
    if (options.order > 0) h = 1.0 / h;
    w.bin.push_back(k);
    w.index.push_back(((k - w.k_c) % w.m + w.m) % w.m);
    w.factor.push_back(2.0 * g * h);
  }
  return w;
}

}  // namespace

BandSignal band_analytic(const Eigen::Ref<const Eigen::VectorXcd>& spectrum, Eigen::Index n_record,
                         Eigen::Index n_fft, double fs, const Band& band,
                         const BandOptions& options, FftCache& cache) {
  assert(spectrum.size() <= n_fft / 2 + 1);
  assert(band.lo > 0 && band.hi > band.lo && band.hi <= fs / 2);
  // Every channel of a record has the same bins and factors: made once per band and size.
  const std::array<double, 8> key{static_cast<double>(n_fft),
                                  fs,
                                  band.lo,
                                  band.hi,
                                  options.taper,
                                  options.oversample,
                                  static_cast<double>(options.order),
                                  options.full_rate ? 1.0 : 0.0};
  const BandWeights& w =
      cache.band_weights(key, [&] { return band_weights(n_fft, fs, band, options); });
  const Eigen::Index m = w.m;
  BandSignal out;
  out.dt = static_cast<double>(n_fft) / (fs * static_cast<double>(m));
  out.carrier_hz = static_cast<double>(w.k_c) * (fs / static_cast<double>(n_fft));
  out.noise_bandwidth_hz = w.noise_bandwidth_hz;
  // The shifted bins straight into the transform's input; of its output only the samples
  // covering the record (the padding dropped).
  Fft& fft = cache.get(m);
  std::complex<double>* shifted = fft.complex_input();
  for (size_t i = 0; i < w.bin.size() && w.bin[i] < spectrum.size(); ++i)  // bins ascend
    shifted[w.index[i]] = w.factor[i] * spectrum(w.bin[i]);
  const double duration = static_cast<double>(n_record - 1) / fs;
  const Eigen::Index keep = std::min<Eigen::Index>(
      m, static_cast<Eigen::Index>(std::floor(duration / out.dt + 1e-9)) + 1);
  out.baseband = fft.inverse_complex_head(keep);
  out.baseband *= static_cast<double>(m) / static_cast<double>(n_fft);
  return out;
}

}  // namespace jointlab::signal
