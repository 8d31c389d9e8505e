#include "jointlab/modal/process.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/signal/spectrum.h"

namespace jointlab::modal {

namespace {

// Below this coherence another channel's band signal is not the same mode (a
// corrupted sample, another source) and does not count in the nodal test.
constexpr double kMinCoherence = 0.5;

// Most samples one continued record may take (its spectrum then takes about 1.5 GB).
constexpr double kMaxSamples = 5e7;

// The band's analytic signal z of channel `channel` at absolute time t, by cubic
// (Lagrange) interpolation of its baseband: the coarse grid samples the baseband at
// 8 times its width, where the cubic's error is below 1e-3.
std::complex<double> band_value(const signal::BandSignal& z, const ChannelSpectrum& channel,
                                double t) {
  const double x = (t - channel.t0) / z.dt;
  const Eigen::Index n = z.baseband.size();
  if (n < 4) return 0.0;
  const auto j = std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::floor(x)) - 1, 0, n - 4);
  const double u = x - static_cast<double>(j);
  std::complex<double> v = 0.0;
  for (int k = 0; k < 4; ++k) {
    double w = 1;
    for (int l = 0; l < 4; ++l) {
      if (l != k) w *= (u - l) / (k - l);
    }
    v += w * z.baseband(j + k);
  }
  return v * std::polar(1.0, 2 * std::numbers::pi * z.carrier_hz * (t - channel.t0));
}

// Channel b's band signal against channel a's over [t1, t2] (a's coarse grid):
// ratio = a^H b / a^H a, coherence = |a^H b|^2 / (|a|^2 |b|^2), and b's complex
// amplitude scaled to a's envelope at t1.
struct Projection {
  std::complex<double> ratio = 0.0;
  double coherence = 0.0;
  std::complex<double> amplitude = 0.0;
};

Projection projection(const signal::BandSignal& za, const ChannelSpectrum& ca,
                      const signal::BandSignal& zb, const ChannelSpectrum& cb, double t1,
                      double t2) {
  Projection p;
  std::complex<double> ab = 0.0;
  double aa = 0, bb = 0;
  for (double t = t1; t <= t2 + 1e-12; t += za.dt) {
    const std::complex<double> a = band_value(za, ca, t), b = band_value(zb, cb, t);
    ab += std::conj(a) * b;
    aa += std::norm(a);
    bb += std::norm(b);
  }
  if (!(aa > 0) || !(bb > 0) || !std::isfinite(aa) || !std::isfinite(bb)) return p;
  p.ratio = ab / aa;
  p.coherence = std::norm(ab) / (aa * bb);
  p.amplitude = p.ratio * std::abs(band_value(za, ca, t1));
  return p;
}

// Refuses, before anything is allocated, what cannot be processed: a continued record
// too large for memory, a band whose filter cannot settle within the record, and a
// requested channel whose quantity is unknown.
void check_processable(const data::Record& record, const std::vector<signal::Band>& bands,
                       const std::vector<const data::Channel*>& chans,
                       const ProcessOptions& options) {
  // Sizes before anything is allocated: the continued record must fit in memory, and
  // each band's filter must settle within the record.
  const double duration = static_cast<double>(record.size() - 1) / record.fs;
  const auto samples_for = [&](double extend_s) { return (duration + 2 * extend_s) * record.fs; };
  if (!(samples_for(options.prepare.extend_s) <= kMaxSamples)) {
    throw InputError(
        where(record.source, 0,
              fmt::format("sample rate {:.3g} Hz: analysing this record would take {:.3g} "
                          "samples (at most {:.3g}); check the file's time column or fs",
                          record.fs, samples_for(options.prepare.extend_s), kMaxSamples)));
  }
  for (const signal::Band& b : bands) {
    const double settle = band_settling_s(b, options.ringdown.taper);
    const double samples =
        samples_for(prepare_for({b}, options.ringdown.taper, options.prepare).extend_s);
    if (!(settle <= duration) || !(samples <= kMaxSamples)) {
      throw InputError(where(
          record.source, 0,
          fmt::format("band {}:{} Hz is too narrow for this {:.3g} s record: its filter takes "
                      "{:.3g} s to settle; give a band at least {:.3g} Hz wide",
                      b.lo, b.hi, duration, settle, 3.0 / (options.ringdown.taper * duration))));
    }
  }
  // A channel without a unit measures what the user says, or nothing can be assumed.
  for (const data::Channel* c : chans) {
    if (c->quantity || options.quantity) continue;
    throw InputError(where(
        record.source, 0,
        fmt::format("channel '{}' has no unit and no --quantity was given: give its unit in the "
                    "header (e.g. '{} [m/s^2]', '{} [m/s]') or --quantity "
                    "acceleration|velocity|displacement",
                    c->name, c->name, c->name)));
  }
}

}  // namespace

