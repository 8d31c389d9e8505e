#include "jointlab/data/backbone_table.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <numeric>
#include <string_view>
#include <tuple>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/core/error.h"
#include "jointlab/core/rank_correlation.h"
#include "jointlab/core/text.h"
#include "jointlab/core/units.h"
#include "jointlab/data/amplitude_measure.h"
#include "jointlab/data/csv_lines.h"

namespace jointlab::data {

namespace fs = std::filesystem;

bool is_point_mark(std::string_view column) { return column == "harmonic" || column == "exchange"; }

namespace {

// The columns read: the three required, then the two optional uncertainties.
constexpr std::array<const char*, 5> kNames = {"amplitude", "frequency_hz", "damping_ratio",
                                               "frequency_std_hz", "damping_std"};
constexpr const char* kHeader =
    "amplitude,frequency_hz,damping_ratio[,frequency_std_hz,damping_std]";

std::string with_article(const std::string& noun) {
  return (std::string("aeiou").find(noun.front()) != std::string::npos ? "an " : "a ") + noun;
}

// "m/s^2, mm/s^2, in/s^2, g or mg": the units an amplitude of `q` takes (core/units.h's).
std::string units_of(Quantity q) {
  std::vector<std::string> u = unit_names(q);
  const std::string last = u.back();
  u.pop_back();
  return fmt::format("{} or {}", fmt::join(u, ", "), last);
}

// Why an amplitude of `quantity` (nullopt: a modal amplitude) cannot carry `unit`, a unit `u`
// parse_unit reads, ending with the --amplitude that takes it where one does ("; a displacement
// amplitude needs --amplitude displacement"); "" when it can. Both the refusal of a unit in square
// brackets and the header a refusal suggests go by it, so a suggested header is one the named
// --amplitude reads: before, 'Amplitude (mm)' with --amplitude modal was told to write
// 'amplitude [mm]', which the same run then refused.
std::string amplitude_kind_mismatch(const std::string& unit, const Unit& u,
                                    std::optional<Quantity> quantity) {
  if (quantity && u.quantity == *quantity) return "";
  const std::string of = quantity_name(u.quantity);
  const std::string fits =
      u.quantity == Quantity::kForce
          ? std::string("; no --amplitude reads a force: the amplitude is the response's")
          : fmt::format("; {} amplitude needs --amplitude {}{}", with_article(of), of,
                        quantity ? "" : " with --dof");
  if (!quantity) {
    return fmt::format("unit '{}' refused: a modal amplitude (--amplitude modal) takes no unit{}",
                       shorten(unit), fits);
  }
  const std::string name = quantity_name(*quantity);
  return fmt::format("unit '{}' measures {}, the amplitude is {} (--amplitude {}, SI unit {}){}",
                     shorten(unit), of, with_article(name), name, si_unit(*quantity), fits);
}

// Whether a unit is an angular frequency's (rad/s): omega = 2 pi f.
bool is_angular_unit(std::string_view unit) {
  std::string u = lower(unit);
  std::erase(u, ' ');
  return u == "rad/s" || u == "rad/sec" || u == "rads^-1" || u == "rad*s^-1";
}

// The factor a value of column k (amplitude, frequency_hz, damping_ratio, frequency_std_hz,
// damping_std) in `unit` takes to the table's units; InputError naming the file, the column and
// the unit when the column does not take it: a unit is converted or refused, never ignored.
double unit_scale(size_t k, const std::string& unit, std::optional<Quantity> quantity,
                  const std::string& file, long line) {
  const auto refuse = [&](const std::string& why) {
    return InputError(
        where(file, line, fmt::format("column '{} [{}]': {}", kNames[k], shorten(unit), why)));
  };
  if (k == 1 || k == 3) {  // frequencies
    if (lower(unit) == "hz") return 1.0;
    throw refuse(fmt::format(
        "unit '{}' refused: {} is in Hz ([Hz] or no unit){}", shorten(unit), kNames[k],
        is_angular_unit(unit)
            ? fmt::format("; a frequency in rad/s is 2 pi times the one in Hz: divide its values "
                          "by 2 pi (6.2832) and write '{} [Hz]'",
                          kNames[k])
            : ""));
  }
  if (k == 2 || k == 4) {  // damping ratios
    if (unit == "1" || unit == "-") return 1.0;
    if (unit == "%") return 0.01;
    throw refuse(fmt::format(
        "unit '{}' refused: {} is a fraction (no unit, [1] or [-]) or in per cent ([%])",
        shorten(unit), kNames[k]));
  }
  const std::optional<Unit> u = parse_unit(unit);
  if (u) {
    const std::string wrong_kind = amplitude_kind_mismatch(unit, *u, quantity);
    if (!wrong_kind.empty()) throw refuse(wrong_kind);
    return u->to_si;
  }
  // How it was measured written beside the unit ('mm/s pk-pk', 'm/s RMS'): the factor is named,
  // not merely the unit refused (with the measure deleted alone, the values were read zero to
  // peak and F_S came out 2 or 0.707 times the truth).
  if (const std::optional<UnitMeasure> m = unit_measure(unit); k == 0 && m) {
    throw refuse(
        fmt::format("'{}' says how it was measured, not a unit: {}, then write 'amplitude{}'",
                    shorten(m->written), measure_fix(m->measure),
                    m->rest.empty() ? std::string() : fmt::format(" [{}]", shorten(m->rest))));
  }
  if (!quantity) {
    throw refuse(fmt::format(
        "unit '{}' refused: a modal amplitude (--amplitude modal) takes no unit; a measured one "
        "needs --amplitude displacement, velocity or acceleration with --dof",
        shorten(unit)));
  }
  const std::string name = quantity_name(*quantity);
  // Units are case-sensitive (mm is not Mm, g is not G): a spelling of the quantity's units
  // (every one parse_unit reads: 'Micron' names micron) that differs only in case is named as the
  // fix, not read in its place.
  for (const std::string& c : unit_spellings(*quantity)) {
    if (lower(c) == lower(unit)) {
      throw refuse(
          fmt::format("unknown unit '{}': write 'amplitude [{}]' (units are "
                      "case-sensitive; {} amplitude takes {})",
                      shorten(unit), c, with_article(name), units_of(*quantity)));
    }
  }
  throw refuse(fmt::format("unknown unit '{}': {} amplitude takes {} (SI {})", shorten(unit),
                           with_article(name), units_of(*quantity), si_unit(*quantity)));
}

// --- What a header the reader cannot use most likely meant, for a refusal that names the fix.

// A header field that is not one of kNames, as the column it most likely means.
struct Guess {
  int column = -1;             // index into kNames; -1: none of them
  bool uncertainty = false;    // a std, sigma, error ... (of `column` when that is 3 or 4)
  bool loss_factor = false;    // eta = 2 zeta, not a damping ratio
  bool relative = false;       // "rel", "relative": a std divided by its value
  bool angular = false;        // omega = 2 pi f (rad/s): a frequency, divided by 2 pi
  std::string unit;            // the unit it gives, in [] or (); "" if none
  bool parenthesised = false;  // the unit in round brackets
  bool unit_taken = false;     // `unit` is one the guessed column takes
  // An amplitude's known unit of another kind than --amplitude names: why it is refused and the
  // --amplitude that takes it (amplitude_kind_mismatch); "" otherwise. `unit_measures`: the
  // quantity of a known amplitude unit.
  std::string kind_mismatch;
  std::optional<Quantity> unit_measures;
  std::string case_slip;  ///< the unit as written where `unit` is its spelling in another case
  // How an amplitude's name says it was measured where not zero to peak: "peak-to-peak" or
  // "RMS"; "" otherwise. Renamed plainly, such a column was read as zero to peak and scaled F_S
  // by 2 or 0.707, which no fit can tell.
  std::string measure;
};

Guess guess_column(const std::string& name, const std::string& bracket_unit,
                   std::optional<Quantity> quantity) {
  Guess g;
  std::string base = name;
  g.unit = bracket_unit;
  if (const auto round = split_round_brackets(name); bracket_unit.empty() && round) {
    std::tie(base, g.unit) = *round;
    g.parenthesised = true;
  }
  const std::vector<std::string> words = header_words(base);
  const auto any = [&](auto&& pred) { return std::any_of(words.begin(), words.end(), pred); };
  const auto has = [](const std::string& w, const char* part) {
    return w.find(part) != std::string::npos;
  };
  // Word starts, not any part of a word: 'interrupted' and 'ferrite' hold no error.
  g.uncertainty = any([&](const std::string& w) {
                    return w.starts_with("std") || w.starts_with("sigma") || has(w, "σ") ||
                           w.starts_with("uncert") || w.starts_with("err") || has(w, "deviation") ||
                           has(w, "±") || w == "sd" || w == "unc" || w == "dev";
                  }) ||
                  base.find("+/-") != std::string::npos;
  g.relative = any([](const std::string& w) { return w == "rel" || w == "relative"; });
  g.loss_factor = any([](const std::string& w) {
    return w == "loss" || w.starts_with("lossfactor") || w == "eta" || w == "η";
  });
  const bool damping = any([](const std::string& w) {
    // Not "damped": a damped frequency is a frequency.
    return (w.starts_with("damp") && w != "damped") || w.starts_with("zeta") || w == "ζ" ||
           w == "xi";
  });
  g.angular = is_angular_unit(g.unit) || any([](const std::string& w) {
                return w == "omega" || w == "ω" || w == "angular" || w == "wn" || w == "w0";
              });
  const bool frequency =
      g.angular || any([](const std::string& w) {
        return w.starts_with("freq") || w == "f" || w == "fn" || w == "f0" || w == "hz";
      });
  const bool amplitude = any([](const std::string& w) {
    return w.starts_with("amp") || w.starts_with("acc") || w.starts_with("vel") ||
           w.starts_with("disp") || w == "a" || w == "q";
  });
  if (g.loss_factor) return g;
  if (amplitude) {
    // The measure in the name or in its brackets: amp_pp, amplitude_p2p, Amplitude
    // (peak-to-peak), velocity_rms [mm/s].
    g.measure = amplitude_measure(name + " " + bracket_unit);
    if (!g.measure.empty() && g.parenthesised && !parse_unit(g.unit)) {
      // "(peak-to-peak)", "(RMS)": the measure, not a unit; "(g RMS)": the unit is kept (told
      // "rename it 'amplitude'", values in g were read as m/s^2, F_S 9.81 times off).
      g.unit = unit_without_measure(g.unit);
      g.parenthesised = false;
    }
  }
  if (damping) {
    g.column = g.uncertainty ? 4 : 2;
  } else if (frequency) {
    g.column = g.uncertainty ? 3 : 1;
  } else if (amplitude && g.uncertainty) {
    g.uncertainty = false;  // an amplitude's uncertainty: not used by the update, not asked for
  } else if (amplitude) {
    g.column = 0;
  }
  if (g.column == 1 || g.column == 3) g.unit_taken = lower(g.unit) == "hz";
  if (g.column == 2 || g.column == 4)
    g.unit_taken = g.unit == "%" || g.unit == "1" || g.unit == "-";
  if (g.column == 0) {
    // Units are case-sensitive: 'G' is no unit, but a case slip of 'g'. Suggesting the name
    // without it ('rename it amplitude') led to the values being read in SI, 9.81 times off,
    // without a word; the suggestion names the spelling instead (--amplitude's kind first).
    if (!g.unit.empty() && !parse_unit(g.unit)) {
      std::vector<Quantity> kinds;
      if (quantity) kinds.push_back(*quantity);
      for (const Quantity q :
           {Quantity::kDisplacement, Quantity::kVelocity, Quantity::kAcceleration}) {
        if (!quantity || q != *quantity) kinds.push_back(q);
      }
      for (const Quantity q : kinds) {
        const std::vector<std::string> spellings = unit_spellings(q);
        const auto c = std::find_if(spellings.begin(), spellings.end(), [&](const std::string& x) {
          return lower(x) == lower(g.unit);
        });
        if (c == spellings.end()) continue;
        g.case_slip = g.unit;
        g.unit = *c;
        break;
      }
    }
    if (const std::optional<Unit> u = parse_unit(g.unit)) {
      g.unit_measures = u->quantity;
      g.kind_mismatch = amplitude_kind_mismatch(g.unit, *u, quantity);
      g.unit_taken = g.kind_mismatch.empty();
    }
  }
  return g;
}

// The header a guessed column should have: its name, and its unit in square brackets when it
// gave one the column takes.
std::string suggested_header(const Guess& g) {
  const std::string name = kNames[static_cast<size_t>(g.column)];
  return g.unit_taken ? fmt::format("{} [{}]", name, g.unit) : name;
}

// "column 3 'damping_ratio (%)': write the unit in square brackets, 'damping_ratio [%]'" or
// "column 2 'Freq (Hz)': rename it 'frequency_hz [Hz]' (the unit in square brackets)".
std::string rename_hint(size_t i, const std::string& field, const Guess& g) {
  const std::string name = kNames[static_cast<size_t>(g.column)];
  const std::string to = suggested_header(g);
  const std::string base(trim(std::string_view(field).substr(0, field.find_first_of("(["))));
  std::string fix;
  std::vector<std::string> notes;
  // A unit of another kind than --amplitude names: the header is named with the --amplitude
  // that reads it ("...; a displacement amplitude needs --amplitude displacement and the header
  // 'amplitude [mm]'"), not as one this run would refuse; a force's, which none reads, is not.
  if (!g.kind_mismatch.empty()) {
    return fmt::format("column {} '{}': {}{}", i + 1, shorten(field), g.kind_mismatch,
                       g.unit_measures == Quantity::kForce
                           ? std::string()
                           : fmt::format(" and the header '{} [{}]'", name, g.unit));
  }
  if (g.angular && (g.column == 1 || g.column == 3)) {
    return fmt::format(
        "column {} '{}': an angular frequency: divide its values by 2 pi (6.2832) and name the "
        "column '{}'",
        i + 1, shorten(field), name);
  }
  if (g.column == 0 && !g.measure.empty()) {
    // Renamed alone, it would be read as zero to peak: F_S x 2 (peak-to-peak) or x 0.707 (RMS).
    fix = fmt::format("{}, then rename it '{}'", measure_fix(g.measure), to);
    if (!g.unit.empty() && !g.unit_taken)
      notes.push_back(fmt::format("'{}' is no unit of {}", shorten(g.unit), name));
  } else if (g.parenthesised && g.unit_taken && lower(base) == name) {
    fix = fmt::format("write the unit in square brackets, '{}'", to);
  } else {
    fix = fmt::format("rename it '{}'", to);
    if (!g.unit.empty() && !g.unit_taken) {
      notes.push_back(fmt::format("'{}' is no unit of {}", shorten(g.unit), name));
    } else if (g.parenthesised) {
      notes.emplace_back("the unit in square brackets");
    }
  }
  if (g.column == 3) notes.emplace_back("one standard deviation in Hz");
  if (g.column == 4) {
    notes.emplace_back(g.relative ? "one standard deviation of the damping ratio, absolute: a "
                                    "relative one times damping_ratio"
                                  : "one standard deviation of the damping ratio");
  }
  if (!g.case_slip.empty()) {
    notes.push_back(fmt::format("units are case-sensitive: '{}' is written '{}'",
                                shorten(g.case_slip), g.unit));
  }
  if (!notes.empty()) fix += fmt::format(" ({})", fmt::join(notes, "; "));
  return fmt::format("column {} '{}': {}", i + 1, shorten(field), fix);
}

// Whether a line holds the names of at least two of the three columns a backbone needs: a
// header row below the line the reader took as its header.
bool looks_like_header(std::string_view line) {
  CsvLineSplitter splitter(detect_delimiter(line));
  int found = 0;
  for (const std::string& field : splitter.split(line)) {
    const std::string name = lower(trim(std::string_view(field).substr(0, field.find('['))));
    for (size_t k = 0; k < 3; ++k) found += name == kNames[k];
  }
  return found >= 2;
}

// InputError for a header without the required columns (col[k] < 0), naming for each the
// column that most likely meant it and the fix: a name to use, a unit to write in square
// brackets, '#' before lines above the header, or the header row that a table of numbers lacks.
[[noreturn]] void refuse_header(std::string_view header, const std::vector<std::string>& fields,
                                const std::vector<Guess>& guesses, const std::array<int, 5>& col,
                                TextLines lines, const std::string& file, long header_line) {
  std::vector<std::string> fixes;
  std::vector<bool> used(fields.size(), false);
  for (size_t k = 0; k < 3; ++k) {
    if (col[k] >= 0) continue;
    size_t i = 0;
    while (i < fields.size() && (used[i] || guesses[i].column != static_cast<int>(k))) ++i;
    if (i < fields.size()) {
      used[i] = true;
      fixes.push_back(rename_hint(i, fields[i], guesses[i]));
      continue;
    }
    const auto loss =
        std::find_if(guesses.begin(), guesses.end(), [](const Guess& g) { return g.loss_factor; });
    if (k == 2 && loss != guesses.end()) {
      const size_t j = static_cast<size_t>(loss - guesses.begin());
      fixes.push_back(fmt::format(
          "column {} '{}': a loss factor is twice the damping ratio: halve its values and name "
          "the column 'damping_ratio'",
          j + 1, shorten(fields[j])));
      continue;
    }
    fixes.push_back(fmt::format("no column '{}'", kNames[k]));
  }
  // Lines above the header without '#' (an export's title, a sensor name): not skipped, as such
  // a line may say what the numbers are ("amplitudes in mm"); the fix names the header's line.
  std::string_view line;
  for (int seen = 0; seen < 200 && lines.next(line); ++seen) {
    if (!looks_like_header(line)) continue;
    throw InputError(
        where(file, header_line,
              fmt::format("'{}' is read as the header, but the header row is line {}: start each "
                          "line above it with '#', or delete them",
                          shorten(trim(header)), lines.line_no())));
  }
  if (std::all_of(fields.begin(), fields.end(),
                  [](const std::string& f) { return parse_double(f).has_value(); })) {
    throw InputError(where(file, header_line,
                           "the first row is numbers, not a header: add the header row above "
                           "it, e.g. amplitude,frequency_hz,damping_ratio (names in the columns' "
                           "order)"));
  }
  // The header to write is named only where a column was not recognised at all; a renamed one
  // has its fix above.
  const bool unknown = std::any_of(fixes.begin(), fixes.end(),
                                   [](const std::string& f) { return f.starts_with("no column"); });
  throw InputError(where(file, header_line,
                         fmt::format("{}{}", fmt::join(fixes, "; "),
                                     unknown ? fmt::format(" (a backbone table's header: {}, "
                                                           "units in square brackets)",
                                                           kHeader)
                                             : "")));
}

// Refuses columns that look like the uncertainties but are not read, naming the names read.
// Refused, not warned about: the update weighs every point by frequency_std_hz and damping_std
// and states the parameters' uncertainties from them; a column it does not read leaves its
// floors in their place, so the fit and its stated std change with no sign in the result, and
// a user who wrote the column believes it is used. A warning among a fit's progress lines is
// easily missed; the fix is a rename, and a column that is no uncertainty can be renamed out of
// the way. Checked while the pair is incomplete only: with both read, a further column (a
// relative copy, an amplitude's std) is one of the further columns, ignored.
void refuse_unread_uncertainties(const std::vector<std::string>& fields,
                                 const std::vector<Guess>& guesses, const std::array<int, 5>& col,
                                 const std::string& file, long header_line) {
  if (col[3] >= 0 && col[4] >= 0) return;
  std::vector<std::string> fixes;
  std::array<bool, 5> hinted{};
  for (size_t i = 0; i < fields.size(); ++i) {
    const Guess& g = guesses[i];
    if (!g.uncertainty) continue;
    // Only an uncertainty of the frequency or the damping by its name: the contract ignores
    // further columns, and 'sigma' alone may be a decay rate (the contract's own notation).
    if ((g.column == 3 || g.column == 4) && col[static_cast<size_t>(g.column)] < 0 &&
        !hinted[static_cast<size_t>(g.column)]) {
      hinted[static_cast<size_t>(g.column)] = true;
      fixes.push_back(rename_hint(i, fields[i], g));
    }
  }
  if (fixes.empty()) return;
  throw InputError(where(file, header_line,
                         fmt::format("{}; an uncertainty under another name is not read, and the "
                                     "fit would weigh the points by its floors instead",
                                     fmt::join(fixes, "; "))));
}

}  // namespace

double coverage_factor_of_row(double value, double before, std::string_view cell,
                              const std::string& file, long line) {
  if (!(value >= 1) || !std::isfinite(value) || (before > 0 && value != before)) {
    throw InputError(where(file, line,
                           fmt::format("coverage_factor '{}' must be a finite number >= 1, the "
                                       "same on every row",
                                       cell)));
  }
  return value;
}

namespace {

// Whether a further column's name labels the hit or test a row belongs to ('hit', 'Test No.',
// 'run_id', 'file_name'): a word for a curve, then at most words for a number, an id or a name.
// Not a force or level: a stepped sine's level labels a point.
bool is_curve_label(std::string_view name) {
  static constexpr std::array<std::string_view, 11> kCurve = {
      "hit",    "test",   "run",         "curve", "record",  "shot",
      "impact", "series", "measurement", "file",  "filename"};
  static constexpr std::array<std::string_view, 9> kTag = {"id",  "no",    "nr",   "number", "num",
                                                           "idx", "index", "name", "label"};
  const std::vector<std::string> words = header_words(name);
  const auto in = [](const auto& set, const std::string& w) {
    return std::find(set.begin(), set.end(), w) != set.end();
  };
  return !words.empty() && in(kCurve, words.front()) &&
         std::all_of(words.begin() + 1, words.end(),
                     [&](const std::string& w) { return in(kTag, w) || in(kCurve, w); });
}

// What the header row says: where each column read is and its unit's factor, and the further
// columns the reader uses (a `process` backbone's marks and coverage factor).
struct Columns {
  std::array<int, 5> col;       // index of each of kNames in a row; -1: absent
  std::array<double, 5> scale;  // value in the file's unit -> the table's (SI, Hz, a fraction)
  std::vector<size_t> marks;    // columns of is_point_mark: their marked rows are skipped
  int coverage_col = -1;        // a `process` backbone's coverage_factor: k of the std columns
  int displacement_col = -1;    // a `process` or `stepped-sine` backbone's displacement_m
  std::vector<size_t> labels;   // columns naming the hit or test a row is of (is_curve_label)
  std::string amplitude_unit;   // as the header gives it ("": none)
  bool ours = false;            // a `process` or `stepped-sine` backbone (BackboneTable)
  size_t fields = 0;            // the number of columns the header names
  size_t needed = 0;            // the cells a row needs: up to the last column read
};

// Reads the header's fields: each of kNames found (case-blind) with its unit's factor, the marks
// and the coverage factor, and for every other field the column it most likely means
// (`guesses`, for the refusals); InputError for a unit a column does not take and for two
// fields that are the same column.
Columns resolve_columns(const std::vector<std::string>& fields, std::optional<Quantity> quantity,
                        std::vector<Guess>& guesses, const std::string& file, long header_line) {
  Columns c;
  c.col.fill(-1);
  c.scale.fill(1.0);
  c.fields = fields.size();
  guesses.assign(fields.size(), Guess{});
  for (size_t i = 0; i < fields.size(); ++i) {
    // An amplitude's measure after its unit ('amplitude [m/s] (rms)'): split_name_unit would
    // say only that the unit goes in square brackets, and with the measure deleted alone the
    // values were read zero to peak (F_S 0.707 or 2 times the truth); its factor is named.
    if (const std::optional<MeasureAfterUnit> m = measure_after_unit(fields[i])) {
      if (lower(m->name) == "amplitude" || guess_column(m->name, m->unit, quantity).column == 0) {
        throw InputError(
            where(file, header_line,
                  fmt::format("column {} '{}': {}, then write 'amplitude [{}]'", i + 1,
                              shorten(fields[i]), measure_fix(m->measure), shorten(m->unit))));
      }
    }
    const auto [name, unit] = split_name_unit(fields[i], file, header_line);
    // Case-blind as the read columns are: a re-cased `process` output keeps its marks and k.
    const std::string lowered = lower(name);
    if (is_point_mark(lowered)) c.marks.push_back(i);
    if (lowered == "coverage_factor") c.coverage_col = static_cast<int>(i);
    if (lowered == "displacement_m") c.displacement_col = static_cast<int>(i);
    if (lowered == "coverage_factor" || lowered == "response_controlled") c.ours = true;
    // Names are read case-blind ("Amplitude", "Frequency_Hz"), as a test file's "time" is.
    const auto k =
        static_cast<size_t>(std::find(kNames.begin(), kNames.end(), lowered) - kNames.begin());
    if (k == kNames.size()) {
      guesses[i] = guess_column(name, unit, quantity);
      if (is_curve_label(name)) c.labels.push_back(i);
      continue;
    }
    if (c.col[k] >= 0) {
      throw InputError(
          where(file, header_line,
                fmt::format("columns {} '{}' and {} '{}' are both {}: keep one", c.col[k] + 1,
                            shorten(fields[static_cast<size_t>(c.col[k])]), i + 1,
                            shorten(fields[i]), kNames[k])));
    }
    c.col[k] = static_cast<int>(i);
    if (!unit.empty()) c.scale[k] = unit_scale(k, unit, quantity, file, header_line);
    if (k == 0) c.amplitude_unit = unit;
  }
  c.needed = static_cast<size_t>(*std::max_element(c.col.begin(), c.col.end())) + 1;
  return c;
}

// Refuses a header without the three required columns, with an uncertainty under another name,
// or with one of the two uncertainties alone. `lines`: the cursor after the header, read on to
// find a header row further down.
void check_columns(std::string_view header, const std::vector<std::string>& fields,
                   const std::vector<Guess>& guesses, const Columns& c, const TextLines& lines,
                   const std::string& file, long header_line) {
  if (c.col[0] < 0 || c.col[1] < 0 || c.col[2] < 0) {
    refuse_header(header, fields, guesses, c.col, lines, file, header_line);
  }
  refuse_unread_uncertainties(fields, guesses, c.col, file, header_line);
  if ((c.col[3] < 0) != (c.col[4] < 0)) {
    throw InputError(where(file, header_line,
                           fmt::format("give both frequency_std_hz and damping_std, or neither "
                                       "(the table has {} alone)",
                                       kNames[c.col[3] >= 0 ? 3 : 4])));
  }
}

// Whether a line holds no row: blank, a '#' comment, or empty cells only (a spreadsheet's ",,"),
// skipped anywhere. Otherwise `cells` holds its cells.
bool holds_no_row(std::string_view line, CsvLineSplitter& splitter,
                  std::vector<std::string>& cells) {
  const std::string_view trimmed =
      line.substr(std::min(line.find_first_not_of(" \t"), line.size()));
  if (trimmed.empty() || trimmed.front() == '#') return true;
  if (!splitter.split(line, cells)) return true;
  return std::all_of(cells.begin(), cells.end(),
                     [](const std::string& cell) { return trim(cell).empty(); });
}

// Refuses a row with fewer cells than the columns read need, or with more than the header
// names. With ',' between the columns, decimal commas split each number in two ("1,5" read as
// 1 and 5), and the row would be read shifted.
void check_cell_count(const std::vector<std::string>& cells, const Columns& c, char delim,
                      const std::string& file, long n) {
  if (cells.size() < c.needed) {
    throw InputError(where(
        file, n, fmt::format("{} cells, the header needs at least {}", cells.size(), c.needed)));
  }
  if (cells.size() > c.fields &&
      std::any_of(cells.begin() + static_cast<std::ptrdiff_t>(c.fields), cells.end(),
                  [](const std::string& cell) { return !trim(cell).empty(); })) {
    throw InputError(where(
        file, n,
        fmt::format("{} cells, the header names {}: {}", cells.size(), c.fields,
                    delim == ','
                        ? "decimal commas with ',' separators split each number in two "
                          "(write numbers with a decimal point, '0.0123'), or a column has no "
                          "name in the header row"
                        : "a column without a name in the header row")));
  }
}

// Whether a row is marked as not the mode's own (a mark cell that is a number other than 0).
bool marked(const std::vector<std::string>& cells, const Columns& c) {
  return std::any_of(c.marks.begin(), c.marks.end(), [&](size_t m) {
    if (m >= cells.size()) return false;
    const auto v = parse_double(cells[m]);
    return v && *v != 0;
  });
}

// The value of column k's cell in the table's units; InputError naming the line and the column
// for an empty cell, a decimal comma, a value that is not finite and > 0 (>= 0 for the
// uncertainties), and a damping ratio of 1 or more.
double read_cell(size_t k, const std::string& cell, const Columns& c, char delim,
                 const std::string& file, long n) {
  const auto v = parse_double(cell);
  const bool uncertainty = k >= 3;
  if (!v && trim(cell).empty()) {
    throw InputError(where(file, n,
                           fmt::format("column {} '{}' is empty: fill it or delete the row",
                                       c.col[k] + 1, kNames[k])));
  }
  // A decimal comma is never read as a decimal point: "1,234" may be a thousand.
  if (std::string point = cell; !v && cell.find(',') != std::string::npos) {
    std::replace(point.begin(), point.end(), ',', '.');
    if (parse_double(point)) {
      const std::string separator = delim == '\t' ? "tab" : fmt::format("'{}'", delim);
      throw InputError(
          where(file, n,
                fmt::format("decimal comma in '{}' (column {} '{}') with {} separators: write "
                            "numbers with a decimal point, '{}', and no thousands separators "
                            "(e.g. export with '.' as the decimal symbol)",
                            shorten(cell), c.col[k] + 1, kNames[k], separator, shorten(point))));
    }
  }
  if (!v || !std::isfinite(*v) || (uncertainty ? !(*v >= 0) : !(*v > 0))) {
    throw InputError(where(file, n,
                           fmt::format("{} '{}' must be a finite number {}", kNames[k], cell,
                                       uncertainty ? ">= 0" : "> 0")));
  }
  // A damping ratio of 1 or more is no ring-down (critical damping): per cent read as a
  // fraction (a table of 0.05-4.85 % ran to a fit with an RMS damping error of 99 %).
  if (k == 2 && *v * c.scale[k] >= 1) {
    // (Under a header already in per cent the value is no damping ratio either way.)
    throw InputError(
        where(file, n,
              c.scale[k] == 1.0
                  ? fmt::format("damping_ratio '{}' is not a fraction below 1; per cent? write the "
                                "header as 'damping_ratio [%]'",
                                cell)
                  : fmt::format("damping_ratio '{}' % is 1 or more, critical damping: no ring-down",
                                cell)));
  }
  return *v * c.scale[k];
}

// The rows read: each column's values in file order, and the coverage factor (0: none).
struct Rows {
  std::array<std::vector<double>, 5> values;
  double coverage = 0;
  /// Per Columns::labels column, each row's cell (trimmed) and line.
  std::vector<std::vector<std::pair<std::string, long>>> labels;
  std::vector<long> lines;  ///< each row's line
  /// Each row's displacement_m (NaN where none: no column, or no number).
  std::vector<double> displacement;
};

// Reads every row after the header: rows that hold none and marked rows skipped, each other one
// checked and its columns read.
Rows read_rows(TextLines& lines, char delim, const Columns& c, const std::string& file) {
  CsvLineSplitter splitter(delim);
  Rows rows;
  rows.labels.resize(c.labels.size());
  std::vector<std::string> cells;
  std::string_view line;
  while (lines.next(line)) {
    if (holds_no_row(line, splitter, cells)) continue;
    const long n = lines.line_no();
    check_cell_count(cells, c, delim, file, n);
    if (marked(cells, c)) continue;
    if (c.coverage_col >= 0 && static_cast<size_t>(c.coverage_col) < cells.size()) {
      const std::string& cell = cells[static_cast<size_t>(c.coverage_col)];
      rows.coverage =
          coverage_factor_of_row(parse_double(cell).value_or(NAN), rows.coverage, cell, file, n);
    }
    for (size_t k = 0; k < kNames.size(); ++k) {
      if (c.col[k] < 0) continue;
      rows.values[k].push_back(
          read_cell(k, cells[static_cast<size_t>(c.col[k])], c, delim, file, n));
    }
    for (size_t j = 0; j < c.labels.size(); ++j) {
      const size_t i = c.labels[j];
      rows.labels[j].emplace_back(i < cells.size() ? std::string(trim(cells[i])) : "", n);
    }
    rows.lines.push_back(n);
    const auto d = static_cast<size_t>(c.displacement_col);
    rows.displacement.push_back(
        c.displacement_col >= 0 && d < cells.size() ? parse_double(cells[d]).value_or(NAN) : NAN);
  }
  return rows;
}

// Refuses a `process` or `stepped-sine` backbone read as another quantity than it was written
// in: its displacement_m column gives amplitude = displacement_m (2 pi f)^p, p 0 for a
// displacement, 1 a velocity, 2 an acceleration (to 5 %, the median over the rows). Its own
// files are SI whatever the header says, so nothing else would say it: F_S came out scaled by
// (2 pi f)^(p - p read), 921 at 146.7 Hz for a velocity read as a displacement.
void refuse_another_quantity(const Rows& rows, std::optional<Quantity> quantity,
                             const std::string& file) {
  if (!quantity) return;
  const std::array<Quantity, 3> kinds = {Quantity::kDisplacement, Quantity::kVelocity,
                                         Quantity::kAcceleration};
  const auto read = std::find(kinds.begin(), kinds.end(), *quantity);
  if (read == kinds.end()) return;
  std::array<double, 3> miss{};
  for (int p = 0; p < 3; ++p) {
    std::vector<double> e;
    for (size_t i = 0; i < rows.displacement.size(); ++i) {
      const double d = rows.displacement[i];
      if (!(d > 0) || !std::isfinite(d)) continue;
      const double w = 2 * M_PI * rows.values[1][i];
      e.push_back(std::abs(std::log(rows.values[0][i] / d) - p * std::log(w)));
    }
    if (e.empty()) return;
    std::nth_element(e.begin(), e.begin() + static_cast<std::ptrdiff_t>(e.size() / 2), e.end());
    miss[static_cast<size_t>(p)] = e[e.size() / 2];
  }
  const auto written = static_cast<int>(std::min_element(miss.begin(), miss.end()) - miss.begin());
  const int asked = static_cast<int>(read - kinds.begin());
  if (miss[static_cast<size_t>(written)] > 0.05 || written == asked) return;
  static constexpr std::array<const char*, 3> kRatio = {"1", "2 pi f", "(2 pi f)^2"};
  static constexpr std::array<const char*, 5> kScale = {"1 / (2 pi f)^2", "1 / (2 pi f)", "1",
                                                        "2 pi f", "(2 pi f)^2"};
  const std::string name = quantity_name(kinds[static_cast<size_t>(written)]);
  throw InputError(where(
      file, 0,
      fmt::format("its amplitude is {} (amplitude / displacement_m = {} on every row, as process "
                  "and stepped-sine --amplitude {} write it), but it is read as {}: give "
                  "--amplitude {} (F_S "
                  "would come out scaled by {})",
                  with_article(name), kRatio[static_cast<size_t>(written)], name,
                  with_article(quantity_name(*quantity)), name,
                  kScale[static_cast<size_t>(written - asked + 2)])));
}

// Refuses hits one under another without a label column: each hit's rows run through its
// amplitudes in one direction (in time order, falling; or sorted), and the next hit's begin again
// at the other end. The rows fall apart, at the jumps against the rows' main direction of more
// than a quarter of the table's span of log amplitude, into two or more runs, each of four rows
// or more, a quarter of that span or more, and running the main way (rank correlation with the
// row 0.9 or more). Rows in any other order (shuffled, sorted, a stepped sine's levels up and
// down) are one curve; a ring-down's wiggles jump far less. (Six hits of a beam, K_T and F_S
// scattered 2 % and 3 % between them, in one such file: no sigma, and the structure's own
// damping named as the cause; one file per hit named the scatter and stated a sigma.)
void refuse_hits_one_under_another(const Rows& rows, const std::string& file) {
  std::vector<double> x, step;
  for (const double a : rows.values[0]) x.push_back(std::log(a));
  if (x.size() < 8) return;
  for (size_t i = 1; i < x.size(); ++i) step.push_back(x[i] - x[i - 1]);
  std::vector<double> sorted = step;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2),
                   sorted.end());
  const double direction = sorted[sorted.size() / 2] > 0 ? 1.0 : -1.0;
  if (sorted[sorted.size() / 2] == 0) return;
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double span = *hi - *lo;
  std::vector<size_t> starts = {0};
  for (size_t i = 1; i < x.size(); ++i)
    if (step[i - 1] * direction < -0.25 * span) starts.push_back(i);
  if (starts.size() < 2) return;
  starts.push_back(x.size());
  size_t shortest = x.size();
  for (size_t k = 0; k + 1 < starts.size(); ++k) {
    const std::vector<double> run(x.begin() + static_cast<std::ptrdiff_t>(starts[k]),
                                  x.begin() + static_cast<std::ptrdiff_t>(starts[k + 1]));
    const auto [rlo, rhi] = std::minmax_element(run.begin(), run.end());
    if (run.size() < 4 || *rhi - *rlo < 0.25 * span || rank_trend(run) * direction < 0.9) return;
    shortest = std::min(shortest, run.size());
  }
  const size_t j = starts[1];
  throw InputError(where(
      file, rows.lines[j],
      fmt::format("the amplitude jumps back {} here, from {:.4g} (line {}) to {:.4g}, and the "
                  "rows before and after run {} in amplitude ({} runs of {} rows or more): "
                  "several hits one under another? A backbone table is one curve, one hit or "
                  "test, per file: read as one, the hits' offsets from one another look like the "
                  "model's misfit, and the fit states no sigma or names a wrong cause; write each "
                  "hit's rows to a file of its own; if the rows are one curve, sort them by "
                  "amplitude",
                  direction < 0 ? "up" : "down", rows.values[0][j - 1], rows.lines[j - 1],
                  rows.values[0][j], direction < 0 ? "down" : "up", starts.size() - 1, shortest)));
}

