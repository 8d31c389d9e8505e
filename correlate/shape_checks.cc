#include "jointlab/correlate/shape_checks.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <complex>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/correlate/mac.h"

namespace jointlab::correlate {
namespace {

// Measured modes with an entry at three sensors or more.
std::vector<Eigen::Index> counted_modes(const Eigen::Ref<const Eigen::MatrixXcd>& shapes) {
  std::vector<Eigen::Index> out;
  for (Eigen::Index i = 0; i < shapes.cols(); ++i)
    if ((shapes.col(i).array().abs() > 0.0).count() >= 3) out.push_back(i);
  return out;
}

// Best MAC of measured shape x (mode at test frequency f) over the visible model modes in the
// window.
double best_mac(const Eigen::Ref<const Eigen::VectorXcd>& x, double f,
                const Eigen::Ref<const Eigen::MatrixXd>& model,
                const Eigen::Ref<const Eigen::VectorXd>& model_f, const std::vector<char>& visible,
                double window) {
  double best = 0;
  for (Eigen::Index j = 0; j < model.cols(); ++j) {
    if (!visible[static_cast<size_t>(j)]) continue;
    if (window > 0 && std::abs(model_f(j) / f - 1) > window) continue;
    best = std::max(best, mac(x, model.col(j)));
  }
  return best;
}

struct Score {
  int matched = 0;
  double mean = 0;
};

Score score(const Eigen::MatrixXcd& shapes, const std::vector<Eigen::Index>& counted,
            const Eigen::Ref<const Eigen::VectorXd>& f,
            const Eigen::Ref<const Eigen::MatrixXd>& model,
            const Eigen::Ref<const Eigen::VectorXd>& model_f, const std::vector<char>& visible,
            double window, double strong) {
  Score s;
  for (const Eigen::Index i : counted) {
    const double b = best_mac(shapes.col(i), f(i), model, model_f, visible, window);
    s.matched += b >= strong;
    s.mean += b / static_cast<double>(counted.size());
  }
  return s;
}

// The rows of x with an entry (a measured value is never exactly zero).
std::vector<Eigen::Index> entries(const Eigen::Ref<const Eigen::VectorXcd>& x) {
  std::vector<Eigen::Index> out;
  for (Eigen::Index c = 0; c < x.size(); ++c)
    if (std::abs(x(c)) > 0) out.push_back(c);
  return out;
}

// f(flip) for each of `rows` alone, then each pair of them: the reversals both checks try.
template <class F>
void for_each_reversal(const std::vector<Eigen::Index>& rows, F&& f) {
  for (const Eigen::Index c : rows) f(std::vector<Eigen::Index>{c});
  for (size_t a = 0; a < rows.size(); ++a)
    for (size_t b = a + 1; b < rows.size(); ++b) f(std::vector<Eigen::Index>{rows[a], rows[b]});
}

}  // namespace

Reversal best_reversal(const Eigen::Ref<const Eigen::VectorXcd>& measured,
                       const Eigen::Ref<const Eigen::VectorXd>& model) {
  Reversal out;
  const std::vector<Eigen::Index> rows = entries(measured);
  if (rows.size() < 3) return out;
  Eigen::VectorXcd x = measured;
  for_each_reversal(rows, [&](const std::vector<Eigen::Index>& flip) {
    for (const Eigen::Index c : flip) x(c) = -x(c);
    const double m = mac(x, model);
    for (const Eigen::Index c : flip) x(c) = -x(c);
    if (m > out.mac + 1e-9) {
      out.mac = m;
      out.channels.assign(flip.begin(), flip.end());
    }
  });
  return out;
}

SignCheck check_channel_signs(const Eigen::Ref<const Eigen::MatrixXcd>& measured_shapes,
                              const Eigen::Ref<const Eigen::VectorXd>& test_frequency_hz,
                              const Eigen::Ref<const Eigen::MatrixXd>& model_at_sensors,
                              const Eigen::Ref<const Eigen::VectorXd>& model_frequency_hz,
                              const std::vector<int>& hidden, double frequency_window,
                              double strong_mac) {
  assert(measured_shapes.rows() == model_at_sensors.rows());
  SignCheck out;
  const std::vector<Eigen::Index> counted = counted_modes(measured_shapes);
  out.counted = static_cast<int>(counted.size());
  if (counted.size() < 2) return out;
  std::vector<char> visible(static_cast<size_t>(model_at_sensors.cols()), 1);
  for (const int j : hidden)
    if (j >= 0 && j < model_at_sensors.cols()) visible[static_cast<size_t>(j)] = 0;
  Eigen::MatrixXcd shapes = measured_shapes;
  const Score given = score(shapes, counted, test_frequency_hz, model_at_sensors,
                            model_frequency_hz, visible, frequency_window, strong_mac);
  out.matched = given.matched;
  out.mean_mac = given.mean;
  // Every channel, then every pair of channels, reversed; the first best kept (one before two).
  std::vector<Eigen::Index> rows;
  for (Eigen::Index c = 0; c < shapes.rows(); ++c)
    if ((shapes.row(c).array().abs() > 0.0).any()) rows.push_back(c);
  Score best;
  std::vector<int> chosen;
  for_each_reversal(rows, [&](const std::vector<Eigen::Index>& flip) {
    for (const Eigen::Index c : flip) shapes.row(c) *= -1.0;
    const Score r = score(shapes, counted, test_frequency_hz, model_at_sensors, model_frequency_hz,
                          visible, frequency_window, strong_mac);
    for (const Eigen::Index c : flip) shapes.row(c) *= -1.0;
    if (chosen.empty() || r.matched > best.matched ||
        (r.matched == best.matched && r.mean > best.mean + 1e-9)) {
      best = r;
      chosen.assign(flip.begin(), flip.end());
    }
  });
  // Two more modes matching, three in four of them; or, with few modes, every mode matching
  // where one did not, the mean best MAC up by 0.1 (modes 1, 4 and 5 of the example beam with s2
  // and s4 reversed: 2 of 3 matched, 3 reversed, and K_T came out 5.1e6 against 1.2e7 as given).
  const bool more = best.matched >= given.matched + 2 && 4 * best.matched >= 3 * out.counted;
  const bool all = best.matched == out.counted && best.matched == given.matched + 1 &&
                   best.mean >= given.mean + 0.1;
  out.best = chosen;
  out.matched_reversed = best.matched;
  out.mean_mac_reversed = best.mean;
  if (!chosen.empty() && (more || all)) out.channels = std::move(chosen);
  return out;
}

std::string phaseless_shapes(const Eigen::Ref<const Eigen::MatrixXcd>& measured_shapes,
                             const Eigen::Ref<const Eigen::VectorXd>& test_frequency_hz,
                             const Eigen::Ref<const Eigen::MatrixXd>& model_at_sensors,
                             const Eigen::Ref<const Eigen::VectorXd>& model_frequency_hz,
                             const std::vector<std::string>& ids, double frequency_window) {
  if (model_frequency_hz.size() == 0) return "";
  // Whether model mode j keeps one sign at the sensors (entries above a tenth of its largest).
  const auto one_signed = [&](Eigen::Index j) {
    const Eigen::VectorXd v = model_at_sensors.col(j);
    const double floor = 0.1 * v.cwiseAbs().maxCoeff();
    return !((v.array() > floor).any() && (v.array() < -floor).any());
  };
  std::vector<std::string> modes, signed_model;
  for (const Eigen::Index i : counted_modes(measured_shapes)) {
    const Eigen::VectorXcd x = measured_shapes.col(i);
    Eigen::Index top = 0;
    x.cwiseAbs().maxCoeff(&top);
    const std::complex<double> unit = std::conj(x(top)) / std::abs(x(top));
    bool one_phase = true;
    for (Eigen::Index k = 0; k < x.size() && one_phase; ++k) {
      // An entry in phase with the largest to rounding: a magnitude, or a dropped sign.
      one_phase = x(k) == 0.0 || std::abs(std::arg(x(k) * unit)) <= 1e-9;
    }
    if (!one_phase) continue;
    // A measured mode of one sign is a magnitude only where no model mode that could be its
    // partner (within the window; none: the nearest in frequency) keeps one sign too.
    Eigen::Index near = 0;
    (model_frequency_hz.array() / test_frequency_hz(i)).log().abs().minCoeff(&near);
    bool partner_one_signed = one_signed(near);
    for (Eigen::Index j = 0; j < model_frequency_hz.size() && frequency_window > 0; ++j)
      if (std::abs(model_frequency_hz(j) / test_frequency_hz(i) - 1) <= frequency_window)
        partner_one_signed = partner_one_signed || one_signed(j);
    if (partner_one_signed) continue;
    modes.push_back(ids[static_cast<size_t>(i)]);
    signed_model.push_back(fmt::format("{} ({:.5g} Hz)", near + 1, model_frequency_hz(near)));
  }
  if (modes.size() < 2) return "";
  return fmt::format(
      "the shape{} of measured mode{} {} {} one phase at every sensor (magnitudes without their "
      "phase or sign?), while model mode{} {} nearest in frequency, and every model mode within "
      "the frequency window, change{} sign between the sensors; MAC cannot pair shapes without "
      "their signs: give each entry with its sign (the real part of the complex shape, or "
      "magnitude times the sign of cos(phase))",
      modes.size() == 1 ? "" : "s", modes.size() == 1 ? "" : "s", fmt::join(modes, ", "),
      modes.size() == 1 ? "has" : "have", signed_model.size() == 1 ? "" : "s",
      fmt::join(signed_model, ", "), signed_model.size() == 1 ? "s" : "");
}

}  // namespace jointlab::correlate