std::string ProcessOptions::check() const {
  if (modes < 0) return "--modes must be positive";
  if (modes == 0 && bands.empty()) return "give --band LO:HI or --modes N";
  for (const signal::Band& b : bands) {
    if (!(b.lo > 0 && b.hi > b.lo)) {
      return fmt::format("band {}:{} must satisfy 0 < LO < HI", b.lo, b.hi);
    }
  }
  if (quantity == Quantity::kForce) return "--quantity must be a motion quantity";
  if (!(min_share >= 0 && min_share < 1)) return "--min-share must be in [0, 1)";
  if (std::string r = ringdown.check(); !r.empty()) return r;
  return {};
}

std::vector<signal::Band> bands_from_peaks(const data::Record& record,
                                           const std::vector<const data::Channel*>& channels,
                                           int count, signal::FftCache& cache) {
  Eigen::VectorXd total;
  Eigen::VectorXd freq;
  for (const data::Channel* c : channels) {
    const signal::AmplitudeSpectrum s = signal::amplitude_spectrum(c->samples, record.fs, cache);
    const double top = s.amplitude.maxCoeff();
    if (!(top > 0)) continue;
    if (total.size() == 0) {
      total = Eigen::VectorXd::Zero(s.amplitude.size());
      freq = s.frequency_hz;
    }
    total += s.amplitude / top;
  }
  if (total.size() == 0) return {};
  const double df = freq(1) - freq(0);
  // Peaks closer than 1 Hz (or 3 bins) are one mode.
  const auto min_distance = std::max<Eigen::Index>(3, static_cast<Eigen::Index>(1.0 / df));
  // Ignore the bottom 2 Hz (offsets, drift) and the top 5 % below Nyquist.
  const auto k_lo = static_cast<Eigen::Index>(2.0 / df) + 1;
  const Eigen::Index k_hi = static_cast<Eigen::Index>(0.95 * static_cast<double>(total.size()));
  Eigen::VectorXd searched = Eigen::VectorXd::Zero(total.size());
  searched.segment(k_lo, k_hi - k_lo) = total.segment(k_lo, k_hi - k_lo);
  const std::vector<Eigen::Index> peaks = signal::strongest_peaks(searched, count, min_distance);
  std::vector<signal::Band> bands;
  for (size_t i = 0; i < peaks.size(); ++i) {
    const double f = freq(peaks[i]);
    double lo = 0.85 * f, hi = 1.15 * f;
    if (i > 0) lo = std::max(lo, 0.5 * (f + freq(peaks[i - 1])));
    if (i + 1 < peaks.size()) hi = std::min(hi, 0.5 * (f + freq(peaks[i + 1])));
    hi = std::min(hi, 0.5 * record.fs * 0.99);
    bands.push_back({lo, hi});
  }
  return bands;
}

