#include "jointlab/campaign/steps/campaign_report.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "jointlab/campaign/option_keys.h"
#include "jointlab/campaign/steps/iwan_step.h"
#include "jointlab/campaign/steps/known_parameters.h"
#include "jointlab/modal/ringdown.h"

namespace jointlab::campaign {

namespace fs = std::filesystem;

namespace {

std::string g6(double v) { return fmt::format("{:.6g}", v); }
// A damping ratio or its spread to significant digits (a fixed number of decimals prints
// 0.00057 - 0.00057 for an interval of 5.68e-4 - 5.74e-4).
std::string zeta(double v) { return fmt::format("{:.3g}", v); }
// A spread in significant digits: a deviation of 3e-5 Hz is not "0.0000 Hz".
std::string spread(double v) { return fmt::format("{:.2g}", v); }
std::string pct(double v) { return fmt::format("{:+.3f} %", v); }

// At the very top of the report: each hit that could not be read or processed, and why.
ReportSection left_out_section(const RunSummary& summary) {
  ReportSection s;
  s.heading = "Hits left out";
  s.paragraphs.push_back(fmt::format(
      "{} hit(s) could not be read or processed and are left out of everything below; the "
      "next run tries them again.",
      summary.failed_hits.size()));
  ReportTable t{"Why each hit is left out", {"file", "group", "reason"}, {}};
  for (const FailedHit& f : summary.failed_hits)
    t.rows.push_back({f.file.string(), f.group, f.why});
  s.tables.push_back(t);
  return s;
}

// At the top of the report: each step not run because the step before gave a result it must
// not start from, and why.
ReportSection stopped_section(const RunSummary& summary) {
  ReportSection s;
  s.heading = "Steps not run";
  s.paragraphs = summary.stopped;
  return s;
}

// At the top of the report: each mode no hit gave a backbone for, and every hit's reason.
ReportSection no_backbone_section(const Campaign& c, const MeasuredSide& m) {
  ReportSection s;
  s.heading = "Modes without a backbone";
  for (size_t k = 0; k < c.modes.size(); ++k) {
    if (!m.curves[k].empty()) continue;
    s.paragraphs.push_back(fmt::format(
        "{} ({:g} - {:g} Hz band, channel {}): no backbone in any hit; its results are left "
        "out.{}",
        c.modes[k].name, c.modes[k].band.lo, c.modes[k].band.hi, c.modes[k].reference,
        k < m.reference_hint.size() && !m.reference_hint[k].empty()
            ? " At the other channels: " + m.reference_hint[k] + "."
            : ""));
    ReportTable t{fmt::format("{}: why each hit gave no backbone", c.modes[k].name),
                  {"hit", "group", "reason"},
                  {}};
    for (const HitSpan& h : m.spans[k])
      t.rows.push_back({h.hit, h.group, h.ok ? "backbone kept" : "no backbone: " + h.reason});
    s.tables.push_back(t);
  }
  return s;
}

ReportSection data_section(const Campaign& c, const RunSummary& summary,
                           const CampaignFigures& figures) {
  ReportSection s;
  s.heading = "Data processed";
  const bool has_model = !c.model.file.empty() || !c.model.description.empty();
  std::string channels;
  for (const CampaignChannel& ch : c.channels) {
    if (!channels.empty()) channels += ", ";
    channels += ch.name;
    if (!ch.dof.empty() && has_model) channels += fmt::format(" (model DOF {})", ch.dof);
  }
  s.paragraphs.push_back(fmt::format(
      "Campaign file {}. {} hit(s) in {} group(s); channels {}; {} mode(s). {}; backbone "
      "amplitudes are {} amplitudes [{}].",
      c.file.string(), summary.hits, c.groups.size(), channels, c.modes.size(),
      c.quantity ? fmt::format("Channels without a unit measure {}", quantity_name(*c.quantity))
                 : std::string("Every channel's unit is taken from its file"),
      quantity_name(c.amplitude), si_unit(c.amplitude)));
  ReportTable t{"Groups", {"group", "level", "hits", "files"}, {}};
  for (const CampaignGroup& g : c.groups) {
    std::string files;
    for (const fs::path& f : g.files) {
      if (!files.empty()) files += ' ';
      files += f.filename().string();
    }
    t.rows.push_back({g.name, g.level, std::to_string(g.files.size()), files});
  }
  s.tables.push_back(t);
  ReportTable mt{"Modes", {"mode", "band [Hz]", "reference channel"}, {}};
  if (has_model) mt.header.push_back("model mode");
  for (const CampaignMode& m : c.modes) {
    mt.rows.push_back({m.name, fmt::format("{:g} - {:g}", m.band.lo, m.band.hi), m.reference});
    if (has_model) mt.rows.back().push_back(m.model_mode ? std::to_string(m.model_mode) : "-");
  }
  s.tables.push_back(mt);
  if (!figures.spectrum.image.empty()) s.figures.push_back(figures.spectrum);
  return s;
}

ReportSection settings_section(const Campaign& c) {
  ReportSection s;
  s.heading = "Settings";
  const ScatterOptions& so = c.scatter;
  s.paragraphs.push_back(fmt::format(
      "Processing: jointlab process defaults (Hilbert envelope and phase, local fits, "
      "uncertainties at k = {:g}). Scatter: {} bins per decade of amplitude, {:g} % Student-t "
      "confidence intervals of the mean, bins need {} curves; a hit is flagged when a robust "
      "z-score (median/MAD of its mean relative deviation from the per-bin medians, and of its "
      "linear frequency and damping) exceeds {:g} (spread floors {:g} in frequency, {:g} in "
      "damping); flagged hits are {} the bins.{}",
      modal::RingdownOptions{}.coverage_factor, so.bins_per_decade, 100 * so.confidence,
      so.min_curves, so.outlier_threshold, so.frequency_floor, so.damping_floor,
      so.exclude_outliers ? "left out of" : "kept in",
      c.model.file.empty() && c.model.description.empty()
          ? ""
          : fmt::format(" QSMA: {} points per curve.", c.qsma_points)));
  return s;
}

// A hit's backbone value at one amplitude, interpolated linearly in log amplitude between its
// two nearest points that bracket it, with its own uncertainty interpolated alike.
struct HitValue {
  double frequency_hz = 0, frequency_std_hz = 0, damping = 0, damping_std = 0;
};

std::optional<HitValue> hit_value_at(const Curve& cv, const PointStd& u, double a) {
  if (!(a > 0)) return std::nullopt;
  std::vector<Eigen::Index> order;
  for (Eigen::Index j = 0; j < cv.amplitude.size(); ++j)
    if (cv.amplitude(j) > 0) order.push_back(j);
  std::sort(order.begin(), order.end(),
            [&](Eigen::Index x, Eigen::Index y) { return cv.amplitude(x) < cv.amplitude(y); });
  for (size_t i = 0; i + 1 < order.size(); ++i) {
    const Eigen::Index j0 = order[i], j1 = order[i + 1];
    const double a0 = cv.amplitude(j0), a1 = cv.amplitude(j1);
    if (!(a >= a0 && a <= a1)) continue;
    const double w = a1 > a0 ? std::log(a / a0) / std::log(a1 / a0) : 0.0;
    const auto at = [&](const Eigen::VectorXd& v) { return (1 - w) * v(j0) + w * v(j1); };
    return HitValue{at(cv.frequency_hz), at(u.frequency_hz), at(cv.damping), at(u.damping)};
  }
  return std::nullopt;
}

// One row of the stepped-sine comparison: point j of curve i against a hammer value (f_h,
// zeta_h) of uncertainty (uf_h, uz_h), combined with the point's own.
std::vector<std::string> sine_row(const ModeBackbones& sine, size_t i, Eigen::Index j,
                                  const std::string& against, double f_h, double uf_h, double z_h,
                                  double uz_h) {
  const Curve& cv = sine.curves[i];
  const double uf = std::hypot(sine.frequency_std_hz[i](j), uf_h);
  const double uz = std::hypot(sine.damping_std[i](j), uz_h);
  const double df = cv.frequency_hz(j) - f_h;
  const double dz = cv.damping(j) - z_h;
  return {cv.id,
          fmt::format("{:.3g}", cv.amplitude(j)),
          against,
          fmt::format("{:.4f}", cv.frequency_hz(j)),
          fmt::format("{:.4f}", f_h),
          fmt::format("{:+.4f}", df),
          uf > 0 ? fmt::format("{:.2g}", std::abs(df) / uf) : "-",
          zeta(cv.damping(j)),
          zeta(z_h),
          z_h > 0 ? fmt::format("{:+.1f} %", 100 * dz / z_h) : "-",
          uz > 0 ? fmt::format("{:.2g}", std::abs(dz) / uz) : "-"};
}

// Each stepped-sine point against the hammer hits at its amplitude: the hits' mean where a
// scatter bin covers the point, else (too few hits for a bin there, one hit alone for
// instance) each hit's own backbone interpolated at the point's amplitude. The difference and
// its ratio to the combined uncertainty u = sqrt(u_sine^2 + u_hits^2), u_sine the point's own
// (k sigma, as stepped-sine writes it), u_hits the half-width of the bin's interval or the
// hit's own interpolated uncertainty (k sigma, as process writes it).
ReportTable sine_against_hammer(const Campaign& c, const MeasuredSide& m, size_t k) {
  ReportTable t{fmt::format("Stepped sine against the hammer hits where their amplitudes overlap "
                            "(hits: the bin's mean and the half-width of its {:g} % interval "
                            "where a scatter bin covers the point, else each hit's own backbone "
                            "interpolated at the point's amplitude and its own uncertainty, as "
                            "the column 'against' says; stepped sine: its own uncertainty; a "
                            "difference between steady state and ring-down is a finding, not a "
                            "failure)",
                            100 * c.scatter.confidence),
                {"file", "amplitude", "against", "f sine [Hz]", "f hits [Hz]", "df [Hz]", "|df|/u",
                 "zeta sine", "zeta hits", "dzeta / zeta hits", "|dzeta|/u"},
                {}};
  const ModeBackbones sine = stepped_sine_backbones(c, k, m.reference[k]);
  for (size_t i = 0; i < sine.curves.size(); ++i) {
    const Curve& cv = sine.curves[i];
    for (Eigen::Index j = 0; j < cv.amplitude.size(); ++j) {
      const double a = cv.amplitude(j);
      bool binned = false;
      for (const ScatterBin& b : m.scatter[k].bins) {
        if (!(a >= b.amplitude_low && a < b.amplitude_high)) continue;
        if (b.curves < 1) continue;
        binned = true;
        t.rows.push_back(sine_row(sine, i, j, fmt::format("bin mean ({} hits)", b.curves),
                                  b.frequency_hz.mean,
                                  0.5 * (b.frequency_hz.ci_high - b.frequency_hz.ci_low),
                                  b.damping.mean, 0.5 * (b.damping.ci_high - b.damping.ci_low)));
      }
      if (binned) continue;
      for (size_t h = 0; h < m.curves[k].size(); ++h) {
        const Curve& hit = m.curves[k][h];
        const std::optional<HitValue> v = hit_value_at(hit, m.point_std[k][h], a);
        if (!v) continue;
        bool flagged = false;
        for (const HitDeviation& d : m.scatter[k].hits) flagged |= d.id == hit.id && d.outlier;
        t.rows.push_back(
            sine_row(sine, i, j, fmt::format("hit {}{}", hit.id, flagged ? " (flagged)" : ""),
                     v->frequency_hz, v->frequency_std_hz, v->damping, v->damping_std));
      }
    }
  }
  if (t.rows.empty()) t.caption += ": no stepped-sine point lies within the hits' amplitudes";
  return t;
}

ReportSection scatter_section(const Campaign& c, const MeasuredSide& m, size_t k,
                              const CampaignFigures& figures) {
  ReportSection s;
  s.heading = fmt::format("Scatter summary: {}", c.modes[k].name);
  const ScatterSummary& sc = m.scatter[k];
  ReportTable spans{"Kept span of each hit at the reference channel",
                    {"hit", "group", "from [s]", "to [s]", "decades"},
                    {}};
  for (const HitSpan& h : m.spans[k]) {
    if (h.ok)
      spans.rows.push_back({h.hit, h.group, fmt::format("{:.3f}", h.start_s),
                            fmt::format("{:.3f}", h.end_s), fmt::format("{:.2f}", h.decades)});
    else
      spans.rows.push_back({h.hit, h.group, "-", "-", "no backbone: " + h.reason});
  }
  if (m.curves[k].empty()) {
    s.paragraphs.push_back(
        fmt::format("No backbone at channel {} in any hit.", c.modes[k].reference));
    s.tables.push_back(spans);
    return s;
  }
  s.paragraphs.push_back(fmt::format("{} curve(s) at channel {}. {}", m.curves[k].size(),
                                     c.modes[k].reference, sc.report()));
  s.tables.push_back(spans);
  ReportTable bt{"Bins (frequency and damping: mean, standard deviation, confidence interval)",
                 {"amplitude", "curves", "f mean [Hz]", "f std [Hz]", "f interval [Hz]",
                  "zeta mean", "zeta std", "zeta interval"},
                 {}};
  for (const ScatterBin& b : sc.bins) {
    bt.rows.push_back(
        {fmt::format("{:.3g}", b.amplitude_center), std::to_string(b.curves),
         fmt::format("{:.4f}", b.frequency_hz.mean), spread(b.frequency_hz.std),
         fmt::format("{:.4f} - {:.4f}", b.frequency_hz.ci_low, b.frequency_hz.ci_high),
         zeta(b.damping.mean), zeta(b.damping.std),
         fmt::format("{} - {}", zeta(b.damping.ci_low), zeta(b.damping.ci_high))});
  }
  s.tables.push_back(bt);
  ReportTable ht{"Hits (robust z-scores; |z| > threshold is flagged)",
                 {"hit", "group", "f dev", "zeta dev", "z f", "z zeta", "linear f [Hz]",
                  "linear zeta", "flagged"},
                 {}};
  for (const HitDeviation& h : sc.hits) {
    ht.rows.push_back({h.id, h.group, fmt::format("{:+.2e}", h.frequency_deviation),
                       fmt::format("{:+.3f}", h.damping_deviation),
                       fmt::format("{:+.1f}", h.frequency_z), fmt::format("{:+.1f}", h.damping_z),
                       h.has_linear ? fmt::format("{:.4f}", h.linear_frequency_hz) : "-",
                       h.has_linear ? zeta(h.linear_damping) : "-",
                       h.outlier ? "yes: " + h.reason : "no"});
  }
  s.tables.push_back(ht);
  if (!c.modes[k].stepped_sine.empty()) s.tables.push_back(sine_against_hammer(c, m, k));
  if (sc.linear_frequency_hz.has_spread())
    s.paragraphs.push_back(fmt::format(
        "Linear (low-amplitude) values over {} hit(s): frequency {:.4f} Hz, standard deviation "
        "{} Hz, interval {:.4f} - {:.4f} Hz; damping ratio {}, standard deviation {}.",
        sc.linear_count, sc.linear_frequency_hz.mean, spread(sc.linear_frequency_hz.std),
        sc.linear_frequency_hz.ci_low, sc.linear_frequency_hz.ci_high, zeta(sc.linear_damping.mean),
        zeta(sc.linear_damping.std)));
  else if (sc.linear_count == 1)
    s.paragraphs.push_back(fmt::format(
        "Linear (low-amplitude) values of one hit: frequency {:.4f} Hz, damping ratio {} (one "
        "hit has no spread between tests).",
        sc.linear_frequency_hz.mean, zeta(sc.linear_damping.mean)));
  // Only a figure that was drawn: draw_figures gives one per mode, but a report whose figures
  // were not drawn (CampaignFigures{}) is still written, without them (indexing the empty
  // vector here was a segfault).
  if (k < figures.backbone.size() && !figures.backbone[k].image.empty())
    s.figures.push_back(figures.backbone[k]);
  return s;
}

ReportTable frequency_table(const Campaign& c, const MeasuredSide& m, const ModelResults& r) {
  ReportTable ft{"Linear frequencies, test versus model",
                 {"mode", "test [Hz]", "test std [Hz]", "model start [Hz]", "error start",
                  "model updated [Hz]", "error updated"},
                 {}};
  if (r.linear.ran && r.linear.summary.status == correlate::LinearUpdateStatus::kPairsUnconfirmed)
    ft.caption += " (updated: the linear update's pairs are not confirmed by the shapes, below)";
  std::vector<std::string> lowest;  // modes whose update fitted the lowest-level hits' value
  for (size_t k = 0; k < c.modes.size(); ++k) {
    if (r.start.frequency_hz[k] <= 0 || m.scatter[k].linear_count == 0) continue;
    // The value the linear update fitted, where it ran: the hits' mean, or, where their linear
    // frequencies fall with the level, the lowest-level hits' (its warning says so). The table
    // showed the mean there, beside a model updated to another value.
    double fe = m.scatter[k].linear_frequency_hz.mean;
    if (r.linear.ran && k < r.linear.lowest_level_hz.size() && r.linear.lowest_level_hz[k] > 0) {
      fe = r.linear.lowest_level_hz[k];
      lowest.push_back(c.modes[k].name);
    }
    ft.rows.push_back({c.modes[k].name, fmt::format("{:.4f}", fe),
                       m.scatter[k].linear_frequency_hz.has_spread()
                           ? spread(m.scatter[k].linear_frequency_hz.std)
                           : "-",
                       fmt::format("{:.4f}", r.start.frequency_hz[k]),
                       pct(100 * (r.start.frequency_hz[k] - fe) / fe),
                       r.have_updated ? fmt::format("{:.4f}", r.after.frequency_hz[k]) : "-",
                       r.have_updated ? pct(100 * (r.after.frequency_hz[k] - fe) / fe) : "-"});
  }
  if (!lowest.empty())
    ft.caption += fmt::format(
        " (test, {}: the lowest-level hits' linear frequency, which the linear update fitted, not "
        "the mean of every hit's: they fall with the level, see its warning)",
        fmt::join(lowest, ", "));
  return ft;
}

double spring_value(const model::Model& m, const std::string& element) {
  for (const model::Joint& j : m.joints)
    if (j.element == element) return j.stiffness;
  return 0;
}

// True when the linear update changed `element`.
bool linearly_updated(const Campaign& c, const ModelResults& r, const std::string& element) {
  return r.have_updated && std::find(c.linear_update.sets.begin(), c.linear_update.sets.end(),
                                     element) != c.linear_update.sets.end();
}

// What the linear update's result leaves in doubt about `element`'s updated value: " (...)" or
// "" (identified, or not a set of the linear update).
std::string linear_doubt(const Campaign& c, const ModelResults& r, const std::string& element) {
  if (!r.linear.ran || !linearly_updated(c, r, element)) return "";
  const correlate::LinearUpdateSummary& s = r.linear.summary;
  std::string doubt;
  for (const correlate::ParameterReport& p : s.parameters) {
    if (p.name != element) continue;
    if (p.flat) doubt = "flat: not identified by the frequencies";
    if (!p.acts_with.empty())
      doubt = fmt::format("not identifiable alone: acts together with {}",
                          fmt::join(p.acts_with, ", "));
  }
  if (s.status == correlate::LinearUpdateStatus::kPairsUnconfirmed)
    doubt += std::string(doubt.empty() ? "" : "; ") + "pairs unconfirmed by the shapes";
  return doubt.empty() ? "" : " (" + doubt + ")";
}

// The joint parameters before and after, with the known values of a simulated campaign.
ReportTable parameter_table(const Campaign& c, const ModelResults& r, const Truth& truth) {
  model::IwanParameters p0, p1;
  std::string set;
  // The fitted set's (the truth file gives its table), not the first Iwan joint's: with two
  // sets the first may be another's (a [[joint_set]] bolt before the rivets).
  const bool has_iwan = first_iwan(r.data.model, p0, set, truth_set(c));
  p1 = p0;
  if (r.have_updated) first_iwan(r.updated, p1, set, truth_set(c));
  ReportTable pt{
      "Joint parameters", {"parameter", "start", "updated", "known", "updated / known"}, {}};
  const auto row = [&](const std::string& name, double a, double b, double known,
                       bool updated_here) {
    pt.rows.push_back(
        {name, g6(a), updated_here ? g6(b) : "(not updated)",
         truth.present && known != 0 ? g6(known) : "-",
         truth.present && known != 0 && updated_here ? fmt::format("{:.4f}", b / known) : "-"});
  };
  const bool iwan_ran = r.iwan.ran;
  if (has_iwan) {
    row(set + " Kt [N/m]", p0.Kt, p1.Kt, truth.iwan.Kt, linearly_updated(c, r, set) || iwan_ran);
    if (!iwan_ran) pt.rows.back()[2] += linear_doubt(c, r, set);
    // Each Iwan parameter's note, as parameters.csv and update-iwan's report word it
    // (IwanUpdateSummary::sigma_reason(): one decision). Before, this table decided apart: beta
    // held at its start by the fit read "(held)", as if asked, and data without slip said nothing.
    const auto note = [&](int k) {
      const std::string n = iwan_ran ? r.iwan.summary.parameter_note(k) : std::string();
      if (!n.empty()) pt.rows.back()[2] += " (" + n + ")";
    };
    note(1);
    row(set + " Fs [N]", p0.Fs, p1.Fs, truth.iwan.Fs, iwan_ran);
    note(0);
    row(set + " chi", p0.chi, p1.chi, truth.iwan.chi, iwan_ran);
    note(2);
    row(set + " beta", p0.beta, p1.beta, truth.iwan.beta, iwan_ran);
    note(3);
    if (iwan_ran && r.iwan.summary.modal_ratio_fitted) {
      row("modal_ratio (own damping)", r.iwan.summary.modal_ratio_start, r.iwan.summary.modal_ratio,
          0, true);
      note(4);
    }
  }
  for (const std::string& name : c.linear_update.sets) {
    if (name.rfind("spring.", 0) != 0) continue;
    const double a = spring_value(r.data.model, name);
    const double b = r.have_updated ? spring_value(r.updated, name) : a;
    row(name, a, b, 0, linearly_updated(c, r, name));
    pt.rows.back()[2] += linear_doubt(c, r, name);
  }
  return pt;
}

ReportSection model_section(const Campaign& c, const MeasuredSide& m, const ModelResults& r,
                            const CampaignFigures& figures) {
  ReportSection s;
  s.heading = "Model";
  const model::Model& model = r.data.model;
  s.paragraphs.push_back(fmt::format("Model file {} ({} DOFs, {} joint elements, {} Iwan).",
                                     r.data.file.string(), model.size(), model.joints.size(),
                                     model.iwan_count()));
  for (const std::string& n : r.start.qsma_notes) s.paragraphs.push_back("QSMA " + n);
  s.tables.push_back(frequency_table(c, m, r));
  const Truth truth = read_truth(c.truth, truth_set(c));
  s.tables.push_back(parameter_table(c, r, truth));
  if (r.linear.ran) s.paragraphs.push_back("Linear updating: " + r.linear.summary.report());
  if (r.iwan.stopped) {
    const std::string prefix = "update.iwan: not run: ";
    s.paragraphs.push_back(
        "Iwan identification: not run: " +
        (r.iwan.note.starts_with(prefix) ? r.iwan.note.substr(prefix.size()) : r.iwan.note) + ".");
  }
  if (r.iwan.ran) {
    s.paragraphs.push_back("Iwan identification: " + r.iwan.summary.report());
    for (const std::string& w : r.iwan.warnings) s.paragraphs.push_back(w);
    ReportTable mc{
        "Backbone cost per mode (mean squared error in units of the scatter between "
        "hits: about 2 when the model lies within it)",
        {"mode", "fitted", "cost, start", "cost, updated"},
        {}};
    for (const ModeCost& mcost : r.iwan.mode_costs)
      mc.rows.push_back({mcost.mode, mcost.fitted ? "yes" : "no",
                         fmt::format("{:.3g}", mcost.start), fmt::format("{:.3g}", mcost.updated)});
    s.tables.push_back(mc);
  }
  model::IwanParameters p0, p1;
  std::string set;
  if (truth.present && first_iwan(model, p0, set, truth_set(c))) {
    p1 = p0;
    if (r.have_updated) first_iwan(r.updated, p1, set, truth_set(c));
    KnownComparison kc;
    kc.truth = truth;
    kc.updated = p1;
    kc.kt_updated = linearly_updated(c, r, set) || r.iwan.ran;
    kc.iwan_ran = r.iwan.ran;
    kc.beta_held = r.iwan.beta_held;
    kc.curves = r.iwan.curves;
    kc.iwan = r.iwan.summary;
    kc.cost_known = r.iwan.cost_known;
    if (r.iwan.ran && !r.iwan.summary.held[1]) {
      kc.kt_std = r.iwan.summary.relative_std(1);
    } else if (r.linear.ran && linearly_updated(c, r, set)) {
      for (const correlate::ParameterReport& p : r.linear.summary.parameters)
        if (p.name == set && p.relative_std) kc.kt_std = *p.relative_std;
    }
    compare_with_known(kc, c.truth.filename().string(), s);
  }
  for (const ReportFigure& f : figures.model)
    if (!f.image.empty()) s.figures.push_back(f);
  return s;
}

ReportSection notes_section(const Campaign& c, const RunSummary& summary) {
  ReportSection s;
  s.heading = "Notes and errors";
  if (summary.notes.empty()) s.paragraphs.push_back("No step was skipped.");
  for (const std::string& n : summary.notes) s.paragraphs.push_back(n);
  const bool has_model = !c.model.file.empty() || !c.model.description.empty();
  s.paragraphs.push_back(
      fmt::format("This run: {} hit(s) processed, {} reused from earlier runs{}{}.",
                  summary.hits_processed, summary.hits_reused,
                  summary.failed_hits.empty()
                      ? ""
                      : fmt::format(", {} left out (see the top)", summary.failed_hits.size()),
                  !has_model             ? ""
                  : summary.model_built  ? "; model built"
                  : summary.model_reused ? "; model reused"
                                         : "; model given as a file"));
  return s;
}

}  // namespace

Report campaign_report(const Campaign& c, const RunSummary& summary, const MeasuredSide& measured,
                       const ModelResults* model, const CampaignFigures& figures) {
  Report report;
  report.title = fmt::format("Test campaign: {}", c.name);
  if (!summary.failed_hits.empty()) report.sections.push_back(left_out_section(summary));
  if (!summary.stopped.empty()) report.sections.push_back(stopped_section(summary));
  if (!summary.no_backbone.empty()) report.sections.push_back(no_backbone_section(c, measured));
  report.sections.push_back(data_section(c, summary, figures));
  report.sections.push_back(settings_section(c));
  for (size_t k = 0; k < c.modes.size(); ++k)
    report.sections.push_back(scatter_section(c, measured, k, figures));
  if (model) report.sections.push_back(model_section(c, measured, *model, figures));
  report.sections.push_back(notes_section(c, summary));
  // The libraries' advice names command-line options; a campaign sets them with its keys.
  for (ReportSection& section : report.sections) {
    for (std::string& p : section.paragraphs) p = with_campaign_keys(p);
    for (ReportTable& t : section.tables) {
      t.caption = with_campaign_keys(t.caption);
      for (std::vector<std::string>& row : t.rows)
        for (std::string& cell : row) cell = with_campaign_keys(cell);
    }
  }
  return report;
}

}  // namespace jointlab::campaign
