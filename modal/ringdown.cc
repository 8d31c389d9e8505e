#include "jointlab/modal/ringdown.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Dense>

#include "jointlab/modal/ringdown_detail.h"
#include "jointlab/signal/extend.h"
#include "jointlab/signal/local_poly.h"
#include "jointlab/signal/spectrum.h"
#include "jointlab/signal/vector_math.h"

namespace jointlab::modal {

using namespace ringdown_detail;  // the steps the band extraction's files share

namespace ringdown_detail {

WindowOnGrid window_on_grid(const Estimate& e, double dt, Eigen::Index grid) {
  WindowOnGrid w;
  w.half = e.window / 2;
  w.offset = std::clamp((e.t - e.centre) / w.half, -1.0, 1.0);
  w.stride = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(e.window / dt) / 48);
  w.j0 = std::clamp<Eigen::Index>(static_cast<Eigen::Index>((e.centre - w.half) / dt), 0, grid - 1);
  w.j1 =
      std::clamp<Eigen::Index>(static_cast<Eigen::Index>((e.centre + w.half) / dt), w.j0, grid - 1);
  return w;
}

}  // namespace ringdown_detail

namespace {

// |z| as sqrt(re^2 + im^2) where that cannot overflow or underflow, else std::abs (a
// hypot, which guards every sample at four times the cost; the estimates' uncertainties,
// summed in quadrature as |(a, b)|, took a seventieth of process's time through it).
double magnitude(std::complex<double> z) {
  const double n = std::norm(z);
  return n > 1e-290 && n < 1e290 ? std::sqrt(n) : std::abs(z);
}

}  // namespace

namespace ringdown_detail {

// Hilbert estimate at `at` from ln A and theta on the grid t_j = j dt, fitted
// over a window of length `window` centred at `centre` (at lies in its middle
// half: off-centre windows serve points near the ends of the span).
// `noise` is the noise floor (RMS of the complex analytic-signal noise); each of
// ln A and theta then carries noise of standard deviation noise / (sqrt(2) A).
Estimate estimate_hilbert(const Eigen::VectorXd& log_amp, const Eigen::VectorXd& theta, double dt,
                          double at, double centre, double window, double correlation, double noise,
                          int degree) {
  // Samples closer than the noise's correlation length add little: thin long
  // windows to about 48 samples while keeping at least one per 1/bandwidth.
  const auto in_window = static_cast<Eigen::Index>(window / dt);
  const Eigen::Index stride = std::clamp<Eigen::Index>(
      in_window / 48, 1, std::max<Eigen::Index>(1, static_cast<Eigen::Index>(correlation)));
  const double corr = std::max(1.0, correlation / static_cast<double>(stride));
  const auto [fa, fp] = signal::fit_local_pair(log_amp, theta, 0.0, dt, centre, window / 2, degree,
                                               corr, stride, (at - centre) / (window / 2));
  Estimate e;
  e.t = at;
  e.log_amp = fa.value;
  // The residual-based std is scaled by the residual RMS; the floor-based one
  // by the known noise level: take whichever is larger.
  const double floor_rel = noise / (std::sqrt(2.0) * std::exp(fa.value));
  const double scale_a = fa.residual_rms > 0 ? std::max(1.0, floor_rel / fa.residual_rms) : 1.0;
  const double scale_p = fp.residual_rms > 0 ? std::max(1.0, floor_rel / fp.residual_rms) : 1.0;
  e.log_amp_std = magnitude({fa.value_std * scale_a, fa.value_change});
  e.sigma = -fa.slope;
  e.sigma_std = magnitude({fa.slope_std * scale_a, fa.slope_change});
  e.omega_d = fp.slope;
  e.omega_d_std = magnitude({fp.slope_std * scale_p, fp.slope_change});
  e.misfit = std::exp(fa.value) * magnitude({fa.residual_rms, fp.residual_rms});
  e.window = window;
  e.centre = centre;
  return e;
}

}  // namespace ringdown_detail

namespace {

// Peak-fitting estimate: t(k) and ln|y_k| over the extremum index k (uniform in k).
// Successive extrema are `correlation` apart in units of the noise's correlation
// length or closer (the band-passed noise is correlated over 1 / bandwidth);
// `noise` is the noise floor, giving each peak a relative error of about
// noise / (sqrt(2) A) in height and noise / (sqrt(2) A omega) in time.
Estimate estimate_peaks(const Eigen::VectorXd& log_peak, const Eigen::VectorXd& t_peak,
                        double centre_index, double half_count, int degree, double correlation,
                        double noise) {
  const auto [ft, fa] = signal::fit_local_pair(t_peak, log_peak, 0.0, 1.0, centre_index, half_count,
                                               degree, correlation);
  Estimate e;
  const double half_period = ft.slope;  // seconds per extremum
  const double omega = std::numbers::pi / half_period;
  const double floor_rel = noise / (std::sqrt(2.0) * std::exp(fa.value));
  const double scale_a = fa.residual_rms > 0 ? std::max(1.0, floor_rel / fa.residual_rms) : 1.0;
  const double scale_t =
      ft.residual_rms > 0 ? std::max(1.0, floor_rel / omega / ft.residual_rms) : 1.0;
  e.t = ft.value;
  e.log_amp = fa.value;
  e.log_amp_std = std::hypot(fa.value_std * scale_a, fa.value_change);
  e.sigma = -fa.slope / half_period;
  const double rel_t = std::hypot(ft.slope_std * scale_t, ft.slope_change) / half_period;
  e.sigma_std = std::hypot(std::hypot(fa.slope_std * scale_a, fa.slope_change) / half_period,
                           std::abs(e.sigma) * rel_t);
  e.omega_d = omega;
  e.omega_d_std = e.omega_d * rel_t;
  e.misfit = std::exp(fa.value) * fa.residual_rms;
  e.window = 2 * half_count * half_period;
  e.centre = e.t;
  return e;
}

}  // namespace

namespace ringdown_detail {

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

}  // namespace ringdown_detail

std::string RingdownOptions::check() const {
  if (!(taper > 0 && taper < 0.5)) return "taper must be in (0, 0.5)";
  if (!(snr_min >= 1)) return "snr_min must be at least 1";
  if (!(min_periods >= 2)) return "min_periods must be at least 2";
  if (!(max_window_s > 0)) return "max_window_s must be positive";
  if (!(target_damping_rel_std > 0)) return "target_damping_rel_std must be positive";
  if (!(max_damping_rel_std > 0)) return "max_damping_rel_std must be positive";
  if (!(points_per_window >= 1)) return "points_per_window must be at least 1";
  if (degree < 1 || degree > 5) return "degree must be 1 to 5";
  if (!(coverage_factor >= 1)) return "coverage factor must be at least 1";
  if (amplitude == Quantity::kForce)
    return "amplitude must be displacement, velocity or acceleration";
  return {};
}

std::string RingdownSummary::report() const {
  if (status != RingdownStatus::kOk) return "no backbone: " + message;
  if (!linear_reason.empty()) {
    return fmt::format(
        "kept {:.4f} s to {:.4f} s ({:.2f} decades of amplitude); noise floor "
        "{:.3e} m; {}{}{}",
        span_start_s, span_end_s, amplitude_decades, noise_floor_m, linear_reason,
        message.empty() ? "" : "; ", message);
  }
  return fmt::format(
      "kept {:.4f} s to {:.4f} s ({:.2f} decades of amplitude); noise floor {:.3e} m; "
      "linear (at amplitude {:.3g}, the lowest of a straight-line fit up to {:.3g}): frequency "
      "{:.4f} +- {:.2g} Hz, damping ratio {:.4g} +- {:.2g}{}{}",
      span_start_s, span_end_s, amplitude_decades, noise_floor_m, linear_fit_min, linear_fit_max,
      linear_frequency_hz, linear_frequency_std_hz, linear_damping, linear_damping_std,
      message.empty() ? "" : "; ", message);
}

double band_settling_s(const signal::Band& band, double taper) {
  return 3.0 / (taper * (band.hi - band.lo));
}

PrepareOptions prepare_for(const std::vector<signal::Band>& bands, double taper,
                           PrepareOptions base) {
  // A long record's padding: its ends are pad_s apart through every filter read from the
  // spectrum. The slowest is the superharmonic check's third of a band (mark_superharmonics),
  // settling 3 times slower; twice its settling time takes its kernel from exp(-11) to
  // exp(-44), 5e-20 (the exponent grows as the square of the time), so the record's start,
  // its largest samples, adds nothing to its end, its noise. Moved bands are only wider.
  constexpr double kPadSettlings = 2 * 3;
  double top = 0;
  for (const signal::Band& b : bands) {
    top = std::max(top, b.hi);
    base.extend_s = std::max(base.extend_s, 1.1 * band_settling_s(b, taper));
    base.pad_s = std::max(base.pad_s, kPadSettlings * band_settling_s(b, taper));
  }
  if (base.lowpass_hz == 0) base.lowpass_hz = 1.5 * top;
  return base;
}

Eigen::Index impact_index(const Eigen::Ref<const Eigen::VectorXd>& x) {
  const Eigen::VectorXd centred = x.array() - x.mean();
  const Eigen::Index quarter = std::max<Eigen::Index>(1, x.size() / 4);
  const double peak = centred.head(quarter).cwiseAbs().maxCoeff();
  // The first sample at half the peak: the impact's rise in a triggered record,
  // the first cycle of the fastest mode in one that starts with the ring-down
  // (whose largest sample may come several periods later).
  Eigen::Index i = 0;
  while (i + 1 < quarter && std::abs(centred(i)) < 0.5 * peak) ++i;
  return i;
}

namespace {

// Transform sizes of a channel's spectrum and of its low-pass.
struct Padding {
  Eigen::Index n_fft = 0, n_lowpass = 0;
};

// Sizes for an analysed record of n_record samples whose m measured samples are low-passed
// and then lose `guard` at each end. Twice the lengths, unless the record is long: then the
// spectrum is padded by options.pad_s (prepare_for) and the low-pass by two guards, so that
// a kept sample is three guards from the other end through the low-pass's kernel, whose
// Gaussian factor exp(-8) at one guard is exp(-72) there. Long sizes are even: FFTW's
// tables for them are then a fifth as large (signal::Fft::forward_in_place).
Padding padding(Eigen::Index n_record, Eigen::Index m, Eigen::Index guard, double fs,
                const PrepareOptions& options) {
  if (n_record <= options.pad_above || !(options.pad_s > 0)) {
    return {signal::fast_size(2 * n_record), signal::fast_size(2 * m)};
  }
  const double wanted = std::ceil(options.pad_s * fs);
  const Eigen::Index pad = wanted < static_cast<double>(n_record)
                               ? static_cast<Eigen::Index>(wanted)
                               : n_record;  // never more than the short records' padding
  const auto even = [](Eigen::Index k) { return 2 * signal::fast_size((k + 1) / 2); };
  return {even(n_record + pad), even(m + std::min(2 * guard, m))};
}

// The bins of channel c's spectrum that are kept. A low-passed record keeps those up to
// where the low-pass's gain is zero (lowpass_hz to twice it, Gaussian edge of standard
// deviation lowpass_hz / 4: zero from 3.75 lowpass_hz, 5.6 times the highest band edge with
// prepare_for's low-pass): above them the record holds nothing but the rounding of its
// continuations' joins and the images of their poles, and a long record's spectrum then
// costs a few per cent of the record instead of a double a sample for the rest of its
// extraction. Readers take missing bins as zero.
// With `step`, the bins of every step-th bin's spectrum (ChannelSpectrum::measured).
Eigen::Index stored_bins(const ChannelSpectrum& c, bool cut, double lowpass_hz,
                         Eigen::Index step = 1) {
  const Eigen::Index all = c.n_fft / 2 / step + 1;
  if (!cut) return all;
  const double df = c.fs * static_cast<double>(step) / static_cast<double>(c.n_fft);
  return std::min(all, static_cast<Eigen::Index>(std::ceil(3.75 * lowpass_hz / df)) + 2);
}

// The step of the measured samples' spectrum over the continued record's (n_fft points, of
// which `kept` measured, continued by `ext` at either end): the largest divisor of n_fft up to
// 8 that keeps its bins no farther apart than the measured samples' own resolution fs / kept,
// or than 0.2 / extend_s, if that is wider. Continued over 1.1 settling times of its slowest
// band (prepare_for), a band is at least 3.3 / (taper extend_s) wide, 13 / extend_s with
// the default taper, so the narrowest band the checks read, a third of it, then spans 22
// bins or more. An even n_fft always has one (2: n_fft is at least twice `kept`, or a long
// record's, far longer than 10 ext); an odd one may not, and then takes its smallest divisor,
// up to 7, its bins up to 3.5 times farther apart, rather than a transform of the full size
// in a buffer of its own beside the record's (at a half-size one, a 4e6-sample record came
// within 2 MB of process_test.cc's memory limit). 1 when n_fft has no divisor up to 8.
Eigen::Index measured_step(Eigen::Index n_fft, Eigen::Index kept, Eigen::Index ext) {
  const Eigen::Index spacing = ext > 0 ? std::min(kept, 5 * ext) : kept;
  Eigen::Index step = 1;
  for (Eigen::Index d = 8; d >= 2; --d) {
    if (n_fft % d != 0) continue;
    if (d * spacing <= n_fft) return d;
    step = d;
  }
  return step;
}

}  // namespace

namespace {

// Where a channel's record is read and how it is continued (channel_spectrum): its n samples,
// the measured ones (m from i_begin), the scale they are analysed at, the low-pass's stop
// frequency, guard and lag, and the continuations' fit and lengths (`wanted` each side of the
// `kept` samples they extend).
struct RecordLayout {
  Eigen::Index n = 0, i_begin = 0, m = 0, guard = 0, lag = 1, ext = 0, fit = 0, wanted = 0,
               kept = 0;
  double scale = 1.0, f_stop = 0;
  bool lowpass = false;
};

// The layout of record x (sample rate fs) from its impact (impact_index where `impact` < 0).
RecordLayout record_layout(const Eigen::Ref<const Eigen::VectorXd>& x, double fs,
                           const PrepareOptions& options, Eigen::Index impact) {
  const Eigen::Index n = x.size();
  const Eigen::Index i_peak = impact >= 0 ? std::min(impact, n - 1) : impact_index(x);
  const Eigen::Index i_begin = std::min<Eigen::Index>(
      n - 1, i_peak + static_cast<Eigen::Index>(std::round(options.onset_skip_s * fs)));
  const Eigen::Index m = n - i_begin;
  // Samples of 1e300 are finite but their squares are not (1e-300 likewise underflow): such
  // a channel is analysed at an exact power-of-two scale and extract_backbone scales back.
  const double peak = x.segment(i_begin, m).cwiseAbs().maxCoeff();
  const double scale =
      peak > 1e100 || (peak > 0 && peak < 1e-100) ? std::ldexp(1.0, -std::ilogb(peak)) : 1.0;
  const bool lowpass = options.lowpass_hz > 0 && 2 * options.lowpass_hz < 0.5 * fs;
  const double f_stop = 2 * options.lowpass_hz;
  Eigen::Index guard = 0, lag = 1;
  if (lowpass) {
    // The edge's kernel exp(-2 pi^2 sd^2 t^2), sd = f_stop / 8, is below 1e-6 by 4 / sd.
    guard =
        static_cast<Eigen::Index>(std::ceil(4.0 / (f_stop / 8.0) / (2 * std::numbers::pi) * fs));
    lag = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(fs / (3 * f_stop)));
  }
  guard = std::min(guard, m / 4);
  const Eigen::Index ext = static_cast<Eigen::Index>(std::round(options.extend_s * fs));
  const Eigen::Index fit = static_cast<Eigen::Index>(std::round(options.ar_fit_s * fs));
  const Eigen::Index wanted = ext + guard;
  const Eigen::Index kept = m - 2 * guard;  // the samples the continuations extend
  RecordLayout l;
  l.n = n, l.i_begin = i_begin, l.m = m, l.guard = guard, l.lag = lag, l.ext = ext, l.fit = fit;
  l.wanted = wanted, l.kept = kept, l.scale = scale, l.f_stop = f_stop, l.lowpass = lowpass;
  return l;
}

// The continuations of the measured samples y (low-passed, if at all) before and after them.
signal::Continuation continued_ends(const Eigen::Map<Eigen::VectorXd>& y, const RecordLayout& l,
                                    const PrepareOptions& options) {
  const Eigen::Index guard = l.guard, kept = l.kept, wanted = l.wanted, fit = l.fit, lag = l.lag;
  const auto extend = [&](int order, bool before, bool after) {
    return signal::continue_record(y.segment(guard, kept), before ? wanted : 0, after ? wanted : 0,
                                   order, fit, 1e3, lag);
  };
  signal::Continuation e = extend(options.ar_order, true, true);
  // A model with more poles than the record has modes fits some to the noise;
  // run backwards, a heavily damped one of those can blow up within the span the
  // band filters need. Lower orders (halving, down to 4) then take over that end
  // if they continue it further (an end already continued in full is not tried again).
  for (int order = options.ar_order / 2;
       order >= 4 && (e.before_valid < wanted || e.after_valid < wanted); order /= 2) {
    signal::Continuation f = extend(order, e.before_valid < wanted, e.after_valid < wanted);
    if (f.before_valid > e.before_valid) {
      e.before = std::move(f.before);
      e.before_valid = f.before_valid;
    }
    if (f.after_valid > e.after_valid) {
      e.after = std::move(f.after);
      e.after_valid = f.after_valid;
    }
  }
  return e;
}

// The continuations' spectrum at every m_fold-th bin of the continued record's: e placed
// before and after the kept samples, folded modulo m_fold (a run of whole stretches) and
// transformed, in a buffer of its own.
Eigen::VectorXcd continuations_spectrum(const signal::Continuation& e, const RecordLayout& l,
                                        Eigen::Index m_fold, signal::FftCache& cache) {
  const Eigen::Index wanted = l.wanted, kept = l.kept;
  Eigen::VectorXcd continuations = Eigen::VectorXcd::Zero(m_fold / 2 + 1);
  {
    double* f = reinterpret_cast<double*>(continuations.data());
    // Adds x, placed from `at` on, folded modulo m_fold: a run of whole stretches.
    const auto fold = [&](const Eigen::VectorXd& x, Eigen::Index at) {
      for (Eigen::Index j = 0; j < x.size();) {
        const Eigen::Index place = (at + j) % m_fold, run = std::min(x.size() - j, m_fold - place);
        Eigen::Map<Eigen::VectorXd>(f + place, run) += x.segment(j, run);
        j += run;
      }
    };
    fold(e.before, 0);
    fold(e.after, wanted + kept);
    cache.get(m_fold).forward_through_buffer(continuations.data());
  }
  return continuations;
}

