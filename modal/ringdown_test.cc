#include "jointlab/modal/ringdown.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/data/read_record.h"
#include "jointlab/tests/synthetic.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::modal {
namespace {

struct Errors {
  double decades = 0, max_f = 0, max_z = 0, median_z = 0, coverage_f = 0, coverage_z = 0;
  Eigen::Index points = 0;
};

Errors score(const Ringdown& r, const testing::SlowFlowMode& truth) {
  Errors e;
  const Backbone& b = r.backbone;
  e.points = b.size();
  if (e.points == 0) return e;
  e.decades = r.summary.amplitude_decades;
  std::vector<double> zerr;
  int cf = 0, cz = 0;
  for (Eigen::Index i = 0; i < b.size(); ++i) {
    const double a = b.displacement(i);
    const double f_true = truth.omega_n(a) / (2 * std::numbers::pi);
    const double z_true = truth.zeta(a);
    const double ef = std::abs(b.frequency_hz(i) - f_true);
    const double ez = std::abs(b.damping(i) - z_true);
    e.max_f = std::max(e.max_f, ef / f_true);
    e.max_z = std::max(e.max_z, ez / z_true);
    zerr.push_back(ez / z_true);
    cf += ef <= b.frequency_std_hz(i);
    cz += ez <= b.damping_std(i);
  }
  std::sort(zerr.begin(), zerr.end());
  e.median_z = zerr[zerr.size() / 2];
  e.coverage_f = double(cf) / b.size();
  e.coverage_z = double(cz) / b.size();
  return e;
}

// Runs one record of `measured` through the extraction in `band`, reporting
// displacement amplitude, with the record preparation process_record uses.
Ringdown extract_band(const Eigen::VectorXd& x, double fs, Quantity measured,
                      const signal::Band& band, Method method = Method::kHilbert,
                      bool long_path = false) {
  signal::FftCache cache;
  PrepareOptions prep = prepare_for({band}, RingdownOptions{}.taper);
  if (long_path) prep.pad_above = 0;  // padded as a record above 2^22 samples is
  const ChannelSpectrum cs = channel_spectrum(x, fs, 0.0, prep, cache);
  RingdownOptions opt;
  opt.amplitude = Quantity::kDisplacement;
  opt.method = method;
  return extract_backbone(cs, measured, band, opt, cache);
}

// Runs one synthetic record (`higher` scales modes 2 and 3) through the extraction.
Ringdown extract(const testing::ThreeModeRecord& rec, double f1, bool from_acceleration,
                 Method method) {
  return extract_band(from_acceleration ? rec.acceleration : rec.displacement, rec.fs,
                      from_acceleration ? Quantity::kAcceleration : Quantity::kDisplacement,
                      {0.8 * f1, 1.2 * f1}, method);
}

void print(const char* what, Method method, double f1, bool acc, unsigned seed, const Errors& e) {
  std::printf(
      "%s %s f1 %.0f acc %d seed %u: %ld points, %.2f decades, max f err %.2e, max z err "
      "%.3f, median z err %.4f, coverage f %.2f z %.2f\n",
      what, method == Method::kHilbert ? "hilbert" : "pff", f1, acc, seed, long(e.points),
      e.decades, e.max_f, e.max_z, e.median_z, e.coverage_f, e.coverage_z);
}

// The measured noise floor against the closed form: white noise of variance s^2
// per sample puts 4 s^2 B / fs into the band's analytic signal (B the integral of
// the band gain squared over positive frequencies). A linear mode (zeta 0.2 %)
// rings through the whole record, so every fit window holds signal and noise.
// Bands of +-10 % (36-44 Hz needs fits over seconds), +-20 % and +-40 %; 40 and
// 150 Hz; 3 seeds. The floor is a lower quartile over the record's windows, as
// fewer than ten for the narrow band at 40 Hz, so it scatters by about 10 %, and it
// reads 5-10 % high on average. Required: 0.8 to 1.3 times the closed form (a
// floor read high only shortens the span; quadratic fits read 3.7 times here).
TEST(RingdownNoiseFloor, MatchesTheBandNoiseOfNarrowAndWideBands) {
  const double fs = 5120, s = 1e-6, a0 = 1e-3, zeta = 0.002;
  const Eigen::Index n = static_cast<Eigen::Index>(6 * fs);
  for (const double f1 : {40.0, 150.0}) {
    for (const double half : {0.1, 0.2, 0.4}) {
      for (const unsigned seed : {1u, 2u, 3u}) {
        std::mt19937 rng(seed);
        std::normal_distribution<double> g(0.0, s);
        const double w = 2 * std::numbers::pi * f1;
        Eigen::VectorXd x(n);
        for (Eigen::Index k = 0; k < n; ++k) {
          const double t = static_cast<double>(k) / fs;
          x(k) = a0 * std::exp(-zeta * w * t) * std::cos(w * t + 0.4) + g(rng);
        }
        const Ringdown r =
            extract_band(x, fs, Quantity::kDisplacement, {(1 - half) * f1, (1 + half) * f1});
        const double expected = 2 * s * std::sqrt(r.band.noise_bandwidth_hz / fs);
        const double ratio = r.summary.noise_floor_m / expected;
        std::printf("noise floor f1 %.0f band +-%.0f %% seed %u: %.3f of the closed form\n", f1,
                    100 * half, seed, ratio);
        EXPECT_GT(ratio, 0.8) << "f1 " << f1 << " band +-" << half << " seed " << seed;
        EXPECT_LT(ratio, 1.3) << "f1 " << f1 << " band +-" << half << " seed " << seed;
      }
    }
  }
}

// A 20 s acceleration record at fs: a 100 Hz ring-down (damping 0.2 %) from 0.1 m/s^2 and
// a 45 Hz one a tenth as strong, into noise of 1e-6 m/s^2.
Eigen::VectorXd two_mode_ringdown(double fs) {
  const double zeta = 0.002;
  const Eigen::Index n = static_cast<Eigen::Index>(20 * fs);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-6);
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    x(k) = noise(rng);
    for (const auto& [f, a] : {std::pair{100.0, 0.1}, std::pair{45.0, 0.01}}) {
      const double w = 2 * std::numbers::pi * f;
      x(k) += a * std::exp(-zeta * w * t) * std::cos(w * t + 0.3);
    }
  }
  return x;
}
// ChannelSpectrum::measured is the spectrum of the measured samples alone, without the
// continuations: for A exp(-sigma t) sin(2 pi f0 t) read from t_b (data_begin_s) on, at
// spacing dt, its bin k holds (A/2) exp(-sigma t_b) / |1 - r exp(i D)|, r = exp(-sigma dt),
// D = 2 pi (f_k - f0) dt, plus the negative frequency's image, (A/2) / (2 sin(2 pi f0 dt))
// at most, 0.5 % of it here. Required within 1 %. The continued record's spectrum, which holds
// the decay run backwards as well, is 10 % larger at f0.
TEST(RingdownSpectrum, TheMeasuredSamplesAloneMatchTheDecaysClosedForm) {
  const double fs = 2000, f0 = 100, zeta = 0.01, a = 1.0;
  const double sigma = 2 * std::numbers::pi * f0 * zeta, dt = 1 / fs;
  Eigen::VectorXd x(static_cast<Eigen::Index>(3 * fs));
  for (Eigen::Index n = 0; n < x.size(); ++n) {
    const double t = static_cast<double>(n) * dt;
    x(n) = a * std::exp(-sigma * t) * std::sin(2 * std::numbers::pi * f0 * t);
  }
  const signal::Band band{80, 120};
  signal::FftCache cache;
  const ChannelSpectrum c =
      channel_spectrum(x, fs, 0.0, prepare_for({band}, RingdownOptions{}.taper), cache, 0);
  const double df = fs * static_cast<double>(c.measured_step) / static_cast<double>(c.n_fft);
  const Eigen::Index k = static_cast<Eigen::Index>(std::round(f0 / df));
  ASSERT_LT(k, c.measured.size());
  const double r = std::exp(-sigma * dt);
  const double d = 2 * std::numbers::pi * (static_cast<double>(k) * df - f0) * dt;
  const double expected = a / 2 * std::exp(-sigma * c.data_begin_s) /
                          std::abs(1.0 - r * std::exp(std::complex<double>(0, d)));
  const double measured = std::abs(c.measured(k));
  const double continued = std::abs(c.spectrum(k * c.measured_step));
  std::printf("bin %.2f Hz: measured samples %.4g, closed form %.4g, with the continuations %.4g\n",
              static_cast<double>(k) * df, measured, expected, continued);
  EXPECT_NEAR(measured / expected, 1.0, 0.01);
}

// A long record's spectrum is padded by PrepareOptions::pad_s (six settling times of the
// band's filter) instead of to twice its length. A 20 s record: a 100 Hz ring-down (damping
// 0.2 %) from 0.1 m/s^2 into noise of 1e-6, and a 45 Hz mode a tenth as strong, so that the
// superharmonic check's half and third of the band (the slowest filters read from the
// spectrum) see a mode too. Its analysed record (continuations included) padded by pad_s
// gives, at every sample, the band's analytic signal and those of its half and third of the
// twice-padded spectrum but for rounding: the third's kernel is down to 5e-20 across the
// padding, so the start adds below 1e-18 of itself to the end; transforms of 8e4 points
// round to about 1e-15 of the largest value. Required: 1e-12 of the largest value
// everywhere, and over the last second (the noise alone) 1e-6 of its RMS. Padded by a
// quarter of a settling time instead, the start leaks onto the end by far more (the check
// sees a wrap).
TEST(RingdownLongRecord, PaddingBySettlingTimesGivesTheTwicePaddedBandSignals) {
  const double fs = 2000;
  const Eigen::VectorXd x = two_mode_ringdown(fs);
  const signal::Band band{80, 120};
  const RingdownOptions options;
  const PrepareOptions prepare = prepare_for({band}, options.taper);
  signal::FftCache cache;
  const ChannelSpectrum analysed = channel_spectrum(x, fs, 0.0, prepare, cache);
  ASSERT_GE(analysed.n_fft, 2 * analysed.n_record);
  // The analysed samples (the spectrum is zero past the low-pass, so that what it transforms
  // back to spreads a little past them: all three spectra below are of these samples).
  const Eigen::VectorXd y =
      cache.get(analysed.n_fft).inverse_real(analysed.spectrum).head(analysed.n_record);
  const auto padded_to = [&](Eigen::Index n_fft) {
    ChannelSpectrum c = analysed;
    c.n_fft = n_fft;
    c.spectrum = cache.get(c.n_fft).forward(y);
    c.measured.resize(0);  // not read here
    return c;
  };
  const auto padded_by = [&](double pad_s) {
    return padded_to(
        signal::fast_size(y.size() + static_cast<Eigen::Index>(std::ceil(pad_s * fs))));
  };
  const ChannelSpectrum twice = padded_to(analysed.n_fft);
  const ChannelSpectrum padded = padded_by(prepare.pad_s);
  const ChannelSpectrum short_pad = padded_by(band_settling_s(band, options.taper) / 4);
  EXPECT_LT(padded.n_fft, twice.n_record + twice.n_record / 8);  // 21 s and 1.8 s of padding
  signal::BandOptions full;
  full.taper = options.taper;
  full.order = 2;
  full.full_rate = true;
  const auto z = [&](const ChannelSpectrum& s, const signal::Band& k) {
    return signal::band_analytic(s.spectrum, s.n_record, s.n_fft, s.fs, k, full, cache).baseband;
  };
  const Eigen::Index tail = static_cast<Eigen::Index>(fs);
  for (const int part : {1, 2, 3}) {
    const signal::Band k{band.lo / part, band.hi / part};
    const Eigen::VectorXcd za = z(twice, k), zb = z(padded, k), zc = z(short_pad, k);
    const double top = za.cwiseAbs().maxCoeff();
    const double rms = za.tail(tail).norm() / std::sqrt(static_cast<double>(tail));
    const double all = (za - zb).cwiseAbs().maxCoeff() / top;
    const double end = (za - zb).tail(tail).cwiseAbs().maxCoeff() / rms;
    const double wrapped = (za - zc).tail(tail).cwiseAbs().maxCoeff() / rms;
    std::printf(
        "band / %d: largest difference %.2e of the peak, %.2e of the end's noise; %.2e with a "
        "quarter settling time\n",
        part, all, end, wrapped);
    EXPECT_LT(all, 1e-12) << "band / " << part;
    EXPECT_LT(end, 1e-6) << "band / " << part;
    EXPECT_GT(wrapped, 1e-2) << "band / " << part;
  }
}

// channel_spectrum's long-record path (pad_above lowered to 0 so that a 20 s record takes
// it): the low-pass padded by two guards, the spectrum by pad_s and cut where the low-pass's
// gain is zero (above 675 Hz). Away from the ends (the continuations and two settling times
// of the third's filter), the band's, its half's and its third's signals match the
// twice-padded path's but for rounding (below 1e-13 of the peak; required 1e-12). The
// continuations are linear predictions fitted to the ends: a rounding apart in their inputs
// moves them (7e-7 of the peak at the noise-level end), as any change of transform size
// would, and the backbones' linear values then differ by below 1e-9 (frequency) and 4e-7
// (damping) of themselves, 1e-4 of their stated uncertainty (required a tenth).
TEST(RingdownLongRecord, TheLongRecordPathKeepsTheBackbone) {
  const double fs = 2000;
  const Eigen::VectorXd x = two_mode_ringdown(fs);
  const signal::Band band{80, 120};
  RingdownOptions options;
  options.amplitude = Quantity::kDisplacement;
  const PrepareOptions twice = prepare_for({band}, options.taper);
  PrepareOptions padded = twice;
  padded.pad_above = 0;
  signal::FftCache cache;
  const ChannelSpectrum a = channel_spectrum(x, fs, 0.0, twice, cache);
  const ChannelSpectrum b = channel_spectrum(x, fs, 0.0, padded, cache);
  ASSERT_EQ(a.n_record, b.n_record);
  EXPECT_LT(b.n_fft, b.n_record + b.n_record / 8);
  EXPECT_EQ(a.spectrum.size(), a.n_fft / 2 + 1);
  EXPECT_LT(b.spectrum.size(), b.n_fft / 2);
  signal::BandOptions full;
  full.taper = options.taper;
  full.order = 2;
  full.full_rate = true;
  const auto z = [&](const ChannelSpectrum& s, const signal::Band& k) {
    return signal::band_analytic(s.spectrum, s.n_record, s.n_fft, s.fs, k, full, cache).baseband;
  };
  const auto ends = static_cast<Eigen::Index>(std::ceil(
      (twice.extend_s + 2 * band_settling_s({band.lo / 3, band.hi / 3}, options.taper)) * fs));
  for (const int part : {1, 2, 3}) {
    const signal::Band k{band.lo / part, band.hi / part};
    const Eigen::VectorXcd za = z(a, k), zb = z(b, k);
    const double middle = (za - zb).segment(ends, a.n_record - 2 * ends).cwiseAbs().maxCoeff() /
                          za.cwiseAbs().maxCoeff();
    std::printf("band / %d: away from the ends the signals differ by %.2e of the peak\n", part,
                middle);
    EXPECT_LT(middle, 1e-12) << "band / " << part;
  }
  const Ringdown ra = extract_backbone(a, Quantity::kAcceleration, band, options, cache);
  const Ringdown rb = extract_backbone(b, Quantity::kAcceleration, band, options, cache);
  ASSERT_TRUE(ra.summary.has_linear());
  ASSERT_TRUE(rb.summary.has_linear());
  const RingdownSummary &sa = ra.summary, &sb = rb.summary;
  const double df = std::abs(sb.linear_frequency_hz - sa.linear_frequency_hz);
  const double dz = std::abs(sb.linear_damping - sa.linear_damping);
  std::printf("linear frequency %.9g and %.9g Hz (+- %.2g), damping %.9g and %.9g (+- %.2g)\n",
              sa.linear_frequency_hz, sb.linear_frequency_hz, sa.linear_frequency_std_hz,
              sa.linear_damping, sb.linear_damping, sa.linear_damping_std);
  EXPECT_LT(df, 0.1 * sa.linear_frequency_std_hz);
  EXPECT_LT(dz, 0.1 * sa.linear_damping_std);
}

// A band too narrow for the mode's drift: 77-85 Hz around a mode that falls from
// 80 to 77.2 Hz as the amplitude grows (half-gain points 78 and 84 Hz). The band's
// gain is divided out where the band passes at least half of the mode; points where
// it passes less, or where the correction is not known to the damping limit, are left
// out. On seed 11 the span starts 0.21 s after the impact, with the mode at 78.5 Hz on the
// band's slope drifting 1.8 Hz/s: the correction is a third of the decay rate there and
// rests on the mode before the first estimate, which the filter reaches but no estimate
// describes. Held there, it left the first points 12 % off (+12, +8, -8 %); the difference
// to the model continued along its line back to the impact now counts in their
// uncertainty, and they drop out. That left 0.91, 0.42 and 0.71 decades. Since the band
// follows the mode (it is read through about 73:87 Hz, the track held in the flat part):
// 1.65, 1.98 and 1.96 decades (seed 12 1.83 before a window could shift away from the
// backbone's bend), median damping errors 0.31-0.42 %, worst 1.0, 2.1 and 1.2 %.
// Required: 1.2 decades, every frequency within 0.05 %, the median damping within 1 %,
// every damping within 10 %.
TEST(RingdownBandEdge, DividesOutTheGainOrLeavesThePointOut) {
  for (const unsigned seed : {11u, 12u, 13u}) {
    const testing::ThreeModeRecord rec = testing::three_mode_record(80.0, 6.0, 1e-3, seed, 0.1);
    const Ringdown r =
        extract_band(rec.displacement, rec.fs, Quantity::kDisplacement, {77.0, 85.0});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const Errors e = score(r, rec.first);
    print("band edge", Method::kHilbert, 80.0, false, seed, e);
    std::printf("  note: %s\n", r.summary.message.c_str());
    EXPECT_GE(e.decades, 1.2) << "seed " << seed;
    EXPECT_LE(e.median_z, 0.01) << "seed " << seed;
    EXPECT_LE(e.max_z, 0.10) << "seed " << seed;
    EXPECT_LE(e.max_f, 5e-4) << "seed " << seed;
  }
}

