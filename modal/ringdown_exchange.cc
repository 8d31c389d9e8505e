// An energy exchange between the band's mode and another in internal resonance (n or 1/n times
// its frequency), read from the turns of the envelope's decay rate along the estimates and the
// envelope of the partner's band (exchange_of); see ringdown_detail.h.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <complex>
#include <cstddef>
#include <functional>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <vector>

#include <Eigen/Dense>

#include "jointlab/core/rank_correlation.h"
#include "jointlab/modal/ringdown_detail.h"
#include "jointlab/signal/band_analytic.h"
#include "jointlab/signal/local_poly.h"

namespace jointlab::modal::ringdown_detail {

// A turn of the decay rate or a growth of the envelope counts beyond kExchangeSigmas of its
// uncertainty and kExchangeRel of the mode's typical decay rate (the median over the span):
// a mode's own decay rate changes with its amplitude, monotonically or turning once where its
// damping peaks, but does not oscillate.
constexpr double kExchangeSigmas = 3.0;
constexpr double kExchangeRel = 0.05;

// Whether two decay rates lie clearly apart in that sense, `typical` the rate kExchangeRel is
// taken of (a rate known exactly has one-sigma 0).
bool rates_apart(double a, double a_std, double b, double b_std, double typical) {
  return std::abs(a - b) >
         std::max(kExchangeSigmas * std::hypot(a_std, b_std), kExchangeRel * typical);
}

// Whether the envelope in [r lo, r hi] (r = n or 1/n, n = 2, 3: a mode that can be in
// internal resonance with the band's) takes what the band's mode gives and gives it back:
// over the estimates `at` (those up to the exchange's end and the one after it that shows
// its last turn, at least 5), the decay rates of the two envelopes, each fitted over the
// estimate's window, move against each other (rank correlation at most kAntiCorrelated; ranks, as
// the rates swing by factors while energy flows). In the 1:2 internal resonance of ringdown_test.cc
// it is -0.50 to -0.90; two modes that merely decay side by side do not: a beam's 297 Hz mode,
// whose decay rate wanders by 5 % and turns 14 times, has a peak 2.5 % off twice its frequency, and
// the rates of the two (and of a third at 3 times) move together, +0.5 to +0.8.
constexpr double kAntiCorrelated = -0.3;
// ... or the changes of the two rates from one estimate to the next (where both are known to
// better than their median) move against each other (at most kAntiCorrelatedChanges). Where
// the hammer strikes both modes of the twin alike, the rates' own falls from the start
// swamp their swings: the rates' ranks gave +0.02, their changes' -0.85.
constexpr double kAntiCorrelatedChanges = -0.6;
// A decay rate that turns once (and an envelope that never grows) may be the mode's own
// damping peaking with amplitude, beside a neighbour whose damping changes too: then the two
// rates must move against each other nearly throughout (-0.7 to -0.9 where a hammer strikes
// both modes of the twin), and the partner's rate must turn the other way within kTurnApart
// estimates of this one's turn. Without that second condition 9 of 54 joint-like twins (a
// damping peak, an uncoupled neighbour at twice the frequency, its damping constant, falling
// or peaking; ringdown_test.cc) were taken for an exchange, and 12 of 54 with the neighbour
// at half; with it none of 162 are.
constexpr double kAntiCorrelatedOneTurn = -0.6;
constexpr std::ptrdiff_t kTurnApart = 2;

// The median of |v|: a typical decay rate.
double median_magnitude(const std::vector<double>& v) {
  std::vector<double> magnitudes(v.size());
  std::transform(v.begin(), v.end(), magnitudes.begin(), [](double x) { return std::abs(x); });
  return quantile(magnitudes, 0.5);
}

// The rank correlation of the changes from one estimate to the next of two decay rates, over
// the estimates where both are known to better than their typical (median) magnitude; 0 with
// fewer than kMinChanges changes.
double changes_correlation(const std::vector<double>& a, const std::vector<double>& a_std,
                           const std::vector<double>& b, const std::vector<double>& b_std) {
  constexpr size_t kMinChanges = 5;
  const double typical_a = median_magnitude(a), typical_b = median_magnitude(b);
  std::vector<double> ka, kb;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a_std[i] <= typical_a && b_std[i] <= typical_b) ka.push_back(a[i]), kb.push_back(b[i]);
  }
  if (ka.size() < kMinChanges + 1) return 0.0;
  std::vector<double> da(ka.size() - 1), db(kb.size() - 1);
  for (size_t i = 0; i + 1 < ka.size(); ++i) da[i] = ka[i + 1] - ka[i], db[i] = kb[i + 1] - kb[i];
  return rank_correlation(da, db);
}

// How many of the band's turns (among the estimates `used`) the partner's rates `other` (one
// per estimate used) mirror: within kTurnApart estimates of the turn they have a local extreme
// of the other kind (a minimum where the band's rate peaks), clearly apart (rates_apart) from a
// neighbouring estimate's; the last estimate's does not count, as it may only be the start of a
// change. A joint-like mode whose damping peaks twice (its rate turns three times) beside an
// uncoupled neighbour had the two rates' ranks move against each other (-0.58 to -0.85 over
// 38-50 estimates) in 155 of 162 records (ringdown_test.cc), none of its turns mirrored in 155
// and one of three in 7; in the 1:2 twins 29 of the 31 partner bands tried mirrored at least
// half.
std::ptrdiff_t mirrored_turns(const std::vector<const Estimate*>& used,
                              const std::vector<Turn>& turns, const std::vector<double>& other,
                              const std::vector<double>& other_std) {
  const auto n = static_cast<std::ptrdiff_t>(used.size());
  const double typical = median_magnitude(other);
  // Whether other[j] is a local maximum (dir +1) or minimum (-1), clearly apart from a
  // neighbour's.
  const auto extreme = [&](std::ptrdiff_t j, int dir) {
    bool clear = false;
    for (const std::ptrdiff_t k : {j - 1, j + 1}) {
      if (k < 0 || k >= n) continue;
      if ((other[j] - other[k]) * dir < 0) return false;
      clear = clear || rates_apart(other[j], other_std[j], other[k], other_std[k], typical);
    }
    return clear;
  };
  std::ptrdiff_t mirrored = 0;
  for (const Turn& turn : turns) {
    const auto it = std::find(used.begin(), used.end(), turn.at);
    if (it == used.end()) continue;
    const std::ptrdiff_t i = it - used.begin();
    const bool peak = turn.peak;
    for (std::ptrdiff_t j = std::max<std::ptrdiff_t>(0, i - kTurnApart);
         j <= std::min(n - 2, i + kTurnApart); ++j) {
      if (extreme(j, peak ? -1 : 1)) {
        ++mirrored;
        break;
      }
    }
  }
  return mirrored;
}