// Refuses a table whose label column (is_curve_label) holds two or more values on two rows or
// more each: several hits one under another, a lab's long file. Read as one curve, the hits'
// offsets from one another looked like the model's misfit (six hits of a beam with K_T and F_S
// scattered between them: one file per hit named the scatter and stated F_S -0.30 % +/- 0.19 %;
// the same rows as one file stated no sigma and named no cause, or the structure's own damping
// where the scatter was larger). A value on one row only labels a point (a run per level).
void refuse_several_curves(const Rows& rows, const Columns& c,
                           const std::vector<std::string>& fields, const std::string& file) {
  for (size_t j = 0; j < c.labels.size(); ++j) {
    const auto& cells = rows.labels[j];
    std::vector<std::pair<std::string, size_t>> counts;  // value, rows
    for (const auto& cell : cells) {
      // Not a structured binding: clang (the fuzz build) refuses to capture one in a lambda.
      const std::string& value = cell.first;
      auto it = std::find_if(counts.begin(), counts.end(),
                             [&](const auto& v) { return v.first == value; });
      if (it == counts.end()) {
        counts.emplace_back(value, 1);
      } else {
        ++it->second;
      }
    }
    const auto curves =
        std::count_if(counts.begin(), counts.end(), [](const auto& v) { return v.second >= 2; });
    if (curves < 2) continue;
    const auto change = std::find_if(cells.begin(), cells.end(),
                                     [&](const auto& v) { return v.first != cells.front().first; });
    const std::string& name = fields[c.labels[j]];
    throw InputError(where(
        file, change->second,
        fmt::format("column {} '{}' changes from '{}' (line {}) to '{}' here: the file holds {} "
                    "curves ({} values of '{}'), and a backbone table is one curve, one hit or "
                    "test, per file: read as one, the hits' offsets from one another look like "
                    "the model's misfit, and the fit states no sigma or names a wrong cause; "
                    "write each hit's rows to a file of its own and give each file "
                    "(update-iwan --backbone, or a campaign mode's backbones)",
                    c.labels[j] + 1, shorten(name), shorten(cells.front().first),
                    cells.front().second, shorten(change->first), counts.size(), counts.size(),
                    shorten(name))));
  }
}