// A mode on the sloping part of the band a user typed: the band 148.9:158.9 Hz around a
// mode that drifts from 150.3 Hz (damping 0.6 %) to 151.0 Hz (0.2 %) as it decays, from
// acceleration; the band's half-gain point is at 150.15 Hz, so the mode sits on the edge,
// where its own half-power width (up to 1.8 Hz) exceeds the edge's. The band's effect,
// divided out, must leave at least 1.2 decades with median errors within 0.05 % in
// frequency and 10 % in damping (the acceptance of a real record read this way) and every
// damping within 10 %; the same record in the wide band 130:175 Hz is the reference
// (measured 2.07-2.15 decades, median damping error 0.2-0.4 %). Measured here: 1.56-1.74
// decades (1.56-1.92 before the ends of the model counted), median errors at most 4.3e-5
// and 1.2 %, worst damping 5.8 %.
TEST(RingdownBandGain, ModeOnTheBandsSlopeKeepsItsSpan) {
  const double fs = 5120, f1 = 151.0;
  const Eigen::Index n = static_cast<Eigen::Index>(4.0 * fs);
  const double w1 = 2 * std::numbers::pi * f1, a_ref = 2e-5;
  const auto slip = [a_ref](double a) {
    const double x = std::pow(a / a_ref, 0.9);
    return x / (1 + x);
  };
  testing::SlowFlowMode m;
  m.omega_n = [=](double a) { return w1 * (1.0 - 0.006 * slip(a)); };
  m.zeta = [=](double a) { return 0.002 + 0.004 * slip(a); };
  m.a0 = 1e-4;
  const testing::SlowFlowSignal sf = testing::slow_flow(m, fs, n);
  for (const unsigned seed : {1u, 2u, 3u}) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, 1e-3 * sf.acceleration.cwiseAbs().maxCoeff());
    Eigen::VectorXd x = sf.acceleration;
    for (Eigen::Index k = 0; k < n; ++k) x(k) += g(rng);
    for (const signal::Band band : {signal::Band{148.9, 158.9}, signal::Band{130, 175}}) {
      const Ringdown r = extract_band(x, fs, Quantity::kAcceleration, band);
      ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
      const Backbone& b = r.backbone;
      std::vector<double> ef, ez;
      for (Eigen::Index i = 0; i < b.size(); ++i) {
        const double a = b.displacement(i);
        ef.push_back(std::abs(b.frequency_hz(i) / (m.omega_n(a) / (2 * std::numbers::pi)) - 1));
        ez.push_back(std::abs(b.damping(i) / m.zeta(a) - 1));
      }
      std::sort(ef.begin(), ef.end());
      std::sort(ez.begin(), ez.end());
      std::printf(
          "band %.1f:%.1f seed %u: %ld points, %.2f decades from %.2f s, median f err %.1e, "
          "median z err %.3f, max z err %.3f\n",
          band.lo, band.hi, seed, long(b.size()), r.summary.amplitude_decades,
          r.summary.span_start_s, ef[ef.size() / 2], ez[ez.size() / 2], ez.back());
      EXPECT_GE(r.summary.amplitude_decades, 1.2) << band.lo << " seed " << seed;
      EXPECT_LE(ef[ef.size() / 2], 5e-4) << band.lo << " seed " << seed;
      EXPECT_LE(ez[ez.size() / 2], 0.10) << band.lo << " seed " << seed;
      EXPECT_LE(ez.back(), 0.10) << band.lo << " seed " << seed;
    }
  }
}

// The twin of a real LMS hammer record (issue 26): 51.2 kHz, 2.55 s, acceleration, a
// 0.1 s pre-trigger. Mode 1 drifts from 149.9 Hz at 200 m/s^2 to 151.7 Hz at 3.6 m/s^2
// (frequency rising 1.2 % as it decays) while its damping falls from 0.38 % to 0.14 %; a
// linear mode at 412 Hz rings beside it; white noise of 4 m/s^2 per sample puts the
// band's noise floor near 0.1 m/s^2, so the mode starts 60 dB above it. Its authors'
// band, 148.9:158.9 Hz, puts the mode 1-3 Hz above the lower edge. `neighbour_hz` > 0
// adds a linear mode there (`neighbour_acc` m/s^2 at the impact, damping `neighbour_zeta`).
// At another sample rate `fs` the noise per sample `noise` keeps its density when scaled by
// sqrt(fs / 51200).
struct LmsTwin {
  double fs = 51200;
  Eigen::VectorXd x;         // acceleration [m/s^2]
  testing::SlowFlowMode m1;  // the planted backbone (displacement amplitude)
};

LmsTwin lms_twin(unsigned seed, double neighbour_hz = 0, double noise = 4.0, double shift_hz = 0,
                 double neighbour_acc = 100.0, double neighbour_zeta = 0.003, double fs = 51200) {
  LmsTwin t;
  t.fs = fs;
  const Eigen::Index n = static_cast<Eigen::Index>(2.55 * t.fs);
  const Eigen::Index pre = static_cast<Eigen::Index>(0.1 * t.fs);
  const double two_pi = 2 * std::numbers::pi;
  const double a_hi = 200 / std::pow(two_pi * 149.9, 2), a_lo = 3.6 / std::pow(two_pi * 151.7, 2);
  const auto slip = [](double a) {
    const double x = std::pow(a / 4e-5, 0.8);
    return x / (1 + x);
  };
  const double s_hi = slip(a_hi), s_lo = slip(a_lo);
  const auto part = [=](double a) { return (slip(a) - s_lo) / (s_hi - s_lo); };
  t.m1.omega_n = [=](double a) { return two_pi * (shift_hz + 151.7 - 1.8 * part(a)); };
  t.m1.zeta = [=](double a) { return 0.0014 + 0.0024 * part(a); };
  t.m1.a0 = 350 / std::pow(two_pi * 149.6, 2);
  t.m1.theta0 = 0.2;
  const auto linear = [&](double f, double zeta, double acc0, double theta0) {
    testing::SlowFlowMode m;
    m.omega_n = [=](double) { return two_pi * f; };
    m.zeta = [=](double) { return zeta; };
    m.a0 = acc0 / std::pow(two_pi * f, 2);
    m.theta0 = theta0;
    return testing::slow_flow(m, t.fs, n - pre).acceleration;
  };
  Eigen::VectorXd ring = testing::slow_flow(t.m1, t.fs, n - pre).acceleration;
  ring += linear(412.0, 0.004, 150.0, 1.1);
  if (neighbour_hz > 0) ring += linear(neighbour_hz, neighbour_zeta, neighbour_acc, 2.3);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, noise);
  t.x.resize(n);
  for (Eigen::Index k = 0; k < n; ++k) t.x(k) = (k < pre ? 0.0 : ring(k - pre)) + g(rng);
  return t;
}

// Median relative errors of a backbone against the planted one, and its worst damping error.
struct Medians {
  double f = 0, z = 0, z_max = 0;
};

Medians medians(const Backbone& b, const testing::SlowFlowMode& m) {
  std::vector<double> ef, ez;
  for (Eigen::Index i = 0; i < b.size(); ++i) {
    const double a = b.displacement(i);
    ef.push_back(std::abs(b.frequency_hz(i) / (m.omega_n(a) / (2 * std::numbers::pi)) - 1));
    ez.push_back(std::abs(b.damping(i) / m.zeta(a) - 1));
  }
  if (ef.empty()) return {1, 1, 1};
  std::sort(ef.begin(), ef.end());
  std::sort(ez.begin(), ez.end());
  return {ef[ef.size() / 2], ez[ez.size() / 2], ez.back()};
}

// Issue 26's first part: the twin of the LMS record read with its authors' band
// 148.9:158.9 Hz. A band says which mode; the mode must be read wherever it sits inside it.
// Acceptance: at least 1.2 decades kept (the authors kept 1.5 over 0.3-2 s), median errors
// within 0.05 % in frequency and 5 % in damping of the planted backbone.
TEST(RingdownBandGain, ModeWalkingAlongTheLowerEdgeKeepsItsSpan) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const LmsTwin t = lms_twin(seed);
    const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
    if (std::getenv("JOINTLAB_TEST_VERBOSE")) {
      const Ringdown w = extract_band(t.x, t.fs, Quantity::kAcceleration, {130, 175});
      const Medians ew = medians(w.backbone, t.m1);
      std::printf("  wide band: %.2f decades %.2f-%.2f s, f %.1e z %.3f: %s\n",
                  w.summary.amplitude_decades, w.summary.span_start_s, w.summary.span_end_s, ew.f,
                  ew.z, w.summary.message.c_str());
      for (Eigen::Index i = 0; i < r.backbone.size(); i += 3)
        std::printf("  %.3f %.3e %.3f %.5f\n", r.backbone.time_s(i), r.backbone.displacement(i),
                    r.backbone.frequency_hz(i), r.backbone.damping(i));
    }
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const Medians e = medians(r.backbone, t.m1);
    std::printf(
        "LMS twin seed %u: %ld points, %.2f decades, %.2f-%.2f s, median f err %.1e, median z "
        "err %.3f, max z err %.3f\n  %s\n",
        seed, long(r.backbone.size()), r.summary.amplitude_decades, r.summary.span_start_s,
        r.summary.span_end_s, e.f, e.z, e.z_max, r.summary.message.c_str());
    EXPECT_GE(r.summary.amplitude_decades, 1.2) << "seed " << seed;
    EXPECT_LE(e.f, 5e-4) << "seed " << seed;
    EXPECT_LE(e.z, 0.05) << "seed " << seed;
  }
}

// The same twin with its mode 1.5-2 Hz higher, 2.5-4.8 Hz inside the typed band: in its flat
// part, so the band was not moved, and its 10 Hz filter settles in 1.2 s where the record's
// backward continuation holds 0.45 s: nothing was kept ("no span ... widen it to at least
// 17 Hz") where the mode 1 Hz inside the band kept 1.7 decades. A band whose filter settles
// longer than the continuation holds is now widened about the mode as well (up to three
// times). Required as above: 1.2 decades, medians 5e-4 and 5 %.
TEST(RingdownBandGain, ModeInsideTheTypedBandIsReadAsOneNearItsEdge) {
  for (const double shift : {1.5, 2.0}) {
    for (const unsigned seed : {1u, 2u}) {
      const LmsTwin t = lms_twin(seed, 0, 4.0, shift);
      const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
      ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
      const Medians e = medians(r.backbone, t.m1);
      std::printf("LMS twin %+g Hz, seed %u: %.2f decades, median f err %.1e, median z err %.3f\n",
                  shift, seed, r.summary.amplitude_decades, e.f, e.z);
      EXPECT_GE(r.summary.amplitude_decades, 1.2) << shift << " seed " << seed;
      EXPECT_LE(e.f, 5e-4) << shift << " seed " << seed;
      EXPECT_LE(e.z, 0.05) << shift << " seed " << seed;
      EXPECT_NE(r.summary.message.find("the band widened about the mode"), std::string::npos)
          << r.summary.message;
    }
  }
  // The twin itself cut to 2 s: too short for the typed band's filter (1.12 s usable, 1.18
  // needed), so no point of it tracks the mode; the spectrum's peak inside the band stands for
  // the track. Before, "record too short for this band" and no backbone (seeds 1 and 2).
  for (const unsigned seed : {1u, 2u}) {
    LmsTwin t = lms_twin(seed);
    t.x.conservativeResize(static_cast<Eigen::Index>(2.0 * t.fs));
    const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const Medians e = medians(r.backbone, t.m1);
    std::printf("LMS twin cut to 2 s, seed %u: %.2f decades, median f err %.1e, z err %.3f\n", seed,
                r.summary.amplitude_decades, e.f, e.z);
    EXPECT_GE(r.summary.amplitude_decades, 1.2) << "seed " << seed;
    EXPECT_LE(e.f, 5e-4) << "seed " << seed;
    EXPECT_LE(e.z, 0.05) << "seed " << seed;
  }
}

// The same twin with slow content beside it, as a sensor's high-pass or a rigid-body motion
// leaves after an impact: a heavily damped 10 Hz component (damping 0.1 or 0.3) of 5, 20 or
// 80 m/s^2. The record's backward continuation then holds as long as the 10 Hz band filter
// settles, so that the band was moved but not widened: its 0.4 s windows could not follow the
// mode's nonlinear start, and 7 of the 12 records kept 0.75-1.16 decades. Followed, a band is
// widened until its shortest window is at most half the mode's decay time (up to three times
// the typed width). Required as above: 1.2 decades, medians 5e-4 and 5 %.
TEST(RingdownBandGain, ModeWalkingAlongTheLowerEdgeBesideSlowContentKeepsItsSpan) {
  const double two_pi = 2 * std::numbers::pi;
  for (const double level : {5.0, 20.0, 80.0}) {
    for (const double zeta : {0.1, 0.3}) {
      for (const unsigned seed : {1u, 2u}) {
        LmsTwin t = lms_twin(seed);
        const Eigen::Index pre = static_cast<Eigen::Index>(0.1 * t.fs);
        testing::SlowFlowMode slow;
        slow.omega_n = [=](double) { return two_pi * 10; };
        slow.zeta = [=](double) { return zeta; };
        slow.a0 = level / std::pow(two_pi * 10, 2);
        slow.theta0 = 0.5;
        t.x.tail(t.x.size() - pre) += testing::slow_flow(slow, t.fs, t.x.size() - pre).acceleration;
        const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
        ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
        const Medians e = medians(r.backbone, t.m1);
        std::printf(
            "LMS twin, slow content %g m/s^2 damping %g, seed %u: %.2f decades, median f "
            "err %.1e, median z err %.3f\n",
            level, zeta, seed, r.summary.amplitude_decades, e.f, e.z);
        char where[80];
        std::snprintf(where, sizeof where, "level %g damping %g seed %u", level, zeta, seed);
        EXPECT_GE(r.summary.amplitude_decades, 1.2) << where << ": " << r.summary.message;
        EXPECT_LE(e.f, 5e-4) << where;
        EXPECT_LE(e.z, 0.05) << where;
      }
    }
  }
}

// The LMS twin with its mode placed by where it starts, `start_hz` above the typed band's lower
// edge (148.9 Hz) at the impact (350 m/s^2), its frequency rising 1.2 % as it decays to
// 3.6 m/s^2, and a constant damping of 0.14 % (the twin's value at low amplitude); the 412 Hz
// mode and the noise (4 m/s^2) as in lms_twin.
LmsTwin lms_twin_lightly_damped(double start_hz, unsigned seed) {
  LmsTwin t;
  const Eigen::Index n = static_cast<Eigen::Index>(2.55 * t.fs);
  const Eigen::Index pre = static_cast<Eigen::Index>(0.1 * t.fs);
  const double two_pi = 2 * std::numbers::pi;
  const double f0 = 148.9 + start_hz, f1 = 1.012 * f0;
  const double a_hi = 350 / std::pow(two_pi * f0, 2), a_lo = 3.6 / std::pow(two_pi * f1, 2);
  const auto slip = [](double a) {
    const double x = std::pow(a / 4e-5, 0.8);
    return x / (1 + x);
  };
  const double s_hi = slip(a_hi), s_lo = slip(a_lo);
  t.m1.omega_n = [=](double a) {
    return two_pi * (f1 - (f1 - f0) * (slip(a) - s_lo) / (s_hi - s_lo));
  };
  t.m1.zeta = [](double) { return 0.0014; };
  t.m1.a0 = a_hi;
  t.m1.theta0 = 0.2;
  testing::SlowFlowMode other;
  other.omega_n = [=](double) { return two_pi * 412.0; };
  other.zeta = [](double) { return 0.004; };
  other.a0 = 150 / std::pow(two_pi * 412.0, 2);
  other.theta0 = 1.1;
  const Eigen::VectorXd ring = testing::slow_flow(t.m1, t.fs, n - pre).acceleration +
                               testing::slow_flow(other, t.fs, n - pre).acceleration;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 4.0);
  t.x.resize(n);
  for (Eigen::Index k = 0; k < n; ++k) t.x(k) = (k < pre ? 0.0 : ring(k - pre)) + g(rng);
  return t;
}