// The decay rates of the band's envelope and of the envelope in [r lo, r hi] at the estimates
// `at` (each fitted over the estimate's window), with their one-sigmas; none where that band
// lies beyond the Nyquist frequency, settles longer than the record or shows no peak inside.
struct PartnerRates {
  std::vector<const Estimate*> used;
  std::vector<double> own, own_std, other, other_std;
};

PartnerRates partner_rates(const std::vector<const Estimate*>& at, double r, const BandSetting& s,
                           Quantity measured, signal::FftCache& cache) {
  const ChannelSpectrum& channel = s.channel;
  const RingdownOptions& options = s.options;
  PartnerRates out;
  const signal::Band sub{s.band.lo * r, s.band.hi * r};
  const double duration = static_cast<double>(channel.n_record - 1) / channel.fs;
  if (sub.hi >= channel.fs / 2 || band_settling_s(sub, options.taper) > duration ||
      !has_interior_peak(channel, sub))
    return out;
  const signal::BandSignal zs = band_signal(channel, measured, sub, options, cache);
  const EnvelopePhase ep = envelope_phase(zs.baseband, zs.carrier_hz, zs.dt);
  const double correlation = std::max(1.0, 1.0 / (zs.dt * zs.noise_bandwidth_hz));
  const double span = static_cast<double>(zs.baseband.size() - 1) * zs.dt;
  for (const Estimate* e : at) {
    const double w = std::min(e->window, span);
    const double c = std::clamp(e->centre, w / 2, span - w / 2);
    if (static_cast<Eigen::Index>(w / zs.dt) < options.degree + 4) continue;
    const auto [fa, fp] =
        signal::fit_local_pair(ep.log_amp, ep.theta, 0.0, zs.dt, c, w / 2, options.degree,
                               correlation, 1, std::clamp((e->t - c) / (w / 2), -1.0, 1.0));
    if (!std::isfinite(fa.slope)) continue;
    out.used.push_back(e);
    out.own.push_back(e->sigma);
    out.own_std.push_back(e->sigma_std);
    out.other.push_back(-fa.slope);
    out.other_std.push_back(std::hypot(fa.slope_std, fa.slope_change));
  }
  return out;
}

bool takes_energy(const std::vector<const Estimate*>& at, double r, bool one_turn, bool grows,
                  const std::vector<Turn>& turns, const BandSetting& s, Quantity measured,
                  signal::FftCache& cache) {
  const PartnerRates pr = partner_rates(at, r, s, measured, cache);
  const std::vector<const Estimate*>& used = pr.used;
  const std::vector<double>&own = pr.own, &own_std = pr.own_std, &other = pr.other,
        &other_std = pr.other_std;
  if (own.size() < 5) return false;
  const double limit = one_turn ? kAntiCorrelatedOneTurn : kAntiCorrelated;
  const double moves = rank_correlation(own, other);
  if (!one_turn) {
    if (!(moves <= limit ||
          changes_correlation(own, own_std, other, other_std) <= kAntiCorrelatedChanges))
      return false;
    // Where the envelope never grows, the partner mirrors at least half of the turns.
    return grows || 2 * mirrored_turns(used, turns, other, other_std) >=
                        static_cast<std::ptrdiff_t>(turns.size());
  }
  if (!(moves <= limit)) return false;
  // The partner's rate turns the other way within kTurnApart estimates of this one's turn
  // (its extreme inside `at`; the partner's may be the first, the exchange having begun
  // before the first estimate, but not the last, and it lies clearly apart from the last, as
  // turns do: `at` runs past the exchange's end).
  const auto n = static_cast<std::ptrdiff_t>(own.size());
  const auto at_max = std::max_element(own.begin(), own.end()) - own.begin();
  const auto at_min = std::min_element(own.begin(), own.end()) - own.begin();
  const bool max_inside = at_max > 0 && at_max < n - 1;
  const std::ptrdiff_t turn = max_inside ? at_max : at_min;
  const std::ptrdiff_t opposite =
      max_inside ? std::min_element(other.begin(), other.end()) - other.begin()
                 : std::max_element(other.begin(), other.end()) - other.begin();
  const auto o = static_cast<size_t>(opposite);
  return opposite < n - 1 && std::abs(opposite - turn) <= kTurnApart &&
         rates_apart(other[o], other_std[o], other.back(), other_std.back(),
                     median_magnitude(other));
}

// The mode's own decay rate: the median over the later half of the rates `known` (in time order),
// where a transfer has died away.
double own_rate(const std::vector<const Estimate*>& known) {
  std::vector<double> late;
  for (size_t i = known.size() / 2; i < known.size(); ++i) late.push_back(known[i]->sigma);
  return quantile(late, 0.5);
}

