#include "jointlab/signal/spectrum.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include "jointlab/signal/vector_math.h"

namespace jointlab::signal {

AmplitudeSpectrum amplitude_spectrum(const Eigen::Ref<const Eigen::VectorXd>& x, double fs,
                                     FftCache& cache) {
  const Eigen::Index n = x.size();
  const Eigen::Index nfft = fast_size(n);
  Eigen::VectorXd w(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    w(j) = 0.5 -
           0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(n));
  }
  const Eigen::VectorXd xw = ((x.array() - x.mean()) * w.array()).matrix();
  const Eigen::VectorXcd X = cache.get(nfft).forward(xw);
  AmplitudeSpectrum s;
  s.frequency_hz = Eigen::VectorXd::LinSpaced(
      X.size(), 0.0, fs * static_cast<double>(X.size() - 1) / static_cast<double>(nfft));
  s.amplitude = X.cwiseAbs() * (2.0 / w.sum());
  return s;
}

std::vector<Eigen::Index> prominent_peaks(const Eigen::Ref<const Eigen::VectorXd>& a, int count,
                                          Eigen::Index min_distance, double min_prominence) {
  const Eigen::Index n = a.size();
  struct Peak {
    Eigen::Index index;
    double height;
    double prominence;
  };
  std::vector<Peak> peaks;
  for (Eigen::Index k = 1; k + 1 < n; ++k) {
    if (!(a(k) > a(k - 1) && a(k) >= a(k + 1))) continue;
    // Prominence: height above the higher of the two minima reached before a higher sample.
    double left_min = a(k), right_min = a(k);
    for (Eigen::Index j = k - 1; j >= 0 && a(j) <= a(k); --j) left_min = std::min(left_min, a(j));
    for (Eigen::Index j = k + 1; j < n && a(j) <= a(k); ++j) right_min = std::min(right_min, a(j));
    peaks.push_back({k, a(k), a(k) - std::max(left_min, right_min)});
  }
  if (peaks.empty()) return {};
  const double top = std::max_element(peaks.begin(), peaks.end(), [](auto& p, auto& q) {
                       return p.height < q.height;
                     })->height;
  std::sort(peaks.begin(), peaks.end(),
            [](const Peak& p, const Peak& q) { return p.prominence > q.prominence; });
  std::vector<Eigen::Index> chosen;
  for (const Peak& p : peaks) {
    if (static_cast<int>(chosen.size()) >= count) break;
    if (p.prominence < min_prominence * top) break;
    const bool clear = std::all_of(chosen.begin(), chosen.end(), [&](Eigen::Index c) {
      return std::abs(c - p.index) >= min_distance;
    });
    if (clear) chosen.push_back(p.index);
  }
  return chosen;
}

