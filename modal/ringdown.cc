#include "jointlab/modal/ringdown.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <fmt/format.h>

#include "jointlab/signal/extend.h"
#include "jointlab/signal/local_poly.h"
#include "jointlab/signal/spectrum.h"

namespace jointlab::modal {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// One local estimate of the envelope's decay and the phase's rate.
struct Estimate {
  double t = 0;            // centre [s from record start]
  double log_amp = 0;      // ln A at the centre
  double sigma = 0;        // decay rate [1/s]
  double sigma_std = 0;    // one-sigma of sigma
  double omega_d = 0;      // damped angular frequency [rad/s]
  double omega_d_std = 0;  // one-sigma of omega_d
  double misfit = 0;       // RMS of the signal about the fit [m]
  double log_amp_std = 0;  // one-sigma of ln A
  double window = 0;       // window length [s]
};

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
  e.log_amp_std = std::hypot(fa.value_std * scale_a, fa.value_change);
  e.sigma = -fa.slope;
  e.sigma_std = std::hypot(fa.slope_std * scale_a, fa.slope_change);
  e.omega_d = fp.slope;
  e.omega_d_std = std::hypot(fp.slope_std * scale_p, fp.slope_change);
  e.misfit = std::exp(fa.value) * std::hypot(fa.residual_rms, fp.residual_rms);
  e.window = window;
  return e;
}

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
  return e;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

double median(std::vector<double> v) { return quantile(std::move(v), 0.5); }

}  // namespace

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
  return fmt::format(
      "kept {:.4f} s to {:.4f} s ({:.2f} decades of amplitude); noise floor {:.3e} m; "
      "low-amplitude frequency {:.4f} Hz, damping ratio {:.5f}{}{}",
      span_start_s, span_end_s, amplitude_decades, noise_floor_m, linear_frequency_hz,
      linear_damping, message.empty() ? "" : "; ", message);
}

double band_settling_s(const signal::Band& band, double taper) {
  return 3.0 / (taper * (band.hi - band.lo));
}