// The two bands of a 1:n bookkeeping (r = n or 1/n, the partner's band r times the band's):
// the band's signal and the partner's, which of them is the higher, n, and the beat of
// z_hi conj(z_lo)^n's carriers, carrier_hi - n carrier_lo.
struct DriveBands {
  signal::BandSignal partner, own;
  bool upper = false;  ///< the partner is the mode at n times the band's
  int n = 1;
  double beat_hz = 0;
  /// The band at n times the other's.
  const signal::BandSignal& hi() const { return upper ? partner : own; }
  /// The band at 1/n times the other's.
  const signal::BandSignal& lo() const { return upper ? own : partner; }
};

// The bands of the 1:n bookkeeping; none where the partner band lies beyond the Nyquist
// frequency, settles longer than the record or shows no peak inside.
std::optional<DriveBands> drive_bands(double r, const BandSetting& s, Quantity measured,
                                      signal::FftCache& cache) {
  const ChannelSpectrum& channel = s.channel;
  const signal::Band sub{s.band.lo * r, s.band.hi * r};
  const double duration = static_cast<double>(channel.n_record - 1) / channel.fs;
  if (sub.hi >= channel.fs / 2 || band_settling_s(sub, s.options.taper) > duration ||
      !has_interior_peak(channel, sub))
    return std::nullopt;
  DriveBands b;
  b.partner = band_signal(channel, measured, sub, s.options, cache);
  b.own = band_signal(channel, measured, s.band, s.options, cache);
  b.upper = r > 1;
  b.n = static_cast<int>(std::lround(b.upper ? r : 1 / r));
  b.beat_hz = b.hi().carrier_hz - b.n * b.lo().carrier_hz;
  return b;
}

// z(t) = baseband(t) exp(2 pi i carrier t), the baseband interpolated linearly (it changes over
// the band's width, far slower than the grid's 8 samples a width); z_hi conj(z_lo)^n is then
// b_hi conj(b_lo)^n exp(2 pi i (carrier_hi - n carrier_lo) t): one phasor, turned, and
// conj(b_lo)^n by products (std::pow of a complex goes through its logarithm). Written with a
// phasor per band and std::pow, the drive took 15 % of `process` on the bench record.
std::complex<double> interpolated(const signal::BandSignal& z, double t) {
  const double x = t / z.dt;
  const auto j = std::clamp<Eigen::Index>(static_cast<Eigen::Index>(x), 0, z.baseband.size() - 2);
  const double w = std::clamp(x - static_cast<double>(j), 0.0, 1.0);
  return (1 - w) * z.baseband(j) + w * z.baseband(j + 1);
}

// Energy bookkeeping of a 1:n transfer, read from the phase of the two bands. Where the band's
// mode drives a mode at n times its frequency (or is driven by one at 1/n), the power passed
// is proportional to A_lo^n A_hi sin(psi), psi = arg z_hi - n arg z_lo, both analytic signals
// as displacement: a harmonic that the structure or the sensor makes quasi-statically (no mode
// there taking energy) lies in phase or in antiphase (sin psi = 0), a mode driven at its
// resonance lags the drive by a quarter period. The band's decay rate above its own, the power
// over the energy it holds (A_this^2), is then proportional to the drive
// d = Im(z_hi conj(z_lo)^n) / |z_this|^2, averaged over each estimate's window. Returns the
// window means of z_hi conj(z_lo)^n / |z_this|^2 (their imaginary part d), one per estimate of
// `at` before the first that `keep` (given it and the window mean of its modulus) refuses; none
// where the partner band lies beyond the Nyquist frequency, settles longer than the record or
// shows no peak inside.
std::vector<std::complex<double>> quadrature_drive(
    const std::vector<const Estimate*>& at, double r, const BandSetting& s, Quantity measured,
    signal::FftCache& cache, const std::function<bool(std::complex<double>, double)>& keep) {
  std::vector<std::complex<double>> out;
  const std::optional<DriveBands> bands = drive_bands(r, s, measured, cache);
  if (!bands) return out;
  const signal::BandSignal &hi = bands->hi(), &lo = bands->lo();
  const bool upper = bands->upper;
  const int n = bands->n;
  const double beat_hz = bands->beat_hz;
  const double span = static_cast<double>(hi.baseband.size() - 1) * hi.dt;
  for (const Estimate* e : at) {
    const double w = std::min(e->window, span);
    const double c = std::clamp(e->centre, w / 2, span - w / 2);
    std::complex<double> sum = 0;
    double modulus = 0;
    int count = 0;
    // The beat's phasor turned a grid step at a time: its error grows by about 1e-16 a step, 1e-13
    // over a thousand.
    std::complex<double> phasor = std::polar(1.0, 2 * std::numbers::pi * beat_hz * (c - w / 2));
    const std::complex<double> turn = std::polar(1.0, 2 * std::numbers::pi * beat_hz * hi.dt);
    for (double t = c - w / 2; t <= c + w / 2; t += hi.dt, ++count, phasor *= turn) {
      const std::complex<double> h = interpolated(hi, t), l = interpolated(lo, t);
      const double own = std::norm(upper ? l : h);
      if (!(own > 0)) continue;
      std::complex<double> l_n = std::conj(l);
      for (int k = 1; k < n; ++k) l_n *= std::conj(l);
      const std::complex<double> u = h * l_n / own;  // the drive's baseband part
      sum += u * phasor;
      modulus += std::sqrt(std::norm(u));
    }
    const std::complex<double> mean = count > 0 ? sum / static_cast<double>(count) : 0.0;
    const double mean_modulus = count > 0 ? modulus / count : 0.0;
    if (!keep(mean, mean_modulus)) break;
    out.push_back(mean);
  }
  return out;
}

