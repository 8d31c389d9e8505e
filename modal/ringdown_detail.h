// What the steps of a band's ring-down extraction share across their files (internal to
// modal/ringdown*.cc): a local estimate of the envelope's decay rate sigma and the phase's rate
// omega_d (ln A + i theta fitted over a window), the band signal's envelope and phase, the set-up
// of one band, and the beat of a second mode, ln(1 + c e^{i dw t}) on ln A + i theta, that
// ringdown_beat.cc finds and extract_backbone adds to the points' uncertainty, and the band
// that follows the mode past a typed edge (ringdown_follow.cc), and an energy exchange with a
// mode in internal resonance (ringdown_exchange.cc).
#pragma once

#include <cstddef>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "jointlab/modal/ringdown.h"
#include "jointlab/signal/band_analytic.h"

namespace jointlab::modal::ringdown_detail {

/// 2 pi.
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// One local estimate of the envelope's decay and the phase's rate.
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
  double centre = 0;       // window centre [s from record start]
  // Hilbert: the window the next point's search starts from (hilbert_point) [s].
  double next_search = 0;
};

/// An estimate's local window on a grid of step dt and `grid` samples: its half width, the
/// estimate's place in it (-1 at its start to 1 at its end), the stride that samples it about
/// 48 times, and the samples [j0, j1] it covers.
struct WindowOnGrid {
  double half = 0, offset = 0;
  Eigen::Index stride = 1, j0 = 0, j1 = 0;
};

/// The window of estimate `e` on a grid of step dt [s] and `grid` samples.
WindowOnGrid window_on_grid(const Estimate& e, double dt, Eigen::Index grid);

/// The q-quantile of v (its element of rank floor(q n), 0 for none).
double quantile(std::vector<double> v, double q);

/// Envelope, its logarithm and the unwrapped phase (carrier restored) of a band
/// signal z(t_j) = baseband_j exp(2 pi i carrier t_j).
struct EnvelopePhase {
  Eigen::VectorXd amp, log_amp, theta;
};

/// What the steps of one band's extraction share.
struct BandSetting {
  BandSetting(const ChannelSpectrum& c, const signal::Band& b, const RingdownOptions& o)
      : channel(c), band(b), options(o) {}
  const ChannelSpectrum& channel;
  const signal::Band& band;
  const RingdownOptions& options;
  double dt = 0;           // coarse grid step [s]
  double begin = 0;        // first measured sample used [s from channel.t0]
  double start = 0;        // first usable time [s from channel.t0]
  double stop = 0;         // last usable time [s from channel.t0]
  double edge = 0;         // band edge width [Hz]
  double f_guess = 0;      // carrier frequency from the phase [Hz]
  double period = 0;       // 1 / f_guess [s]
  double w_min = 0;        // shortest fit window [s]
  double correlation = 0;  // coarse samples per independent noise sample
  double noise_bandwidth_hz = 0;
};

/// Hilbert estimate at `at` [s] from ln A and theta on the grid t_j = j dt, fitted over a
/// window of length `window` centred at `centre`, its noise `noise` (ringdown.cc).
Estimate estimate_hilbert(const Eigen::VectorXd& log_amp, const Eigen::VectorXd& theta, double dt,
                          double at, double centre, double window, double correlation, double noise,
                          int degree);

/// The envelope, ln A and unwrapped phase of a band's baseband signal (carrier restored).
EnvelopePhase envelope_phase(const Eigen::VectorXcd& baseband, double carrier_hz, double dt);

/// The set-up of one band read from its signal `bs`: grid, usable span, windows.
BandSetting band_setting(const ChannelSpectrum& channel, const signal::Band& band,
                         const RingdownOptions& options, const signal::BandSignal& bs);

/// The band's noise floor (RMS of the complex noise) from fits over ln A and theta.
double noise_floor(const EnvelopePhase& ep, const BandSetting& s);

/// The highest local maximum of the measured spectrum over bins [k0, k1], or -1.
Eigen::Index strongest_peak(const ChannelSpectrum& channel, Eigen::Index k0, Eigen::Index k1);

/// Whether an estimate is usable: finite, decaying, above snr_min times the noise floor.
bool usable(const Estimate& e, double noise, double snr_min);

/// Full half-power width [Hz] of the measured spectrum's peak nearest `fp` [Hz].
double half_power_width(const ChannelSpectrum& channel, double fp, signal::FftCache& cache);