std::vector<Eigen::Index> strongest_peaks(const Eigen::Ref<const Eigen::VectorXd>& a, int count,
                                          Eigen::Index min_distance, double min_prominence) {
  std::vector<Eigen::Index> chosen = prominent_peaks(a, count, min_distance, min_prominence);
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

namespace {

// The low-pass gain over an nfft-point transform's bins: 1 below the Gaussian edge, 0 above it
// and, on the edge (nine standard deviations each side of its middle), erfc taken for all its
// bins in one vector call (signal/vector_math.h; one a bin was a fortieth of process's time).
class LowpassGain {
 public:
  LowpassGain(Eigen::Index nfft, double fs, double f_pass, double f_stop) {
    const double df = fs / static_cast<double>(nfft);
    const double mid = 0.5 * (f_pass + f_stop), sd = 0.25 * (f_stop - f_pass);
    const Eigen::Index bins = nfft / 2 + 1;
    // The first bin with f >= mid - 9 sd (from a bin below it) and the first after it with
    // f > mid + 9 sd.
    const auto first = [&](Eigen::Index k, auto above) {
      while (k < bins && !above(static_cast<double>(k) * df)) ++k;
      return k;
    };
    begin_ = first(std::clamp<Eigen::Index>(
                       static_cast<Eigen::Index>(std::floor((mid - 9 * sd) / df)) - 1, 0, bins),
                   [&](double f) { return !(f < mid - 9 * sd); });
    end_ = first(begin_, [&](double f) { return f > mid + 9 * sd; });
    Eigen::ArrayXd x(end_ - begin_);
    for (Eigen::Index k = begin_; k < end_; ++k) {
      x(k - begin_) = (static_cast<double>(k) * df - mid) / (std::sqrt(2.0) * sd);
    }
    edge_.resize(x.size());
    erfc_array(x, edge_);
    edge_ *= 0.5;
  }
  /// Bins [0, begin) pass whole; [begin, end) by edge(k - begin); from end on nothing.
  Eigen::Index begin() const { return begin_; }
  Eigen::Index end() const { return end_; }
  double operator()(Eigen::Index k) const {
    return k < begin_ ? 1.0 : k < end_ ? edge_(k - begin_) : 0.0;
  }

 private:
  Eigen::Index begin_ = 0, end_ = 0;
  Eigen::ArrayXd edge_;
};

}  // namespace

Eigen::VectorXd lowpass(const Eigen::Ref<const Eigen::VectorXd>& x, double fs, double f_pass,
                        double f_stop, FftCache& cache) {
  const Eigen::Index n = x.size();
  const Eigen::Index nfft = fast_size(2 * n);
  Fft& fft = cache.get(nfft);
  Eigen::VectorXcd X = fft.forward(x);
  // The gain is shared by every channel of a record: computed once per size and edge.
  const Eigen::VectorXd& g = cache.gain({0.0, static_cast<double>(nfft), fs, f_pass, f_stop}, [&] {
    const LowpassGain g(nfft, fs, f_pass, f_stop);
    Eigen::VectorXd gain(X.size());
    for (Eigen::Index k = 0; k < X.size(); ++k) gain(k) = g(k);
    return gain;
  });
  X.array() *= g.array();
  return fft.inverse_real(X).head(n);
}

void lowpass_in_place(std::complex<double>* data, Eigen::Index n, double fs, double f_pass,
                      double f_stop, FftCache& cache) {
  lowpass_in_place(data, n, fast_size(2 * n), fs, f_pass, f_stop, cache);
}

void lowpass_in_place(std::complex<double>* data, Eigen::Index n, Eigen::Index nfft, double fs,
                      double f_pass, double f_stop, FftCache& cache) {
  assert(nfft >= n);
  const Eigen::Index bins = nfft / 2 + 1;
  auto* real = reinterpret_cast<double*>(data);
  std::fill(real + n, real + 2 * bins, 0.0);
  Fft& fft = cache.get(nfft);
  fft.forward_in_place(data);
  // The gain bin by bin (a stored gain would cost a copy of the record), its edge alone
  // stored, and kept with the cache as [begin, end, edge...]: every channel of a record shares
  // it (its erfc at every edge bin of every channel and band was a seventieth of process's
  // time).
  const Eigen::VectorXd& kept =
      cache.gain({3.0, static_cast<double>(nfft), fs, f_pass, f_stop}, [&] {
        const LowpassGain g(nfft, fs, f_pass, f_stop);
        Eigen::VectorXd v(2 + g.end() - g.begin());
        v(0) = static_cast<double>(g.begin());
        v(1) = static_cast<double>(g.end());
        for (Eigen::Index k = g.begin(); k < g.end(); ++k) v(2 + k - g.begin()) = g(k);
        return v;
      });
  const auto begin = static_cast<Eigen::Index>(kept(0)), end = static_cast<Eigen::Index>(kept(1));
  for (Eigen::Index k = begin; k < std::min(end, bins); ++k) data[k] *= kept(2 + k - begin);
  for (Eigen::Index k = std::max(end, begin); k < bins; ++k) data[k] *= 0.0;  // as g(k) did
  fft.inverse_real_in_place(data);
}

Eigen::VectorXd integrate(const Eigen::Ref<const Eigen::VectorXd>& x, double fs, int order,
                          double f_min, FftCache& cache) {
  const Eigen::Index n = x.size();
  const Eigen::Index nfft = fast_size(2 * n);
  Fft& fft = cache.get(nfft);
  const Eigen::VectorXcd X = fft.forward(x);
  Eigen::VectorXcd half = Eigen::VectorXcd::Zero(X.size());
  const double df = fs / static_cast<double>(nfft);
  for (Eigen::Index k = 1; k < X.size(); ++k) {
    const double f = static_cast<double>(k) * df;
    if (f < f_min) continue;
    half(k) = std::pow(std::complex<double>(0.0, 2.0 * std::numbers::pi * f), -order) * X(k);
  }
  return fft.inverse_real(half).head(n);
}

}  // namespace jointlab::signal