// A partner locked in quadrature: at each estimate the window mean of the drive holds at least
// kLocked of its modulus (the phase psi steady over the window, not turning as an uncoupled
// neighbour's does against n times the band's) and its imaginary part at least kQuadrature of
// that mean (|sin psi| >= 0.9: within 26 degrees of quadrature), with one sign throughout.
// The band's decay rate above its own must then follow the drive: the slope of its logarithm
// against the drive's, fitted over the estimates, between 1/kSlope and kSlope (1 where the
// power passed is all the band loses beyond its own damping). In the 1:2 twins in tune (mode 2
// at exactly 2 f1, damping 0.6 %), struck at mode 1 or as a hammer strikes, |sin psi| was 1.00
// at every estimate and the ratio of the excess rate to the drive stayed within a factor 1.7
// (alpha 1e9) and 2.7 (2e9) while the excess fell 60 and 155 times; the Brake-Reuss beam's
// harmonic at twice 80.5 Hz lies within 3 degrees of antiphase.
constexpr double kLocked = 0.5;
constexpr double kQuadrature = 0.9;
constexpr double kSlope = 2.0;

bool drained_in_quadrature(const std::vector<const Estimate*>& during, double own, double r,
                           const BandSetting& s, Quantity measured, signal::FftCache& cache) {
  // Fewer than 5 estimates above the band's own rate give no slope: said before the drive is read.
  if (std::count_if(during.begin(), during.end(),
                    [own](const Estimate* e) { return e->sigma - own > 0; }) < 5)
    return false;
  // The drive read up to the first estimate that is not locked in quadrature with one sign.
  int sign = 0;
  const auto locked = [&sign](std::complex<double> m, double modulus) {
    if (!(std::abs(m) >= kLocked * modulus) || !(std::abs(m.imag()) >= kQuadrature * std::abs(m)))
      return false;
    const int here = m.imag() > 0 ? 1 : -1;
    if (sign != 0 && here != sign) return false;
    sign = here;
    return true;
  };
  const std::vector<std::complex<double>> drive =
      quadrature_drive(during, r, s, measured, cache, locked);
  if (drive.size() != during.size()) return false;
  std::vector<double> lx, ly;
  for (size_t k = 0; k < during.size(); ++k) {
    const std::complex<double> m = drive[k];
    const double excess = during[k]->sigma - own;
    if (excess > 0) lx.push_back(std::log(std::abs(m.imag()))), ly.push_back(std::log(excess));
  }
  if (lx.size() < 5) return false;  // as takes_energy: fewer say little
  const double mx = std::accumulate(lx.begin(), lx.end(), 0.0) / static_cast<double>(lx.size());
  const double my = std::accumulate(ly.begin(), ly.end(), 0.0) / static_cast<double>(ly.size());
  double sxx = 0, sxy = 0;
  for (size_t k = 0; k < lx.size(); ++k) {
    sxx += (lx[k] - mx) * (lx[k] - mx);
    sxy += (lx[k] - mx) * (ly[k] - my);
  }
  if (!(sxx > 0)) return false;
  const double slope = sxy / sxx;
  return slope >= 1 / kSlope && slope <= kSlope;
}

// A transfer one way only: the band's decay rate falls from the start, without an exchange
// found by its turns, to the mode's own while the envelope in n or 1/n times the band (n = 2, 3)
// takes what the band's mode gives: its decay rate starts clearly below where it ends up (slowed
// or growing as it is fed) and rises while the band's falls (rank correlation at most
// kAntiCorrelatedOneTurn). A joint's damping falls too as the amplitude falls, but a neighbour's
// rate beside it does not rise from below then. In a 1:2 twin struck at mode 1 (the band read
// from 0.12 s) the band's rate fell from 24 to 2.3 1/s over 0.4 s, read as a damping 7 times the
// mode's, unmarked, while mode 2's rose from -2.9 to 9. `seen` are the estimates above the
// noise threshold, `typical` their median decay rate.
Exchange one_way_exchange(const std::vector<const Estimate*>& seen, double typical,
                          const BandSetting& s, Quantity measured, signal::FftCache& cache) {
  Exchange x;
  std::vector<const Estimate*> known;
  for (const Estimate* e : seen)
    if (e->sigma_std <= typical) known.push_back(e);
  if (known.size() < 6) return x;
  const double own = own_rate(known);
  const auto apart = [&](const Estimate* e) {
    return e->sigma > own && rates_apart(e->sigma, e->sigma_std, own, 0.0, typical);
  };
  // The fall starts at the first rate clearly above the mode's own. The rates before it, read
  // where the exchange swings fastest (within a window of the impact), may be too uncertain to
  // say where they lie, but none may lie clearly apart from that first one: a rate that rises to
  // it has turned, which exchange_of's turns judge.
  const auto first =
      std::find_if(known.begin(), known.end(), [&](const Estimate* e) { return apart(e); });
  if (first == known.end()) return x;
  for (auto e = known.begin(); e != first; ++e) {
    if (rates_apart((*e)->sigma, (*e)->sigma_std, (*first)->sigma, (*first)->sigma_std, typical))
      return x;
  }
  const double start_t = (*first)->t;
  double end_t = start_t;
  for (auto e = first; e != known.end() && apart(*e); ++e) end_t = (*e)->t;
  std::vector<const Estimate*> during;
  for (const Estimate* e : seen) {
    if (e->t < start_t) continue;
    if (e->t <= end_t || (!during.empty() && during.back()->t <= end_t)) during.push_back(e);
  }
  if (during.size() < 5) return x;
  for (const double r : {2.0, 0.5, 3.0, 1 / 3.0}) {
    const PartnerRates pr = partner_rates(during, r, s, measured, cache);
    if (pr.used.size() < 5) continue;  // as takes_energy: ranks of fewer say little
    const double partner_typical = median_magnitude(pr.other);
    const bool fed = pr.other.front() < pr.other.back() &&
                     rates_apart(pr.other.front(), pr.other_std.front(), pr.other.back(),
                                 pr.other_std.back(), partner_typical);
    if (fed && rank_correlation(pr.own, pr.other) <= kAntiCorrelatedOneTurn) {
      x.partner = r;
      x.one_way = true;
      x.end_t = end_t;
      return x;
    }
  }
  // The partner's rate need not move against the band's: a mode in tune, fed from the start,
  // rises and then follows n times the band's rate (its energy slaved to the band's), so the
  // ranks move together over most of the fall (-0.12 to -0.18 in the 1:2 twin in tune, where
  // the first points then read damping 164 % and 328 % above mode 1's, unmarked). The phase
  // of the two bands says whether the partner takes the energy (drained_in_quadrature).
  for (const double r : {2.0, 0.5}) {
    if (drained_in_quadrature(during, own, r, s, measured, cache)) {
      x.partner = r;
      x.one_way = true;
      x.quadrature = true;
      x.end_t = end_t;
      return x;
    }
  }
  return x;
}