/// The narrowest band a mode is read well through, in half-power widths of the mode. Measured
/// on 80 Hz modes of 0.3-3 % damping: narrower bands mostly gave no span or under one decade,
/// bands of 12 half-power widths two (ringdown_test.cc, RingdownAdvice).
inline constexpr double kBandWidths = 12.0;

/// Spectral peaks in a band other than its strongest (band_peaks): frequencies [Hz] and their
/// heights over the strongest's.
struct BandPeaks {
  double main_hz = 0;
  std::vector<std::pair<double, double>> others;
};

/// The strongest spectral peak in `band` and up to `count` others (ringdown_beat.cc).
BandPeaks band_peaks(const ChannelSpectrum& channel, const signal::Band& band, double taper,
                     size_t count);

/// The beat of the band's mode with a second mode dw [rad/s] away, as what it adds to
/// ln A + i theta on the coarse grid in two phases (beat_of, edge_beat).
struct Beat {
  double dw = 0;       // [rad/s]
  double c_max = 0;    // the largest c over the span
  double c_first = 0;  // c at the first block that shows it
  Eigen::VectorXd u0, u1, v0, v1;
  // 1 on the grid within a block where the second mode is the larger: the band follows
  // that mode there, not the one it names.
  Eigen::VectorXi other;
  bool found() const { return c_max > 0; }
};

/// A second mode in the band read whose beat moves usable points by more than their
/// uncertainty (two_modes).
struct TwoModes {
  double f1 = 0;       // the band's mode's spectral peak [Hz]
  double f2 = 0;       // the second mode's spectral peak [Hz]
  double ratio = 0;    // its height over the band's mode's
  double beat_hz = 0;  // |f2 - f1|
  double c_first = 0;  // its amplitude over the band's mode's where first seen in the signal
  size_t moved = 0;    // usable estimates moved by more than their uncertainty
  std::vector<std::pair<double, double>> errors;
  bool found() const { return moved > 0; }
};

/// The second mode in the band read whose beat matters, if any (ringdown_beat.cc).
TwoModes two_modes(const std::vector<Estimate>& est, const ChannelSpectrum& channel,
                   const signal::Band& read, const EnvelopePhase& ep, const BandSetting& s,
                   double noise);

/// Whether two_modes finds a second mode.
bool beats_with_second_mode(const std::vector<Estimate>& est, const ChannelSpectrum& channel,
                            const signal::Band& read, const EnvelopePhase& ep, const BandSetting& s,
                            double noise);

/// The summary's note on a second mode in the band, with a band that would leave it out.
std::string beat_message(const TwoModes& two, const ChannelSpectrum& channel,
                         const signal::Band& read, const RingdownOptions& options, size_t left,
                         signal::FftCache& cache);

/// A second mode in the part of a moved band beyond the typed edge, seen by its beat alone
/// (edge_beat).
struct EdgeBeat {
  Beat beat;
  double f1 = 0;      // the mode's frequency at the block's start [Hz]
  double f2 = 0;      // the second mode's [Hz]
  double t0 = 0;      // the block's start [s from the channel's t0]
  double dsigma = 0;  // its decay rate less the mode's [1/s]
  size_t moved = 0;   // usable estimates moved by more than their uncertainty
  std::vector<std::pair<double, double>> errors;  // beat_errors
  bool found() const { return moved > 0; }
};

/// The beat of a second mode the band's move took in beyond the typed band, if any.
EdgeBeat edge_beat(const std::vector<Estimate>& est, const EnvelopePhase& ep, const BandSetting& s,
                   double noise, const signal::Band& typed, const signal::Band& read);

/// The mode's track through a band: its lowest and highest frequency and largest decay rate
/// (track_mode).
struct ModeTrack {
  double f_lo = 0, f_hi = 0, sigma = 0;  // [Hz], [Hz], [1/s]
  int points = 0;
};

/// The mode's track through the band read (ringdown_follow.cc).
ModeTrack track_mode(const EnvelopePhase& ep, double noise, const BandSetting& s);

/// The band a mode is read through, what was moved and why, and its signal (follow_mode).
struct FollowedBand {
  signal::Band band;
  std::string note;           // what was moved and why; "" when the typed band is read
  signal::BandSignal signal;  // the moved band's signal (empty when not moved)
  double held_by = 0;         // a neighbouring mode's spectral peak that held it back [Hz]; 0: none
};