// The times and clipping of channel c, read from x at t0 [s] with layout l and continuations e.
void set_times(ChannelSpectrum& c, const Eigen::Ref<const Eigen::VectorXd>& x, double fs, double t0,
               const RecordLayout& l, const signal::Continuation& e, const Clipping* clipping) {
  const Eigen::Index n = l.n, i_begin = l.i_begin, wanted = l.wanted, guard = l.guard;
  c.t0 = t0 + static_cast<double>(i_begin - wanted + guard) / fs;
  c.data_begin_s = t0 + static_cast<double>(i_begin + guard) / fs;
  c.data_end_s = t0 + static_cast<double>(n - 1 - guard) / fs;
  c.clipping = clipping ? *clipping : find_clipping(x);
  c.clipped_until_s = t0 + static_cast<double>(c.clipping.last) / fs;
  c.continued_begin_s = static_cast<double>(e.before_valid) / fs;
  c.continued_end_s = static_cast<double>(e.after_valid) / fs;
}

}  // namespace

ChannelSpectrum channel_spectrum(const Eigen::Ref<const Eigen::VectorXd>& x, double fs, double t0,
                                 const PrepareOptions& options, signal::FftCache& cache,
                                 Eigen::Index impact, const Clipping* clipping) {
  const RecordLayout l = record_layout(x, fs, options, impact);
  const Eigen::Index i_begin = l.i_begin, m = l.m, guard = l.guard, ext = l.ext, wanted = l.wanted,
                     kept = l.kept;
  const bool lowpass = l.lowpass;
  ChannelSpectrum c;
  c.scale = l.scale;
  c.fs = fs;
  c.n_record = wanted + kept + wanted;
  const Padding pad = padding(c.n_record, m, guard, fs, options);
  c.n_fft = pad.n_fft;
  // One buffer for the record, its low-pass and its spectrum, transformed in place: a long
  // record's peak memory is its samples and this spectrum (1 double a sample), no copies.
  const Eigen::Index n_lowpass = lowpass ? pad.n_lowpass : 0;
  Eigen::VectorXcd buffer(std::max(c.n_fft, n_lowpass) / 2 + 1);
  double* r = reinterpret_cast<double*>(buffer.data());
  Eigen::Map<Eigen::VectorXd> y(r, m);
  y = x.segment(i_begin, m) * l.scale;
  y.array() -= y.mean();
  if (lowpass) {
    signal::lowpass_in_place(buffer.data(), m, n_lowpass, fs, options.lowpass_hz, l.f_stop, cache);
  }
  const signal::Continuation e = continued_ends(y, l, options);
  // The measured samples' spectrum is the continued record's less the continuations', at
  // every step-th bin: the continuations folded modulo n_fft / step transform there exactly
  // (a transform of a step-th of the size, in a buffer of its own, while the record waits
  // in the main one). Both are kept only up to where the low-pass leaves nothing
  // (stored_bins). (The measured samples transformed on their own in the main buffer, then
  // the continuations, cost 14 % more time on the bench record; a copy of the whole
  // measured spectrum doubled the memory of a 4e6-sample record.)
  c.measured_step = measured_step(c.n_fft, kept, ext);
  const Eigen::Index m_fold = c.n_fft / c.measured_step;
  Eigen::VectorXcd continuations = continuations_spectrum(e, l, m_fold, cache);
  const Eigen::Index measured_bins =
      std::min(m_fold / 2 + 1, stored_bins(c, lowpass, options.lowpass_hz, c.measured_step));
  continuations.conservativeResize(measured_bins);
  // The analysed record, before + kept + after, zero-padded to n_fft, then its spectrum.
  std::memmove(r + wanted, r + guard, sizeof(double) * static_cast<size_t>(kept));
  std::copy(e.before.data(), e.before.data() + wanted, r);
  std::copy(e.after.data(), e.after.data() + wanted, r + wanted + kept);
  std::fill(r + c.n_record, r + 2 * buffer.size(), 0.0);
  cache.get(c.n_fft).forward_through_buffer(buffer.data());
  c.measured.resize(measured_bins);
  for (Eigen::Index q = 0; q < measured_bins; ++q) {
    c.measured(q) = buffer(q * c.measured_step) - continuations(q);
  }
  // Cut only where every reader takes the long record's way (ChannelSpectrum::padded_by_pad_s):
  // a record whose settling times reach past its own length is padded as a short one, whole.
  buffer.conservativeResize(stored_bins(c, c.padded_by_pad_s() && lowpass, options.lowpass_hz));
  set_times(c, x, fs, t0, l, e, clipping);
  c.spectrum = std::move(buffer);
  return c;
}

namespace {

// Whether the unwrapping may step between two samples: two whose imaginary parts share a sign
// lie in one closed half plane, where the difference of their arguments is within pi (their
// arguments are then not needed).
bool may_wrap(double im_before, double im) { return std::signbit(im) != std::signbit(im_before); }

// The unwrapping's step between two samples that may wrap, from their arguments: -2 pi, 0 or
// +2 pi added to the phase from the second on.
double unwrap_step(double arg_before, double arg) {
  const double d = arg - arg_before;
  if (d > std::numbers::pi) return -kTwoPi;
  if (d < -std::numbers::pi) return kTwoPi;
  return 0.0;
}

}  // namespace

namespace ringdown_detail {

// The logarithms and arguments of a signal's samples take one vector call each
// (signal/vector_math.h): they were a sixth of process's time a sample at a time.
EnvelopePhase envelope_phase(const Eigen::VectorXcd& baseband, double carrier_hz, double dt) {
  const Eigen::Index n = baseband.size();
  EnvelopePhase ep;
  ep.amp.resize(n);
  ep.log_amp.resize(n);
  ep.theta.resize(n);
  for (Eigen::Index j = 0; j < n; ++j) ep.amp(j) = magnitude(baseband(j));
  signal::log_array(ep.amp.array().max(1e-300), ep.log_amp.array());
  const Eigen::ArrayXd re = baseband.real(), im = baseband.imag();
  signal::atan2_array(im, re, ep.theta.array());  // the arguments, unwrapped below
  double offset = 0, arg_before = 0;
  for (Eigen::Index j = 0; j < n; ++j) {
    const double arg = ep.theta(j);
    if (j > 0 && may_wrap(im(j - 1), im(j))) offset += unwrap_step(arg_before, arg);
    ep.theta(j) = arg + offset + kTwoPi * carrier_hz * static_cast<double>(j) * dt;
    arg_before = arg;
  }
  return ep;
}

}  // namespace ringdown_detail

namespace {

// The unwrapped phase of envelope_phase at samples a <= b alone (the same numbers, without
// the envelope or the phase between them: a record too short for its band is refused
// from these).
std::pair<double, double> phases_at(const Eigen::VectorXcd& baseband, double carrier_hz, double dt,
                                    Eigen::Index a, Eigen::Index b) {
  double offset = 0, at_a = 0;
  const auto phase_at = [&](Eigen::Index j) {
    return std::arg(baseband(j)) + offset + kTwoPi * carrier_hz * static_cast<double>(j) * dt;
  };
  for (Eigen::Index j = 0; j <= b; ++j) {
    if (j > 0 && may_wrap(baseband(j - 1).imag(), baseband(j).imag())) {
      offset += unwrap_step(std::arg(baseband(j - 1)), std::arg(baseband(j)));
    }
    if (j == a) at_a = phase_at(j);
  }
  return {at_a, phase_at(b)};
}

// The band's effect on the mode, divided out: z_band(t) = r(t) z_mode(t). A mode
// whose frequency and decay rate change slowly passes the band multiplied by the
// gain at its complex frequency, G(f + i sigma / 2 pi); where they change within the
// filter's response time the factor differs from that. r is taken exactly instead:
// the mode as the local estimates describe it, m(t) = exp(int (-sigma + 2 pi i f) dt),
// is filtered by the band's gain and r = band(m) / m (a linear filter: m's scale
// cancels). Stored as ln r on the coarse grid.
struct GainCorrection {
  double dt = 0;           // grid step [s]
  Eigen::VectorXcd log_r;  // ln r(t_j), t_j = j dt from the channel's t0
  bool active = false;     // r changes along the span
  std::complex<double> log_at(double at) const {
    if (!active) return 0.0;
    const auto [j, w] = node(at);
    return (1 - w) * log_r(j) + w * log_r(j + 1);
  }
  // log_at at the grid's node j, read rather than interpolated.
  std::complex<double> log_at_node(Eigen::Index j) const { return active ? log_r(j) : 0.0; }
  double abs_at(double at) const { return std::exp(log_abs_at(at)); }
  // log_at(at).real() without the imaginary part's interpolation.
  double log_abs_at(double at) const {
    if (!active) return 0.0;
    const auto [j, w] = node(at);
    return (1 - w) * log_r(j).real() + w * log_r(j + 1).real();
  }
  // The grid interval [j, j + 1] holding `at` (clamped to the grid) and the weight of j + 1.
  std::pair<Eigen::Index, double> node(double at) const {
    const double x = std::clamp(at / dt, 0.0, static_cast<double>(log_r.size() - 1));
    const auto j = std::min<Eigen::Index>(static_cast<Eigen::Index>(x), log_r.size() - 2);
    return {j, x - static_cast<double>(j)};
  }
};

}  // namespace

namespace ringdown_detail {

// Band signal, noise floor, span and windows of one band (the set-up of the steps).
BandSetting band_setting(const ChannelSpectrum& channel, const signal::Band& band,
                         const RingdownOptions& options, const signal::BandSignal& bs) {
  BandSetting s(channel, band, options);
  s.dt = bs.dt;
  const Eigen::Index m = bs.baseband.size();
  const double duration = static_cast<double>(channel.n_record - 1) / channel.fs;
  // A faithfully continued end loses only what its continuation does not cover
  // of the filter's settling time: the transient then lies in the continuation.
  s.edge = options.taper * (band.hi - band.lo);
  const double settle = band_settling_s(band, options.taper);
  const double begin = channel.data_begin_s - channel.t0;
  const double end = channel.data_end_s - channel.t0;
  s.begin = begin;
  s.start = begin + std::max(0.0, settle - channel.continued_begin_s);
  // A clipped channel's band is read from its last clipped sample on: what the band sees of
  // the clipped stretch is the recorder's range, not the structure's response.
  if (channel.clipping.found()) s.start = std::max(s.start, channel.clipped_until_s - channel.t0);
  s.stop = std::min(duration, end - std::max(0.0, settle - channel.continued_end_s));
  s.noise_bandwidth_hz = bs.noise_bandwidth_hz;
  s.correlation = std::max(1.0, 1.0 / (s.dt * bs.noise_bandwidth_hz));
  // Period from the phase over the first part of the usable span.
  const Eigen::Index a = std::min<Eigen::Index>(m - 1, static_cast<Eigen::Index>(s.start / s.dt));
  const Eigen::Index b = std::min<Eigen::Index>(m - 1, a + std::max<Eigen::Index>(4, m / 20));
  const auto [theta_a, theta_b] = phases_at(bs.baseband, bs.carrier_hz, bs.dt, a, b);
  s.f_guess =
      b > a ? (theta_b - theta_a) / (kTwoPi * static_cast<double>(b - a) * s.dt) : bs.carrier_hz;
  s.period = 1.0 / std::max(s.f_guess, band.lo);
  s.w_min = std::max({options.min_periods * s.period, 4.0 / bs.noise_bandwidth_hz, 6.0 * s.dt});
  return s;
}

}  // namespace ringdown_detail

namespace {

// Whether the band's usable span starts at the channel's last clipped sample (band_setting).
bool clipped_from_start(const BandSetting& s) {
  const ChannelSpectrum& c = s.channel;
  return c.clipping.found() && c.clipped_until_s - c.t0 >= s.start - 1e-12;
}

// The note on a clipped channel (ChannelSpectrum::clipping), or nothing.
std::string clipping_note(const BandSetting& s, Quantity measured) {
  const Clipping& c = s.channel.clipping;
  if (!c.found()) return {};
  const std::string unit = si_unit(measured);
  std::string values;
  if (c.high_pinned) values = fmt::format("{:.6g} {}", c.high, unit);
  if (c.low_pinned)
    values += fmt::format("{}{:.6g} {}", values.empty() ? "" : " and ", c.low, unit);
  return fmt::format(
      "the channel is clipped (the sensor or the recorder past its range): {} samples pinned at "
      "{}, the last at {:.4f} s{}",
      c.samples, values, s.channel.clipped_until_s,
      clipped_from_start(s) ? "; the band is read from there on" : "");
}

}  // namespace

namespace ringdown_detail {

// Noise floor: residual RMS about fits spanning kNoiseSamples independent noise
// samples, lower quartile over the record (robust to windows the fit cannot
// follow). A window's squared misfit is noise^2 chi^2_k / dof, with dof = 2 w B
// real noise samples and k = dof less the parameters the two fits absorb; the
// chi^2 quartile is the Wilson-Hilferty approximation. The fits have the
// backbone's degree: for a narrow band the windows take seconds, over which a
// quadratic cannot follow ln A and would count model error as noise (a 36-44 Hz
// band read a floor nearly 4 times too high that way).
double noise_floor(const EnvelopePhase& ep, const BandSetting& s) {
  constexpr double kNoiseSamples = 12.0;
  const int degree = s.options.degree;
  const double w_noise = std::min(std::max(s.w_min, kNoiseSamples / s.noise_bandwidth_hz),
                                  std::max(s.w_min, (s.stop - s.start) / 2));
  std::vector<double> misfits;
  for (double c = s.start + w_noise / 2; c <= s.stop - w_noise / 2; c += w_noise / 4) {
    misfits.push_back(
        estimate_hilbert(ep.log_amp, ep.theta, s.dt, c, c, w_noise, s.correlation, 0.0, degree)
            .misfit);
  }
  const double dof = std::max(4.0, 2.0 * w_noise * s.noise_bandwidth_hz);
  const double k = std::max(2.0, dof - 2.0 * (degree + 1));
  const double wh = 1.0 - 2.0 / (9.0 * k) - 0.6745 * std::sqrt(2.0 / (9.0 * k));
  const double quartile_ratio = std::sqrt(k * wh * wh * wh / dof);
  return std::max(quantile(misfits, 0.25) / quartile_ratio, 1e-300);
}

}  // namespace ringdown_detail

namespace {

// A window holds its point in its middle half: centred where the span allows,
// pushed inside it near the span's ends (the evaluation then sits off-centre,
// at most kMaxOffset half-widths, where the fit's slope is still well determined).
constexpr double kMaxOffset = 0.5;

// The Hilbert estimate at c with the window that determines its decay rate best. The search
// starts from `search` (the previous point's choice: the best window changes slowly along the
// record); the estimate's next_search is where the next point's starts. `noise` is the floor
// of the band signal; divided by the gain correction it is the floor of the corrected signal
// at c.
Estimate hilbert_point(const EnvelopePhase& ep, const BandSetting& s, double noise,
                       const GainCorrection& gain, double c, double search,
                       Estimate* centred = nullptr) {
  const RingdownOptions& options = s.options;
  const double start = s.start, stop = s.stop, w_min = s.w_min;
  const auto window_centre = [&](double c, double w) {
    return std::clamp(c, start + w / 2, std::max(start + w / 2, stop - w / 2));
  };
  const double allowed = std::min(
      {options.max_window_s, stop - start, 2 * std::min(c - start, stop - c) / (1 - kMaxOffset)});
  const double noise_c = noise / gain.abs_at(c);
  // The window of length w centred at `centre` (c in its middle half), or centred on c.
  const auto fit_at = [&](double w, double centre) {
    return estimate_hilbert(ep.log_amp, ep.theta, s.dt, c, centre, w, s.correlation, noise_c,
                            options.degree);
  };
  const auto fit = [&](double w) { return fit_at(w, window_centre(c, w)); };
  // The slope and the envelope each take the window that determines them
  // best: longer windows average noise (std ~ W^-1.5 for the slope) but bend
  // less with the backbone (model error ~ W^2); the search stops once the
  // damping meets its target or the uncertainty clearly grows again.
  Estimate best = fit(w_min);
  Estimate best_amp = best;
  const auto met = [&] {
    return best.sigma_std <= options.target_damping_rel_std * std::abs(best.sigma);
  };
  // Below the noise threshold a point is dropped whatever its window.
  const bool buried = std::exp(best.log_amp) < options.snr_min * noise_c;
  // Start the search two steps below the previous point's choice rather than at the shortest.
  double w_first = w_min * std::sqrt(2.0);
  while (w_first * 2.0 < search) w_first *= std::sqrt(2.0);
  for (double w = w_first; !buried && w <= allowed; w *= std::sqrt(2.0)) {
    if (met()) break;
    const Estimate next = fit(w);
    if (next.log_amp_std < best_amp.log_amp_std) best_amp = next;
    if (next.sigma_std < best.sigma_std) {
      best = next;
    } else if (next.sigma_std > 1.5 * best.sigma_std) {
      break;  // clearly past the minimum: model error now dominates
    }
  }
  // A point whose centred windows leave its damping over the limit (it would be dropped)
  // may do better with its window shifted along the record (the point at kMaxOffset of
  // the half-width from the centre): on the side where the backbone bends less (a tail
  // after a strongly nonlinear start or an exchange) the window can grow longer before
  // its model error dominates. As above, the search stops at the first window that meets
  // the target. (The next point's search starts from the centred choice: a shifted
  // window is this point's alone.)
  const double centred_window = best.window;
  if (centred != nullptr) {
    *centred = best;
    centred->log_amp = best_amp.log_amp;
    centred->log_amp_std = best_amp.log_amp_std;
  }
  if (!buried && best.sigma_std > options.max_damping_rel_std * std::abs(best.sigma)) {
    const double longest = std::min(options.max_window_s, stop - start);
    for (const double side : {1.0, -1.0}) {
      for (double w = w_first; w <= longest && !met(); w *= std::sqrt(2.0)) {
        const double centre =
            std::clamp(c + side * kMaxOffset * w / 2, start + w / 2, stop - w / 2);
        if (std::abs(centre - c) > kMaxOffset * w / 2 + 1e-12) continue;
        const Estimate next = fit_at(w, centre);
        if (next.sigma_std < best.sigma_std) best = next;
      }
    }
  }
  best.log_amp = best_amp.log_amp;
  best.log_amp_std = best_amp.log_amp_std;
  best.next_search = buried ? search : centred_window;
  return best;
}

// Hilbert estimates along the span, every w_min / points_per_window, each with the window
// that determines its decay rate best (hilbert_point).
std::vector<Estimate> hilbert_estimates(const EnvelopePhase& ep, const BandSetting& s, double noise,
                                        const GainCorrection& gain,
                                        std::vector<Estimate>* centred = nullptr) {
  const double start = s.start, stop = s.stop, w_min = s.w_min;
  std::vector<Estimate> est;
  const double step = w_min / s.options.points_per_window;
  const double margin = w_min / 2 * (1 - kMaxOffset);
  double search = w_min;
  for (double c = start + margin; c <= stop - margin + 1e-12; c += step) {
    Estimate centred_one;
    est.push_back(hilbert_point(ep, s, noise, gain, c, search, &centred_one));
    if (centred != nullptr) centred->push_back(centred_one);
    search = est.back().next_search;
  }
  return est;
}

// Peak-fitting estimates from the extrema of the (full-rate, gain-corrected)
// band-passed displacement y, each refined by a parabola.
std::vector<Estimate> peak_estimates(const Eigen::VectorXd& y, const BandSetting& s, double noise) {
  const RingdownOptions& options = s.options;
  const double ts = 1.0 / s.channel.fs;
  std::vector<double> tk, lk;
  const Eigen::Index j0 = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(s.start / ts));
  const Eigen::Index j1 =
      std::min<Eigen::Index>(y.size() - 2, static_cast<Eigen::Index>(s.stop / ts));
  for (Eigen::Index j = j0; j <= j1; ++j) {
    const bool is_max = y(j) > y(j - 1) && y(j) >= y(j + 1) && y(j) > 0;
    const bool is_min = y(j) < y(j - 1) && y(j) <= y(j + 1) && y(j) < 0;
    if (!is_max && !is_min) continue;
    const double ym = y(j - 1), y0 = y(j), yp = y(j + 1);
    const double den = ym - 2 * y0 + yp;
    const double d = den != 0 ? 0.5 * (ym - yp) / den : 0.0;
    if (std::abs(d) > 1) continue;
    const double peak = y0 - 0.25 * (ym - yp) * d;
    // Successive extrema alternate in sign; a repeated sign is noise: keep the larger.
    if (!tk.empty() && ((peak > 0) == (lk.back() > 0))) {
      if (std::abs(peak) > std::abs(lk.back())) {
        tk.back() = (static_cast<double>(j) + d) * ts;
        lk.back() = peak;
      }
      continue;
    }
    tk.push_back((static_cast<double>(j) + d) * ts);
    lk.push_back(peak);
  }
  const Eigen::Index np = static_cast<Eigen::Index>(tk.size());
  Eigen::VectorXd tpk(np), lpk(np);
  for (Eigen::Index k = 0; k < np; ++k) {
    tpk(k) = tk[k];
    lpk(k) = std::log(std::abs(lk[k]));
  }
  const double half_count = std::max(3.0, std::ceil(s.w_min / s.period));  // per half window
  // Extrema per correlation length of the band-passed noise.
  const double peak_correlation = std::max(1.0, 2.0 * s.f_guess / s.noise_bandwidth_hz);
  std::vector<Estimate> est;
  for (double k = half_count; k + half_count < static_cast<double>(np);
       k += std::max(1.0, 2 * half_count / options.points_per_window)) {
    // The same search as for the Hilbert estimates.
    Estimate best =
        estimate_peaks(lpk, tpk, k, half_count, options.degree, peak_correlation, noise);
    for (double wider = half_count * std::sqrt(2.0);
         best.sigma_std > options.target_damping_rel_std * std::abs(best.sigma) && k - wider >= 0 &&
         k + wider <= static_cast<double>(np - 1) && wider * s.period <= options.max_window_s;
         wider *= std::sqrt(2.0)) {
      const Estimate next =
          estimate_peaks(lpk, tpk, k, wider, options.degree, peak_correlation, noise);
      if (next.sigma_std < best.sigma_std) {
        best = next;
      } else if (next.sigma_std > 1.5 * best.sigma_std) {
        break;
      }
    }
    est.push_back(best);
  }
  return est;
}

}  // namespace

