#include "jointlab/campaign/campaign_run.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <exception>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "jointlab/campaign/figures.h"
#include "jointlab/campaign/report.h"
#include "jointlab/campaign/scatter.h"
#include "jointlab/core/error.h"
#include "jointlab/core/parallel.h"
#include "jointlab/correlate/iwan_update.h"
#include "jointlab/correlate/linear_update.h"
#include "jointlab/correlate/mac.h"
#include "jointlab/correlate/mode_interference.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/data/read_record.h"
#include "jointlab/data/table_writer.h"
#include "jointlab/modal/process.h"
#include "jointlab/modal/process_output.h"
#include "jointlab/model/fe/model_builder.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/qsma.h"
#include "jointlab/model/sim/simulated_record.h"
#include "jointlab/signal/spectrum.h"

namespace jointlab::campaign {

using correlate::amplitude_power;
using correlate::AmplitudeQuantity;
using correlate::IwanObjective;
using correlate::IwanTarget;
using correlate::IwanUpdateOptions;
using correlate::IwanUpdateSummary;
using correlate::LinearUpdateOptions;
using correlate::LinearUpdateSummary;
using correlate::mac_matrix;
using correlate::MeasuredBackbone;
using correlate::MeasuredModes;
using correlate::mode_slip;
using correlate::ModeSlip;
using correlate::Sensor;
using correlate::slip_share;
using correlate::StiffnessSets;
using correlate::update_iwan;
using correlate::update_linear;

namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

void say(const RunOptions& o, const std::string& s) {
  if (o.progress) o.progress(s);
}

// A numeric CSV as written by data::write_table: header, then rows of numbers.
struct NumericTable {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
  const std::vector<double>& column(const std::string& name, const fs::path& file) const {
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return columns[i];
    throw InputError(
        fmt::format("{}: no column '{}' (delete the file to recompute it)", file.string(), name));
  }
};

NumericTable read_numeric_table(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(fmt::format("{}: cannot read", path.string()));
  NumericTable t;
  std::string line;
  if (!std::getline(in, line)) throw InputError(fmt::format("{}: empty", path.string()));
  std::stringstream hs(line);
  for (std::string name; std::getline(hs, name, ',');) t.names.push_back(name);
  t.columns.resize(t.names.size());
  long row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (line.empty()) continue;
    std::stringstream rs(line);
    size_t c = 0;
    for (std::string cell; std::getline(rs, cell, ','); ++c) {
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      if (c >= t.columns.size() || end == cell.c_str() || !std::isfinite(v))
        throw InputError(where(path.string(), row,
                               "not a row of numbers (delete the file to "
                               "recompute it)"));
      t.columns[c].push_back(v);
    }
    if (c != t.columns.size()) throw InputError(where(path.string(), row, "wrong number of cells"));
  }
  return t;
}

