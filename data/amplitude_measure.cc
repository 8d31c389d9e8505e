#include "jointlab/data/amplitude_measure.h"

#include <algorithm>
#include <cctype>
#include <initializer_list>
#include <utility>

#include "jointlab/core/text.h"

namespace jointlab::data {

std::vector<std::string> header_words(std::string_view name) {
  std::vector<std::string> out(1);
  for (const char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (std::isalnum(u) || u >= 0x80) {
      out.back().push_back(static_cast<char>(std::tolower(u)));
    } else if (!out.back().empty()) {
      out.emplace_back();
    }
  }
  if (out.back().empty()) out.pop_back();
  return out;
}

std::string amplitude_measure(std::string_view text) {
  const std::vector<std::string> words = header_words(text);
  const auto word = [&](std::initializer_list<const char*> ws) {
    return std::any_of(words.begin(), words.end(), [&](const std::string& w) {
      return std::any_of(ws.begin(), ws.end(), [&](const char* x) { return w == x; });
    });
  };
  std::string flat;  // the letters and digits alone: "peaktopeak", "pkpk"
  for (const std::string& w : words) flat += w;
  // "p-p" (two words "p"), as oscilloscopes and vibration meters write it.
  bool p_p = false;
  for (size_t i = 0; i + 1 < words.size(); ++i)
    p_p = p_p || (words[i] == "p" && words[i + 1] == "p");
  if (p_p || word({"pp", "p2p", "ptp", "pkpk", "peak2peak"}) ||
      flat.find("peaktopeak") != flat.npos || flat.find("pkpk") != flat.npos ||
      flat.find("pktopk") != flat.npos || flat.find("peakpeak") != flat.npos)
    return "peak-to-peak";
  if (word({"rms"})) return "RMS";
  return {};
}

std::string measure_factor(const std::string& measure) {
  return measure == "RMS" ? "multiply its values by sqrt(2) = 1.4142" : "halve its values";
}

std::string measure_fix(const std::string& measure) {
  return measure_factor(measure) +
         (measure == "RMS"
              ? " (an amplitude is read zero to peak, a sine's RMS times sqrt(2); read as it is, "
                "F_S comes out 0.707 times the truth)"
              : " (an amplitude is read zero to peak; peak-to-peak values read as they are give "
                "F_S twice the truth)");
}

namespace {

// A unit token that joins the measure to the unit ('grms', 'Grms', 'g_rms', 'Npp', 'm/s^2-pk-pk',
// 'g(rms)'): the measure's spelling as written after the unit, and the unit before it; none
// where the token does not end in a measure or what precedes it could be no unit.
std::optional<std::pair<std::string, std::string>> joined_measure(std::string_view token) {
  std::string_view body = token;
  if (body.ends_with(')')) body.remove_suffix(1);
  const std::string low = lower(body);
  for (const std::string_view s : {"peak-to-peak", "pk-to-pk", "peak-peak", "pk-pk", "pk_pk",
                                   "pkpk", "p-p", "p2p", "ptp", "pp", "rms"}) {
    if (low.size() <= s.size() || !low.ends_with(s)) continue;
    std::string_view unit = body.substr(0, body.size() - s.size());
    while (!unit.empty() && (unit.back() == '_' || unit.back() == '-' || unit.back() == '('))
      unit.remove_suffix(1);
    const bool unit_like = !unit.empty() && std::all_of(unit.begin(), unit.end(), [](char c) {
      const auto u = static_cast<unsigned char>(c);
      return std::isalnum(u) || u >= 0x80 || c == '/' || c == '^' || c == '*' || c == '.';
    });
    if (unit_like)
      return std::pair{std::string(body.substr(body.size() - s.size())), std::string(unit)};
  }
  return std::nullopt;
}

}  // namespace

std::optional<UnitMeasure> unit_measure(std::string_view unit) {
  UnitMeasure out;
  for (size_t at = 0; at < unit.size();) {
    const size_t end = std::min(unit.find(' ', at), unit.size());
    const std::string token(unit.substr(at, end - at));
    at = end + 1;
    if (token.empty()) continue;
    if (const auto joined = joined_measure(token)) {
      // The unit kept in the fix: 'g_rms' told "write 'amplitude'" read values in g as m/s^2.
      out.measure = amplitude_measure(joined->first);
      out.written = joined->first;
      out.rest += (out.rest.empty() ? "" : " ") + joined->second;
    } else if (const std::string m = amplitude_measure(token); !m.empty()) {
      out.measure = m;
      out.written = token;
    } else {
      out.rest += (out.rest.empty() ? "" : " ") + token;
    }
  }
  if (out.measure.empty()) return std::nullopt;
  return out;
}

std::string unit_without_measure(std::string_view unit) {
  const std::optional<UnitMeasure> m = unit_measure(unit);
  return m ? m->rest : std::string(trim(unit));
}

std::optional<MeasureAfterUnit> measure_after_unit(std::string_view field) {
  const size_t close = field.rfind(']');
  const size_t open = field.find('[');
  if (close == std::string_view::npos || !(open < close)) return std::nullopt;
  const std::string measure = amplitude_measure(field.substr(close + 1));
  if (measure.empty()) return std::nullopt;
  return MeasureAfterUnit{std::string(trim(field.substr(0, open))),
                          std::string(trim(field.substr(open + 1, close - open - 1))), measure};
}

}  // namespace jointlab::data
