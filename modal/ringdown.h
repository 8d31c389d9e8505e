// Ring-down -> backbone: natural frequency and damping versus amplitude of one
// mode in one channel (method.md section 1).
//
// 1. The band's analytic signal of the record converted to displacement (one
//    frequency-domain pass: zero-phase band-pass, integration, Hilbert; see
//    signal/band_analytic.h): z(t) = A(t) exp(i theta(t)), A in metres.
//    Damping refers to displacement, so ln A is taken after the conversion.
// 2. Local weighted polynomial fits of ln A(t) and theta(t) (signal/local_poly.h),
//    differentiated analytically:  omega_d = d theta/dt,  sigma = -d ln A/dt,
//    omega_n = sqrt(omega_d^2 + sigma^2),  zeta = sigma / omega_n.
//    Each point's window (from a few periods up to max_window_s, pushed inside
//    the span near its ends with the point off-centre) is the one with the
//    smallest damping uncertainty, or the shortest that meets
//    target_damping_rel_std. A point whose centred windows miss max_damping_rel_std
//    also tries each length shifted either way (the point half a half-width off centre),
//    so a window can grow away from a bend of the backbone on one side of the point.
// 3. Noise floor: the RMS of the analytic signal about its local smooth fit over
//    windows of 16 / noise bandwidth (lower quartile over the record, corrected
//    for the degrees of freedom the fit absorbs). Kept span: from the impact
//    (continued backwards, see ChannelSpectrum) plus the filter's settling time
//    to where the envelope falls below snr_min times the noise floor or the
//    damping's relative uncertainty exceeds max_damping_rel_std. Points lie every
//    shortest window / points_per_window; where the next one fails the damping limit alone, the
//    span's end is placed between the two by three halvings (the last point that meets
//    the limit, made and screened as the others are).
// 4. Uncertainty per point: the larger of the fit's residual-based and the noise
//    floor's standard deviation of each slope (both corrected for correlated
//    samples), combined with the change of the slope when the polynomial degree
//    is raised by two (a model-error estimate), and with the amplitude's own
//    uncertainty carried along the backbone's slope. Monte Carlo on synthetic ring-downs shows this
//    one-sigma u matching the RMS error; the reported uncertainty is the expanded k u
//    (the GUM's expanded uncertainty), coverage_factor k = 3 by default. The points of one
//    record share their noise over windows of up to seconds, so a record's errors move
//    together and its coverage is a handful of independent draws: on 240 synthetic records
//    (two backbone shapes, 40/80/150 Hz, from displacement and acceleration) k = 2 covered
//    95-99 % of all points but fewer than 90 % of one record's points in 29 records; k = 3
//    left one record below 90 %.
// 5. Energy exchange (an internal resonance: a mode near n or 1/n times this one's frequency,
//    n = 2, 3, taking energy and giving it back): the envelope's decay rate then oscillates
//    or the envelope grows. Where, in the first pass's estimates, the decay rate turns by
//    more than three of its uncertainties and 5 % of its median, or the envelope grows by as
//    much, and the envelope in n (or 1/n) times the band has a decay rate moving against this
//    one's there (rank correlation at most -0.3, or -0.6 in their changes, the partner's rate
//    mirroring half the turns where the envelope never grows; for a single turn -0.6, the
//    partner's rate turning the other way there), the points up to
//    the last such turn or growth and the relaxation after it are kept where their amplitude (to 5
//    %) and frequency (to the mode's half-power half-width) are well determined, and marked
//    (Backbone::exchange): their damping is damping plus transfer, an apparent damping that may be
//    negative. They are left out of the linear values and of the band-gain correction's model of
//    the mode. Records without such an exchange are unchanged. A one-way fall beside a
//    neighbour held beyond the band's edge, its partner band holding noise alone, is marked
//    as that neighbour's leak through the edge, no exchange. Swings faster than the shortest
//    window (a partner detuned by a few per cent) show no turn: where the first estimates miss
//    max_damping_rel_std, the envelope's swings there are taken for an exchange where the
//    power the partner takes and gives back explains them (ringdown_exchange.cc).
// 6. Two modes in one band: a second resolved peak of the measured spectrum inside the band
//    read, whose beat with the mode (ln A + i theta oscillating at the difference frequency)
//    shows in the first estimates, has what it moves each point's decay rate and frequency by
//    added to the point's uncertainty (where it exceeds it somewhere), so the points it moves
//    past max_damping_rel_std drop out, and the summary names the second mode. Not applied
//    beside an energy exchange (5), which is marked on its own.
// The band a user gives says which mode. Where the mode's track comes within three
// half-power half-widths of the band's sloping edge, the mode is read through a band moved
// (and, if the typed band's filter would lose the start of the decay, widened) to hold it
// in its flat part, never toward a neighbouring mode's spectral peak beyond the typed band
// (of the smoothed spectrum, or where it shows none a resolved peak of the measured samples');
// Ringdown::band stays the typed band's signal (shapes compare channels through it).
// The amplitude column is A * omega_n^k for displacement (k = 0), velocity (1)
// or acceleration (2) amplitude.
//
// Method kPeaks (peak finding and fitting) instead fits parabolas through the
// samples around each extremum of the band-passed displacement: the extrema
// times give theta (pi per extremum) and their heights give A; the same local
// fits then run over the extremum index.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/core/units.h"
#include "jointlab/modal/clipping.h"
#include "jointlab/signal/band_analytic.h"

