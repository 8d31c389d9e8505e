#include "jointlab/campaign/steps/measured_side.h"

#include <algorithm>
#include <complex>

#include <fmt/format.h>

namespace jointlab::campaign {

namespace fs = std::filesystem;

namespace {

// The mean operating shape and linear frequency of each mode over the kept hits.
correlate::MeasuredModes linear_modes(const Campaign& c, const std::vector<HitData>& hits,
                                      const MeasuredSide& m) {
  const size_t nm = c.modes.size(), nc = c.channels.size();
  correlate::MeasuredModes measured;
  measured.frequency_hz.resize(static_cast<Eigen::Index>(nm));
  measured.shapes =
      Eigen::MatrixXcd::Zero(static_cast<Eigen::Index>(nc), static_cast<Eigen::Index>(nm));
  for (size_t k = 0; k < nm; ++k) {
    measured.frequency_hz(static_cast<Eigen::Index>(k)) = m.scatter[k].linear_frequency_hz.mean;
    measured.labels.push_back(c.modes[k].name);
    for (size_t h = 0; h < hits.size(); ++h) {
      if (m.flagged[h] && c.scatter.exclude_outliers) continue;
      const std::complex<double> r = hits[h].linear[k][m.reference[k]].amplitude;
      if (std::abs(r) == 0) continue;
      for (size_t i = 0; i < nc; ++i)
        measured.shapes(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) +=
            hits[h].linear[k][i].amplitude / std::abs(r);
    }
  }
  return measured;
}

}  // namespace

std::string reference_hint(const Campaign& c, const std::vector<HitData>& hits, size_t k) {
  const size_t nc = c.channels.size();
  std::vector<int> with(nc, 0);
  for (const HitData& h : hits)
    for (size_t i = 0; i < nc && k < h.curves.size() && i < h.curves[k].size(); ++i)
      if (h.curves[k][i].amplitude.size() > 0) ++with[i];
  std::vector<size_t> order;
  for (size_t i = 0; i < nc; ++i) {
    if (c.channels[i].name == c.modes[k].reference && with[i] > 0) return "";
    if (with[i] > 0) order.push_back(i);
  }
  if (order.empty()) return "";
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return with[a] > with[b]; });
  std::string others;
  for (size_t j = 1; j < order.size(); ++j)
    others +=
        fmt::format("{}{} in {}", j == 1 ? " (" : ", ", c.channels[order[j]].name, with[order[j]]);
  if (!others.empty()) others += ")";
  return fmt::format(
      "channel {} gives one in {} of {} hits{}: give reference = \"{}\" in [[mode]] (the "
      "reference defaults to the first channel)",
      c.channels[order[0]].name, with[order[0]], hits.size(), others, c.channels[order[0]].name);
}

MeasuredSide summarise_measured(const Campaign& c, const std::vector<HitData>& hits,
                                const fs::path& dir,
                                const std::function<void(const std::string&)>& progress) {
  const size_t nm = c.modes.size(), nc = c.channels.size();
  MeasuredSide m;
  m.reference.assign(nm, 0);
  m.curves.resize(nm);
  m.point_std.resize(nm);
  m.spans.resize(nm);
  m.scatter.resize(nm);
  m.flagged.assign(hits.size(), false);
  m.reference_hint.resize(nm);
  fs::create_directories(dir);
  for (size_t k = 0; k < nm; ++k) {
    for (size_t i = 0; i < nc; ++i)
      if (c.channels[i].name == c.modes[k].reference) m.reference[k] = static_cast<int>(i);
    for (const HitData& h : hits) {
      const LinearEntry& le = h.linear[k][m.reference[k]];
      m.spans[k].push_back(
          {h.stem, h.group, le.ok, le.span_start_s, le.span_end_s, le.decades, le.reason});
      const Curve& cv = h.curves[k][m.reference[k]];
      if (cv.amplitude.size() == 0) continue;
      m.curves[k].push_back(cv);
      m.point_std[k].push_back(h.point_std[k][m.reference[k]]);
    }
    if (m.curves[k].empty()) m.reference_hint[k] = reference_hint(c, hits, k);
    m.scatter[k] = summarize_scatter(m.curves[k], c.scatter);
    for (const HitDeviation& d : m.scatter[k].hits) {
      if (!d.outlier) continue;
      for (size_t h = 0; h < hits.size(); ++h)
        if (hits[h].stem == d.id) m.flagged[h] = true;
    }
    const fs::path base = dir / fmt::format("mode{}", k + 1);
    write_scatter_bins_csv(base.string() + ".bins.csv", m.scatter[k]);
    write_scatter_hits_csv(base.string() + ".hits.csv", m.scatter[k]);
    write_scatter_json(base.string() + ".json", c.modes[k].name, m.scatter[k]);
    if (progress) progress(fmt::format("scatter: {}: {}", c.modes[k].name, m.scatter[k].report()));
  }
  m.flagged_hits = static_cast<int>(std::count(m.flagged.begin(), m.flagged.end(), true));
  m.modes = linear_modes(c, hits, m);
  return m;
}

}  // namespace jointlab::campaign