namespace ringdown_detail {

// Whether an estimate is usable: finite, decaying, above the noise threshold.
bool usable(const Estimate& e, double noise, double snr_min) {
  return std::isfinite(e.sigma) && std::isfinite(e.omega_d) && e.omega_d > 0 && e.sigma > 0 &&
         std::isfinite(e.sigma_std) && std::exp(e.log_amp) >= snr_min * noise;
}

}  // namespace ringdown_detail

namespace {

// The estimates the band-gain correction's model of the mode is made of (gain_correction): the
// times [s], frequencies [Hz] and decay rates [1/s over 2 pi] of the usable ones after
// `model_from` [s].
struct ModelPoints {
  std::vector<double> t, f, d;
};

ModelPoints model_points(const std::vector<Estimate>& est, const BandSetting& s, double noise,
                         double model_from) {
  ModelPoints p;
  std::vector<double>&t = p.t, &f = p.f, &d = p.d;
  for (const Estimate& e : est) {
    if (!usable(e, noise, s.options.snr_min) || !(e.t > model_from)) continue;
    t.push_back(e.t);
    f.push_back(e.omega_d / kTwoPi);
    d.push_back(e.sigma / kTwoPi);
  }
  return p;
}

// The model's frequency and decay rate along the grid (at(x), x only growing): interpolated
// between the points (two or more), held beyond them or, `continued`, continued along the
// straight line through the end point and the one a settling time inside, up to the impact and
// the record's end.
class GainModel {
 public:
  GainModel(const ModelPoints& p, const BandSetting& s, bool continued)
      : t(p.t), f(p.f), d(p.d), continued_(continued) {
    // The model's frequency and decay rate: interpolated between the estimates, held
    // beyond them for one settling time (all the filter reaches), then a steady tone.
    reach = band_settling_s(s.band, s.options.taper);
    const double data_end = s.channel.data_end_s - s.channel.t0;
    inside_first_ = inside_from(0);
    inside_last_ = inside_from(t.size() - 1);
    // Continued back to the impact and on to the record's end only: beyond them the band
    // sees the record's continuation, which holds the mode as the end of the data has it.
    continued_from_ = std::max(t.front() - reach, std::min(t.front(), s.begin));
    continued_to_ = std::min(t.back() + reach, std::max(t.back(), data_end));
  }

  // The model's frequency and decay rate at x. Between the estimates, t[k - 1] <= x < t[k]:
  // k walks along with the grid (x only grows), not searched anew at each point.
  std::pair<double, double> at(double x) {
    if (x <= t.front()) {
      if (!continued_) return {f.front(), d.front()};
      return {line_from(f, 0, x), line_from(d, 0, x)};
    }
    if (x >= t.back()) {
      if (!continued_) return {f.back(), d.back()};
      return {line_from(f, t.size() - 1, x), line_from(d, t.size() - 1, x)};
    }
    while (t[k_] <= x) ++k_;
    const double w = (x - t[k_ - 1]) / (t[k_] - t[k_ - 1]);
    return {(1 - w) * f[k_ - 1] + w * f[k_], (1 - w) * d[k_ - 1] + w * d[k_]};
  }

  const std::vector<double>&t, &f, &d;
  double reach = 0;  ///< the band's settling time [s]