// A lightly damped mode's skirt is no neighbour. The mode's half-power half-width (0.2 Hz at
// 0.14 %) is two bins of the continued record's spectrum, and smoothed over that alone the
// ripple on the mode's skirt rose 3.5 times above its dips: a "neighbour" 5-9 Hz away held the
// band, whose filter then settled in 1-1.2 s and lost the decay's start. Started 1 Hz inside
// the band, seeds 2 and 19 of 20 kept 0.53 and 0.58 decades, the others 1.06-1.20; started 3 Hz
// inside, 17 of 20 kept 0.37-0.57 ("the band was not widened about the mode: a neighbouring
// mode's spectral peak at 159.47 Hz"), the others 1.10-1.16. Now all 40 keep 1.06-1.22 of the
// 1.41-1.43 decades the record holds (the mode is still 35 times above the noise threshold at
// its end). Required: 1.0 decade (the record less its first 0.15 s and last 0.3 s, which the
// band's windows cannot reach), median errors within 5e-4 in frequency and 5 % in damping.
TEST(RingdownBandGain, ALightlyDampedModesSkirtRippleIsNoNeighbour) {
  struct Case {
    double start_hz;
    unsigned seed;
  };
  for (const Case c : {Case{1.0, 2}, Case{3.0, 1}}) {
    const LmsTwin t = lms_twin_lightly_damped(c.start_hz, c.seed);
    const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const Medians e = medians(r.backbone, t.m1);
    std::printf(
        "LMS twin, damping 0.14 %%, from %g Hz inside, seed %u: %.2f decades, median f "
        "err %.1e, median z err %.3f\n  %s\n",
        c.start_hz, c.seed, r.summary.amplitude_decades, e.f, e.z, r.summary.message.c_str());
    EXPECT_GE(r.summary.amplitude_decades, 1.0) << c.start_hz << " seed " << c.seed;
    EXPECT_LE(e.f, 5e-4) << c.start_hz << " seed " << c.seed;
    EXPECT_LE(e.z, 0.05) << c.start_hz << " seed " << c.seed;
  }
}

// A band typed beside the mode rather than around it: the LMS twin's mode (149.6 to 151.7 Hz),
// its noise 0.02 m/s^2 (80 dB below the start), read with 140:149.3, which it never enters.
// Followed through the filter's skirt, its points read 149.8-151.8 Hz with their damping known
// to 1 %: before, they were this band's backbone (a Python twin drifting from 148.4 to 150.3 Hz
// read with 140:148 was given one at 148.5-150.6 Hz). Now no backbone, and the reason names
// where the mode is. Above it, 152:162 is refused by the noise test. The band around it,
// 148.9:158.9, keeps its backbone.
TEST(RingdownBandGain, AModeBesideTheTypedBandIsNotItsMode) {
  for (const unsigned seed : {1u, 2u}) {
    const LmsTwin t = lms_twin(seed, 0, 0.02);
    for (const signal::Band band : {signal::Band{140, 149.3}, signal::Band{152, 162}}) {
      const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, band);
      std::printf("LMS twin seed %u, band %g:%g: %s\n", seed, band.lo, band.hi,
                  r.summary.report().c_str());
      EXPECT_NE(r.summary.status, RingdownStatus::kOk) << band.lo << ":" << band.hi;
      EXPECT_NE(r.summary.message.find("no mode in the band"), std::string::npos)
          << r.summary.message;
      if (band.hi < 150) {
        EXPECT_NE(r.summary.message.find("outside the typed band 140:149.3 Hz"), std::string::npos)
            << r.summary.message;
      }
    }
    const Ringdown around = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
    EXPECT_EQ(around.summary.status, RingdownStatus::kOk) << around.summary.message;
    EXPECT_GE(around.summary.amplitude_decades, 1.2);
  }
}

