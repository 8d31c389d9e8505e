// Two modes in one band: the beat of a second mode with the band's mode, found in the
// spectrum and confirmed in the time domain (two_modes), or, beyond a typed edge the band
// moved past, in the time domain alone (edge_beat); see ringdown_detail.h.
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Dense>

#include "jointlab/modal/ringdown_detail.h"
#include "jointlab/signal/band_analytic.h"
#include "jointlab/signal/local_poly.h"

namespace jointlab::modal::ringdown_detail {

// Two modes in one band. A second mode the band passes beside the one it names adds to the
// band signal: z = z1 (1 + rho), rho = z2 / z1 = c exp(i dw t), dw = 2 pi (f2 - f1). Then
// ln A + i theta carries ln(1 + rho), whose part at dw is rho itself (exactly, for c < 1):
// the envelope's decay rate and the frequency both oscillate at the difference frequency, by
// c dw. Local fits shorter than the beat follow that oscillation and state their own noise
// alone: on a 50 Hz mode with a 52 Hz one at a fifth of its size in 40:60 Hz, the damping read
// 0.0089 +- 0.00026 against a true 0.005, none of the points within its uncertainty; with a
// 51 Hz one at 5 %, it swung between 0.00205 and 0.00398 (true 0.003) at +-0.7 %.
// The second mode is found in the measured samples' spectrum (a resolved peak) and confirmed in
// the time domain (the part of ln A + i theta at the difference frequency, over four beats at a
// time); what the beat then moves each point's decay rate and frequency by, fitted over the
// point's own window as the signal is, is added to its uncertainty, so that a point the beat
// moves by more than the damping limit drops out (ringdown_test.cc, RingdownTwoModes).

// Spectral peaks of modes other than the strongest in `band`: local maxima of the measured
// samples' spectrum (ChannelSpectrum::measured) times the band's gain, at least two bins from
// the strongest and kAbove times above the spectrum's lower decile around the band (the
// ripple of the noise floor is no peak), highest first, at most `count`. Each is (frequency
// [Hz], its height over the strongest one's); `main_hz` is the strongest one's frequency. The
// frequencies are refined by a parabola through ln |X| at the three bins around each.
BandPeaks band_peaks(const ChannelSpectrum& channel, const signal::Band& band, double taper,
                     size_t count) {
  // A power 10 times the lower decile, as neighbour_peak asks.
  const double kAbove = std::sqrt(10.0);
  BandPeaks out;
  if (channel.measured.size() < 8) return out;
  const double df = channel.measured_df();
  const Eigen::Index last = channel.measured.size() - 2;
  const auto bin = [&](double f) { return channel.measured_bin(f, 1, last); };
  const Eigen::Index k0 = bin(band.lo), k1 = bin(band.hi);
  if (k1 < k0 + 6) return out;
  const auto mag = [&](Eigen::Index k) { return std::abs(channel.measured(k)); };
  Eigen::VectorXd weighted(k1 - k0 + 3);  // bins k0 - 1 .. k1 + 1
  for (Eigen::Index k = k0 - 1; k <= k1 + 1; ++k) {
    weighted(k - k0 + 1) = mag(k) * signal::band_gain(band, taper, static_cast<double>(k) * df);
  }
  const auto wt = [&](Eigen::Index k) { return weighted(k - k0 + 1); };
  Eigen::Index main = k0;
  for (Eigen::Index k = k0; k <= k1; ++k) {
    if (wt(k) > wt(main)) main = k;
  }
  if (!(wt(main) > 0) || !std::isfinite(wt(main))) return out;
  const double width = band.hi - band.lo;
  std::vector<double> around;
  for (Eigen::Index k = bin(band.lo - width); k <= bin(band.hi + width); ++k) {
    around.push_back(mag(k));
  }
  const double low = quantile(around, 0.1);
  const auto refined = [&](Eigen::Index k) {
    const double a = std::log(std::max(mag(k - 1), 1e-300)), b = std::log(std::max(mag(k), 1e-300)),
                 c = std::log(std::max(mag(k + 1), 1e-300));
    const double den = a - 2 * b + c;
    const double d = den < 0 ? std::clamp(0.5 * (a - c) / den, -0.5, 0.5) : 0.0;
    return (static_cast<double>(k) + d) * df;
  };
  out.main_hz = refined(main);
  std::vector<std::pair<double, Eigen::Index>> found;
  for (Eigen::Index k = k0; k <= k1; ++k) {
    if (std::abs(k - main) < 2 || !(wt(k) > wt(k - 1)) || !(wt(k) >= wt(k + 1)) ||
        !(wt(k) >= kAbove * low)) {
      continue;
    }
    found.emplace_back(wt(k), k);
  }
  std::sort(found.begin(), found.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  for (size_t i = 0; i < found.size() && i < count; ++i) {
    out.others.emplace_back(refined(found[i].second), found[i].first / wt(main));
  }
  return out;
}

// The beat's series at grid node j (time t [s], size c < 1): ln|1 + c e^{i psi}| and
// arg(1 + c e^{i psi}) for psi = dw t and dw t + pi / 2.
void set_beat_at(Beat& beat, Eigen::Index j, double t, double c) {
  const std::complex<double> a = 1.0 + std::polar(c, beat.dw * t),
                             b = 1.0 + std::polar(c, beat.dw * t + 0.5 * std::numbers::pi);
  beat.u0(j) = std::log(std::abs(a));
  beat.u1(j) = std::log(std::abs(b));
  beat.v0(j) = std::arg(a);
  beat.v1(j) = std::arg(b);
}

// The beat of the band's mode with a second mode `dw` [rad/s] away, from ln A + i theta: over
// blocks of kBeats beats, every beat, a least-squares fit of a complex quadratic (the mode's own
// slowly changing decay and phase), exp(+-i dw t) and the same times t (a beat whose size
// changes along the block); the larger of the two exponentials' magnitudes at the block's
// centre is c (exp(-i dw t) where the second mode is the larger, c then its inverse). A
// block's c counts where it is kClear times what the noise alone gives a fit of its samples
// (blocks below the noise threshold are not fitted) and kBeside times the largest part of the
// same fit at a cycle fewer and a cycle more in the block (3/4 and 5/4 of dw), where a beat at
// dw has little: what the quadratic leaves of a mode whose frequency drifts fast spreads over
// all of them. A drifting single mode's spectrum ripples with peaks of its own, and without
// this check the LMS twin (ringdown_test.cc) was read as beating with a "mode" at 151.5 Hz,
// 2 % of its size, and lost its backbone; so did the stress and acceptance records (34 tests
// failed). In blocks of two beats a cycle fewer is one cycle, which the quadratic absorbs in
// part: the check then failed on the twins of two modes as well. c is interpolated between the
// centres of the blocks that count and held beyond them: a beat the noise hides at low
// amplitude is still there (two linear modes keep the ratio of their amplitudes changing
// exponentially). A beat slower than a quarter of the usable span is not looked for.
// The returned series on the grid are ln|1 + c e^{i psi}| and arg(1 + c e^{i psi}) for
// psi = dw t and dw t + pi / 2: the beat's effect on ln A and theta in two phases, so that a
// fit of both over a window gives the amplitude of what it moves a slope by.
Beat beat_of(const EnvelopePhase& ep, const BandSetting& s, double noise, double dw) {
  constexpr double kClear = 4.0, kBeside = 3.0, kBeats = 4.0;
  Beat beat;
  beat.dw = dw;
  const Eigen::Index grid = ep.log_amp.size();
  const double period = kTwoPi / std::abs(dw);
  const auto block = static_cast<Eigen::Index>(std::round(kBeats * period / s.dt));
  const auto hop = std::max<Eigen::Index>(1, block / static_cast<Eigen::Index>(kBeats));
  const auto j_start =
      std::max<Eigen::Index>(0, static_cast<Eigen::Index>(std::ceil(s.start / s.dt)));
  const auto j_stop = std::min<Eigen::Index>(grid - 1, static_cast<Eigen::Index>(s.stop / s.dt));
  if (block < 24 || j_stop - j_start + 1 < block) return beat;
  std::vector<double> centres, cs;
  std::vector<std::pair<Eigen::Index, Eigen::Index>> others;  // blocks [first, last] of it
  // Columns: the quadratic; exp(+-i dw tau), then times tau (a beat whose size changes along
  // the block); exp(+-i f dw tau) at the checks' f, a cycle fewer and a cycle more in the block.
  Eigen::MatrixXcd design(block, 11);
  for (Eigen::Index i = 0; i < block; ++i) {
    const double tau = (static_cast<double>(i) - 0.5 * static_cast<double>(block - 1)) * s.dt;
    const double x = tau / (kBeats * period);
    design(i, 0) = 1.0;
    design(i, 1) = x;
    design(i, 2) = x * x;
    design(i, 3) = std::polar(1.0, dw * tau);
    design(i, 4) = std::polar(1.0, -dw * tau);
    design(i, 5) = x * design(i, 3);
    design(i, 6) = x * design(i, 4);
    for (int h = 0; h < 2; ++h) {
      const double f = 1 + (h == 0 ? -1.0 : 1.0) / kBeats;
      design(i, 7 + 2 * h) = std::polar(1.0, f * dw * tau);
      design(i, 8 + 2 * h) = std::polar(1.0, -f * dw * tau);
    }
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXcd> qr(design);
  // Independent noise samples in a block, for what noise alone gives |coefficient|.
  const double independent =
      std::max(1.0, static_cast<double>(block) / std::max(1.0, s.correlation));
  Eigen::VectorXcd y(block);
  for (Eigen::Index j = j_start; j + block - 1 <= j_stop; j += hop) {
    double weakest = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < block; ++i) {
      y(i) = {ep.log_amp(j + i), ep.theta(j + i)};
      weakest = std::min(weakest, ep.amp(j + i));
    }
    if (!(weakest >= s.options.snr_min * noise)) continue;  // the noise's ln A is no beat
    const Eigen::VectorXcd coef = qr.solve(y);
    const double c = std::max(std::abs(coef(3)), std::abs(coef(4)));
    const double by_noise = noise / weakest / std::sqrt(independent);
    const double beside =
        std::max({std::abs(coef(7)), std::abs(coef(8)), std::abs(coef(9)), std::abs(coef(10))});
    if (!(std::isfinite(c) && c > kClear * by_noise && c > kBeside * beside)) continue;
    centres.push_back((static_cast<double>(j) + 0.5 * static_cast<double>(block - 1)) * s.dt);
    cs.push_back(c);
    if (std::abs(coef(4)) > std::abs(coef(3))) others.emplace_back(j, j + block - 1);
  }
  if (cs.empty()) return beat;
  beat.c_max = *std::max_element(cs.begin(), cs.end());
  beat.c_first = cs.front();
  beat.u0.resize(grid);
  beat.u1.resize(grid);
  beat.v0.resize(grid);
  beat.v1.resize(grid);
  beat.other = Eigen::VectorXi::Zero(grid);
  for (const auto& [first, last] : others) beat.other.segment(first, last - first + 1).setOnes();
  size_t k = 0;
  for (Eigen::Index j = 0; j < grid; ++j) {
    const double t = static_cast<double>(j) * s.dt;
    while (k + 1 < centres.size() && centres[k + 1] <= t) ++k;
    double c = cs[k];
    if (t > centres[k] && k + 1 < centres.size()) {
      const double w = (t - centres[k]) / (centres[k + 1] - centres[k]);
      c = (1 - w) * cs[k] + w * cs[k + 1];
    }
    c = std::min(c, 0.99);  // past 1 the other exponential is the beat (c its inverse)
    set_beat_at(beat, j, t, c);
  }
  return beat;
}

// What the beat moves each estimate's decay rate and angular frequency by (amplitudes over
// the beat's phase), fitted over its window as the signal is; infinite where the window
// reaches where the second mode is the larger (Beat::other).
std::vector<std::pair<double, double>> beat_errors(const std::vector<Estimate>& est,
                                                   const Beat& beat, double dt, int degree) {
  std::vector<std::pair<double, double>> out(est.size(), {0.0, 0.0});
  const Eigen::Index grid = beat.u0.size();
  for (size_t i = 0; i < est.size(); ++i) {
    const Estimate& e = est[i];
    if (!(e.window > 0) || !std::isfinite(e.window)) continue;
    if (static_cast<Eigen::Index>(e.window / dt) < degree + 4 || grid < degree + 4) continue;
    const auto [half, offset, stride, j0, j1] = window_on_grid(e, dt, grid);
    if (beat.other.segment(j0, j1 - j0 + 1).maxCoeff() > 0) {
      constexpr double kInf = std::numeric_limits<double>::infinity();
      out[i] = {kInf, kInf};
      continue;
    }
    const auto [a0, a1, p0, p1] =
        signal::fit_local_quad({&beat.u0, &beat.u1, &beat.v0, &beat.v1}, 0.0, dt, e.centre, half,
                               degree, 1.0, stride, offset);
    out[i] = {std::hypot(a0.slope, a1.slope), std::hypot(p0.slope, p1.slope)};
  }
  return out;
}

// A "second mode" f2 whose distance from the band's mode f1 is the frequency of a spectral
// peak below the band that is stronger than f2's is a sideband: the band's mode
// amplitude-modulated by that mode (the Brake-Reuss beam's 1527 Hz mode shows peaks at 1447
// and 1607 Hz, the 80.5 Hz mode's frequency either side), not a mode of its own. The
// modulating peak is looked for within 3 bins (or 1 % of the spacing) of |f2 - f1|.
bool is_sideband(const ChannelSpectrum& channel, const signal::Band& read, double f1, double f2) {
  const double fm = std::abs(f2 - f1);
  const double df = channel.measured_df();
  const Eigen::Index n = channel.measured.size();
  if (n < 8 || !(df > 0)) return false;
  const auto mag = [&](Eigen::Index k) { return std::abs(channel.measured(k)); };
  const auto bin = [&](double f) { return channel.measured_bin(f, 1, n - 2); };
  const Eigen::Index k2 = bin(f2);
  // A stronger local maximum within 3 bins (or 1 % of f) of f.
  const auto stronger_peak_at = [&](double f) {
    const auto reach = std::max<Eigen::Index>(3, static_cast<Eigen::Index>(0.01 * f / df));
    const Eigen::Index km = bin(f);
    for (Eigen::Index k = std::max<Eigen::Index>(1, km - reach);
         k <= std::min<Eigen::Index>(n - 2, km + reach); ++k) {
      if (mag(k) > mag(k - 1) && mag(k) >= mag(k + 1) && mag(k) > mag(k2)) return true;
    }
    return false;
  };
  if (fm < read.lo && stronger_peak_at(fm)) return true;
  // A harmonic (2 to 6 times) of a stronger peak below the band is no mode either.
  for (int h = 2; h <= 6; ++h) {
    if (f2 / h < read.lo && f2 / h > 3 * df && stronger_peak_at(f2 / h)) return true;
  }
  return false;
}

// The second mode whose beat matters in the band read: of the band's other spectral peaks
// (band_peaks, the three highest), the one whose beat (beat_of) moves the most usable
// estimates' decay rates by more than their own one-sigma uncertainty; none where it moves
// none so (a beat below the uncertainty is left as it is: the records of single modes are
// then read as before). `errors` holds, per estimate, what it moves the decay rate and the
// angular frequency by.
TwoModes two_modes(const std::vector<Estimate>& est, const ChannelSpectrum& channel,
                   const signal::Band& read, const EnvelopePhase& ep, const BandSetting& s,
                   double noise) {
  TwoModes best;
  if (est.empty()) return best;
  const BandPeaks peaks = band_peaks(channel, read, s.options.taper, 3);
  for (const auto& [f2, ratio] : peaks.others) {
    const double dw = kTwoPi * (f2 - peaks.main_hz);
    if (!(std::abs(dw) > 0) || is_sideband(channel, read, peaks.main_hz, f2)) continue;
    const Beat beat = beat_of(ep, s, noise, dw);
    if (!beat.found()) continue;
    std::vector<std::pair<double, double>> errors = beat_errors(est, beat, s.dt, s.options.degree);
    size_t moved = 0;
    for (size_t i = 0; i < est.size(); ++i) {
      moved += usable(est[i], noise, s.options.snr_min) && !(errors[i].first <= est[i].sigma_std);
    }
    if (moved > best.moved) {
      best = {peaks.main_hz,    f2, ratio, std::abs(f2 - peaks.main_hz), beat.c_first, moved,
              std::move(errors)};
    }
  }
  return best;
}

bool beats_with_second_mode(const std::vector<Estimate>& est, const ChannelSpectrum& channel,
                            const signal::Band& read, const EnvelopePhase& ep, const BandSetting& s,
                            double noise) {
  return two_modes(est, channel, read, ep, s, noise).found();
}

// The summary's note on a second mode in the band (two_modes), with a band that would
// leave it out: its edge on the second mode's side a half-power width short of that mode's
// peak (the gain at the edge is 2 %, two of the edge's standard deviations past half gain) and
// as wide as lets the mode, with
// three half-power half-widths either side, lie in its flat part. The half-width is read from
// the measured spectrum's peak (half_power_width), not from the estimates: the beat moves
// their decay rates.
// Where no such band exists the note says the two are too close for a band to part them.
std::string beat_message(const TwoModes& two, const ChannelSpectrum& channel,
                         const signal::Band& read, const RingdownOptions& options, size_t left,
                         signal::FftCache& cache) {
  std::string note = fmt::format(
      "the band {:.2f}:{:.2f} Hz holds a second mode at {:.2f} Hz ({:.0f} % of this one's "
      "spectral peak, about {:.2g} % of its amplitude where first seen): its beat with this mode "
      "makes "
      "the decay rate and the frequency oscillate at {:.2f} Hz, so points it moves by more than "
      "the {:.1f} % damping limit are left out ({} of those that met it)",
      read.lo, read.hi, two.f2, 100 * two.ratio, 100 * two.c_first, two.beat_hz,
      100 * options.max_damping_rel_std, left);
  const double f1 = two.f1;
  const double hp = half_power_width(channel, f1, cache);
  const double m = 1.5 * hp;
  // The edge a half-power width short of the second mode's peak, so that the peak lies beyond
  // the typed band, where a band following the mode stops short of it (follow_mode).
  const double room = std::abs(two.f2 - f1) - m - hp;
  const double width = room / options.taper;  // the widest band whose flat part ends there
  if (!(room > 0) || !(width >= kBandWidths * hp)) {
    return note + fmt::format(
                      "; the two are too close for a band to read this mode without the other "
                      "({:.2f} Hz apart: a band that leaves it out would be narrower than {:g} "
                      "half-power widths of this mode, {:.3g} Hz)",
                      two.beat_hz, kBandWidths, kBandWidths * hp);
  }
  const double edge = two.f2 > f1 ? two.f2 - hp : two.f2 + hp;
  const double lo = two.f2 > f1 ? edge - width : edge;
  const double hi = two.f2 > f1 ? edge : edge + width;
  return note + fmt::format("; a band of {:.2f}:{:.2f} Hz would leave it out", lo, hi);
}

namespace {

// edge_beat's rule; see its comment.
namespace edge {
constexpr double kBeats = 2.0, kStep = 1.0 / 8, kClear = 4.0, kMirror = 10.0, kExplained = 0.05,
                 kAgree = 0.5;
constexpr std::array<double, 7> kRates = {0.0, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0};  // [1/s]
}  // namespace edge

// What a complex quadratic over n samples from grid node j leaves of ln A + i theta (r), and
// the quadratic's basis, orthonormal (q).
struct QuadraticRest {
  Eigen::MatrixXd q;
  Eigen::VectorXcd r;
};

QuadraticRest quadratic_rest(const EnvelopePhase& ep, Eigen::Index j, Eigen::Index n) {
  Eigen::MatrixXd poly(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x = static_cast<double>(i) / static_cast<double>(n - 1) - 0.5;
    poly(i, 0) = 1.0;
    poly(i, 1) = x;
    poly(i, 2) = x * x;
  }
  QuadraticRest out;
  out.q =
      Eigen::HouseholderQR<Eigen::MatrixXd>(poly).householderQ() * Eigen::MatrixXd::Identity(n, 3);
  out.r.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) out.r(i) = {ep.log_amp(j + i), ep.theta(j + i)};
  out.r -= out.q * (out.q.transpose() * out.r);
  return out;
}

// The fit of a quadratic's rest with e^{(+-i dw - ds) tau}, tau from the block's start (dt
// [s] apart), the two columns less their part in the quadratic: their coefficients (ab), and
// the share of the rest the fit leaves.
struct Turns {
  Eigen::Vector2cd ab;
  double share = 1;
};

Turns turns(const QuadraticRest& rest, double dw, double ds, double dt) {
  const Eigen::Index n = rest.r.size();
  Eigen::MatrixXcd e(n, 2);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double tau = static_cast<double>(i) * dt;
    e(i, 0) = std::exp(std::complex<double>(-ds * tau, dw * tau));
    e(i, 1) = std::exp(std::complex<double>(-ds * tau, -dw * tau));
  }
  e -= rest.q * (rest.q.transpose() * e);
  const Eigen::Matrix2cd gram = e.adjoint() * e;
  const Eigen::Vector2cd rhs = e.adjoint() * rest.r;
  Turns out;
  out.ab = gram.fullPivLu().solve(rhs);
  const double left = rest.r.squaredNorm();
  out.share = (left - rhs.dot(out.ab).real()) / left;
  return out;
}

// The best of edge_beat's fits over f2 and dsigma: the one that leaves the smallest share of
// the quadratic's rest, under kExplained.
struct EdgeFit {
  double share = edge::kExplained;
  std::complex<double> a = 0;       // the turn toward f2 at the block's start
  std::complex<double> mirror = 0;  // the other turn
  double dw = 0;                    // 2 pi (f2 - f1) [rad/s]
  double ds = 0;                    // dsigma [1/s]
  double f2 = 0;                    // [Hz]
};

EdgeFit best_edge_fit(const EnvelopePhase& ep, const BandSetting& s, double noise,
                      const signal::Band& typed, const signal::Band& read, double f1,
                      Eigen::Index j0, Eigen::Index j_stop) {
  EdgeFit best;
  const double w = s.options.taper * (read.hi - read.lo);
  for (const int dir : {-1, 1}) {
    const double near = dir < 0 ? typed.lo : typed.hi;
    const double far = dir < 0 ? read.lo + w / 2 : read.hi - w / 2;
    if (!(dir * (far - near) > 0) || !(dir * (near - f1) > 0)) continue;
    for (double f2 = near; dir * (far - f2) >= 0;
         f2 += dir * edge::kStep * std::abs(f2 - f1) / edge::kBeats) {
      const double dw = kTwoPi * (f2 - f1);
      const auto n = static_cast<Eigen::Index>(std::round(edge::kBeats / std::abs(f2 - f1) / s.dt));
      if (n < 24 || j0 + n - 1 > j_stop) continue;
      if (!(ep.amp.segment(j0, n).minCoeff() >= s.options.snr_min * noise)) continue;
      const QuadraticRest rest = quadratic_rest(ep, j0, n);
      if (!(rest.r.squaredNorm() > 0)) continue;
      for (const double ds : edge::kRates) {
        const Turns fit = turns(rest, dw, ds, s.dt);
        if (!fit.ab.allFinite() || !(fit.share < best.share)) continue;
        best = {fit.share, fit.ab(0), fit.ab(1), dw, ds, f2};
      }
    }
  }
  return best;
}

// Whether the fit's c stands clear of what noise alone gives it (kClear times: the noise over
// the envelope at the block's start, over the independent samples the decaying column of n
// samples holds) and of the mirror term (kMirror times).
bool clear_of_noise(const EdgeFit& fit, const EnvelopePhase& ep, const BandSetting& s, double noise,
                    Eigen::Index j0, Eigen::Index n) {
  double held = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    held += std::exp(-2 * fit.ds * static_cast<double>(i) * s.dt);
  }
  const double by_noise = noise / ep.amp(j0) / std::sqrt(std::max(1.0, held / s.correlation));
  const double c0 = std::abs(fit.a);
  return c0 > edge::kClear * by_noise && c0 > edge::kMirror * std::abs(fit.mirror);
}