// A single turn that is a minimum clearly below the rate the envelope settles to afterwards:
// the mode decays slower than its own damping allows while the envelope in n or 1/n times the
// band (n = 2, 3) gives it energy, its decay rate rising from the first estimate to the dip
// (clearly apart) while the band's falls. A joint's damping adds to the mode's own and never
// takes the decay below the rate it has at low amplitude: the joint-like twins of
// ringdown_test.cc turn at peaks, or at a minimum between two peaks above that rate. In a 1:2
// twin with both modes at 1 % damping (mode 2 struck too) the band's rate fell from 14.4 to
// 5.2 1/s and rose to 7.6 while mode 2's rose from 14.3 to 16.5; the first six points read the
// damping +86 % to -12 % off the mode's own, unmarked, as the partner's rate kept rising
// after the dip and its turn (takes_energy) was not within reach. `during` are the estimates
// up to the exchange's end and the one after it.
double fed_at_a_dip(const std::vector<const Estimate*>& during, const Turn& dip,
                    const BandSetting& s, Quantity measured, signal::FftCache& cache) {
  for (const double r : {2.0, 0.5, 3.0, 1 / 3.0}) {
    const PartnerRates pr = partner_rates(during, r, s, measured, cache);
    if (pr.used.size() < 5) continue;  // as takes_energy: ranks of fewer say little
    const auto it = std::find(pr.used.begin(), pr.used.end(), dip.at);
    if (it == pr.used.end() || it == pr.used.begin()) continue;
    const auto i = static_cast<size_t>(it - pr.used.begin());
    const double typical = median_magnitude(pr.other);
    if (pr.other[i] > pr.other.front() &&
        rates_apart(pr.other[i], pr.other_std[i], pr.other.front(), pr.other_std.front(), typical))
      return r;
  }
  return 0.0;
}

// Whether the partner of an exchange found (Exchange::partner) holds energy where the band's
// decay rate turns: its envelope at least snr_min times its own noise floor at every turn.
bool partner_holds_energy(const Exchange& x, const BandSetting& s, Quantity measured,
                          signal::FftCache& cache) {
  const signal::Band sub{s.band.lo * x.partner, s.band.hi * x.partner};
  const signal::BandSignal zs = band_signal(s.channel, measured, sub, s.options, cache);
  const EnvelopePhase ep = envelope_phase(zs.baseband, zs.carrier_hz, zs.dt);
  const BandSetting sp = band_setting(s.channel, sub, s.options, zs);
  const double noise = noise_floor(ep, sp);
  for (const Turn& turn : x.turns) {
    const auto j = std::clamp<Eigen::Index>(static_cast<Eigen::Index>(turn.at->t / zs.dt), 0,
                                            ep.amp.size() - 1);
    if (!(ep.amp(j) >= s.options.snr_min * noise)) return false;
  }
  return true;
}

// An envelope of noise alone (Rayleigh) exceeds kNoiseOnly times its RMS, the noise floor, at
// a sample with probability exp(-kNoiseOnly^2), 1e-4.
constexpr double kNoiseOnly = 3.0;

// A one-way fall of the decay rate beside a neighbouring mode that held the band read back
// from beyond the typed band, while the partner band holds noise alone (its envelope at most
// kNoiseOnly times its noise floor at every estimate up to the fall's end): nothing takes the
// energy the fall seems to give, which is the neighbour's own, more damped decay passing the
// band's edge and dying out. The LMS twin with a linear mode of 1 % damping at 147 Hz, as
// large as its own at the impact (5.12 kHz, seed 1), read through 147.24:164.89 Hz held back
// from a peak at 145.34 Hz: the envelope in 1/2 of the band stood at 0.29-1.20 times its noise
// floor; the 1:2 twins' partners stand at 140-670 times theirs. The points stay marked (their
// frequencies read up to 0.18 Hz low, 11 times their stated uncertainty), under the right
// reason.
void neighbour_leak(Exchange& x, const std::vector<Estimate>& est, double held_by,
                    const signal::Band& typed, const BandSetting& s, Quantity measured,
                    signal::FftCache& cache) {
  if (!x.found() || !x.one_way || !(held_by > 0) || (held_by >= typed.lo && held_by <= typed.hi))
    return;
  const signal::Band sub{s.band.lo * x.partner, s.band.hi * x.partner};
  const signal::BandSignal zs = band_signal(s.channel, measured, sub, s.options, cache);
  const EnvelopePhase ep = envelope_phase(zs.baseband, zs.carrier_hz, zs.dt);
  const BandSetting sp = band_setting(s.channel, sub, s.options, zs);
  const double noise = noise_floor(ep, sp);
  double most = 0;
  for (const Estimate& e : est) {
    if (e.t > x.end_t) break;
    const auto j =
        std::clamp<Eigen::Index>(static_cast<Eigen::Index>(e.t / zs.dt), 0, ep.amp.size() - 1);
    most = std::max(most, ep.amp(j) / noise);
  }
  if (!(most <= kNoiseOnly)) return;
  x.leak_hz = held_by;
  x.partner_snr = most;
}

