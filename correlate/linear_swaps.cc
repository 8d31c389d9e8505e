// Exchanged pairs of a fit's result (linear_swaps.h).
#include "jointlab/correlate/linear_swaps.h"

#include <cmath>
#include <utility>

#include <fmt/format.h>

namespace jointlab::correlate::detail {

namespace {

// Whether the sensors cannot tell model columns a and b apart for measured mode i at `at`: its
// MAC reads no shape (frequency alone pairs it), or it sees both at or above the threshold and
// within the tie MAC of each other.
bool alike(const LinearEvaluation& at, const PairingRules& rules, size_t i, int a, int b) {
  if (i >= at.mac_reads_shape.size() || !at.mac_reads_shape[i]) return true;
  const auto r = static_cast<Eigen::Index>(i);
  return at.mac(r, a) >= rules.mac_threshold && at.mac(r, b) >= rules.mac_threshold &&
         std::abs(at.mac(r, a) - at.mac(r, b)) <= rules.tie_mac;
}

}  // namespace

// Nearest frequency pairs two modes of nearly one frequency without a tie where the sensors
// cannot see them apart, and a fit keeps whichever order its start had. The two chains' five
// modes at one sensor (frequency alone pairs each), 0.3 % noise stated as it is, from ka 1e6,
// kb 3e5 (truth 5e5, 3e5): chain A's first mode started above chain B's, the reverse of the
// truth, and 93 of 100 seeds "converged" with the chains' first modes crosswise, 60 of 68
// stated sigmas beyond 2. Each such exchange is a candidate the data must decide.
std::vector<SwappedPairs> swapped_pairings(const LinearProblem& p, const TrackedPoint& result) {
  std::vector<SwappedPairs> out;
  const LinearEvaluation at = p.evaluate(result);
  if (at.jacobian.rows() == 0) return out;
  const PairingRules rules = p.rules();
  for (size_t i = 0; i < result.columns.size(); ++i)
    for (size_t k = i + 1; k < result.columns.size(); ++k) {
      const int a = result.columns[i], b = result.columns[k];
      if (a < 0 || b < 0 || std::abs(a - b) != 1 || !alike(at, rules, i, a, b) ||
          !alike(at, rules, k, a, b))
        continue;
      TrackedPoint t = result;
      std::swap(t.columns[i], t.columns[k]);
      const auto ii = static_cast<Eigen::Index>(i), kk = static_cast<Eigen::Index>(k);
      out.push_back(
          {std::move(t),
           fmt::format("test modes {} ({:.5g} Hz) and {} ({:.5g} Hz) were paired with model "
                       "modes {} ({:.5g} Hz) and {} ({:.5g} Hz), adjacent in frequency, which the "
                       "sensors cannot tell apart ({}), and fitted again from there with the two "
                       "partners exchanged",
                       p.measured.id(ii), p.measured.frequency_hz(ii), p.measured.id(kk),
                       p.measured.frequency_hz(kk), a + 1, at.all_model_frequency_hz(a), b + 1,
                       at.all_model_frequency_hz(b),
                       at.mac_reads_shape[i] && at.mac_reads_shape[k]
                           ? fmt::format("their MACs within {:.3g} of each other", rules.tie_mac)
                           : "frequency alone pairs them")});
    }
  // A measured mode paired with a model mode beside an unpaired one the sensors cannot tell from
  // it: the one-sensor beam from K_T 4e6 or 3.6e7 (truth 1.2e7, rz 100) tuned rz to 2129 until
  // a twisting mode sat on test mode 4 (766.882 Hz), its bending mode 0.014 Hz below, unpaired,
  // and "converged" with rz +/- 7.37 %, 41 of those off: the truth fits as well.
  std::vector<char> taken(static_cast<size_t>(at.all_model_frequency_hz.size()), 0);
  for (const int c : result.columns)
    if (c >= 0) taken[static_cast<size_t>(c)] = 1;
  for (const int h : at.hidden) taken[static_cast<size_t>(h)] = 1;
  for (size_t i = 0; i < result.columns.size(); ++i) {
    const int a = result.columns[i];
    if (a < 0) continue;
    for (const int b : {a - 1, a + 1}) {
      if (b < 0 || b >= static_cast<int>(taken.size()) || taken[static_cast<size_t>(b)] ||
          !alike(at, rules, i, a, b))
        continue;
      TrackedPoint t = result;
      t.columns[i] = b;
      const auto ii = static_cast<Eigen::Index>(i);
      out.push_back(
          {std::move(t),
           fmt::format("test mode {} ({:.5g} Hz) was paired with model mode {} ({:.5g} Hz), "
                       "beside model mode {} ({:.5g} Hz), unpaired, which the sensors cannot "
                       "tell from it ({}), and fitted again from there paired with the latter",
                       p.measured.id(ii), p.measured.frequency_hz(ii), a + 1,
                       at.all_model_frequency_hz(a), b + 1, at.all_model_frequency_hz(b),
                       at.mac_reads_shape[i]
                           ? fmt::format("their MACs within {:.3g} of each other", rules.tie_mac)
                           : "frequency alone pairs it"),
           true});
    }
  }
  return out;
}

}  // namespace jointlab::correlate::detail