// Whether the fit is one exponential along the decay, as a second mode's part is: fitted again
// (same dw and dsigma) over blocks of n samples a quarter and half a beat later, its
// coefficient must be the first one carried there, a e^{(i dw - dsigma) delta}, to within
// kAgree of it (what the steps of f2 and dsigma allow). What a quadratic leaves of a drifting
// mode's own phase turns one way over one block as well, but is no exponential: on the
// Brake-Reuss beam (acc2, its 80.5 Hz mode 0.2-0.5 Hz inside a band typed 79.5:114.5 or 80:115
// Hz) the fit passed clear_of_noise (c 0.18, the other turn c / 11.2-11.5, 2.8 % left) and took
// 14 points, 0.06-0.84 s, off the span (1.20 decades kept, 1.59 now), but its coefficient half
// a beat on is 4.6-4.7 times the one carried (|ratio - 1| 5.5-5.6). Of the best fits on the
// beam (360 bands typed 0.5-5 Hz beside or inside its modes, three channels) and on the twins
// without a neighbour, 91 are 1.1 or more off; the neighbours of 0.5-2 % damping 1.4-4.9 Hz
// below the LMS twin's band (259 caught, 5.12 and 51.2 kHz, eight seeds) stay within 0.36, as
// do the beam's real second components (a spectral bump 21 Hz below its 1766 Hz mode, 3.6 % of
// its peak over the first 0.6 s on acc2; a peak 30 Hz below the 2015 Hz mode, 2 % on acc1),
// whose beat is counted as before. A block beyond the span (j_stop) or below the noise
// threshold confirms nothing.
bool carried_along(const EdgeFit& fit, const EnvelopePhase& ep, const BandSetting& s, double noise,
                   Eigen::Index j0, Eigen::Index j_stop, Eigen::Index n) {
  for (const double beats : {0.25, 0.5}) {
    const auto shift =
        static_cast<Eigen::Index>(std::round(beats * static_cast<double>(n) / edge::kBeats));
    const Eigen::Index j1 = j0 + shift;
    if (j1 + n - 1 > j_stop || !(ep.amp.segment(j1, n).minCoeff() >= s.options.snr_min * noise)) {
      return false;
    }
    const std::complex<double> a = turns(quadratic_rest(ep, j1, n), fit.dw, fit.ds, s.dt).ab(0);
    const double delta = static_cast<double>(shift) * s.dt;
    const std::complex<double> carried =
        fit.a * std::exp(std::complex<double>(-fit.ds * delta, fit.dw * delta));
    if (!(std::abs(a / carried - 1.0) <= edge::kAgree)) return false;
  }
  return true;
}