// After an exchange's last turn the band's rate relaxes to its own while the partner still
// holds energy; where the partner is a mode in tune it keeps draining the band for as long as
// it rings (in the 1:2 twin in tune with mode 2 damped 0.2 %, alpha 3e9, struck as a hammer
// strikes, the rate relaxed from 2.9 to 1.05 times mode 1's own over 1.2 s, and those points
// read damping up to 47 % above mode 1's, unmarked). The relaxation after `x.end_t` counts as
// the exchange's, as a one-way drain does, where the estimates clearly above the later ones'
// own rate are drained_in_quadrature by the partner (at least 5 of them).
void extend_through_drain(Exchange& x, const std::vector<const Estimate*>& seen, double typical,
                          const BandSetting& s, Quantity measured, signal::FftCache& cache) {
  std::vector<const Estimate*> known;
  for (const Estimate* e : seen)
    if (e->t > x.end_t && e->sigma_std <= typical) known.push_back(e);
  if (known.size() < 6) return;
  const double own = own_rate(known);
  std::vector<const Estimate*> during;
  for (const Estimate* e : known) {
    if (!(e->sigma > own && rates_apart(e->sigma, e->sigma_std, own, 0.0, typical))) break;
    during.push_back(e);
  }
  if (during.size() < 5) return;
  if (drained_in_quadrature(during, own, x.partner, s, measured, cache)) x.end_t = during.back()->t;
}

// An exchange whose swings no fit follows. Where the partner is detuned from n times the band's
// mode, energy passes back and forth at about the detuning d, and the envelope swings at that
// rate. In the double beam's twins with mode 2 1.5 % off 2 f1 (alpha 2e9-3e9) the decay rate swung
// between -5 and 8 times mode 1's own every 0.19-0.27 s, as fast as the shortest window (4 / the
// band's noise bandwidth, 0.235 s): no window followed it, every point's fit took the swing for
// misfit, none showed a turn, and the first 0.3-0.75 s were dropped for their damping uncertainty
// (up to 61 %), keeping 0.69-0.80 of the envelope's decades. The power bookkeeping of
// drained_in_quadrature holds at every instant: the band's decay rate above its own is
// kappa d(t), d = Im(z_hi conj(z_lo)^n) / |z_this|^2 (both as displacement), kappa a constant of
// the coupling and the sensor. So ln A = a + b t + c t^2 - kappa D(t), D the integral of d: the
// exchange is where, over the run of estimates at the start that miss the damping limit (three
// or more), D explains at least kExplained of what a cubic in time leaves of ln A (least squares
// on the grid; a cubic, not the quadratic above, so that a smooth bend of the mode's own decay is
// not left for a smooth D to explain). In those twins it explained 0.979-0.998. A neighbour
// merely beside it at n times (or 1/n) the band turns d at its own beat with no swing of ln A to
// follow; a harmonic the structure or the sensor makes quasi-statically has d near 0.
constexpr double kExplained = 0.9;
// An exchange takes energy and gives it back: the drive d reaches at least kBothWays of its
// largest magnitude on its other side within the run (0.46-0.85 in those twins). Without this,
// the riveted campaign's 500 Hz mode (high_hit1, acc_9003_z; a drive at 1/2 of the band, where
// the joints make twice the 122 Hz mode's frequency) had its first 30 ms, three estimates, taken
// for an exchange (explained 0.98, the drive one-signed: 0.03 of it the other way).
constexpr double kBothWays = 0.25;
// Grid samples the bookkeeping needs at least (a fit of five columns).
constexpr Eigen::Index kMinSwingSamples = 16;

// The bookkeeping of a 1:n exchange (r = n or 1/n) over [from, to], fitted: ln A = a cubic in
// time + c D(t), D the integral of the drive d from `from`.
struct Bookkeeping {
  double explained = 0;      ///< the share of what the cubic leaves of ln A that c D explains
  double c = 0;              ///< D's coefficient: the decay rate above the mode's own is -c d
  double dt = 0;             ///< the band's grid step [s]
  Eigen::VectorXd integral;  ///< D on the band's grid, 0 before `from` [s]
  /// The integral of the drive's other part, Re(z_hi conj(z_lo)^n) / |z_this|^2, signed so that
  /// c times it is the pull's part of the band's phase (D's grid, 0 before `from`) [s].
  Eigen::VectorXd pull_integral;
};