// The same twin hit harder than its recorder's range: clipped at 420, 300, 200 or 100 m/s^2 (its
// peak about 480) for the first 0.03 to 0.38 s after the impact (4 to 57 of the mode's cycles).
// Every pinned sample is the range, not the structure's response, so the band is read from the last
// of them on, and the summary says so with the range and the time. Measured on these eight records:
// 1.25-1.75 decades down to 200 m/s^2, 0.73-0.79 at 100; median frequency errors at most 2.5e-5,
// median damping errors at most 0.8 %. With the pinned stretch left to the screens alone (a point
// whose window read it dropped only where its damping uncertainty grew past the limit): 1.33-1.76
// decades down to 200, 0.89-1.14 at 100, the same medians; but at 420 a first point whose window
// held pinned samples (a Python twin of this record clipped at 420 read its damping 3.8 % off, 1.8
// times its stated uncertainty; read after the range, 0.7 %), and on a Python twin with a 1230 Hz
// mode of 300 m/s^2 besides, clipped at 100, the pinned stretch itself kept as 15 points of an
// 'energy exchange' with damping 92-141 % off. (At 100 the span also ends 0.3-0.5 s before the
// unclipped twin's: the tail's long windows reached back into the first half second, which is now
// the range's; the unclipped twin with its first 0.48 s cut off ends where this one does.)
// Replacing the pinned stretch by the ring-down's backward continuation instead, as the impact is,
// read a linear mode's first points exactly but this nonlinear one's 2-5 % off, 2 to 2.5 times
// their uncertainty: the continuation is linear. Required: issue 26's accuracy (medians 5e-4 and 5
// %), 1.2 decades down to 200 m/s^2, no exchange, the note, and the span after the last pinned
// sample (found here from the unclipped record: the last sample beyond the range).
TEST(RingdownBandGain, AClippedRecordIsReadAfterItsRange) {
  for (const double range : {420.0, 300.0, 200.0, 100.0}) {
    for (const unsigned seed : {1u, 2u}) {
      const LmsTwin t = lms_twin(seed);
      const Eigen::VectorXd x = t.x.cwiseMin(range).cwiseMax(-range);
      Eigen::Index last = -1;
      for (Eigen::Index k = 0; k < t.x.size(); ++k)
        if (std::abs(t.x(k)) >= range) last = k;
      ASSERT_GT(last, 0);
      const double clipped_until = static_cast<double>(last) / t.fs;
      const Ringdown r = extract_band(x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
      ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
      const Medians e = medians(r.backbone, t.m1);
      std::printf(
          "LMS twin clipped at %g m/s^2, seed %u: last pinned sample at %.4f s; %.2f decades "
          "from %.4f to %.4f s, median f err %.1e, median z err %.3f\n  %s\n",
          range, seed, clipped_until, r.summary.amplitude_decades, r.summary.span_start_s,
          r.summary.span_end_s, e.f, e.z, r.summary.message.c_str());
      char where[64];
      std::snprintf(where, sizeof where, "range %g seed %u", range, seed);
      char note[200];
      std::snprintf(note, sizeof note,
                    "the channel is clipped (the sensor or the recorder past its range): %ld "
                    "samples pinned at %g m/s^2 and %g m/s^2, the last at %.4f s; the band is "
                    "read from there on",
                    long((x.array().abs() == range).count()), range, -range, clipped_until);
      EXPECT_NE(r.summary.message.find(note), std::string::npos)
          << where << ": " << r.summary.message;
      EXPECT_GT(r.summary.span_start_s, clipped_until) << where;
      EXPECT_EQ(r.summary.exchange_points, 0) << where;
      if (range >= 200) {
        EXPECT_GE(r.summary.amplitude_decades, 1.2) << where;
      }
      EXPECT_LE(e.f, 5e-4) << where;
      EXPECT_LE(e.z, 0.05) << where;
    }
  }
}

// The same twin with a linear mode below the typed band, at 146, 144 or 140 Hz (100 m/s^2 at
// the impact, damping 0.3 %: 2.9 to 8.9 Hz below the band's lower edge). The band may not
// follow mode 1 onto it: it stops where its gain at the neighbour's spectral peak is 1e-4
// (the summary names the neighbour), so whatever is kept is mode 1's: every frequency
// within 0.05 % (a neighbour passed at a tenth of mode 1's size would swing it by
// 0.1 x 4 Hz / 150 Hz = 0.3 %) and the median damping within 5 %; with the neighbour 9 Hz
// below the band, issue 26's 1.2 decades. Measured: 140 Hz 1.42-1.56 decades, 144 Hz
// 1.07-1.15, 146 Hz 0.48-0.59, worst frequency error 1.4e-4, median damping errors at most
// 1.5 % (before the held band left the mode's track on its slope: 1.35-1.46, 0.69-1.02, and
// none on seed 1 and 0.21 on seed 2). The closer the neighbour, the narrower the band must stay
// on its side and the longer its filter settles (0.8 s for 146 Hz, 1.2 s before), while the
// record's backward continuation holds for 0.45 s: an edge that passes 150 Hz and stops
// 146 Hz rings for most of a second whichever side it is on. (On seed 2 the smoothed
// spectrum's peak lies at 145.0 Hz; the measured samples' bump at 146.1 Hz holds the band.)
TEST(RingdownBandGain, FollowingTheModeStopsShortOfANeighbour) {
  for (const double neighbour : {146.0, 144.0, 140.0}) {
    for (const unsigned seed : {1u, 2u}) {
      const LmsTwin t = lms_twin(seed, neighbour);
      const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
      std::printf("LMS twin + neighbour at %.0f Hz, seed %u: %ld points, %.2f decades: %s\n",
                  neighbour, seed, long(r.backbone.size()), r.summary.amplitude_decades,
                  r.summary.message.c_str());
      EXPECT_NE(r.summary.message.find("neighbouring mode's spectral peak at 1"),
                std::string::npos);
      if (neighbour == 140.0) {
        ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
        EXPECT_GE(r.summary.amplitude_decades, 1.2) << "seed " << seed;
      }
      if (r.summary.status != RingdownStatus::kOk) continue;
      const Medians e = medians(r.backbone, t.m1);
      double worst_f = 0;
      for (Eigen::Index i = 0; i < r.backbone.size(); ++i) {
        const double f = t.m1.omega_n(r.backbone.displacement(i)) / (2 * std::numbers::pi);
        worst_f = std::max(worst_f, std::abs(r.backbone.frequency_hz(i) / f - 1));
      }
      std::printf("  median f err %.1e, worst %.1e, median z err %.3f, max %.3f\n", e.f, worst_f,
                  e.z, e.z_max);
      EXPECT_LE(worst_f, 5e-4) << neighbour << " seed " << seed;
      EXPECT_LE(e.z, 0.05) << neighbour << " seed " << seed;
    }
  }
}

// The LMS twin with a weaker neighbour just below its authors' band, as a real record of
// another lab may have: a linear mode at 146 Hz (2.9 Hz below the band, 4-5.7 Hz below the
// mode) of 0.1, 0.3 or 1 times the mode's 350 m/s^2 at the impact, damping 0.1 or 0.3 %, and
// one at 147 Hz of 0.1 or 0.3 times it, damping 0.1 %. Sampled at 5120 Hz (the noise density
// as at 51.2 kHz) to keep the test cheap; the physics is the same. Before, none of the eight
// kept a point but one (0.24 decades): a band held back from a neighbour had to leave the
// mode's track with three half-power half-widths in its flat part, so it was read through
// 10.5-12 Hz, whose filter settles in 1-1.2 s where the record's backward continuation holds
// 0.45 s, and its points' damping was known to 1.6-4 %; and a 147 Hz mode a tenth of its size,
// a bump of 1.2-1.3 times the mode's skirt in the spectrum, was not found at all: the band was
// moved over it, and their beat lifted the noise floor 1.4-27 times. Now a held band leaves the
// track on its slope (its gain divided out) and is 12-17 Hz wide, and a moved band whose noise
// floor stands 1.25 times above the typed band's (scaled to its bandwidth) is held back from the
// nearest bump of the spectrum beyond the typed edge. Measured: 146 Hz 0.14-0.71 decades (median
// 0.66), 147 Hz 0.34 each; median frequency errors at most 6.1e-5, median damping errors at
// most 1.6 %. The first kept point, though, read the damping 3.8-4.1 % high at 1.39-1.44 times
// its stated 3 sigma in five of the eight (the gain correction's error falling 12 % -> 1.6 % ->
// 0.3 % of the decay rate over the span's first three estimates, the third kept); its error is
// now at least the one before it and it is dropped: 146 Hz 0.48-0.57 decades (median 0.54) where
// 0.48-0.71 (0.68), every point within 0.91 of its stated uncertainty. Where the span was that
// point and one more (147 Hz), nothing is kept, the summary saying the gain's correction was not
// known to the damping limit; so too at 146 Hz, 0.1 times the mode and 0.3 % damping, whose first
// two points (0.14 decades) had been within their uncertainty (the rule cannot tell them apart:
// their correction's error falls 3.5 % -> 2.0 % -> 0.56 % of the decay rate).
// Required: every backbone kept within its stated uncertainty (damping and frequency, k sigma),
// with issue 26's accuracy (median errors 5e-4 in frequency, 5 % in damping), every frequency
// within 5e-4 (a neighbour passed at a tenth of the mode would swing it by 0.1 x 4 Hz / 150 Hz =
// 0.3 %); at 146 Hz a backbone of at least 0.1 decades but where noted and a median of 0.45
// decades; and the summary naming the neighbour that held the band (at 147 Hz and 0.1 times the
// mode, the bump the moved band showed). What is still lost is the start: the held bands settle in
// 0.7-1 s, the continuation holds 0.45 s (the 412 Hz mode, passed at 18 % by the continuation's
// low-pass, grows past its limit backwards).
TEST(RingdownBandGain, AWeakerNeighbourJustBelowTheBandLeavesTheModeItsPoints) {
  struct Case {
    double hz, share, zeta;
  };
  const double fs = 5120, noise = 4.0 * std::sqrt(fs / 51200);
  std::vector<double> decades_146;
  for (const Case c : {Case{146, 0.1, 0.001}, Case{146, 0.1, 0.003}, Case{146, 0.3, 0.001},
                       Case{146, 0.3, 0.003}, Case{146, 1.0, 0.001}, Case{146, 1.0, 0.003},
                       Case{147, 0.1, 0.001}, Case{147, 0.3, 0.001}}) {
    const LmsTwin t = lms_twin(1, c.hz, noise, 0, 350 * c.share, c.zeta, fs);
    const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
    char where[80];
    std::snprintf(where, sizeof where, "neighbour %g Hz, %g x, damping %g", c.hz, c.share, c.zeta);
    EXPECT_NE(r.summary.message.find("held back by a neighbouring mode's spectral peak at 14"),
              std::string::npos)
        << where << ": " << r.summary.message;
    // The span was the biased first point and one more.
    const bool may_refuse = c.hz == 147 || (c.share == 0.1 && c.zeta == 0.003);
    if (may_refuse && r.summary.status != RingdownStatus::kOk) {
      std::printf("LMS twin + %s: nothing kept\n", where);
      EXPECT_NE(r.summary.message.find("the correction for the band's gain was not known"),
                std::string::npos)
          << where << ": " << r.summary.message;
      if (c.hz == 146) decades_146.push_back(0.0);
      continue;
    }
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << where << ": " << r.summary.message;
    const Medians e = medians(r.backbone, t.m1);
    double worst_f = 0, worst_stated = 0;
    for (Eigen::Index i = 0; i < r.backbone.size(); ++i) {
      const double a = r.backbone.displacement(i);
      const double f = t.m1.omega_n(a) / (2 * std::numbers::pi);
      worst_f = std::max(worst_f, std::abs(r.backbone.frequency_hz(i) / f - 1));
      worst_stated = std::max(
          {worst_stated, std::abs(r.backbone.damping(i) - t.m1.zeta(a)) / r.backbone.damping_std(i),
           std::abs(r.backbone.frequency_hz(i) - f) / r.backbone.frequency_std_hz(i)});
    }
    std::printf(
        "LMS twin + %s: %ld points, %.2f decades, median f err %.1e (worst %.1e), median "
        "z err %.3f, worst error / stated %.2f\n",
        where, long(r.backbone.size()), r.summary.amplitude_decades, e.f, worst_f, e.z,
        worst_stated);
    EXPECT_LE(worst_stated, 1.0) << where;
    EXPECT_GE(r.summary.amplitude_decades, 0.1) << where << ": " << r.summary.message;
    EXPECT_LE(e.f, 5e-4) << where;
    EXPECT_LE(worst_f, 5e-4) << where;
    EXPECT_LE(e.z, 0.05) << where;
    if (c.hz == 147 && c.share == 0.1) {  // found by its beat alone
      EXPECT_NE(r.summary.message.find("a bump on the mode's skirt"), std::string::npos)
          << where << ": " << r.summary.message;
    }
    if (c.hz == 146) decades_146.push_back(r.summary.amplitude_decades);
  }
  std::sort(decades_146.begin(), decades_146.end());
  EXPECT_GE(decades_146[decades_146.size() / 2], 0.45);
}

// The LMS twin beside a heavily damped neighbour just below its authors' band: a linear mode
// of 1 % damping at 146 or 147 Hz (2-3 Hz below the band's lower edge), 0.1, 0.3 or 1 times
// the mode's 350 m/s^2 at the impact, at 5120 Hz as above. Its half-power width is 3 Hz: on
// the mode's skirt it is a shoulder, no peak, and it has died before the noise floor's fits see
// it, so the band followed the mode over it (139.4:169.4 Hz) and its beat with the mode moved
// the first one or two kept points' damping 9-57 % high, at 3.4-25 times their stated
// uncertainty (seed 1: 146 Hz at 0.3 times 29 % at 8.1 times, 147 Hz at 0.1 and 0.3 times 20 %
// and 57 % at 8.8 and 19 times). Now the beat is fitted over the decay's start (edge_beat)
// and what it moves each point by joins the point's uncertainty. Measured (seed 1): every
// unmarked point within 1.04 times its stated uncertainty; 146 Hz at 0.1 and 0.3 times 1.18 and
// 1.02 decades kept (1.27 each before, their first points wrong), 147 Hz 1.10 and 0.75 (1.68
// and 1.56); at 1 times, held back from the neighbour's peak as before, 0.37 and 0.09 (unmarked
// points). At 147 Hz and 1 times the band held at 147.24 Hz passes the neighbour's decaying
// start through its edge, and 9 points up to 1.31 s are marked (`exchange` 1) as its leak
// (ANeighbourLeakingThroughTheHeldEdgeIsNoExchange), whose frequencies read up to 0.18 Hz low
// at 11 times their stated uncertainty; they are counted apart here.
// Required: every unmarked point's damping and frequency within 3 times its stated
// uncertainty (a stated one-sigma; three leaves room for the noise, where the worst now reads
// 1.04 and the wrong ones read 3.4-25), at least 0.5 decades kept where the band was moved
// over the neighbour, and the summary naming the second mode there.
TEST(RingdownBandGain, AHeavilyDampedNeighbourTheBandMovedOverIsReadWithItsBeat) {
  const double fs = 5120, noise = 4.0 * std::sqrt(fs / 51200);
  for (const double hz : {146.0, 147.0}) {
    for (const double share : {0.1, 0.3, 1.0}) {
      const LmsTwin t = lms_twin(1, hz, noise, 0, 350 * share, 0.01, fs);
      const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
      char where[80];
      std::snprintf(where, sizeof where, "neighbour %g Hz, %g x, damping 1 %%", hz, share);
      ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << where << ": " << r.summary.message;
      double worst = 0;
      int marked = 0;
      for (Eigen::Index i = 0; i < r.backbone.size(); ++i) {
        if (r.backbone.exchange(i)) {
          ++marked;
          continue;
        }
        const double a = r.backbone.displacement(i);
        const double f = t.m1.omega_n(a) / (2 * std::numbers::pi);
        worst = std::max(
            {worst, std::abs(r.backbone.damping(i) - t.m1.zeta(a)) / r.backbone.damping_std(i),
             std::abs(r.backbone.frequency_hz(i) - f) / r.backbone.frequency_std_hz(i)});
      }
      std::printf("LMS twin + %s: %.2f decades, worst error / stated %.2f (%d points marked)\n",
                  where, r.summary.amplitude_decades, worst, marked);
      EXPECT_LE(worst, 3.0) << where << ": " << r.summary.message;
      if (share < 1) {  // the band moved over it
        EXPECT_EQ(marked, 0) << where;
        EXPECT_GE(r.summary.amplitude_decades, 0.5) << where << ": " << r.summary.message;
        EXPECT_NE(r.summary.message.find("takes in a second mode about"), std::string::npos)
            << where << ": " << r.summary.message;
      }
    }
  }
}

// The LMS twin beside a linear mode of 1 % damping at 147 Hz, as large as the mode at the
// impact (5.12 kHz, seed 1), as in the test above: the band is held back at 147.24 Hz from a
// peak at 145.34 Hz, the neighbour's decay passes the edge, and 9 points up to 1.31 s, whose
// frequencies read up to 0.18 Hz low (11 times their stated uncertainty), were marked with the
// note that the mode exchanges energy with another at half its frequency, where the envelope
// in that band holds noise alone (at most 1.2 times its noise floor): both modes are linear.
// Now the note names the neighbour's leak and says no exchange; the points stay marked
// (skipped by every reader). Required: the leak and the neighbour's peak named, no exchange
// said, points marked, and every unmarked point within 3 times its stated uncertainty (as
// above: a stated one-sigma, room for the noise; the worst reads 0.56).
TEST(RingdownBandGain, ANeighbourLeakingThroughTheHeldEdgeIsNoExchange) {
  const double fs = 5120, noise = 4.0 * std::sqrt(fs / 51200);
  const LmsTwin t = lms_twin(1, 147.0, noise, 0, 350, 0.01, fs);
  const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
  ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
  const std::string& m = r.summary.message;
  EXPECT_NE(m.find("a neighbouring mode beyond the band's edge (its spectral peak at 145.3"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("leaks through it, no energy exchange"), std::string::npos) << m;
  EXPECT_EQ(m.find("exchanges energy"), std::string::npos) << m;
  EXPECT_GT(r.summary.exchange_points, 0) << m;
  for (Eigen::Index i = 0; i < r.backbone.size(); ++i) {
    if (r.backbone.exchange(i)) continue;
    const double a = r.backbone.displacement(i);
    const double f = t.m1.omega_n(a) / (2 * std::numbers::pi);
    EXPECT_LE(std::abs(r.backbone.damping(i) - t.m1.zeta(a)), 3 * r.backbone.damping_std(i)) << i;
    EXPECT_LE(std::abs(r.backbone.frequency_hz(i) - f), 3 * r.backbone.frequency_std_hz(i)) << i;
  }
}

// A second mode inside the typed band, 154 Hz beside the LMS twin's drifting mode (149.9 to
// 151.7 Hz, read in 148.9:158.9 Hz): the band is moved to follow the mode, onto the neighbour,
// and no span meets the damping limit. The refusal said only "the band (10 Hz wide) is narrower
// than 12 times the half-power width of its mode: widen it to at least 16.7 Hz", about a band
// it had read 30 Hz wide; it names the second peak in the band read instead.
TEST(RingdownBandGain, ARefusalNamesASecondModeInTheBandRead) {
  for (const unsigned seed : {1u, 2u}) {
    const LmsTwin t = lms_twin(seed, 154.0);
    const Ringdown r = extract_band(t.x, t.fs, Quantity::kAcceleration, {148.9, 158.9});
    const std::string& m = r.summary.message;
    std::printf("LMS twin + 154 Hz, seed %u: %s\n", seed, m.c_str());
    ASSERT_NE(r.summary.status, RingdownStatus::kOk) << m;
    const std::string mark = "holds a second spectral peak at ";
    const size_t at = m.find(mark);
    ASSERT_NE(at, std::string::npos) << m;
    EXPECT_NEAR(std::stod(m.substr(at + mark.size())), 154.0, 2.0) << m;
    EXPECT_EQ(m.find("widen it"), std::string::npos) << m;
  }
}

// Issue 26's second part: a 1:2 internal resonance (tests/synthetic.h): mode 1 at 122 Hz
// struck, mode 2 at 243 Hz taking energy from it and giving it back while mode 1 is large,
// velocity at 5120 Hz, noise 1e-5 m/s per sample, read in 110:135 Hz. What mode 1's own
// envelope shows above the noise threshold is log10(its largest amplitude / (snr_min x the
// band's noise floor)), its exact amplitude taken from the simulation; the acceptance asks
// for 0.8 of it. While the two modes exchange energy the envelope decays by damping plus
// transfer (its decay rate there is 25-175 % above mode 1's own, or negative while mode 1
// takes energy back): those points are kept where their amplitude and frequency are well
// determined and marked (exchange 1), and they must lie where the exchange is, before its
// end (the last time the simulated envelope's decay rate, smoothed over 0.1 s, is more than
// 5 % off mode 1's own). The unmarked points must be mode 1's linear values: median
// frequency within 0.05 % and median damping within 10 %.
// Kept against the whole envelope: 0.934, 0.944, 0.850, 0.875, 0.806, 0.838 (over seeds 1-6,
// 0.806-0.946, all 18 cases at 0.8 or more). Alpha 3e9 seed 1 had kept 0.798 (and alpha 2e9
// seed 1 0.837) while the span ended at a grid point: its next point, 0.0785 s and 0.08
// decades further, has its damping known to 1.17 % against the 1 % limit; the span's end now
// placed between the two by halving (place_end: 1.08 % at half the step, 0.99 % at a quarter,
// 1.04 % at three eighths) keeps the point a quarter step, 0.0196 s, further. Before the exchange
// was marked 0.57-0.81, and before a point's window could shift away from the bend of the backbone
// 0.72-0.94: alpha 2e9 and 3e9 seed 1 lost their tails to the 1 % damping limit, their centred
// windows reaching back into the exchange's relaxation. Alpha 3e9's first three points swing in
// frequency by more than the mode's half-power half-width and are not kept. Required here: 0.8 of
// the whole envelope in every case, and 0.8 of it after the exchange.
TEST(RingdownInternalResonance, ModeOneKeepsWhatItsEnvelopeShows) {
  struct Case {
    double alpha, zeta2;
  };
  for (const Case c : {Case{1e9, 0.006}, Case{2e9, 0.006}, Case{3e9, 0.002}}) {
    for (const unsigned seed : {1u, 2u}) {
      const testing::InternalResonanceRecord rec =
          testing::internal_resonance_record(c.alpha, 6.5e-5, c.zeta2, 1e-5, seed);
      const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
      ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
      const double threshold = RingdownOptions{}.snr_min * r.summary.noise_floor_m;
      const double whole = std::log10(rec.amplitude1.maxCoeff() / threshold);
      // The end of the exchange: ln A1 averaged over 0.1 s, its slope over 0.1 s.
      const auto half = static_cast<Eigen::Index>(0.05 * rec.fs);
      const Eigen::Index n = rec.amplitude1.size();
      Eigen::VectorXd smooth = Eigen::VectorXd::Zero(n);
      for (Eigen::Index k = half; k + half < n; ++k) {
        if (rec.amplitude1(k - half) > 0) {
          smooth(k) = rec.amplitude1.segment(k - half, 2 * half + 1).array().log().mean();
        }
      }
      const double sigma1 = rec.zeta1 * 2 * std::numbers::pi * rec.f1_hz;
      Eigen::Index free_from = 2 * half;
      for (Eigen::Index k = 2 * half; k + 2 * half < n && rec.amplitude1(k) > threshold; ++k) {
        const double sigma = -(smooth(k + half) - smooth(k - half)) / (0.1 * (1 - 1 / rec.fs));
        if (std::abs(sigma / sigma1 - 1) > 0.05) free_from = k;
      }
      const double free = std::log10(rec.amplitude1(free_from) / threshold);
      std::vector<double> ef, ez;
      const Backbone& b = r.backbone;
      ASSERT_EQ(b.exchange.size(), b.size());
      int marked = 0;
      for (Eigen::Index i = 0; i < b.size(); ++i) {
        EXPECT_TRUE(std::isfinite(b.damping(i)) && std::isfinite(b.damping_std(i)) &&
                    std::isfinite(b.frequency_std_hz(i)))
            << b.time_s(i);
        if (b.exchange(i) != 0) {
          ++marked;
          EXPECT_LE(b.time_s(i), static_cast<double>(free_from) / rec.fs) << b.time_s(i);
          continue;
        }
        EXPECT_GT(b.damping(i), 0) << b.time_s(i);
        ef.push_back(std::abs(b.frequency_hz(i) / rec.f1_hz - 1));
        ez.push_back(std::abs(b.damping(i) / rec.zeta1 - 1));
      }
      EXPECT_EQ(marked, r.summary.exchange_points);
      ASSERT_FALSE(ef.empty());
      std::sort(ef.begin(), ef.end());
      std::sort(ez.begin(), ez.end());
      std::printf(
          "internal resonance alpha %.0e zeta2 %.3f seed %u: %.2f decades, %.2f-%.2f s; the "
          "envelope shows %.2f (%.3f of it kept), %.2f after the exchange ends at %.2f s (%.2f "
          "kept); %d points marked exchange; unmarked: median f err %.1e, median z err %.3f\n  "
          "%s\n",
          c.alpha, c.zeta2, seed, r.summary.amplitude_decades, r.summary.span_start_s,
          r.summary.span_end_s, whole, r.summary.amplitude_decades / whole, free,
          static_cast<double>(free_from) / rec.fs, r.summary.amplitude_decades / free, marked,
          ef[ef.size() / 2], ez[ez.size() / 2], r.summary.message.c_str());
      EXPECT_GE(r.summary.amplitude_decades, 0.8 * whole) << c.alpha << " seed " << seed;
      EXPECT_GE(r.summary.amplitude_decades, 0.8 * free) << c.alpha << " seed " << seed;
      EXPECT_LE(ef[ef.size() / 2], 5e-4) << c.alpha << " seed " << seed;
      EXPECT_LE(ez[ez.size() / 2], 0.10) << c.alpha << " seed " << seed;
    }
  }
}

// Mode 2 struck too (x20 = 1.63e-5 m, half mode 1's velocity), read in 230:256 Hz: after the
// exchange its band holds mode 1's locked second harmonic (2 f1 = 244.0 Hz, decaying at
// 2 sigma1) with some of mode 2's own ring-down beside it, which pulls the read frequency
// further off 2 f1 than the harmonic test allows. Before, the one point left unmarked above
// 13 harmonic ones gave mode 2's linear values 244.51 Hz and damping 0.0035 (mode 2: 243.0 Hz,
// 0.006); in the twins of a double beam struck near mode 2, unmarked points between or after
// marked ones gave 243.92 and 244.13 Hz, damping 0.0031-0.0035. Required: either no linear
// values, or mode 2's own: frequency within 0.2 Hz of 243 Hz and damping within 25 %.
TEST(RingdownInternalResonance, ModeTwosLinearValuesAreNotModeOnesHarmonic) {
  for (const unsigned seed : {1u, 2u}) {
    const testing::InternalResonanceRecord rec =
        testing::internal_resonance_record(1e9, 6.5e-5, 0.006, 1e-5, seed, 4.0, 1.63e-5);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {230, 256});
    std::printf("mode 2 struck too, seed %u: status %d, %s, linear %.4f Hz, damping %.5f\n  %s\n",
                seed, static_cast<int>(r.summary.status),
                r.summary.has_linear() ? "linear values" : r.summary.linear_reason.c_str(),
                r.summary.linear_frequency_hz, r.summary.linear_damping, r.summary.message.c_str());
    if (!r.summary.has_linear()) continue;
    EXPECT_NEAR(r.summary.linear_frequency_hz, rec.f2_hz, 0.2) << r.summary.message;
    EXPECT_NEAR(r.summary.linear_damping / 0.006, 1.0, 0.25) << r.summary.message;
  }
}

// Both modes struck as a hammer strikes (phase -pi/2, mode 2's velocity 0.3 times mode 1's),
// read in a band 28 Hz wide centred between mode 2 (243 or 245.22 Hz) and 2 f1: the band holds mode
// 2's own decay and mode 1's locked second harmonic (2 f1 = 244 Hz, drifting 243.9-244.5 Hz with
// the coupling) a hertz or so apart, closer than the resolution of the lowest points' windows (1/w
// = 2.4-3.4 Hz). Before, 3-4 points were left unmarked there and gave linear values 244.01 Hz (mode
// 2 at 243.0) and 244.08 Hz (mode 2 at 245.22), damping 0.0066 and 0.0024 (0.006 planted), stated
// as right. Required: no linear values, the reason naming the multiple; or mode 2's own within
// 0.2 Hz (a fifth of the separation, so a mixture cannot pass).
TEST(RingdownInternalResonance, ModeTwosLinearValuesRefusedWhereTheHarmonicIsUnresolved) {
  const double pi = std::numbers::pi;
  for (const double f2 : {243.0, 245.22}) {
    const double x20 = 0.3 * 6.5e-5 * 122 / f2;
    const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
        1e9, 6.5e-5, 0.006, 1e-5, 1, 4.0, x20, -pi / 2, -pi / 2, f2);
    const double mid = 0.5 * (f2 + 244.0);  // between mode 2 and 2 f1
    const Ringdown r =
        extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {mid - 14, mid + 14});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    std::printf("mode 2 at %.2f Hz struck by a hammer: %s, linear %.4f Hz, damping %.5f\n", f2,
                r.summary.has_linear() ? "linear values" : r.summary.linear_reason.c_str(),
                r.summary.linear_frequency_hz, r.summary.linear_damping);
    if (!r.summary.has_linear()) {
      EXPECT_NE(r.summary.linear_reason.find("cannot tell its mode from a multiple"),
                std::string::npos)
          << r.summary.linear_reason;
      continue;
    }
    EXPECT_NEAR(r.summary.linear_frequency_hz, f2, 0.2) << r.summary.message;
  }
  // Mode 2 in tune (244 Hz, damping 0.2 %, alpha 3e9, mode 1 struck alone), read in 230:258 Hz:
  // its lowest fitted points lie within 0.09 Hz of 2 f1 and read steadily (reduced chi-square
  // 1.0 in frequency, 0.1 in damping), so they passed the test above; but 2 f1 follows them to
  // lower amplitudes (marked harmonic from 1.39 s), and carried back at its decay rate it is
  // as strong as the lowest fitted point. Before, linear values 244.003 +- 0.0065 Hz and 0.002043
  // +- 0.000018 (seed 1; seed 2 0.002045 +- 0.000015): damping 2.4 and 3.1 times its stated
  // uncertainty off mode 2's 0.002. Required: no linear values, naming the multiple that still
  // carries them; or within their stated uncertainty of mode 2.
  const testing::InternalResonanceRecord tuned =
      testing::internal_resonance_record(3e9, 6.5e-5, 0.002, 1e-5, 1, 4.0, 0.0, 0.0, 0.0, 244.0);
  const Ringdown rt = extract_band(tuned.velocity, tuned.fs, Quantity::kVelocity, {230, 258});
  ASSERT_EQ(rt.summary.status, RingdownStatus::kOk) << rt.summary.message;
  if (!rt.summary.has_linear()) {
    EXPECT_NE(rt.summary.linear_reason.find("still carries"), std::string::npos)
        << rt.summary.linear_reason;
  } else {
    EXPECT_LE(std::abs(rt.summary.linear_frequency_hz - 244.0), rt.summary.linear_frequency_std_hz);
    EXPECT_LE(std::abs(rt.summary.linear_damping - 0.002), rt.summary.linear_damping_std);
  }
}