// The confirmed fit as a beat along the span: c(t) = c e^{-dsigma (t - t0)}, t0 the block's
// start (grid node j0), held at 0.99 before and marking where it exceeds 1 as the other mode's
// (Beat::other), and what it moves each estimate by (beat_errors).
EdgeBeat confirmed_beat(const EdgeFit& fit, const std::vector<Estimate>& est, const BandSetting& s,
                        double noise, Eigen::Index grid, double f1, Eigen::Index j0) {
  EdgeBeat out;
  out.f1 = f1;
  out.f2 = fit.f2;
  out.t0 = static_cast<double>(j0) * s.dt;
  out.dsigma = fit.ds;
  const double c0 = std::abs(fit.a);
  Beat& beat = out.beat;
  beat.dw = fit.dw;
  beat.c_first = c0;
  beat.u0.resize(grid);
  beat.u1.resize(grid);
  beat.v0.resize(grid);
  beat.v1.resize(grid);
  beat.other = Eigen::VectorXi::Zero(grid);
  for (Eigen::Index j = 0; j < grid; ++j) {
    const double t = static_cast<double>(j) * s.dt;
    const double c = c0 * std::exp(-fit.ds * (t - out.t0));
    if (c >= 1) beat.other(j) = 1;
    beat.c_max = std::max(beat.c_max, std::min(c, 0.99));
    set_beat_at(beat, j, t, std::min(c, 0.99));
  }
  out.errors = beat_errors(est, beat, s.dt, s.options.degree);
  for (size_t i = 0; i < est.size(); ++i) {
    out.moved +=
        usable(est[i], noise, s.options.snr_min) && !(out.errors[i].first <= est[i].sigma_std);
  }
  return out;
}

}  // namespace

