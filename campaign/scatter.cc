#include "jointlab/campaign/scatter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>
#include <boost/math/distributions/students_t.hpp>

#include "jointlab/core/error.h"
#include "jointlab/core/median.h"
#include "jointlab/data/atomic_file.h"
#include "jointlab/data/json_writer.h"
#include "jointlab/data/table_writer.h"

namespace jointlab::campaign {

namespace {

// Robust z-scores (x - median) / max(1.4826 MAD, floor); all zero for fewer than 3 values.
std::vector<double> robust_z(const std::vector<double>& x, double floor) {
  std::vector<double> z(x.size(), 0.0);
  if (x.size() < 3) return z;
  const double med = median(x);
  std::vector<double> dev(x.size());
  for (size_t i = 0; i < x.size(); ++i) dev[i] = std::abs(x[i] - med);
  const double scale = std::max(1.4826 * median(dev), floor);
  for (size_t i = 0; i < x.size(); ++i) z[i] = (x[i] - med) / scale;
  return z;
}

// Flags each hit with any |z| above the threshold, naming the z-scores that did.
void flag_outliers(std::vector<HitDeviation>& hits, double thr) {
  for (HitDeviation& h : hits) {
    const std::pair<double, const char*> tests[] = {{h.frequency_z, "frequency"},
                                                    {h.damping_z, "damping"},
                                                    {h.linear_frequency_z, "linear frequency"},
                                                    {h.linear_damping_z, "linear damping"}};
    for (const auto& [z, name] : tests) {
      if (std::abs(z) > thr) {
        h.outlier = true;
        if (!h.reason.empty()) h.reason += ", ";
        h.reason += fmt::format("{} z = {:+.1f}", name, z);
      }
    }
  }
}

}  // namespace

std::string ScatterOptions::check() const {
  if (bins_per_decade < 1 || bins_per_decade > 100)
    return fmt::format("bins_per_decade = {}: need 1 to 100", bins_per_decade);
  if (!(confidence > 0 && confidence < 1))
    return fmt::format("confidence = {}: need 0 < confidence < 1", confidence);
  if (min_curves < 2) return fmt::format("min_curves = {}: need at least 2", min_curves);
  if (!(outlier_threshold > 0 && std::isfinite(outlier_threshold)))
    return fmt::format("outlier_threshold = {}: need a positive number", outlier_threshold);
  if (!(frequency_floor > 0 && std::isfinite(frequency_floor)))
    return fmt::format("frequency_floor = {}: need a positive number", frequency_floor);
  if (!(damping_floor > 0 && std::isfinite(damping_floor)))
    return fmt::format("damping_floor = {}: need a positive number", damping_floor);
  return "";
}

int ScatterSummary::outliers() const {
  return static_cast<int>(
      std::count_if(hits.begin(), hits.end(), [](const HitDeviation& h) { return h.outlier; }));
}

std::string ScatterSummary::report() const {
  std::string s;
  if (bins.empty()) {
    s = "no amplitude bin is reached by enough curves";
  } else {
    s = fmt::format("{} bins from {:.3g} to {:.3g}", bins.size(), bins.front().amplitude_low,
                    bins.back().amplitude_high);
  }
  s += fmt::format("; {} hit(s), {} flagged", hits.size(), outliers());
  for (const HitDeviation& h : hits)
    if (h.outlier) s += fmt::format(" [{}: {}]", h.id, h.reason);
  if (linear_count > 0) {
    if (linear_frequency_hz.has_spread())
      s += fmt::format("; linear frequency {:.6g} Hz (std {:.3g} Hz), damping {:.4g} (std {:.2g})",
                       linear_frequency_hz.mean, linear_frequency_hz.std, linear_damping.mean,
                       linear_damping.std);
    else
      s += fmt::format("; linear frequency {:.6g} Hz, damping {:.4g} (one hit: no spread)",
                       linear_frequency_hz.mean, linear_damping.mean);
  }
  return s;
}

double student_t_quantile(double p, int dof) {
  if (!(p > 0 && p < 1) || dof < 1)
    throw InputError(
        fmt::format("Student t quantile: need 0 < p < 1 and dof >= 1 (p = {}, "
                    "dof = {})",
                    p, dof));
  return boost::math::quantile(boost::math::students_t(dof), p);
}

Statistic describe(const std::vector<double>& values, double confidence) {
  Statistic st;
  const size_t n = values.size();
  st.count = static_cast<int>(n);
  if (n == 0) return st;
  double sum = 0;
  for (double v : values) sum += v;
  st.mean = sum / static_cast<double>(n);
  st.ci_low = st.ci_high = st.mean;
  if (n < 2) return st;
  double ss = 0;
  for (double v : values) ss += (v - st.mean) * (v - st.mean);
  st.std = std::sqrt(ss / static_cast<double>(n - 1));
  const double half = student_t_quantile(0.5 * (1.0 + confidence), static_cast<int>(n - 1)) *
                      st.std / std::sqrt(static_cast<double>(n));
  st.ci_low = st.mean - half;
  st.ci_high = st.mean + half;
  return st;
}

ScatterSummary summarize_scatter(const std::vector<Curve>& curves, const ScatterOptions& options) {
  if (const std::string why = options.check(); !why.empty()) throw InputError("scatter: " + why);
  ScatterSummary out;
  out.options = options;
  const int nd = options.bins_per_decade;

  // Each curve's mean value in every bin it reaches: bin index -> (frequency, damping).
  struct BinValue {
    double f = 0, z = 0;
  };
  std::vector<std::map<int, BinValue>> per_curve(curves.size());
  int kmin = std::numeric_limits<int>::max(), kmax = std::numeric_limits<int>::min();
  for (size_t c = 0; c < curves.size(); ++c) {
    const Curve& cv = curves[c];
    if (cv.amplitude.size() != cv.frequency_hz.size() || cv.amplitude.size() != cv.damping.size())
      throw InputError(fmt::format("scatter: curve {}: columns of unequal length", cv.id));
    std::map<int, std::array<double, 3>> acc;  // sum f, sum z, count
    for (Eigen::Index i = 0; i < cv.amplitude.size(); ++i) {
      const double a = cv.amplitude(i), f = cv.frequency_hz(i), z = cv.damping(i);
      if (!(a > 0) || !std::isfinite(a) || !std::isfinite(f) || !std::isfinite(z))
        throw InputError(fmt::format(
            "scatter: curve {}: point {} is not finite or its amplitude is not > 0", cv.id, i + 1));
      const int k = static_cast<int>(std::floor(std::log10(a) * nd));
      auto& s = acc[k];
      s[0] += f;
      s[1] += z;
      s[2] += 1;
    }
    for (const auto& [k, s] : acc) {
      per_curve[c][k] = {s[0] / s[2], s[1] / s[2]};
      kmin = std::min(kmin, k);
      kmax = std::max(kmax, k);
    }
  }

  // Per-hit deviations from the per-bin medians (bins with at least three curves).
  const size_t nh = curves.size();
  out.hits.resize(nh);
  std::vector<double> dev_f(nh, 0.0), dev_z(nh, 0.0);
  for (int k = kmin; k <= kmax && !curves.empty(); ++k) {
    std::vector<double> fs, zs;
    for (size_t c = 0; c < nh; ++c) {
      if (auto it = per_curve[c].find(k); it != per_curve[c].end()) {
        fs.push_back(it->second.f);
        zs.push_back(it->second.z);
      }
    }
    if (fs.size() < 3) continue;
    const double mf = median(fs), mz = median(zs);
    for (size_t c = 0; c < nh; ++c) {
      if (auto it = per_curve[c].find(k); it != per_curve[c].end()) {
        dev_f[c] += (it->second.f - mf) / mf;
        dev_z[c] += mz > 0 ? (it->second.z - mz) / mz : 0.0;
        out.hits[c].bins += 1;
      }
    }
  }
  std::vector<double> df, dz;
  std::vector<size_t> with_bins;
  for (size_t c = 0; c < nh; ++c) {
    HitDeviation& h = out.hits[c];
    h.id = curves[c].id;
    h.group = curves[c].group;
    h.has_linear = curves[c].has_linear;
    h.linear_frequency_hz = curves[c].linear_frequency_hz;
    h.linear_damping = curves[c].linear_damping;
    if (h.bins > 0) {
      h.frequency_deviation = dev_f[c] / h.bins;
      h.damping_deviation = dev_z[c] / h.bins;
      df.push_back(h.frequency_deviation);
      dz.push_back(h.damping_deviation);
      with_bins.push_back(c);
    }
  }
  const std::vector<double> zf = robust_z(df, options.frequency_floor);
  const std::vector<double> zz = robust_z(dz, options.damping_floor);
  for (size_t i = 0; i < with_bins.size(); ++i) {
    out.hits[with_bins[i]].frequency_z = zf[i];
    out.hits[with_bins[i]].damping_z = zz[i];
  }
  // Linear values: relative to their median, then robust z.
  std::vector<double> lf, lz;
  std::vector<size_t> with_linear;
  for (size_t c = 0; c < nh; ++c) {
    if (!curves[c].has_linear) continue;
    lf.push_back(curves[c].linear_frequency_hz);
    lz.push_back(curves[c].linear_damping);
    with_linear.push_back(c);
  }
  if (!lf.empty()) {
    const double mf = median(lf), mz = median(lz);
    for (size_t i = 0; i < lf.size(); ++i) {
      lf[i] = (lf[i] - mf) / mf;
      lz[i] = mz > 0 ? (lz[i] - mz) / mz : 0.0;
    }
    const std::vector<double> zlf = robust_z(lf, options.frequency_floor);
    const std::vector<double> zlz = robust_z(lz, options.damping_floor);
    for (size_t i = 0; i < with_linear.size(); ++i) {
      out.hits[with_linear[i]].linear_frequency_z = zlf[i];
      out.hits[with_linear[i]].linear_damping_z = zlz[i];
    }
  }
  flag_outliers(out.hits, options.outlier_threshold);

  // Bins over the curves kept.
  const auto kept = [&](size_t c) { return !(options.exclude_outliers && out.hits[c].outlier); };
  for (int k = kmin; k <= kmax && !curves.empty(); ++k) {
    std::vector<double> fs, zs;
    int flagged = 0;
    for (size_t c = 0; c < nh; ++c) {
      const auto it = per_curve[c].find(k);
      if (it == per_curve[c].end()) continue;
      if (out.hits[c].outlier) ++flagged;
      if (!kept(c)) continue;
      fs.push_back(it->second.f);
      zs.push_back(it->second.z);
    }
    if (static_cast<int>(fs.size()) < options.min_curves) continue;
    ScatterBin b;
    b.amplitude_low = std::pow(10.0, static_cast<double>(k) / nd);
    b.amplitude_high = std::pow(10.0, static_cast<double>(k + 1) / nd);
    b.amplitude_center = std::sqrt(b.amplitude_low * b.amplitude_high);
    b.curves = static_cast<int>(fs.size());
    b.flagged = flagged;
    b.frequency_hz = describe(fs, options.confidence);
    b.damping = describe(zs, options.confidence);
    out.bins.push_back(b);
  }
  std::vector<double> keep_f, keep_z;
  for (size_t c = 0; c < nh; ++c) {
    if (!curves[c].has_linear || !kept(c)) continue;
    keep_f.push_back(curves[c].linear_frequency_hz);
    keep_z.push_back(curves[c].linear_damping);
  }
  out.linear_count = static_cast<int>(keep_f.size());
  out.linear_frequency_hz = describe(keep_f, options.confidence);
  out.linear_damping = describe(keep_z, options.confidence);
  return out;
}

void write_scatter_bins_csv(const std::filesystem::path& path, const ScatterSummary& s) {
  const Eigen::Index n = static_cast<Eigen::Index>(s.bins.size());
  std::vector<Eigen::VectorXd> c(13, Eigen::VectorXd(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const ScatterBin& b = s.bins[i];
    const double v[13] = {b.amplitude_low,    b.amplitude_high,      b.amplitude_center,
                          double(b.curves),   double(b.flagged),     b.frequency_hz.mean,
                          b.frequency_hz.std, b.frequency_hz.ci_low, b.frequency_hz.ci_high,
                          b.damping.mean,     b.damping.std,         b.damping.ci_low,
                          b.damping.ci_high};
    for (int j = 0; j < 13; ++j) c[j](i) = v[j];
  }
  const char* names[13] = {"amplitude_low",
                           "amplitude_high",
                           "amplitude_center",
                           "curves",
                           "flagged",
                           "frequency_mean_hz",
                           "frequency_std_hz",
                           "frequency_ci_low_hz",
                           "frequency_ci_high_hz",
                           "damping_mean",
                           "damping_std",
                           "damping_ci_low",
                           "damping_ci_high"};
  data::Table t;
  for (int j = 0; j < 13; ++j) t.add(names[j], c[j]);
  data::write_table(path, t);
}

void write_scatter_hits_csv(const std::filesystem::path& path, const ScatterSummary& s) {
  std::string text =
      "hit,group,bins,frequency_deviation,damping_deviation,frequency_z,damping_z,"
      "linear_frequency_hz,linear_damping,linear_frequency_z,linear_damping_z,outlier,reason\n";
  for (const HitDeviation& h : s.hits) {
    // A hit without linear values has empty cells there, never 0 standing in for "none".
    const std::string linear =
        h.has_linear ? fmt::format("{:.10g},{:.10g},{:.4g},{:.4g}", h.linear_frequency_hz,
                                   h.linear_damping, h.linear_frequency_z, h.linear_damping_z)
                     : ",,,";
    text += fmt::format("{},{},{},{:.10g},{:.10g},{:.4g},{:.4g},{},{},\"{}\"\n", h.id, h.group,
                        h.bins, h.frequency_deviation, h.damping_deviation, h.frequency_z,
                        h.damping_z, linear, h.outlier ? 1 : 0, h.reason);
  }
  data::write_file_atomically(path, text);
}

namespace {
void put(data::JsonWriter& j, const char* key, const Statistic& s) {
  j.key(key).begin_object();
  // One value has no spread: std and interval are absent, never 0.
  j.numbers({{"mean", s.mean}});
  if (s.has_spread()) j.numbers({{"std", s.std}, {"ci_low", s.ci_low}, {"ci_high", s.ci_high}});
  j.end_object();
}
}  // namespace

void write_scatter_json(const std::filesystem::path& path, const std::string& mode,
                        const ScatterSummary& s) {
  data::JsonWriter j;
  j.begin_object();
  j.key("mode").value(mode);
  j.key("settings").begin_object();
  const ScatterOptions& o = s.options;
  j.key("bins_per_decade").value(o.bins_per_decade);
  j.key("confidence").value(o.confidence);
  j.key("min_curves").value(o.min_curves);
  j.numbers({{"outlier_threshold", o.outlier_threshold},
             {"frequency_floor", o.frequency_floor},
             {"damping_floor", o.damping_floor}});
  j.key("exclude_outliers").value(o.exclude_outliers);
  j.end_object();
  j.key("bins").begin_array();
  for (const ScatterBin& b : s.bins) {
    j.begin_object();
    j.numbers({{"amplitude_low", b.amplitude_low},
               {"amplitude_high", b.amplitude_high},
               {"amplitude_center", b.amplitude_center}});
    j.key("curves").value(b.curves);
    j.key("flagged").value(b.flagged);
    put(j, "frequency_hz", b.frequency_hz);
    put(j, "damping_ratio", b.damping);
    j.end_object();
  }
  j.end_array();
  j.key("hits").begin_array();
  for (const HitDeviation& h : s.hits) {
    j.begin_object();
    j.key("hit").value(h.id);
    j.key("group").value(h.group);
    j.key("bins").value(h.bins);
    j.numbers({{"frequency_deviation", h.frequency_deviation},
               {"damping_deviation", h.damping_deviation},
               {"frequency_z", h.frequency_z},
               {"damping_z", h.damping_z}});
    if (h.has_linear) {
      j.numbers({{"linear_frequency_hz", h.linear_frequency_hz},
                 {"linear_damping_ratio", h.linear_damping},
                 {"linear_frequency_z", h.linear_frequency_z},
                 {"linear_damping_z", h.linear_damping_z}});
    }
    j.key("outlier").value(h.outlier);
    j.key("reason").value(h.reason);
    j.end_object();
  }
  j.end_array();
  j.key("linear").begin_object();
  j.key("hits").value(s.linear_count);
  put(j, "frequency_hz", s.linear_frequency_hz);
  put(j, "damping_ratio", s.linear_damping);
  j.end_object();
  j.end_object();
  data::write_file_atomically(path, j.str() + "\n");
}

}  // namespace jointlab::campaign