Eigen::VectorXd vec(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

std::string slug(int k) { return fmt::format("mode{}", k + 1); }

// One hit's linear data per band and channel.
struct LinearEntry {
  bool ok = false;
  double frequency_hz = 0, damping = 0;
  std::complex<double> amplitude;
};

// Everything the run knows about one hit.
struct Hit {
  std::string group, stem;
  fs::path file;
  std::vector<std::vector<LinearEntry>> linear;  // [band][channel]
  std::vector<std::vector<Curve>> curves;        // [band][channel]; empty amplitude: none
};

fs::path hit_dir(const fs::path& out, const std::string& group) { return out / "hits" / group; }

// Processes one hit and writes its cache.
void process_hit(const Campaign& c, const fs::path& file, const fs::path& dir,
                 signal::FftCache& cache) {
  const data::Record rec = data::read_record(file);
  modal::ProcessOptions opt;
  for (const CampaignMode& m : c.modes) opt.bands.push_back(m.band);
  for (const CampaignChannel& ch : c.channels) opt.channels.push_back(ch.name);
  opt.quantity = c.quantity;
  opt.ringdown.amplitude = c.amplitude;
  if (const std::string why = opt.check(); !why.empty())
    throw InputError(fmt::format("{}: {}", c.file.string(), why));
  const modal::RecordResult r = modal::process_record(rec, opt, cache);
  fs::create_directories(dir);
  modal::write_backbones(dir, r, opt.ringdown);
  data::Table t;
  const Eigen::Index n = static_cast<Eigen::Index>(r.results.size());
  Eigen::VectorXd band(n), chan(n), ok(n), f(n), z(n), re(n), im(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const modal::ChannelBand& cb = r.results[i];
    band(i) = cb.band_index;
    chan(i) = 0;
    for (size_t k = 0; k < c.channels.size(); ++k)
      if (c.channels[k].name == cb.channel) chan(i) = static_cast<double>(k);
    const bool good = cb.ringdown.summary.status == modal::RingdownStatus::kOk;
    ok(i) = good;
    f(i) = good ? cb.ringdown.summary.linear_frequency_hz : 0.0;
    z(i) = good ? cb.ringdown.summary.linear_damping : 0.0;
    re(i) = std::isfinite(cb.complex_amplitude.real()) ? cb.complex_amplitude.real() : 0.0;
    im(i) = std::isfinite(cb.complex_amplitude.imag()) ? cb.complex_amplitude.imag() : 0.0;
  }
  t.add("band", band);
  t.add("channel", chan);
  t.add("ok", ok);
  t.add("linear_frequency_hz", f);
  t.add("linear_damping", z);
  t.add("amplitude_re_m", re);
  t.add("amplitude_im_m", im);
  // Written last: its presence marks the hit as complete.
  data::write_table(dir / (file.stem().string() + ".linear.csv"), t);
}

// Reads one hit's cache.
Hit load_hit(const Campaign& c, const CampaignGroup& g, const fs::path& file, const fs::path& dir) {
  Hit h;
  h.group = g.name;
  h.stem = file.stem().string();
  h.file = file;
  const size_t nb = c.modes.size(), nc = c.channels.size();
  h.linear.assign(nb, std::vector<LinearEntry>(nc));
  h.curves.assign(nb, std::vector<Curve>(nc));
  const fs::path lin = dir / (h.stem + ".linear.csv");
  const NumericTable t = read_numeric_table(lin);
  const auto& band = t.column("band", lin);
  const auto& chan = t.column("channel", lin);
  const auto& ok = t.column("ok", lin);
  const auto& f = t.column("linear_frequency_hz", lin);
  const auto& z = t.column("linear_damping", lin);
  const auto& re = t.column("amplitude_re_m", lin);
  const auto& im = t.column("amplitude_im_m", lin);
  for (size_t i = 0; i < band.size(); ++i) {
    const int b = static_cast<int>(band[i]) - 1, ch = static_cast<int>(chan[i]);
    if (b < 0 || b >= static_cast<int>(nb) || ch < 0 || ch >= static_cast<int>(nc)) continue;
    h.linear[b][ch] = {ok[i] > 0.5, f[i], z[i], {re[i], im[i]}};
  }
  for (size_t b = 0; b < nb; ++b) {
    for (size_t ch = 0; ch < nc; ++ch) {
      Curve& cv = h.curves[b][ch];
      cv.id = h.stem;
      cv.group = g.name;
      const LinearEntry& le = h.linear[b][ch];
      cv.has_linear = le.ok;
      cv.linear_frequency_hz = le.frequency_hz;
      cv.linear_damping = le.damping;
      const fs::path p = dir / modal::backbone_file_name(file.string(), c.channels[ch].name,
                                                         static_cast<int>(b) + 1);
      if (!le.ok || !fs::exists(p)) continue;
      const NumericTable bt = read_numeric_table(p);
      cv.time_s = vec(bt.column("time_s", p));
      cv.amplitude = vec(bt.column("amplitude", p));
      cv.frequency_hz = vec(bt.column("frequency_hz", p));
      cv.damping = vec(bt.column("damping_ratio", p));
    }
  }
  return h;
}

// Known parameters of a simulated campaign ([iwan] Kt Fs chi beta, [scatter] Kt Fs).
struct Truth {
  bool present = false;
  model::IwanParameters iwan;
  double scatter_kt = 0, scatter_fs = 0;
};

Truth read_truth(const fs::path& path) {
  Truth t;
  if (path.empty()) return t;
  toml::table doc;
  try {
    doc = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    throw InputError(where(path.string(), static_cast<long>(e.source().begin.line),
                           std::string(e.description())));
  }
  const auto get = [&](const char* table, const char* key, bool required) {
    const auto v = doc[table][key].value<double>();
    if (!v && required)
      throw InputError(where(path.string(), 0, fmt::format("missing {}.{}", table, key)));
    return v.value_or(0.0);
  };
  t.present = true;
  t.iwan = {get("iwan", "Fs", true), get("iwan", "Kt", true), get("iwan", "chi", true),
            get("iwan", "beta", true)};
  t.scatter_kt = get("scatter", "Kt", false);
  t.scatter_fs = get("scatter", "Fs", false);
  return t;
}

// The Iwan parameters of the model's first Iwan joint (the campaign's models share one set).
bool first_iwan(const model::Model& m, model::IwanParameters& p, std::string& set) {
  for (const model::Joint& j : m.joints) {
    if (!j.iwan) continue;
    p = {j.iwan->slip_force(), j.iwan->stiffness(), j.iwan->chi(), j.iwan->beta()};
    set = j.element;
    return true;
  }
  return false;
}

double spring_value(const model::Model& m, const std::string& element, bool& found) {
  for (const model::Joint& j : m.joints) {
    if (j.element == element) {
      found = true;
      return j.stiffness;
    }
  }
  found = false;
  return 0;
}

// A model's side of the comparison: linear frequencies, shapes at the sensors, QSMA curves.
struct ModelSide {
  std::vector<double> frequency_hz;  // per campaign mode (0: no model mode)
  Eigen::MatrixXd sensor_shapes;     // sensors x first elastic modes
  std::vector<double> shape_hz;      // frequency of each column
  std::vector<ModelCurve> curves;    // per campaign mode (may be empty)
  std::vector<std::string> qsma_notes;
};

ModelSide evaluate_model(const Campaign& c, const model::Model& m,
                         const std::vector<Eigen::Index>& dofs, const std::string& label,
                         const fs::path& qsma_dir, const std::string& tag) {
  ModelSide s;
  const model::JointCondensation jc(m);
  const model::LinearModes& lm = jc.modes();
  const int rigid = lm.rigid_count, elastic = jc.elastic_count();
  int needed = 0;
  for (const CampaignMode& cm : c.modes) needed = std::max(needed, cm.model_mode);
  const int ncols = std::min(elastic, std::max(needed + 2, static_cast<int>(c.modes.size()) + 2));
  s.sensor_shapes.resize(static_cast<Eigen::Index>(dofs.size()), ncols);
  for (int j = 0; j < ncols; ++j) {
    s.shape_hz.push_back(lm.frequency_hz(rigid + j));
    for (size_t i = 0; i < dofs.size(); ++i)
      s.sensor_shapes(static_cast<Eigen::Index>(i), j) =
          c.channels[i].sign * lm.shapes(dofs[i], rigid + j);
  }
  for (size_t k = 0; k < c.modes.size(); ++k) {
    const CampaignMode& cm = c.modes[k];
    ModelCurve curve;
    curve.label = label;
    if (cm.model_mode < 1 || cm.model_mode > elastic) {
      s.frequency_hz.push_back(0);
      s.curves.push_back(curve);
      continue;
    }
    const int col = rigid + cm.model_mode - 1;
    s.frequency_hz.push_back(lm.frequency_hz(col));
    int ref = 0;
    for (size_t i = 0; i < c.channels.size(); ++i)
      if (c.channels[i].name == cm.reference) ref = static_cast<int>(i);
    const double phi = std::abs(lm.shapes(dofs[ref], col));
    model::QsmaOptions qo;
    qo.points = c.qsma_points;
    model::QsmaSummary qs;
    const std::vector<model::QsmaPoint> pts = qsma(jc, cm.model_mode, qo, &qs);
    s.qsma_notes.push_back(fmt::format("{} ({}): {}", cm.name, label, qs.message));
    const Eigen::Index n = static_cast<Eigen::Index>(pts.size());
    curve.amplitude.resize(n);
    curve.frequency_hz.resize(n);
    curve.damping.resize(n);
    const int power = c.amplitude == Quantity::kDisplacement ? 0
                      : c.amplitude == Quantity::kVelocity   ? 1
                                                             : 2;
    Eigen::VectorXd q(n), alpha(n), slip(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const double w = 2 * kPi * pts[i].frequency_hz;
      curve.amplitude(i) = phi * pts[i].modal_amplitude * std::pow(w, power);
      curve.frequency_hz(i) = pts[i].frequency_hz;
      curve.damping(i) = pts[i].damping_ratio;
      q(i) = pts[i].modal_amplitude;
      alpha(i) = pts[i].force_amplitude;
      slip(i) = pts[i].max_slip;
    }
    data::Table t;
    t.add("amplitude", curve.amplitude);
    t.add("frequency_hz", curve.frequency_hz);
    t.add("damping_ratio", curve.damping);
    t.add("modal_amplitude", q);
    t.add("force_amplitude", alpha);
    t.add("max_slip", slip);
    fs::create_directories(qsma_dir);
    data::write_table(qsma_dir / fmt::format("{}.{}.csv", slug(static_cast<int>(k)), tag), t);
    s.curves.push_back(curve);
  }
  return s;
}

// What the report compares with the known parameters of a simulated campaign.
struct KnownComparison {
  Truth truth;
  model::IwanParameters updated;  // the updated model's Iwan set
  bool kt_updated = false;        // K_T changed by the linear or the Iwan update
  bool iwan_ran = false;
  bool beta_held = false;  // beta held in the Iwan update (microslip data, or by the campaign)
  int curves = 0;          // backbones the Iwan update fitted
  IwanUpdateSummary iwan;
  double cost_known = 0;  // the Iwan update's cost at the known parameters
};

// The slip force that, with beta, keeps p's Kt, chi and R (the microslip response):
// from R = Fs (chi+1) / (phi_max^(chi+2) (beta+c)), phi_max = Fs (1+beta) / (Kt (beta+c)),
// c = (chi+1)/(chi+2):  Fs^(chi+1) = (chi+1) (Kt (beta+c))^(chi+2) / (R (1+beta)^(chi+2) (beta+c)).
double slip_force_for(const model::IwanParameters& p, double beta) {
  const double e = p.chi + 1, c = e / (p.chi + 2);
  const double phi = p.Fs * (1 + p.beta) / (p.Kt * (p.beta + c));
  const double r = p.Fs * e / (std::pow(phi, p.chi + 2) * (p.beta + c));
  return std::pow(
      e * std::pow(p.Kt * (beta + c), p.chi + 2) / (r * std::pow(1 + beta, p.chi + 2) * (beta + c)),
      1 / e);
}

// ln D(u) of an Iwan element at slip amplitude u, and its gradient with respect to
// x = (ln F_S, ln K_T, chi, ln beta) by central differences.
double log_dissipation(const model::IwanParameters& p, double u) {
  return std::log(model::Iwan(p).dissipation(u));
}
Eigen::Vector4d log_dissipation_gradient(const model::IwanParameters& p, double u) {
  Eigen::Vector4d g;
  for (int k = 0; k < 4; ++k) {
    const double h = 1e-5;
    model::IwanParameters a = p, b = p;
    if (k == 0) a.Fs *= std::exp(h), b.Fs *= std::exp(-h);
    if (k == 1) a.Kt *= std::exp(h), b.Kt *= std::exp(-h);
    if (k == 2) a.chi += h, b.chi -= h;
    if (k == 3) a.beta *= std::exp(h), b.beta *= std::exp(-h);
    g(k) = (log_dissipation(a, u) - log_dissipation(b, u)) / (2 * h);
  }
  return g;
}

// The "Known parameters" table and paragraph: per quantity the updated and the known value,
// the difference, the tolerance (twice the planted one-sigma scatter where scatter was planted,
// else twice the update's own one-sigma uncertainty from the scatter between hits) and whether
// the update recovers it. Parameters the data cannot identify are said to be so.
void compare_with_known(const KnownComparison& k, const std::string& truth_name, ReportSection& s) {
  const model::IwanParameters& t = k.truth.iwan;
  const model::IwanParameters& u = k.updated;
  ReportTable tb{"Updated versus known (" + truth_name + ")",
                 {"quantity", "updated", "known", "difference", "tolerance", "recovered"},
                 {}};
  int recovered = 0, judged = 0;
  std::vector<std::string> missed, unidentified;
  const auto judge = [&](const std::string& name, double got, double known, double tol,
                         const std::string& why) {
    const double r = got / known - 1;
    const bool ok = tol > 0 && std::abs(r) <= tol;
    ++judged;
    if (ok)
      ++recovered;
    else
      missed.push_back(name);
    tb.rows.push_back({name, fmt::format("{:.4g}", got), fmt::format("{:.4g}", known),
                       fmt::format("{:+.2f} %", 100 * r),
                       tol > 0 ? fmt::format("{:.1f} % ({})", 100 * tol, why) : "none known",
                       ok ? "yes" : "NO"});
  };
  const auto own = [&] {
    return fmt::format("2 x its uncertainty from the scatter between the {} hits", k.curves);
  };
  if (k.kt_updated) {
    judge("Kt [N/m]", u.Kt, t.Kt, 2 * k.truth.scatter_kt,
          fmt::format("2 x planted {:.1f} %", 100 * k.truth.scatter_kt));
  }
  std::string micro;
  if (k.iwan_ran) {
    judge("chi", u.chi, t.chi, 2 * k.iwan.relative_std(2), own());
    if (k.iwan.microslip_only()) {
      // The identified combination: the dissipation per cycle of one element at the geometric
      // middle of the measured slip range (D = 4 R u^(chi+3)/((chi+2)(chi+3)) below phi_max).
      const double uref = std::sqrt(k.iwan.bottom_slip * k.iwan.top_slip);
      const Eigen::Vector4d gt = log_dissipation_gradient(t, uref);
      const double planted = std::hypot(gt(0) * k.truth.scatter_fs, gt(1) * k.truth.scatter_kt);
      const Eigen::Vector4d gu = log_dissipation_gradient(u, uref);
      const double own_sd = std::sqrt(std::max(0.0, gu.dot(k.iwan.covariance * gu)));
      const double tol = 2 * std::max(planted, own_sd);
      judge(fmt::format("D({:.3g} m) [J]", uref), std::exp(log_dissipation(u, uref)),
            std::exp(log_dissipation(t, uref)), tol,
            planted >= own_sd ? fmt::format("2 x planted {:.1f} % via Kt and Fs", 100 * planted)
                              : fmt::format("2 x its uncertainty {:.1f} %", 100 * own_sd));
      unidentified = {"Fs", "beta"};
      tb.rows.push_back({"Fs [N]", fmt::format("{:.4g}", u.Fs), fmt::format("{:.4g}", t.Fs),
                         fmt::format("{:+.2f} %", 100 * (u.Fs / t.Fs - 1)), "-",
                         "not identifiable (microslip)"});
      tb.rows.push_back({"beta", fmt::format("{:.4g}", u.beta), fmt::format("{:.4g}", t.beta),
                         fmt::format("{:+.2f} %", 100 * (u.beta / t.beta - 1)), "-",
                         "not identifiable (held)"});
      // The family of (Fs, beta) pairs that share the identified Kt, chi and R.
      const double fs_known_beta = slip_force_for(u, t.beta);
      tb.rows.push_back({fmt::format("Fs at the known beta {:.4g} [N]", t.beta),
                         fmt::format("{:.4g}", fs_known_beta), fmt::format("{:.4g}", t.Fs),
                         fmt::format("{:+.2f} %", 100 * (fs_known_beta / t.Fs - 1)), "-",
                         "not judged (the identified family Fs(beta))"});
      std::vector<std::string> family;
      for (const double b : {0.25, 0.5, 1.0, 2.0, 4.0})
        family.push_back(fmt::format("{:.3g} N at beta {:g}", slip_force_for(u, b), b));
      const std::string family_text = fmt::format(
          " Every (Fs, beta) pair with the identified Kt, chi and R fits these backbones alike: "
          "{}; at the known beta {:.4g} it gives Fs = {:.4g} N (known {:.4g} N).",
          fmt::join(family, ", "), t.beta, fs_known_beta, t.Fs);
      micro = fmt::format(
          " The backbones stay in microslip: over the measured amplitudes the most loaded joint "
          "slips {:.3g} to {:.3g} m, at most {:.0f} % of phi_max ({:.3g} m in the updated model). "
          "Below phi_max an Iwan element's response depends on Kt, chi and R alone, so these data "
          "fix Kt, chi and R but not Fs and beta separately: beta is held at its starting value "
          "{:.4g} and Fs is the slip force that gives the identified R with it. The table "
          "compares the identified combination instead: D(u), the energy one joint element "
          "dissipates per cycle at the middle slip u = {:.3g} m (D = 4 R u^(chi+3) / ((chi+2) "
          "(chi+3))), whose planted scatter follows from that of Kt and Fs. Fs and beta need "
          "backbones that reach past phi_max.",
          k.iwan.bottom_slip, k.iwan.top_slip, 100 * k.iwan.top_slip / k.iwan.phi_max,
          k.iwan.phi_max, u.beta, uref);
      micro += family_text;
    } else {
      judge("Fs [N]", u.Fs, t.Fs, 2 * k.truth.scatter_fs,
            fmt::format("2 x planted {:.1f} %", 100 * k.truth.scatter_fs));
      if (k.beta_held) {
        unidentified.push_back("beta");
        tb.rows.push_back({"beta", fmt::format("{:.4g}", u.beta), fmt::format("{:.4g}", t.beta),
                           fmt::format("{:+.2f} %", 100 * (u.beta / t.beta - 1)), "-",
                           "held by the campaign"});
      } else {
        judge("beta", u.beta, t.beta, 2 * k.iwan.relative_std(3), own());
      }
    }
  } else {
    unidentified = {"Fs", "chi", "beta"};
    micro =
        " Fs, chi and beta are not identified (update.iwan is off): their starting values stand.";
  }
  s.tables.push_back(tb);
  std::string verdict =
      missed.empty()
          ? fmt::format("the update recovers all {} identified quantities within the tolerance",
                        judged)
          : fmt::format("the update recovers {} of {} identified quantities; NOT recovered: {}",
                        recovered, judged, fmt::join(missed, ", "));
  if (!unidentified.empty())
    verdict += fmt::format("; not identifiable from these data: {}", fmt::join(unidentified, ", "));
  if (k.iwan_ran && k.cost_known > 0)
    micro += fmt::format(
        " The backbone cost is {:.4g} at the known parameters and {:.4g} at the updated ones{}.",
        k.cost_known, k.iwan.final_cost,
        k.iwan.final_cost <= k.cost_known ? " (the optimiser reaches at least the known fit)"
                                          : " (the optimiser stopped short of the known fit)");
  s.paragraphs.push_back(fmt::format(
      "Known parameters ({}): {}. Tolerance: twice the planted one-sigma hit-to-hit scatter "
      "(Kt {:.1f} %, Fs {:.1f} %); where none was planted (chi, beta), twice the update's own "
      "one-sigma uncertainty, which the planted scatter causes (cluster-robust: the {} hits' "
      "backbones are the independent samples, not their points).{}",
      truth_name, verdict, 100 * k.truth.scatter_kt, 100 * k.truth.scatter_fs, k.curves, micro));
}

std::string g6(double v) { return fmt::format("{:.6g}", v); }
std::string pct(double v) { return fmt::format("{:+.3f} %", v); }

}  // namespace

