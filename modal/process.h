// Processing of one test record: every selected channel in every band.
//
// Bands come from the user or, with `modes = N`, from the N most prominent
// peaks of the channels' summed (peak-normalised) amplitude spectra that give
// modal data: each band reaches half-way to the neighbouring chosen peaks and at
// most 15 % of its peak frequency on either side; a peak whose band gives no
// backbone or no linear values (a harmonic, noise) is left out with its reason
// and the next one taken. Per band the linear (low-amplitude) modal data are
// the reference channel's low-amplitude frequency and damping and, for every
// channel, a complex amplitude: the least-squares projection of the channel's
// displacement analytic signal onto the reference channel's over the
// reference's kept span, scaled to the reference's envelope at the span's
// start (so the reference channel's complex amplitude is real and positive).
//
// A channel that sees a band's mode at less than `min_share` of the strongest
// channel's complex amplitude gives no backbone, only its shape entry: near a
// node its envelope follows the change of the mode shape with amplitude (and
// whatever else leaks into the band) as much as the mode's own decay, so its
// damping would be confidently wrong. Its summary says so.
#pragma once

#include <complex>
#include <optional>
#include <string>
#include <vector>

#include "jointlab/core/units.h"
#include "jointlab/data/record.h"
#include "jointlab/modal/ringdown.h"

namespace jointlab::modal {

/// What to process in a record.
struct ProcessOptions {
  std::vector<signal::Band> bands;  ///< explicit bands (used when modes == 0)
  int modes = 0;                    ///< number of spectral peaks to use as bands
  /// Channels to process (empty: all non-force); a channel named twice is processed once.
  std::vector<std::string> channels;
  std::optional<Quantity> quantity;  ///< quantity of channels without a unit
  RingdownOptions ringdown;          ///< backbone extraction settings
  PrepareOptions prepare;            ///< onset trimming and continuation
  double min_share = 0.1;  ///< weakest channel share of a mode that still gives a backbone
  /// Workers for the record's channels (0: every core); at most 2e7 / the samples of the
  /// record continued for its narrowest band, as each holds one channel's continued record
  /// and spectra. The results do not depend on it.
  unsigned threads = 1;
  /// Empty if usable, else what is wrong.
  std::string check() const;
};

/// One channel in one band.
struct ChannelBand {
  std::string channel;                     ///< channel name
  Quantity measured;                       ///< what the channel measures
  int band_index = 0;                      ///< 1-based band number
  Ringdown ringdown;                       ///< backbone and summary (its band signal left empty)
  std::complex<double> complex_amplitude;  ///< operating-shape entry [m]
};

/// A spectral peak that `modes = N` examined and left out, and why.
struct LeftOutPeak {
  double frequency_hz = 0;  ///< the peak [Hz]
  signal::Band band;        ///< the band it was given
  std::string reason;       ///< why that band gave no modal data
};

/// Why `peak` was left out, as the command and the Python module say it: "the spectral peak at
/// 100.00 Hz is left out (band 92.5:107.5 Hz gives no modal data): <reason>".
std::string left_out_line(const LeftOutPeak& peak);

/// Everything found in one record.
struct RecordResult {
  std::string source;                  ///< file processed
  std::vector<signal::Band> bands;     ///< bands used (1-based in outputs)
  std::vector<std::string> reference;  ///< per band: reference channel for the shape
  std::vector<ChannelBand> results;    ///< band-major, then channel
  std::vector<LeftOutPeak> left_out;   ///< with `modes`: peaks left out, ascending frequency
  /// With `modes = N`: why fewer than N bands were found ("" when N were).
  std::string shortfall;
};

/// Why band `band` (1-based) of `record` gave a backbone at no channel: its reference
/// channel's name and reason ("acc1: no span of ..."); "" when some channel gave one.
std::string band_without_backbone(const RecordResult& record, int band);

/// Why band `band` (1-based) of `record` gives no modal data: band_without_backbone(), or
/// its reference channel's backbone has no linear values ("acc1: no linear values: ...");
/// "" when the reference channel gives a backbone with linear values.
std::string band_refusal(const RecordResult& record, int band);

/// Frequencies [Hz] of the `count` most prominent peaks of the channels' summed
/// (peak-normalised) amplitude spectra, most prominent first: between 2 Hz and 95 % of the
/// Nyquist frequency, peaks closer than 1 Hz (or 3 bins) counted as one.
std::vector<double> peak_frequencies(const data::Record& record,
                                     const std::vector<const data::Channel*>& channels, int count,
                                     signal::FftCache& cache);

/// Bands around peaks given in ascending frequency: each reaches half-way to its
/// neighbours and at most `reach` (per peak; default 15 %) of its frequency either side, and
/// stays below 99 % of fs / 2.
std::vector<signal::Band> bands_around(const std::vector<double>& peaks_hz, double fs,
                                       const std::vector<double>& reach = {});

/// Chooses `count` bands around the most prominent spectral peaks of the channels
/// (bands_around() the peak_frequencies()), whatever each band holds.
std::vector<signal::Band> bands_from_peaks(const data::Record& record,
                                           const std::vector<const data::Channel*>& channels,
                                           int count, signal::FftCache& cache);

/// Why channel `name` of `record` cannot be processed as a response (it is missing, or a
/// force), or "" when it can.
std::string not_a_response(const data::Record& record, const std::string& name);

/// Processes a record; throws InputError for unknown channels, bands outside (0, fs/2), or a
/// requested channel without a unit when options.quantity is not given. With `modes = N`
/// the bands are those of the N most prominent spectral peaks that give a backbone with
/// linear values (the others are listed in `left_out`; fewer than N found: `shortfall`;
/// none: InputError).
RecordResult process_record(const data::Record& record, const ProcessOptions& options,
                            signal::FftCache& cache);

}  // namespace jointlab::modal
