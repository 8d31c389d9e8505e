#include "jointlab/campaign/backbone_comparison.h"

#include <fmt/format.h>

#include "jointlab/campaign/scatter.h"
#include "jointlab/data/atomic_file.h"

namespace jointlab::campaign {

namespace fs = std::filesystem;

std::string amplitude_axis_label(bool modal, correlate::AmplitudeQuantity quantity) {
  if (modal) return "modal amplitude q [m kg^1/2]";
  switch (quantity) {
    case correlate::AmplitudeQuantity::kDisplacement:
      return "displacement amplitude [m]";
    case correlate::AmplitudeQuantity::kVelocity:
      return "velocity amplitude [m/s]";
    case correlate::AmplitudeQuantity::kAcceleration:
      return "acceleration amplitude [m/s^2]";
  }
  return "amplitude";
}

BackboneFigure comparison_figure(const BackboneComparison& c) {
  BackboneFigure f;
  f.title = c.title;
  f.amplitude_label = c.amplitude_label;
  for (size_t i = 0; i < c.measured.size(); ++i) {
    const correlate::MeasuredBackbone& b = c.measured[i];
    Curve cv;
    cv.id = b.source.empty() ? fmt::format("curve {}", i + 1) : fs::path(b.source).stem().string();
    cv.amplitude = b.amplitude;
    cv.frequency_hz = b.frequency_hz;
    cv.damping = b.damping_ratio;
    cv.time_s = Eigen::VectorXd::Zero(b.amplitude.size());
    f.hits.push_back(std::move(cv));
  }
  // The curves the fit used (the hits its scatter summary flagged are already left out): a
  // second screen of them drew a hit as "flagged" that the fit had used. The 0.4 m beam's mode
  // 1, after the slip screen, kept 6 curves; the figure showed "hits (5)" and "flagged hit (1)"
  // with the mean over five, and the report named no hit left out.
  ScatterOptions all;
  all.exclude_outliers = false;
  if (!f.hits.empty()) f.summary = summarize_scatter(f.hits, all);
  for (HitDeviation& h : f.summary.hits) h.outlier = false;
  f.model = c.models;
  return f;
}

void plot_backbone_comparison(const BackboneComparison& c, const fs::path& figure,
                              const fs::path& csv) {
  const BackboneFigure f = comparison_figure(c);
  if (!csv.empty()) {
    std::string t = "model,amplitude,frequency_hz,damping_ratio\n";
    for (const ModelCurve& m : c.models) {
      std::string label = m.label;
      if (label.find_first_of(",\"") != std::string::npos) {
        std::string q = "\"";
        for (char ch : label) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
        label = q + "\"";
      }
      for (Eigen::Index i = 0; i < m.amplitude.size(); ++i) {
        t += fmt::format("{},{:.10g},{:.10g},{:.10g}\n", label, m.amplitude(i), m.frequency_hz(i),
                         m.damping(i));
      }
    }
    data::write_file_atomically(csv, t);
  }
  plot_backbones(f, figure);
}

}  // namespace jointlab::campaign