namespace jointlab::modal {

/// How the instantaneous envelope and phase are obtained.
enum class Method { kHilbert, kPeaks };

/// Settings of backbone extraction.
struct RingdownOptions {
  Method method = Method::kHilbert;          ///< Hilbert (default) or peak fitting
  Quantity amplitude = Quantity::kVelocity;  ///< quantity of the amplitude column
  double taper = 0.25;                       ///< band edge width / band width
  double snr_min = 30.0;                     ///< envelope / noise floor to keep a point
  double min_periods = 8.0;                  ///< shortest fit window [periods]
  double max_window_s = 8.0;                 ///< longest fit window [s]
  double target_damping_rel_std = 0.005;     ///< window grows until zeta std / zeta <= this
  double max_damping_rel_std = 0.01;         ///< points with a larger zeta std / zeta are dropped
  double points_per_window = 3.0;            ///< output points per shortest window
  int degree = 3;                            ///< degree of the local polynomials
  double coverage_factor = 3.0;              ///< k of the reported uncertainty k * sigma
  /// Empty if the options are usable, else what is wrong.
  std::string check() const;
};

/// The backbone of one mode in one channel: one entry per retained point, time increasing.
struct Backbone {
  Eigen::VectorXd time_s;               ///< time of the point [s] (record time base)
  Eigen::VectorXd amplitude;            ///< amplitude of RingdownOptions::amplitude [SI]
  Eigen::VectorXd frequency_hz;         ///< natural frequency omega_n / 2 pi [Hz]
  Eigen::VectorXd damping;              ///< damping ratio zeta (fraction)
  Eigen::VectorXd frequency_std_hz;     ///< expanded uncertainty (k sigma) of frequency_hz
  Eigen::VectorXd damping_std;          ///< expanded uncertainty (k sigma) of damping
  Eigen::VectorXd damped_frequency_hz;  ///< omega_d / 2 pi [Hz]
  Eigen::VectorXd decay_rate;           ///< sigma [1/s]
  Eigen::VectorXd displacement;         ///< displacement amplitude A [m]
  Eigen::VectorXd snr;                  ///< envelope / noise floor
  Eigen::VectorXd window_s;             ///< fit window used [s]
  Eigen::VectorXi harmonic;  ///< n > 1 where the point follows n times a stronger mode, else 0
  /// 1 where the mode exchanges energy with another mode (its envelope's decay there is
  /// damping plus transfer, an apparent damping that may be negative), else 0.
  Eigen::VectorXi exchange;
  /// Number of points.
  Eigen::Index size() const { return time_s.size(); }
};

/// How extraction ended.
enum class RingdownStatus { kOk, kNoSpan };

/// What extraction found besides the points.
struct RingdownSummary {
  RingdownStatus status = RingdownStatus::kNoSpan;  ///< kOk when a span was kept
  std::string message;                              ///< why no span was kept, or notes
  double noise_floor_m = 0.0;            ///< noise floor of the displacement envelope [m]
  double peak_time_s = 0.0;              ///< time of the envelope maximum [s]
  double span_start_s = 0.0;             ///< first kept point [s]
  double span_end_s = 0.0;               ///< last kept point [s]
  double amplitude_decades = 0.0;        ///< log10(max/min amplitude) over the span
  double linear_frequency_hz = 0.0;      ///< natural frequency in the limit of zero amplitude [Hz]
  double linear_frequency_std_hz = 0.0;  ///< its expanded uncertainty (k sigma) [Hz]
  double linear_damping = 0.0;           ///< damping ratio in the limit of zero amplitude
  double linear_damping_std = 0.0;       ///< its expanded uncertainty (k sigma)
  double linear_fit_min = 0.0;  ///< lowest amplitude of the fit behind the linear values [SI]
  double linear_fit_max = 0.0;  ///< highest amplitude of that fit [SI]
  /// Why the band has no linear values ("" when it has them: the four linear_* values above
  /// and the fit range are measured only then; never read them otherwise).
  std::string linear_reason;
  /// True when the linear values were measured.
  bool has_linear() const { return status == RingdownStatus::kOk && linear_reason.empty(); }
  int superharmonic_points = 0;  ///< points following a multiple of a stronger mode
  int exchange_points = 0;       ///< points where the mode exchanges energy (Backbone::exchange)
  double carrier_hz = 0.0;       ///< dominant frequency in the band [Hz]
  /// One paragraph for a person.
  std::string report() const;
};

/// Settings of the record preparation shared by all bands of a channel.
struct PrepareOptions {
  double onset_skip_s = 0.002;  ///< data skipped after the impact (see impact_index) [s]
  double extend_s = 0.5;        ///< linear-prediction continuation at each end [s]
  int ar_order = 32;            ///< order of the continuation model (lower if it blows up)
  double ar_fit_s = 0.25;       ///< data the continuation model is fitted on [s]
  double lowpass_hz = 0.0;      ///< content kept for the continuation (0: everything) [Hz]
  /// Zero padding of a long record's spectrum [s], what the slowest band filter read from it
  /// needs to die out between the record's ends (0: twice the record; prepare_for sets it).
  double pad_s = 0.0;
  /// Records of more analysed samples than this are padded by pad_s alone: twice a record
  /// of 2e7 samples made its spectrum and FFTW's tables 33 bytes a sample. Shorter ones are
  /// padded to twice their length, the finer bins their results were first made with.
  Eigen::Index pad_above = Eigen::Index{1} << 22;
};

/// The spectrum of one channel, computed once and shared by all its bands.
///
/// The analysed record starts just after the impact (impact_index, plus
/// onset_skip_s): the pre-trigger and the impact itself are
/// replaced by the ring-down's own backward continuation, and the end is
/// continued forward, so band filters see no abrupt start or end. With
/// lowpass_hz set, the record is first low-passed (zero phase, edge from
/// lowpass_hz to twice it) so that heavily damped high modes, which grow without
/// bound when continued backwards, are not continued at all; the low-pass's own
/// settling time at each end is continued too and not counted as data.
struct ChannelSpectrum {
  /// One-sided spectrum of the zero-padded analysed record; bins past its size are zero (a
  /// long record keeps those its low-pass leaves anything in).
  Eigen::VectorXcd spectrum;
  /// Every measured_step-th bin of the measured samples' spectrum alone, the continuations
  /// zeroed, up to where the low-pass leaves nothing: what the record itself holds, for the
  /// checks that ask whether a mode is there. (A continuation run backwards can grow
  /// hundreds of times past the record's peak and dominate `spectrum`.)
  Eigen::VectorXcd measured;
  Eigen::Index measured_step = 1;  ///< bin k of `measured` is bin k times this of `spectrum`