RecordResult process_record(const data::Record& record, const ProcessOptions& options,
                            signal::FftCache& cache) {
  RecordResult out;
  out.source = record.source;
  std::vector<const data::Channel*> chans;
  if (options.channels.empty()) {
    for (const data::Channel& c : record.channels) {
      if (c.quantity != Quantity::kForce) chans.push_back(&c);
    }
  } else {
    for (const std::string& name : options.channels) {
      const data::Channel* c = record.find(name);
      if (!c) {
        std::string have;
        for (const data::Channel& k : record.channels) have += (have.empty() ? "" : ", ") + k.name;
        throw InputError(
            where(record.source, 0, fmt::format("no channel '{}' (channels: {})", name, have)));
      }
      if (c->quantity == Quantity::kForce) {
        throw InputError(
            where(record.source, 0, fmt::format("channel '{}' is a force, not a response", name)));
      }
      chans.push_back(c);
    }
  }
  if (chans.empty()) throw InputError(where(record.source, 0, "no response channel to process"));
  if (record.size() < 64) {
    throw InputError(where(record.source, 0,
                           fmt::format("{} samples: too short for a ring-down", record.size())));
  }

  out.bands =
      options.modes > 0 ? bands_from_peaks(record, chans, options.modes, cache) : options.bands;
  if (options.modes > 0 && static_cast<int>(out.bands.size()) < options.modes) {
    throw InputError(where(
        record.source, 0,
        fmt::format("--modes {}: only {} spectral peaks found", options.modes, out.bands.size())));
  }
  for (const signal::Band& b : out.bands) {
    if (b.hi > record.fs / 2) {
      throw InputError(where(record.source, 0,
                             fmt::format("band {}:{} Hz reaches past the Nyquist frequency {} Hz",
                                         b.lo, b.hi, record.fs / 2)));
    }
  }

  check_processable(record, out.bands, chans, options);
  // Every band, channel and file is processed on its own: each channel from its own
  // impact, each band with the continuation and low-pass it alone needs (bands that
  // need the same share one). The nodal test below compares a channel with every
  // response channel of the file, requested or not.
  const double taper = options.ringdown.taper;
  std::vector<const data::Channel*> all;
  for (const data::Channel& c : record.channels) {
    // Channels whose quantity is unknown cannot be compared (requested ones have one).
    if (c.quantity != Quantity::kForce && (c.quantity || options.quantity)) all.push_back(&c);
  }
  std::vector<Eigen::Index> impact(all.size());
  for (size_t c = 0; c < all.size(); ++c) impact[c] = impact_index(all[c]->samples);
  const auto index_of = [&](const data::Channel* ch) {
    return static_cast<size_t>(std::find(all.begin(), all.end(), ch) - all.begin());
  };
  for (size_t b = 0; b < out.bands.size(); ++b) {
    const signal::Band& band = out.bands[b];
    const PrepareOptions prepare = prepare_for({band}, taper, options.prepare);
    // Band signals of every response channel (for the nodal test and the shape).
    std::vector<Ringdown> others(all.size());
    std::vector<ChannelSpectrum> spectra(all.size());
    for (size_t c = 0; c < all.size(); ++c) {
      spectra[c] =
          channel_spectrum(all[c]->samples, record.fs, record.t0, prepare, cache, impact[c]);
    }
    const size_t first = out.results.size();
    for (const data::Channel* ch : chans) {
      const size_t c = index_of(ch);
      ChannelBand r;
      r.channel = ch->name;
      r.measured = ch->quantity ? *ch->quantity : *options.quantity;
      r.band_index = static_cast<int>(b) + 1;
      r.ringdown = extract_backbone(spectra[c], r.measured, band, options.ringdown, cache);
      out.results.push_back(std::move(r));
    }
    // A requested channel's band signal is the one its extraction made.
    std::vector<char> have(all.size(), 0);
    for (size_t i = first; i < out.results.size(); ++i) {
      const size_t c = index_of(record.find(out.results[i].channel));
      others[c].band = out.results[i].ringdown.band;
      have[c] = 1;
    }
    for (size_t c = 0; c < all.size(); ++c) {
      if (have[c]) continue;
      others[c].band =
          band_signal(spectra[c], all[c]->quantity ? *all[c]->quantity : *options.quantity, band,
                      options.ringdown, cache);
    }
    // Reference: the channel with the widest kept span (ties: the first).
    size_t ref = first;
    for (size_t i = first; i < out.results.size(); ++i) {
      const auto span = [](const Ringdown& r) {
        return r.summary.status == RingdownStatus::kOk ? r.summary.amplitude_decades : -1.0;
      };
      if (span(out.results[i].ringdown) > span(out.results[ref].ringdown)) ref = i;
    }
    out.reference.push_back(out.results[ref].channel);
    const Ringdown& rr = out.results[ref].ringdown;
    if (rr.summary.status == RingdownStatus::kOk) {
      const size_t rc = index_of(record.find(out.results[ref].channel));
      for (size_t i = first; i < out.results.size(); ++i) {
        const size_t c = index_of(record.find(out.results[i].channel));
        out.results[i].complex_amplitude =
            projection(others[rc].band, spectra[rc], others[c].band, spectra[c],
                       rr.summary.span_start_s, rr.summary.span_end_s)
                .amplitude;
      }
    }
    // A channel near a node: some coherent channel of the file sees the mode over
    // this channel's own span more than 1 / min_share times as strongly.
    for (size_t i = first; i < out.results.size(); ++i) {
      ChannelBand& r = out.results[i];
      if (r.ringdown.summary.status != RingdownStatus::kOk || options.min_share == 0) continue;
      const size_t c = index_of(record.find(r.channel));
      double share = 1.0;
      for (size_t d = 0; d < all.size(); ++d) {
        if (d == c) continue;
        const Projection p =
            projection(others[c].band, spectra[c], others[d].band, spectra[d],
                       r.ringdown.summary.span_start_s, r.ringdown.summary.span_end_s);
        if (p.coherence >= kMinCoherence && std::abs(p.ratio) > 0) {
          share = std::min(share, 1.0 / std::abs(p.ratio));
        }
      }
      if (!(share < options.min_share)) continue;
      r.ringdown.backbone = Backbone{};
      r.ringdown.summary.status = RingdownStatus::kNoSpan;
      r.ringdown.summary.message = fmt::format(
          "sees this mode at {:.1f} % of the strongest channel's amplitude (below --min-share "
          "{:g} %): near a node the envelope follows the mode shape's change with amplitude, "
          "so no backbone is given (the shape entry is kept)",
          100 * share, 100 * options.min_share);
    }
  }
  return out;
}

}  // namespace jointlab::modal
