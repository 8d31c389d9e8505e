#include "jointlab/correlate/measured_data.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <boost/math/distributions/students_t.hpp>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/correlate/mac.h"
#include "jointlab/correlate/noise_limits.h"
#include "jointlab/correlate/shape_checks.h"
#include "jointlab/data/backbone_table.h"
#include "jointlab/data/csv_lines.h"
#include "jointlab/data/json_reader.h"
#include "jointlab/data/output_stage.h"
#include "jointlab/model/linear_modes.h"

namespace jointlab::correlate {
namespace {

namespace fs = std::filesystem;
using data::JsonValue;

// Calls on_header(cells, line) for the first non-empty, non-comment line of a small CSV file
// and on_row(cells, line) for each later one, after checking it has the header's width;
// returns whether a header was seen. InputError naming the file ("cannot open the <what>").
// With `detect`, the cells are split at whichever of ',', ';' and tab the header holds most
// (data::detect_delimiter), else at ','.
template <typename OnHeader, typename OnRow>
bool for_each_csv_row(const fs::path& path, const std::string& what, OnHeader on_header,
                      OnRow on_row, bool detect = false) {
  const std::string name = path.string();
  const auto text = data::read_text_file(path);
  if (!text) throw InputError(fmt::format("{}: cannot open the {}", name, what));
  char delim = ',';
  if (detect) {
    data::TextLines lines(data::strip_bom(*text));
    std::string_view line;
    while (lines.next(line)) {
      const std::string_view t = trim(line);
      if (t.empty() || t.front() == '#') continue;
      delim = data::detect_delimiter(t);
      break;
    }
  }
  bool header = false;
  size_t width = 0;
  data::for_each_csv_line(
      *text,
      [&](const std::vector<std::string>& cells, long n) {
        if (!header) {
          on_header(cells, n);
          header = true;
          width = cells.size();
          return;
        }
        if (cells.size() != width) {
          // "(0.1,0.2)" unquoted in a comma-separated file is split in two.
          const bool split_pair =
              delim == ',' && std::any_of(cells.begin(), cells.end(), [](const std::string& c) {
                return !c.empty() && c.front() == '(' && c.back() != ')';
              });
          throw InputError(where(
              name, n,
              fmt::format("{} cells where the header has {}{}", cells.size(), width,
                          split_pair ? " (a complex cell written (re,im) splits at its comma in "
                                       "a comma-separated file: quote it, \"(0.1,0.2)\", or "
                                       "write 0.1+0.2i)"
                                     : "")));
        }
        on_row(cells, n);
      },
      delim);
  return header;
}

// What a shape column of a modes table holds: a whole entry (real or complex), or the real or
// imaginary part of one; kMagnitudeOrPhase (row -1) names a sensor's magnitude or phase column.
// kModalParameter (row -1) a column of what other tools export beside the shapes (damping,
// MPC, MPD, modal mass), which the linear update does not use and which is left out.
constexpr int kWhole = 0, kRealPart = 1, kImaginaryPart = 2, kMagnitudeOrPhase = 4,
              kModalParameter = 8;
struct TableColumn {
  int row = -1;        // sensor index, -1: none
  int part = kWhole;   // kWhole, kRealPart, kImaginaryPart or kMagnitudeOrPhase
  std::string header;  // as written
  std::string base;    // the sensor channel, for parts
};

// The column headed `header`: a sensor channel, or one with a suffix _re/_im (also _real/_imag,
// any case, after '_', '.' or ' ').
// Whether a modes-table column headed `header` (not a sensor channel) holds a modal parameter
// other tools export beside the shapes: damping (a ratio or in %), zeta, MPC, MPD, MCF, MOV or
// the modal mass, any case, a unit in brackets or after a blank or '_' allowed ("Damping [%]",
// "damping_ratio", "MPC (%)", "Modal mass").
bool modal_parameter_column(const std::string& header) {
  const std::string h(trim(lower(header.substr(0, header.find_first_of("[(")))));
  const auto begins = [&](std::string_view w) {
    return h.rfind(w, 0) == 0 &&
           (h.size() == w.size() || h[w.size()] == '_' || h[w.size()] == ' ' || h[w.size()] == '.');
  };
  for (const std::string_view w :
       {"damping", "damping_ratio", "damping ratio", "zeta", "mpc", "mpd", "mcf", "mov"})
    if (begins(w)) return true;
  return h == "modal_mass" || h == "modal mass";
}

TableColumn table_column(const std::vector<Sensor>& sensors, const std::string& header) {
  TableColumn out;
  out.header = header;
  out.row = find_sensor(sensors, header);
  if (out.row >= 0) return out;
  if (modal_parameter_column(header)) {
    out.part = kModalParameter;
    return out;
  }
  const size_t cut = header.find_last_of("_. ");
  if (cut == std::string::npos || cut == 0) return out;
  const std::string suffix = lower(header.substr(cut + 1));
  out.base = std::string(trim(std::string_view(header).substr(0, cut)));
  const int row = find_sensor(sensors, out.base);
  if (row < 0) return out;
  if (suffix == "re" || suffix == "real") {
    out.row = row, out.part = kRealPart;
  } else if (suffix == "im" || suffix == "imag") {
    out.row = row, out.part = kImaginaryPart;
  } else if (suffix == "mag" || suffix == "abs" || suffix == "amp" || suffix == "phase" ||
             suffix == "deg" || suffix == "arg") {
    out.part = kMagnitudeOrPhase;
  }
  return out;
}

// A cell as a complex number: a real number, a+bi or a-bj (blanks allowed, i or j, optionally
// in round brackets, "bi" alone imaginary), or (a,b); nothing else, and finite parts only.
std::optional<std::complex<double>> complex_cell(const std::string& cell) {
  std::string t;
  for (const char ch : cell)
    if (!std::isspace(static_cast<unsigned char>(ch))) t += ch;
  if (t.size() >= 2 && t.front() == '(' && t.back() == ')') t = t.substr(1, t.size() - 2);
  const auto real = [](std::string_view x) -> std::optional<double> {
    const std::optional<double> v = data::parse_double(x);
    if (!v || !std::isfinite(*v)) return std::nullopt;
    return v;
  };
  if (const size_t comma = t.find(','); comma != std::string::npos) {
    if (cell.find('(') == std::string::npos) return std::nullopt;  // "0,5": a decimal comma?
    const auto re = real(std::string_view(t).substr(0, comma));
    const auto im = real(std::string_view(t).substr(comma + 1));
    if (!re || !im) return std::nullopt;
    return std::complex<double>(*re, *im);
  }
  if (t.empty()) return std::nullopt;
  const char last = static_cast<char>(std::tolower(static_cast<unsigned char>(t.back())));
  if (last != 'i' && last != 'j') {
    const auto re = real(t);
    if (!re) return std::nullopt;
    return std::complex<double>(*re, 0.0);
  }
  const std::string_view body = std::string_view(t).substr(0, t.size() - 1);
  // The imaginary part starts at the last sign that is neither first nor an exponent's.
  size_t split = std::string_view::npos;
  for (size_t k = body.size(); k-- > 1;) {
    if ((body[k] == '+' || body[k] == '-') && body[k - 1] != 'e' && body[k - 1] != 'E') {
      split = k;
      break;
    }
  }
  const std::string_view re_text = split == std::string_view::npos ? "" : body.substr(0, split);
  const std::string_view im_text = split == std::string_view::npos ? body : body.substr(split);
  std::optional<double> re = re_text.empty() ? std::optional<double>(0.0) : real(re_text);
  std::optional<double> im = im_text.empty() || im_text == "+" ? std::optional<double>(1.0)
                             : im_text == "-"                  ? std::optional<double>(-1.0)
                                                               : real(im_text);
  if (!re || !im) return std::nullopt;
  return std::complex<double>(*re, *im);
}

}  // namespace

MeasuredBackbone sized_backbone(BackboneKind kind, int sensor, Eigen::Index points) {
  MeasuredBackbone b;
  b.kind = kind;
  b.sensor = sensor;
  for (Eigen::VectorXd* v :
       {&b.amplitude, &b.frequency_hz, &b.damping_ratio, &b.frequency_std_hz, &b.damping_std})
    v->setZero(points);
  return b;
}

std::vector<MeasuredBackbone> stepped_sine_backbones(const data::SteppedSineRun& run, int sensor) {
  std::vector<MeasuredBackbone> out;
  for (const data::SteppedSineOutput& o : run.outputs) {
    if (o.file.empty()) continue;
    out.push_back(read_backbone_csv(run.dir / o.file, sensor));
    out.back().kind = BackboneKind::kSteppedSine;
    out.back().coverage_factor = run.coverage_factor;
  }
  if (out.empty()) {
    throw InputError(fmt::format("{}: no file gave a stepped-sine backbone",
                                 (run.dir / "summary.json").string()));
  }
  return out;
}

LinearSpread linear_spread(const std::string& mode, const std::vector<LinearReading>& readings,
                           double frequency_std, const std::string& unit) {
  LinearSpread out;
  const size_t n = readings.size();
  if (n == 0) return out;
  double sum = 0, lo = readings[0].frequency_hz, hi = lo, stated2 = 0, largest = 0;
  double level_lo = readings[0].level, level_hi = level_lo;
  bool all_stated = true;
  for (const LinearReading& r : readings) {
    sum += r.frequency_hz;
    lo = std::min(lo, r.frequency_hz), hi = std::max(hi, r.frequency_hz);
    level_lo = std::min(level_lo, r.level), level_hi = std::max(level_hi, r.level);
    all_stated = all_stated && r.std_hz > 0;
    stated2 += r.std_hz * r.std_hz / static_cast<double>(n);
    largest = std::max(largest, r.std_hz);
  }
  const double mean = sum / static_cast<double>(n);
  out.frequency_hz = mean;
  if (n < 2) return out;
  // The chi-square about the weighted mean, where it is least (about the plain mean it rejects
  // too often where the stated uncertainties differ).
  double ss = 0, chi2 = 0, wsum = 0, wf = 0;
  for (const LinearReading& r : readings) {
    ss += (r.frequency_hz - mean) * (r.frequency_hz - mean);
    if (all_stated) wsum += 1 / (r.std_hz * r.std_hz), wf += r.frequency_hz / (r.std_hz * r.std_hz);
  }
  if (all_stated)
    for (const LinearReading& r : readings)
      chi2 += std::pow((r.frequency_hz - wf / wsum) / r.std_hz, 2);
  const int dof = static_cast<int>(n) - 1;
  const double sd = std::sqrt(ss / dof);
  // Unstated uncertainties cannot show agreement: the spread is then all there is.
  const bool disagree = !all_stated || chi2 / dof > reduced_chi2_limit(dof);
  if (!disagree || !(sd > 0)) return out;
  // A line f = a + b ln(level): its slope below 0 by more than 3 sigmas (the residuals' scatter
  // or the stated uncertainties, the larger) is a frequency that falls as the level rises.
  if (level_lo > 0 && level_hi >= 2 * level_lo) {
    double mx = 0;
    for (const LinearReading& r : readings) mx += std::log(r.level) / static_cast<double>(n);
    double sxx = 0, sxy = 0;
    for (const LinearReading& r : readings) {
      sxx += std::pow(std::log(r.level) - mx, 2);
      sxy += (std::log(r.level) - mx) * (r.frequency_hz - mean);
    }
    const double b = sxy / sxx;
    double var = stated2, limit = 3;
    if (n > 2) {
      double ssr = 0;
      for (const LinearReading& r : readings)
        ssr += std::pow(r.frequency_hz - mean - b * (std::log(r.level) - mx), 2);
      // Estimated from the residuals, the slope's ratio to its sigma is Student's t with n - 2
      // degrees of freedom, not a normal: the normal's 3 called 10 % of trendless 3-level sets
      // falling, 4.9 % of 4-level ones. Its one-sided 1 % point (6.96, 4.54, 3.75 for n = 4, 5,
      // 6): the 3-sigma point (19.2 at n = 4) missed the two-set beam's 5 N / 15 N files, 1 Hz
      // apart at 0.03 Hz within each pair (t = 8).
      if (ssr / static_cast<double>(n - 2) > var) {
        var = ssr / static_cast<double>(n - 2);
        limit = boost::math::quantile(
            boost::math::complement(boost::math::students_t(static_cast<double>(n - 2)), 0.01));
      }
    }
    out.falls_with_level = var > 0 && b < -limit * std::sqrt(var / sxx);
  }
  out.relative_std = out.falls_with_level ? (hi - lo) / mean : sd / mean;
  if (!(out.relative_std > frequency_std)) return out;
  std::vector<std::string> each;
  double low_sum = 0;
  int low_count = 0;
  for (const LinearReading& r : readings) {
    const bool lowest = out.falls_with_level && r.level <= 2 * level_lo;
    if (lowest) low_sum += r.frequency_hz, ++low_count;
    each.push_back(r.level > 0 ? fmt::format("{} {:.2f} Hz at {:.3g}{}", r.source, r.frequency_hz,
                                             r.level, unit.empty() ? "" : " " + unit)
                               : fmt::format("{} {:.2f} Hz", r.source, r.frequency_hz));
  }
  // What the spread exceeds: the update's uncertainty, and the readings' own where stated.
  const std::string beyond =
      all_stated ? fmt::format(
                       "more than the update's frequency uncertainty ({:.2g} %) and than their "
                       "stated uncertainties (up to {:.2g} Hz) allow",
                       100 * frequency_std, largest)
                 : fmt::format(
                       "more than the update's frequency uncertainty ({:.2g} %) allows (not "
                       "every one states its own)",
                       100 * frequency_std);
  if (out.falls_with_level) {
    out.frequency_hz = low_sum / low_count;
    // The range over the value, as a relative uncertainty of the value.
    out.relative_std = (hi - lo) / out.frequency_hz;
    out.note = fmt::format(
        "{}: the {} files' linear frequencies ({}) spread over {:.2f} to {:.2f} Hz, {}, and fall "
        "as the hit's level (the lowest amplitude each read) rises: the "
        "joint still slips at the lowest amplitudes read, so every one is below the linear "
        "frequency and the stiffness of the joint sets this mode fixes comes out biased low. "
        "The update takes the lowest-level files' {:.2f} Hz (levels within a factor 2 of the "
        "lowest, {} of {}) with an uncertainty of {:.2g} % (their range, by which the update "
        "divides this mode's residual; the other modes keep theirs), which covers the change the "
        "levels read make, not what lies below the lowest: hit more gently, or read lower "
        "amplitudes, for the linear value",
        mode, n, fmt::join(each, ", "), lo, hi, beyond, out.frequency_hz, low_count, n,
        100 * out.relative_std);
  } else {
    out.note = fmt::format(
        "{}: the {} files' linear frequencies ({}) spread over {:.2f} to {:.2f} Hz (standard "
        "deviation {:.3g} Hz), {}, with no trend with the hit's level: the "
        "update takes their mean {:.2f} Hz with an uncertainty of {:.2g} % (their standard "
        "deviation, by which the update divides this mode's residual; the other modes keep "
        "theirs)",
        mode, n, fmt::join(each, ", "), lo, hi, sd, beyond, mean, 100 * out.relative_std);
  }
  return out;
}

MeasuredModes measured_modes(const data::ProcessRun& run, const std::vector<Sensor>& sensors,
                             std::vector<int>* bands, double frequency_std) {
  const std::string summary = (run.dir / "summary.json").string();
  std::map<int, std::vector<const data::ProcessBand*>> by_band;
  for (const data::ProcessBand& b : run.bands) {
    if (b.linear_frequency_hz > 0) by_band[b.band].push_back(&b);
  }
  if (by_band.empty()) throw InputError(fmt::format("{}: no band has a linear frequency", summary));
  MeasuredModes m;
  const auto n_s = static_cast<Eigen::Index>(sensors.size());
  m.frequency_hz.resize(static_cast<Eigen::Index>(by_band.size()));
  m.shapes = Eigen::MatrixXcd::Zero(n_s, m.frequency_hz.size());
  if (bands) bands->clear();
  Eigen::Index col = 0;
  bool any_sensor = false;
  m.frequency_std = Eigen::VectorXd::Zero(m.frequency_hz.size());
  const std::string unit = si_unit(run.amplitude);
  for (const auto& [k, list] : by_band) {
    std::vector<LinearReading> readings;
    int best_count = -1;
    const data::ProcessBand* best = nullptr;
    for (const data::ProcessBand* b : list) {
      // process states k sigma (coverage_factor, 3 by default): the test wants one sigma (read
      // as one, files 0.6 Hz apart at 0.08 Hz each were taken to agree, chi-square 3.1 not 28).
      readings.push_back({b->source, b->linear_frequency_hz,
                          b->linear_frequency_std_hz / run.coverage_factor,
                          b->linear_fit_amplitude_min});
      int count = 0;
      for (const auto& [channel, value] : b->shape) count += find_sensor(sensors, channel) >= 0;
      if (count > best_count) best_count = count, best = b;
    }
    const LinearSpread spread =
        linear_spread(fmt::format("band {}", k), readings, frequency_std, unit);
    m.frequency_hz(col) = spread.frequency_hz;
    m.frequency_std(col) = spread.relative_std;
    if (!spread.note.empty()) m.warnings.push_back(spread.note);
    for (const auto& [channel, value] : best->shape) {
      const int s = find_sensor(sensors, channel);
      if (s >= 0) m.shapes(s, col) = value, any_sensor = true;
    }
    m.labels.push_back(fmt::format("band{}", k));
    m.ids.push_back(std::to_string(k));
    if (bands) bands->push_back(k);
    ++col;
  }
  if (!any_sensor) {
    throw InputError(
        fmt::format("{}: no channel of the sensors file appears in any operating shape", summary));
  }
  return m;
}

MeasuredBackbone read_backbone_csv(const fs::path& path, int sensor) {
  const std::string name = path.string();
  const char* wanted[] = {"amplitude", "frequency_hz", "damping_ratio", "frequency_std_hz",
                          "damping_std"};
  int column[5] = {-1, -1, -1, -1, -1};
  std::vector<double> values[5];
  std::vector<size_t> marks;  // columns of data::is_point_mark: their marked rows are skipped
  int coverage_col = -1;      // process's coverage_factor: k of the std columns
  double coverage = 0;        // its value (0: none read)
  const auto on_header = [&](const std::vector<std::string>& cells, long n) {
    for (size_t c = 0; c < cells.size(); ++c)
      if (cells[c] == "coverage_factor") coverage_col = static_cast<int>(c);
    for (int k = 0; k < 5; ++k) {
      for (size_t c = 0; c < cells.size(); ++c) {
        if (cells[c] == wanted[k]) column[k] = static_cast<int>(c);
      }
      if (column[k] < 0)
        throw InputError(where(name, n, fmt::format("no column '{}' in the header", wanted[k])));
    }
    for (size_t c = 0; c < cells.size(); ++c) {
      if (data::is_point_mark(cells[c])) marks.push_back(c);
    }
  };
  const auto on_row = [&](const std::vector<std::string>& cells, long n) {
    for (const size_t c : marks) {
      if (c < cells.size() && !cells[c].empty() && std::strtod(cells[c].c_str(), nullptr) != 0)
        return;
    }
    if (coverage_col >= 0 && static_cast<size_t>(coverage_col) < cells.size()) {
      const std::string& cell = cells[static_cast<size_t>(coverage_col)];
      coverage =
          data::coverage_factor_of_row(std::strtod(cell.c_str(), nullptr), coverage, cell, name, n);
    }
    for (int k = 0; k < 5; ++k) {
      const std::string& cell = cells[static_cast<size_t>(column[k])];
      double x = 0;
      size_t used = 0;
      try {
        x = std::stod(cell, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != cell.size() || cell.empty() || !std::isfinite(x)) {
        throw InputError(
            where(name, n, fmt::format("{} '{}' is not a finite number", wanted[k], cell)));
      }
      if (k == 0 && !(x > 0)) throw InputError(where(name, n, "amplitude must be > 0"));
      if (k == 1 && !(x > 0)) throw InputError(where(name, n, "frequency_hz must be > 0"));
      if (k >= 3 && x < 0)
        throw InputError(where(name, n, fmt::format("{} must be >= 0", wanted[k])));
      values[k].push_back(x);
    }
  };
  const bool header = for_each_csv_row(path, "backbone file", on_header, on_row);
  if (!header) throw InputError(where(name, 0, "empty file, expected a backbone header"));
  if (values[0].empty()) throw InputError(where(name, 0, "no backbone point"));
  MeasuredBackbone b;
  b.sensor = sensor;
  b.source = name;  // for messages, and which hit a curve is where several are returned
  auto vec = [](const std::vector<double>& v) {
    return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
  };
  b.amplitude = vec(values[0]);
  b.frequency_hz = vec(values[1]);
  b.damping_ratio = vec(values[2]);
  b.frequency_std_hz = vec(values[3]);
  b.damping_std = vec(values[4]);
  if (coverage > 0) b.coverage_factor = coverage;
  return b;
}

BandChannel band_channel(const data::ProcessRun& run, const std::vector<Sensor>& sensors,
                         int band) {
  // Per sensor: the hits (sources) with a backbone there, and the hits naming it reference.
  std::vector<std::set<std::string>> with(sensors.size()), naming(sensors.size());
  std::vector<std::string> hits;  // in the order first met
  for (const data::ProcessBand& b : run.bands) {
    if (b.band != band) continue;
    if (std::find(hits.begin(), hits.end(), b.source) == hits.end()) hits.push_back(b.source);
    if (const int s = find_sensor(sensors, b.reference_channel); s >= 0)
      naming[static_cast<size_t>(s)].insert(b.source);
  }
  for (const data::ProcessOutput& o : run.outputs) {
    if (o.band != band || o.file.empty()) continue;
    if (const int s = find_sensor(sensors, o.channel); s >= 0)
      with[static_cast<size_t>(s)].insert(o.source);
  }
  std::optional<size_t> best;
  for (size_t s = 0; s < sensors.size(); ++s) {
    if (naming[s].empty()) continue;
    if (!best || with[s].size() > with[*best].size() ||
        (with[s].size() == with[*best].size() && naming[s].size() > naming[*best].size()))
      best = s;
  }
  BandChannel out;
  if (!best) return out;
  out.channel = sensors[*best].channel;
  // Which hits name another reference channel, and which have no backbone at this one.
  // Other channels in the order first met, each with its hits: "a5 in hit1, hit4".
  std::vector<std::pair<std::string, std::vector<std::string>>> named;
  std::vector<std::string> missing;
  size_t named_other = 0;
  for (const data::ProcessBand& b : run.bands) {
    if (b.band != band) continue;
    const std::string hit = fs::path(b.source).stem().string();
    if (b.reference_channel != out.channel) {
      auto it = std::find_if(named.begin(), named.end(),
                             [&](const auto& n) { return n.first == b.reference_channel; });
      if (it == named.end()) {
        named.emplace_back(b.reference_channel, std::vector<std::string>{});
        it = std::prev(named.end());
      }
      it->second.push_back(hit);
      ++named_other;
    }
    if (!with[*best].count(b.source)) missing.push_back(hit);
  }
  std::vector<std::string> others;
  for (const auto& [channel, in] : named)
    others.push_back(fmt::format("{} in {}", channel, fmt::join(in, ", ")));
  if (others.empty() && missing.empty()) return out;
  // Where every hit names it, a hit without a backbone there (its ring-down failed at that
  // channel) is left out all the same, and named.
  out.note = others.empty()
                 ? fmt::format(
                       "band {}: every hit is read at its reference channel {} (a backbone there "
                       "in {} of {} hits; --channel chooses another)",
                       band, out.channel, with[*best].size(), hits.size())
                 : fmt::format(
                       "band {}: the hits' reference channels differ ({}; {} in the other {}): "
                       "every hit is read at {} (a backbone there in {} of {} hits), so that "
                       "their curves share one amplitude (--channel chooses another)",
                       band, fmt::join(others, "; "), out.channel, hits.size() - named_other,
                       out.channel, with[*best].size(), hits.size());
  if (!missing.empty())
    out.note += fmt::format("; {} no backbone there and {} left out: {}",
                            missing.size() == 1 ? "one hit has" : "some hits have",
                            missing.size() == 1 ? "is" : "are", fmt::join(missing, ", "));
  return out;
}

std::vector<BandOutput> band_outputs(const data::ProcessRun& run,
                                     const std::vector<Sensor>& sensors, int band,
                                     const std::vector<std::string>& chosen, std::string* note) {
  for (const std::string& c : chosen) {
    if (find_sensor(sensors, c) < 0)
      throw InputError(fmt::format("channel '{}' is not in the sensors file", c));
  }
  std::vector<std::string> channels = chosen;
  if (channels.empty()) {
    BandChannel bc = band_channel(run, sensors, band);
    if (!bc.channel.empty()) channels.push_back(std::move(bc.channel));
    if (note) *note = std::move(bc.note);
  }
  std::vector<BandOutput> out;
  for (const data::ProcessOutput& o : run.outputs) {
    if (o.band != band || o.file.empty()) continue;
    const bool selected = std::find(channels.begin(), channels.end(), o.channel) != channels.end();
    const int s = find_sensor(sensors, o.channel);
    if (selected && s >= 0) out.push_back({&o, s});
  }
  if (out.empty()) {
    throw InputError(fmt::format(
        "{}: no backbone of band {} on {}", (run.dir / "summary.json").string(), band,
        chosen.empty() ? "a reference channel that is a sensor" : "the selected channels"));
  }
  return out;
}

std::vector<MeasuredBackbone> measured_backbones(const data::ProcessRun& run,
                                                 const std::vector<Sensor>& sensors, int band,
                                                 const std::vector<std::string>& chosen) {
  std::vector<MeasuredBackbone> out;
  for (const BandOutput& b : band_outputs(run, sensors, band, chosen))
    out.push_back(read_backbone_csv(run.dir / b.output->file, b.sensor));
  return out;
}

namespace {

// The sensors' channels, for a message: "z1, z2, z3" (the first 8, then how many more).
std::string sensor_channels(const std::vector<Sensor>& sensors) {
  std::vector<std::string> names;
  for (size_t i = 0; i < sensors.size() && i < 8; ++i) names.push_back(sensors[i].channel);
  if (sensors.size() > 8) names.push_back(fmt::format("and {} more", sensors.size() - 8));
  return fmt::format("{} channel{}: {}", sensors.size(), sensors.size() == 1 ? "" : "s",
                     fmt::join(names, ", "));
}

// The factor to Hz of a modes table's frequency column `cell` (column 2 of line n of `name`):
// `frequency_hz`, or a frequency named as test-modal tools write it (frequency, freq, f, fn,
// natural frequency, eigenfrequency; any case) with its unit in Hz or kHz given in brackets
// ([Hz], (kHz)) or after '_' (f_Hz, Frequency_kHz); 0 where the cell names no frequency. A
// frequency without a unit, or in any other, is refused naming the column; rad/s says to give Hz.
double frequency_column_scale(const std::string& name, long n, const std::string& cell) {
  const std::string f = lower(cell);
  const auto refuse = [&](const std::string& why) {
    return InputError(where(name, n, fmt::format("column 2 '{}': {}", printable(cell), why)));
  };
  if (f.find("rad") != std::string::npos || f.find("omega") != std::string::npos)
    throw refuse(
        "frequencies are read in Hz only, under frequency_hz: give them so (rad/s "
        "divided by 2 pi)");
  std::string base = f, unit, written;  // written: the unit as the cell gives it
  if (cell.find_first_of("[(") != std::string::npos) {
    // "Frequency [Hz]" or "Freq (Hz)" (data/csv_lines' splits); brackets that do not close the
    // cell name no frequency.
    const auto split = cell.find('[') != std::string::npos ? data::split_square_brackets(cell)
                                                           : data::split_round_brackets(cell);
    if (!split) return 0;
    base = lower(split->first);
    written = split->second;
    unit = lower(written);
  } else {
    for (const char* u : {"hz", "khz"})
      if (const std::string tail = std::string("_") + u; base.ends_with(tail)) {
        base.erase(base.size() - tail.size());
        unit = u;
      }
  }
  if (base == "frequency_hz") {  // frequency_hz [Hz]; in another unit, not frequency_hz
    if (unit == "hz") return 1;
    throw refuse(fmt::format("unit '{}' refused: frequency_hz is in Hz ([Hz] or no unit)",
                             printable(written)));
  }
  const std::vector<std::string> names = {"frequency",         "freq",          "f", "fn", "f_n",
                                          "natural frequency", "eigenfrequency"};
  if (std::find(names.begin(), names.end(), base) == names.end()) return 0;
  if (unit == "hz") return 1;
  if (unit == "khz") return 1e3;
  if (unit.empty())
    throw refuse(
        "a frequency needs its unit: write frequency_hz, or the unit in brackets ('Frequency "
        "[Hz]', 'Frequency [kHz]')");
  throw refuse(
      fmt::format("unit '{}' is not read: give the frequencies in Hz (frequency_hz) or kHz",
                  printable(written)));
}

// Whether a modes table's header cell names the mode column: `mode` in any case, or as test-modal
// tools write it, `Mode #`, `Mode No.`, `Mode number`, `mode_nr` (blanks, `_` and `.` aside).
// Before, `Mode #` was refused as "column 1 'Mode #' is not 'mode'".
bool mode_column(const std::string& cell) {
  std::string k;
  for (const char c : lower(cell))
    if (c != ' ' && c != '\t' && c != '_' && c != '.') k += c;
  return k == "mode" || k == "mode#" || k == "modeno" || k == "modenr" || k == "modenumber";
}

// The shape columns of a modes table from its header `cells` (line n of `name`), after the
// mode and frequency columns that must begin it (`to_hz` receives the frequency column's factor
// to Hz): each a sensor channel (or its real or imaginary part), none twice, every part beside
// its other part.
std::vector<TableColumn> modes_table_columns(const std::string& name,
                                             const std::vector<Sensor>& sensors,
                                             const std::vector<std::string>& cells, long n,
                                             double& to_hz) {
  std::vector<TableColumn> columns;
  to_hz = cells.size() >= 2 && mode_column(cells[0])
              ? (cells[1] == "frequency_hz" ? 1 : frequency_column_scale(name, n, cells[1]))
              : 0;
  if (to_hz == 0) {
    // What was found, as written, and where: a swapped pair says to swap it.
    std::string found;
    for (size_t c = 0; c < std::min<size_t>(cells.size(), 2); ++c) {
      if (c > 0) found += ',';
      found += printable(cells[c]);
    }
    const bool swapped =
        cells.size() >= 2 && mode_column(cells[1]) && (cells[0] == "frequency_hz" || [&] {
          try {
            return frequency_column_scale(name, n, cells[0]) > 0;
          } catch (const InputError&) {
            return false;
          }
        }());
    // update-linear's own modes.csv (measured,frequency_hz,model_mode,...) pairs the modes of a
    // past update; it holds no shapes to pair a new one with.
    const bool update_output =
        cells.size() >= 3 && cells[0] == "measured" && cells[2] == "model_mode";
    throw InputError(where(
        name, n,
        fmt::format("the header must begin with mode,frequency_hz (or a frequency with its unit, "
                    "'Frequency [Hz]'); it begins '{}'{}",
                    found,
                    update_output
                        ? ": this is the modes.csv update-linear writes (measured against model "
                          "modes), not a modes table; give --measured DIR or a table of mode, "
                          "frequency_hz and one shape column per sensor"
                    : swapped ? ": put the mode column first"
                    : cells.empty() || !mode_column(cells[0])
                        ? fmt::format(", column 1 '{}' is not 'mode'",
                                      cells.empty() ? "" : printable(cells[0]))
                        : fmt::format(", column 2 '{}' names no frequency",
                                      cells.size() < 2 ? "" : printable(cells[1])))));
  }
  for (size_t c = 2; c < cells.size(); ++c) {
    const TableColumn col = table_column(sensors, cells[c]);
    if (col.part == kModalParameter) {
      columns.push_back(col);
      continue;
    }
    if (col.row < 0) {
      throw InputError(where(
          name, n,
          col.part == kMagnitudeOrPhase
              ? fmt::format("column '{}': magnitude or phase columns are not read; give the "
                            "real and imaginary parts ({}_re, {}_im) or complex cells (0.1+0.2i)",
                            cells[c], col.base, col.base)
              : fmt::format("column '{}' is not a sensor channel (the sensors file has {}); a "
                            "modes table's columns are mode, frequency_hz, one per channel (or "
                            "its _re and _im parts), and damping, MPC, MPD or modal mass "
                            "columns, which are left out: rename or remove it",
                            cells[c], sensor_channels(sensors))));
    }
    for (const TableColumn& other : columns) {
      if (other.part != kModalParameter && other.row == col.row &&
          (other.part == col.part || other.part == kWhole || col.part == kWhole)) {
        throw InputError(where(name, n,
                               fmt::format("column '{}': sensor channel {} twice", cells[c],
                                           sensors[static_cast<size_t>(col.row)].channel)));
      }
    }
    columns.push_back(col);
  }
  for (const TableColumn& col : columns) {
    if (col.part != kRealPart && col.part != kImaginaryPart) continue;
    const bool paired = std::any_of(columns.begin(), columns.end(), [&](const TableColumn& o) {
      return o.row == col.row && o.part == kRealPart + kImaginaryPart - col.part;
    });
    if (!paired) {
      throw InputError(where(name, n,
                             fmt::format("column '{}' has no {} part beside it ({}_{})", col.header,
                                         col.part == kRealPart ? "imaginary" : "real", col.base,
                                         col.part == kRealPart ? "im" : "re")));
    }
  }
  return columns;
}

// The shape of one modes-table row (`cells`, line n of `name`) at the sensors, complex, 0 where
// a sensor has no entry; a sensor with one part of two given is refused. `number` reads cell c.
template <class Number>
Eigen::VectorXcd row_shape(const std::string& name, const std::vector<Sensor>& sensors,
                           const std::vector<TableColumn>& columns,
                           const std::vector<std::string>& cells, long n, const Number& number) {
  const auto n_s = static_cast<Eigen::Index>(sensors.size());
  Eigen::VectorXcd v = Eigen::VectorXcd::Zero(n_s);
  std::vector<char> given(sensors.size(), 0);  // per sensor: parts given (1 real, 2 imaginary)
  for (size_t c = 2; c < cells.size(); ++c) {
    const TableColumn& col = columns[c - 2];
    const std::string& cell = cells[c];
    if (cell.empty() || col.part == kModalParameter) continue;
    if (col.part == kWhole) {
      const std::optional<std::complex<double>> z = complex_cell(cell);
      if (!z) {
        std::string point = cell;  // a decimal comma (a European export) names itself
        std::replace(point.begin(), point.end(), ',', '.');
        const bool comma = point != cell && data::parse_double(point).has_value();
        throw InputError(
            where(name, n,
                  comma ? fmt::format("shape entry '{}' of column '{}' is not a number (a decimal "
                                      "comma: write {} with a decimal point; ';' or tab may still "
                                      "separate the cells)",
                                      cell, col.header, point)
                        : fmt::format("shape entry '{}' of column '{}' is not a number (real, or "
                                      "complex as 0.1+0.2i, 0.1-0.2j or (0.1,0.2))",
                                      cell, col.header)));
      }
      v(col.row) = *z;
      given[static_cast<size_t>(col.row)] = 3;
      continue;
    }
    const double x = number(c, "shape entry");
    if (col.part == kRealPart)
      v(col.row).real(x);
    else
      v(col.row).imag(x);
    given[static_cast<size_t>(col.row)] |= static_cast<char>(col.part);
  }
  for (const TableColumn& col : columns) {
    if (col.part == kModalParameter) continue;
    const char g = given[static_cast<size_t>(col.row)];
    if (col.part != kWhole && g != 0 && g != 3) {
      throw InputError(
          where(name, n,
                fmt::format("sensor {}: its {} part is given and its {} part empty: give both or "
                            "neither (neither: not measured)",
                            sensors[static_cast<size_t>(col.row)].channel,
                            g == kRealPart ? "real" : "imaginary",
                            g == kRealPart ? "imaginary" : "real")));
    }
  }
  return v;
}

// Shape v of `mode` (line n of `name`) as the real shape nearest it: refused below kMpcRefused,
// a warning into `warnings` below kMpcPoor. Parts given as 0 and 0 are an entry of 0, which
// reads as not measured (mac.h).
Eigen::VectorXd real_shape(const std::string& name, long n, int mode, const Eigen::VectorXcd& v,
                           std::vector<std::string>& warnings) {
  Eigen::VectorXd real = v.real();
  if (v.imag().squaredNorm() > 0) {
    const RealisedShape r = realise(v);
    const std::string what = fmt::format(
        "mode {}'s shape is complex: its modal phase collinearity MPC is {:.3f} (1 for a "
        "real normal mode), and the imaginary part left out at the phase that makes it "
        "most nearly real holds {:.1f} % of it",
        mode, r.mpc, 100 * r.imaginary_share);
    if (r.mpc < kMpcRefused) {
      throw InputError(
          where(name, n,
                fmt::format("{}: a real normal-mode model cannot match a shape so complex (MPC "
                            "below {}); check the export (real and imaginary parts, not magnitude "
                            "and phase), or leave its shape cells empty to pair it by frequency "
                            "alone, or leave the mode out",
                            what, kMpcRefused)));
    }
    if (r.mpc < kMpcPoor) {
      warnings.push_back(
          where(name, n,
                fmt::format("{}: it is paired and fitted as that real part, which a real "
                            "normal-mode model matches only in part (MPC below {}): its MAC "
                            "reads that part alone",
                            what, kMpcPoor)));
    }
    real = r.shape;
  }
  return real;
}

}  // namespace

MeasuredModes read_modes_table(const fs::path& path, const std::vector<Sensor>& sensors,
                               std::vector<int>* modes) {
  const std::string name = path.string();
  std::vector<TableColumn> columns;  // what each shape column holds
  std::vector<int> numbers;
  std::vector<double> freq;
  std::vector<Eigen::VectorXd> shape;
  std::vector<std::string> warnings;
  double to_hz = 1;  // the frequency column's unit: Hz or kHz
  const auto on_header = [&](const std::vector<std::string>& cells, long n) {
    columns = modes_table_columns(name, sensors, cells, n, to_hz);
  };
  const auto on_row = [&](const std::vector<std::string>& cells, long n) {
    auto number = [&](size_t c, const char* what) {
      const std::optional<double> x = data::parse_double(cells[c]);
      if (!x || !std::isfinite(*x)) {
        // A decimal comma (a European export): say so where a point would read.
        std::string point = cells[c];
        std::replace(point.begin(), point.end(), ',', '.');
        const bool comma = point != cells[c] && data::parse_double(point).has_value();
        throw InputError(where(
            name, n,
            fmt::format("{} '{}' is not a number{}", what, cells[c],
                        comma ? fmt::format(" (a decimal comma: write {} with a decimal point; "
                                            "';' or tab may still separate the cells)",
                                            point)
                              : "")));
      }
      return *x;
    };
    const double mode = number(0, "mode");
    if (mode != std::floor(mode) || mode < 1) {
      throw InputError(where(name, n, fmt::format("mode '{}' must be an integer >= 1", cells[0])));
    }
    for (int m : numbers) {
      if (m == static_cast<int>(mode)) {
        throw InputError(where(name, n, fmt::format("mode {} twice", m)));
      }
    }
    const double f = to_hz * number(1, "frequency_hz");
    if (!(f > 0)) throw InputError(where(name, n, "frequency_hz must be > 0"));
    const Eigen::VectorXcd v = row_shape(name, sensors, columns, cells, n, number);
    Eigen::VectorXd real = real_shape(name, n, static_cast<int>(mode), v, warnings);
    numbers.push_back(static_cast<int>(mode));
    freq.push_back(f);
    shape.push_back(std::move(real));
  };
  for_each_csv_row(path, "modes table", on_header, on_row, /*detect_delimiter=*/true);
  if (freq.empty()) throw InputError(fmt::format("{}: no mode in the table", name));
  MeasuredModes out;
  const auto count = static_cast<Eigen::Index>(freq.size());
  out.frequency_hz.resize(count);
  out.shapes = Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(sensors.size()), count);
  for (Eigen::Index i = 0; i < count; ++i) {
    out.frequency_hz(i) = freq[static_cast<size_t>(i)];
    out.shapes.col(i) = shape[static_cast<size_t>(i)].cast<std::complex<double>>();
    out.labels.push_back(fmt::format("mode {}", numbers[static_cast<size_t>(i)]));
    out.ids.push_back(std::to_string(numbers[static_cast<size_t>(i)]));
  }
  out.warnings = std::move(warnings);
  if (modes) *modes = numbers;
  return out;
}

int measured_mode_of(const model::Model& model, const std::vector<Sensor>& sensors,
                     const MeasuredModes& measured, int mode, double mac_threshold) {
  const model::LinearModes modes = model::linear_modes(model.mass, model.linear_stiffness());
  const int elastic = modes.size() - modes.rigid_count;
  if (mode < 1 || mode > elastic) {
    throw InputError(
        fmt::format("mode {}: the model has {}", mode, counted(elastic, "elastic mode")));
  }
  const Eigen::MatrixXd model_shapes = shapes_at_sensors(sensors, modes.shapes.rightCols(elastic));
  const Pairing p = pair_modes(mac_matrix(measured.shapes, model_shapes), mac_threshold);
  for (const ModePair& pair : p.pairs) {
    if (pair.model == mode - 1) return pair.measured;
  }
  return -1;
}

ModeShapeMatch mode_shape_match(const model::Model& model, const std::vector<Sensor>& sensors,
                                const MeasuredModes& measured, int column, int mode) {
  const model::LinearModes modes = model::linear_modes(model.mass, model.linear_stiffness());
  const int elastic = modes.size() - modes.rigid_count;
  if (mode < 1 || mode > elastic || column < 0 || column >= measured.shapes.cols()) {
    throw InputError(
        fmt::format("mode {}: the model has {}", mode, counted(elastic, "elastic mode")));
  }
  const Eigen::MatrixXd model_shapes = shapes_at_sensors(sensors, modes.shapes.rightCols(elastic));
  const Eigen::MatrixXd row = mac_matrix(measured.shapes.col(column), model_shapes);
  ModeShapeMatch out;
  out.mac = row(0, mode - 1);
  Eigen::Index best = 0;
  out.best_mac = row.row(0).maxCoeff(&best);
  out.best_mode = static_cast<int>(best) + 1;
  // A low MAC from a sign: each sensor, and each pair, reversed (shape_checks.h; update-linear
  // tries the same for every measured mode at its start).
  if (out.mac >= 0.6) return out;
  const Reversal r = best_reversal(measured.shapes.col(column), model_shapes.col(mode - 1));
  if (r.mac >= 0.9) out.reversed = r.channels, out.reversed_mac = r.mac;
  return out;
}

BackboneCurves read_backbone_curves(const std::vector<std::string>& files,
                                    std::optional<Quantity> quantity, int sensor) {
  BackboneCurves out;
  // One hit given twice would count as two: refused (read_backbone_tables).
  const std::vector<data::BackboneTable> tables =
      data::read_backbone_tables({files.begin(), files.end()}, quantity);
  for (size_t i = 0; i < files.size(); ++i) {
    const data::BackboneTable& table = tables[i];
    if (table.amplitude_unit_assumed()) out.unitless.push_back(files[i]);
    out.curves.push_back(measured_backbone(table, sensor));
  }
  return out;
}

MeasuredBackbone measured_backbone(const data::BackboneTable& table, int sensor) {
  MeasuredBackbone b;
  b.kind = BackboneKind::kRingdown;
  b.modal = sensor < 0;
  b.sensor = sensor < 0 ? 0 : sensor;
  b.source = table.source;
  b.amplitude = table.amplitude;
  b.frequency_hz = table.frequency_hz;
  b.damping_ratio = table.damping_ratio;
  b.frequency_std_hz = table.frequency_std_hz;
  b.damping_std = table.damping_std;
  b.coverage_factor = table.coverage_factor;
  return b;
}

std::string amplitude_reading(int mode, const std::string& quantity, bool defaulted,
                              const std::string& dof_name, const std::string& dof,
                              const std::vector<std::string>& unitless) {
  if (quantity == "modal") {
    return fmt::format(
        "amplitudes read as mode {}'s QSMA modal amplitude q (--amplitude modal{}); a sensor's "
        "displacement, velocity or acceleration needs --amplitude and --dof, else F_S comes out "
        "scaled by the mode's shape value at that sensor",
        mode, defaulted ? ", the default" : "");
  }
  const std::string assumed = unitless_amplitudes(unitless, quantity);
  return fmt::format(
      "amplitudes read as the {} at model DOF {} (--amplitude {} --dof {}), zero to peak{}",
      quantity, dof_name, quantity, dof, assumed.empty() ? "" : "; " + assumed);
}

std::string unitless_amplitudes(const std::vector<std::string>& unitless,
                                const std::string& quantity) {
  if (unitless.empty()) return "";
  return fmt::format(
      "{} give{} no unit in the amplitude header, so {} is assumed (a table in g or mm read so "
      "scales F_S by its factor: give the unit, e.g. 'amplitude [g]')",
      fmt::join(unitless, ", "), unitless.size() == 1 ? "s" : "",
      parse_quantity(quantity) ? si_unit(*parse_quantity(quantity)) : std::string("SI"));
}

}  // namespace jointlab::correlate