/// The band the mode is read through: the typed one, or one that follows the mode past its
/// edge (ringdown_follow.cc).
FollowedBand follow_mode(const ChannelSpectrum& channel, Quantity measured,
                         const signal::Band& typed, const RingdownOptions& options,
                         const signal::BandSignal& typed_signal, const EnvelopePhase& typed_ep,
                         double typed_noise, signal::FftCache& cache);

/// True when the measured spectrum's largest magnitude over `sub` lies strictly inside it.
bool has_interior_peak(const ChannelSpectrum& channel, const signal::Band& sub);

/// A turn of the envelope's decay rate: the estimate where it peaks (or bottoms out).
struct Turn {
  const Estimate* at = nullptr;  // valid while the estimates it was found in live
  bool peak = false;
};

/// An energy exchange between the band's mode and another (ringdown.h, step 5), read from the
/// envelope's decay rate along the estimates.
struct Exchange {
  double end_t = -std::numeric_limits<double>::infinity();  ///< last turn or growth, relaxed [s]
  bool grows = false;                                       ///< the envelope grows somewhere
  double partner = 0;       ///< n or 1/n: the band, times the band's, of the mode taking energy
  std::vector<Turn> turns;  ///< the turns of the decay rate, in time order
  bool one_way = false;     ///< the rate only falls from the start while the partner grows
  bool fed_dip = false;     ///< the one turn is a dip below the settled rate (fed_at_a_dip)
  bool quadrature = false;  ///< one way, the partner locked in quadrature takes the energy
  /// A neighbour's spectral peak beyond the band read whose leak through its edge the one-way
  /// fall is, no exchange (neighbour_leak) [Hz]; 0: none.
  double leak_hz = 0;
  double partner_snr = 0;  ///< with leak_hz: the partner band's largest envelope / noise floor
  /// The envelope swings faster than the fits follow, as the power the partner takes and gives
  /// (swinging_exchange).
  bool swings = false;
  double explained = 0;  ///< with swings: the share of the swings of ln A that power explains
  bool found() const { return partner > 0 && (!turns.empty() || grows || one_way || swings); }
};

/// Whether an exchange's partner band holds energy (above its noise) at every turn.
bool partner_holds_energy(const Exchange& x, const BandSetting& s, Quantity measured,
                          signal::FftCache& cache);

/// Sets x.leak_hz where a one-way exchange is a neighbour held beyond the band read leaking
/// through its edge (ringdown_exchange.cc).
void neighbour_leak(Exchange& x, const std::vector<Estimate>& est, double held_by,
                    const signal::Band& typed, const BandSetting& s, Quantity measured,
                    signal::FftCache& cache);

/// An exchange whose swings of the envelope are faster than the fits follow, read from the
/// power the partner takes and gives, if any (ringdown_exchange.cc).
Exchange swinging_exchange(const std::vector<Estimate>& est, double noise, const BandSetting& s,
                           Quantity measured, signal::FftCache& cache);

/// What the partner of an exchange still does to an estimate after the exchange's end.
struct Transfer {
  double sigma = 0;  ///< the decay rate it takes (the band's reads this much high) [1/s]
  double omega = 0;  ///< its pull on the damped angular frequency (read this much high) [rad/s]
};

/// What the partner of an exchange still does after the exchange's end, as the exchange's 1:n
/// bookkeeping predicts: the transfer's part of the band's ln A and the pull's part of its phase
/// on the band's grid (none where that bookkeeping does not explain the exchange).
struct Relaxation {
  double end_t = std::numeric_limits<double>::infinity();  ///< the exchange's end [s]
  double dt = 0;                                           ///< the grid's step [s]
  int degree = 3;                                          ///< the estimates' local fit degree
  Eigen::VectorXd log_amp;                                 ///< the transfer's part of ln A
  Eigen::VectorXd phase;                                   ///< the pull's part of the phase [rad]
  /// Whether a transfer is predicted.
  bool found() const { return log_amp.size() > 0; }
  /// What it does to estimate `e`, read by e's own local fit (none up to the exchange's end).
  Transfer at(const Estimate& e) const;
};

/// The relaxation after the exchange `x` found in the band (ringdown_exchange.cc).
Relaxation relaxation_after(const Exchange& x, const BandSetting& s, Quantity measured,
                            signal::FftCache& cache);

/// An energy exchange of the band's mode with another, read from the estimates, if any
/// (ringdown_exchange.cc).
Exchange exchange_of(const std::vector<Estimate>& est, double noise, const BandSetting& s,
                     Quantity measured, signal::FftCache& cache);

}  // namespace jointlab::modal::ringdown_detail