 private:
  // The estimate a settling time inside the span from `end` (or the other end).
  size_t inside_from(size_t end) const {
    const double inside = end == 0 ? t.front() + reach : t.back() - reach;
    size_t k = static_cast<size_t>(std::lower_bound(t.begin(), t.end(), inside) - t.begin());
    k = std::min(k, t.size() - 1);
    if (k == end) k = end == 0 ? t.size() - 1 : 0;
    return k;
  }
  double line_from(const std::vector<double>& v, size_t end, double x) const {
    const size_t k = end == 0 ? inside_first_ : inside_last_;
    const double xe = std::clamp(x, continued_from_, continued_to_);
    return v[end] + (v[k] - v[end]) / (t[k] - t[end]) * (xe - t[end]);
  }
  bool continued_ = false;
  size_t inside_first_ = 0, inside_last_ = 0;
  double continued_from_ = 0, continued_to_ = 0;
  size_t k_ = 1;
};

// The model m on the grid (t_j = j dt, `grid` nodes) as ln |m| and the phase of its baseband
// (the carrier taken off); m decays only within a settling time of the points.
struct ModelSignal {
  Eigen::VectorXd log_m, phase;
};

ModelSignal model_signal(GainModel& model, Eigen::Index grid, const BandSetting& s,
                         double carrier_hz) {
  const std::vector<double>& t = model.t;
  const double reach = model.reach;
  ModelSignal out;
  Eigen::VectorXd& log_m = out.log_m;  // m past the grid is zero padding
  Eigen::VectorXd& phase = out.phase;
  log_m.resize(grid);
  phase.resize(grid);
  double la = 0, ph = 0;
  for (Eigen::Index j = 0; j < grid; ++j) {
    const double x = static_cast<double>(j) * s.dt;
    const bool near = x > t.front() - reach && x < t.back() + reach;
    log_m(j) = la;
    phase(j) = ph;
    const auto [f_x, d_x] = model.at(x);
    la -= (near ? kTwoPi * std::max(0.0, d_x) : 0.0) * s.dt;
    ph += kTwoPi * (f_x - carrier_hz) * s.dt;
  }
  return out;
}

// The model through the band: |m| (scaled to 1 at its largest), cos and sin of its phase, and
// band(m) on the grid (transforms of n points).
struct FilteredModel {
  Eigen::ArrayXd mag, cos, sin;
  Eigen::VectorXcd filtered;
};

FilteredModel filtered_model(const ModelSignal& ms, Eigen::Index grid, Eigen::Index n,
                             const BandSetting& s, double carrier_hz, signal::FftCache& cache) {
  const Eigen::VectorXd &log_m = ms.log_m, &phase = ms.phase;
  const double top = log_m.maxCoeff();
  // m = |m| u, u = e^{i phase}: r = band(m) / m = band(m) conj(u) / |m| needs no complex
  // division, and |r| no hypot (both a tenth of process's time together).
  // Forward transform from the inverse one: sum_j m_j e^{-2 pi i jk/n} = n conj(ifft(conj m)),
  // conj m written straight into the transform's input (m past the grid is zero padding).
  // |m|, cos and sin of its phase: one vector call each (signal/vector_math.h).
  FilteredModel out;
  Eigen::ArrayXd &mag = out.mag, &cos = out.cos, &sin = out.sin;
  mag.resize(grid), cos.resize(grid), sin.resize(grid);
  signal::exp_array((log_m.array() - top).max(-700.0), mag);
  signal::sincos_array(phase.array(), sin, cos);
  signal::Fft& fft = cache.get(n);
  std::complex<double>* conj_m = fft.complex_input();
  for (Eigen::Index j = 0; j < grid; ++j) conj_m[j] = {mag(j) * cos(j), -(mag(j) * sin(j))};
  Eigen::VectorXcd spec = fft.inverse_complex_head(n).conjugate() * static_cast<double>(n);
  // The band's gain at each bin around the carrier: the same for every pass and channel.
  const Eigen::VectorXd& gain = cache.gain(
      {1.0, static_cast<double>(n), s.dt, carrier_hz, s.band.lo, s.band.hi, s.options.taper}, [&] {
        Eigen::VectorXd g(n);
        const double df = 1.0 / (static_cast<double>(n) * s.dt);
        for (Eigen::Index k = 0; k < n; ++k) {
          const double fk = carrier_hz + static_cast<double>(k < n / 2 ? k : k - n) * df;
          g(k) = fk > 0 ? signal::band_gain(s.band, s.options.taper, fk) : 0.0;
        }
        return g;
      });
  std::complex<double>* filter_in = fft.complex_input();
  for (Eigen::Index k = 0; k < n; ++k) filter_in[k] = spec(k) * gain(k);
  out.filtered = fft.inverse_complex_head(grid);  // the padding dropped
  return out;
}

// g.log_r = ln r, r = band(m) / m, its phase unwrapped; returns the range of ln |r| over the
// span.
double set_log_r(GainCorrection& g, const FilteredModel& fm, Eigen::Index grid,
                 const BandSetting& s) {
  const Eigen::ArrayXd &mag = fm.mag, &cos = fm.cos, &sin = fm.sin;
  const Eigen::VectorXcd& filtered = fm.filtered;
  // r = band(m) conj(u) / |m|, then ln |r| + i arg r, the logarithms and arguments in one
  // vector call each (std::log of a complex near |r| = 1 takes a slow exact path, a tenth of
  // process's time once, for a precision far below what r is known to).
  Eigen::ArrayXd r_re(grid), r_im(grid), abs_r(grid);
  for (Eigen::Index j = 0; j < grid; ++j) {
    const std::complex<double> r =
        mag(j) > 1e-250 ? filtered(j) * std::complex<double>(cos(j), -sin(j)) / mag(j) : 1.0;
    r_re(j) = r.real();
    r_im(j) = r.imag();
    abs_r(j) = std::sqrt(std::norm(r));  // |r| is near 1: no overflow to guard
  }
  Eigen::ArrayXd log_abs(grid), arg(grid);
  signal::log_array(abs_r.max(1e-12), log_abs);
  signal::atan2_array(r_im, r_re, arg);
  g.log_r.resize(grid);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (Eigen::Index j = 0; j < grid; ++j) {
    std::complex<double> lr =
        abs_r(j) > 1e-12 ? std::complex<double>(log_abs(j), arg(j)) : std::log(1e-12);
    if (j > 0) {  // unwrap the phase (round() only off its usual 0: a libm call a sample)
      const double turns = (g.log_r(j - 1).imag() - lr.imag()) / kTwoPi;
      if (std::abs(turns) >= 0.5) lr.imag(lr.imag() + kTwoPi * std::round(turns));
    }
    g.log_r(j) = lr;
    const double x = static_cast<double>(j) * s.dt;
    if (x >= s.start && x <= s.stop) {
      lo = std::min(lo, lr.real());
      hi = std::max(hi, lr.real());
    }
  }
  return hi - lo;
}

// The band gain along the first pass's usable estimates (see GainCorrection).
// Inactive where ln G varies by less than 1e-9 over them (the mode in the flat part).
// Beyond the estimates the model's frequency and decay rate are held, or, with
// `continued`, continued along the straight line through the end estimate and the one a
// settling time inside, up to the impact and the record's end (see add_model_errors).
// The model is made of the estimates after `model_from` [s] alone (those of an energy
// exchange before it do not decay as the mode does; -infinity: all).
GainCorrection gain_correction(const std::vector<Estimate>& est, const BandSetting& s, double noise,
                               Eigen::Index grid, double carrier_hz, double model_from,
                               signal::FftCache& cache, bool continued = false) {
  GainCorrection g;
  g.dt = s.dt;
  const ModelPoints points = model_points(est, s, noise, model_from);
  if (points.t.size() < 2 || grid < 4) return g;
  GainModel model(points, s, continued);
  const double reach = model.reach;
  // Zero-padded by three settling times, where the band's kernel is down to exp(-100): the
  // model's start, its largest part, then adds nothing to r where the model has decayed by
  // decades (twice the grid where that is less; twice it always cost a twentieth of the time).
  const Eigen::Index n =
      std::min(signal::fast_size(2 * grid),
               signal::fast_size(grid + static_cast<Eigen::Index>(std::ceil(3 * reach / s.dt))));
  const ModelSignal ms = model_signal(model, grid, s, carrier_hz);
  const FilteredModel fm = filtered_model(ms, grid, n, s, carrier_hz, cache);
  const double range = set_log_r(g, fm, grid, s);
  // Below 1e-4 over the span, r moves a decay rate by less than 1e-4 over a window.
  g.active = continued || range > 1e-4;
  return g;
}

// The gain correction's iteration stops once ln r changes by less than this over the span.
constexpr double kGainConverged = 1e-4;

// Model errors taken across one window of neighbouring estimates, added to each
// estimate's uncertainty:
// - A point's amplitude is uncertain too; along a backbone that bends, that moves
//   where the point belongs: (d sigma / d ln A) std(ln A) for sigma and
//   (d omega_d / d ln A) std(ln A) for omega_d.
// - The gain correction rests on estimates it corrects: the change of ln r between
//   its last two iterations, fitted over the point's window as the signal was and
//   scaled by the tail 1 / (1 - q) of a geometric series of such changes, is the slope
//   error still left. q is the ratio of the last change to the one before (`earlier`
//   to `previous`) over the point's own window, so that estimates the correction cannot
//   settle (an envelope that grows while two modes exchange energy) leave points a
//   settling time away alone (q taken over the whole span once made every point's
//   uncertainty infinite and a 1:2 internal resonance lost its whole backbone); the tail
//   is unbounded where the changes do not shrink, and 10 where they no longer
//   shrink but are already below kGainConverged. Where the correction alternates between
//   two states (its last two changes about equal, q <= 1.1, and cancelling to less than
//   half of one: an alternation that grows is no such pair), the truth lies
//   between them and the tail is 1: a moved band of the LMS twin beside slow content
//   alternated by 6e-4 in ln r (two changes summing to 6e-14), and every point's uncertainty
//   had been infinite.
// - Between the impact and the first estimate (and the last one and the record's end)
//   the mode is not estimated, but the zero-phase filter reaches a settling time into
//   that part: the difference between the correction with the model held there (`gain`)
//   and continued along its line (`continued`), fitted the same way, is the slope error
//   from not knowing it. It matters for the first points of a mode that drifts along the
//   band's slope (a correction of a third of the decay rate, known to a few per cent).
// The model errors' parts that rest on the gain correction, on the grid.
struct GainSteps {
  bool active = false;   // the correction was applied (gain.active)
  bool earlier = false;  // an earlier correction is known (earlier.active)
  Eigen::VectorXd step_re, step_im, ends_re, ends_im, step_abs, before_abs, two_steps_abs;
};

GainSteps gain_steps(const GainCorrection& gain, const GainCorrection& previous,
                     const GainCorrection& continued, const GainCorrection& earlier,
                     Eigen::Index grid) {
  GainSteps g;
  g.active = gain.active;
  g.earlier = earlier.active;
  if (!gain.active) return g;
  g.step_re.resize(grid);
  g.step_im.resize(grid);
  g.ends_re.resize(grid);
  g.ends_im.resize(grid);
  g.step_abs = Eigen::VectorXd::Zero(grid);
  g.before_abs = g.step_abs;
  g.two_steps_abs = g.step_abs;
  // The corrections at the grid's nodes, which are their own (log_at interpolated between
  // two of them at every node, 2 % of process's time).
  for (Eigen::Index j = 0; j < grid; ++j) {
    const std::complex<double> step = gain.log_at_node(j) - previous.log_at_node(j);
    g.step_re(j) = step.real();
    g.step_im(j) = step.imag();
    g.step_abs(j) = magnitude(step);
    if (earlier.active) {
      g.before_abs(j) = magnitude(previous.log_at_node(j) - earlier.log_at_node(j));
      g.two_steps_abs(j) = magnitude(gain.log_at_node(j) - earlier.log_at_node(j));
    }
    const std::complex<double> ends = continued.log_at_node(j) - gain.log_at_node(j);
    g.ends_re(j) = ends.real();
    g.ends_im(j) = ends.imag();
  }
  return g;
}

// What the model errors add to one estimate's sigma and omega_d: from its amplitude along the
// backbone's slope (sigma, omega_d; `lo` and `hi` are the estimates a window's half-width
// before and after it) and from the gain correction (gain, gain_w).
struct ModelError {
  double sigma = 0, omega_d = 0, gain = 0, gain_w = 0;
};

ModelError model_error(const Estimate& e, const Estimate& lo, const Estimate& hi,
                       const GainSteps& g, double dt, int degree) {
  ModelError out;
  const double dl = hi.log_amp - lo.log_amp;
  if (&hi != &lo && std::abs(dl) > 0) {
    out.sigma = (hi.sigma - lo.sigma) / dl * e.log_amp_std;
    out.omega_d = (hi.omega_d - lo.omega_d) / dl * e.log_amp_std;
  }
  if (!g.active) return out;
  const Eigen::Index grid = g.step_abs.size();
  const auto [half, offset, stride, j0, j1] = window_on_grid(e, dt, grid);
  const double now = g.step_abs.segment(j0, j1 - j0 + 1).maxCoeff();
  const double before = g.before_abs.segment(j0, j1 - j0 + 1).maxCoeff();
  const double q = !g.earlier   ? 0.0
                   : before > 0 ? now / before
                   : now > 0    ? std::numeric_limits<double>::infinity()
                                : 0.0;
  const double two = g.two_steps_abs.segment(j0, j1 - j0 + 1).maxCoeff();
  const double tail = q < 0.9                       ? 1.0 / (1.0 - q)
                      : now < kGainConverged        ? 10.0
                      : q <= 1.1 && two < 0.5 * now ? 1.0
                                                    : std::numeric_limits<double>::infinity();
  const auto scaled = [tail](double x) { return x == 0 ? 0.0 : tail * std::abs(x); };
  // The four series share one design (its weights and factors made once).
  const auto [step_s, step_w, ends_s, ends_w] =
      signal::fit_local_quad({&g.step_re, &g.step_im, &g.ends_re, &g.ends_im}, 0.0, dt, e.centre,
                             half, degree, 1.0, stride, offset);
  out.gain = std::hypot(scaled(step_s.slope), ends_s.slope);
  out.gain_w = std::hypot(scaled(step_w.slope), ends_w.slope);
  return out;
}

// The estimates' spacing (add_model_errors takes a window's neighbours by it).
double spacing_of(const std::vector<Estimate>& est) {
  const size_t ne = est.size();
  return ne < 2 ? 0.0 : (est[ne - 1].t - est[0].t) / static_cast<double>(ne - 1);
}

// How many estimates `spacing` apart a window's half-width reaches (at most ne).
size_t reach_of(const Estimate& e, double spacing, size_t ne) {
  return static_cast<size_t>(
      std::min(std::ceil(e.window / 2 / std::max(1e-12, spacing)), static_cast<double>(ne)));
}

// The model errors added to each estimate's uncertainty; returns them per estimate.
std::vector<ModelError> add_model_errors(std::vector<Estimate>& est, const GainSteps& g, double dt,
                                         int degree) {
  const size_t ne = est.size();
  std::vector<ModelError> add(ne);
  if (ne < 2) return add;
  const double spacing = spacing_of(est);
  for (size_t i = 0; i < ne; ++i) {
    const Estimate& e = est[i];
    // A peak-fitting estimate whose extrema do not advance in its window (a fitted half period
    // of zero or less: omega_d <= 0, never usable) has no window to take errors across.
    if (!(e.window > 0) || !std::isfinite(e.window)) continue;
    const size_t reach = reach_of(e, spacing, ne);
    const size_t lo = i >= reach ? i - reach : 0, hi = std::min(ne - 1, i + reach);
    add[i] = model_error(e, est[lo], est[hi], g, dt, degree);
  }
  // After the impact, while the correction's error in the decay rate falls from estimate to
  // estimate, each point's is at least the one of the estimate before it where that estimate
  // lies inside the point's fit window: the fit's data come from all of it, and with the mode
  // on the band's slope the error's slope fitted over the window misses how fast it falls (on
  // the LMS twin beside a mode at 146-147 Hz, 12 %, 1.6 % and 0.27 % of the decay rate at
  // three points in a row, the third reading the damping 2.2-4.3 % high at 1.1-1.9 times its
  // stated 3 sigma). Taken from each estimate's own error, not carried further.
  std::vector<double> own(ne);
  for (size_t i = 0; i < ne; ++i) own[i] = add[i].gain;
  for (size_t i = 1; i < ne && own[i] < own[i - 1]; ++i) {
    const Estimate& e = est[i];
    if (e.window > 0 && std::isfinite(e.window) && est[i - 1].t >= e.centre - e.window / 2)
      add[i].gain = own[i - 1];
  }
  for (size_t i = 0; i < ne; ++i) {
    est[i].sigma_std = std::hypot(std::hypot(est[i].sigma_std, add[i].sigma), add[i].gain);
    est[i].omega_d_std = std::hypot(est[i].omega_d_std, std::hypot(add[i].omega_d, add[i].gain_w));
  }
  return add;
}

// The kept points: the longest run of valid estimates, bridging gaps of at most
// kMaxGap points (one point whose uncertainty strays over the limit is dropped on
// its own rather than cutting the span in two) and any gap whose points all stand above
// the noise threshold (`above`): those are dropped for their own reasons (the envelope
// not decaying or its decay not known to the limit, as while two modes exchange energy),
// not for noise, and the decay on either side of them is still the mode's. (Cutting there
// lost mode 2's locked harmonic after 0.5 s in the internal-resonance twin.) A longer gap
// is bridged only where the frequency on its two sides agrees within two half-power
// half-widths (or three of its uncertainties): a band holding two resolved modes that beat
// through the gap would otherwise join one mode's points to the other's. (Mode 2's free
// ring-down and mode 1's locked harmonic in mode 2's band differ by 0.7 Hz, 1.02 half-widths.)
// Returns [begin, end) and the count of valid points in it.
struct Run {
  size_t begin = 0, end = 0, count = 0;
};

Run longest_run(const std::vector<Estimate>& est, const std::vector<char>& valid,
                const std::vector<char>& above) {
  constexpr size_t kMaxGap = 2;
  // Whether the valid points a and b (a < b) can be one mode's across the gap between them.
  const auto same_mode = [&est](size_t a, size_t b) {
    const Estimate &p = est[a], &q = est[b];
    const double width = 0.5 * (std::abs(p.sigma) + std::abs(q.sigma));
    const double tolerance = std::max(2 * width, 3.0 * std::hypot(p.omega_d_std, q.omega_d_std));
    return std::abs(p.omega_d - q.omega_d) <= tolerance;
  };
  Run best;
  for (size_t i = 0; i < valid.size();) {
    if (!valid[i]) {
      ++i;
      continue;
    }
    size_t j = i, count = 0, last = i;
    while (j < valid.size()) {
      if (valid[j]) {
        if (j - last > kMaxGap + 1 && !same_mode(last, j)) break;
        ++count;
        last = j;
      } else if (j - last > kMaxGap && !above[j]) {
        break;
      }
      ++j;
    }
    if (count > best.count) best = {i, last + 1, count};
    i = last + 1;
  }
  return best;
}

// The backbone of the valid estimates in `run`, uncertainties expanded.
Backbone backbone_of(const std::vector<Estimate>& est, const std::vector<char>& valid,
                     const std::vector<char>& exchange, Run run, double t0, double noise,
                     const RingdownOptions& options) {
  Backbone bb;
  bb.exchange.resize(static_cast<Eigen::Index>(run.count));
  const auto n = static_cast<Eigen::Index>(run.count);
  for (Eigen::VectorXd* v : {&bb.time_s, &bb.amplitude, &bb.frequency_hz, &bb.damping,
                             &bb.frequency_std_hz, &bb.damping_std, &bb.damped_frequency_hz,
                             &bb.decay_rate, &bb.displacement, &bb.snr, &bb.window_s}) {
    v->resize(n);
  }
  const int k_out = derivative_order(options.amplitude);
  Eigen::Index i = 0;
  for (size_t k = run.begin; k < run.end; ++k) {
    if (!valid[k]) continue;
    const Estimate& e = est[k];
    const double wn = std::hypot(e.omega_d, e.sigma);
    const double a = std::exp(e.log_amp);
    bb.time_s(i) = t0 + e.t;
    bb.displacement(i) = a;
    bb.amplitude(i) = a * std::pow(wn, k_out);
    bb.frequency_hz(i) = wn / kTwoPi;
    bb.damping(i) = e.sigma / wn;
    bb.frequency_std_hz(i) =
        std::hypot(e.omega_d * e.omega_d_std, e.sigma * e.sigma_std) / wn / kTwoPi;
    bb.damping_std(i) = e.sigma_std / wn;
    bb.damped_frequency_hz(i) = e.omega_d / kTwoPi;
    bb.decay_rate(i) = e.sigma;
    bb.snr(i) = a / noise;
    bb.window_s(i) = e.window;
    bb.exchange(i) = exchange[k] ? 1 : 0;
    ++i;
  }
  assert(i == n);
  // Reported uncertainties are expanded: coverage factor times one sigma.
  bb.frequency_std_hz *= options.coverage_factor;
  bb.damping_std *= options.coverage_factor;
  return bb;
}

// Local estimates of the band signal z (coarse grid, or full rate for peak fitting).
std::vector<Estimate> estimates_of(const Eigen::VectorXcd& z, double carrier_hz,
                                   const BandSetting& s, double noise, const GainCorrection& gain) {
  if (s.options.method == Method::kHilbert) {
    return hilbert_estimates(envelope_phase(z, carrier_hz, s.dt), s, noise, gain);
  }
  return peak_estimates(z.real(), s, noise);
}

// z divided by the gain correction at each sample (grid step dt from channel.t0).
// (exp(-ln r) as exp(-Re ln r) (cos, sin)(-Im ln r), each one vector call.)
Eigen::VectorXcd corrected(const Eigen::VectorXcd& z, double dt, const GainCorrection& gain) {
  const Eigen::Index n = z.size();
  Eigen::ArrayXd minus_re(n), minus_im(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const std::complex<double> l = gain.log_at(static_cast<double>(j) * dt);
    minus_re(j) = -l.real();
    minus_im(j) = -l.imag();
  }
  Eigen::ArrayXd scale(n), sin(n), cos(n);
  signal::exp_array(minus_re, scale);
  signal::sincos_array(minus_im, sin, cos);
  Eigen::VectorXcd out(n);
  for (Eigen::Index j = 0; j < n; ++j)
    out(j) = z(j) * std::complex<double>(scale(j) * cos(j), scale(j) * sin(j));
  return out;
}

// Low-amplitude limit of y(A): a weighted straight line y = y0 + c A through the
// lower half of the kept span (in log amplitude, at least 4 points, superharmonic and
// exchange points left out); y0 and its one-sigma from the points' one-sigma, inflated by the
// square root of the points per window (neighbouring points share their data).
struct Limit {
  double value = 0, std = 0;
  Eigen::Index lo = -1, hi = -1;  // lowest- and highest-amplitude points fitted
  // Reduced chi-square of the fitted points about the line (about their mean where fewer than
  // 3 are fitted) against their one-sigma, not inflated; infinite for a single point.
  double chi2 = std::numeric_limits<double>::infinity();
};

Limit low_amplitude_limit(const Backbone& bb, const Eigen::VectorXd& y, const Eigen::VectorXd& u,
                          double inflate) {
  Limit out;
  const Eigen::Index n = bb.size();
  std::vector<Eigen::Index> order;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (bb.harmonic(i) == 0 && bb.exchange(i) == 0) order.push_back(i);
  }
  if (order.empty()) return out;
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) {
    return bb.displacement(a) < bb.displacement(b);
  });
  const double l0 = std::log(bb.displacement(order.front()));
  const double l1 = std::log(bb.displacement(order.back()));
  size_t used = 0;
  while (used < order.size() &&
         (used < 4 || std::log(bb.displacement(order[used])) <= 0.5 * (l0 + l1))) {
    ++used;
  }
  double sw = 0, swa = 0, swaa = 0, swy = 0, sway = 0;
  for (size_t k = 0; k < used; ++k) {
    const Eigen::Index i = order[k];
    const double w = 1.0 / std::max(1e-300, u(i) * u(i));
    const double a = bb.displacement(i);
    sw += w;
    swa += w * a;
    swaa += w * a * a;
    swy += w * y(i);
    sway += w * a * y(i);
  }
  const double det = sw * swaa - swa * swa;
  if (used >= 3 && det > 1e-12 * sw * swaa) {
    // The line at the lowest fitted amplitude, not its intercept: extrapolating a straight
    // line to zero amplitude moves with the range each hit happens to span (a microslip
    // backbone bends as A^(chi+1) there), which reads as hit-to-hit scatter.
    const double a0 = bb.displacement(order.front());
    const double c0 = (swaa * swy - swa * sway) / det, c1 = (sw * sway - swa * swy) / det;
    out.value = c0 + c1 * a0;
    out.std = std::sqrt((swaa - 2 * a0 * swa + a0 * a0 * sw) / det) * inflate;
    double chi = 0;
    for (size_t k = 0; k < used; ++k) {
      const Eigen::Index i = order[k];
      const double r = (y(i) - c0 - c1 * bb.displacement(i)) / std::max(1e-150, u(i));
      chi += r * r;
    }
    out.chi2 = chi / static_cast<double>(used - 2);
  } else {
    out.value = swy / sw;
    out.std = std::sqrt(1.0 / sw) * inflate;
    double chi = 0;
    for (size_t k = 0; k < used; ++k) {
      const Eigen::Index i = order[k];
      const double r = (y(i) - out.value) / std::max(1e-150, u(i));
      chi += r * r;
    }
    if (used >= 2) out.chi2 = chi / static_cast<double>(used - 1);
  }
  out.lo = order.front();
  out.hi = order[used - 1];
  return out;
}

// The one-sided spectrum of the analysed record's samples [i0, i0 + count), zero-padded to
// n points (set here). A short record's is padded to 4 times their length for resolution.
// A long record's bins, a record's duration apart, need no finer grid: its samples are
// taken out of the spectrum and transformed again in one buffer (through the transform's own
// buffer up to 2^17 points, in place above: padded to 4x it was 130 bytes a sample, five times
// the rest of the record's analysis).
Eigen::VectorXcd measured_spectrum(const ChannelSpectrum& channel, Eigen::Index i0,
                                   Eigen::Index count, signal::FftCache& cache, Eigen::Index& n) {
  if (!channel.padded_by_pad_s()) {
    const Eigen::VectorXd y = cache.get(channel.n_fft).inverse_real(channel.spectrum);
    n = signal::fast_size(4 * count);
    return cache.get(n).forward(y.segment(i0, count));
  }
  Eigen::VectorXcd buffer = Eigen::VectorXcd::Zero(channel.n_fft / 2 + 1);  // bins not kept: 0
  buffer.head(channel.spectrum.size()) = channel.spectrum;
  cache.get(channel.n_fft).inverse_real_in_place(buffer.data());
  double* r = reinterpret_cast<double*>(buffer.data());
  std::memmove(r, r + i0, sizeof(double) * static_cast<size_t>(count));
  n = 2 * signal::fast_size((count + 1) / 2);  // even, at most n_fft
  std::fill(r + count, r + 2 * buffer.size(), 0.0);
  cache.get(n).forward_through_buffer(buffer.data());
  buffer.conservativeResize(n / 2 + 1);
  return buffer;
}

}  // namespace

namespace ringdown_detail {

// Full half-power width [Hz] of the spectral peak nearest `fp` in the measured part of the
// record alone (measured_spectrum), the crossings interpolated linearly between bins: 2 zeta f
// for a decaying mode. (The continuation runs the decay backwards too; its spectrum read
// 0.77-0.79 times 2 zeta f on modes of 0.3-3 % damping.)
double half_power_width(const ChannelSpectrum& channel, double fp, signal::FftCache& cache) {
  const auto at = [&](double t) {
    return std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::round(t * channel.fs)), 0,
                                    channel.n_record - 1);
  };
  const Eigen::Index i0 = at(channel.data_begin_s - channel.t0);
  const Eigen::Index i1 = at(channel.data_end_s - channel.t0);
  if (i1 <= i0 + 4) return 0.0;
  Eigen::Index n = 0;
  const Eigen::VectorXcd x = measured_spectrum(channel, i0, i1 - i0 + 1, cache, n);
  const double df = channel.fs / static_cast<double>(n);
  const auto mag = [&](Eigen::Index k) { return std::abs(x(k)); };
  Eigen::Index kp =
      std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::round(fp / df)), 1, x.size() - 2);
  while (kp > 1 && mag(kp - 1) > mag(kp)) --kp;
  while (kp + 2 < x.size() && mag(kp + 1) > mag(kp)) ++kp;
  const double half = mag(kp) / std::sqrt(2.0);
  Eigen::Index kl = kp, kr = kp;
  while (kl > 0 && mag(kl) > half) --kl;
  while (kr + 1 < x.size() && mag(kr) > half) ++kr;
  const auto cross = [&](Eigen::Index below, Eigen::Index above) {
    const double a = mag(below), b = mag(above);
    return static_cast<double>(below) +
           (b > a ? (half - a) / (b - a) : 0.0) * static_cast<double>(above - below);
  };
  return (cross(kr, kr - 1) - cross(kl, kl + 1)) * df;
}

}  // namespace ringdown_detail