// The table of at least two rows, by increasing amplitude (rows of equal amplitude in file order).
BackboneTable sorted_table(const Rows& rows, const Columns& c, const std::string& file) {
  const size_t points = rows.values[0].size();
  if (points < 2) {
    throw InputError(where(
        file, 0, fmt::format("a backbone needs at least two points, the table has {}", points)));
  }
  std::vector<size_t> order(points);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return rows.values[0][a] < rows.values[0][b]; });
  BackboneTable t;
  t.source = file;
  t.amplitude_unit = c.amplitude_unit;
  t.written_by_jointlab = c.ours;
  if (rows.coverage > 0) t.coverage_factor = rows.coverage;
  t.has_uncertainty = !rows.values[3].empty();
  Eigen::VectorXd* out[] = {&t.amplitude, &t.frequency_hz, &t.damping_ratio, &t.frequency_std_hz,
                            &t.damping_std};
  for (size_t k = 0; k < kNames.size(); ++k) {
    out[k]->setZero(static_cast<Eigen::Index>(points));
    if (rows.values[k].empty()) continue;
    for (size_t i = 0; i < points; ++i)
      (*out[k])(static_cast<Eigen::Index>(i)) = rows.values[k][order[i]];
  }
  return t;
}

}  // namespace

BackboneTable read_backbone_table(const fs::path& path, std::optional<Quantity> quantity) {
  const std::string file = path.string();
  const auto text = read_text_file(path);
  if (!text) throw InputError(where(file, 0, "cannot open the backbone table"));
  TextLines lines(strip_bom(*text));
  const std::string_view header = read_preamble(lines, file, [](const auto&, const auto&) {});
  const long header_line = lines.line_no();
  const char delim = detect_delimiter(header);
  const std::vector<std::string> fields = CsvLineSplitter(delim).split(header);
  std::vector<Guess> guesses;  // what each field not read most likely means
  const Columns columns = resolve_columns(fields, quantity, guesses, file, header_line);
  check_columns(header, fields, guesses, columns, lines, file, header_line);
  const Rows rows = read_rows(lines, delim, columns, file);
  refuse_several_curves(rows, columns, fields, file);
  refuse_hits_one_under_another(rows, file);
  refuse_another_quantity(rows, quantity, file);
  return sorted_table(rows, columns, file);
}