PrepareOptions prepare_for(const std::vector<signal::Band>& bands, double taper,
                           PrepareOptions base) {
  double top = 0;
  for (const signal::Band& b : bands) {
    top = std::max(top, b.hi);
    base.extend_s = std::max(base.extend_s, 1.1 * band_settling_s(b, taper));
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

ChannelSpectrum channel_spectrum(const Eigen::Ref<const Eigen::VectorXd>& x, double fs, double t0,
                                 const PrepareOptions& options, signal::FftCache& cache,
                                 Eigen::Index impact) {
  const Eigen::Index n = x.size();
  const Eigen::Index i_peak = impact >= 0 ? std::min(impact, n - 1) : impact_index(x);
  const Eigen::Index i_begin = std::min<Eigen::Index>(
      n - 1, i_peak + static_cast<Eigen::Index>(std::round(options.onset_skip_s * fs)));
  const Eigen::VectorXd data = x.segment(i_begin, n - i_begin);
  Eigen::VectorXd y = data.array() - data.mean();
  Eigen::Index guard = 0, lag = 1;
  if (options.lowpass_hz > 0 && 2 * options.lowpass_hz < 0.5 * fs) {
    const double f_stop = 2 * options.lowpass_hz;
    y = signal::lowpass(y, fs, options.lowpass_hz, f_stop, cache);
    // The edge's kernel exp(-2 pi^2 sd^2 t^2), sd = f_stop / 8, is below 1e-6 by 4 / sd.
    guard =
        static_cast<Eigen::Index>(std::ceil(4.0 / (f_stop / 8.0) / (2 * std::numbers::pi) * fs));
    lag = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(fs / (3 * f_stop)));
  }
  guard = std::min(guard, y.size() / 4);
  const Eigen::Index ext = static_cast<Eigen::Index>(std::round(options.extend_s * fs));
  const Eigen::Index fit = static_cast<Eigen::Index>(std::round(options.ar_fit_s * fs));
  const auto extend = [&](int order) {
    return signal::extend_record(y.segment(guard, y.size() - 2 * guard), ext + guard, ext + guard,
                                 order, fit, 1e3, lag);
  };
  signal::Extension e = extend(options.ar_order);
  // A model with more poles than the record has modes fits some to the noise;
  // run backwards, a heavily damped one of those can blow up within the span the
  // band filters need. Lower orders (halving, down to 4) then take over that end
  // if they continue it further.
  const Eigen::Index wanted = ext + guard;
  for (int order = options.ar_order / 2;
       order >= 4 && (e.before_valid < wanted || e.after_valid < wanted); order /= 2) {
    const signal::Extension f = extend(order);
    if (f.before_valid > e.before_valid) {
      e.samples.head(wanted) = f.samples.head(wanted);
      e.before_valid = f.before_valid;
    }
    if (f.after_valid > e.after_valid) {
      e.samples.tail(wanted) = f.samples.tail(wanted);
      e.after_valid = f.after_valid;
    }
  }

  ChannelSpectrum c;
  c.n_record = e.samples.size();
  c.n_fft = signal::fast_size(2 * c.n_record);
  c.fs = fs;
  c.t0 = t0 + static_cast<double>(i_begin - e.before + guard) / fs;
  c.data_begin_s = t0 + static_cast<double>(i_begin + guard) / fs;
  c.data_end_s = t0 + static_cast<double>(n - 1 - guard) / fs;
  c.continued_begin_s = static_cast<double>(e.before_valid) / fs;
  c.continued_end_s = static_cast<double>(e.after_valid) / fs;
  c.spectrum = cache.get(c.n_fft).forward(e.samples);
  return c;
}

Ringdown extract_backbone(const ChannelSpectrum& channel, Quantity measured,
                          const signal::Band& band, const RingdownOptions& options,
                          signal::FftCache& cache) {
  Ringdown out;
  RingdownSummary& sum = out.summary;
  signal::BandOptions bo;
  bo.taper = options.taper;
  bo.order = derivative_order(measured);
  out.band = signal::band_analytic(channel.spectrum, channel.n_record, channel.n_fft, channel.fs,
                                   band, bo, cache);
  const signal::BandSignal& bs = out.band;
  const Eigen::Index m = bs.baseband.size();
  const double dt = bs.dt;
  const double duration = static_cast<double>(channel.n_record - 1) / channel.fs;

  // Envelope and unwrapped phase on the coarse grid.
  Eigen::VectorXd amp(m), log_amp(m), theta(m);
  double prev = 0, offset = 0;
  for (Eigen::Index j = 0; j < m; ++j) {
    amp(j) = std::abs(bs.baseband(j));
    log_amp(j) = std::log(std::max(amp(j), 1e-300));
    double ph = std::arg(bs.baseband(j));
    if (j > 0) {
      const double d = ph - prev;
      if (d > std::numbers::pi) offset -= kTwoPi;
      if (d < -std::numbers::pi) offset += kTwoPi;
    }
    prev = ph;
    theta(j) = ph + offset + kTwoPi * bs.carrier_hz * static_cast<double>(j) * dt;
  }
  sum.carrier_hz = bs.carrier_hz;

  // A faithfully continued end loses only what its continuation does not cover
  // of the filter's settling time: the transient then lies in the continuation.
  const double edge = options.taper * (band.hi - band.lo);
  const double settle = band_settling_s(band, options.taper);
  const double begin = channel.data_begin_s - channel.t0;
  const double end = channel.data_end_s - channel.t0;
  const double start = begin + std::max(0.0, settle - channel.continued_begin_s);
  const double stop = std::min(duration, end - std::max(0.0, settle - channel.continued_end_s));
  sum.peak_time_s = channel.data_begin_s;

  const double correlation = std::max(1.0, 1.0 / (dt * bs.noise_bandwidth_hz));
  // Period from the phase over the first part of the usable span.
  const double f_guess = [&] {
    const Eigen::Index a = std::min<Eigen::Index>(m - 1, static_cast<Eigen::Index>(start / dt));
    const Eigen::Index b = std::min<Eigen::Index>(m - 1, a + std::max<Eigen::Index>(4, m / 20));
    return b > a ? (theta(b) - theta(a)) / (kTwoPi * static_cast<double>(b - a) * dt)
                 : bs.carrier_hz;
  }();
  const double period = 1.0 / std::max(f_guess, band.lo);
  const double w_min =
      std::max({options.min_periods * period, 4.0 / bs.noise_bandwidth_hz, 6.0 * dt});

  if (stop - start < 2 * w_min) {
    sum.message = fmt::format(
        "record too short for this band: {:.3f} s usable after the filter's "
        "settling time, {:.3f} s needed",
        std::max(0.0, stop - start), 2 * w_min);
    return out;
  }

  // Noise floor: residual RMS about fits spanning kNoiseSamples independent
  // noise samples, lower quartile over the record (robust to windows the fit
  // cannot follow). A window's squared misfit is noise^2 chi^2_k / dof, with dof
  // = 2 w B real noise samples and k = dof less the parameters the two fits
  // absorb; the chi^2 quartile is the Wilson-Hilferty approximation. The fits
  // have the backbone's degree: for a narrow band the windows take seconds, over
  // which a quadratic cannot follow ln A and would count model error as noise
  // (a 36-44 Hz band read a floor nearly 4 times too high that way).
  constexpr double kNoiseSamples = 12.0;
  const double w_noise = std::min(std::max(w_min, kNoiseSamples / bs.noise_bandwidth_hz),
                                  std::max(w_min, (stop - start) / 2));
  std::vector<double> misfits;
  for (double c = start + w_noise / 2; c <= stop - w_noise / 2; c += w_noise / 4) {
    misfits.push_back(
        estimate_hilbert(log_amp, theta, dt, c, c, w_noise, correlation, 0.0, options.degree)
            .misfit);
  }
  const double dof = std::max(4.0, 2.0 * w_noise * bs.noise_bandwidth_hz);
  const double k = std::max(2.0, dof - 2.0 * (options.degree + 1));
  const double wh = 1.0 - 2.0 / (9.0 * k) - 0.6745 * std::sqrt(2.0 / (9.0 * k));
  const double quartile_ratio = std::sqrt(k * wh * wh * wh / dof);
  sum.noise_floor_m = std::max(quantile(misfits, 0.25) / quartile_ratio, 1e-300);
  const double noise = sum.noise_floor_m;

  // Local estimates along the span.
  std::vector<Estimate> est;
  if (options.method == Method::kHilbert) {
    const double step = w_min / options.points_per_window;
    // A window holds its point in its middle half: centred where the span allows,
    // pushed inside it near the span's ends (the evaluation then sits off-centre,
    // at most kMaxOffset half-widths, where the fit's slope is still well determined).
    constexpr double kMaxOffset = 0.5;
    const auto window_centre = [&](double c, double w) {
      return std::clamp(c, start + w / 2, std::max(start + w / 2, stop - w / 2));
    };
    const double margin = w_min / 2 * (1 - kMaxOffset);
    double previous_window = w_min;
    for (double c = start + margin; c <= stop - margin + 1e-12; c += step) {
      const double allowed = std::min({options.max_window_s, stop - start,
                                       2 * std::min(c - start, stop - c) / (1 - kMaxOffset)});
      // Longer windows average noise (std ~ W^-1.5) but bend less with the
      // backbone (model error ~ W^2): take the window with the smallest total
      // uncertainty, stopping early once it meets the target.
      // The slope and the envelope each take the window that determines them
      // best: longer windows average noise (std ~ W^-1.5 for the slope) but bend
      // less with the backbone (model error ~ W^2).
      Estimate best = estimate_hilbert(log_amp, theta, dt, c, window_centre(c, w_min), w_min,
                                       correlation, noise, options.degree);
      Estimate best_amp = best;
      // Below the noise threshold a point is dropped whatever its window.
      const bool buried = std::exp(best.log_amp) < options.snr_min * noise;
      // The best window changes slowly along the record: start the search two
      // steps below the previous point's choice rather than at the shortest.
      double w_first = w_min * std::sqrt(2.0);
      while (w_first * 2.0 < previous_window) w_first *= std::sqrt(2.0);
      for (double w = w_first; !buried && w <= allowed; w *= std::sqrt(2.0)) {
        if (best.sigma_std <= options.target_damping_rel_std * std::abs(best.sigma)) break;
        const Estimate next = estimate_hilbert(log_amp, theta, dt, c, window_centre(c, w), w,
                                               correlation, noise, options.degree);
        if (next.log_amp_std < best_amp.log_amp_std) best_amp = next;
        if (next.sigma_std < best.sigma_std) {
          best = next;
        } else if (next.sigma_std > 1.5 * best.sigma_std) {
          break;  // clearly past the minimum: model error now dominates
        }
      }
      best.log_amp = best_amp.log_amp;
      best.log_amp_std = best_amp.log_amp_std;
      if (!buried) previous_window = best.window;
      est.push_back(best);
    }
  } else {
    // Extrema of the band-passed displacement at full rate, refined by parabolas.
    signal::BandOptions full = bo;
    full.full_rate = true;
    const signal::BandSignal fr = signal::band_analytic(
        channel.spectrum, channel.n_record, channel.n_fft, channel.fs, band, full, cache);
    const Eigen::VectorXd y = fr.baseband.real();
    const double ts = 1.0 / channel.fs;
    std::vector<double> tk, lk;
    const Eigen::Index j0 = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(start / ts));
    const Eigen::Index j1 =
        std::min<Eigen::Index>(y.size() - 2, static_cast<Eigen::Index>(stop / ts));
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
    const double half_count = std::max(3.0, std::ceil(w_min / period));  // extrema per half window
    // Extrema per correlation length of the band-passed noise.
    const double peak_correlation = std::max(1.0, 2.0 * f_guess / bs.noise_bandwidth_hz);
    for (double k = half_count; k + half_count < static_cast<double>(np);
         k += std::max(1.0, 2 * half_count / options.points_per_window)) {
      // The same search as above: the window with the smallest uncertainty,
      // stopping once it meets the target or is clearly past the minimum.
      Estimate best =
          estimate_peaks(lpk, tpk, k, half_count, options.degree, peak_correlation, noise);
      for (double wider = half_count * std::sqrt(2.0);
           best.sigma_std > options.target_damping_rel_std * std::abs(best.sigma) &&
           k - wider >= 0 && k + wider <= static_cast<double>(np - 1) &&
           wider * period <= options.max_window_s;
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
  }

  // Two model errors taken across one window of neighbouring estimates:
  // - A point's amplitude is uncertain too; along a backbone that bends, that
  //   moves where the point belongs: add (d sigma / d ln A) std(ln A) to sigma's
  //   uncertainty and (d omega_d / d ln A) std(ln A) to omega_d's.
  // - The envelope is read through the band's gain G(f). A linear mode keeps its
  //   decay rate through any gain (a decaying exponential passes a linear filter
  //   unchanged but for a constant factor), but where the frequency drifts across
  //   a sloping part of G (a band's edge) ln A picks up d ln G/df * df/dt, and the
  //   decay rate is biased by as much. That is added to sigma's uncertainty, so a
  //   point in an edge is dropped rather than reported wrong; one outside the
  //   band's half-gain points is dropped outright. (A first-order estimate: on a
  //   band too narrow for the mode's drift the first kept points can still be off
  //   by several per cent; process.md asks for bands whose flat middle holds the
  //   drift.)
  std::vector<char> in_edge(est.size(), 0);
  {
    const size_t ne = est.size();
    const double spacing = ne > 1 ? (est[ne - 1].t - est[0].t) / static_cast<double>(ne - 1) : 1;
    const auto gain = [&](double f) { return signal::band_gain(band, options.taper, f); };
    const double df = 1e-3 * edge;
    std::vector<double> add_s(ne, 0.0), add_w(ne, 0.0), add_g(ne, 0.0);
    for (size_t i = 0; i < ne; ++i) {
      const Estimate& e = est[i];
      const auto reach = static_cast<size_t>(std::ceil(e.window / 2 / std::max(1e-12, spacing)));
      const size_t lo = i >= reach ? i - reach : 0, hi = std::min(ne - 1, i + reach);
      const double dl = est[hi].log_amp - est[lo].log_amp;
      if (hi != lo && std::abs(dl) > 0) {
        add_s[i] = (est[hi].sigma - est[lo].sigma) / dl * e.log_amp_std;
        add_w[i] = (est[hi].omega_d - est[lo].omega_d) / dl * e.log_amp_std;
      }
      const double f = e.omega_d / kTwoPi;
      const double g = gain(f);
      if (!(g > 0.5)) {
        add_g[i] = std::numeric_limits<double>::infinity();
        in_edge[i] = 1;
        continue;
      }
      if (hi == lo || !(est[hi].t > est[lo].t)) continue;
      const double dfdt = (est[hi].omega_d - est[lo].omega_d) / kTwoPi / (est[hi].t - est[lo].t);
      const double dlng = (gain(f + df) - gain(f - df)) / (2 * df) / g;
      const double term = std::abs(dlng * dfdt);
      if (!std::isfinite(term)) continue;
      add_g[i] = term;
      in_edge[i] = term > options.max_damping_rel_std * std::abs(e.sigma);
    }
    for (size_t i = 0; i < ne; ++i) {
      est[i].sigma_std = std::hypot(std::hypot(est[i].sigma_std, add_s[i]), add_g[i]);
      est[i].omega_d_std = std::hypot(est[i].omega_d_std, add_w[i]);
    }
  }

  // Valid points: envelope well above the noise floor, finite, positive decay rate.
  std::vector<char> valid(est.size());
  for (size_t i = 0; i < est.size(); ++i) {
    const Estimate& e = est[i];
    const double a = std::exp(e.log_amp);
    valid[i] = std::isfinite(e.sigma) && std::isfinite(e.omega_d) && e.omega_d > 0 && e.sigma > 0 &&
               std::isfinite(e.sigma_std) && a >= options.snr_min * sum.noise_floor_m &&
               e.sigma_std <= options.max_damping_rel_std * e.sigma;
  }
  // Longest run of valid points, bridging gaps of at most kMaxGap points: one
  // point whose uncertainty strays over the limit is dropped on its own rather
  // than cutting the span in two.
  constexpr size_t kMaxGap = 2;
  size_t best_begin = 0, best_end = 0, best_len = 0;  // [begin, end), valid points in it
  for (size_t i = 0; i < est.size();) {
    if (!valid[i]) {
      ++i;
      continue;
    }
    size_t j = i, count = 0, last = i;
    while (j < est.size()) {
      if (valid[j]) {
        ++count;
        last = j;
      } else if (j - last > kMaxGap) {
        break;
      }
      ++j;
    }
    if (count > best_len) {
      best_len = count;
      best_begin = i;
      best_end = last + 1;
    }
    i = last + 1;
  }
  // The band's flat part: the gain is within 1e-4 of 1 from 1.43 edge widths
  // inside each nominal edge (the half-gain point at 0.5 w plus 3.72 standard
  // deviations of the Gaussian, sqrt(2) w / 4).
  const double flat_lo = band.lo + 1.43 * edge, flat_hi = band.hi - 1.43 * edge;
  const auto edge_note = [&](size_t count) {
    return fmt::format(
        "{} points left out where the mode's frequency crossed the band's sloping edge "
        "(flat from {:.2f} to {:.2f} Hz); widen the band",
        count, flat_lo, flat_hi);
  };
  if (best_len < 2) {
    const size_t edged = static_cast<size_t>(std::count(in_edge.begin(), in_edge.end(), 1));
    if (edged > 0) {
      sum.message = "no span: " + edge_note(edged);
      return out;
    }
    const double a_max = amp.maxCoeff();
    sum.message = fmt::format(
        "no span of the envelope stays above {} x the noise floor with a "
        "decaying fit whose damping is known to {:.0f} % (peak envelope "
        "{:.3e} m, noise floor {:.3e} m)",
        options.snr_min, 100 * options.max_damping_rel_std, a_max, sum.noise_floor_m);
    return out;
  }

  Backbone& bb = out.backbone;
  const Eigen::Index n = static_cast<Eigen::Index>(best_len);
  for (Eigen::VectorXd* v : {&bb.time_s, &bb.amplitude, &bb.frequency_hz, &bb.damping,
                             &bb.frequency_std_hz, &bb.damping_std, &bb.damped_frequency_hz,
                             &bb.decay_rate, &bb.displacement, &bb.snr, &bb.window_s}) {
    v->resize(n);
  }
  const int k_out = derivative_order(options.amplitude);
  Eigen::Index i = 0;
  for (size_t k = best_begin; k < best_end; ++k) {
    if (!valid[k]) continue;
    const Estimate& e = est[k];
    const double wn = std::hypot(e.omega_d, e.sigma);
    const double a = std::exp(e.log_amp);
    bb.time_s(i) = channel.t0 + e.t;
    bb.displacement(i) = a;
    bb.amplitude(i) = a * std::pow(wn, k_out);
    bb.frequency_hz(i) = wn / kTwoPi;
    bb.damping(i) = e.sigma / wn;
    bb.frequency_std_hz(i) =
        std::hypot(e.omega_d * e.omega_d_std, e.sigma * e.sigma_std) / wn / kTwoPi;
    bb.damping_std(i) = e.sigma_std / wn;
    bb.damped_frequency_hz(i) = e.omega_d / kTwoPi;
    bb.decay_rate(i) = e.sigma;
    bb.snr(i) = a / sum.noise_floor_m;
    bb.window_s(i) = e.window;
    ++i;
  }
  assert(i == n);
  // Reported uncertainties are expanded: coverage factor times one sigma.
  bb.frequency_std_hz *= options.coverage_factor;
  bb.damping_std *= options.coverage_factor;
  sum.status = RingdownStatus::kOk;
  sum.span_start_s = bb.time_s(0);
  sum.span_end_s = bb.time_s(n - 1);
  sum.amplitude_decades = std::log10(bb.displacement.maxCoeff() / bb.displacement.minCoeff());
  // Low-amplitude (linear) values: medians over the lowest-amplitude fifth of the span.
  const Eigen::Index tail = std::max<Eigen::Index>(1, n / 5);
  std::vector<double> f_low, z_low;
  for (Eigen::Index i = n - tail; i < n; ++i) {
    f_low.push_back(bb.frequency_hz(i));
    z_low.push_back(bb.damping(i));
  }
  sum.linear_frequency_hz = median(f_low);
  sum.linear_damping = median(z_low);
  if (sum.linear_frequency_hz < band.lo + edge || sum.linear_frequency_hz > band.hi - edge) {
    sum.message = fmt::format("the mode at {:.3f} Hz lies in the band's edge; widen the band",
                              sum.linear_frequency_hz);
  }
  size_t edged = 0;
  for (size_t k = 0; k < in_edge.size(); ++k)
    edged += in_edge[k] && (k < best_begin || k >= best_end);
  if (edged > 0) sum.message += (sum.message.empty() ? "" : "; ") + edge_note(edged);
  return out;
}

}  // namespace jointlab::modal