// The bookkeeping of a 1:n exchange over [from, to] (the share of what a cubic in time leaves of
// the band's ln A there that the integral of the drive explains), D carried on to the grid's
// end; explained 0 where the partner band cannot be read or, with `both_ways`, the drive does
// not pass both ways there.
Bookkeeping bookkeeping(double from, double to, double r, const BandSetting& s, Quantity measured,
                        signal::FftCache& cache, bool both_ways) {
  Bookkeeping out;
  const std::optional<DriveBands> bands = drive_bands(r, s, measured, cache);
  if (!bands) return out;
  const signal::BandSignal &hi = bands->hi(), &lo = bands->lo(), &zb = bands->own;
  const bool upper = bands->upper;
  const int n = bands->n;
  const Eigen::Index grid = zb.baseband.size();
  const auto j0 = std::max<Eigen::Index>(0, static_cast<Eigen::Index>(std::ceil(from / zb.dt)));
  const auto j1 =
      std::min<Eigen::Index>(grid - 1, static_cast<Eigen::Index>(std::floor(to / zb.dt)));
  if (j1 - j0 + 1 < kMinSwingSamples) return out;
  const Eigen::Index m = j1 - j0 + 1;
  // Columns: 1, x, x^2, x^3 (x the time scaled to [-1, 1]) and D; y = ln A.
  Eigen::MatrixXd design(m, 5);
  Eigen::VectorXd y(m), integral = Eigen::VectorXd::Zero(grid), pull = Eigen::VectorXd::Zero(grid);
  const double mid = 0.5 * (from + to), half = 0.5 * (to - from);
  // The slow flow of the 1:n coupling: d(ln z_this)/dt = i k q with k real, q = z_hi conj(z_lo)^n
  // / |z_this|^2 in the lower band, conj(q) in the upper. Its real part, -k Im q (k Im q), is the
  // rate of ln A, c d; its imaginary part, k Re q (the same), the rate of the phase: -c Re q in
  // the lower band, c Re q in the upper.
  const double pull_sign = upper ? -1.0 : 1.0;
  double previous = 0, previous_pull = 0, gives = 0, takes = 0;
  for (Eigen::Index j = j0; j < grid; ++j) {
    const double t = static_cast<double>(j) * zb.dt;
    const std::complex<double> h = interpolated(hi, t), l = interpolated(lo, t);
    const double own = std::norm(upper ? l : h);
    if (!(own > 0) && j <= j1) return out;
    std::complex<double> l_n = std::conj(l);
    for (int i = 1; i < n; ++i) l_n *= std::conj(l);
    const std::complex<double> q =
        own > 0 ? h * l_n * std::polar(1.0, kTwoPi * bands->beat_hz * t) / own : 0.0;
    const double d = q.imag(), p = pull_sign * q.real();
    if (j > j0) {
      integral(j) = integral(j - 1) + 0.5 * (d + previous) * zb.dt;
      pull(j) = pull(j - 1) + 0.5 * (p + previous_pull) * zb.dt;
    }
    previous = d;
    previous_pull = p;
    if (j > j1) continue;
    gives = std::max(gives, d);
    takes = std::min(takes, d);
    const double x = (t - mid) / half;
    design.row(j - j0) << 1.0, x, x * x, x * x * x, integral(j);
    y(j - j0) = 0.5 * std::log(own);
  }
  // The power passes both ways (an exchange takes and gives back).
  if (both_ways && !(std::min(gives, -takes) >= kBothWays * std::max(gives, -takes))) return out;
  const auto fit = [&](Eigen::Index columns) {
    const Eigen::MatrixXd a = design.leftCols(columns);
    return Eigen::VectorXd(a.colPivHouseholderQr().solve(y));
  };
  const Eigen::VectorXd cubic = fit(4), with_d = fit(5);
  const double trend = (y - design.leftCols(4) * cubic).squaredNorm();
  if (!(trend > 0)) return out;
  out.explained = 1.0 - (y - design * with_d).squaredNorm() / trend;
  out.c = with_d(4);
  out.dt = zb.dt;
  out.integral = std::move(integral);
  out.pull_integral = std::move(pull);
  return out;
}

// After an exchange the partner still takes energy while it rings, less and less: the band's
// decay rate relaxes to the mode's own. The exchange's bookkeeping (its drive's integral D and
// coefficient c, fitted over the exchange, without asking the drive to pass both ways: a
// partner in tune takes energy one way) predicts what that transfer adds to each later
// estimate's decay rate: the estimate's own local fit (estimate_hilbert's degree, stride and
// offset) applied to c D. In the 1:2 twin in tune (mode 2 at 244 Hz, damped 0.2 %, alpha 1e9)
// it predicted 16.8, 12.9 and 9.7 % of the first three points' decay rates after the exchange,
// whose rates exceeded mode 1's own by 16.9, 12.8 and 9.9 % of the rate read. Over the 72
// twins of the double beam (alpha 1e9-3e9, mode 2 0-1.5 % off 2 f1, damped 0.2 and 0.6 %) it
// explained 0.957-1.000 of the exchange in 70; in the other two (alpha 2e9 in tune, 0.6 %),
// 0.895 and 0.898, under kExplained, nothing is predicted. The same partner pulls the band's
// phase (the drive's other part, c times its integral P): after the exchange the points read the
// mode's frequency plus that pull, which the same local fit applied to c P predicts. In the twin
// in tune (alpha 1e9, mode 2 damped 0.2 %) it predicted 0.0737, 0.0620, 0.0510 and 0.0413 Hz at
// the first four points after the exchange, which read 0.0739, 0.0618, 0.0510 and 0.0410 Hz above
// mode 1's 122 Hz (13.2, 9.1, 6.4 and 9.3 times their stated k = 3 uncertainty).
Relaxation relaxation_after(const Exchange& x, const BandSetting& s, Quantity measured,
                            signal::FftCache& cache) {
  Relaxation out;
  if (!x.found() || x.leak_hz > 0 || !std::isfinite(x.end_t)) return out;
  const Bookkeeping b = bookkeeping(s.start, x.end_t, x.partner, s, measured, cache, false);
  if (!(b.explained >= kExplained)) return out;
  out.end_t = x.end_t;
  out.dt = b.dt;
  out.degree = s.options.degree;
  out.log_amp = b.c * b.integral;
  out.phase = b.c * b.pull_integral;
  return out;
}

Transfer Relaxation::at(const Estimate& e) const {
  if (!found() || !(e.t > end_t) || !(e.window > 0)) return {};
  const Eigen::Index stride =
      std::max<Eigen::Index>(1, static_cast<Eigen::Index>(e.window / dt) / 48);
  const auto fits = signal::fit_local_pair(log_amp, phase, 0.0, dt, e.centre, e.window / 2, degree,
                                           1.0, stride, (e.t - e.centre) / (e.window / 2));
  return {-fits[0].slope, fits[1].slope};
}