namespace {

// Whether two tables hold the same points: as many, each amplitude, frequency and damping equal
// to 1e-9 relative (a copy re-saved with fewer digits), in amplitude order.
bool same_points(const BackboneTable& a, const BackboneTable& b) {
  const auto close = [](const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
    return ((x - y).array().abs() <= 1e-9 * x.array().abs().max(y.array().abs())).all();
  };
  return a.size() == b.size() && close(a.amplitude, b.amplitude) &&
         close(a.frequency_hz, b.frequency_hz) && close(a.damping_ratio, b.damping_ratio);
}

}  // namespace

std::vector<BackboneTable> read_backbone_tables(const std::vector<fs::path>& paths,
                                                std::optional<Quantity> quantity) {
  std::vector<BackboneTable> out;
  for (const fs::path& path : paths) {
    BackboneTable t = read_backbone_table(path, quantity);
    for (size_t i = 0; i < out.size(); ++i) {
      if (!same_points(out[i], t)) continue;
      const bool again = paths[i].lexically_normal() == path.lexically_normal();
      throw InputError(where(
          t.source, 0,
          fmt::format("{}: a hit's table given twice counts as two hits, its points weighed "
                      "twice and the stated sigmas shrunk by up to sqrt(2); give each hit once",
                      again ? "given twice"
                            : fmt::format("holds the same {} points as {} (every amplitude, "
                                          "frequency and damping equal)",
                                          t.size(), out[i].source))));
    }
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace jointlab::data