bool up_to_date(const fs::path& output, const std::vector<fs::path>& inputs) {
  std::error_code ec;
  const auto t = fs::last_write_time(output, ec);
  if (ec) return false;
  for (const fs::path& in : inputs) {
    std::error_code e2;
    const auto ti = fs::last_write_time(in, e2);
    if (!e2 && ti > t) return false;
  }
  return true;
}

std::string RunSummary::report() const {
  std::string s = fmt::format("{} hit(s): {} processed, {} up to date; {} flagged", hits,
                              hits_processed, hits_reused, flagged_hits);
  if (model_built) s += "; model built";
  if (model_reused) s += "; model up to date";
  for (const std::string& n : notes) s += "\n  note: " + n;
  s +=
      fmt::format("\n  report: {}\n  markdown: {}", report_html.string(), report_markdown.string());
  return s;
}

RunSummary run_campaign(const Campaign& c, const RunOptions& o) {
  RunSummary summary;
  summary.hits = c.hit_count();
  const fs::path out = fs::absolute(o.out);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (!fs::is_directory(out))
    throw InputError(fmt::format("{}: cannot create the output directory", out.string()));

  // 1. The model.
  fs::path model_path = c.model.file;
  if (!c.model.description.empty()) {
    const fs::path dir = out / "model";
    model_path = dir / "model.toml";
    if (!o.force && up_to_date(model_path, {c.model.description, c.file})) {
      summary.model_reused = true;
      say(o, fmt::format("model: {} is up to date", model_path.string()));
    } else {
      say(o, fmt::format("model: building from {}", c.model.description.string()));
      model::fe::RivetedBeamDescription d =
          model::fe::read_riveted_beam_description(c.model.description);
      if (c.model.fixed_interface_modes >= 0)
        d.fixed_interface_modes = c.model.fixed_interface_modes;
      model::fe::BuildOptions bo;
      bo.progress = [&](const std::string& s) { say(o, "model: " + s); };
      const model::fe::ReducedModel rm = model::fe::build_reduced_model(d, bo);
      if (!rm.summary.ok)
        throw InputError(fmt::format("{}: the reduction failed: {}", c.model.description.string(),
                                     rm.summary.report));
      model::fe::write_model_directory(dir, rm);
      summary.model_built = true;
    }
  }

  // 2. Every hit: processed when its cache is missing or stale.
  struct Job {
    const CampaignGroup* group;
    fs::path file;
  };
  std::vector<Job> jobs, todo;
  for (const CampaignGroup& g : c.groups)
    for (const fs::path& f : g.files) jobs.push_back({&g, f});
  for (const Job& j : jobs) {
    const fs::path marker = hit_dir(out, j.group->name) / (j.file.stem().string() + ".linear.csv");
    if (!o.force && up_to_date(marker, {j.file, c.file})) {
      ++summary.hits_reused;
    } else {
      todo.push_back(j);
    }
  }
  if (!todo.empty()) {
    say(o, fmt::format("process: {} hit(s) to process, {} up to date", todo.size(),
                       summary.hits_reused));
    parallel_for(
        todo.size(), o.threads, [] { return signal::FftCache{}; },
        [&](size_t i, signal::FftCache& cache) {
          process_hit(c, todo[i].file, hit_dir(out, todo[i].group->name), cache);
        });
    summary.hits_processed = static_cast<int>(todo.size());
  } else {
    say(o, fmt::format("process: all {} hit(s) up to date", jobs.size()));
  }
  std::vector<Hit> hits;
  for (const Job& j : jobs)
    hits.push_back(load_hit(c, *j.group, j.file, hit_dir(out, j.group->name)));

  // 3. Scatter summaries of each mode at its reference channel.
  const size_t nm = c.modes.size(), nc = c.channels.size();
  std::vector<int> ref(nm, 0);
  std::vector<std::vector<Curve>> curves(nm);
  std::vector<ScatterSummary> scatter(nm);
  fs::create_directories(out / "scatter");
  std::vector<bool> flagged_any(hits.size(), false);
  for (size_t k = 0; k < nm; ++k) {
    for (size_t i = 0; i < nc; ++i)
      if (c.channels[i].name == c.modes[k].reference) ref[k] = static_cast<int>(i);
    for (const Hit& h : hits) {
      const Curve& cv = h.curves[k][ref[k]];
      if (cv.amplitude.size() > 0) curves[k].push_back(cv);
    }
    scatter[k] = summarize_scatter(curves[k], c.scatter);
    for (const HitDeviation& d : scatter[k].hits) {
      if (!d.outlier) continue;
      for (size_t h = 0; h < hits.size(); ++h)
        if (hits[h].stem == d.id) flagged_any[h] = true;
    }
    const fs::path base = out / "scatter" / slug(static_cast<int>(k));
    write_scatter_bins_csv(base.string() + ".bins.csv", scatter[k]);
    write_scatter_hits_csv(base.string() + ".hits.csv", scatter[k]);
    write_scatter_json(base.string() + ".json", c.modes[k].name, scatter[k]);
    say(o, fmt::format("scatter: {}: {}", c.modes[k].name, scatter[k].report()));
  }
  summary.flagged_hits = static_cast<int>(std::count(flagged_any.begin(), flagged_any.end(), true));

  // Measured linear modal data: mean frequency and mean shape over the kept hits.
  MeasuredModes measured;
  measured.frequency_hz.resize(static_cast<Eigen::Index>(nm));
  measured.shapes =
      Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(nc), static_cast<Eigen::Index>(nm));
  for (size_t k = 0; k < nm; ++k) {
    measured.frequency_hz(static_cast<Eigen::Index>(k)) = scatter[k].linear_frequency_hz.mean;
    measured.labels.push_back(c.modes[k].name);
    for (size_t h = 0; h < hits.size(); ++h) {
      if (flagged_any[h] && c.scatter.exclude_outliers) continue;
      const std::complex<double> r = hits[h].linear[k][ref[k]].amplitude;
      if (std::abs(r) == 0) continue;
      for (size_t i = 0; i < nc; ++i)
        measured.shapes(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) +=
            hits[h].linear[k][i].amplitude / std::abs(r);
    }
  }

  // 4. Model side: QSMA before and after updating, linear frequencies, MAC.
  const fs::path fig = out / "figures";
  fs::create_directories(fig);
  Report report;
  report.title = fmt::format("Test campaign: {}", c.name);
  bool have_model = !model_path.empty();
  ModelSide start, updated;
  bool have_updated = false;
  model::Model model, model_updated;
  std::vector<Eigen::Index> dofs;
  std::vector<std::string> parameter_rows_names;
  LinearUpdateSummary linear_summary;
  bool linear_ran = false;
  IwanUpdateSummary iwan_summary;
  bool iwan_ran = false;
  bool iwan_beta_held = false;  // beta held: at start (microslip) or by campaign
  int iwan_curves = 0;
  struct ModeCost {
    std::string mode;
    bool fitted;
    double start, updated;
  };
  std::vector<ModeCost> iwan_mode_costs;
  double iwan_cost_known = 0;  // backbone cost at the known parameters (simulated campaign)
  Eigen::VectorXd theta;
  if (have_model) {
    say(o, fmt::format("model: reading {}", model_path.string()));
    model = model::read_model(model_path);
    for (const CampaignChannel& ch : c.channels)
      dofs.push_back(model::resolve_dof(model, ch.dof, fmt::format("channel '{}' dof", ch.name)));
    start = evaluate_model(c, model, dofs, "model, start", out / "qsma", "start");
    // Linear updating.
    if (c.linear_update.enabled) {
      if (c.linear_update.sets.empty()) {
        summary.notes.push_back("update.linear: no 'sets' given; linear updating skipped");
      } else {
        std::vector<Sensor> sensors;
        for (size_t i = 0; i < nc; ++i)
          sensors.push_back({c.channels[i].name, dofs[i], c.channels[i].sign});
        LinearUpdateOptions lo;
        const auto& st = c.linear_update.settings;
        for (const auto& [key, value] : st) {
          if (key == "mac_threshold")
            lo.mac_threshold = value;
          else if (key == "lower_factor")
            lo.lower_factor = value;
          else if (key == "upper_factor")
            lo.upper_factor = value;
          else if (key == "max_iterations")
            lo.max_iterations = static_cast<int>(value);
          else if (key == "tolerance")
            lo.tolerance = value;
          else if (key == "flat_sensitivity")
            lo.flat_sensitivity = value;
          else if (key == "frequency_std")
            lo.frequency_std = value;
          else
            throw InputError(
                where(c.file.string(), 0, fmt::format("update.linear: unknown setting '{}'", key)));
        }
        if (const std::string e = lo.error(); !e.empty())
          throw InputError(where(c.file.string(), 0, "update.linear: " + e));
        say(o, "update: linear updating of " +
                   fmt::format("{}", fmt::join(c.linear_update.sets, ", ")));
        // The measured modes it fits: those named in 'modes' (default every mode).
        MeasuredModes fitted;
        std::vector<Eigen::Index> keep;
        for (size_t k = 0; k < nm; ++k)
          if (c.linear_update.fits(c.modes[k].name)) keep.push_back(static_cast<Eigen::Index>(k));
        fitted.frequency_hz = measured.frequency_hz(keep);
        fitted.shapes = measured.shapes(Eigen::all, keep);
        for (Eigen::Index k : keep) fitted.labels.push_back(measured.labels[k]);
        theta = update_linear(model, c.linear_update.sets, sensors, fitted, lo, &linear_summary);
        const StiffnessSets sets(model, c.linear_update.sets);
        model_updated = sets.apply(theta);
        have_updated = true;
        linear_ran = true;
        say(o, "update: " + linear_summary.report());
      }
    }
    if (c.iwan_update.enabled) {
      // The Iwan set: the one named in 'sets', else the model's first Iwan set.
      model::IwanParameters first;
      std::string set;
      if (!c.iwan_update.sets.empty()) {
        set = c.iwan_update.sets.front();
      } else if (!first_iwan(model, first, set)) {
        throw InputError(where(c.file.string(), 0, "update.iwan: the model has no Iwan joint"));
      }
      IwanUpdateOptions io;
      // Other modes' share of the joint slip a fitted point may carry: at 5 % the
      // excess damping it causes (about half the share in the example campaign)
      // stays below the hit-to-hit scatter of the damping.
      double max_share = 0.05;
      io.amplitude = c.amplitude == Quantity::kDisplacement   ? AmplitudeQuantity::kDisplacement
                     : c.amplitude == Quantity::kAcceleration ? AmplitudeQuantity::kAcceleration
                                                              : AmplitudeQuantity::kVelocity;
      for (const auto& [key, value] : c.iwan_update.settings) {
        if (key == "max_evaluations")
          io.max_evaluations = static_cast<int>(value);
        else if (key == "gamma")
          io.fixed_gamma = value;
        else if (key == "beta")
          io.fixed_beta = value;
        else if (key == "qsma_points")
          io.qsma_points = static_cast<int>(value);
        else if (key == "samples")
          io.samples = static_cast<int>(value);
        else if (key == "local_starts")
          io.local_starts = static_cast<int>(value);
        else if (key == "seed")
          io.seed = static_cast<unsigned>(value);
        else if (key == "max_slip_share")
          max_share = value;
        else
          throw InputError(
              where(c.file.string(), 0, fmt::format("update.iwan: unknown setting '{}'", key)));
      }
      if (const std::string e = io.error(); !e.empty())
        throw InputError(where(c.file.string(), 0, "update.iwan: " + e));
      std::vector<Sensor> sensors;
      for (size_t i = 0; i < nc; ++i)
        sensors.push_back({c.channels[i].name, dofs[i], c.channels[i].sign});
      // Every kept hit's backbone of each mode that names its model mode.
      std::vector<IwanTarget> targets;
      std::vector<std::pair<size_t, IwanTarget>> every;  // each mode's target, fitted or not
      // Each measured mode's joint-slip pattern in the model the update starts from.
      const model::Model& base = have_updated ? model_updated : model;
      const model::JointCondensation start_jc(base);
      const int power = amplitude_power(io.amplitude);
      std::vector<ModeSlip> slips(nm);
      for (size_t k = 0; k < nm; ++k) {
        const int mm = c.modes[k].model_mode;
        if (mm > 0 && mm <= start_jc.elastic_count() && ref[k] >= 0)
          slips[k] = mode_slip(base, start_jc.modes(), mm, dofs[ref[k]], power);
      }
      Eigen::Index interfered = 0;
      for (size_t k = 0; k < nm; ++k) {
        if (c.modes[k].model_mode <= 0 || ref[k] < 0) continue;
        IwanTarget t;
        t.mode = c.modes[k].model_mode;
        t.linear_frequency_hz = measured.frequency_hz(static_cast<Eigen::Index>(k));
        // Each point weighs by the scatter between hits in its amplitude bin (the
        // spread a single set of joint parameters cannot fit); 0 leaves the floor.
        const auto bin_std = [&](double a, bool frequency) {
          for (const ScatterBin& b : scatter[k].bins) {
            if (a >= b.amplitude_low && a < b.amplitude_high && b.curves >= 2) {
              return frequency ? b.frequency_hz.std : b.damping.std;
            }
          }
          return 0.0;
        };
        for (const Curve& cv : curves[k]) {
          // Flagged hits are left out as they are left out of the bins.
          const bool flagged =
              std::any_of(scatter[k].hits.begin(), scatter[k].hits.end(),
                          [&](const HitDeviation& d) { return d.outlier && d.id == cv.id; });
          if (flagged && c.scatter.exclude_outliers) continue;
          // Points where the other modes still slip the joints are left out: no
          // single-mode QSMA curve describes them (correlate/mode_interference.h).
          std::vector<const Curve*> same_hit(nm, nullptr);
          for (size_t j = 0; j < nm; ++j) {
            for (const Curve& o : curves[j]) {
              if (o.id == cv.id && o.time_s.size() > 0) same_hit[j] = &o;
            }
          }
          const Eigen::VectorXd share = slip_share(slips, same_hit, k);
          // A mode that is not fitted keeps every point: its fit error is only reported.
          const bool fitted = c.iwan_update.fits(c.modes[k].name);
          std::vector<Eigen::Index> keep;
          for (Eigen::Index j = 0; j < cv.amplitude.size(); ++j) {
            if (!fitted || share(j) <= max_share) keep.push_back(j);
          }
          interfered += cv.amplitude.size() - static_cast<Eigen::Index>(keep.size());
          if (keep.size() < 2) continue;
          MeasuredBackbone mb;
          mb.sensor = ref[k];
          mb.amplitude = cv.amplitude(keep);
          mb.frequency_hz = cv.frequency_hz(keep);
          mb.damping_ratio = cv.damping(keep);
          mb.frequency_std_hz.resize(mb.amplitude.size());
          mb.damping_std.resize(mb.amplitude.size());
          for (Eigen::Index j = 0; j < mb.amplitude.size(); ++j) {
            mb.frequency_std_hz(j) = bin_std(mb.amplitude(j), true);
            mb.damping_std(j) = bin_std(mb.amplitude(j), false);
          }
          t.curves.push_back(std::move(mb));
        }
        if (t.curves.empty()) continue;
        every.emplace_back(k, t);
        if (c.iwan_update.fits(c.modes[k].name)) targets.push_back(std::move(t));
      }
      if (targets.empty()) {
        summary.notes.push_back(
            "update.iwan: no mode names its model mode (model_mode); Iwan updating skipped");
      } else {
        const IwanObjective objective(base, set, sensors, targets, io.amplitude, io.qsma_points,
                                      io.frequency_floor, io.damping_floor);
        size_t n_curves = 0;
        for (const IwanTarget& t : targets) n_curves += t.curves.size();
        say(o, fmt::format("update: Iwan identification of {} ({} modes, {} curves; {} points "
                           "left out where other modes carry over {:g} % of the joint slip)",
                           set, targets.size(), n_curves, interfered, 100 * max_share));
        // First with beta held at its starting value (unless the campaign holds it): below
        // phi_max the response depends on K_T, chi and R only, and (F_S, beta) along a line
        // of equal R all fit alike. Only when that fit puts the top of the data past phi_max
        // do the backbones reach macroslip; then beta is freed as well.
        IwanUpdateOptions held = io;
        if (held.fixed_beta == 0) held.fixed_beta = objective.initial().beta;
        update_iwan(objective, held, &iwan_summary);
        if (io.fixed_beta == 0 && !iwan_summary.microslip_only()) {
          say(o, "update: " + iwan_summary.report() +
                     "update: the data reach macroslip; Iwan identification with beta free");
          IwanUpdateSummary full;
          update_iwan(objective, io, &full);
          full.evaluations += iwan_summary.evaluations;
          if (full.final_cost < iwan_summary.final_cost) iwan_summary = full;
        }
        iwan_beta_held = iwan_summary.microslip_only() || io.fixed_beta > 0;
        iwan_curves = static_cast<int>(n_curves);
        model_updated = objective.apply(iwan_summary.best);
        if (!c.truth.empty()) iwan_cost_known = objective.cost(read_truth(c.truth).iwan);
        // Each mode's backbone cost at the start and at the result, fitted or not: a mode the
        // one-mode QSMA cannot describe (its joints moved by another mode) stands out.
        for (const auto& [k, t] : every) {
          const IwanObjective one(base, set, sensors, {t}, io.amplitude, io.qsma_points,
                                  io.frequency_floor, io.damping_floor);
          iwan_mode_costs.push_back({c.modes[k].name, c.iwan_update.fits(c.modes[k].name),
                                     one.cost(iwan_summary.start), one.cost(iwan_summary.best)});
        }
        have_updated = true;
        iwan_ran = true;
        say(o, "update: " + iwan_summary.report());
      }
    }
    if (have_updated)
      updated = evaluate_model(c, model_updated, dofs, "model, updated", out / "qsma", "updated");
  }

  // 5. Figures.
  say(o, "figures: drawing");
  std::vector<ReportFigure> figures_backbone;
  for (size_t k = 0; k < nm; ++k) {
    BackboneFigure bf;
    bf.title = fmt::format("{} ({:g}-{:g} Hz band), channel {}", c.modes[k].name,
                           c.modes[k].band.lo, c.modes[k].band.hi, c.modes[k].reference);
    bf.amplitude_label =
        fmt::format("{} amplitude [{}]", quantity_name(c.amplitude), si_unit(c.amplitude));
    bf.hits = curves[k];
    bf.summary = scatter[k];
    if (have_model && start.curves[k].amplitude.size() > 1) bf.model.push_back(start.curves[k]);
    if (have_updated && updated.curves[k].amplitude.size() > 1)
      bf.model.push_back(updated.curves[k]);
    const fs::path p = fig / fmt::format("backbone_{}.png", slug(static_cast<int>(k)));
    plot_backbones(bf, p);
    figures_backbone.push_back(
        {fmt::format("{}: natural frequency and damping ratio versus {} "
                     "amplitude; every hit faint, the mean over hits per "
                     "bin with its {:g} % confidence interval, and the "
                     "model's QSMA curve{}.",
                     c.modes[k].name, quantity_name(c.amplitude), 100 * c.scatter.confidence,
                     c.iwan_update.enabled && c.modes[k].model_mode > 0 &&
                             !c.iwan_update.fits(c.modes[k].name)
                         ? " (a mode the Iwan update does not fit, [update.iwan] modes; its "
                           "backbone cost is listed with the update)"
                         : ""),
         p});
  }
  // Spectrum of the first hit of the last group (the strongest level, by convention).
  ReportFigure spectrum_figure;
  {
    const fs::path& f = c.groups.back().files.front();
    const data::Record rec = data::read_record(f);
    signal::FftCache cache;
    SpectrumFigure sf;
    sf.title = fmt::format("spectrum of {}", f.filename().string());
    for (const CampaignChannel& ch : c.channels) {
      const data::Channel* rc = rec.find(ch.name);
      if (!rc) throw InputError(fmt::format("{}: no channel '{}'", f.string(), ch.name));
      const signal::AmplitudeSpectrum s = signal::amplitude_spectrum(rc->samples, rec.fs, cache);
      sf.frequency_hz = s.frequency_hz;
      sf.spectra.push_back(s.amplitude);
      sf.channel_names.push_back(ch.name);
      const Quantity q = rc->quantity.value_or(c.quantity);
      sf.amplitude_label = fmt::format("{} amplitude [{}]", quantity_name(q), si_unit(q));
    }
    double fmax = 0;
    for (const CampaignMode& m : c.modes) {
      sf.bands.push_back({m.name, m.band.lo, m.band.hi});
      fmax = std::max(fmax, m.band.hi);
    }
    sf.max_frequency_hz = std::min(rec.fs / 2, 1.5 * fmax);
    const fs::path p = fig / "spectrum.png";
    plot_spectrum(sf, p);
    spectrum_figure = {"Amplitude spectrum (Hann window) of one hit with the analysis bands.", p};
  }
  std::vector<ReportFigure> model_figures;
  if (have_model) {
    const ModelSide& side = have_updated ? updated : start;
    const Eigen::MatrixXd mm = mac_matrix(measured.shapes, side.sensor_shapes);
    std::vector<std::string> rows, cols;
    for (const CampaignMode& m : c.modes) rows.push_back(m.name);
    for (size_t j = 0; j < side.shape_hz.size(); ++j)
      cols.push_back(fmt::format("{} ({:.0f} Hz)", j + 1, side.shape_hz[j]));
    const fs::path p = fig / "mac.png";
    plot_mac(
        mm, rows, cols,
        fmt::format("MAC, measured shapes versus {} model", have_updated ? "updated" : "starting"),
        p);
    model_figures.push_back(
        {fmt::format("MAC of the measured operating shapes ({} channels) and the "
                     "model's elastic modes at the sensors.",
                     nc),
         p});
    std::vector<std::string> labels;
    ErrorSeries before{"starting model", {}}, after{"updated model", {}};
    for (size_t k = 0; k < nm; ++k) {
      if (start.frequency_hz[k] <= 0 || scatter[k].linear_count == 0) continue;
      const double fe = scatter[k].linear_frequency_hz.mean;
      labels.push_back(c.modes[k].name);
      before.percent.push_back(100 * (start.frequency_hz[k] - fe) / fe);
      if (have_updated) after.percent.push_back(100 * (updated.frequency_hz[k] - fe) / fe);
    }
    if (!labels.empty()) {
      std::vector<ErrorSeries> series{before};
      if (have_updated) series.push_back(after);
      const fs::path pe = fig / "frequency_errors.png";
      plot_frequency_errors(labels, series, "linear frequency errors, model versus test", pe);
      model_figures.push_back(
          {"Linear (low-amplitude) frequency error of the model per mode.", pe});
    }
  }

  // 6. The report.
  {
    ReportSection s;
    s.heading = "Data processed";
    s.paragraphs.push_back(fmt::format(
        "Campaign file {}. {} hit(s) in {} group(s); channels {}; {} mode(s). Channels without a "
        "unit measure {}; backbone amplitudes are {} amplitudes [{}].",
        c.file.string(), summary.hits, c.groups.size(),
        [&] {
          std::string t;
          for (const CampaignChannel& ch : c.channels)
            t += (t.empty() ? "" : ", ") + ch.name +
                 (ch.dof.empty() ? "" : " (model DOF " + ch.dof + ")");
          return t;
        }(),
        nm, quantity_name(c.quantity), quantity_name(c.amplitude), si_unit(c.amplitude)));
    ReportTable t{"Groups", {"group", "level", "hits", "files"}, {}};
    for (const CampaignGroup& g : c.groups) {
      std::string files;
      for (const fs::path& f : g.files) files += (files.empty() ? "" : " ") + f.filename().string();
      t.rows.push_back({g.name, g.level, std::to_string(g.files.size()), files});
    }
    s.tables.push_back(t);
    ReportTable mt{"Modes", {"mode", "band [Hz]", "reference channel", "model mode"}, {}};
    for (const CampaignMode& m : c.modes)
      mt.rows.push_back({m.name, fmt::format("{:g} - {:g}", m.band.lo, m.band.hi), m.reference,
                         m.model_mode ? std::to_string(m.model_mode) : "-"});
    s.tables.push_back(mt);
    s.figures.push_back(spectrum_figure);
    report.sections.push_back(s);
  }
  {
    ReportSection s;
    s.heading = "Settings";
    const ScatterOptions& so = c.scatter;
    s.paragraphs.push_back(fmt::format(
        "Processing: jointlab process defaults (Hilbert envelope and phase, local fits, "
        "uncertainties at k = {:g}). Scatter: {} bins per decade of amplitude, {:g} % Student-t "
        "confidence intervals of the mean, bins need {} curves; a hit is flagged when a robust "
        "z-score (median/MAD of its mean relative deviation from the per-bin medians, and of its "
        "linear frequency and damping) exceeds {:g} (spread floors {:g} in frequency, {:g} in "
        "damping); flagged hits are {} the bins. QSMA: {} points per curve.",
        modal::RingdownOptions{}.coverage_factor, so.bins_per_decade, 100 * so.confidence,
        so.min_curves, so.outlier_threshold, so.frequency_floor, so.damping_floor,
        so.exclude_outliers ? "left out of" : "kept in", c.qsma_points));
    report.sections.push_back(s);
  }
  for (size_t k = 0; k < nm; ++k) {
    ReportSection s;
    s.heading = fmt::format("Scatter summary: {}", c.modes[k].name);
    const ScatterSummary& sc = scatter[k];
    s.paragraphs.push_back(fmt::format("{} curve(s) at channel {}. {}", curves[k].size(),
                                       c.modes[k].reference, sc.report()));
    ReportTable bt{"Bins (frequency and damping: mean, standard deviation, confidence interval)",
                   {"amplitude", "curves", "f mean [Hz]", "f std [Hz]", "f interval [Hz]",
                    "zeta mean", "zeta std", "zeta interval"},
                   {}};
    for (const ScatterBin& b : sc.bins) {
      bt.rows.push_back(
          {fmt::format("{:.3g}", b.amplitude_center), std::to_string(b.curves),
           fmt::format("{:.4f}", b.frequency_hz.mean), fmt::format("{:.4f}", b.frequency_hz.std),
           fmt::format("{:.4f} - {:.4f}", b.frequency_hz.ci_low, b.frequency_hz.ci_high),
           fmt::format("{:.5f}", b.damping.mean), fmt::format("{:.5f}", b.damping.std),
           fmt::format("{:.5f} - {:.5f}", b.damping.ci_low, b.damping.ci_high)});
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
                         h.has_linear ? fmt::format("{:.5f}", h.linear_damping) : "-",
                         h.outlier ? "yes: " + h.reason : "no"});
    }
    s.tables.push_back(ht);
    s.paragraphs.push_back(fmt::format(
        "Linear (low-amplitude) values over {} hit(s): frequency {:.4f} Hz, standard deviation "
        "{:.4f} Hz, interval {:.4f} - {:.4f} Hz; damping ratio {:.5f}, standard deviation {:.5f}.",
        sc.linear_count, sc.linear_frequency_hz.mean, sc.linear_frequency_hz.std,
        sc.linear_frequency_hz.ci_low, sc.linear_frequency_hz.ci_high, sc.linear_damping.mean,
        sc.linear_damping.std));
    s.figures.push_back(figures_backbone[k]);
    report.sections.push_back(s);
  }
  if (have_model) {
    ReportSection s;
    s.heading = "Model";
    s.paragraphs.push_back(fmt::format("Model file {} ({} DOFs, {} joint elements, {} Iwan).",
                                       model_path.string(), model.size(), model.joints.size(),
                                       model.iwan_count()));
    for (const std::string& n : start.qsma_notes) s.paragraphs.push_back("QSMA " + n);
    ReportTable ft{"Linear frequencies, test versus model",
                   {"mode", "test [Hz]", "test std [Hz]", "model start [Hz]", "error start",
                    "model updated [Hz]", "error updated"},
                   {}};
    for (size_t k = 0; k < nm; ++k) {
      if (start.frequency_hz[k] <= 0) continue;
      const double fe = scatter[k].linear_frequency_hz.mean;
      ft.rows.push_back({c.modes[k].name, fmt::format("{:.4f}", fe),
                         fmt::format("{:.4f}", scatter[k].linear_frequency_hz.std),
                         fmt::format("{:.4f}", start.frequency_hz[k]),
                         pct(100 * (start.frequency_hz[k] - fe) / fe),
                         have_updated ? fmt::format("{:.4f}", updated.frequency_hz[k]) : "-",
                         have_updated ? pct(100 * (updated.frequency_hz[k] - fe) / fe) : "-"});
    }
    s.tables.push_back(ft);

    // Parameters before and after, and the known values of a simulated campaign.
    const Truth truth = read_truth(c.truth);
    model::IwanParameters p0, p1;
    std::string set;
    const bool has_iwan = first_iwan(model, p0, set);
    p1 = p0;
    if (have_updated) first_iwan(model_updated, p1, set);
    ReportTable pt{
        "Joint parameters", {"parameter", "start", "updated", "known", "updated / known"}, {}};
    const auto row = [&](const std::string& name, double a, double b, double known,
                         bool updated_here) {
      pt.rows.push_back(
          {name, g6(a), updated_here ? g6(b) : "(not updated)",
           truth.present && known != 0 ? g6(known) : "-",
           truth.present && known != 0 && updated_here ? fmt::format("{:.4f}", b / known) : "-"});
    };
    const auto is_updated = [&](const std::string& element) {
      return have_updated && std::find(c.linear_update.sets.begin(), c.linear_update.sets.end(),
                                       element) != c.linear_update.sets.end();
    };
    if (has_iwan) {
      row(set + " Kt [N/m]", p0.Kt, p1.Kt, truth.iwan.Kt, is_updated(set) || iwan_ran);
      row(set + " Fs [N]", p0.Fs, p1.Fs, truth.iwan.Fs, iwan_ran);
      if (iwan_ran && iwan_summary.microslip_only())
        pt.rows.back()[2] += " (not identified: microslip data)";
      row(set + " chi", p0.chi, p1.chi, truth.iwan.chi, iwan_ran);
      row(set + " beta", p0.beta, p1.beta, truth.iwan.beta, iwan_ran);
      if (iwan_ran && iwan_beta_held) pt.rows.back()[2] += " (held)";
    }
    for (const std::string& name : c.linear_update.sets) {
      if (name.rfind("spring.", 0) != 0) continue;
      bool found = false;
      const double a = spring_value(model, name, found);
      const double b = have_updated ? spring_value(model_updated, name, found) : a;
      row(name, a, b, 0, is_updated(name));
    }
    s.tables.push_back(pt);
    if (linear_ran) s.paragraphs.push_back("Linear updating: " + linear_summary.report());
    if (iwan_ran) {
      s.paragraphs.push_back("Iwan identification: " + iwan_summary.report());
      ReportTable mc{
          "Backbone cost per mode (mean squared error in units of the scatter between "
          "hits: about 2 when the model lies within it)",
          {"mode", "fitted", "cost, start", "cost, updated"},
          {}};
      for (const ModeCost& m : iwan_mode_costs)
        mc.rows.push_back({m.mode, m.fitted ? "yes" : "no", fmt::format("{:.3g}", m.start),
                           fmt::format("{:.3g}", m.updated)});
      s.tables.push_back(mc);
    }
    if (truth.present && has_iwan) {
      KnownComparison kc;
      kc.truth = truth;
      kc.updated = p1;
      kc.kt_updated = is_updated(set) || iwan_ran;
      kc.iwan_ran = iwan_ran;
      kc.beta_held = iwan_beta_held;
      kc.curves = iwan_curves;
      kc.iwan = iwan_summary;
      kc.cost_known = iwan_cost_known;
      compare_with_known(kc, c.truth.filename().string(), s);
    }
    s.figures = model_figures;
    report.sections.push_back(s);
  }
  {
    ReportSection s;
    s.heading = "Notes and errors";
    if (summary.notes.empty()) s.paragraphs.push_back("No step was skipped.");
    for (const std::string& n : summary.notes) s.paragraphs.push_back(n);
    s.paragraphs.push_back(
        fmt::format("This run: {} hit(s) processed, {} reused from earlier runs; model {}.",
                    summary.hits_processed, summary.hits_reused,
                    summary.model_built    ? "built"
                    : summary.model_reused ? "reused"
                                           : "given as a file"));
    report.sections.push_back(s);
  }
  summary.report_html = out / "report.html";
  summary.report_markdown = out / "report.md";
  write_report_html(report, summary.report_html);
  write_report_markdown(report, summary.report_markdown);
  return summary;
}

}  // namespace jointlab::campaign
