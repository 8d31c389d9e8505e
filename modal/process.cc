#include "jointlab/modal/process.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/signal/spectrum.h"

namespace jointlab::modal {

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

  // One impact instant for all channels keeps their coarse grids aligned.
  Eigen::Index impact = record.size();
  for (const data::Channel* c : chans) impact = std::min(impact, impact_index(c->samples));
  // Continue only what the bands need (content and length).
  const double taper = options.ringdown.taper;
  const PrepareOptions prepare = prepare_for(out.bands, taper, options.prepare);
  std::vector<ChannelSpectrum> spectra;
  std::vector<Quantity> measured;
  for (const data::Channel* c : chans) {
    spectra.push_back(channel_spectrum(c->samples, record.fs, record.t0, prepare, cache, impact));
    measured.push_back(c->quantity.value_or(options.quantity));
  }
  for (size_t b = 0; b < out.bands.size(); ++b) {
    // A heavily damped higher mode can make the shared continuation blow up
    // within a lower band's settling time: that band then gets its own, low-passed
    // just above it (every channel alike, so their coarse grids stay aligned).
    const signal::Band& band = out.bands[b];
    const double settle = band_settling_s(band, taper);
    std::vector<ChannelSpectrum> own;
    const bool short_continuation =
        std::any_of(spectra.begin(), spectra.end(), [settle](const ChannelSpectrum& s) {
          return s.continued_begin_s < settle || s.continued_end_s < settle;
        });
    const double own_lowpass_hz = prepare_for({band}, taper).lowpass_hz;
    if (short_continuation && options.prepare.lowpass_hz == 0 &&
        own_lowpass_hz < 0.99 * prepare.lowpass_hz) {
      PrepareOptions narrow = prepare;
      narrow.lowpass_hz = own_lowpass_hz;
      for (const data::Channel* c : chans) {
        own.push_back(channel_spectrum(c->samples, record.fs, record.t0, narrow, cache, impact));
      }
    }
    const std::vector<ChannelSpectrum>& used = own.empty() ? spectra : own;
    const size_t first = out.results.size();
    for (size_t c = 0; c < chans.size(); ++c) {
      ChannelBand r;
      r.channel = chans[c]->name;
      r.measured = measured[c];
      r.band_index = static_cast<int>(b) + 1;
      r.ringdown = extract_backbone(used[c], measured[c], band, options.ringdown, cache);
      out.results.push_back(std::move(r));
    }
    // Reference: the channel with the widest kept span (ties: the largest envelope).
    size_t ref = first;
    for (size_t i = first; i < out.results.size(); ++i) {
      const auto& s = out.results[i].ringdown;
      const auto& best = out.results[ref].ringdown;
      const double span =
          s.summary.status == RingdownStatus::kOk ? s.summary.amplitude_decades : -1;
      const double best_span =
          best.summary.status == RingdownStatus::kOk ? best.summary.amplitude_decades : -1;
      if (span > best_span) ref = i;
    }
    out.reference.push_back(out.results[ref].channel);
    const Ringdown& rr = out.results[ref].ringdown;
    if (rr.summary.status != RingdownStatus::kOk) continue;
    // Complex amplitudes over the reference's kept span (same coarse grid for all channels).
    const double dt = rr.band.dt;
    const double t_first = used[0].t0;
    const auto j0 = static_cast<Eigen::Index>(std::ceil((rr.summary.span_start_s - t_first) / dt));
    const auto j1 = static_cast<Eigen::Index>(std::floor((rr.summary.span_end_s - t_first) / dt));
    if (j1 <= j0) continue;
    const Eigen::VectorXcd u = rr.band.baseband.segment(j0, j1 - j0 + 1);
    const std::complex<double> u0 = u(0);
    const double uu = u.squaredNorm();
    for (size_t i = first; i < out.results.size(); ++i) {
      const Eigen::VectorXcd& zc = out.results[i].ringdown.band.baseband;
      if (zc.size() < j1 + 1) continue;
      const std::complex<double> proj = u.dot(zc.segment(j0, j1 - j0 + 1)) / uu;  // u^H z / u^H u
      out.results[i].complex_amplitude = proj * std::abs(u0);
    }
    double strongest = 0;
    for (size_t i = first; i < out.results.size(); ++i) {
      strongest = std::max(strongest, std::abs(out.results[i].complex_amplitude));
    }
    for (size_t i = first; i < out.results.size(); ++i) {
      ChannelBand& r = out.results[i];
      const double share = std::abs(r.complex_amplitude) / strongest;
      if (i == ref || r.ringdown.summary.status != RingdownStatus::kOk ||
          !(share < options.min_share)) {
        continue;
      }
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
