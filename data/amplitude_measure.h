// How a column's header says its amplitudes were measured where not zero to peak: peak to peak
// or RMS. Every reader takes an amplitude (a backbone's, a stepped sine's response and force) for
// zero to peak; a table of RMS or peak-to-peak values read so scales F_S by 0.707 or 2, which no
// fit can tell. The readers name the factor instead (one wording, here): in the column's name
// ('amplitude_rms', 'response_pp'), beside its unit ('[mm/s pk-pk]', '[m/s^2 RMS]') or after it
// ('amplitude [m/s] (rms)').
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace jointlab::data {

/// The words of a header name or unit, lower-cased: runs of letters and digits (the bytes of
/// UTF-8 letters such as 'ζ' and 'σ' kept in them).
std::vector<std::string> header_words(std::string_view name);

/// How the words of an amplitude's name or unit say it was measured where not zero to peak:
/// "peak-to-peak" (pp, p2p, ptp, pkpk, pk-pk, pk_pk, p-p, pk-to-pk, peak-peak, peak to peak) or
/// "RMS"; "" otherwise.
std::string amplitude_measure(std::string_view text);

/// What to do with values measured as `measure` (amplitude_measure()) to read them zero to peak:
/// "multiply its values by sqrt(2) = 1.4142" (RMS) or "halve its values" (peak to peak).
std::string measure_factor(const std::string& measure);

/// measure_factor() with why, for a response amplitude: read as it is, it is taken for zero to
/// peak and F_S comes out 2 (peak to peak) or 0.707 (RMS) times the truth.
std::string measure_fix(const std::string& measure);

/// A unit written with how it was measured ("mm/s pk-pk", "RMS m/s^2"): the measure, the word
/// that says it, and the unit's other words.
struct UnitMeasure {
  std::string measure;  ///< "peak-to-peak" or "RMS"
  std::string written;  ///< the word as written ("pk-pk")
  std::string rest;     ///< the other words ("mm/s"); "" where none
};

/// The measure in a bracketed unit's words (separated by blanks, or joined to the unit as in
/// 'grms', 'g_rms', 'Npp'); none where no word says one.
std::optional<UnitMeasure> unit_measure(std::string_view unit);

/// A unit with the measure its words say taken out ("g RMS", "grms": "g"); the unit trimmed
/// where none says one.
std::string unit_without_measure(std::string_view unit);

/// A header "name [unit] (rms)", a measure written after the unit: the name, the unit and the
/// measure; none where nothing after the ']' says one.
struct MeasureAfterUnit {
  std::string name;     ///< trimmed, before the '['
  std::string unit;     ///< trimmed, inside the brackets
  std::string measure;  ///< "peak-to-peak" or "RMS"
};

/// The measure written after a header's unit in square brackets; none where there is none.
std::optional<MeasureAfterUnit> measure_after_unit(std::string_view field);

}  // namespace jointlab::data