namespace {

// Bins first..last of a spectrum, compared by magnitude as std::abs gives it: from the
// squared magnitudes where they differ by far more than their rounding (1e-12 against
// 1e-15), else from std::abs itself, so the comparisons are those of std::abs but cost a
// hypot only at near ties.
class SpectrumMagnitudes {
 public:
  SpectrumMagnitudes(const Eigen::VectorXcd& spectrum, Eigen::Index first, Eigen::Index last)
      : spectrum_(spectrum), first_(first), squared_(last - first + 1) {
    for (Eigen::Index k = first; k <= last; ++k) {
      const double re = spectrum(k).real(), im = spectrum(k).imag();
      squared_(k - first) = re * re + im * im;
    }
  }
  // |X(a)| > |X(b)|, or >= with or_equal (false when either is NaN).
  bool greater(Eigen::Index a, Eigen::Index b, bool or_equal = false) const {
    constexpr double kClear = 1 + 1e-12, kNormal = 1e-290;
    const double sa = squared_(a - first_), sb = squared_(b - first_);
    if (std::isfinite(sa) && std::isfinite(sb) && std::min(sa, sb) >= kNormal) {
      if (sa > sb * kClear) return true;
      if (sb > sa * kClear) return false;
    }
    const double ma = std::abs(spectrum_(a)), mb = std::abs(spectrum_(b));
    return or_equal ? ma >= mb : ma > mb;
  }

 private:
  const Eigen::VectorXcd& spectrum_;
  Eigen::Index first_;
  Eigen::VectorXd squared_;
};

}  // namespace

namespace ringdown_detail {

// The highest local maximum of the measured samples' spectrum over bins [k0, k1] (k0 >= 0; a
// rising or falling edge of the range is not a peak), or -1 where it has none.
Eigen::Index strongest_peak(const ChannelSpectrum& channel, Eigen::Index k0, Eigen::Index k1) {
  const Eigen::Index first = std::max<Eigen::Index>(k0, 1) - 1;
  const Eigen::Index last = std::min<Eigen::Index>(k1 + 1, channel.measured.size() - 1);
  if (last <= first) return -1;
  const SpectrumMagnitudes mag(channel.measured, first, last);
  Eigen::Index kp = -1;
  for (Eigen::Index k = first + 1; k <= k1; ++k) {
    if (k + 1 >= channel.measured.size() || !mag.greater(k, k - 1) ||
        !mag.greater(k, k + 1, true)) {
      continue;
    }
    if (kp < 0 || mag.greater(k, kp)) kp = k;
  }
  return kp;
}

}  // namespace ringdown_detail

namespace {

// What the measured samples' spectrum shows around a band with no span: the strongest peak
// near it, or that the band is narrower than kWidths half-power widths of its mode. `read_width`
// is the width the mode was read through (the typed band's unless follow_mode moved it): a band
// already read wider is not told to widen.
std::string spectral_advice(const ChannelSpectrum& channel, const signal::Band& band, double taper,
                            signal::FftCache& cache, double read_width = 0) {
  constexpr double kWidths = kBandWidths;
  if (channel.measured.size() < 3) return {};
  const double df = channel.measured_df();
  const double width = band.hi - band.lo;
  const auto bin = [&](double f) {
    return channel.measured_bin(f, 1, channel.measured.size() - 1);
  };
  const Eigen::Index k0 = bin(band.lo - width), k1 = bin(band.hi + width);
  if (k1 <= k0 + 2) return {};
  const Eigen::Index kp = strongest_peak(channel, k0, k1);
  if (kp < 0) {
    return fmt::format("no mode in the band and no spectral peak from {:.2f} to {:.2f} Hz",
                       static_cast<double>(k0) * df, static_cast<double>(k1) * df);
  }
  const double fp = static_cast<double>(kp) * df;
  const double edge = taper * width;
  if (fp < band.lo + edge / 2 || fp > band.hi - edge / 2) {
    return fmt::format(
        "no mode in the band: the strongest spectral peak near it is at {:.2f} Hz, outside the "
        "band's half-gain points {:.2f} to {:.2f} Hz",
        fp, band.lo + edge / 2, band.hi - edge / 2);
  }
  const double hp = half_power_width(channel, fp, cache);
  if (std::max(width, read_width) < kWidths * hp) {
    return fmt::format(
        "the band ({:.3g} Hz wide) is narrower than {:g} times the half-power width of its mode "
        "({:.3g} Hz at {:.2f} Hz): widen it to at least {:.3g} Hz",
        width, kWidths, hp, fp, kWidths * hp);
  }
  return fmt::format("the strongest spectral peak in the band is at {:.2f} Hz", fp);
}

}  // namespace

namespace ringdown_detail {

// True when the spectrum of the channel's measured samples (ChannelSpectrum::measured, not the
// continuations: run backwards, the one before the record once peaked at the edge of a 1:2
// resonance twin's 220:270 Hz band, 20 times above the record's own 242 Hz mode) has its
// largest magnitude over `sub` strictly inside it (two bins or more from either edge): a mode
// of its own there. A heavily damped mode above
// the range only leaks its tail into it, rising towards the upper edge, and its displacement
// (integrated twice from acceleration) can then outweigh the mode's own band: a 100 Hz mode
// of 5 % damping in 80:120 Hz once had every point flagged as following twice a "mode" at
// 40:60 Hz that is not there.
bool has_interior_peak(const ChannelSpectrum& channel, const signal::Band& sub) {
  const Eigen::Index last = channel.measured.size() - 1;
  const auto bin = [&](double f) { return channel.measured_bin(f, 0, last); };
  const Eigen::Index k0 = bin(sub.lo), k1 = bin(sub.hi);
  if (k1 <= k0 + 4) return true;  // too few bins to tell: leave the decision to the fits
  const SpectrumMagnitudes mag(channel.measured, k0, k1);
  Eigen::Index kp = k0;
  for (Eigen::Index k = k0 + 1; k <= k1; ++k) {
    if (mag.greater(k, kp)) kp = k;
  }
  return kp >= k0 + 2 && kp <= k1 - 2;
}

}  // namespace ringdown_detail

