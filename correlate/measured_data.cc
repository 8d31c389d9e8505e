#include "jointlab/correlate/measured_data.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>
#include <optional>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <boost/math/distributions/students_t.hpp>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"
#include "jointlab/correlate/mac.h"
#include "jointlab/correlate/noise_limits.h"
#include "jointlab/correlate/shape_checks.h"
#include "jointlab/data/backbone_table.h"
#include "jointlab/model/linear_modes.h"

namespace jointlab::correlate {
namespace fs = std::filesystem;

MeasuredBackbone sized_backbone(BackboneKind kind, int sensor, Eigen::Index points) {
  MeasuredBackbone b;
  b.kind = kind;
  b.sensor = sensor;
  for (Eigen::VectorXd* v :
       {&b.amplitude, &b.frequency_hz, &b.damping_ratio, &b.frequency_std_hz, &b.damping_std})
    v->setZero(points);
  return b;
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

namespace {

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

std::vector<std::string> channels_of(const std::vector<Sensor>& sensors) {
  std::vector<std::string> out;
  for (const Sensor& s : sensors) out.push_back(s.channel);
  return out;
}

MeasuredModes measured_modes(const data::ModesTable& table,
                             [[maybe_unused]] const std::vector<Sensor>& sensors) {
  assert(table.shapes.rows() == static_cast<Eigen::Index>(sensors.size()));
  MeasuredModes out;
  const auto count = table.frequency_hz.size();
  out.frequency_hz = table.frequency_hz;
  out.shapes = Eigen::MatrixXcd::Zero(table.shapes.rows(), count);
  for (Eigen::Index i = 0; i < count; ++i) {
    const auto k = static_cast<size_t>(i);
    out.shapes.col(i) =
        real_shape(table.source, table.lines[k], table.modes[k], table.shapes.col(i), out.warnings)
            .cast<std::complex<double>>();
    out.labels.push_back(fmt::format("mode {}", table.modes[k]));
    out.ids.push_back(std::to_string(table.modes[k]));
  }
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

BackboneCurves backbone_curves(const std::vector<data::BackboneTable>& tables, int sensor) {
  BackboneCurves out;
  for (const data::BackboneTable& table : tables) {
    if (table.amplitude_unit_assumed()) out.unitless.push_back(table.source);
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