// Mode 2 at 244.0 Hz, 0.05 Hz from mode 1's 2 f1, both modes struck as a hammer strikes
// (mode 2's velocity equal to mode 1's, alpha 2e9, seed 1), read in 230:258 Hz: six points
// follow 2 f1 (harmonic 2), and the four below them drift from 243.61 to 243.22 Hz, their
// damping rising to 0.0078, decaying at 11.9 1/s where 2 f1 decays at 4.5 1/s: mode 2 (9.2 1/s)
// and the harmonic together, nearly cancelling. They read steadily (reduced chi-square 1.3),
// so multiple_within_resolution let them stand: linear values 243.23 +- 0.047 Hz and 0.0078,
// where mode 2 is 244.0 Hz and 0.006. A mode dying faster than a multiple it gave way to cannot
// come back from under it. Required: no linear values, naming that; or mode 2's own within
// 0.2 Hz and 25 % (as ModeTwosLinearValuesAreNotModeOnesHarmonic asks).
// The 1:2 twin with mode 2 at `f2` Hz (damping 0.006; coupling `alpha`, seed 1), both modes struck
// as a hammer strikes, read in 230:258 Hz: no linear values, naming why; or mode 2's own within
// 0.2 Hz and 25 % (as ModeTwosLinearValuesAreNotModeOnesHarmonic asks).
void expect_mode_two_or_refused(double alpha, double f2) {
  const double blow = -std::numbers::pi / 2;
  const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
      alpha, 6.5e-5, 0.006, 1e-5, 1, 4.0, 6.5e-5 * 122 / f2, blow, blow, f2);
  const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {230, 258});
  ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
  if (!r.summary.has_linear()) {
    EXPECT_NE(r.summary.linear_reason.find("cannot come back from under it"), std::string::npos)
        << r.summary.linear_reason;
    return;
  }
  EXPECT_NEAR(r.summary.linear_frequency_hz, f2, 0.2);
  EXPECT_NEAR(r.summary.linear_damping / 0.006, 1.0, 0.25);
}

TEST(RingdownInternalResonance, ModeTwosLinearValuesRefusedWhereItDiesUnderTheHarmonic) {
  expect_mode_two_or_refused(2e9, 244.0);
}

// Mode 2 at 244.3 Hz (0.006), alpha 3e9, seed 1, both struck as a hammer strikes, read in
// 230:258 Hz: eight points follow 2 f1 (harmonic 2), and the eight fitted points below them
// decay at 5.6 falling to 4.6 1/s, reaching 2 f1's own rate (2 sigma_1 = 4.6 1/s; mode 2's is
// 9.2), at 243.6-243.73 Hz: the multiple itself, mode 1's damping 0.003 read at 2 f1. Not
// faster than the multiple, so the rule of the test above let them stand: linear values
// 243.728 +- 0.057 Hz and damping 0.00302 +- 0.00010 (k = 3), 10 and 30 of those off mode 2's
// 244.3 Hz and 0.006. A mode comes back from under a multiple only if it dies clearly slower.
// Required: no linear values, naming that; or mode 2's own within 0.2 Hz and 25 %. About 0.03 s.
TEST(RingdownInternalResonance, ModeTwosLinearValuesRefusedWhereItDiesNoSlowerThanTheHarmonic) {
  expect_mode_two_or_refused(3e9, 244.3);
}

// The 1:2 twin (coupling `alpha`, mode 2 at `f2` Hz with damping `zeta2`, noise `seed`), both
// modes struck as a hammer strikes (mode 2's velocity equal to mode 1's), read in 230:258 Hz.
// Required: no linear values, the reason containing `why`; or mode 2's own within their stated
// (expanded, k = 3) uncertainty. A twin takes about 0.02 s.
void expect_mode_two_covered_or_refused(double alpha, double f2, double zeta2, unsigned seed,
                                        const std::string& why) {
  const double blow = -std::numbers::pi / 2;
  const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
      alpha, 6.5e-5, zeta2, 1e-5, seed, 4.0, 6.5e-5 * 122 / f2, blow, blow, f2);
  const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {230, 258});
  ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
  const RingdownSummary& s = r.summary;
  if (!s.has_linear()) {
    EXPECT_NE(s.linear_reason.find(why), std::string::npos) << s.linear_reason;
    return;
  }
  EXPECT_LE(std::abs(s.linear_frequency_hz - f2), s.linear_frequency_std_hz)
      << s.linear_frequency_hz << " +- " << s.linear_frequency_std_hz;
  EXPECT_LE(std::abs(s.linear_damping - zeta2), s.linear_damping_std)
      << s.linear_damping << " +- " << s.linear_damping_std;
}

// Mode 2 at 245.0 Hz (0.4 %, alpha 3e9, seed 2): 44 points marked exchange and 9 harmonic, the
// last of them 0.17 s before the two fitted points; 2 f1 (4.9 1/s against mode 2's 6.2) carried
// there is 0.71 of their amplitude. Before, 244.303 +- 0.123 Hz and 0.00265 +- 0.00009, 5.7 and
// 15 times their uncertainty off mode 2. Mode 2 at 244.1 Hz (0.4 %, alpha 1e9, seed 2) gives way
// to 2 f1 below its fitted points (0.85 of the lowest's amplitude there): before, 244.030 +-
// 0.007 Hz and 0.00418 +- 0.00003, 10.4 and 6.9 times it off.
TEST(RingdownInternalResonance, ModeTwosLinearValuesRefusedWhereAMultipleStillCarriesThem) {
  expect_mode_two_covered_or_refused(3e9, 245.0, 0.004, 2, "still carries the lowest fitted point");
  expect_mode_two_covered_or_refused(1e9, 244.1, 0.004, 2, "still carries the lowest fitted point");
}

// Mode 2 at 243.0 Hz (0.2 %, alpha 2e9, seed 2): 80 points marked exchange, the swings of mode 2
// beside 2 f1 (244.0 Hz) at 1.0 Hz; the two fitted points 0.04 of a swing after the last marked
// one, their windows 0.79 s (0.8 swings). Before, damping 0.00239 +- 0.00009, 4.5 times its
// uncertainty off mode 2's 0.002. Mode 2 at 245.0 Hz (alpha 3e9, seed 1), 0.27 of a swing
// after: 0.00253 +- 0.00007, 7.1 times off.
TEST(RingdownInternalResonance, ModeTwosLinearValuesRefusedWhereAnExchangesSwingsMayGoOn) {
  expect_mode_two_covered_or_refused(2e9, 243.0, 0.002, 2,
                                     "the points cannot show that they ended");
  expect_mode_two_covered_or_refused(3e9, 245.0, 0.002, 1,
                                     "the points cannot show that they ended");
}

// Where the swings are fast enough for the windows to average them (mode 2 at 247.66 Hz, 3.66 Hz
// from 2 f1, seed 1: the lowest fitted point's window 3.2 s, 11.6 swings) or the multiple died
// long before the fitted points (mode 2 in tune at 244.0 Hz, alpha 3e9: the nearest harmonic
// point 1.33 s earlier, 2 f1 carried from it at 10.8 1/s is 3.4e-5 of the lowest point), mode
// 2's linear values stay, within their uncertainty (247.658 +- 0.017 Hz, 0.00200 +- 0.00004;
// 243.998 +- 0.006 Hz, 0.00201 +- 0.00002): a guard against refusing too much.
TEST(RingdownInternalResonance, ModeTwosLinearValuesStayWhereNoMultipleReachesThem) {
  for (const auto& [alpha, f2] : {std::pair{1e9, 247.66}, std::pair{3e9, 244.0}}) {
    const double blow = -std::numbers::pi / 2;
    const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
        alpha, 6.5e-5, 0.002, 1e-5, 1, 4.0, 6.5e-5 * 122 / f2, blow, blow, f2);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {230, 258});
    ASSERT_TRUE(r.summary.has_linear()) << f2 << " Hz: " << r.summary.linear_reason;
    EXPECT_LE(std::abs(r.summary.linear_frequency_hz - f2), r.summary.linear_frequency_std_hz);
    EXPECT_LE(std::abs(r.summary.linear_damping - 0.002), r.summary.linear_damping_std);
  }
}

// A weak coupling (alpha 3e8) moves energy one way only: mode 1's decay rate falls from the
// start to its own, without a turn, while mode 2's envelope, fed, decays slower than its own
// and then at it. Before, the first three points read damping 19-20 % above mode 1's
// (3.56e-3 against 3.0e-3, stated to 2e-5) unmarked: a joint's damping falls so too, and a
// rate that only falls is not an exchange by its turns. Now the partner's rate rising from
// below its own while this one falls marks them (exchange 1): 5 and 4 points, the worst
// unmarked damping then 3.0 % and 5.0 % off, where the transfer's tail still adds to it.
// Required: every unmarked point's damping within 7 % of mode 1's (before, 20 %), and the
// marked points before the first unmarked one.
TEST(RingdownInternalResonance, AOneWayTransferAtTheStartIsMarked) {
  for (const unsigned seed : {1u, 2u}) {
    const testing::InternalResonanceRecord rec =
        testing::internal_resonance_record(3e8, 6.5e-5, 0.006, 1e-5, seed);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const Backbone& b = r.backbone;
    double first_unmarked = std::numeric_limits<double>::infinity(), worst = 0;
    for (Eigen::Index i = 0; i < b.size(); ++i) {
      if (b.exchange(i) != 0) {
        EXPECT_LT(b.time_s(i), first_unmarked) << b.time_s(i);
        continue;
      }
      first_unmarked = std::min(first_unmarked, b.time_s(i));
      worst = std::max(worst, std::abs(b.damping(i) / rec.zeta1 - 1));
    }
    std::printf(
        "one-way transfer seed %u: %d points marked, worst unmarked damping error %.3f\n  %s\n",
        seed, r.summary.exchange_points, worst, r.summary.message.c_str());
    EXPECT_GT(r.summary.exchange_points, 0) << r.summary.message;
    EXPECT_LE(worst, 0.07) << r.summary.message;
  }
}

// Mode 2 in tune (f2 = 2 f1 = 244 Hz, damping 0.6 %), fed by mode 1 from the start (mode 1
// struck alone, or both as a hammer strikes): energy drains one way, mode 1's decay rate falling
// from 2.6-6 times its own to its own while mode 2's rises and then follows twice mode 1's (its
// ranks then move with mode 1's: -0.12 to -0.18, not the -0.6 the one-way test asks). Before,
// the first points were kept unmarked with damping 164 % (alpha 1e9) and 328 % (2e9) above mode
// 1's, stated to about 1 %. The partner band lies a quarter period from mode 1's square (|sin
// psi| 1.00), and mode 1's excess rate follows the power it takes (drained_in_quadrature).
// Required: points marked, every unmarked point's damping within 7 % of mode 1's (measured
// 3.3-5.2 %: the transfer's tail, as in the tests above), and the note saying why. A joint-like
// mode whose damping falls as much, read through a sensor with a quadratic term (its harmonic in
// phase with the mode's square, as a quasi-static harmonic is), must not be marked.
TEST(RingdownInternalResonance, AOneWayDrainIntoAModeInTuneIsMarked) {
  const double pi = std::numbers::pi;
  struct Case {
    double alpha, x20, phase;
  };
  for (const Case c :
       {Case{1e9, 0.0, 0.0}, Case{2e9, 0.0, 0.0}, Case{1e9, 0.5 * 6.5e-5 * 122 / 244, -pi / 2}}) {
    const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
        c.alpha, 6.5e-5, 0.006, 1e-5, 1, 4.0, c.x20, c.phase, c.phase, 244.0);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const Backbone& b = r.backbone;
    double worst = 0;
    for (Eigen::Index i = 0; i < b.size(); ++i) {
      if (b.exchange(i) == 0) worst = std::max(worst, std::abs(b.damping(i) / rec.zeta1 - 1));
    }
    std::printf("drain into mode 2 in tune, alpha %.0e, x20 %.2e: %d marked, worst %.3f\n  %s\n",
                c.alpha, c.x20, r.summary.exchange_points, worst, r.summary.message.c_str());
    EXPECT_GT(r.summary.exchange_points, 0) << r.summary.message;
    EXPECT_LE(worst, 0.07) << r.summary.message;
    EXPECT_NE(r.summary.message.find("a quarter period from the drive"), std::string::npos)
        << r.summary.message;
  }
  // Mode 2 in tune damped less (0.2 %), alpha 3e9, both struck (mode 2's velocity as large as
  // mode 1's): the modes swing (turns, marked) and then mode 2 keeps draining mode 1, whose rate
  // relaxes from 2.9 to 1.05 times its own over 1.2 s (extend_through_drain). Before, the
  // relaxation was unmarked, damping up to 43 % off; now 12 more points are marked and the
  // worst unmarked is 15 % off (the later rates' median, taken as the mode's own, is still
  // 9 % above it, so the last of the relaxation is not clearly apart). Required: within 20 %.
  {
    const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
        3e9, 6.5e-5, 0.002, 1e-5, 1, 4.0, 6.5e-5 * 122 / 244, -pi / 2, -pi / 2, 244.0);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    double worst = 0;
    for (Eigen::Index i = 0; i < r.backbone.size(); ++i) {
      if (r.backbone.exchange(i) == 0)
        worst = std::max(worst, std::abs(r.backbone.damping(i) / rec.zeta1 - 1));
    }
    std::printf("swings, then a drain, alpha 3e9: %d marked, worst %.3f\n  %s\n",
                r.summary.exchange_points, worst, r.summary.message.c_str());
    EXPECT_LE(worst, 0.20) << r.summary.message;
  }
  // The joint-like twin: 122 Hz, damping 0.8 % falling to 0.3 % over the first decade, read by
  // a velocity sensor v + k d(x^2)/dt whose harmonic starts at a tenth of the mode's velocity.
  testing::SlowFlowMode m;
  m.omega_n = [](double) { return 2 * std::numbers::pi * 122.0; };
  m.zeta = [](double a) { return 0.003 + 0.005 * std::min(1.0, a / 6.5e-5); };
  m.a0 = 6.5e-5;
  const Eigen::Index n = static_cast<Eigen::Index>(4.0 * 5120);
  const testing::SlowFlowSignal sf = testing::slow_flow(m, 5120, n);
  const double k = 0.05 / 6.5e-5;
  std::mt19937 rng(1);
  std::normal_distribution<double> g(0.0, 1e-5);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i)
    v(i) = sf.velocity(i) + 2 * k * sf.displacement(i) * sf.velocity(i) + g(rng);
  const Ringdown rj = extract_band(v, 5120, Quantity::kVelocity, {110, 135});
  ASSERT_EQ(rj.summary.status, RingdownStatus::kOk) << rj.summary.message;
  std::printf("joint-like with a quadratic sensor: %d marked\n  %s\n", rj.summary.exchange_points,
              rj.summary.message.c_str());
  EXPECT_EQ(rj.summary.exchange_points, 0) << rj.summary.message;
}

// The strongest coupling of the double-beam twin (alpha 1e10), struck by a hammer (both modes
// from rest, mode 2 a tenth as hard): mode 1 gives most of its energy to mode 2 within 0.5 s,
// the two envelopes swinging, and its decay rate then falls to its own as mode 2 dies out. The
// first estimates, read through those swings and the step at the impact, are too uncertain to
// place (-0.7 +- 2.0 1/s, mode 1's own 2.3); the one-way transfer was looked for only from the
// first of them, which does not lie above the mode's own, and none was found: 5 points from 0.6
// to 0.9 s were read as damping up to 2.2 times mode 1's, unmarked and stated to 1.5 %, and the
// span began at 0.6 s (1.5 decades, where the twin's independent analysis shows 2.8). Required:
// every unmarked point's damping within 7 % of mode 1's (the transfer's tail adds up to 5 %
// where the rate is no longer clearly apart), some points marked, and at least 2.2 decades
// (measured 2.43 and 2.49).
TEST(RingdownInternalResonance, AOneWayTransferAfterUncertainSwingsIsMarked) {
  const double w1 = 2 * std::numbers::pi * 122.0, w2 = 2 * std::numbers::pi * 243.0;
  for (const unsigned seed : {1u, 2u}) {
    // Both modes from rest at x = 0 with velocities V2 = 0.1 V1 (amplitudes V / w).
    const double blow = -std::numbers::pi / 2;
    const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
        1e10, 6.5e-5, 0.006, 1e-5, seed, 4.0, 0.1 * 6.5e-5 * w1 / w2, blow, blow);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const Backbone& b = r.backbone;
    double worst = 0;
    for (Eigen::Index i = 0; i < b.size(); ++i) {
      if (b.exchange(i) == 0) worst = std::max(worst, std::abs(b.damping(i) / rec.zeta1 - 1));
    }
    std::printf(
        "alpha 1e10 hammer blow, seed %u: %.2f decades, %d points marked, worst "
        "unmarked damping error %.3f\n  %s\n",
        seed, r.summary.amplitude_decades, r.summary.exchange_points, worst,
        r.summary.message.c_str());
    EXPECT_GT(r.summary.exchange_points, 0) << r.summary.message;
    EXPECT_LE(worst, 0.07) << r.summary.message;
    EXPECT_GE(r.summary.amplitude_decades, 2.2) << r.summary.message;
  }
}

