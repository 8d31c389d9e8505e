// Pairs at the result the shapes do not confirm (linear_unconfirmed.h).
#include "jointlab/correlate/linear_unconfirmed.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/correlate/noise_limits.h"

namespace jointlab::correlate::detail {

namespace {

// Pairs crosswise to the frequency order (the lower test mode with the higher model mode), each
// shape at two sensors, where the fit leaves a misfit: their MACs confirm nothing, as one sign
// wrong turns one shape into the other. The twin cantilevers' first two modes alone, channel a
// reversed, paired crosswise at MAC 0.973 and 0.973 at the result, errors +14.1 % and -15.9 %
// at a reduced chi-square of 4.5e4, and were called converged.
// Each such pair adds its two modes to `ids`, a line to `lines` and its rows to
// s.unconfirmed_modes (modes listed already are not).
void crosswise_pairs(const MeasuredModes& measured, const LinearEvaluation& e, bool misfit,
                     std::vector<std::string>& ids, std::vector<std::string>& lines,
                     bool& two_sensors, LinearUpdateSummary& s) {
  const auto at_two = [&](Eigen::Index i) {
    return (measured.shapes.col(i).array().abs() > 0.0).count() == 2;
  };
  const auto listed = [&](int i) {
    return std::find(s.unconfirmed_modes.begin(), s.unconfirmed_modes.end(), i) !=
           s.unconfirmed_modes.end();
  };
  for (const ModePair& p : e.pairing.pairs) {
    for (const ModePair& q : e.pairing.pairs) {
      const double fp = e.measured_frequency_hz(p.measured),
                   fq = e.measured_frequency_hz(q.measured);
      if (!misfit || !(fp < fq) ||
          !(e.all_model_frequency_hz(p.model) > e.all_model_frequency_hz(q.model)) ||
          !at_two(p.measured) || !at_two(q.measured) || listed(p.measured) || listed(q.measured))
        continue;
      two_sensors = true;
      ids.push_back(e.measured_id(p.measured));
      ids.push_back(e.measured_id(q.measured));
      lines.push_back(fmt::format(
          "test modes {} ({:.5g} Hz) and {} ({:.5g} Hz) pair crosswise to the frequency order, "
          "with model modes {} ({:.5g} Hz) and {} ({:.5g} Hz), at MAC {:.3f} and {:.3f}",
          e.measured_id(p.measured), fp, e.measured_id(q.measured), fq, p.model + 1,
          e.all_model_frequency_hz(p.model), q.model + 1, e.all_model_frequency_hz(q.model),
          e.pair_mac(p.measured).value_or(p.mac), e.pair_mac(q.measured).value_or(q.mac)));
      s.unconfirmed_modes.push_back(p.measured);
      s.unconfirmed_modes.push_back(q.measured);
    }
  }
}

}  // namespace

// The pairs at the result whose MAC with their partner is below the threshold (a shape at two
// sensors or more): they rest on the start's MACs and on following each mode's shape, not on the
// shapes themselves. With two sensors the start's MACs are weak evidence: a sign wrong at one of
// them turns one shape into the other (the sign checks need three), and the trial's twin
// cantilevers with channel a reversed paired their first two modes crosswise at MAC 0.96-0.97,
// the fit then pulled the coupling spring from 200 to 6.8 until the modes' shapes no longer
// told them apart (MAC 0.48 and 0.49 at the result, errors +9.98 % and -16.5 %), and the
// headline said "converged". Returns the line for the report naming them, why, and what to do
// ("" when every pair is confirmed), their rows in s.unconfirmed_modes.
std::string unconfirmed_pairs(const MeasuredModes& measured, const LinearUpdateOptions& options,
                              LinearUpdateSummary& s) {
  const LinearEvaluation& e = s.final;
  std::vector<char> hidden(static_cast<size_t>(e.all_model_frequency_hz.size()), 0);
  for (const int j : e.hidden) hidden[static_cast<size_t>(j)] = 1;
  std::vector<std::string> ids, lines;
  bool two_sensors = false;
  for (const ModePair& q : e.pairing.pairs) {
    const std::optional<double> mac = e.pair_mac(q.measured);
    if (!mac || *mac >= options.mac_threshold) continue;
    const Eigen::Index i = q.measured;
    const double fe = e.measured_frequency_hz(i);
    int other = -1;
    for (Eigen::Index j = 0; j < e.mac.cols(); ++j) {
      const double f = e.all_model_frequency_hz(j);
      if (j == q.model || hidden[static_cast<size_t>(j)] || !(f > 0) ||
          (options.frequency_window > 0 && std::abs(f / fe - 1) > options.frequency_window))
        continue;
      if (other < 0 || e.mac(i, j) > e.mac(i, other)) other = static_cast<int>(j);
    }
    two_sensors = two_sensors || (measured.shapes.col(i).array().abs() > 0.0).count() == 2;
    ids.push_back(e.measured_id(i));
    lines.push_back(fmt::format(
        "test mode {} ({:.5g} Hz) has MAC {:.3f} with its partner, model mode {} ({:.5g} Hz){}",
        e.measured_id(i), fe, *mac, q.model + 1, e.model_frequency_hz(i),
        other < 0 ? ""
                  : fmt::format(", and {:.3f} with model mode {} ({:.5g} Hz)", e.mac(i, other),
                                other + 1, e.all_model_frequency_hz(other))));
    s.unconfirmed_modes.push_back(static_cast<int>(i));
  }
  const double sf2 = options.frequency_std * options.frequency_std;
  const bool misfit =
      s.degrees_of_freedom > 0
          ? s.reduced_chi2 > reduced_chi2_limit(s.degrees_of_freedom)
          : e.weighted_squared_norm() / sf2 > 9.0 * static_cast<double>(e.pairing.pairs.size());
  crosswise_pairs(measured, e, misfit, ids, lines, two_sensors, s);
  if (lines.empty()) return "";
  const bool one = ids.size() == 1;
  return fmt::format(
      "the shapes do not confirm the pair{} of test mode{} {}: at the result {} (the MAC "
      "threshold is {:g}); {} on the start's MACs and on following each mode's shape{}{}: add "
      "sensors that see these modes apart, or check the signs of their shapes (a campaign's "
      "[[channel]] sign); to pair a mode by frequency alone, give its shape at one sensor only "
      "(the other cells of its modes-table row empty); in a campaign (jointlab run), whose shapes "
      "come from every [[channel]], leave test mode{} {} out of the linear update (list the other "
      "[[mode]] names in [update.linear] modes)",
      one ? "" : "s", one ? "" : "s", fmt::join(ids, one ? "" : " and "), fmt::join(lines, "; "),
      options.mac_threshold, one ? "it rests" : "they rest",
      two_sensors ? ", and at two sensors a MAC tells shapes apart poorly: one sign wrong (a "
                    "channel mounted reversed, or a mode's phase) turns one shape into the "
                    "other, and the channel sign checks need three sensors"
                  : "",
      misfit
          ? fmt::format("; the fit leaves {} (largest frequency error {:.3g} %), which wrong pairs "
                        "would explain",
                        s.degrees_of_freedom > 0
                            ? fmt::format("a reduced chi-square of {:.3g}", s.reduced_chi2)
                            : fmt::format("a chi-square of {:.3g} with no degree of freedom left",
                                          e.weighted_squared_norm() / sf2),
                        100 * e.max_error())
          : "",
      one ? "" : "s", fmt::join(ids, one ? "" : " and "));
}

}  // namespace jointlab::correlate::detail
