// Checks of measured shapes against the model before they pair: a channel whose sign reads the
// model reversed, and shapes without phase.
//
// A measured mode i "matches" when some visible model mode within the pairing's frequency window
// has sensor MAC >= strong_mac (0.9) with it. Only modes with an entry at three sensors or more
// count (at two, flipping one sign only swaps which of two shapes they look like).
// Reversed channels: for each sensor c, and each pair of sensors, those rows of the measured
// shapes are negated and the matches counted again (the most matches win, then the highest mean
// best MAC, then one channel over two). They are named when, reversed, at least two more modes
// match than as given, and at least three in four of the counted modes; or every counted mode
// matches where one did not as given, with the mean best MAC up by 0.1 (few modes: with three,
// a reversal often turns one). A channel mounted the
// other way round (sensors file `sign` wrong or missing) otherwise pairs modes crosswise: with
// five sensors on the example beam and one reversed, two of five paired, one at +25 % and one at
// -38 %, and K_T came out 3.1 times low, "converged"; with two reversed, one of five paired and
// K_T came out twice the truth, "converged".
// Shapes without phase: counted modes whose every entry has the same phase (magnitudes, or a
// sign dropped) while every model mode within the frequency window (none: the nearest in
// frequency) changes sign between the sensors (entries above a tenth of its largest with both
// signs); at least two such modes. MAC cannot pair magnitudes: on the example beam all five
// as magnitudes paired one, crosswise; modes 2-5 alone as magnitudes gave K_T 2.77e6 against
// 1.2e7, "converged", and modes 1, 3 and 5 were read as a channel reversed. Checked before the
// channels' signs.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointlab::correlate {

/// What check_channel_signs() found.
struct SignCheck {
  std::vector<int> channels;     ///< the sensor rows whose signs look reversed (one or two); none
  int counted = 0;               ///< measured modes with entries at three sensors or more
  int matched = 0;               ///< of them, modes with a strong match as given
  int matched_reversed = 0;      ///< of them, modes with a strong match with `best` reversed
  double mean_mac = 0;           ///< mean best MAC over the counted modes as given
  double mean_mac_reversed = 0;  ///< the same with `best` reversed
  /// The reversal with the most matches, then the highest mean best MAC, whether or not it
  /// meets the rule above (`channels`, when it does); none with fewer than two counted modes.
  std::vector<int> best;
  /// True when `best` matches at least as many modes as given with a mean best MAC at least
  /// 0.02 higher: not enough to refuse before a fit, but worth a fit where the given signs
  /// leave a misfit (linear_update.h).
  bool best_looks_better() const {
    return !best.empty() && matched_reversed >= matched && mean_mac_reversed >= mean_mac + 0.02;
  }
};

/// Tries each channel and each pair of channels reversed (above); `hidden` lists model columns
/// never paired.
SignCheck check_channel_signs(const Eigen::Ref<const Eigen::MatrixXcd>& measured_shapes,
                              const Eigen::Ref<const Eigen::VectorXd>& test_frequency_hz,
                              const Eigen::Ref<const Eigen::MatrixXd>& model_at_sensors,
                              const Eigen::Ref<const Eigen::VectorXd>& model_frequency_hz,
                              const std::vector<int>& hidden, double frequency_window,
                              double strong_mac = 0.9);

/// The one or two entries of one measured shape whose reversal gives it the highest MAC with a
/// model shape (each entry alone, then each pair; the first best kept).
struct Reversal {
  std::vector<int> channels;  ///< the reversed rows; none with fewer than three entries
  double mac = 0;             ///< the MAC with them reversed
};
/// The reversal of one or two of `measured`'s entries that gives the highest MAC with `model`
/// (mode_shape_match(): a band whose shape does not look like its mode).
Reversal best_reversal(const Eigen::Ref<const Eigen::VectorXcd>& measured,
                       const Eigen::Ref<const Eigen::VectorXd>& model);

/// Why the measured shapes look like magnitudes without phase (above), or ""; `ids` names the
/// measured modes in the message.
std::string phaseless_shapes(const Eigen::Ref<const Eigen::MatrixXcd>& measured_shapes,
                             const Eigen::Ref<const Eigen::VectorXd>& test_frequency_hz,
                             const Eigen::Ref<const Eigen::MatrixXd>& model_at_sensors,
                             const Eigen::Ref<const Eigen::VectorXd>& model_frequency_hz,
                             const std::vector<std::string>& ids, double frequency_window);

}  // namespace jointlab::correlate