// A detuned resonance (issue 26's double beam, whose mode 2 need not lie at 2 f1): mode 2 at
// 241.56 Hz, 2.4 Hz below 2 f1, one hammer blow at both modes (V2 = 0.5 V1), alpha 3e9. The
// exchange then swings every 0.4 s. Points whose damping misses the limit through windows
// centred on them search longer windows shifted along the record, which average the swings
// away: from those rates no turn was found, no exchange, and the first 0.5 s were dropped for
// their damping uncertainty (up to 30 %). The exchange is looked for again in the rates of the
// centred windows, which show the swings, provided the partner holds energy there (its
// envelope above snr_min times its noise floor at every turn: a band of noise at half an LMS
// twin's mode, whose rates swung with a weak neighbour's beat, is no partner) and no second
// mode beats in the band. Kept of what mode 1's envelope shows: 0.696 and 0.680 before (seeds 1
// and 2, no point marked), 0.799 and 0.785 now (8 points marked, unmarked damping within 0.3 %
// median, 2.4 % worst). Required: 0.75, a point marked, median damping error 5 %.
TEST(RingdownInternalResonance, ADetunedExchangeSeenThroughCentredWindowsIsMarked) {
  const double f2 = 241.56;
  const double w1 = 2 * std::numbers::pi * 122.0, w2 = 2 * std::numbers::pi * f2;
  const double blow = -std::numbers::pi / 2;
  for (const unsigned seed : {1u, 2u}) {
    const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
        3e9, 6.5e-5, 0.006, 1e-5, seed, 4.0, 0.5 * 6.5e-5 * w1 / w2, blow, blow, f2);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const double threshold = RingdownOptions{}.snr_min * r.summary.noise_floor_m;
    const double share =
        r.summary.amplitude_decades / std::log10(rec.amplitude1.maxCoeff() / threshold);
    std::vector<double> ez;
    for (Eigen::Index i = 0; i < r.backbone.size(); ++i) {
      if (r.backbone.exchange(i) == 0)
        ez.push_back(std::abs(r.backbone.damping(i) / rec.zeta1 - 1));
    }
    ASSERT_FALSE(ez.empty());
    std::sort(ez.begin(), ez.end());
    std::printf(
        "detuned to %.2f Hz, seed %u: %.3f of the envelope kept, %d points marked; unmarked "
        "damping error median %.3f, worst %.3f\n  %s\n",
        f2, seed, share, r.summary.exchange_points, ez[ez.size() / 2], ez.back(),
        r.summary.message.c_str());
    EXPECT_GT(r.summary.exchange_points, 0);
    EXPECT_GE(share, 0.75);
    EXPECT_LE(ez[ez.size() / 2], 0.05);
  }
}

// Mode 2 1.5 % off 2 f1 (247.66 or 240.34 Hz), mode 1 struck alone, band 110:135 Hz: energy
// passes back and forth every 0.19-0.27 s, the decay rate of mode 1's envelope swinging between
// -5 and 8 times its own, as fast as the shortest window (4 / the band's noise bandwidth,
// 0.235 s) lasts. No window follows the swings: every fit takes them for misfit, no turn shows,
// and the first 0.3-0.75 s were dropped for their damping uncertainty (up to 61 %), unmarked and
// unnamed: 0.69-0.70 of the envelope's decades kept (alpha 3e9, mode 2 damped 0.2 %) and 0.79
// (2e9, 0.6 %), under the acceptance's 0.8. The power the partner band takes and gives (its
// drive's integral) explains 0.98-1.00 of what a cubic leaves of ln A there: those points are
// now kept where their amplitude and frequency are well determined, marked (exchange 1): 0.81-0.91
// kept, 4-5 points marked. Required: 0.8 of the envelope's decades, the marked points before
// every unmarked one and named in the note, the unmarked points mode 1's own (median frequency
// within 0.05 %, median damping within 10 %, as ModeOneKeepsWhatItsEnvelopeShows asks).
TEST(RingdownInternalResonance, FastSwingsOfADetunedExchangeAreMarked) {
  struct Case {
    double alpha, zeta2, f2;
  };
  for (const Case c :
       {Case{3e9, 0.002, 247.66}, Case{3e9, 0.002, 240.34}, Case{2e9, 0.006, 247.66}}) {
    const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
        c.alpha, 6.5e-5, c.zeta2, 1e-5, 1, 4.0, 0.0, 0.0, 0.0, c.f2);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const double threshold = RingdownOptions{}.snr_min * r.summary.noise_floor_m;
    const double share =
        r.summary.amplitude_decades / std::log10(rec.amplitude1.maxCoeff() / threshold);
    const Backbone& b = r.backbone;
    std::vector<double> ef, ez;
    double first_unmarked = std::numeric_limits<double>::infinity(), last_marked = 0;
    for (Eigen::Index i = 0; i < b.size(); ++i) {
      if (b.exchange(i) != 0) {
        last_marked = b.time_s(i);
        continue;
      }
      first_unmarked = std::min(first_unmarked, b.time_s(i));
      ef.push_back(std::abs(b.frequency_hz(i) / rec.f1_hz - 1));
      ez.push_back(std::abs(b.damping(i) / rec.zeta1 - 1));
    }
    ASSERT_FALSE(ez.empty());
    std::sort(ef.begin(), ef.end());
    std::sort(ez.begin(), ez.end());
    std::printf(
        "alpha %.0e, mode 2 at %.2f Hz: %.3f of the envelope kept, %d points marked; unmarked: "
        "median f err %.1e, median z err %.3f\n  %s\n",
        c.alpha, c.f2, share, r.summary.exchange_points, ef[ef.size() / 2], ez[ez.size() / 2],
        r.summary.message.c_str());
    EXPECT_GE(share, 0.8) << c.alpha << " " << c.f2;
    EXPECT_GT(r.summary.exchange_points, 0);
    EXPECT_LT(last_marked, first_unmarked);
    EXPECT_NE(r.summary.message.find("swings faster than its fits follow"), std::string::npos);
    EXPECT_LE(ef[ef.size() / 2], 5e-4);
    EXPECT_LE(ez[ez.size() / 2], 0.10);
  }
}

// The points of `b` not marked `exchange`, each required to read `truth` in column `value`
// within its stated uncertainty in column `uncertainty` (the k = 3 interval); returns how many
// there are.
int unmarked_within(const Backbone& b, Eigen::VectorXd Backbone::*value,
                    Eigen::VectorXd Backbone::*uncertainty, double truth) {
  int unmarked = 0;
  for (Eigen::Index i = 0; i < b.size(); ++i) {
    if (b.exchange(i) != 0) continue;
    ++unmarked;
    const double read = (b.*value)(i), stated = (b.*uncertainty)(i);
    EXPECT_LE(std::abs(read - truth), stated) << b.time_s(i) << " s: " << read << " +- " << stated;
  }
  return unmarked;
}

// The same for damping `zeta`.
int unmarked_within_their_uncertainty(const Backbone& b, double zeta) {
  return unmarked_within(b, &Backbone::damping, &Backbone::damping_std, zeta);
}

// After an exchange the partner still takes energy while it rings, and the band's decay rate
// relaxes to mode 1's own (tests/synthetic.h's twin, band 110:135). Mode 2 at 247.66 Hz (1.5 %
// above 2 f1), damped 0.6 %, alpha 2e9, seed 1: 4 points marked, and the unmarked ones after
// them read damping up to 10.9 % above mode 1's 0.003, 7 beyond their stated uncertainty (k = 3;
// 3 beyond 3 times it), the span 0.907 of the envelope. The exchange's bookkeeping predicts that
// transfer (transfer_after; up to 9.4 % of the decay rate here), which now joins each point's
// uncertainty: 7 points pass the 1 % damping limit and are left out inside the span, the worst
// kept 1.2 % off, the span unchanged. Mode 2 in tune at 244 Hz, damped 0.2 %, alpha 1e9: the
// transfer stays above every later point's one-sigma until the noise (they read up to 20 %
// above mode 1's damping, 7 beyond their uncertainty); joined, no point would meet the limit
// and no span be kept, so the transfer is taken off their decay rates (they had stayed as read,
// a note alone saying by how much they read high). Required: in both, every unmarked damping
// within its stated uncertainty of mode 1's (the k = 3 interval; noise alone leaves it at 0.3 %
// of points); the first 0.8 of the envelope kept; the second a span and the note. About 0.05 s.
TEST(RingdownInternalResonance, RelaxationAfterAnExchangeCarriesItsTransfer) {
  {
    const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
        2e9, 6.5e-5, 0.006, 1e-5, 1, 4.0, 0.0, 0.0, 0.0, 244.0 * 1.015);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const double threshold = RingdownOptions{}.snr_min * r.summary.noise_floor_m;
    EXPECT_GE(r.summary.amplitude_decades, 0.8 * std::log10(rec.amplitude1.maxCoeff() / threshold));
    EXPECT_GT(unmarked_within_their_uncertainty(r.backbone, rec.zeta1), 10);
  }
  // Mode 2 in tune, damped 0.2 %: no point after the exchange would meet the damping limit with
  // the transfer joined; the points stay as read, the note saying by how much they read high.
  const testing::InternalResonanceRecord rec =
      testing::internal_resonance_record(1e9, 6.5e-5, 0.002, 1e-5, 1, 4.0, 0.0, 0.0, 0.0, 244.0);
  const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
  ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
  EXPECT_NE(r.summary.message.find("the damping reading high by that) is taken off"),
            std::string::npos)
      << r.summary.message;
  EXPECT_GT(unmarked_within_their_uncertainty(r.backbone, rec.zeta1), 5);
}

// The same in-tune twin at alpha 3e9 (seed 1): after the exchange mode 2 gives energy back, the
// bookkeeping's transfer is -13.7 % of the decay rate, and the eight unmarked points read mode
// 1's damping 12.1 % falling to 1.6 % low (down to -8.5 times their k = 3 uncertainty). The note
// had said "their damping reads high by up to 13.7 %" (the sign dropped): the wrong direction.
// The transfer is now taken off their decay rates (the note says it read low). Required: the
// note says so, and every unmarked point reads mode 1's damping within its stated uncertainty
// (the k = 3 interval). About 0.03 s.
TEST(RingdownInternalResonance, ATransferGivenBackIsNamedAsReadingLow) {
  const testing::InternalResonanceRecord rec =
      testing::internal_resonance_record(3e9, 6.5e-5, 0.002, 1e-5, 1, 4.0, 0.0, 0.0, 0.0, 244.0);
  const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
  ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
  EXPECT_GT(unmarked_within_their_uncertainty(r.backbone, rec.zeta1), 5);
  EXPECT_NE(r.summary.message.find("still gives back energy until the noise"), std::string::npos)
      << r.summary.message;
  EXPECT_NE(r.summary.message.find("the damping reading low by that) is taken off"),
            std::string::npos)
      << r.summary.message;
  EXPECT_EQ(r.summary.message.find("reading high"), std::string::npos) << r.summary.message;
}

// The partner that still takes energy after an exchange also pulls the band's phase: the points
// read mode 1's frequency plus the pull, which is not the mode's own (it follows the partner's
// amplitude and phase, not mode 1's amplitude; another hit of the same mode pulls otherwise).
// Mode 2 in tune, damped 0.2 %, alpha 1e9, seed 1: the nine unmarked points from 0.99 to 1.62 s
// read 0.074 to 0.018 Hz above mode 1's 122 Hz, up to 13.2 times their stated k = 3
// uncertainty, and the span's end point (1.66 s, placed after the transfer was dealt with) 1.31
// times it; mode 2 1.5 % below 2 f1, damped 0.6 %: six points 0.67-1.07 s, 0.028 Hz high at
// first, up to 22.3 times it. The exchange's bookkeeping predicts the pull (0.0737 / 0.0620 /
// 0.0510 Hz at the first three points in tune, against 0.0739 / 0.0618 / 0.0510 read), which now
// joins the frequency uncertainty where it exceeds the one-sigma, the span's end point included.
// Required: every unmarked point reads 122 Hz within its stated uncertainty (noise alone leaves
// 0.3 % of points outside it; over 72 twins none of 1330 unmarked points lay outside it about
// the planted instantaneous frequency, 132 about 122 Hz) and the note names the pull. About
// 0.06 s.
TEST(RingdownInternalResonance, ThePullAfterAnExchangeJoinsTheFrequencyUncertainty) {
  for (const double f2 : {244.0, 244.0 * (1 - 0.015)}) {
    const double zeta2 = f2 == 244.0 ? 0.002 : 0.006;
    const testing::InternalResonanceRecord rec =
        testing::internal_resonance_record(1e9, 6.5e-5, zeta2, 1e-5, 1, 4.0, 0.0, 0.0, 0.0, f2);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    EXPECT_GE(unmarked_within(r.backbone, &Backbone::frequency_hz, &Backbone::frequency_std_hz,
                              rec.f1_hz),
              10)
        << f2;
    EXPECT_NE(r.summary.message.find("pulls the frequency"), std::string::npos)
        << r.summary.message;
  }
}

// The riveted campaign's 500 Hz mode (high_hit1, acc_9003_z, band 440:570 Hz), whose first three
// estimates (30 ms) miss the damping limit beside a drive at 1/2 of the band (where the joints
// make twice the 122 Hz mode's frequency): that drive explains 0.98 of what a cubic leaves of ln A
// over those 30 ms, but it is one-signed (0.03 of it the other way): the energy goes one way, no
// exchange, and the points stay dropped as before (1.90 decades kept, none marked).
TEST(RingdownInternalResonance, ARivetedBeamsNonlinearStartIsNoSwingingExchange) {
  const data::Record rec = data::read_record(testing::source_dir() +
                                             "/data/examples/riveted-campaign/high/high_hit1.csv");
  const data::Channel* ch = rec.find("acc_9003_z");
  ASSERT_NE(ch, nullptr);
  const Ringdown r = extract_band(ch->samples, rec.fs, Quantity::kAcceleration, {440, 570});
  ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
  EXPECT_EQ(r.summary.exchange_points, 0) << r.summary.message;
}

// Both modes damped at 1 %, mode 2 struck at half mode 1's velocity (alpha 3e9): mode 2 gives
// mode 1 energy for about 0.2 s after the impact, and mode 1's decay rate falls from twice its
// own to two thirds of it, then rises to it: one turn, a minimum. Mode 2's rate rises all the
// while (it gives, and it dies faster), so its turn is not within reach of mode 1's, as
// takes_energy asks of a single turn; but a joint's damping never takes the decay below the
// rate it settles to at low amplitude. Before, no point was marked and the unmarked damping
// was up to 53 % off the mode's own (seeds 1 and 2: 0.527, 0.525), each point outside its
// uncertainty. Now the dip is taken for energy fed by mode 2 (its rate clearly higher at the
// dip than at the first estimate; its envelope above its noise threshold): 10 points marked,
// the unmarked damping within 3.8 % and 3.0 %. Required: a point marked, every unmarked
// point within 10 %.
TEST(RingdownInternalResonance, ADipOfTheDecayRateFedByTheOtherModeIsMarked) {
  const double w1 = 2 * std::numbers::pi * 122.0, w2 = 2 * std::numbers::pi * 243.0;
  const double blow = -std::numbers::pi / 2;
  for (const unsigned seed : {1u, 2u}) {
    const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
        3e9, 6.5e-5, 0.01, 1e-5, seed, 4.0, 0.5 * 6.5e-5 * w1 / w2, blow, blow, 243.0, 0.01);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    double worst = 0;
    for (Eigen::Index i = 0; i < r.backbone.size(); ++i) {
      if (r.backbone.exchange(i) == 0)
        worst = std::max(worst, std::abs(r.backbone.damping(i) / rec.zeta1 - 1));
    }
    std::printf("seed %u: %d points marked, unmarked damping worst error %.3f\n  %s\n", seed,
                r.summary.exchange_points, worst, r.summary.message.c_str());
    EXPECT_GT(r.summary.exchange_points, 0);
    EXPECT_LE(worst, 0.10);
  }
}

// The same resonance read in mode 2's band, 230:260 Hz, with mode 2 damped more (0.6 %)
// than twice mode 1 (2 x 0.3 %): once mode 2's own ring-down has died, the band sees mode
// 1's square, locked at 2 f1 and decaying at 2 sigma1. Those points must be marked
// (harmonic 2), not read as mode 2: of the points decaying within 15 % of 2 sigma1 at a
// frequency within 0.1 Hz of 2 f1 (f1 read in mode 1's band at the same time), at least 3
// in 4 are marked; no marked point lies more than 0.3 Hz from 2 f1 (mode 2 is 1 Hz from
// it). Before the tolerance allowed for the pull of mode 2's residue 3 of 12 points were
// marked. (With alpha 2e9 the exchange lasts until 0.8 s and mode 2's band keeps only
// three points, too few to test.)
TEST(RingdownInternalResonance, ModeTwosBandMarksModeOnesHarmonic) {
  const double alpha = 1e9;
  for (const unsigned seed : {1u, 2u}) {
    const testing::InternalResonanceRecord rec =
        testing::internal_resonance_record(alpha, 6.5e-5, 0.006, 1e-5, seed);
    const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {230, 260});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const Backbone& b = r.backbone;
    // Mode 1's damped frequency at each time, from its own band.
    const Ringdown r1 = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
    ASSERT_EQ(r1.summary.status, RingdownStatus::kOk) << r1.summary.message;
    const Backbone& b1 = r1.backbone;
    const auto f1_at = [&](double t) {
      Eigen::Index k = 1;
      while (k + 1 < b1.size() && b1.time_s(k) < t) ++k;
      const double w =
          std::clamp((t - b1.time_s(k - 1)) / (b1.time_s(k) - b1.time_s(k - 1)), 0.0, 1.0);
      return (1 - w) * b1.damped_frequency_hz(k - 1) + w * b1.damped_frequency_hz(k);
    };
    const double two_sigma1 = 2 * rec.zeta1 * 2 * std::numbers::pi * rec.f1_hz;
    int harmonic_like = 0, marked = 0;
    for (Eigen::Index i = 0; i < b.size(); ++i) {
      const double off = std::abs(b.damped_frequency_hz(i) - 2 * f1_at(b.time_s(i)));
      std::printf("  %.3f s: %.4f Hz, decay %.2f /s, harmonic %d\n", b.time_s(i),
                  b.damped_frequency_hz(i), b.decay_rate(i), b.harmonic(i));
      if (std::abs(b.decay_rate(i) / two_sigma1 - 1) <= 0.15 && off <= 0.1) {
        ++harmonic_like;
        marked += b.harmonic(i) == 2;
      }
      if (b.harmonic(i) != 0) {
        EXPECT_LE(off, 0.3) << b.time_s(i);
      }
    }
    std::printf("mode 2's band, seed %u: %d of %d harmonic-like points marked; %s\n", seed, marked,
                harmonic_like, r.summary.message.c_str());
    EXPECT_GE(harmonic_like, 3) << seed;
    EXPECT_GE(marked, 0.75 * harmonic_like) << seed;
  }
}