  /// Spacing of `measured`'s bins [Hz].
  double measured_df() const {
    return fs * static_cast<double>(measured_step) / static_cast<double>(n_fft);
  }
  /// Bin of `measured` nearest `f` [Hz], clamped to [lo, hi].
  Eigen::Index measured_bin(double f, Eigen::Index lo, Eigen::Index hi) const {
    return std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::round(f / measured_df())), lo,
                                    hi);
  }
  Eigen::Index n_record = 0;  ///< samples analysed (continuations included)
  Eigen::Index n_fft = 0;     ///< padded length (twice n_record, or n_record and pad_s if long)
  double fs = 0.0;            ///< sample rate [Hz]
  double t0 = 0.0;            ///< time of the analysed record's first sample [s]
  double data_begin_s = 0.0;  ///< first measured sample used [s]
  double data_end_s = 0.0;    ///< last measured sample [s]
  double continued_begin_s = 0.0;  ///< faithful continuation before the data [s]
  double continued_end_s = 0.0;    ///< faithful continuation after the data [s]
  /// The channel's samples pinned at its range (find_clipping), over the whole record.
  Clipping clipping;
  /// Time of the last clipped sample [s] (meaningful where clipping.found()).
  double clipped_until_s = 0.0;
  /// The analysed samples are the record's times this power of two: 1 unless the channel's
  /// magnitude lies outside [1e-100, 1e100], where squares would overflow or underflow.
  double scale = 1.0;

  /// Padded by PrepareOptions::pad_s rather than to twice the record (a long record): only
  /// then may the spectrum stop short of n_fft / 2 + 1 bins.
  bool padded_by_pad_s() const { return n_fft < 2 * n_record; }
};