namespace {

// Marks the points of `bb` that follow n times (n = 2, 3) the frequency of a stronger
// mode: the channel's own band [lo/n, hi/n] carries a larger displacement envelope
// there and n times its frequency is within the point's frequency uncertainty, widened
// by kPull of the point's half-power half-width (decay rate / 2 pi). The widening is for
// a band that holds the locked harmonic and what is left of its own mode: in a 1:2
// internal resonance (122 and 243 Hz, ringdown_test.cc) mode 2's band follows 2 f1 once
// its free part has decayed, but a residue of the free mode a tenth of the harmonic's
// size, 1 Hz away, pulls the read frequency 0.04-0.07 Hz off 2 f1, three times the
// points' stated uncertainty; an independent mode 1 Hz from 2 f1 stays well outside.
// The widening is at most kMaxPull of the frequency (0.1 %, above the twin's 0.03 %): for a
// heavily damped mode a tenth of its half-width would reach a separate mode a hertz away.
// Uses this band and channel alone. Returns, per point, n times the stronger mode's frequency
// where a stronger mode's n-th multiple was read over the point's window (the first n that
// was), else 0: set_linear_values asks whether the band can tell its mode from it.
constexpr double kPull = 0.1;
constexpr double kMaxPull = 1e-3;

/// Per point: n times the stronger mode's frequency [Hz] and decay rate [1/s] where a stronger
/// mode's n-th multiple was read over the point's window (the first n that was), else 0.
struct Multiples {
  std::vector<double> hz, rate;
};

Multiples mark_superharmonics(Backbone& bb, const ChannelSpectrum& channel, Quantity measured,
                              const signal::Band& band, const RingdownOptions& options,
                              signal::FftCache& cache) {
  bb.harmonic = Eigen::VectorXi::Zero(bb.size());
  Multiples multiples{std::vector<double>(static_cast<size_t>(bb.size()), 0.0),
                      std::vector<double>(static_cast<size_t>(bb.size()), 0.0)};
  std::vector<double>& multiple_hz = multiples.hz;
  const double duration = static_cast<double>(channel.n_record - 1) / channel.fs;
  for (int n = 2; n <= 3; ++n) {
    const signal::Band sub{band.lo / n, band.hi / n};
    if (band_settling_s(sub, options.taper) > duration) continue;
    if (!has_interior_peak(channel, sub)) continue;
    const signal::BandSignal zs = band_signal(channel, measured, sub, options, cache);
    const EnvelopePhase ep = envelope_phase(zs.baseband, zs.carrier_hz, zs.dt);
    const double correlation = std::max(1.0, 1.0 / (zs.dt * zs.noise_bandwidth_hz));
    const double span = static_cast<double>(zs.baseband.size() - 1) * zs.dt;
    std::vector<char> near(static_cast<size_t>(bb.size()), 0);
    for (Eigen::Index i = 0; i < bb.size(); ++i) {
      if (bb.harmonic(i) != 0) continue;
      const double t = bb.time_s(i) - channel.t0;
      const double w = std::min(bb.window_s(i), span);
      const double c = std::clamp(t, w / 2, span - w / 2);
      if (static_cast<Eigen::Index>(w / zs.dt) < options.degree + 4) continue;
      // A sub-band whose envelope stays below half the point's amplitude over the whole
      // window cannot be fitted above it: no fit needed (most points of most bands).
      const auto j0 = std::clamp<Eigen::Index>(static_cast<Eigen::Index>((c - w / 2) / zs.dt), 0,
                                               ep.amp.size() - 1);
      const auto j1 = std::clamp<Eigen::Index>(static_cast<Eigen::Index>((c + w / 2) / zs.dt) + 1,
                                               j0, ep.amp.size() - 1);
      if (ep.amp.segment(j0, j1 - j0 + 1).maxCoeff() < 0.5 * bb.displacement(i)) continue;
      const auto [fa, fp] =
          signal::fit_local_pair(ep.log_amp, ep.theta, 0.0, zs.dt, c, w / 2, options.degree,
                                 correlation, 1, std::clamp((t - c) / (w / 2), -1.0, 1.0));
      const double f_sub = fp.slope / kTwoPi;
      const double u_sub = std::hypot(fp.slope_std, fp.slope_change) / kTwoPi;
      const double tol = std::hypot(
          std::hypot(bb.frequency_std_hz(i), options.coverage_factor * n * u_sub),
          std::min(kPull * bb.decay_rate(i) / kTwoPi, kMaxPull * bb.damped_frequency_hz(i)));
      const bool stronger = std::exp(fa.value) > bb.displacement(i);
      const double off = std::abs(bb.damped_frequency_hz(i) - n * f_sub);
      if (stronger && off <= tol) bb.harmonic(i) = n;
      if (stronger && multiple_hz[static_cast<size_t>(i)] == 0) {
        multiple_hz[static_cast<size_t>(i)] = n * f_sub;
        multiples.rate[static_cast<size_t>(i)] = -n * fa.slope;
      }
      near[static_cast<size_t>(i)] = stronger && off <= kMaxPull * bb.damped_frequency_hz(i);
    }
    // Points after the first marked one (between two marked ones, or after the last) that lie
    // within kMaxPull of n times the stronger mode's frequency follow it too: the locked
    // harmonic with more of the band's own mode left beside it, which pulls the read frequency
    // further than kPull allows. In the 1:2 twin of a double beam struck near mode 2, eight such
    // points (0.68-0.83 s, 0.09-0.11 Hz off 2 f1) between marked ones gave mode 2's linear
    // values 243.92 Hz and damping 0.0031, against 243.0 Hz and 0.006, unmarked; two after the
    // last, where the harmonic runs on to the record's lowest amplitudes, 244.13 Hz and 0.0035.
    Eigen::Index first = 0;
    while (first < bb.size() && bb.harmonic(first) != n) ++first;
    for (Eigen::Index j = first + 1; j < bb.size(); ++j)
      if (bb.harmonic(j) == 0 && near[static_cast<size_t>(j)]) bb.harmonic(j) = n;
  }
  return multiples;
}

// Whether the linear values' points could be a stronger mode's multiple as much as the band's
// own mode; the reason if so, else empty. Two components df apart are told apart over a window
// w only where df w >= 1 (the window's resolution 1/w: their correlation over it,
// sin(pi df w) / (pi df w), is 0.64 at df w = 1/2 and first vanishes at 1). Where n times the
// stronger mode's frequency lies within that resolution of the linear frequency at its
// lowest-amplitude point, the window sees the band's mode and the multiple as one; a single
// mode then still reads steadily, within its points' uncertainties, while the two beside each
// other beat: the read frequency and decay rate swing as their shares change. So the linear
// values are refused where, in addition, the fitted points scatter about their line by more
// than kSteadyChi2 (reduced chi-square against their one-sigma: on average more than 3 sigma),
// or where one point alone cannot show it. In twins of a double beam (mode 2 at 243, 244 or
// 245.22 Hz beside mode 1's locked 2 f1, 244 Hz, struck as a hammer strikes), the linear
// values read 243.26-244.62 Hz, 0.5-1.45 Hz off mode 2, with reduced chi-square 4-2834 in
// frequency or damping (largest of the two at least 110), while mode 2 read in tune (244 Hz,
// 2 f1 within 0.06 Hz) gave 243.97-244.01 Hz at 1.0 or less.
constexpr double kSteadyChi2 = 10.0;

std::string multiple_within_resolution(const Backbone& bb, const std::vector<double>& multiple_hz,
                                       const Limit& lf, const Limit& lz, double frequency_hz) {
  const auto lo = static_cast<size_t>(lf.lo);
  if (multiple_hz.size() != static_cast<size_t>(bb.size()) || multiple_hz[lo] <= 0) return {};
  const double resolution = 1.0 / bb.window_s(lf.lo);
  if (std::abs(frequency_hz - multiple_hz[lo]) >= resolution) return {};
  const double chi2 = std::max(lf.chi2, lz.chi2);
  if (chi2 <= kSteadyChi2) return {};
  return fmt::format(
      "no linear values: the band cannot tell its mode from a multiple of a stronger mode's "
      "frequency there: at its lowest-amplitude point the linear fit reads {:.3f} Hz, {:.3f} "
      "Hz from {:.3f} Hz (that multiple), within the resolution of the point's window ({:.2f} "
      "Hz), and {}",
      frequency_hz, std::abs(frequency_hz - multiple_hz[lo]), multiple_hz[lo], resolution,
      std::isfinite(chi2)
          ? fmt::format("its points swing about their line as two components beside each other "
                        "beat, not as one mode reads (reduced chi-square {:.3g}, above {:g})",
                        chi2, kSteadyChi2)
          : std::string("it rests on one point, which cannot show that it reads one mode"));
}

// Whether the linear values' lowest points read the band's own mode come back from under a
// stronger mode's multiple; the reason if not, else empty. Where points that follow the multiple
// (Backbone::harmonic) lie above the fit's lowest point in amplitude, the band's own mode had
// given way to the multiple there; it can come back at lower amplitudes only if it dies slower
// than the multiple does (n times the stronger mode's decay rate). Points below that do not
// decay clearly slower (by more than kDyingSigmas of their own one-sigma) read the two together
// or the multiple alone, not the mode: faster, the two nearly cancelling; at the multiple's
// rate, the multiple itself (mode 2 at 244.3 Hz, 0.006, alpha 3e9, seed 1: its eight lowest
// points decay at 5.6 to 4.6 1/s toward 2 f1's 4.6, 243.6 to 243.73 Hz, and stated 243.728
// +- 0.057 Hz and damping 0.00302 +- 0.00010, mode 1's own 0.003 read at 2 f1). In the 1:2 twin of
// the double beam with mode 2 at 244.0 Hz (2 f1 at 243.95 Hz, alpha 2e9, both modes struck as a
// hammer strikes), the four points below the six that follow 2 f1 drifted from 243.61 to 243.22 Hz
// and their damping rose to 0.0078, decaying at 11.9 1/s against the multiple's 4.5, steadily
// enough (reduced chi-square 1.3) to pass multiple_within_resolution: linear values 243.23 +- 0.047
// Hz and 0.0078, where mode 2 is 244.0 Hz and 0.006. Mode 2 in tune at 0.2 % (3.1 1/s, slower than
// 2 f1's 4.6) keeps its linear values.
constexpr double kDyingSigmas = 3.0;

std::string dying_under_a_multiple(const Backbone& bb, const Multiples& multiples, const Limit& lf,
                                   const RingdownOptions& options) {
  if (multiples.rate.size() != static_cast<size_t>(bb.size())) return {};
  const double floor = bb.displacement(lf.lo), top = bb.displacement(lf.hi);
  double highest_following = 0;
  for (Eigen::Index i = 0; i < bb.size(); ++i) {
    if (bb.harmonic(i) != 0) highest_following = std::max(highest_following, bb.displacement(i));
  }
  if (!(highest_following > floor)) return {};
  Eigen::Index dying = 0, below = 0;
  double rate = 0, multiple_rate = 0;
  for (Eigen::Index i = 0; i < bb.size(); ++i) {
    const double a = bb.displacement(i);
    if (bb.harmonic(i) != 0 || bb.exchange(i) != 0 || a < floor || a > top ||
        a >= highest_following)
      continue;
    ++below;
    const auto u = static_cast<size_t>(i);
    const double sigma_std =
        bb.damping_std(i) / options.coverage_factor * kTwoPi * bb.frequency_hz(i);
    if (multiples.rate[u] > 0 && bb.decay_rate(i) - multiples.rate[u] > -kDyingSigmas * sigma_std) {
      ++dying;
      rate = bb.decay_rate(i);
      multiple_rate = multiples.rate[u];
    }
  }
  if (below == 0 || 2 * dying <= below) return {};
  return fmt::format(
      "no linear values: below points that follow a multiple of a stronger mode's frequency "
      "(superharmonic), {} of the {} fitted points decay no slower than that multiple (the "
      "lowest of them at {:.3g} 1/s against its {:.3g} 1/s): the band's own mode, dying no "
      "slower, cannot come back from under it, and the points read the two together or the "
      "multiple alone",
      dying, below, rate, multiple_rate);
}

// Whether a stronger mode's multiple still carries the linear values' lowest point; the reason
// if so (given the values' expanded uncertainties), else empty. The band reads its own mode
// (amplitude a, rate sigma, omega) beside the multiple (b, sigma_m, omega_m) as a e^{-sigma t}
// (1 + s e^{i phi}), s = b / a: the log of the second factor moves the read rate and angular
// frequency by the real and imaginary parts of s (sigma - sigma_m + i (omega_m - omega))
// e^{i phi} / (1 + s e^{i phi}), at most s / (1 - s) |sigma_m - sigma + i (omega_m - omega)|
// (s < 1). At a point that follows the multiple (Backbone::harmonic) the band reads the
// multiple, b about the point's amplitude; carried to the lowest fitted point at the
// multiple's decay rate, b over that point's amplitude is s there. Where the pull this bounds
// exceeds the stated uncertainty the linear values are refused. In the 1:2 twins of a double
// beam (mode 2 at 243.8-245 Hz, 0.2-0.6 %, alpha 1e9-3e9, both modes struck or mode 1 alone,
// read in 230:258 Hz), 35 stated linear values read s 0.04-1.06 at the lowest point (bounds
// 1.7-2400 times the uncertainty where s < 1) and lay 1.2-15 times their expanded uncertainty
// off mode 2, one 0.2 times (by the beat's phase; its other seed 1.4); where the nearest such
// point lies 1.3-1.8 s earlier and the multiple died at 11-19 1/s, s < 4e-5 (bounds under 0.01
// of the uncertainty) and the values stay, within 0.5 times their uncertainty of mode 2.
std::string multiple_still_carries(const Backbone& bb, const Multiples& multiples, Eigen::Index lo,
                                   double frequency_hz, double frequency_u, double damping_u) {
  if (multiples.rate.size() != static_cast<size_t>(bb.size())) return {};
  Eigen::Index near = -1;
  for (Eigen::Index j = 0; j < bb.size(); ++j) {
    const auto u = static_cast<size_t>(j);
    if (bb.harmonic(j) == 0 || !(multiples.rate[u] > 0) || !(multiples.hz[u] > 0)) continue;
    if (near < 0 ||
        std::abs(bb.time_s(j) - bb.time_s(lo)) < std::abs(bb.time_s(near) - bb.time_s(lo)))
      near = j;
  }
  if (near < 0) return {};
  const auto m = static_cast<size_t>(near);
  const double share = bb.displacement(near) *
                       std::exp(-multiples.rate[m] * (bb.time_s(lo) - bb.time_s(near))) /
                       bb.displacement(lo);
  const double omega = kTwoPi * frequency_hz;
  const double apart =
      std::hypot(multiples.rate[m] - bb.decay_rate(lo), kTwoPi * multiples.hz[m] - omega);
  const double pull =
      share < 1 ? share / (1 - share) * apart : std::numeric_limits<double>::infinity();
  if (pull / kTwoPi <= frequency_u && pull / omega <= damping_u) return {};
  return fmt::format(
      "no linear values: a multiple of a stronger mode's frequency (superharmonic, {:.3f} Hz at "
      "{:.4f} s) still carries the lowest fitted point: carried there at its decay rate ({:.3g} "
      "1/s) it is {:.2f} of that point's amplitude, and beside it the point's frequency and "
      "damping read {}, more than their uncertainty ({:.3g} Hz, {:.3g})",
      multiples.hz[m], bb.time_s(near), multiples.rate[m], share,
      std::isfinite(pull)
          ? fmt::format("up to {:.3g} Hz and {:.3g} off", pull / kTwoPi, pull / omega)
          : std::string("the multiple more than the mode"),
      frequency_u, damping_u);
}

// Whether the linear values' lowest point may still read an exchange's swings; the reason if
// so, else empty. After an exchange (Backbone::exchange) with a stronger mode whose multiple
// lies df from the band's mode, the band's envelope swings at df (the mode beside the multiple
// it takes energy through); its turns come every 1 / (2 df), and the marking ends at the last
// one found. A point less than half a swing after the last marked one cannot show that the
// swings ended: the next turn was not due. Where its window w holds fewer than
// kSwingsAveraged swings, the swings also reach its fit: a straight line fitted over w takes
// 3 (sin x - x cos x) / x^3 of a swing's slope (x = pi df w), 30 % at df w = 1 (the window's
// resolution), 7.6 % at df w = 2 and 3 / x^2 beyond. In the 1:2 twins of a double beam (band
// 230:258 Hz, mode 2 at 243-245 Hz, 0.2 %, alpha 1e9-3e9, both modes struck), 14 stated linear
// values (df w 0.27-1.24, the lowest point 0.04-0.31 of a swing after the last marked one) lay
// 1.4-7.1 times their expanded uncertainty off mode 2 (13 of 14; the 14th 0.9); those of mode 2
// at 246 and 247.66 Hz (df w 5.8-11.7, 0.43-3.1 swings after) within 0.3 times it.
constexpr double kSwingsAveraged = 2.0;

std::string exchange_swings_unfinished(const Backbone& bb, const Multiples& multiples,
                                       Eigen::Index lo, double frequency_hz) {
  const auto u = static_cast<size_t>(lo);
  if (multiples.hz.size() != static_cast<size_t>(bb.size()) || !(multiples.hz[u] > 0)) return {};
  double last = -std::numeric_limits<double>::infinity();
  for (Eigen::Index j = 0; j < bb.size(); ++j) {
    if (bb.exchange(j) != 0 && bb.time_s(j) < bb.time_s(lo)) last = std::max(last, bb.time_s(j));
  }
  if (!std::isfinite(last)) return {};
  const double df = std::abs(frequency_hz - multiples.hz[u]);
  const double swings = (bb.time_s(lo) - last) * df;
  if (df * bb.window_s(lo) >= kSwingsAveraged || swings >= 0.5) return {};
  return fmt::format(
      "no linear values: the lowest fitted point ({:.4f} s) lies {:.2f} of a swing after the "
      "last point marked as exchanging energy ({:.4f} s; the swings at {:.3f} Hz, the mode beside "
      "a multiple of a stronger mode's frequency, {:.3f} Hz): their next turn was not due, so "
      "the points cannot show that they ended, and the point's window ({:.3f} s) holds fewer "
      "than {:g} of them, too few to average them out of its damping and frequency",
      bb.time_s(lo), swings, last, df, multiples.hz[u], bb.window_s(lo), kSwingsAveraged);
}

// Linear values: the straight-line fit of the backbone's lower half, at its lowest amplitude.
void set_linear_values(RingdownSummary& sum, const Backbone& bb, const Multiples& multiples,
                       const RingdownOptions& options) {
  const double k = options.coverage_factor;
  const double inflate = std::sqrt(options.points_per_window);
  const Limit lf = low_amplitude_limit(bb, bb.frequency_hz, bb.frequency_std_hz / k, inflate);
  const Limit lz = low_amplitude_limit(bb, bb.damping, bb.damping_std / k, inflate);
  if (lf.lo < 0 || lz.lo < 0) {
    sum.linear_reason =
        sum.exchange_points == 0
            ? fmt::format(
                  "no linear values: every one of the {} points follows a multiple of a stronger "
                  "mode's frequency (superharmonic)",
                  bb.size())
            : fmt::format(
                  "no linear values: every one of the {} points follows a multiple of a stronger "
                  "mode's frequency (superharmonic, {}) or exchanges energy with another mode "
                  "(exchange, {})",
                  bb.size(), sum.superharmonic_points, sum.exchange_points);
    return;
  }
  if (!std::isfinite(lf.value) || !std::isfinite(lz.value) || !std::isfinite(lf.std) ||
      !std::isfinite(lz.std) || !(lf.value > 0)) {
    sum.linear_reason = "no linear values: the low-amplitude fit is not finite";
    return;
  }
  // One or two points of the band's own mode above a harmonic that runs to lower amplitudes
  // are no low-amplitude limit: there the band's own mode has given way to a multiple of a
  // stronger mode's frequency. (A 1:2 twin's mode 2, struck too, gave 244.51 Hz and damping
  // 0.0035 from the one point left above 13 harmonic ones: mode 2 is 243.0 Hz, 0.006.)
  Eigen::Index own = 0, harmonic_below = 0;
  for (Eigen::Index i = 0; i < bb.size(); ++i) {
    own += bb.harmonic(i) == 0 && bb.exchange(i) == 0;
    harmonic_below += bb.harmonic(i) != 0 && bb.displacement(i) < bb.displacement(lf.lo);
  }
  if (own < 3 && harmonic_below > 0) {
    sum.linear_reason = fmt::format(
        "no linear values: {} point(s) read the band's own mode, above {} that follow a "
        "multiple of a stronger mode's frequency (superharmonic) to lower amplitudes, where the "
        "band's mode has given way to it",
        own, harmonic_below);
    return;
  }
  sum.linear_reason = multiple_within_resolution(bb, multiples.hz, lf, lz, lf.value);
  if (!sum.linear_reason.empty()) return;
  sum.linear_reason = dying_under_a_multiple(bb, multiples, lf, options);
  if (!sum.linear_reason.empty()) return;
  sum.linear_reason =
      multiple_still_carries(bb, multiples, lf.lo, lf.value, k * lf.std, k * lz.std);
  if (!sum.linear_reason.empty()) return;
  sum.linear_reason = exchange_swings_unfinished(bb, multiples, lf.lo, lf.value);
  if (!sum.linear_reason.empty()) return;
  sum.linear_frequency_hz = lf.value;
  sum.linear_frequency_std_hz = k * lf.std;
  sum.linear_damping = lz.value;
  sum.linear_damping_std = k * lz.std;
  sum.linear_fit_min = bb.amplitude(lf.lo);
  sum.linear_fit_max = bb.amplitude(lf.hi);
}

// "1 point" or "n points", for the notes.
std::string points(size_t n) { return fmt::format("{} point{}", n, n == 1 ? "" : "s"); }

// The summary's note on an exchange found: up to when, how it shows, against which band, and
// how many points are marked; or, where it is a neighbour's leak (Exchange::leak_hz), that.
std::string exchange_note(const Exchange& exchange, const RingdownSummary& sum,
                          const ChannelSpectrum& channel) {
  if (exchange.leak_hz > 0) {
    const double r = exchange.partner;
    return fmt::format(
        "up to {:.4f} s a neighbouring mode beyond the band's edge (its spectral peak at "
        "{:.2f} Hz, outside the typed band) leaks through it, no energy exchange: the envelope's "
        "decay rate falls from the start to the mode's own as the more damped neighbour dies "
        "out, and no mode takes energy (the envelope in {} the band at most {:.1f} times its "
        "noise floor): {} there marked (column exchange), their frequency and damping pulled by "
        "the neighbour, left out of the linear values",
        channel.t0 + exchange.end_t, exchange.leak_hz,
        r >= 1 ? fmt::format("{:g} times", r) : fmt::format("1/{:g} of", std::round(1 / r)),
        exchange.partner_snr, points(sum.exchange_points));
  }
  const double r = exchange.partner;
  if (exchange.swings) {
    return fmt::format(
        "up to {:.4f} s the mode exchanges energy with another mode (the envelope swings faster "
        "than its fits follow, as the power the envelope in {} the band takes and gives: it "
        "explains {:.0f} % of the swings): {} there marked (column exchange), their damping "
        "apparent (damping plus transfer), left out of the linear values",
        channel.t0 + exchange.end_t,
        r >= 1 ? fmt::format("{:g} times", r) : fmt::format("1/{:g} of", std::round(1 / r)),
        100 * exchange.explained, points(sum.exchange_points));
  }
  const std::string turns =
      exchange.turns.size() == 1
          ? std::string("the envelope's decay rate turns once")
          : fmt::format("the envelope's decay rate turns {} times", exchange.turns.size());
  const std::string how =
      exchange.quadrature
          ? std::string(
                "the envelope's decay rate falls from the start to the mode's own while the "
                "other, locked a quarter period from the drive, takes the energy: the excess "
                "rate follows the power it takes")
      : exchange.one_way
          ? std::string(
                "the envelope's decay rate falls from the start to the mode's own as "
                "the other's rises to its own")
      : exchange.fed_dip
          ? std::string(
                "the envelope's decay rate dips below the rate it settles to, as the other's "
                "rises")
      : !exchange.turns.empty() && exchange.grows ? turns + " and the envelope grows"
      : !exchange.turns.empty()                   ? turns
                                                  : std::string("the envelope grows");
  return fmt::format(
      "up to {:.4f} s the mode exchanges energy with another mode ({}, against the decay rate "
      "of the envelope in {} the band): {} there marked (column exchange), their "
      "damping apparent (damping plus transfer), left out of the linear values",
      channel.t0 + exchange.end_t, how,
      r >= 1 ? fmt::format("{:g} times", r) : fmt::format("1/{:g} of", std::round(1 / r)),
      points(sum.exchange_points));
}

// Notes for the summary: what was left out at the start and why, superharmonic and
// exchange points.
std::vector<std::string> span_notes(const BandSetting& s, const std::vector<Estimate>& est,
                                    const Run& run, const GainCorrection& applied, double noise,
                                    const RingdownSummary& sum, const Exchange& exchange,
                                    Quantity measured) {
  const ChannelSpectrum& channel = s.channel;
  const signal::Band& band = s.band;
  const RingdownOptions& options = s.options;
  const GainCorrection& previous = applied;  // the correction the estimates carry
  std::vector<std::string> notes;
  const std::string clipped = clipping_note(s, measured);
  if (!clipped.empty()) notes.push_back(clipped);
  if (s.start > s.begin + 1e-9 && !clipped_from_start(s)) {
    notes.push_back(fmt::format(
        "the first {:.3f} s after the impact are not used: the band's filter settles in "
        "{:.3f} s and the record's backward continuation holds for {:.3f} s",
        s.start - s.begin, band_settling_s(band, options.taper), channel.continued_begin_s));
  }
  if (run.begin > 0) {
    size_t over = 0, other = 0;
    double worst = 0;
    for (size_t i = 0; i < run.begin; ++i) {
      const Estimate& e = est[i];
      if (usable(e, noise / previous.abs_at(e.t), options.snr_min)) {
        ++over;
        worst = std::max(worst, e.sigma_std / e.sigma);
      } else {
        ++other;
      }
    }
    // Only the reasons that apply: "0 with a damping uncertainty ... (up to 0.0 %)" read as
    // if an uncertainty had been measured.
    std::vector<std::string> why;
    if (over > 0) {
      why.push_back(fmt::format(
          "{} with a damping uncertainty over the {:.1f} % limit (up to {:.1f} %) or read "
          "through less than half the band's gain",
          over, 100 * options.max_damping_rel_std, 100 * worst));
    }
    if (other > 0)
      why.push_back(fmt::format("{} not decaying or below the noise threshold", other));
    const std::string which =
        run.begin == 1 ? fmt::format("1 point at {:.4f} s", channel.t0 + est.front().t)
                       : fmt::format("{} from {:.4f} s to {:.4f} s", points(run.begin),
                                     channel.t0 + est.front().t, channel.t0 + est[run.begin - 1].t);
    notes.push_back(fmt::format("{} dropped before the span: {}", which, fmt::join(why, ", ")));
  }
  if (sum.superharmonic_points > 0) {
    notes.push_back(
        fmt::format("{} an integer multiple of a stronger mode's frequency (superharmonic, "
                    "column harmonic); left out of the linear values",
                    sum.superharmonic_points == 1 ? std::string("1 point follows")
                                                  : points(sum.superharmonic_points) + " follow"));
  }
  if (exchange.found()) notes.push_back(exchange_note(exchange, sum, s.channel));
  return notes;
}

// Amplitudes of a channel analysed at `scale` (ChannelSpectrum::scale) back in the record's
// units; no backbone if they lie beyond the range of a double.
void unscale(Ringdown& r, double scale) {
  Backbone& bb = r.backbone;
  RingdownSummary& sum = r.summary;
  bb.amplitude /= scale;
  bb.displacement /= scale;
  sum.linear_fit_min /= scale;
  sum.linear_fit_max /= scale;
  if (bb.amplitude.allFinite() && bb.displacement.allFinite() && std::isfinite(sum.linear_fit_max))
    return;
  r.backbone = Backbone{};
  const double carrier = sum.carrier_hz, peak_time = sum.peak_time_s;
  sum = RingdownSummary{};
  sum.carrier_hz = carrier;
  sum.peak_time_s = peak_time;
  sum.message =
      "the backbone's amplitudes exceed the largest double (1.8e308): check the channel's unit "
      "and scale";
}

// How the decay rate the partner of an exchange still takes after it enters the estimates there
// (add_transfer): not at all, joined to their uncertainty, or taken off their decay rates.
enum class TransferUse { kNone, kJoined, kTakenOff };

// Local estimates along the span and the band-gain correction they carry.
struct CorrectedEstimates {
  std::vector<Estimate> est;       ///< the last pass's estimates
  GainCorrection previous;         ///< the correction `est` was made with
  std::vector<ModelError> errors;  ///< each estimate's model errors (add_model_errors)
  Exchange exchange;               ///< an energy exchange with another mode, from the first pass
  Relaxation relaxation;           ///< what the exchange's partner still does after it
  TransferUse transfer_use = TransferUse::kNone;  ///< how add_transfer used its decay rate
};

// Local estimates along the span: a first pass on the band signal, then, where the
// band's effect on the mode changes along the span (the mode on a sloping part of
// the gain), passes on the band signal divided by that effect (GainCorrection).
CorrectedEstimates corrected_estimates(const ChannelSpectrum& channel, const signal::Band& band,
                                       const RingdownOptions& options, const signal::BandSignal& bs,
                                       const EnvelopePhase& ep, const BandSetting& s, double noise,
                                       Quantity measured, signal::FftCache& cache) {
  signal::BandSignal full;
  if (options.method == Method::kPeaks) {
    signal::BandOptions fo;
    fo.taper = options.taper;
    fo.order = derivative_order(measured);
    fo.full_rate = true;
    full = signal::band_analytic(channel.spectrum, channel.n_record, channel.n_fft, channel.fs,
                                 band, fo, cache);
  }
  const signal::BandSignal& z = options.method == Method::kPeaks ? full : bs;
  Exchange exchange;
  // The mode's model for the correction leaves out an exchange's estimates (exchange, set
  // after the first pass): their decay is not the mode's own, and a correction modelled on
  // it never settles (its uncertainty made the first 0.5 s of a 1:2 internal resonance
  // infinite, and the long windows of its tail reaching back there).
  const auto correct = [&](const std::vector<Estimate>& from) {
    return gain_correction(from, s, noise, bs.baseband.size(), bs.carrier_hz, exchange.end_t,
                           cache);
  };
  const auto redo = [&](const GainCorrection& g) {
    return estimates_of(corrected(z.baseband, z.dt, g), z.carrier_hz, s, noise, g);
  };
  // The first pass: on bs's envelope and phase `ep` (made by the caller) for the Hilbert
  // method.
  std::vector<Estimate> centred;
  std::vector<Estimate> est = options.method == Method::kHilbert
                                  ? hilbert_estimates(ep, s, noise, {}, &centred)
                                  : estimates_of(z.baseband, z.carrier_hz, s, noise, {});
  exchange = exchange_of(est, noise, s, measured, cache);
  // The centred rates differ from those only where a point's window was shifted (else the same
  // search would run twice on the same rates).
  const auto shifted = [&] {
    for (size_t i = 0; i < centred.size(); ++i) {
      if (centred[i].window != est[i].window || centred[i].centre != est[i].centre) return true;
    }
    return false;
  };
  if (!exchange.found() && !centred.empty() && shifted()) {
    Exchange swings = exchange_of(centred, noise, s, measured, cache);
    if (swings.found() && swings.turns.size() >= 2 && !swings.grows && !swings.one_way &&
        partner_holds_energy(swings, s, measured, cache) &&
        !beats_with_second_mode(centred, channel, band, ep, s, noise))
      exchange = std::move(swings);
  }
  if (!exchange.found()) exchange = swinging_exchange(est, noise, s, measured, cache);
  GainCorrection previous;
  GainCorrection gain = correct(est);
  // Iterated until ln r changes by less than kConverged anywhere in the span (each
  // pass's estimates describe the mode better, and r with them; the error shrinks by
  // about half per pass where the mode's own width is comparable to the band's edge).
  // The estimates kept are those of the last pass, made with `previous`; what is left
  // to the fixed point is about the last change times 1 / (1 - q), q the ratio of the
  // last two changes (a geometric tail, taken over each point's window in
  // add_model_errors), and unbounded if the changes do not shrink.
  constexpr int kMaxPasses = 12;
  GainCorrection earlier;
  for (int pass = 0; pass < kMaxPasses && gain.active; ++pass) {
    est = redo(gain);
    if (pass > 0) earlier = std::move(previous);
    previous = gain;
    gain = correct(est);
    if (!gain.active) break;
    const auto j0 = static_cast<Eigen::Index>(s.start / s.dt);
    const auto j1 =
        std::min<Eigen::Index>(gain.log_r.size(), static_cast<Eigen::Index>(s.stop / s.dt) + 1);
    double now = 0;
    for (Eigen::Index j = j0; j < j1; ++j) {
      now = std::max(now, magnitude(gain.log_r(j) - previous.log_r(j)));
    }
    if (now < kGainConverged) break;
  }
  const GainCorrection continued = gain.active
                                       ? gain_correction(est, s, noise, bs.baseband.size(),
                                                         bs.carrier_hz, exchange.end_t, cache, true)
                                       : GainCorrection{};
  std::vector<ModelError> errors =
      add_model_errors(est, gain_steps(gain, previous, continued, earlier, bs.baseband.size()),
                       bs.dt, options.degree);
  return {std::move(est), previous, std::move(errors), exchange, Relaxation{}, TransferUse::kNone};
}

// Which estimates may form the backbone, with notes on those left out for the band's gain.
struct Screening {
  std::vector<char> valid;     ///< per estimate
  std::vector<char> above;     ///< per estimate: the envelope above the noise threshold
  std::vector<char> exchange;  ///< per estimate: valid and exchanging energy (Backbone::exchange)
  std::string weak_note;       ///< points where the band passes less than half of the mode
  std::string gain_note;       ///< points whose gain correction is not known well enough
};

// Whether the band passes at least kMinPassed of the mode throughout an estimate's fit window
// (`previous`, the correction the estimates carry): where it passes less, dividing by r lifts
// the noise and whatever else the band holds above the mode's own share, anywhere in the
// point's fit window (its data come from all of it).
class PassedCheck {
 public:
  explicit PassedCheck(const GainCorrection& previous) : previous_(previous) {
    if (!previous.active) return;
    low_before_.assign(static_cast<size_t>(previous.log_r.size()) + 1, 0);
    for (Eigen::Index j = 0; j < previous.log_r.size(); ++j) {
      const auto u = static_cast<size_t>(j);
      low_before_[u + 1] = low_before_[u] + !(previous.log_r(j).real() >= kLogMinPassed + 1e-9);
    }
  }
  bool operator()(const Estimate& e, double dt) const {
    bool passed = true;
    const double from = e.centre - e.window / 2, to = e.centre + e.window / 2;
    if (previous_.active && from <= to) {  // (a window not a number reads no nodes)
      const auto first = static_cast<size_t>(previous_.node(from).first),
                 last = static_cast<size_t>(previous_.node(to).first) + 1;
      for (double t = from; passed && low_before_[last + 1] > low_before_[first] && t <= to;
           t += dt) {
        passed = previous_.log_abs_at(t) >= kLogMinPassed;
      }
    }
    return passed;
  }