// A linear mode (80 Hz, damping 0.2 %, noise 1e-3 of the peak): the linear values, the
// straight-line fit of the backbone's lower half at its lowest amplitude, must hold the truth
// within their stated (k = 3) uncertainty, which must be below 1e-4 in frequency and
// 5 % in damping; the fit spans amplitudes inside the kept span.
// A linear decay of 1 mm at 80 Hz, damping 0.2 %, 6 s at 5120 Hz, noise 1e-6 m (realisation
// `seed`).
constexpr double kDecayFs = 5120, kDecayHz = 80.0, kDecayZeta = 0.002;
Eigen::VectorXd linear_decay(unsigned seed) {
  const double fs = kDecayFs, f0 = kDecayHz, zeta = kDecayZeta;
  const Eigen::Index n = static_cast<Eigen::Index>(6 * fs);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1e-6);
  const double w = 2 * std::numbers::pi * f0 * std::sqrt(1 - zeta * zeta);
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    x(k) = 1e-3 * std::exp(-zeta * 2 * std::numbers::pi * f0 * t) * std::cos(w * t) + g(rng);
  }
  return x;
}

TEST(RingdownLinearValues, ZeroAmplitudeLimitHoldsTheTruth) {
  const double fs = kDecayFs, f0 = kDecayHz, zeta = kDecayZeta;
  for (const unsigned seed : {1u, 2u, 3u}) {
    const Eigen::VectorXd x = linear_decay(seed);
    const Ringdown r = extract_band(x, fs, Quantity::kDisplacement, {64, 96});
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const RingdownSummary& s = r.summary;
    std::printf("linear seed %u: %.5f +- %.1e Hz, %.6f +- %.1e over %.3g to %.3g\n", seed,
                s.linear_frequency_hz, s.linear_frequency_std_hz, s.linear_damping,
                s.linear_damping_std, s.linear_fit_min, s.linear_fit_max);
    EXPECT_LE(std::abs(s.linear_frequency_hz - f0), s.linear_frequency_std_hz);
    EXPECT_LE(std::abs(s.linear_damping - zeta), s.linear_damping_std);
    EXPECT_GT(s.linear_frequency_std_hz, 0);
    EXPECT_LT(s.linear_frequency_std_hz, 1e-4 * f0);
    EXPECT_LT(s.linear_damping_std, 0.05 * zeta);
    EXPECT_LT(s.linear_fit_min, s.linear_fit_max);
    EXPECT_GE(s.linear_fit_min, r.backbone.amplitude.minCoeff());
  }
}

// Where the span ends with the envelope still above the noise threshold, the summary says so, to
// when, and which limit ended it: a 13 Hz mode of a strongly nonlinear joint rung down by
// `simulate` kept 0.7-6.6 s, its envelope above the threshold until 15 s, and said nothing. An
// 80 Hz linear decay read with a damping limit of 0.5 % (its points' one-sigma is 0.1-5 %)
// ends early; the time the note names is where the same record read with a 10 % limit ends
// (the noise threshold), to within one point's spacing (about 0.01 s here).
TEST(RingdownSpanEnd, ASpanEndedByTheDampingLimitNamesItAndHowFarTheEnvelopeGoes) {
  const double fs = kDecayFs;
  const Eigen::VectorXd x = linear_decay(1);
  signal::FftCache cache;
  const signal::Band band{64, 96};
  const ChannelSpectrum cs =
      channel_spectrum(x, fs, 0.0, prepare_for({band}, RingdownOptions{}.taper), cache);
  const auto read = [&](double limit) {
    RingdownOptions opt;
    opt.amplitude = Quantity::kDisplacement;
    opt.max_damping_rel_std = limit;
    return extract_backbone(cs, Quantity::kDisplacement, band, opt, cache);
  };
  const Ringdown strict = read(0.005), loose = read(0.1);
  ASSERT_EQ(strict.summary.status, RingdownStatus::kOk) << strict.summary.message;
  ASSERT_EQ(loose.summary.status, RingdownStatus::kOk) << loose.summary.message;
  const std::string& m = strict.summary.message;
  std::printf("limit 0.5 %%: %.3f to %.3f s: %s\nlimit 10 %%: %.3f to %.3f s\n",
              strict.summary.span_start_s, strict.summary.span_end_s, m.c_str(),
              loose.summary.span_start_s, loose.summary.span_end_s);
  const std::string mark = "after the span, up to ";
  const size_t at = m.find(mark);
  ASSERT_NE(at, std::string::npos) << m;
  EXPECT_NE(m.find("the damping not known to the 0.5 % limit (--max-damping-std)", at),
            std::string::npos)
      << m;
  const double until = std::stod(m.substr(at + mark.size()));
  EXPECT_LT(strict.summary.span_end_s, until - 0.5);
  EXPECT_NEAR(until, loose.summary.span_end_s, 0.02);
  // Read to the noise threshold, nothing is said of the end.
  EXPECT_EQ(loose.summary.message.find(mark), std::string::npos) << loose.summary.message;
}

// A band that follows twice a stronger mode's frequency: mode 1 at 122 Hz (softening,
// as three_mode_record's first mode) plus a locked second harmonic at a twentieth of
// its amplitude, read in 230:260 Hz. At least three quarters of the kept points of that
// band must be flagged harmonic 2 (measured 19 of 24: the flag needs twice the
// sub-band's frequency within the point's uncertainty, and a few points miss it) and
// the summary must say so; an independent mode at 250 Hz of the same size (twice the
// first mode's frequency stays at or below 244 Hz) must not be flagged.
TEST(RingdownSuperharmonic, FlagsABandFollowingTwiceAStrongerMode) {
  const testing::ThreeModeRecord rec = testing::three_mode_record(122.0, 6.0, 1e-4, 7, 0.0);
  const Eigen::Index n = rec.displacement.size();
  Eigen::VectorXd locked = rec.displacement, free = rec.displacement;
  // The first mode's phase, from its analytic signal: cos(2 theta) = 2 cos^2 - 1 of
  // the normalised displacement (the record holds mode 1 and noise 1e-4 of the peak).
  for (Eigen::Index k = 0; k < n; ++k) {
    const double a = rec.first_amplitude(k);
    const double c = std::clamp(rec.displacement(k) / a, -1.0, 1.0);
    locked(k) += 0.05 * a * (2 * c * c - 1);
    const double t = static_cast<double>(k) / rec.fs;
    free(k) += 0.05 * 1e-3 * std::exp(-0.002 * 2 * std::numbers::pi * 250 * t) *
               std::cos(2 * std::numbers::pi * 250 * t);
  }
  const Ringdown rl = extract_band(locked, rec.fs, Quantity::kDisplacement, {230, 260});
  ASSERT_EQ(rl.summary.status, RingdownStatus::kOk) << rl.summary.message;
  std::printf("locked: %ld points, %d flagged; %s\n", long(rl.backbone.size()),
              rl.summary.superharmonic_points, rl.summary.message.c_str());
  EXPECT_GE(rl.summary.superharmonic_points, 0.75 * static_cast<double>(rl.backbone.size()));
  EXPECT_NE(rl.summary.message.find("superharmonic"), std::string::npos);
  const Ringdown rf = extract_band(free, rec.fs, Quantity::kDisplacement, {230, 260});
  ASSERT_EQ(rf.summary.status, RingdownStatus::kOk) << rf.summary.message;
  std::printf("free: %ld points, %d flagged\n", long(rf.backbone.size()),
              rf.summary.superharmonic_points);
  EXPECT_EQ(rf.summary.superharmonic_points, 0);
}

// A band with no mode in it says what the spectrum shows instead: the strongest peak
// near the band (a linear mode at 80 Hz, band 90:110 Hz).
TEST(RingdownAdvice, NoModeInTheBandNamesThePeakNearIt) {
  const double fs = 2048, f0 = 80.0;
  const Eigen::Index n = static_cast<Eigen::Index>(4 * fs);
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1e-6);
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    x(k) = 1e-3 * std::exp(-0.003 * 2 * std::numbers::pi * f0 * t) *
               std::cos(2 * std::numbers::pi * f0 * t) +
           g(rng);
  }
  const Ringdown r = extract_band(x, fs, Quantity::kDisplacement, {90, 110});
  std::printf("advice: %s\n", r.summary.report().c_str());
  ASSERT_NE(r.summary.status, RingdownStatus::kOk);
  EXPECT_NE(r.summary.message.find("no mode in the band"), std::string::npos);
  // The peak's bin is within 0.05 Hz of 80 Hz (4 s record, Hann window).
  EXPECT_TRUE(r.summary.message.find("at 79.9") != std::string::npos ||
              r.summary.message.find("at 80.0") != std::string::npos)
      << r.summary.message;
}

// The advice's numbers against modes of known damping: 80 Hz, damping 0.3, 1 and 3 % (noise
// 1e-4 of the peak, 10 s at 1 kHz). The half-power width it names must be 2 zeta f within 5 %
// (measured: exact to its 3 digits; read from the continued record's spectrum, as before, it
// was 0.77-0.79 times that: 0.37, 1.25 and 3.78 Hz). Its factor (was 4): bands of 0.5-8
// half-power widths gave no span in 16 of 21 cases, 0.44-1.00 decades in 4 and 2.34 in one
// (0.3 %, 8 widths); bands of 12 and 16 widths gave 1.96-2.67 decades. A band whose filter
// settles longer than the record's continuation holds is now widened about its mode (at most 3
// times): a band of 4 widths is read through 12 (its points' damping within 1.2 % of the truth),
// one of a single width not (3 widths are still too few) and gets the advice. Required: a band
// of one width gets the advice with the width; bands of 4 and 12 widths at least 1.5 decades, a
// band of 4 widths with every point's damping within 3 %.
TEST(RingdownAdvice, HalfPowerWidthOfAModeOfKnownDamping) {
  const double fs = 1000, f0 = 80.0;
  const Eigen::Index n = static_cast<Eigen::Index>(10 * fs);
  for (const double zeta : {0.003, 0.01, 0.03}) {
    std::mt19937 rng(1);
    std::normal_distribution<double> g(0.0, 1e-4);
    Eigen::VectorXd x(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const double t = static_cast<double>(k) / fs;
      x(k) = std::exp(-zeta * 2 * std::numbers::pi * f0 * t) *
                 std::cos(2 * std::numbers::pi * f0 * t) +
             g(rng);
    }
    const double hp = 2 * zeta * f0;
    const auto named_width = [&](bool long_path) {
      const Ringdown narrow = extract_band(x, fs, Quantity::kDisplacement,
                                           {f0 - hp / 2, f0 + hp / 2}, Method::kHilbert, long_path);
      EXPECT_NE(narrow.summary.status, RingdownStatus::kOk) << zeta;
      const std::string said = "narrower than 12 times the half-power width of its mode (";
      const size_t at = narrow.summary.message.find(said);
      EXPECT_NE(at, std::string::npos) << narrow.summary.message;
      return at == std::string::npos ? 0.0
                                     : std::stod(narrow.summary.message.substr(at + said.size()));
    };
    const double width = named_width(false);
    // A long record's measured part is not padded to 4x (its bins are fine already): on 10 s
    // the crossings still fall between bins 0.1 Hz apart.
    const double long_width = named_width(true);
    std::printf("zeta %.3f: half-power width %.3g Hz on the long record's path\n", zeta,
                long_width);
    EXPECT_NEAR(long_width / hp, 1.0, 0.05) << zeta;
    const Ringdown wide = extract_band(x, fs, Quantity::kDisplacement, {f0 - 6 * hp, f0 + 6 * hp});
    std::printf(
        "zeta %.3f: half-power width %.3g Hz named, %.3g Hz true; 12 widths: %.2f decades\n", zeta,
        width, hp, wide.summary.amplitude_decades);
    EXPECT_NEAR(width / hp, 1.0, 0.05) << zeta;
    ASSERT_EQ(wide.summary.status, RingdownStatus::kOk) << wide.summary.message;
    EXPECT_GE(wide.summary.amplitude_decades, 1.5) << zeta;
    const Ringdown four = extract_band(x, fs, Quantity::kDisplacement, {f0 - 2 * hp, f0 + 2 * hp});
    ASSERT_EQ(four.summary.status, RingdownStatus::kOk) << four.summary.message;
    EXPECT_GE(four.summary.amplitude_decades, 1.5) << zeta;
    for (Eigen::Index i = 0; i < four.backbone.size(); ++i)
      EXPECT_NEAR(four.backbone.damping(i) / zeta, 1.0, 0.03) << zeta << " at " << i;
  }
}

// A band narrower than its mode: 79:81 Hz around a mode at 80 Hz with 3 % damping
// (half-power width 4.8 Hz). The reason must say the band is narrower than 12 times the
// mode's half-power width rather than only that the record is too short.
TEST(RingdownAdvice, ABandNarrowerThanItsModeSaysSo) {
  const double fs = 1000, f0 = 80.0;
  const Eigen::Index n = static_cast<Eigen::Index>(10 * fs);
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    x(k) =
        std::exp(-0.03 * 2 * std::numbers::pi * f0 * t) * std::cos(2 * std::numbers::pi * f0 * t);
  }
  const Ringdown r = extract_band(x, fs, Quantity::kDisplacement, {79, 81});
  std::printf("advice: %s\n", r.summary.report().c_str());
  ASSERT_NE(r.summary.status, RingdownStatus::kOk);
  EXPECT_NE(r.summary.message.find("narrower than 12 times the half-power width"),
            std::string::npos)
      << r.summary.message;
}

using Case = std::tuple<double, bool, Method>;

// Issue 2's acceptance as written: fs 5120 Hz, 6 s, three modes, the first
// nonlinear (frequency falls 3.5 %, damping rises from 0.1 % to 0.95 %), white
// noise at 0.1 % of the record's peak, which mode 1 dominates here (modes 2 and 3
// at a tenth of their stress-test amplitude). Every record: at least 1.5 decades
// (1.4 for peak fitting, which has about half as many independent points), every
// frequency within 0.05 %, every damping within 3 %, median damping within 1 %.
// Coverage of the stated (expanded, k = 3) uncertainties: at least 90 % of the
// points of every record. The points of one record share their noise over a
// window (up to several seconds), so one record's coverage is a handful of
// independent draws; k = 3 is what makes single records hold (see ringdown.h).
class RingdownAcceptance : public ::testing::TestWithParam<Case> {};

TEST_P(RingdownAcceptance, MeetsTheIssueOnThreeRecords) {
  const auto [f1, acc, method] = GetParam();
  for (const unsigned seed : {11u, 12u, 13u}) {
    const testing::ThreeModeRecord rec = testing::three_mode_record(f1, 6.0, 1e-3, seed, 0.1);
    const Ringdown r = extract(rec, f1, acc, method);
    ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
    const Errors e = score(r, rec.first);
    print("acceptance", method, f1, acc, seed, e);
    // Independent modes, one of them jointed: no point is taken for an energy exchange.
    EXPECT_EQ(r.summary.exchange_points, 0) << "seed " << seed << ": " << r.summary.message;
    EXPECT_GE(e.decades, method == Method::kHilbert ? 1.5 : 1.4) << "seed " << seed;
    EXPECT_LE(e.max_f, 5e-4) << "seed " << seed;
    EXPECT_LE(e.max_z, 0.03) << "seed " << seed;
    EXPECT_LE(e.median_z, 0.01) << "seed " << seed;
    EXPECT_GE(e.coverage_f, 0.9) << "seed " << seed;
    EXPECT_GE(e.coverage_z, 0.9) << "seed " << seed;
  }
}

INSTANTIATE_TEST_SUITE_P(Issue, RingdownAcceptance,
                         ::testing::Combine(::testing::Values(40.0, 80.0, 150.0), ::testing::Bool(),
                                            ::testing::Values(Method::kHilbert, Method::kPeaks)));

// A harder record: the third mode dominates the peak the noise is scaled to, so
// from acceleration the noise is 3.5 times larger against mode 1 than from
// displacement, and at f1 = 150 Hz the mode also decays 3.75 times faster (fewer
// samples carry each amplitude). Over 8 seeds the Hilbert spans are 1.75-2.06
// decades from displacement; from acceleration 1.41-1.55 at 40 Hz, 1.34-1.50 at
// 80 Hz and 1.12-1.31 at 150 Hz (this seed: 1.50, 1.44, 1.24). Required here: 1.5
// and 1.2 decades (1.4 and 0.8 for peak fitting), worst damping error 4 %,
// frequency 0.05 %, median damping 1 %, coverage 90 %.
class RingdownStress : public ::testing::TestWithParam<Case> {};