Exchange swinging_exchange(const std::vector<Estimate>& est, double noise, const BandSetting& s,
                           Quantity measured, signal::FftCache& cache) {
  Exchange x;
  // The run of estimates above the noise threshold at the start whose decay rate misses the
  // damping limit (or does not decay).
  double end = -std::numeric_limits<double>::infinity();
  size_t missed = 0;
  for (const Estimate& e : est) {
    if (!(std::exp(e.log_amp) >= s.options.snr_min * noise)) continue;
    if (std::isfinite(e.sigma) && e.sigma > 0 &&
        e.sigma_std <= s.options.max_damping_rel_std * e.sigma)
      break;
    end = e.t;
    ++missed;
  }
  if (missed < 3) return x;
  for (const double r : {2.0, 0.5}) {
    const double explained = bookkeeping(s.start, end, r, s, measured, cache, true).explained;
    if (explained >= kExplained) {
      x.partner = r;
      x.swings = true;
      x.explained = explained;
      x.end_t = end;
      return x;
    }
  }
  return x;
}

// The turns of the decay rate along the estimates above the noise threshold (a zig-zag: a
// turn is confirmed once a later estimate lies clearly the other way of the running
// extreme), and where the envelope grows.
Exchange exchange_of(const std::vector<Estimate>& est, double noise, const BandSetting& s,
                     Quantity measured, signal::FftCache& cache) {
  Exchange x;
  std::vector<const Estimate*> seen;
  std::vector<double> rates;
  for (const Estimate& e : est) {
    if (!std::isfinite(e.sigma) || !std::isfinite(e.sigma_std) || !std::isfinite(e.omega_d) ||
        !(e.omega_d > 0) || !(std::exp(e.log_amp) >= s.options.snr_min * noise))
      continue;
    seen.push_back(&e);
    rates.push_back(std::abs(e.sigma));
  }
  if (seen.size() < 4) return x;
  const double typical = quantile(rates, 0.5);
  const auto apart = [&](const Estimate& a, const Estimate& b) {
    return rates_apart(a.sigma, a.sigma_std, b.sigma, b.sigma_std, typical);
  };
  // A rate known to better than the typical rate itself.
  const auto known = [&](const Estimate& e) { return e.sigma_std <= typical; };
  // The zig-zag runs over the rates known to better than the typical rate itself: a first
  // estimate of 1.6 +- 7.6 1/s (typical 2.3) once stood as the running minimum that no later
  // rate could lie clearly above.
  const Estimate *lo = nullptr, *hi = nullptr, *extreme = nullptr;
  int dir = 0;  // +1 rising, -1 falling, 0 not yet known
  for (const Estimate* e : seen) {
    if (e->sigma + kExchangeSigmas * e->sigma_std < -kExchangeRel * typical) {
      x.grows = true;
      x.end_t = std::max(x.end_t, e->t);
    }
    if (!known(*e)) continue;
    if (lo == nullptr) {
      lo = hi = e;
      continue;
    }
    if (dir == 0) {
      if (e->sigma > lo->sigma && apart(*e, *lo)) {
        dir = 1, extreme = e;
      } else if (e->sigma < hi->sigma && apart(*e, *hi)) {
        dir = -1, extreme = e;
      } else {
        if (e->sigma < lo->sigma) lo = e;
        if (e->sigma > hi->sigma) hi = e;
      }
      continue;
    }
    if ((e->sigma - extreme->sigma) * dir >= 0) {
      extreme = e;
    } else if (apart(*e, *extreme)) {
      x.turns.push_back({extreme, dir > 0});
      x.end_t = std::max(x.end_t, extreme->t);
      dir = -dir;
      extreme = e;
    }
  }
  // After its last turn the decay rate relaxes to the mode's own while the partner still
  // holds energy: the exchange lasts until the first rate within the turns' tolerance of the
  // median of those after it. (A rate that only falls from the start is what a joint's
  // damping does as the amplitude falls: on the bench record's nonlinear 58 Hz mode, taking
  // such a fall for an exchange by itself marked 31 points; one_way_exchange asks the partner.)
  if (x.turns.empty() && !x.grows) return one_way_exchange(seen, typical, s, measured, cache);
  std::vector<const Estimate*> later;
  std::vector<double> later_rates;
  for (const Estimate* e : seen) {
    if (e->t > x.end_t && known(*e)) {
      later.push_back(e);
      later_rates.push_back(e->sigma);
    }
  }
  const double settled = later_rates.empty() ? 0.0 : quantile(later_rates, 0.5);
  for (const Estimate* e : later) {
    if (!rates_apart(e->sigma, e->sigma_std, settled, 0.0, typical)) break;
    x.end_t = e->t;
  }
  // The rates up to the exchange's end and the one after it, which shows where it ends.
  std::vector<const Estimate*> during;
  for (const Estimate* e : seen) {
    if (e->t <= x.end_t || (!during.empty() && during.back()->t <= x.end_t)) during.push_back(e);
  }
  const bool one_turn = x.turns.size() == 1 && !x.grows;
  for (const double r : {2.0, 0.5, 3.0, 1 / 3.0}) {
    if (takes_energy(during, r, one_turn, x.grows, x.turns, s, measured, cache)) {
      x.partner = r;
      break;
    }
  }
  if (!x.found() && one_turn && !x.turns.front().peak && !later_rates.empty() &&
      x.turns.front().at->sigma < settled &&
      rates_apart(x.turns.front().at->sigma, x.turns.front().at->sigma_std, settled, 0.0,
                  typical)) {
    x.partner = fed_at_a_dip(during, x.turns.front(), s, measured, cache);
    if (x.found() && !partner_holds_energy(x, s, measured, cache)) x.partner = 0;
    x.fed_dip = x.found();
  }
  if (!x.found()) return one_way_exchange(seen, typical, s, measured, cache);
  if (!x.turns.empty()) extend_through_drain(x, seen, typical, s, measured, cache);
  return x;
}

}  // namespace jointlab::modal::ringdown_detail