/// Backbone, summary and the band's displacement analytic signal.
struct Ringdown {
  Backbone backbone;        ///< retained points (amplitudes in the record's units)
  RingdownSummary summary;  ///< span, noise floor, linear values, status
  signal::BandSignal
      band;  ///< displacement analytic signal of the band times ChannelSpectrum::scale
};

/// Settling time of a band's filter [s]: its kernel is down to exp(-11) by then, so
/// data closer than this to an end that is not faithfully continued are not used.
double band_settling_s(const signal::Band& band, double taper);

/// The continuation settings `bands` need, from `base`: unless base sets a low-pass,
/// content up to 1.5 times the highest band edge; continued over at least 1.1 times
/// the slowest band filter's settling time, so that no band loses data to its own
/// transient; a long record padded by at least 6 such times (process_record uses these).
PrepareOptions prepare_for(const std::vector<signal::Band>& bands, double taper,
                           PrepareOptions base = {});

/// Index of the impact: the first sample reaching half the largest |sample| of the record's
/// first quarter.
Eigen::Index impact_index(const Eigen::Ref<const Eigen::VectorXd>& x);

/// Mean-removed, onset-trimmed, continued and zero-padded spectrum of a channel;
/// `impact` is the impact's sample index (negative: found by impact_index), `clipping` the
/// channel's find_clipping (null: found here).
ChannelSpectrum channel_spectrum(const Eigen::Ref<const Eigen::VectorXd>& x, double fs, double t0,
                                 const PrepareOptions& options, signal::FftCache& cache,
                                 Eigen::Index impact = -1, const Clipping* clipping = nullptr);

/// The displacement analytic signal of `band` from a channel measuring `measured`, times
/// channel.scale.
signal::BandSignal band_signal(const ChannelSpectrum& channel, Quantity measured,
                               const signal::Band& band, const RingdownOptions& options,
                               signal::FftCache& cache);

/// Extracts the backbone of the mode in `band` from a channel measuring `measured`.
Ringdown extract_backbone(const ChannelSpectrum& channel, Quantity measured,
                          const signal::Band& band, const RingdownOptions& options,
                          signal::FftCache& cache);

}  // namespace jointlab::modal