 private:
  // (|r| >= kMinPassed compared as ln |r|: an exp per sample of every window was a
  // twentieth of process's time.)
  static constexpr double kMinPassed = 0.5;
  static inline const double kLogMinPassed = std::log(kMinPassed);
  const GainCorrection& previous_;
  // The grid nodes of ln |r| below kMinPassed (or within 1e-9 of it, beyond the rounding of an
  // interpolation between two nodes above it; or not a number), counted before each node: a
  // window whose nodes hold none passes without its samples read (reading them was a thirtieth
  // of process's time).
  std::vector<Eigen::Index> low_before_;
};

// An exchange's point is kept where its amplitude is known to this (one sigma of ln A) ...
constexpr double kExchangeLogAmpStd = 0.05;
// ... and its frequency to the mode's half-power half-width (its own decay rate, the median
// over the valid points after the exchange; a point whose frequency swings by more is not
// the mode's).

// Valid points: envelope well above the noise floor, finite, positive decay rate,
// damping known to max_damping_rel_std; or, up to the end of an exchange with another mode,
// amplitude and frequency well determined (marked, whatever their decay).
Screening screen_estimates(const CorrectedEstimates& c, const BandSetting& s, double noise,
                           const RingdownOptions& options) {
  const std::vector<Estimate>& est = c.est;
  const GainCorrection& previous = c.previous;
  std::vector<char> valid(est.size()), gain_limited(est.size(), 0), above(est.size(), 0),
      exchange(est.size(), 0);
  std::vector<double> own;  // decay rates of the valid points after an exchange
  size_t weak = 0;
  const PassedCheck passes(previous);
  for (size_t i = 0; i < est.size(); ++i) {
    const Estimate& e = est[i];
    const double noise_i = noise / previous.abs_at(e.t);  // the correction est carries
    const double limit = options.max_damping_rel_std * e.sigma;
    above[i] = std::exp(e.log_amp) >= options.snr_min * noise_i;
    const bool passed = passes(e, s.dt);
    weak += usable(e, noise_i, options.snr_min) && !passed;
    valid[i] = usable(e, noise_i, options.snr_min) && passed && e.sigma_std <= limit;
    if (c.exchange.found() && e.t <= c.exchange.end_t) {
      // Decided below, once the mode's own decay rate is known.
      exchange[i] = above[i] && passed && std::isfinite(e.sigma) && std::isfinite(e.sigma_std) &&
                    std::isfinite(e.omega_d) && e.omega_d > 0 && std::isfinite(e.omega_d_std) &&
                    e.log_amp_std <= kExchangeLogAmpStd;
      valid[i] = 0;
      continue;
    }
    if (valid[i] && c.exchange.found()) own.push_back(e.sigma);
    gain_limited[i] =
        usable(e, noise_i, options.snr_min) && !valid[i] &&
        std::sqrt(std::max(0.0, e.sigma_std * e.sigma_std - c.errors[i].gain * c.errors[i].gain)) <=
            limit;
  }
  const double half_width = quantile(own, 0.5);
  for (size_t i = 0; i < est.size(); ++i) {
    exchange[i] = exchange[i] && !own.empty() && est[i].omega_d_std <= half_width;
    if (exchange[i]) valid[i] = 1;
  }
  const size_t limited =
      static_cast<size_t>(std::count(gain_limited.begin(), gain_limited.end(), 1));
  const std::string weak_note =
      weak == 0 ? std::string()
                : fmt::format(
                      "{} points left out where the band passes less than half of the "
                      "mode (the mode's frequency outside the band's half-gain points)",
                      weak);
  const std::string gain_note =
      limited == 0 ? std::string()
                   : fmt::format(
                         "{} points left out where the correction for the band's gain was not "
                         "known to the damping limit (the mode on the band's steep edge)",
                         limited);
  return {std::move(valid), std::move(above), std::move(exchange), weak_note, gain_note};
}

// What the relaxation after an exchange does to an estimate (defined beside add_transfer).
void relax(Estimate& e, const Transfer& t, TransferUse use);

// The span's end between the grid's points. Where the kept run ends at a point whose
// successor fails the damping limit alone (decaying, above the noise threshold, read through
// at least half the band's gain), the span's true end lies between the two, up to a grid
// step (a third of the shortest window) past the last grid point. kEndHalvings halvings of
// that interval place a point there, each made and screened as the grid's points are: its
// window searched from the last point's; the model errors from its amplitude taken across its
// neighbours (the farthest estimates its half-width reaches on either side), the gain
// correction's the larger of the two grid points' around it (they change over a window's
// length; the correction's steps on the grid, seven values a grid sample, kept through
// two_modes raised a record of 4e6 samples' peak by 10 MB). The last that meets the limit
// joins the run as its end. The limit itself is not moved. Not beside a second mode's beat
// (two_modes), whose errors are fitted at the grid's points alone: the span ends there. (A 1:2
// internal resonance, alpha 3e9 seed 1, kept 0.798 of what its envelope shows, the next grid
// point's damping known to 1.17 %.)
void place_end(CorrectedEstimates& corr, Screening& screened, Run& run, const signal::BandSignal& z,
               const EnvelopePhase& ep, const BandSetting& s, double noise, bool beat) {
  constexpr int kEndHalvings = 3;
  const RingdownOptions& options = s.options;
  std::vector<Estimate>& est = corr.est;
  if (options.method != Method::kHilbert || run.end >= est.size()) return;
  const size_t k = run.end - 1;  // the run's last point, valid
  if (screened.exchange[k]) return;
  const GainCorrection& previous = corr.previous;
  const PassedCheck passes(previous);
  const auto screened_in = [&](const Estimate& e, bool damping) {
    return usable(e, noise / previous.abs_at(e.t), options.snr_min) && passes(e, s.dt) &&
           (e.sigma_std <= options.max_damping_rel_std * e.sigma) == damping;
  };
  if (beat || !screened_in(est[k + 1], false)) return;
  // The estimates were read from the corrected envelope and phase (or the band's own), made
  // again here rather than kept through the passes and two_modes (three values a grid sample).
  const EnvelopePhase applied =
      previous.active ? envelope_phase(corrected(z.baseband, z.dt, previous), z.carrier_hz, s.dt)
                      : EnvelopePhase{};
  const EnvelopePhase& from = previous.active ? applied : ep;
  const size_t ne = est.size();
  const double spacing = spacing_of(est);
  double lo = est[k].t, hi = est[k + 1].t;
  std::optional<std::pair<Estimate, ModelError>> end;
  for (int h = 0; h < kEndHalvings; ++h) {
    const double c = 0.5 * (lo + hi);
    Estimate e = hilbert_point(from, s, noise, previous, c, est[k].next_search);
    ModelError m;
    if (e.window > 0 && std::isfinite(e.window)) {
      const size_t reach = reach_of(e, spacing, ne);
      const size_t first = k + 1 >= reach ? k + 1 - reach : 0, last = std::min(ne - 1, k + reach);
      m = model_error(e, est[first], est[last], GainSteps{}, s.dt, options.degree);
      const ModelError &a = corr.errors[k], &b = corr.errors[k + 1];
      m.gain = std::max(a.gain, b.gain);
      m.gain_w = std::max(a.gain_w, b.gain_w);
      e.sigma_std = std::hypot(std::hypot(e.sigma_std, m.sigma), m.gain);
      e.omega_d_std = std::hypot(e.omega_d_std, std::hypot(m.omega_d, m.gain_w));
      // After an exchange, as add_transfer did to the estimates beside it.
      relax(e, corr.relaxation.at(e), corr.transfer_use);
    }
    if (screened_in(e, true)) {
      end = {e, m};
      lo = c;
    } else {
      hi = c;
    }
  }
  if (!end) return;
  const auto at = static_cast<std::ptrdiff_t>(k + 1);
  est.insert(est.begin() + at, end->first);
  corr.errors.insert(corr.errors.begin() + at, end->second);
  screened.valid.insert(screened.valid.begin() + at, 1);
  screened.above.insert(screened.above.begin() + at, 1);
  screened.exchange.insert(screened.exchange.begin() + at, 0);
  ++run.end;
  ++run.count;
}

// Whether the band setting `x` leaves too short a record: less than two shortest windows
// between the filter's settling and the record's end.
bool short_for(const BandSetting& x) { return x.stop - x.start < 2 * x.w_min; }

// The refusal of a record too short for the band setting `x`, after what the spectrum shows of
// the typed band first: a band too narrow for its mode is the usual cause.
std::string too_short(const ChannelSpectrum& channel, const signal::Band& band,
                      const RingdownOptions& options, const BandSetting& x,
                      signal::FftCache& cache) {
  const std::string advice = spectral_advice(channel, band, options.taper, cache);
  return fmt::format(
      "{}{}record too short for this band: {:.3f} s usable after the filter's settling "
      "time, {:.3f} s needed",
      advice, advice.empty() ? "" : "; ", std::max(0.0, x.stop - x.start), 2 * x.w_min);
}

// The refusal of a record too short for the typed band's setting `s`, quickly ("" where it
// is long enough, or where the band may still be followed: a band whose filter settles longer
// than the record's continuation holds may be widened about its mode (follow_mode), which
// settles sooner).
std::string short_record_refusal(const ChannelSpectrum& channel, Quantity measured,
                                 const signal::Band& band, const RingdownOptions& options,
                                 const BandSetting& s, signal::FftCache& cache) {
  if (short_for(s)) {
    if (clipped_from_start(s)) {
      return fmt::format("{}; {:.3f} s of the record usable after it, {:.3f} s needed",
                         clipping_note(s, measured), std::max(0.0, s.stop - s.start), 2 * s.w_min);
    }
    if (!(channel.continued_begin_s < band_settling_s(band, options.taper))) {
      return too_short(channel, band, options, s, cache);
    }
  }
  return "";
}

// What a beat moves each point by joins its uncertainty; how many points that met the
// damping limit it takes past it. Sets `beat`.
size_t add_beat(CorrectedEstimates& corr, const std::vector<std::pair<double, double>>& errors,
                double noise, const RingdownOptions& options, bool& beat) {
  beat = true;
  size_t left = 0;
  for (size_t i = 0; i < corr.est.size(); ++i) {
    Estimate& e = corr.est[i];
    const double limit = options.max_damping_rel_std * e.sigma;
    const bool met = usable(e, noise, options.snr_min) && e.sigma_std <= limit;
    e.sigma_std = std::hypot(e.sigma_std, errors[i].first);
    e.omega_d_std = std::hypot(e.omega_d_std, errors[i].second);
    left += met && !(e.sigma_std <= limit);
  }
  return left;
}

// After an exchange the partner still takes energy while it rings (transfer_after): where that
// transfer exceeds a point's decay-rate one-sigma, it joins the one-sigma in quadrature; the
// points then read damping plus transfer with an uncertainty that covers the transfer. In the
// double beam's twins (band 110:135, 72 of them: alpha 1e9-3e9, mode 2 0-1.5 % off 2 f1, damped
// 0.2 and 0.6 %) unmarked points had read up to 11 % above mode 1's damping (20 % in the four
// below), 353 beyond their stated uncertainty and 115 beyond 3 times it; now 33 and 16: 27 and
// 16 in those four, 4 and 0 in the two (alpha 2e9 in tune, 0.6 %) whose exchange the
// bookkeeping explains 0.895-0.898, under kExplained, and 2 at 1.0 times it. Only where at least
// kKeptAfterTransfer points after the exchange still meet the damping limit with it: with mode 2
// in tune and damped 0.2 % the transfer stays above every later point's one-sigma until the
// noise, and joined it would leave no span; there it is taken off the points' decay rates, a
// share of it (kTransferShare) joining their uncertainty (they had been left as read, up to 20 %
// high in alpha 1e9's twin and 12 % low in 3e9's, with a note alone). Only for a partner at n
// times the band (the band's mode drives it): in mode 2's band the points after the exchange
// follow mode 1's square, which the bookkeeping does not describe. The note ("" for none).
constexpr size_t kKeptAfterTransfer = 3;
// Where the transfer is taken off instead, the share of it that joins the points' one-sigma: the
// prediction's own error. Read through each point's local fit it matched the excess the twins
// read to 0.1-0.2 % of the decay rate where the excess was 9.7-16.8 % (1e9 in tune: 16.8 / 12.9
// / 9.7 % predicted against 16.9 / 12.8 / 9.9 % read), at most 2 % of the transfer.
constexpr double kTransferShare = 0.03;

// What the relaxation after an exchange does to estimate `e` (transfer `t`), as add_transfer
// decided (`use`): a pull on the frequency beyond its one-sigma joins it in quadrature; a
// transfer beyond the decay rate's one-sigma joins it or is taken off the decay rate.
void relax(Estimate& e, const Transfer& t, TransferUse use) {
  if (std::abs(t.omega) > e.omega_d_std) e.omega_d_std = std::hypot(e.omega_d_std, t.omega);
  if (!(std::abs(t.sigma) > e.sigma_std)) return;
  if (use == TransferUse::kJoined) {
    e.sigma_std = std::hypot(e.sigma_std, t.sigma);
  } else if (use == TransferUse::kTakenOff) {
    e.sigma -= t.sigma;
    e.sigma_std = std::hypot(e.sigma_std, kTransferShare * t.sigma);
  }
}

std::string add_transfer(CorrectedEstimates& corr, const BandSetting& s, double noise,
                         Quantity measured, const RingdownOptions& options,
                         signal::FftCache& cache) {
  if (!(corr.exchange.partner > 1)) return "";
  corr.relaxation = relaxation_after(corr.exchange, s, measured, cache);
  if (!corr.relaxation.found()) return "";
  std::vector<Transfer> transfer(corr.est.size());
  size_t joined = 0, left = 0, kept = 0, pulled = 0;
  // The transfer of largest magnitude over the decay rate, signed: > 0 the partner takes energy
  // and the damping reads high, < 0 it gives energy back and the damping reads low (the 1:2
  // twin with mode 2 in tune at 0.2 %, alpha 3e9, seed 1: -13.7 %, its points read 12 % low,
  // where the note had said "reads high by up to 13.7 %"); and the pull of largest magnitude
  // on the frequency, signed [Hz].
  double most = 0, most_pull = 0;
  for (size_t i = 0; i < corr.est.size(); ++i) {
    const Estimate& e = corr.est[i];
    transfer[i] = corr.relaxation.at(e);
    if (!(e.t > corr.exchange.end_t) || !usable(e, noise, options.snr_min)) continue;
    if (std::abs(transfer[i].omega) > e.omega_d_std) {
      ++pulled;
      if (std::abs(transfer[i].omega / kTwoPi) > std::abs(most_pull))
        most_pull = transfer[i].omega / kTwoPi;
    }
    const bool over = std::abs(transfer[i].sigma) > e.sigma_std;
    const double joined_std = over ? std::hypot(e.sigma_std, transfer[i].sigma) : e.sigma_std;
    const double limit = options.max_damping_rel_std * e.sigma;
    kept += joined_std <= limit;
    if (!over) continue;
    left += e.sigma_std <= limit && !(joined_std <= limit);
    ++joined;
    if (std::abs(transfer[i].sigma / e.sigma) > std::abs(most)) most = transfer[i].sigma / e.sigma;
  }
  // Where joined the transfer would leave no point, it is taken off the points' decay rates
  // instead (the mode's own rate is what is read less what the partner takes), kTransferShare
  // of it joining their uncertainty for the prediction's own error.
  corr.transfer_use = joined == 0                 ? TransferUse::kNone
                      : kept < kKeptAfterTransfer ? TransferUse::kTakenOff
                                                  : TransferUse::kJoined;
  for (size_t i = 0; i < corr.est.size(); ++i) relax(corr.est[i], transfer[i], corr.transfer_use);
  std::string note;
  if (corr.transfer_use == TransferUse::kTakenOff) {
    note = fmt::format(
        "after the exchange the mode at {:g} times the band still {} energy until the noise, "
        "more than the points' damping uncertainty: the transfer its bookkeeping predicts (up "
        "to {:.1f} % of the decay rate, the damping reading {} by that) is taken off {}",
        corr.exchange.partner, most < 0 ? "gives back" : "takes", 100 * std::abs(most),
        most < 0 ? "low" : "high", points(joined));
  } else if (corr.transfer_use == TransferUse::kJoined) {
    note = fmt::format(
        "after the exchange the mode at {:g} times the band still {} energy: the transfer its "
        "bookkeeping predicts (up to {:.1f} % of the decay rate) joins the damping uncertainty "
        "of {}, {} of them past the {:.1f} % limit",
        corr.exchange.partner, most < 0 ? "gives back" : "takes", 100 * std::abs(most),
        points(joined), left, 100 * options.max_damping_rel_std);
  }
  if (pulled == 0) return note;
  return note + (note.empty() ? "after the exchange" : ";") +
         fmt::format(
             " the mode at {:g} times the band still pulls the frequency: the pull its "
             "bookkeeping predicts (up to {:+.4f} Hz) joins the frequency uncertainty of {}",
             corr.exchange.partner, most_pull, points(pulled));
}

// A second mode in the band read: what its beat moves each point by joins the point's
// uncertainty, so the points it moves past the damping limit drop out (two_modes); or a second
// mode the move took in beyond the typed edge, seen by its beat alone (edge_beat). Neither
// beside an energy exchange with another mode, marked on its own: its rates swing too; but
// after an exchange whose swings no fit follows (Exchange::swings) the band still holds the
// coupling's combination tone (the partner's frequency less the mode's), whose beat, the
// exchange's last swings, moves the points after it as a second mode's would. The note (""
// for none); `beat` says whether either was found.
std::string beat_note_of(CorrectedEstimates& corr, const ChannelSpectrum& channel,
                         const signal::Band& band, const signal::Band& read,
                         const RingdownOptions& options, const EnvelopePhase& ep,
                         const BandSetting& sr, double noise, bool& beat, signal::FftCache& cache) {
  std::string beat_note;
  if (const TwoModes two = corr.exchange.found() && !corr.exchange.swings
                               ? TwoModes{}
                               : two_modes(corr.est, channel, read, ep, sr, noise);
      two.found()) {
    const size_t left = add_beat(corr, two.errors, noise, options, beat);
    beat_note =
        corr.exchange.swings
            ? fmt::format(
                  "after the exchange the band holds a second spectral peak at {:.2f} Hz, {:.0f} "
                  "% of the mode's (a 1:2 exchange's combination tone lies at the partner's "
                  "frequency less this mode's): what their beat moves each point's "
                  "decay rate and frequency by is added to its uncertainty, and points it moves "
                  "by more than the {:.1f} % damping limit are left out ({} of those that met it)",
                  two.f2, 100 * two.ratio, 100 * options.max_damping_rel_std, left)
            : beat_message(two, channel, read, options, left, cache);
  } else if (const EdgeBeat edge =
                 corr.exchange.found() || (read.lo >= band.lo && read.hi <= band.hi)
                     ? EdgeBeat{}
                     : edge_beat(corr.est, ep, sr, noise, band, read);
             edge.found()) {
    const size_t left = add_beat(corr, edge.errors, noise, options, beat);
    beat_note = fmt::format(
        "the band moved past the typed edge takes in a second mode about {:.1f} Hz {} this one "
        "(near {:.1f} Hz, seen in the decay, not as a resolved spectral peak; its beat at the "
        "decay's start, about {:.0f} % of this mode's amplitude at {:.3f} s, {}): what the beat "
        "moves each point's decay rate and frequency by is added to its uncertainty, and points "
        "it moves by more than the {:.1f} % damping limit are left out ({} of those that met it)",
        std::abs(edge.f2 - edge.f1), edge.f2 < edge.f1 ? "below" : "above", edge.f2,
        100 * edge.beat.c_first, channel.t0 + edge.t0,
        edge.dsigma > 0 ? fmt::format("dying {:g}/s faster", edge.dsigma)
                        : std::string("dying as fast"),
        100 * options.max_damping_rel_std, left);
  }
  return beat_note;
}

// A second spectral peak in a moved band read, which the typed band left out or could not
// leave out (a peak beyond the mode's track by more than its half-power half-width; without a
// track, beyond the spectral peak's half-power width): the LMS twin's drifting mode beside a
// 10 % mode at 154 Hz, read through 139.7:169.7 Hz, was told only to widen the typed band;
// widening leaves a mode inside it where it is. "" for none.
std::string second_peak_note(const ChannelSpectrum& channel, const signal::Band& read,
                             const RingdownOptions& options, const EnvelopePhase& ep, double noise,
                             const BandSetting& sr, signal::FftCache& cache) {
  std::string second;
  const ModeTrack tr = track_mode(ep, noise, sr);
  const BandPeaks peaks = band_peaks(channel, read, options.taper, 3);
  double lo = peaks.main_hz, hi = peaks.main_hz, half = 0;
  if (tr.points > 0) {
    lo = tr.f_lo, hi = tr.f_hi, half = tr.sigma / kTwoPi;
  } else {
    half = half_power_width(channel, peaks.main_hz, cache);
  }
  for (const auto& [f2, ratio] : peaks.others) {
    if (f2 > lo - half && f2 < hi + half) continue;
    second = fmt::format(
        "the band read ({:.2f}:{:.2f} Hz) holds a second spectral peak at {:.2f} Hz, {:.0f} % "
        "of the mode's: a band that leaves it out may keep a span",
        read.lo, read.hi, f2, 100 * ratio);
    break;
  }
  return second;
}

// The message of a band where no span of two points or more meets the limits: the limits and
// the envelope's peak and noise floor, then each note that applies, "; " between them (an
// advice followed by the weak-gain note once ran together as "... 96.75 Hz20 points left out").
std::string no_span_message(const ChannelSpectrum& channel, Quantity measured,
                            const signal::Band& band, const signal::Band& read,
                            const RingdownOptions& options, bool moved, const EnvelopePhase& ep,
                            double noise, const BandSetting& sr, const std::string& beat_note,
                            const Screening& screened, const std::string& followed_note,
                            signal::FftCache& cache) {
  // A moved band may hold a second mode the typed band left out (second_peak_note).
  std::string second;
  if (moved && beat_note.empty())
    second = second_peak_note(channel, read, options, ep, noise, sr, cache);
  // (A band read wider than the advice asks, or holding a second mode, is not told to widen.)
  std::string advice =
      spectral_advice(channel, band, options.taper, cache,
                      second.empty() ? read.hi - read.lo : std::numeric_limits<double>::infinity());
  if (!second.empty()) advice += (advice.empty() ? "" : "; ") + second;
  std::string message = fmt::format(
      "no span of the envelope stays above {} x the noise floor with a "
      "decaying fit whose damping is known to {:g} % (peak envelope "
      "{:.3e} m, noise floor {:.3e} m)",
      options.snr_min, 100 * options.max_damping_rel_std, ep.amp.maxCoeff() / channel.scale,
      noise / channel.scale);
  const std::string clipped = clipping_note(sr, measured);
  for (const std::string* note :
       std::initializer_list<const std::string*>{&beat_note, &clipped, &advice, &screened.gain_note,
                                                 &screened.weak_note, &followed_note}) {
    if (!note->empty()) message += "; " + *note;
  }
  return message;
}

// The band says which mode: one that lies outside it at every point is another band's, seen
// through the filter's skirt and followed there (an LMS-like mode drifting from 148.4 to
// 150.3 Hz, read with 140:148, was reported at 150.3 Hz). The refusal of such a backbone ("" for
// one inside the typed band).
std::string outside_band_refusal(const Backbone& bb, const signal::Band& band) {
  if (const auto [f_min, f_max] =
          std::pair{bb.damped_frequency_hz.minCoeff(), bb.damped_frequency_hz.maxCoeff()};
      f_max < band.lo || f_min > band.hi) {
    return fmt::format(
        "no mode in the band: the mode its filter passes lies at {:.2f} to {:.2f} Hz, outside "
        "the typed band {:g}:{:g} Hz; type a band around it",
        f_min, f_max, band.lo, band.hi);
  }
  return "";
}

// Notes on the points left out inside the span (above the noise for their decay, or the few of
// a short gap below it, each said apart) and on those after it whose envelope stays above the
// noise threshold: why the span ends there. A 13 Hz mode of a strongly nonlinear joint, rung
// down by `simulate`, kept 0.7-6.6 s and said nothing of its envelope above the threshold until
// 15 s, where its damping was known to 2-7 %.
void add_left_out_notes(std::vector<std::string>& notes, const std::vector<Estimate>& est,
                        const Screening& screened, const Run& run, const ChannelSpectrum& channel,
                        const RingdownOptions& options) {
  const std::vector<char>& valid = screened.valid;
  size_t left_above = 0, left_below = 0;
  for (size_t k = run.begin; k < run.end; ++k) {
    if (!valid[k]) ++(screened.above[k] ? left_above : left_below);
  }
  if (left_above > 0) {
    notes.push_back(fmt::format(
        "{} inside the span left out, above the noise: the envelope not decaying or its "
        "damping not known to the {:.1f} % limit there",
        points(left_above), 100 * options.max_damping_rel_std));
  }
  if (left_below > 0) {
    notes.push_back(
        fmt::format("{} inside the span left out below the noise threshold (at most 2 in a row)",
                    points(left_below)));
  }
  size_t after_limit = 0, after_gap = 0, last_above = 0;
  for (size_t k = run.end; k < est.size(); ++k) {
    if (!screened.above[k]) continue;
    ++(valid[k] ? after_gap : after_limit);
    last_above = k;
  }
  if (after_limit + after_gap >= 2) {
    const bool both = after_limit > 0 && after_gap > 0;
    std::vector<std::string> why;
    if (after_limit > 0) {
      why.push_back(
          fmt::format("{}the envelope not decaying or the damping not known to the {:.1f} % limit "
                      "(--max-damping-std)",
                      both ? fmt::format("{} with ", after_limit) : std::string(),
                      100 * options.max_damping_rel_std));
    }
    if (after_gap > 0) {
      why.push_back(fmt::format("{}beyond a gap of more than 2 such points",
                                both ? fmt::format("{} ", after_gap) : std::string()));
    }
    notes.push_back(fmt::format(
        "{} after the span, up to {:.4f} s, left out above the noise threshold: {}",
        points(after_limit + after_gap), channel.t0 + est[last_above].t, fmt::join(why, ", ")));
  }
}

// The summary of a kept span: its status, ends, decades of amplitude, superharmonic and
// exchange points and linear values, and the notes, those on the band followed and a beat
// first, then the span's, the points left out, and the gain's.
void summarise_span(Ringdown& out, const BandSetting& sr, const std::vector<Estimate>& est,
                    const Run& run, const CorrectedEstimates& corr, const Screening& screened,
                    double noise, Quantity measured, const std::string& beat_note,
                    const std::string& followed_note, const ChannelSpectrum& channel,
                    const Multiples& multiples, const RingdownOptions& options) {
  RingdownSummary& sum = out.summary;
  const Backbone& bb = out.backbone;
  const Eigen::Index n = bb.size();
  sum.status = RingdownStatus::kOk;
  sum.span_start_s = bb.time_s(0);
  sum.span_end_s = bb.time_s(n - 1);
  sum.amplitude_decades = std::log10(bb.displacement.maxCoeff() / bb.displacement.minCoeff());
  sum.superharmonic_points = static_cast<int>((bb.harmonic.array() > 0).count());
  sum.exchange_points = static_cast<int>((bb.exchange.array() > 0).count());
  set_linear_values(sum, bb, multiples, options);
  std::vector<std::string> notes =
      span_notes(sr, est, run, corr.previous, noise, sum, corr.exchange, measured);
  add_left_out_notes(notes, est, screened, run, channel, options);
  if (!beat_note.empty()) notes.insert(notes.begin(), beat_note);
  if (!followed_note.empty()) notes.insert(notes.begin(), followed_note);
  if (!screened.gain_note.empty()) notes.push_back(screened.gain_note);
  if (!screened.weak_note.empty()) notes.push_back(screened.weak_note);
  for (const std::string& note : notes) sum.message += (sum.message.empty() ? "" : "; ") + note;
}

}  // namespace

