#include "jointlab/campaign/steps/campaign_figures.h"

#include <algorithm>

#include <fmt/format.h>

#include "jointlab/campaign/figures.h"
#include "jointlab/campaign/steps/iwan_step.h"
#include "jointlab/core/error.h"
#include "jointlab/correlate/mac.h"
#include "jointlab/data/read_record.h"
#include "jointlab/signal/spectrum.h"

namespace jointlab::campaign {

namespace fs = std::filesystem;

namespace {

ReportFigure backbone_figure(const Campaign& c, const MeasuredSide& measured,
                             const ModelResults* model, size_t k, const fs::path& dir) {
  BackboneFigure bf;
  bf.title = fmt::format("{} ({:g}-{:g} Hz band), channel {}", c.modes[k].name, c.modes[k].band.lo,
                         c.modes[k].band.hi, c.modes[k].reference);
  bf.amplitude_label =
      fmt::format("{} amplitude [{}]", quantity_name(c.amplitude), si_unit(c.amplitude));
  bf.hits = measured.curves[k];
  bf.summary = measured.scatter[k];
  if (model && model->start.curves[k].amplitude.size() > 1)
    bf.model.push_back(model->start.curves[k]);
  if (model && model->have_updated && model->after.curves[k].amplitude.size() > 1)
    bf.model.push_back(model->after.curves[k]);
  if (!c.modes[k].stepped_sine.empty()) {
    const ModeBackbones sine = stepped_sine_backbones(c, k, measured.reference[k]);
    for (size_t i = 0; i < sine.curves.size(); ++i) {
      const Curve& cv = sine.curves[i];
      const std::string label = sine.curves.size() == 1 ? "stepped sine" : "sine " + cv.id;
      bf.stepped_sine.push_back({label, cv.amplitude, cv.frequency_hz, cv.damping,
                                 sine.frequency_std_hz[i], sine.damping_std[i]});
    }
  }
  const fs::path p = dir / fmt::format("backbone_mode{}.png", k + 1);
  plot_backbones(bf, p);
  const bool curve = !bf.model.empty();
  return {fmt::format("{}: natural frequency and damping ratio versus {} "
                      "amplitude; every hit faint, the mean over hits per "
                      "bin with its {:g} % confidence interval{}{}{}.",
                      c.modes[k].name, quantity_name(c.amplitude), 100 * c.scatter.confidence,
                      bf.stepped_sine.empty()
                          ? ""
                          : ", the stepped-sine points with their uncertainty bars (as written "
                            "by stepped-sine: k sigma)",
                      curve ? ", and the model's QSMA curve" : "",
                      curve && c.iwan_update.enabled && c.modes[k].model_mode > 0 &&
                              !c.iwan_update.fits(c.modes[k].name)
                          ? " (a mode the Iwan update does not fit, [update.iwan] modes; its "
                            "backbone cost is listed with the update)"
                          : ""),
          p};
}

// The hit whose spectrum is shown: the first of the last group (the strongest level, by
// convention) that is not left out, else of the group before, and so on; empty when none.
fs::path spectrum_hit(const Campaign& c, const std::vector<FailedHit>& left_out) {
  for (auto g = c.groups.rbegin(); g != c.groups.rend(); ++g)
    for (const fs::path& f : g->files)
      if (std::none_of(left_out.begin(), left_out.end(),
                       [&](const FailedHit& h) { return h.file == f; }))
        return f;
  return {};
}

// Spectrum of the hit `f`.
ReportFigure spectrum_figure(const Campaign& c, const fs::path& f, const fs::path& dir) {
  const data::Record rec = data::read_record(f);
  signal::FftCache cache;
  SpectrumFigure sf;
  sf.title = fmt::format("spectrum of {}", f.filename().string());
  for (const CampaignChannel& ch : c.channels) {
    const data::Channel* rc = rec.find(ch.name);
    if (!rc) continue;  // a channel this hit lacks: its reason is in the hit's rows
    const signal::AmplitudeSpectrum s = signal::amplitude_spectrum(rc->samples, rec.fs, cache);
    sf.frequency_hz = s.frequency_hz;
    sf.spectra.push_back(s.amplitude);
    sf.channel_names.push_back(ch.name);
    const std::optional<Quantity> q = rc->quantity ? rc->quantity : c.quantity;
    sf.amplitude_label =
        q ? fmt::format("{} amplitude [{}]", quantity_name(*q), si_unit(*q)) : "amplitude";
  }
  double fmax = 0;
  for (const CampaignMode& m : c.modes) {
    sf.bands.push_back({m.name, m.band.lo, m.band.hi});
    fmax = std::max(fmax, m.band.hi);
  }
  sf.max_frequency_hz = std::min(rec.fs / 2, 1.5 * fmax);
  const fs::path p = dir / "spectrum.png";
  plot_spectrum(sf, p);
  return {"Amplitude spectrum (Hann window) of one hit with the analysis bands.", p};
}

// The MAC of the measured shapes against the (updated) model, and the frequency errors.
std::vector<ReportFigure> model_figures(const Campaign& c, const MeasuredSide& measured,
                                        const ModelResults& model, const fs::path& dir) {
  std::vector<ReportFigure> figures;
  const bool have_updated = model.have_updated;
  const ModelSide& side = have_updated ? model.after : model.start;
  // Modes without a measured shape (no backbone in any hit) have no row.
  std::vector<Eigen::Index> with_data;
  std::vector<std::string> rows, cols;
  for (size_t k = 0; k < c.modes.size(); ++k) {
    if (measured.modes.shapes.col(static_cast<Eigen::Index>(k)).norm() == 0) continue;
    with_data.push_back(static_cast<Eigen::Index>(k));
    rows.push_back(c.modes[k].name);
  }
  if (with_data.empty()) return figures;
  const Eigen::MatrixXcd shapes = measured.modes.shapes(Eigen::all, with_data);
  const Eigen::MatrixXd mm = correlate::mac_matrix(shapes, side.sensor_shapes);
  for (size_t j = 0; j < side.shape_hz.size(); ++j)
    cols.push_back(fmt::format("{} ({:.0f} Hz)", j + 1, side.shape_hz[j]));
  const fs::path p = dir / "mac.png";
  plot_mac(
      mm, rows, cols,
      fmt::format("MAC, measured shapes versus {} model", have_updated ? "updated" : "starting"),
      p);
  figures.push_back({fmt::format("MAC of the measured operating shapes ({} channels) and the "
                                 "model's elastic modes at the sensors.",
                                 c.channels.size()),
                     p});
  std::vector<std::string> labels;
  ErrorSeries before{"starting model", {}}, after{"updated model", {}};
  for (size_t k = 0; k < c.modes.size(); ++k) {
    if (model.start.frequency_hz[k] <= 0 || measured.scatter[k].linear_count == 0) continue;
    const double fe = measured.scatter[k].linear_frequency_hz.mean;
    labels.push_back(c.modes[k].name);
    before.percent.push_back(100 * (model.start.frequency_hz[k] - fe) / fe);
    if (have_updated) after.percent.push_back(100 * (model.after.frequency_hz[k] - fe) / fe);
  }
  if (!labels.empty()) {
    std::vector<ErrorSeries> series{before};
    if (have_updated) series.push_back(after);
    const fs::path pe = dir / "frequency_errors.png";
    plot_frequency_errors(labels, series, "linear frequency errors, model versus test", pe);
    figures.push_back({"Linear (low-amplitude) frequency error of the model per mode.", pe});
  }
  return figures;
}

}  // namespace

CampaignFigures draw_figures(const Campaign& c, const MeasuredSide& measured,
                             const ModelResults* model, const fs::path& dir,
                             const std::vector<FailedHit>& left_out) {
  fs::create_directories(dir);
  CampaignFigures f;
  for (size_t k = 0; k < c.modes.size(); ++k) {
    // No backbone: no figure (an empty plot would show a meaningless axis).
    f.backbone.push_back(measured.curves[k].empty() ? ReportFigure{}
                                                    : backbone_figure(c, measured, model, k, dir));
  }
  if (const fs::path hit = spectrum_hit(c, left_out); !hit.empty())
    f.spectrum = spectrum_figure(c, hit, dir);
  if (model) f.model = model_figures(c, measured, *model, dir);
  return f;
}

}  // namespace jointlab::campaign