TEST_P(RingdownStress, RecoversPrescribedBackbone) {
  const auto [f1, acc, method] = GetParam();
  const testing::ThreeModeRecord rec = testing::three_mode_record(f1, 6.0, 1e-3, 11);
  const Ringdown r = extract(rec, f1, acc, method);
  ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
  const Errors e = score(r, rec.first);
  print("stress", method, f1, acc, 11, e);
  EXPECT_EQ(r.summary.exchange_points, 0) << r.summary.message;
  const bool hilbert = method == Method::kHilbert;
  EXPECT_GE(e.decades, hilbert ? (acc ? 1.2 : 1.5) : (acc ? 0.8 : 1.4));
  EXPECT_LE(e.max_f, 5e-4);
  EXPECT_LE(e.max_z, 0.04);
  EXPECT_LE(e.median_z, 0.01);
  EXPECT_GE(e.coverage_f, 0.9);
  EXPECT_GE(e.coverage_z, 0.9);
}

INSTANTIATE_TEST_SUITE_P(Harsh, RingdownStress,
                         ::testing::Combine(::testing::Values(40.0, 80.0, 150.0), ::testing::Bool(),
                                            ::testing::Values(Method::kHilbert, Method::kPeaks)));

// The same resonance struck as a hammer strikes it: both modes at once (mode 2 at 0.1, 0.3
// and 1 times mode 1's amplitude, in three phases), alpha 1e9-3e9, zeta2 0.6 %. Mode 2 then
// takes energy from the start and mode 1's decay rate is up to three times its own, turning
// once or not at all before it relaxes. Measured on these 27 cases: kept 0.75-1.00 of what the
// envelope shows (median 0.90; before a single turn with strongly anti-correlated rates counted
// as an exchange, 0.50-1.00, median 0.82), the unmarked points' median frequency error at most
// 3.7e-5 and median damping error at most 1.0 %. Where the exchange is marked (24 of 27), no
// unmarked point's damping is more than 5.7 % off (before, in 19 of the 27 cases some unmarked
// point was more than 10 % off, up to 170 %, with a stated uncertainty of 1 %: the relaxation
// after the last turn was not marked). Where it is not (3 of the 27: the rate only falls from
// the start), unmarked points at the start still read 19-65 % more damping: the envelope's
// decay there looks as a joint's damping does, falling as the amplitude falls. Required: 0.7
// kept in every case and 0.85 in the median, the medians above within 5e-4 and 10 %, and no
// unmarked point more than 10 % off where an exchange is marked.
TEST(RingdownInternalResonance, BothModesStruck) {
  std::vector<double> kept;
  for (const double alpha : {1e9, 2e9, 3e9}) {
    for (const double ratio : {0.1, 0.3, 1.0}) {
      for (const double phase : {0.0, std::numbers::pi / 2, std::numbers::pi}) {
        const testing::InternalResonanceRecord rec = testing::internal_resonance_record(
            alpha, 6.5e-5, 0.006, 1e-5, 1, 4.0, ratio * 6.5e-5, phase);
        const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
        ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
        const double threshold = RingdownOptions{}.snr_min * r.summary.noise_floor_m;
        const double share =
            r.summary.amplitude_decades / std::log10(rec.amplitude1.maxCoeff() / threshold);
        kept.push_back(share);
        std::vector<double> ef, ez;
        for (Eigen::Index i = 0; i < r.backbone.size(); ++i) {
          if (r.backbone.exchange(i) != 0) continue;
          ef.push_back(std::abs(r.backbone.frequency_hz(i) / rec.f1_hz - 1));
          ez.push_back(std::abs(r.backbone.damping(i) / rec.zeta1 - 1));
        }
        ASSERT_FALSE(ef.empty());
        std::sort(ef.begin(), ef.end());
        std::sort(ez.begin(), ez.end());
        std::printf(
            "both struck: alpha %.0e ratio %.1f phase %.2f: %.3f of the envelope kept, %d "
            "points marked exchange; unmarked: median f err %.1e, median z err %.3f, worst "
            "%.3f\n",
            alpha, ratio, phase, share, r.summary.exchange_points, ef[ef.size() / 2],
            ez[ez.size() / 2], ez.back());
        char where[64];
        std::snprintf(where, sizeof where, "alpha %g ratio %g phase %g", alpha, ratio, phase);
        EXPECT_GE(share, 0.7) << where;
        EXPECT_LE(ef[ef.size() / 2], 5e-4) << where;
        EXPECT_LE(ez[ez.size() / 2], 0.10) << where;
        if (r.summary.exchange_points > 0) {
          EXPECT_LE(ez.back(), 0.10) << where;
        }
      }
    }
  }
  std::sort(kept.begin(), kept.end());
  EXPECT_GE(kept[kept.size() / 2], 0.85);
}

// The first twin with slow content beside it, as a sensor's high-pass or a rigid-body motion
// leaves after an impact: a 10 Hz component of damping 0.2 whose velocity starts at 1 or 3
// times mode 1's. Its rates then swing harder at the start (up to 28 1/s), the band is moved
// and widened to follow them, and the exchange is read through shorter windows: kept 0.81-0.93
// of what mode 1's envelope shows (0.80-0.94 without it). Required: 0.8 in every record.
TEST(RingdownInternalResonance, SlowContentBesideKeepsWhatTheEnvelopeShows) {
  const double two_pi = 2 * std::numbers::pi;
  for (const double level : {1.0, 3.0}) {
    for (const double alpha : {1e9, 3e9}) {
      for (const unsigned seed : {1u, 2u}) {
        testing::InternalResonanceRecord rec = testing::internal_resonance_record(
            alpha, 6.5e-5, alpha > 2e9 ? 0.002 : 0.006, 1e-5, seed);
        testing::SlowFlowMode slow;
        slow.omega_n = [=](double) { return two_pi * 10; };
        slow.zeta = [](double) { return 0.2; };
        slow.a0 = level * 6.5e-5 * 122 / 10;  // velocity level times mode 1's, at 10 Hz
        slow.theta0 = 0.5;
        rec.velocity += testing::slow_flow(slow, rec.fs, rec.velocity.size()).velocity;
        const Ringdown r = extract_band(rec.velocity, rec.fs, Quantity::kVelocity, {110, 135});
        ASSERT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
        const double threshold = RingdownOptions{}.snr_min * r.summary.noise_floor_m;
        const double share =
            r.summary.amplitude_decades / std::log10(rec.amplitude1.maxCoeff() / threshold);
        std::printf(
            "slow content %g times mode 1, alpha %g seed %u: %.3f of the envelope kept, "
            "%d points marked exchange\n",
            level, alpha, seed, share, r.summary.exchange_points);
        EXPECT_GE(share, 0.8) << "level " << level << " alpha " << alpha << " seed " << seed;
      }
    }
  }
}

// The joint-like mode of the tests below beside an uncoupled neighbour at `neighbour_hz`, over
// 54 records (3 amplitudes of the damping peak, 3 of the neighbour, 3 kinds of its damping, 2
// noise seeds); with `two_peaks` the mode's damping peaks a second time, a decade of amplitude
// below the first, so that its decay rate turns three times. Returns how many mark an exchange
// (each one a test failure).
int exchanges_beside_an_uncoupled_neighbour(double neighbour_hz, bool two_peaks) {
  const double fs = 5120, two_pi = 2 * std::numbers::pi, a0 = 1e-4;
  const Eigen::Index n = static_cast<Eigen::Index>(4.0 * fs);
  int flagged = 0;
  for (const double peak_at : {0.3, 0.1, 0.03}) {
    for (const double ratio : {0.25, 0.75, 2.25}) {
      for (const int kind : {0, 1, 2}) {
        const auto bump = [](double a, double at) {
          const double l = std::log(a / at) / 0.7;
          return std::exp(-0.5 * l * l);
        };
        const auto bumps = [=](double a) {
          return bump(a, peak_at * a0) + (two_peaks ? bump(a, 0.1 * peak_at * a0) : 0.0);
        };
        testing::SlowFlowMode m1;
        m1.omega_n = [=](double a) { return two_pi * 100 * (1 - 0.004 * bumps(a)); };
        m1.zeta = [=](double a) { return 0.002 + 0.006 * bumps(a); };
        m1.a0 = a0;
        testing::SlowFlowMode m2;
        m2.omega_n = [=](double) { return two_pi * neighbour_hz; };
        m2.zeta = [=](double a) {
          if (kind == 0) return 0.003;
          if (kind == 1) return 0.002 + 0.004 * std::min(1.0, a / (ratio * a0));
          return 0.002 + 0.005 * bump(a, 0.4 * ratio * a0);
        };
        m2.a0 = ratio * a0;
        m2.theta0 = 1.0;
        const Eigen::VectorXd clean =
            testing::slow_flow(m1, fs, n).velocity + testing::slow_flow(m2, fs, n).velocity;
        for (const unsigned seed : {1u, 2u}) {
          std::mt19937 rng(seed);
          std::normal_distribution<double> g(0.0, 1e-5 * clean.cwiseAbs().maxCoeff());
          Eigen::VectorXd x = clean;
          for (Eigen::Index k = 0; k < n; ++k) x(k) += g(rng);
          const Ringdown r = extract_band(x, fs, Quantity::kVelocity, {85, 115});
          EXPECT_EQ(r.summary.status, RingdownStatus::kOk) << r.summary.message;
          flagged += r.summary.exchange_points > 0;
          EXPECT_EQ(r.summary.exchange_points, 0)
              << "neighbour " << neighbour_hz << " Hz, peak at " << peak_at << ", ratio " << ratio
              << ", kind " << kind << ", seed " << seed << ", two peaks " << two_peaks << ": "
              << r.summary.message;
        }
      }
    }
  }
  return flagged;
}

// What a single turn of the decay rate must not be taken for: a joint-like mode (100 Hz, its
// damping peaking at 0.8 % where the amplitude is 0.3, 0.1 or 0.03 of the start, so that its
// decay rate turns once) beside an uncoupled neighbour at about 2, 1/2 or 3 times its
// frequency (0.25, 0.75 or 2.25 times its amplitude; linear, its damping falling with its
// amplitude, or peaking too), two noise seeds: 162 records, none may mark an exchange. With
// the rank correlation alone (at most -0.6), 9 of the 54 records with the neighbour at twice
// the frequency, 12 of 54 at half and 1 of 54 at three times marked one; the partner's rate
// must also turn the other way near this one's turn, clearly apart from where it ends.
TEST(RingdownInternalResonance, OneTurnBesideAnUncoupledNeighbourIsNoExchange) {
  for (const double neighbour_hz : {201.3, 50.4, 301.7}) {
    const int flagged = exchanges_beside_an_uncoupled_neighbour(neighbour_hz, false);
    std::printf("neighbour at %.1f Hz: %d of 54 records mark an exchange\n", neighbour_hz, flagged);
  }
}

// As above, with the mode's damping peaking twice (its decay rate turns three times, so the
// partner's rate must move against it, in its ranks or its changes, and mirror at least half
// of its turns): 162 records, none may mark an exchange. With the rank correlation alone
// (at most -0.3), 41 of them marked most of their points.
TEST(RingdownInternalResonance, ThreeTurnsBesideAnUncoupledNeighbourAreNoExchange) {
  for (const double neighbour_hz : {201.3, 50.4, 301.7}) {
    const int flagged = exchanges_beside_an_uncoupled_neighbour(neighbour_hz, true);
    std::printf("neighbour at %.1f Hz, two damping peaks: %d of 54 records mark an exchange\n",
                neighbour_hz, flagged);
  }
}

// Two modes in one band (a newcomer's trial): m(f, z, A) = A exp(-z 2 pi f t) cos(2 pi f
// sqrt(1 - z^2) t), displacement at 2048 Hz for 8 s, white noise 1e-7 m. The band's mode is
// m(50 Hz, ...); the band's signal beats with the second mode at the difference frequency, and
// the envelope's decay rate and the frequency oscillate with it. Before, 40:60 Hz read
// 50 Hz + 52 Hz (a fifth of its size) as 51.11 +- 0.012 Hz and damping 0.0089 +- 0.00026
// (true 0.005), no point's damping within its uncertainty and no word of the second mode;
// 51 Hz at 5 % swung the damping between 0.00205 and 0.00398 (true 0.003), 31 % of the
// points within their uncertainty. Now the summary names the second mode (its spectral peak,
// refined between bins 1/8 Hz apart: within 0.2 Hz) and the beat joins each point's
// uncertainty: what is kept has at least 90 % of its points' damping and frequency within their
// stated k sigma (what k = 3 gives a record of a single mode, docs/process.md step 4), or
// nothing is kept. Measured: 52 Hz at 20 % and 51 Hz at 50 % keep nothing; 51 Hz at 5 %
// keeps 0.8 decades of the tail, where the windows span several beats, every point within.
struct TwoModeCase {
  double f2, z1, z2, a2;
};

Eigen::VectorXd two_close_modes(const TwoModeCase& c, unsigned seed) {
  constexpr double fs = 2048.0;
  const Eigen::Index n = static_cast<Eigen::Index>(8 * fs);
  const auto m = [](double f, double z, double a, double t) {
    const double w = 2 * std::numbers::pi * f;
    return a * std::exp(-z * w * t) * std::cos(w * std::sqrt(1 - z * z) * t);
  };
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1e-7);
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    x(k) = m(50.0, c.z1, 1e-3, t) + (c.a2 > 0 ? m(c.f2, c.z2, c.a2, t) : 0.0) + noise(rng);
  }
  return x;
}

// Share of the backbone's points whose damping and frequency are both within their stated
// expanded uncertainty of the single 50 Hz mode's.
double within(const Backbone& b, double z_true) {
  int in = 0;
  for (Eigen::Index i = 0; i < b.size(); ++i) {
    in += std::abs(b.damping(i) - z_true) <= b.damping_std(i) &&
          std::abs(b.frequency_hz(i) - 50.0) <= b.frequency_std_hz(i);
  }
  return b.size() > 0 ? double(in) / double(b.size()) : 1.0;
}

TEST(RingdownTwoModes, ABeatWithASecondModeInTheBandIsNamedAndNotReadAsDamping) {
  for (const TwoModeCase c :
       {TwoModeCase{52.0, 0.005, 0.003, 2e-4}, TwoModeCase{51.0, 0.003, 0.003, 5e-5},
        TwoModeCase{51.0, 0.003, 0.003, 5e-4}}) {
    for (const unsigned seed : {1u, 2u}) {
      const Ringdown r =
          extract_band(two_close_modes(c, seed), 2048.0, Quantity::kDisplacement, {40, 60});
      const std::string& msg = r.summary.message;
      std::printf(
          "50 Hz + %.0f Hz at %.0f %%, seed %u: %ld points, %.2f decades, within %.2f: %s\n", c.f2,
          100 * c.a2 / 1e-3, seed, long(r.backbone.size()), r.summary.amplitude_decades,
          within(r.backbone, c.z1), msg.c_str());
      const auto at = msg.find("holds a second mode at ");
      ASSERT_NE(at, std::string::npos) << msg;
      EXPECT_NEAR(std::stod(msg.substr(at + 23)), c.f2, 0.2) << msg;
      EXPECT_GE(within(r.backbone, c.z1), 0.9) << msg;
      if (r.summary.has_linear()) {
        EXPECT_LE(std::abs(r.summary.linear_damping - c.z1), r.summary.linear_damping_std) << msg;
      }
      EXPECT_EQ(r.summary.exchange_points, 0) << msg;  // a beat is no energy exchange
    }
  }
}

// The same 50 Hz mode with the 52 Hz one (a fifth of its size) typed as 42:51 Hz, the user
// leaving 52 Hz out on purpose: the band may follow the mode up (it sits past the band's
// half-gain point, 49.9 Hz) but not onto 52 Hz, a resolved peak of the measured spectrum
// (before, the band was moved to 33:60 Hz and read damping 0.0217 +- 0.00064, true 0.005).
// Whatever is kept is the 50 Hz mode's, to the same 90 % as above (measured: nothing, the
// mode on the held band's edge). A single 50 Hz mode in 40:60 Hz is read as before, with no
// word of a second mode (48 points, 3.15 decades, every one within).
TEST(RingdownTwoModes, TheBandFollowingTheModeStopsShortOfASecondModeBesideTheTypedBand) {
  for (const unsigned seed : {1u, 2u}) {
    const Ringdown r = extract_band(two_close_modes({52.0, 0.005, 0.003, 2e-4}, seed), 2048.0,
                                    Quantity::kDisplacement, {42, 51});
    const std::string& msg = r.summary.message;
    std::printf("50 Hz + 52 Hz in 42:51 Hz, seed %u: %ld points, within %.2f: %s\n", seed,
                long(r.backbone.size()), within(r.backbone, 0.005), msg.c_str());
    const auto read = msg.find("read through ");
    if (read != std::string::npos) {
      const double hi = std::stod(msg.substr(msg.find(':', read) + 1));
      EXPECT_LT(hi, 52.0) << msg;
      EXPECT_NE(msg.find("neighbouring mode's spectral peak at 52"), std::string::npos) << msg;
    }
    EXPECT_GE(within(r.backbone, 0.005), 0.9) << msg;
    const Ringdown single = extract_band(two_close_modes({0, 0.005, 0, 0}, seed), 2048.0,
                                         Quantity::kDisplacement, {40, 60});
    std::printf("50 Hz alone in 40:60 Hz, seed %u: %ld points, %.2f decades, within %.2f: %s\n",
                seed, long(single.backbone.size()), single.summary.amplitude_decades,
                within(single.backbone, 0.005), single.summary.message.c_str());
    ASSERT_EQ(single.summary.status, RingdownStatus::kOk) << single.summary.message;
    EXPECT_EQ(single.summary.message.find("second mode"), std::string::npos);
    EXPECT_GE(single.summary.amplitude_decades, 3.0);
    EXPECT_GE(within(single.backbone, 0.005), 0.9);
  }
}

}  // namespace

}  // namespace jointlab::modal