signal::BandSignal band_signal(const ChannelSpectrum& channel, Quantity measured,
                               const signal::Band& band, const RingdownOptions& options,
                               signal::FftCache& cache) {
  signal::BandOptions bo;
  bo.taper = options.taper;
  bo.order = derivative_order(measured);
  return signal::band_analytic(channel.spectrum, channel.n_record, channel.n_fft, channel.fs, band,
                               bo, cache);
}

Ringdown extract_backbone(const ChannelSpectrum& channel, Quantity measured,
                          const signal::Band& band, const RingdownOptions& options,
                          signal::FftCache& cache) {
  Ringdown out;
  RingdownSummary& sum = out.summary;
  out.band = band_signal(channel, measured, band, options, cache);
  const signal::BandSignal& bs = out.band;
  sum.carrier_hz = bs.carrier_hz;
  sum.peak_time_s = channel.data_begin_s;
  if (!bs.baseband.allFinite()) {
    sum.message =
        "the band signal is not finite: the record holds samples too large to process "
        "(check the channel for corrupted samples)";
    return out;
  }
  // The envelope and phase only for a record long enough for the band (many short
  // channels are refused quickly).
  const BandSetting s = band_setting(channel, band, options, bs);
  sum.message = short_record_refusal(channel, measured, band, options, s, cache);
  if (!sum.message.empty()) return out;
  // The mode is read through a band that follows it (follow_mode); out.band stays the typed
  // band's signal, which the shapes and the nodal test compare across channels.
  // The typed band's envelope, phase and noise floor serve the mode's track and, where the
  // band is not moved, the estimates (each made once).
  const EnvelopePhase typed_ep = envelope_phase(bs.baseband, bs.carrier_hz, bs.dt);
  const double typed_noise = short_for(s) ? 0.0 : noise_floor(typed_ep, s);
  const FollowedBand followed =
      follow_mode(channel, measured, band, options, bs, typed_ep, typed_noise, cache);
  const signal::Band& read = followed.band;
  const bool moved = followed.signal.baseband.size() > 0;
  const signal::BandSignal& zb = moved ? followed.signal : bs;
  const BandSetting sr = band_setting(channel, read, options, zb);
  if (short_for(sr)) {
    sum.message = too_short(channel, band, options, sr, cache);
    return out;
  }
  const EnvelopePhase moved_ep =
      moved ? envelope_phase(zb.baseband, zb.carrier_hz, zb.dt) : EnvelopePhase{};
  const EnvelopePhase& ep = moved ? moved_ep : typed_ep;
  const double noise = moved ? noise_floor(ep, sr) : typed_noise;
  // A channel analysed at a scale (samples beyond [1e-100, 1e100]) may have a displacement
  // beyond the range of a double in the record's units: at a sample rate of 1e-277 Hz, a
  // velocity of 1e297 m/s is a displacement of 1e574 m. Nothing about it can be written.
  const double peak_m = ep.amp.maxCoeff() / channel.scale;
  if (!std::isfinite(peak_m) || !std::isfinite(noise / channel.scale)) {
    sum.message =
        "the band's displacement envelope exceeds the largest double (1.8e308 m): check the "
        "channel's unit and the sample rate";
    return out;
  }
  sum.noise_floor_m = noise / channel.scale;

  CorrectedEstimates corr =
      corrected_estimates(channel, read, options, zb, ep, sr, noise, measured, cache);
  neighbour_leak(corr.exchange, corr.est, followed.held_by, band, sr, measured, cache);
  bool beat = false;
  std::string beat_note =
      beat_note_of(corr, channel, band, read, options, ep, sr, noise, beat, cache);
  if (const std::string relaxing = add_transfer(corr, sr, noise, measured, options, cache);
      !relaxing.empty())
    beat_note += (beat_note.empty() ? "" : "; ") + relaxing;
  const std::vector<Estimate>& est = corr.est;
  Screening screened = screen_estimates(corr, sr, noise, options);
  Run run = longest_run(est, screened.valid, screened.above);
  if (run.count >= 2) place_end(corr, screened, run, zb, ep, sr, noise, beat);
  if (run.count < 2) {
    sum.message = no_span_message(channel, measured, band, read, options, moved, ep, noise, sr,
                                  beat_note, screened, followed.note, cache);
    return out;
  }
  out.backbone =
      backbone_of(est, screened.valid, screened.exchange, run, channel.t0, noise, options);
  if (std::string outside = outside_band_refusal(out.backbone, band); !outside.empty()) {
    out.backbone = Backbone{};
    sum.message = outside;
    return out;
  }
  const Multiples multiples =
      mark_superharmonics(out.backbone, channel, measured, read, options, cache);
  summarise_span(out, sr, est, run, corr, screened, noise, measured, beat_note, followed.note,
                 channel, multiples, options);
  if (channel.scale != 1.0) unscale(out, channel.scale);
  return out;
}

}  // namespace jointlab::modal