// A second mode in the part of a moved band beyond the typed band's edge. The band follows the
// mode past the edge the user typed (follow_mode) and is held back only from a neighbour the
// spectrum shows; a heavily damped one is a shoulder of the mode's skirt, no peak, and dies
// before the noise floor's fits see it (hidden_content), but beats with the mode at the start
// of the decay: the LMS twin with a mode of 1 % damping at 146 or 147 Hz, 0.1-0.3 times its
// size at the impact, read the first one or two points' damping 9-57 % high, 3.4-25 times
// their stated uncertainty. Its part of ln A + i theta is c e^{(i dw - dsigma) t} (Beat), dw =
// 2 pi (f2 - f1): it turns toward the neighbour's side alone, where what a quadratic leaves of
// a single drifting mode, and the noise, turn both ways. Over kBeats beats from the span's
// start, ln A + i theta is fitted with a complex quadratic and e^{(+-i dw - dsigma) tau}, for
// f2 from the typed edge to the moved band's half-gain point beyond it (steps of kStep of a
// block's resolution) and relative decay rates dsigma (kRates); of the fits, the one that
// leaves the smallest share of what the quadratic alone leaves. Its c at the block's start
// counts where it is kClear times what the noise gives, kMirror times the mirror term's (the
// other turn) and the fit leaves at most kExplained of the quadratic's residual. On the LMS
// twins the neighbours of 1 % damping gave c = 0.06-0.21, the mirror c / 17 to c / 46, and
// left 0.5-1.1 %; without a second mode, or beside one of 0.1-0.3 % damping held outside the
// band, no fit with c above the noise's left under 25 % (mirror at least c / 3.4). A real
// jointed beam's drifting modes leave a one-sided rest of their own: the Brake-Reuss beam's
// 80.5 and 297.7 Hz modes typed with an edge 0.2-4.5 Hz beside them (71 channel-bands above
// the noise) left 1.3 % and more, with a mirror of at least c / 6.2 where under 5 % (c / 9.7
// at most anywhere); with a cubic for the mode's part they reached c / 66, left 0.55 %. A fit
// counts only where it is one exponential along the decay (carried_along). Then
// c(t) = c e^{-dsigma (t - t0)} stands for the beat along the span (held at 0.99 before,
// marking where it exceeds 1 as the other mode's, Beat::other) and what it moves each point by
// joins the point's uncertainty as a second mode's inside the band does (two_modes).
EdgeBeat edge_beat(const std::vector<Estimate>& est, const EnvelopePhase& ep, const BandSetting& s,
                   double noise, const signal::Band& typed, const signal::Band& read) {
  const Eigen::Index grid = ep.log_amp.size();
  const auto j0 = std::max<Eigen::Index>(0, static_cast<Eigen::Index>(std::ceil(s.start / s.dt)));
  const auto j_stop = std::min<Eigen::Index>(grid - 1, static_cast<Eigen::Index>(s.stop / s.dt));
  if (j0 >= grid) return {};
  // The mode's frequency where the span starts: its first usable estimate's.
  double f1 = 0;
  for (const Estimate& e : est) {
    if (usable(e, noise, s.options.snr_min)) {
      f1 = e.omega_d / kTwoPi;
      break;
    }
  }
  if (!(f1 > 0)) return {};
  const EdgeFit fit = best_edge_fit(ep, s, noise, typed, read, f1, j0, j_stop);
  if (!(std::abs(fit.a) > 0)) return {};
  const auto n =
      static_cast<Eigen::Index>(std::round(edge::kBeats * kTwoPi / std::abs(fit.dw) / s.dt));
  if (!clear_of_noise(fit, ep, s, noise, j0, n) ||
      !carried_along(fit, ep, s, noise, j0, j_stop, n)) {
    return {};
  }
  return confirmed_beat(fit, est, s, noise, grid, f1, j0);
}

}  // namespace jointlab::modal::ringdown_detail
