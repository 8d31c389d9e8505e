#include "jointlab/modal/process.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <complex>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <numeric>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/parallel.h"
#include "jointlab/core/text.h"
#include "jointlab/signal/spectrum.h"

namespace jointlab::modal {

namespace {

// Below this coherence another channel's band signal is not the same mode (a
// corrupted sample, another source) and does not count in the nodal test.
constexpr double kMinCoherence = 0.5;

// Most samples a record's channel may hold (5e7 peak at about 1.1 GB), and most its continued
// record may take: the continuations at its ends add at most a fifth.
constexpr double kMaxSamples = 5e7;
constexpr double kMaxContinued = 1.2 * kMaxSamples;

// What the shape and the nodal test need of one channel in one band: its band signal and
// the time base and scale of the spectrum it came from. Channels are analysed one at a
// time and only these (on the band's coarse grid) are kept, never every channel's spectrum.
struct BandOfChannel {
  signal::BandSignal z;    // displacement analytic signal times scale, from sample `first`
  double t0 = 0;           // time of the analysed record's first sample [s]
  double scale = 1;        // ChannelSpectrum::scale
  Eigen::Index first = 0;  // coarse-grid index of z.baseband(0)
  // Time until which the band signal carries the channel's clipped stretch [s] (its last
  // pinned sample, ChannelSpectrum::clipping, and the band filter's settling time); -inf:
  // the channel is not clipped.
  double clipped_until = -std::numeric_limits<double>::infinity();
  double record_end = 0;  // time of the record's last sample [s]
};

// Keeps only the samples of c's band signal over the record's time span [begin, end] (and
// two on either side for the cubic): spans are measured data, never the continuations,
// which for a short record are far longer than the data.
void keep_record_span(BandOfChannel& c, double begin, double end) {
  const Eigen::Index n = c.z.baseband.size();
  if (n < 4) return;
  const auto j0 = std::clamp<Eigen::Index>(
      static_cast<Eigen::Index>(std::floor((begin - c.t0) / c.z.dt)) - 2, 0, n - 4);
  const auto j1 = std::clamp<Eigen::Index>(
      static_cast<Eigen::Index>(std::ceil((end - c.t0) / c.z.dt)) + 2, j0 + 3, n - 1);
  c.z.baseband = Eigen::VectorXcd(c.z.baseband.segment(j0, j1 - j0 + 1));
  c.first = j0;
}

// Where the cubic (Lagrange) interpolation of a channel's band signal at absolute time t
// reads it: from sample j on, with weights w (of j to j + 3).
struct Node {
  Eigen::Index j = -1;  // -1: the band signal has fewer than 4 samples
  double w[4] = {};
  bool inside = false;  // j not moved by the band signal's ends (t has a node on either side)
};

// The node of `channel`'s band signal at absolute time t.
Node node_at(const BandOfChannel& channel, double t) {
  const signal::BandSignal& z = channel.z;
  const double x = (t - channel.t0) / z.dt - static_cast<double>(channel.first);
  const Eigen::Index n = z.baseband.size();
  if (n < 4) return {};
  Node node;
  const auto j = static_cast<Eigen::Index>(std::floor(x)) - 1;
  node.j = std::clamp<Eigen::Index>(j, 0, n - 4);
  node.inside = j == node.j;
  const double u = x - static_cast<double>(node.j);
  // The Lagrange weights of nodes 0 to 3, their denominators -6, 2, -2, 6 taken together.
  const double a = u, b = u - 1, c = u - 2, d = u - 3;
  node.w[0] = -(b * c * d) / 6;
  node.w[1] = a * c * d / 2;
  node.w[2] = -(a * b * d) / 2;
  node.w[3] = a * b * c / 6;
  return node;
}

// The interpolation at `node` moved on by `steps` samples of the band signal.
std::complex<double> value_at(const BandOfChannel& channel, const Node& node,
                              Eigen::Index steps = 0) {
  if (node.j < 0) return 0.0;
  const std::complex<double>* z = channel.z.baseband.data() + node.j + steps;
  std::complex<double> v = 0.0;
  for (int k = 0; k < 4; ++k) v += node.w[k] * z[k];
  return v;
}

// The baseband of a channel's band signal at absolute time t, by cubic (Lagrange)
// interpolation: the coarse grid samples the baseband at 8 times its width, where the
// cubic's error is below 1e-3.
std::complex<double> baseband_value(const BandOfChannel& channel, double t) {
  return value_at(channel, node_at(channel, t));
}

// The carrier's phase of a channel's band signal at absolute time t.
double carrier_phase(const BandOfChannel& channel, double t) {
  return 2 * std::numbers::pi * channel.z.carrier_hz * (t - channel.t0);
}

// Channel b's band signal against channel a's over [t1, t2] (a's coarse grid):
// ratio = a^H b / a^H a, coherence = |a^H b|^2 / (|a|^2 |b|^2), and b's complex
// amplitude scaled to a's envelope at t1; in the record's units (band signals carry their
// channel's ChannelSpectrum::scale).
struct Projection {
  std::complex<double> ratio = 0.0;
  double coherence = 0.0;
  std::complex<double> amplitude = 0.0;
};

Projection projection(const BandOfChannel& ca, const BandOfChannel& cb, double t1, double t2) {
  Projection p;
  // A clipped stretch is the recorder's range, not the mode's shape: the ratio is taken after
  // the band signals have settled from it (BandOfChannel::clipped_until), over a span as long
  // as [t1, t2] as far as the record goes; the amplitude is still scaled to a's envelope at t1.
  const double span = t2 - t1;
  const double from = std::max({t1, ca.clipped_until, cb.clipped_until});
  const double to = from == t1 ? t2 : std::min(from + span, std::min(ca.record_end, cb.record_end));
  std::complex<double> ab = 0.0;
  double aa = 0, bb = 0;
  // a = a_base e^{i phi_a}, b = b_base e^{i phi_b}: |a| and |b| need no carrier, and
  // conj(a) b only the difference of the carriers' phases, constant when the carriers are
  // equal (two sines per point were a twentieth of process's time).
  const bool same_carrier = ca.z.carrier_hz == cb.z.carrier_hz;
  const std::complex<double> constant_turn =
      std::polar(1.0, carrier_phase(cb, from) - carrier_phase(ca, from));
  // On one grid spacing, every point of the span keeps the first one's interpolation
  // weights, the nodes one sample on per point (the weights at every point were a twentieth
  // of process's time); interpolated anew where a step would leave the band signal.
  const Node na = node_at(ca, from), nb = node_at(cb, from);
  const Eigen::Index last_a = ca.z.baseband.size() - 4, last_b = cb.z.baseband.size() - 4;
  const bool one_grid = ca.z.dt == cb.z.dt;
  Eigen::Index i = 0;
  for (double t = from; t <= to + 1e-12; t += ca.z.dt, ++i) {
    const bool inside =
        one_grid && na.inside && nb.inside && na.j + i <= last_a && nb.j + i <= last_b;
    const std::complex<double> a = inside ? value_at(ca, na, i) : baseband_value(ca, t);
    const std::complex<double> b = inside ? value_at(cb, nb, i) : baseband_value(cb, t);
    const std::complex<double> turn =
        same_carrier ? constant_turn : std::polar(1.0, carrier_phase(cb, t) - carrier_phase(ca, t));
    ab += std::conj(a) * b * turn;
    aa += std::norm(a);
    bb += std::norm(b);
  }
  if (!(aa > 0) || !(bb > 0) || !std::isfinite(aa) || !std::isfinite(bb)) return p;
  p.ratio = ab / aa;
  const double c = std::abs(ab) / std::sqrt(aa) / std::sqrt(bb);  // aa * bb may overflow
  p.coherence = c * c;
  p.amplitude = p.ratio * std::abs(baseband_value(ca, t1)) / cb.scale;
  p.ratio *= ca.scale / cb.scale;
  if (!std::isfinite(std::abs(p.amplitude)) || !std::isfinite(std::abs(p.ratio))) return {};
  return p;
}

// Why band b cannot be processed in this record, or "": its continuation would not fit in
// memory, or its filter cannot settle within the record.
std::string band_unprocessable(const data::Record& record, const signal::Band& b,
                               const ProcessOptions& options) {
  const double duration = static_cast<double>(record.size() - 1) / record.fs;
  const auto samples_for = [&](double extend_s) { return (duration + 2 * extend_s) * record.fs; };
  const double settle = band_settling_s(b, options.ringdown.taper);
  const double samples =
      samples_for(prepare_for({b}, options.ringdown.taper, options.prepare).extend_s);
  if (settle <= duration && !(samples <= kMaxContinued)) {
    return fmt::format(
        "band {:g}:{:g} Hz: continuing this record's {} samples at its ends for the band's filter "
        "would take {:.4g} samples (at most {:.4g}); give a wider band or a shorter record",
        b.lo, b.hi, record.size(), samples, kMaxContinued);
  }
  if (!(settle <= duration)) {
    return fmt::format(
        "band {:g}:{:g} Hz is too narrow for this {:.3g} s record: its filter takes {:.3g} s to "
        "settle; give a band at least {:.3g} Hz wide",
        b.lo, b.hi, duration, settle, 3.0 / (options.ringdown.taper * duration));
  }
  return {};
}

// Whether a channel's name says it is the hammer's force: "Force", "hammer", "Impact 1",
// "load_cell" (case-blind).
bool named_as_force(const std::string& name) {
  const std::string n = lower(name);
  for (const char* word :
       {"force", "hammer", "impact", "impulse", "load cell", "load_cell", "loadcell"}) {
    if (n.find(word) != std::string::npos) return true;
  }
  return false;
}

// How to mark channel `name` as the hammer's force (one phrase for both messages that give it).
std::string force_unit_hint(const std::string& name) {
  return fmt::format(
      "if it is the hammer's force, give its unit in the header ('{} [N]'), which leaves it out "
      "of the responses",
      name);
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
  if (static_cast<double>(record.size()) > kMaxSamples) {
    throw InputError(where(record.source, 0,
                           fmt::format("{} samples a channel: at most {:.0f} can be analysed",
                                       record.size(), kMaxSamples)));
  }
  if (!(samples_for(options.prepare.extend_s) <= kMaxContinued)) {
    throw InputError(where(
        record.source, 0,
        fmt::format("sample rate {:.3g} Hz: continuing this record's {} samples at its ends would "
                    "take {:.4g} samples (at most {:.4g}); check the file's time column or fs",
                    record.fs, record.size(), samples_for(options.prepare.extend_s),
                    kMaxContinued)));
  }
  for (const signal::Band& b : bands) {
    if (std::string why = band_unprocessable(record, b, options); !why.empty())
      throw InputError(where(record.source, 0, why));
  }
  // A channel without a unit measures what the user says, or nothing can be assumed. One
  // named as the hammer's force ("Force") is told first how to mark it a force: the response
  // units alone ('Force [m/s^2]') would have it processed as a response.
  for (const data::Channel* c : chans) {
    if (c->quantity || options.quantity) continue;
    const std::string force =
        named_as_force(c->name) ? force_unit_hint(c->name) + "; if it is a response, " : "";
    throw InputError(where(
        record.source, 0,
        fmt::format("channel '{}' has no unit and no --quantity was given: {}give its unit in "
                    "the header (e.g. '{} [m/s^2]', '{} [m/s]') or --quantity "
                    "acceleration|velocity|displacement",
                    c->name, force, c->name, c->name)));
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

std::vector<double> peak_frequencies(const data::Record& record,
                                     const std::vector<const data::Channel*>& channels, int count,
                                     signal::FftCache& cache) {
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
  std::vector<double> peaks;
  for (const Eigen::Index k : signal::prominent_peaks(searched, count, min_distance))
    peaks.push_back(freq(k));
  return peaks;
}

std::vector<signal::Band> bands_around(const std::vector<double>& peaks_hz, double fs,
                                       const std::vector<double>& reach) {
  std::vector<signal::Band> bands;
  for (size_t i = 0; i < peaks_hz.size(); ++i) {
    const double f = peaks_hz[i];
    const double r = i < reach.size() ? reach[i] : 0.15;
    double lo = (1 - r) * f, hi = (1 + r) * f;
    if (i > 0) lo = std::max(lo, 0.5 * (f + peaks_hz[i - 1]));
    if (i + 1 < peaks_hz.size()) hi = std::min(hi, 0.5 * (f + peaks_hz[i + 1]));
    hi = std::min(hi, 0.5 * fs * 0.99);
    bands.push_back({lo, hi});
  }
  return bands;
}

std::vector<signal::Band> bands_from_peaks(const data::Record& record,
                                           const std::vector<const data::Channel*>& channels,
                                           int count, signal::FftCache& cache) {
  std::vector<double> peaks = peak_frequencies(record, channels, count, cache);
  std::sort(peaks.begin(), peaks.end());
  return bands_around(peaks, record.fs);
}

std::string not_a_response(const data::Record& record, const std::string& name) {
  const data::Channel* c = record.find(name);
  if (!c) {
    std::string have;
    for (const data::Channel& k : record.channels) have += (have.empty() ? "" : ", ") + k.name;
    return fmt::format("no channel '{}' (channels: {})", name, have);
  }
  if (c->quantity == Quantity::kForce)
    return fmt::format("channel '{}' is a force, not a response", name);
  return "";
}

namespace {

// The requested response channels (default: every channel that is not a force).
std::vector<const data::Channel*> requested_channels(const data::Record& record,
                                                     const ProcessOptions& options) {
  std::vector<const data::Channel*> chans;
  if (options.channels.empty()) {
    for (const data::Channel& c : record.channels) {
      if (c.quantity != Quantity::kForce) chans.push_back(&c);
    }
  } else {
    std::unordered_set<const data::Channel*> given;  // a channel named twice is processed once
    for (const std::string& name : options.channels) {
      if (const std::string why = not_a_response(record, name); !why.empty())
        throw InputError(where(record.source, 0, why));
      const data::Channel* c = record.find(name);
      if (given.insert(c).second) chans.push_back(c);
    }
  }
  if (chans.empty()) throw InputError(where(record.source, 0, "no response channel to process"));
  if (record.size() < 64) {
    throw InputError(where(record.source, 0,
                           fmt::format("{} samples: too short for a ring-down", record.size())));
  }
  return chans;
}

// The typed bands, each below Nyquist.
void check_typed_bands(const data::Record& record, const std::vector<signal::Band>& bands) {
  for (const signal::Band& b : bands) {
    if (b.hi > record.fs / 2) {
      throw InputError(where(record.source, 0,
                             fmt::format("band {}:{} Hz reaches past the Nyquist frequency {} Hz",
                                         b.lo, b.hi, record.fs / 2)));
    }
  }
}

// Every response channel the nodal test compares with (requested or not), its impact, and
// which requests each answers (looked up once: records may hold 1e5 channels).
struct ChannelSet {
  const data::Record& record;
  const ProcessOptions& options;
  std::vector<const data::Channel*> all;
  std::vector<Eigen::Index> impact;           ///< impact sample of each of `all`
  std::vector<Clipping> clipping;             ///< clipped samples of each of `all`
  std::vector<size_t> index_of;               ///< position in `all` of each request
  std::vector<std::vector<size_t>> requests;  ///< requests each of `all` answers

  ChannelSet(const data::Record& r, const ProcessOptions& o,
             const std::vector<const data::Channel*>& chans)
      : record(r), options(o) {
    for (const data::Channel& c : record.channels) {
      // Channels whose quantity is unknown cannot be compared (requested ones have one).
      if (c.quantity != Quantity::kForce && (c.quantity || options.quantity)) all.push_back(&c);
    }
    impact.resize(all.size());
    clipping.resize(all.size());
    for (size_t c = 0; c < all.size(); ++c) {
      impact[c] = impact_index(all[c]->samples);
      clipping[c] = find_clipping(all[c]->samples);
    }
    std::unordered_map<const data::Channel*, size_t> position;
    for (size_t c = 0; c < all.size(); ++c) position.emplace(all[c], c);
    index_of.resize(chans.size());
    requests.resize(all.size());
    for (size_t i = 0; i < chans.size(); ++i) {
      index_of[i] = position.at(chans[i]);
      requests[index_of[i]].push_back(i);
    }
  }
  Quantity measured_by(size_t c) const {
    return all[c]->quantity ? *all[c]->quantity : *options.quantity;
  }
  ChannelSpectrum spectrum(size_t c, const PrepareOptions& prepare, signal::FftCache& cache) const {
    return channel_spectrum(all[c]->samples, record.fs, record.t0, prepare, cache, impact[c],
                            &clipping[c]);
  }
  BandOfChannel band_of(const ChannelSpectrum& spectrum, signal::BandSignal z,
                        const signal::Band& band) const {
    const double record_end = record.t0 + static_cast<double>(record.size() - 1) / record.fs;
    BandOfChannel k{std::move(z), spectrum.t0, spectrum.scale, 0};
    if (spectrum.clipping.found())
      k.clipped_until = spectrum.clipped_until_s + band_settling_s(band, options.ringdown.taper);
    k.record_end = record_end;
    keep_record_span(k, record.t0, record_end);
    return k;
  }
};

// The FFT workspaces of a record's channel workers: the caller's for the first worker, its
// helpers' (kept with it, plans and all, for the next record) for the others.
class Workspaces {
 public:
  Workspaces(signal::FftCache& first, unsigned threads)
      : first_(first), threads_(std::max(1u, threads)) {
    for (unsigned w = 1; w < threads_; ++w) first_.helper(w - 1);  // made here, not in a worker
  }
  /// Runs body(i, cache) for i in [0, n), each worker with its own cache.
  template <typename Body>
  void run(size_t n, Body body) {
    std::atomic<unsigned> next{0};
    parallel_for(
        n, threads_,
        [&]() -> signal::FftCache* {
          const unsigned w = next++;
          return w == 0 ? &first_ : &first_.helper(w - 1);
        },
        [&](size_t i, signal::FftCache* cache) { body(i, *cache); });
  }

 private:
  signal::FftCache& first_;
  unsigned threads_;
};

// A group of bands' results and kept band signals, band b of the group being the record's
// band first + b: results[(first + b) * requests + i] for request i, kept[b][c] for channel c
// of the set.
struct BandResults {
  std::vector<ChannelBand>& results;
  size_t requests = 0;
  size_t first = 0;
  std::vector<std::vector<std::optional<BandOfChannel>>> kept;
  ChannelBand* of(size_t band) { return results.data() + (first + band) * requests; }
};

// Pass 1, every band of every requested channel, as independent jobs (one barrier for all
// bands: a barrier per band left a worker idle while the other finished the band's slowest
// channel): the channel's spectrum for the band (dropped when the job ends) and its
// backbones; the band signal is kept only where a backbone was found.
void extract_bands(const ChannelSet& set, const std::vector<signal::Band>& bands,
                   const std::vector<PrepareOptions>& prepare, BandResults& out,
                   Workspaces& workers) {
  const size_t channels = set.all.size();
  out.kept.assign(bands.size(), std::vector<std::optional<BandOfChannel>>(channels));
  // The costliest jobs first, so that the last ones, which a worker may run alone, are
  // short: a band's points are spaced by a few of its periods, so a band's cost grows
  // with its frequency (on the bench record a 320:410 Hz job takes about 2.8 times
  // a 48:72 Hz one).
  std::vector<size_t> order(bands.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return bands[a].lo + bands[a].hi > bands[b].lo + bands[b].hi;
  });
  // Each job writes only its band and channel's results and slot.
  workers.run(bands.size() * channels, [&](size_t job, signal::FftCache& cache) {
    const size_t b = order[job / channels], c = job % channels;
    if (set.requests[c].empty()) return;
    const ChannelSpectrum spectrum = set.spectrum(c, prepare[b], cache);
    ChannelBand* results = out.of(b);
    std::optional<BandOfChannel>& kept = out.kept[b][c];
    for (const size_t i : set.requests[c]) {
      ChannelBand& r = results[i];
      r.channel = set.all[c]->name;
      r.measured = set.measured_by(c);
      r.band_index = static_cast<int>(out.first + b) + 1;
      r.ringdown = extract_backbone(spectrum, r.measured, bands[b], set.options.ringdown, cache);
      if (r.ringdown.summary.status == RingdownStatus::kOk && !kept)
        kept = set.band_of(spectrum, std::move(r.ringdown.band), bands[b]);
      r.ringdown.band = signal::BandSignal{};
    }
  });
}

// The reference channel: the widest kept span (ties: the first).
size_t reference_channel(const ChannelBand* results, size_t n) {
  const auto span = [](const Ringdown& r) {
    return r.summary.status == RingdownStatus::kOk ? r.summary.amplitude_decades : -1.0;
  };
  size_t ref = 0;
  for (size_t i = 0; i < n; ++i)
    if (span(results[i].ringdown) > span(results[ref].ringdown)) ref = i;
  return ref;
}

// Pass 2, every response channel against the kept ones, for every band with a reference
// (`ref[band]`, or none) as independent jobs: each channel's shape entry (projected on the
// reference over its span) and, for each channel with a backbone, the largest share
// another coherent channel of the file sees of the mode over that channel's own span. A
// channel without a kept band signal is analysed again here and dropped after its
// projections, so memory holds only the channels with backbones.
// Returns each band's shares of each request (1 where not computed).
std::vector<std::vector<double>> shapes_and_shares(const ChannelSet& set,
                                                   const std::vector<signal::Band>& bands,
                                                   const std::vector<PrepareOptions>& prepare,
                                                   const std::vector<std::optional<size_t>>& ref,
                                                   BandResults& out, Workspaces& workers) {
  const size_t n = out.requests, channels = set.all.size();
  std::vector<std::vector<double>> share(bands.size(), std::vector<double>(n, 1.0));
  std::mutex share_lock;  // the smallest share wins, whichever worker finds it first
  std::vector<std::vector<size_t>> with_backbone(bands.size());
  for (size_t b = 0; b < bands.size(); ++b) {
    for (size_t i = 0; i < n; ++i)
      if (out.of(b)[i].ringdown.summary.status == RingdownStatus::kOk)
        with_backbone[b].push_back(i);
  }
  workers.run(bands.size() * channels, [&](size_t job, signal::FftCache& cache) {
    const size_t b = job / channels, d = job % channels;
    if (!ref[b]) return;  // no backbone in this band: no shapes, no nodal test
    ChannelBand* results = out.of(b);
    const std::vector<std::optional<BandOfChannel>>& kept = out.kept[b];
    const Ringdown& rr = results[*ref[b]].ringdown;
    const BandOfChannel& reference = *kept[set.index_of[*ref[b]]];
    std::optional<BandOfChannel> again;
    if (!kept[d]) {
      const ChannelSpectrum spectrum = set.spectrum(d, prepare[b], cache);
      again = set.band_of(
          spectrum,
          band_signal(spectrum, set.measured_by(d), bands[b], set.options.ringdown, cache),
          bands[b]);
    }
    const BandOfChannel& zd = kept[d] ? *kept[d] : *again;
    for (const size_t i : set.requests[d]) {
      results[i].complex_amplitude =
          projection(reference, zd, rr.summary.span_start_s, rr.summary.span_end_s).amplitude;
    }
    if (set.options.min_share == 0) return;
    for (const size_t i : with_backbone[b]) {
      const size_t c = set.index_of[i];
      if (c == d) continue;
      const RingdownSummary& rs = results[i].ringdown.summary;
      const Projection p = projection(*kept[c], zd, rs.span_start_s, rs.span_end_s);
      if (p.coherence >= kMinCoherence && std::abs(p.ratio) > 0) {
        const std::lock_guard<std::mutex> lock(share_lock);
        share[b][i] = std::min(share[b][i], 1.0 / std::abs(p.ratio));
      }
    }
  });
  return share;
}

// A channel near a node: some coherent channel of the file sees the mode over this
// channel's own span more than 1 / min_share times as strongly. Its backbone is dropped.
void drop_near_nodes(const std::vector<double>& share, double min_share, ChannelBand* results) {
  for (size_t i = 0; i < share.size(); ++i) {
    ChannelBand& r = results[i];
    if (r.ringdown.summary.status != RingdownStatus::kOk || !(share[i] < min_share)) continue;
    r.ringdown.backbone = Backbone{};
    r.ringdown.summary.status = RingdownStatus::kNoSpan;
    r.ringdown.summary.message = fmt::format(
        "sees this mode at {:.1f} % of the strongest channel's amplitude (below --min-share "
        "{:g} %): near a node the envelope follows the mode shape's change with amplitude, "
        "so no backbone is given (the shape entry is kept)",
        100 * share[i], 100 * min_share);
  }
}

}  // namespace

std::string left_out_line(const LeftOutPeak& peak) {
  return fmt::format(
      "the spectral peak at {:.2f} Hz is left out (band {:g}:{:g} Hz gives no "
      "modal data): {}",
      peak.frequency_hz, peak.band.lo, peak.band.hi, peak.reason);
}

std::string band_without_backbone(const RecordResult& record, int band) {
  const ChannelBand* reference = nullptr;
  for (const ChannelBand& r : record.results) {
    if (r.band_index != band) continue;
    if (r.ringdown.summary.status == RingdownStatus::kOk) return {};
    if (!reference || r.channel == record.reference[static_cast<size_t>(band - 1)]) reference = &r;
  }
  if (!reference) return {};
  return reference->channel + ": " + reference->ringdown.summary.message;
}

std::string band_refusal(const RecordResult& record, int band) {
  if (std::string why = band_without_backbone(record, band); !why.empty()) return why;
  for (const ChannelBand& r : record.results) {
    if (r.band_index != band || r.channel != record.reference[static_cast<size_t>(band - 1)])
      continue;
    const RingdownSummary& s = r.ringdown.summary;
    if (s.status == RingdownStatus::kOk && !s.has_linear())
      return r.channel + ": " + s.linear_reason;
  }
  return {};
}

namespace {

// Every requested channel of `record` in every band of `bands`.
RecordResult process_bands(const data::Record& record,
                           const std::vector<const data::Channel*>& chans,
                           const std::vector<signal::Band>& bands, const ProcessOptions& options,
                           signal::FftCache& cache) {
  RecordResult out;
  out.source = record.source;
  out.bands = bands;
  check_processable(record, out.bands, chans, options);
  // Every band, channel and file is processed on its own: each channel from its own
  // impact, each band with the continuation and low-pass it alone needs (bands that
  // need the same share one). The nodal test compares a channel with every response
  // channel of the file, requested or not.
  const ChannelSet set(record, options, chans);
  // Each channel worker holds a channel's continued record and spectra (about 50 bytes a
  // sample of the continued record, which a narrow band's continuation makes several times
  // the record; about 15 beside the samples above 2^22 samples, padded by pad_s): a long
  // record gets fewer workers, so that together they stay near 1 GB.
  constexpr double kWorkerSamples = 2e7;
  std::vector<PrepareOptions> prepare;  // each band's own continuation and low-pass
  for (const signal::Band& band : out.bands)
    prepare.push_back(prepare_for({band}, options.ringdown.taper, options.prepare));
  double continued = static_cast<double>(record.size());
  for (const PrepareOptions& p : prepare) {
    continued =
        std::max(continued, static_cast<double>(record.size()) + 2 * p.extend_s * record.fs);
  }
  const auto by_memory = static_cast<unsigned>(std::clamp(kWorkerSamples / continued, 1.0, 1024.0));
  Workspaces workers(cache, std::min(threads_or_cores(options.threads), by_memory));
  // Bands in groups of at most kJobsAtOnce band-channel jobs: a group's kept band signals
  // are held until its nodal test (a record of many channels goes band by band).
  constexpr size_t kJobsAtOnce = 256;
  const size_t per_group = std::max<size_t>(1, kJobsAtOnce / std::max<size_t>(1, set.all.size()));
  out.results.resize(out.bands.size() * chans.size());
  for (size_t g0 = 0; g0 < out.bands.size(); g0 += per_group) {
    const size_t g1 = std::min(out.bands.size(), g0 + per_group);
    const auto from = static_cast<std::ptrdiff_t>(g0), to = static_cast<std::ptrdiff_t>(g1);
    const std::vector<signal::Band> bands(out.bands.begin() + from, out.bands.begin() + to);
    const std::vector<PrepareOptions> group_prepare(prepare.begin() + from, prepare.begin() + to);
    BandResults group{out.results, chans.size(), g0, {}};
    extract_bands(set, bands, group_prepare, group, workers);
    std::vector<std::optional<size_t>> ref(bands.size());
    for (size_t b = 0; b < bands.size(); ++b) {
      const ChannelBand* results = group.of(b);
      const size_t r = reference_channel(results, chans.size());
      out.reference.push_back(results[r].channel);
      if (results[r].ringdown.summary.status == RingdownStatus::kOk) ref[b] = r;
    }
    const std::vector<std::vector<double>> share =
        shapes_and_shares(set, bands, group_prepare, ref, group, workers);
    for (size_t b = 0; b < bands.size(); ++b) {
      if (ref[b]) drop_near_nodes(share[b], options.min_share, group.of(b));
    }
  }
  return out;
}

// `--modes N`: the N most prominent spectral peaks that the program processes. Peaks are
// taken in order of prominence, each with a band reaching half-way to its chosen neighbours
// and at most 15 % of its frequency either side. A peak whose band cannot be processed, or
// gives a backbone at no channel, or no linear values at its reference channel (a harmonic
// of a stronger mode, whose every point is superharmonic; noise; a strong neighbour's
// leakage) is tried once more with a band reaching at most 7.5 % either side (a weak mode
// beside a stronger mode's harmonic), and then left out with its reason and the next peak
// taken, until N bands pass or the examined peaks run out. A band depends on that band
// alone, so a band whose edges did not move is not processed again.
RecordResult process_modes(const data::Record& record,
                           const std::vector<const data::Channel*>& chans,
                           const ProcessOptions& options, signal::FftCache& cache) {
  check_processable(record, {}, chans, options);
  const int wanted = options.modes;
  const std::vector<double> peaks = peak_frequencies(record, chans, 2 * wanted + 4, cache);
  std::map<std::pair<double, double>, RecordResult> done;  // one band each, by its edges
  const auto key = [](const signal::Band& b) { return std::pair{b.lo, b.hi}; };
  struct Chosen {
    double frequency_hz;
    double reach;  // the band's largest reach either side, a fraction of the frequency
  };
  std::vector<Chosen> chosen;  // ascending frequency
  std::vector<signal::Band> bands;
  std::vector<LeftOutPeak> left_out;
  size_t next = 0;
  for (;;) {
    while (static_cast<int>(chosen.size()) < wanted && next < peaks.size()) {
      const double f = peaks[next++];
      chosen.insert(std::upper_bound(chosen.begin(), chosen.end(), f,
                                     [](double g, const Chosen& c) { return g < c.frequency_hz; }),
                    Chosen{f, 0.15});
    }
    std::vector<double> freq, reach;
    for (const Chosen& c : chosen) {
      freq.push_back(c.frequency_hz);
      reach.push_back(c.reach);
    }
    bands = bands_around(freq, record.fs, reach);
    std::vector<std::string> why(chosen.size());
    for (size_t k = 0; k < chosen.size(); ++k)
      why[k] = band_unprocessable(record, bands[k], options);
    if (std::all_of(why.begin(), why.end(), [](const std::string& w) { return w.empty(); })) {
      std::vector<signal::Band> todo;
      for (const signal::Band& b : bands)
        if (!done.contains(key(b))) todo.push_back(b);
      if (!todo.empty()) {
        RecordResult r = process_bands(record, chans, todo, options, cache);
        const size_t per_band = chans.size();
        for (size_t k = 0; k < todo.size(); ++k) {
          RecordResult one;
          one.source = record.source;
          one.bands = {todo[k]};
          one.reference = {r.reference[k]};
          for (size_t i = 0; i < per_band; ++i) {
            one.results.push_back(std::move(r.results[k * per_band + i]));
            one.results.back().band_index = 1;
          }
          done.emplace(key(todo[k]), std::move(one));
        }
      }
      for (size_t k = 0; k < chosen.size(); ++k) why[k] = band_refusal(done.at(key(bands[k])), 1);
    }
    bool refused = false;
    for (size_t k = chosen.size(); k-- > 0;) {
      if (why[k].empty()) continue;
      refused = true;
      if (chosen[k].reach > 0.075) {
        chosen[k].reach = 0.075;  // once more, narrower
        continue;
      }
      left_out.push_back({chosen[k].frequency_hz, bands[k], why[k]});
      chosen.erase(chosen.begin() + static_cast<std::ptrdiff_t>(k));
    }
    if (!refused) break;
  }
  std::sort(left_out.begin(), left_out.end(), [](const LeftOutPeak& a, const LeftOutPeak& b) {
    return a.frequency_hz < b.frequency_hz;
  });
  std::string left;
  for (const LeftOutPeak& p : left_out)
    left += fmt::format("{}{:.2f} Hz: {}", left.empty() ? "" : "; ", p.frequency_hz, p.reason);
  if (chosen.empty()) {
    throw InputError(
        where(record.source, 0,
              peaks.empty()
                  ? fmt::format("--modes {}: no spectral peak found", wanted)
                  : fmt::format("--modes {}: none of the {} most prominent spectral peaks gives "
                                "a backbone: {}; type the bands (--band LO:HI)",
                                wanted, peaks.size(), left)));
  }
  RecordResult out;
  out.source = record.source;
  out.bands = bands;
  out.left_out = std::move(left_out);
  for (size_t k = 0; k < bands.size(); ++k) {
    const RecordResult& one = done.at(key(bands[k]));
    out.reference.push_back(one.reference[0]);
    for (ChannelBand r : one.results) {
      r.band_index = static_cast<int>(k) + 1;
      out.results.push_back(std::move(r));
    }
  }
  if (static_cast<int>(chosen.size()) < wanted) {
    std::string kept;
    for (const Chosen& c : chosen)
      kept += fmt::format("{}{:.2f} Hz", kept.empty() ? "" : ", ", c.frequency_hz);
    out.shortfall = fmt::format(
        fmt::runtime(left.empty()
                         ? "--modes {0}: only {1} spectral peak(s) stand out ({3}), each giving a "
                           "backbone"
                         : "--modes {0}: only {1} of the {2} most prominent spectral peaks give a "
                           "backbone ({3}); left out: {4}"),
        wanted, chosen.size(), peaks.size(), kept, left);
  }
  return out;
}

// A hammer's force channel exported without a unit ("Force" beside "Acc1") is read as the
// --quantity's response and gives no ring-down: its refusals say how to mark it a force,
// where they would otherwise leave a newcomer reading the hammer's noise floor.
void name_unitless_forces(const data::Record& record, RecordResult& out) {
  for (ChannelBand& r : out.results) {
    const data::Channel* c = record.find(r.channel);
    if (r.ringdown.summary.status == RingdownStatus::kOk || !c || !c->unit.empty() ||
        !named_as_force(r.channel))
      continue;
    r.ringdown.summary.message +=
        fmt::format("; the channel '{}' has no unit and was read as {}: {}", r.channel,
                    quantity_name(r.measured), force_unit_hint(r.channel));
  }
}

}  // namespace

RecordResult process_record(const data::Record& record, const ProcessOptions& options,
                            signal::FftCache& cache) {
  const std::vector<const data::Channel*> chans = requested_channels(record, options);
  RecordResult out;
  if (options.modes > 0) {
    out = process_modes(record, chans, options, cache);
  } else {
    check_typed_bands(record, options.bands);
    out = process_bands(record, chans, options.bands, options, cache);
  }
  name_unitless_forces(record, out);
  return out;
}

}  // namespace jointlab::modal
