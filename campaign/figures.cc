#include "jointlab/campaign/figures.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include <fmt/format.h>
#include <plplot.h>

#include "jointlab/campaign/plot_layout.h"
#include "jointlab/core/error.h"
#include "jointlab/data/atomic_file.h"

namespace jointlab::campaign {

namespace {

namespace fs = std::filesystem;

// Colour map 0 entries set by every figure (0 is the white background).
enum Colour : PLINT {
  kWhite = 0,
  kBlack = 1,
  kHit = 2,       // faint grey
  kMean = 3,      // blue
  kBand = 4,      // translucent blue
  kModel1 = 5,    // red
  kModel2 = 6,    // green
  kModel3 = 7,    // purple
  kFlagged = 8,   // faint orange
  kGrid = 9,      // light grey
  kCell = 10,     // reset per MAC cell
  kChannel2 = 11  // dark orange
};

// True when `file` ends as a complete file of its format does (PNG's IEND chunk, SVG's closing
// tag, PDF's %%EOF): the cairo drivers report no write errors, a full disk truncates the file.
bool figure_complete(const fs::path& file, const std::string& ext) {
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  const std::streamoff size = in ? static_cast<std::streamoff>(in.tellg()) : 0;
  if (size <= 0) return false;
  const std::streamoff n = std::min<std::streamoff>(size, 1024);
  std::string tail(static_cast<size_t>(n), '\0');
  in.seekg(size - n);
  if (!in.read(tail.data(), n)) return false;
  if (ext == ".png") {
    static const std::string iend("\0\0\0\0IEND\xae\x42\x60\x82", 12);
    return tail.size() >= iend.size() && tail.compare(tail.size() - 12, 12, iend) == 0;
  }
  if (ext == ".svg") return tail.find("</svg>") != std::string::npos;
  return tail.find("%%EOF") != std::string::npos;
}

// One PLplot stream on a temporary file, renamed into place by finish().
class Plot {
 public:
  Plot(const fs::path& file, const FigureSize& size) : file_(file) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    const char* device = ext == ".png"   ? "pngcairo"
                         : ext == ".svg" ? "svgcairo"
                         : ext == ".pdf" ? "pdfcairo"
                                         : nullptr;
    if (!device)
      throw InputError(fmt::format("{}: figure files end in .png, .svg or .pdf", file.string()));
    if (size.width < 100 || size.height < 100 || size.width > 10000 || size.height > 10000)
      throw InputError(fmt::format("{}: figure size {}x{} out of range (100 to 10000)",
                                   file.string(), size.width, size.height));
    const fs::path dir = file.has_parent_path() ? file.parent_path() : fs::path(".");
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir))
      throw InputError(fmt::format("{}: cannot create the directory", dir.string()));
    const std::string prefix = fmt::format(".{}.tmp-", file.filename().string());
    data::remove_stale_temporaries(dir, prefix);
    tmp_ = data::temporary_name(dir, prefix, ext);
    claim_ = data::TemporaryClaim(tmp_);
    ext_ = ext;
    plgstrm(&previous_);
    plmkstrm(&stream_);
    plsdev(device);
    plsfnam(tmp_.c_str());
    plspage(0, 0, size.width, size.height, 0, 0);
    plscolbg(255, 255, 255);
    plscmap0n(16);
    plinit();
    plscol0a(kBlack, 0, 0, 0, 1.0);
    plscol0a(kHit, 90, 90, 90, 0.35);
    plscol0a(kMean, 20, 60, 200, 1.0);
    plscol0a(kBand, 60, 120, 230, 0.30);
    plscol0a(kModel1, 210, 30, 30, 1.0);
    plscol0a(kModel2, 20, 150, 60, 1.0);
    plscol0a(kModel3, 140, 40, 170, 1.0);
    plscol0a(kFlagged, 240, 130, 0, 0.8);
    plscol0a(kGrid, 200, 200, 200, 1.0);
    plscol0a(kChannel2, 220, 110, 0, 0.9);
    pladv(0);
    plschr(0, 1.15);
  }
  ~Plot() {
    if (!ended_) {
      plend1();
      plsstrm(previous_);
    }
    if (!finished_) {
      std::error_code ec;
      fs::remove(tmp_, ec);
    }
  }
  Plot(const Plot&) = delete;
  Plot& operator=(const Plot&) = delete;

  // Closes the stream (the driver writes the file) and renames it into place.
  void finish() {
    plend1();
    plsstrm(previous_);
    ended_ = true;
    std::error_code ec;
    if (!fs::exists(tmp_))
      throw InputError(fmt::format("{}: the plot driver wrote no file", file_.string()));
    if (!figure_complete(tmp_, ext_))
      throw InputError(
          fmt::format("{}: the figure was written incomplete (disk full?)", file_.string()));
    fs::rename(tmp_, file_, ec);
    if (ec) throw InputError(fmt::format("{}: cannot write: {}", file_.string(), ec.message()));
    finished_ = true;
  }

 private:
  fs::path file_, tmp_;
  std::string ext_;
  data::TemporaryClaim claim_;
  PLINT previous_ = 0, stream_ = 0;
  bool ended_ = false, finished_ = false;
};

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return !(hi >= lo); }
  // Widened by `margin` of its width (or +-`pad` when flat).
  Range padded(double margin, double pad) const {
    Range r = *this;
    if (empty()) return {0, 1};
    const double w = hi - lo;
    const double m = w > 0 ? margin * w : pad;
    r.lo -= m;
    r.hi += m;
    return r;
  }
};

// x and y of the points with x inside [xlo, xhi] (log10 of each when asked; non-positive
// values are left out of a log axis).
void points(const Eigen::VectorXd& x, const Eigen::VectorXd& y, bool logx, bool logy,
            std::vector<PLFLT>& px, std::vector<PLFLT>& py, double xlo = -1e300,
            double xhi = 1e300) {
  px.clear();
  py.clear();
  for (Eigen::Index i = 0; i < std::min(x.size(), y.size()); ++i) {
    if ((logx && !(x(i) > 0)) || (logy && !(y(i) > 0))) continue;
    const double u = logx ? std::log10(x(i)) : x(i);
    const double v = logy ? std::log10(y(i)) : y(i);
    if (!std::isfinite(u) || !std::isfinite(v) || u < xlo || u > xhi) continue;
    px.push_back(u);
    py.push_back(v);
  }
}

void line(const std::vector<PLFLT>& x, const std::vector<PLFLT>& y, PLINT colour, double width,
          PLINT style = 1) {
  if (x.size() < 2) return;
  plcol0(colour);
  plwidth(width);
  pllsty(style);
  plline(static_cast<PLINT>(x.size()), x.data(), y.data());
  pllsty(1);
  plwidth(1.0);
}

// A legend in the upper right (or lower right) inside the current viewport.
struct LegendEntry {
  std::string text;
  PLINT colour;
  bool box = false;  // a filled box instead of a line
  double width = 2.0;
  PLINT style = 1;
};
void legend(const std::vector<LegendEntry>& entries, PLINT position, bool outside = false) {
  if (entries.empty()) return;
  const size_t n = entries.size();
  std::vector<PLINT> opt(n), text_colors(n, kBlack), box_colors(n), box_patterns(n, 0),
      line_colors(n), line_styles(n), symbol_colors(n, kBlack), symbol_numbers(n, 0);
  std::vector<PLFLT> box_scales(n, 0.8), box_line_widths(n, 1.0), line_widths(n),
      symbol_scales(n, 1.0);
  std::vector<const char*> text(n), symbols(n, "");
  for (size_t i = 0; i < n; ++i) {
    opt[i] = entries[i].box ? PL_LEGEND_COLOR_BOX : PL_LEGEND_LINE;
    text[i] = entries[i].text.c_str();
    box_colors[i] = line_colors[i] = entries[i].colour;
    line_styles[i] = entries[i].style;
    line_widths[i] = entries[i].width;
  }
  PLFLT w = 0, h = 0;
  plschr(0, 0.95);
  pllegend(&w, &h, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
           position | (outside ? PL_POSITION_OUTSIDE : PL_POSITION_INSIDE) | PL_POSITION_VIEWPORT,
           outside ? 0.02 : 0.015, 0.02, outside ? 0.08 : 0.07, kWhite, kBlack, 1, 0, 0,
           static_cast<PLINT>(n), opt.data(), 0.8, 0.9, 1.8, 0.0, text_colors.data(), text.data(),
           box_colors.data(), box_patterns.data(), box_scales.data(), box_line_widths.data(),
           line_colors.data(), line_styles.data(), line_widths.data(), symbol_colors.data(),
           symbol_scales.data(), symbol_numbers.data(), symbols.data());
  plschr(0, 1.15);
}

void axes(const char* xopt, const char* yopt) {
  plcol0(kBlack);
  plwidth(1.0);
  plbox(xopt, 0.0, 0, yopt, 0.0, 0);
}

// Numeric labels of a log10 y axis over [lo, hi] (PLplot labels only whole decades, so a
// range under a decade would show none), kept min_gap of the axis apart (plot_layout.h).
void log_y_labels(double lo, double hi, double min_gap) {
  plcol0(kBlack);
  for (const double v : log_label_values(lo, hi, min_gap))
    plmtex("lv", 0.6, (std::log10(v) - lo) / (hi - lo), 1.0, fmt::format("{:g}", v).c_str());
}

// Grid lines under the data.
void grid(const char* xopt, const char* yopt) {
  plcol0(kGrid);
  pllsty(2);
  plbox(xopt, 0.0, 0, yopt, 0.0, 0);
  pllsty(1);
}

// Amplitude window of a backbone figure (log10): the hits, bins and stepped-sine points
// (else the model curves), widened by a quarter decade each side.
Range amplitude_window(const BackboneFigure& figure) {
  Range ax;
  for (const Curve& c : figure.hits) {
    for (Eigen::Index i = 0; i < c.amplitude.size(); ++i)
      if (c.amplitude(i) > 0) ax.add(std::log10(c.amplitude(i)));
  }
  for (const ScatterBin& b : figure.summary.bins) {
    ax.add(std::log10(b.amplitude_low));
    ax.add(std::log10(b.amplitude_high));
  }
  for (const SinePoints& sp : figure.stepped_sine) {
    for (Eigen::Index i = 0; i < sp.amplitude.size(); ++i)
      if (sp.amplitude(i) > 0) ax.add(std::log10(sp.amplitude(i)));
  }
  if (ax.empty()) {
    for (const ModelCurve& m : figure.model)
      for (Eigen::Index i = 0; i < m.amplitude.size(); ++i)
        if (m.amplitude(i) > 0) ax.add(std::log10(m.amplitude(i)));
  }
  if (ax.empty()) ax = {-3, 0};
  ax = ax.padded(0.0, 0.5);
  ax.lo -= 0.25;
  ax.hi += 0.25;
  return ax;
}

// The frequency [Hz] and log10 damping ranges: every curve as drawn (cut at the amplitude
// window), bin and point lies inside them.
std::pair<Range, Range> value_ranges(const BackboneFigure& figure, const Range& ax) {
  Range fy, zy;
  std::vector<PLFLT> px, py;
  const auto add_curve = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& v, bool logy,
                             Range& r) {
    points(a, v, true, logy, px, py);
    clip_x(px, py, ax.lo, ax.hi);
    for (double u : py) r.add(u);
  };
  for (const Curve& c : figure.hits) {
    add_curve(c.amplitude, c.frequency_hz, false, fy);
    add_curve(c.amplitude, c.damping, true, zy);
  }
  for (const ModelCurve& m : figure.model) {
    add_curve(m.amplitude, m.frequency_hz, false, fy);
    add_curve(m.amplitude, m.damping, true, zy);
  }
  for (const ScatterBin& b : figure.summary.bins) {
    fy.add(b.frequency_hz.ci_low);
    fy.add(b.frequency_hz.ci_high);
    if (b.damping.ci_low > 0) zy.add(std::log10(b.damping.ci_low));
    if (b.damping.ci_high > 0) zy.add(std::log10(b.damping.ci_high));
  }
  for (const SinePoints& sp : figure.stepped_sine) {
    points(sp.amplitude, sp.frequency_hz, true, false, px, py, ax.lo, ax.hi);
    for (double v : py) fy.add(v);
    points(sp.amplitude, sp.damping, true, true, px, py, ax.lo, ax.hi);
    for (double v : py) zy.add(v);
  }
  return {fy.padded(0.08, 0.5), zy.padded(0.08, 0.2)};
}

// Mean and confidence band of one quantity (damping or frequency) from the scatter bins.
void draw_bins(const std::vector<ScatterBin>& bins, bool damping, bool logy) {
  if (bins.empty()) return;
  std::vector<PLFLT> x, mean, bx, by;
  for (const ScatterBin& b : bins) {
    const Statistic& s = damping ? b.damping : b.frequency_hz;
    const double m = s.mean, lo = s.ci_low, hi = s.ci_high;
    if (logy && !(m > 0 && lo > 0)) continue;
    x.push_back(std::log10(b.amplitude_center));
    mean.push_back(logy ? std::log10(m) : m);
    bx.push_back(x.back());
    by.push_back(logy ? std::log10(hi) : hi);
  }
  for (size_t k = bins.size(); k-- > 0;) {
    const Statistic& s = damping ? bins[k].damping : bins[k].frequency_hz;
    if (logy && !(s.mean > 0 && s.ci_low > 0)) continue;
    bx.push_back(std::log10(bins[k].amplitude_center));
    by.push_back(logy ? std::log10(s.ci_low) : s.ci_low);
  }
  if (bx.size() >= 3) {
    plcol0(kBand);
    plfill(static_cast<PLINT>(bx.size()), bx.data(), by.data());
  }
  line(x, mean, kMean, 2.5);
  plcol0(kMean);
  plschr(0, 0.9);
  plpoin(static_cast<PLINT>(x.size()), x.data(), mean.data(), 17);
  plschr(0, 1.15);
}

// Stepped-sine points: a marker and its uncertainty bar (clipped to the panel's y range).
void draw_stepped_sine(const std::vector<SinePoints>& stepped_sine, bool damping, bool logy,
                       const Range& y) {
  for (const SinePoints& sp : stepped_sine) {
    std::vector<PLFLT> x, v, lo, hi;
    for (Eigen::Index i = 0; i < sp.amplitude.size(); ++i) {
      const double m = damping ? sp.damping(i) : sp.frequency_hz(i);
      const double u = damping ? sp.damping_std(i) : sp.frequency_std_hz(i);
      if (!(sp.amplitude(i) > 0) || (logy && !(m > 0))) continue;
      x.push_back(std::log10(sp.amplitude(i)));
      v.push_back(logy ? std::log10(m) : m);
      const double l = logy ? std::log10(std::max(m - u, 0.01 * m)) : m - u;
      lo.push_back(std::max(l, y.lo));
      hi.push_back(std::min(logy ? std::log10(m + u) : m + u, y.hi));
    }
    if (x.empty()) continue;
    plcol0(kChannel2);
    plwidth(1.5);
    plerry(static_cast<PLINT>(x.size()), x.data(), lo.data(), hi.data());
    plschr(0, 1.0);
    plpoin(static_cast<PLINT>(x.size()), x.data(), v.data(), 22);
    plschr(0, 1.15);
  }
}

constexpr PLINT kModelColours[3] = {kModel1, kModel2, kModel3};

// One panel (frequency or damping against amplitude) of a backbone figure.
void backbone_panel(const BackboneFigure& figure, const std::vector<bool>& flagged, const Range& ax,
                    const Range& y, bool damping) {
  const bool logy = damping;
  std::vector<PLFLT> px, py;
  plwind(ax.lo, ax.hi, y.lo, y.hi);
  grid("gl", logy ? "gl" : "g");
  for (size_t i = 0; i < figure.hits.size(); ++i) {
    const Curve& c = figure.hits[i];
    points(c.amplitude, damping ? c.damping : c.frequency_hz, true, logy, px, py);
    clip_x(px, py, ax.lo, ax.hi);
    line(px, py, flagged[i] ? kFlagged : kHit, 1.2, flagged[i] ? 2 : 1);
  }
  draw_bins(figure.summary.bins, damping, logy);
  for (size_t m = 0; m < figure.model.size(); ++m) {
    const ModelCurve& mc = figure.model[m];
    points(mc.amplitude, damping ? mc.damping : mc.frequency_hz, true, logy, px, py);
    clip_x(px, py, ax.lo, ax.hi);
    line(px, py, kModelColours[m % 3], 2.2, m < 3 ? 1 : 3);
  }
  draw_stepped_sine(figure.stepped_sine, damping, logy, y);
  axes(damping ? "bcnstl" : "bcstl", logy ? "bcstl" : "bcnstv");
  if (logy) log_y_labels(y.lo, y.hi, 0.1);
}

// The legend entries of a backbone figure.
std::vector<LegendEntry> backbone_legend(const BackboneFigure& figure,
                                         const std::vector<bool>& flagged) {
  std::vector<LegendEntry> entries;
  int n_flagged = static_cast<int>(std::count(flagged.begin(), flagged.end(), true));
  entries.push_back(
      {fmt::format("hits ({})", figure.hits.size() - static_cast<size_t>(n_flagged)), kHit});
  if (n_flagged > 0)
    entries.push_back({fmt::format("flagged hit ({})", n_flagged), kFlagged, false, 2.0, 2});
  if (!figure.summary.bins.empty()) {
    entries.push_back({"mean over hits", kMean, false, 2.5});
    entries.push_back(
        {fmt::format("{:g} % CI of the mean", 100 * figure.summary.options.confidence), kBand,
         true});
  }
  for (const SinePoints& sp : figure.stepped_sine) entries.push_back({sp.label, kChannel2, false});
  for (size_t m = 0; m < figure.model.size(); ++m)
    entries.push_back({figure.model[m].label, kModelColours[m % 3], false, 2.2, m < 3 ? 1 : 3});
  return entries;
}

}  // namespace

void plot_backbones(const BackboneFigure& figure, const fs::path& file, const FigureSize& size) {
  const Range ax = amplitude_window(figure);
  const auto [fy, zy] = value_ranges(figure, ax);
  std::vector<bool> flagged(figure.hits.size(), false);
  for (size_t i = 0; i < figure.hits.size(); ++i) {
    for (const HitDeviation& h : figure.summary.hits)
      if (h.id == figure.hits[i].id && h.outlier) flagged[i] = true;
  }

  Plot plot(file, size);
  plvpor(0.15, 0.67, 0.53, 0.92);
  backbone_panel(figure, flagged, ax, fy, false);
  plcol0(kBlack);
  plmtex("l", 6.2, 0.5, 0.5, "frequency [Hz]");
  plmtex("t", 1.2, 0.5, 0.5, figure.title.c_str());

  plvpor(0.15, 0.67, 0.14, 0.49);
  backbone_panel(figure, flagged, ax, zy, true);
  plcol0(kBlack);
  plmtex("l", 6.2, 0.5, 0.5, "damping ratio");
  plmtex("b", 3.4, 0.5, 0.5, figure.amplitude_label.c_str());
  // The legend sits to the right of the panels, clear of the data.
  legend(backbone_legend(figure, flagged), PL_POSITION_RIGHT | PL_POSITION_TOP, true);
  plot.finish();
}

void plot_spectrum(const SpectrumFigure& figure, const fs::path& file, const FigureSize& size) {
  if (figure.spectra.size() != figure.channel_names.size())
    throw InputError(fmt::format("{}: {} spectra but {} channel names", file.string(),
                                 figure.spectra.size(), figure.channel_names.size()));
  const double fmax = figure.max_frequency_hz > 0
                          ? figure.max_frequency_hz
                          : (figure.frequency_hz.size() ? figure.frequency_hz.maxCoeff() : 1.0);
  Range y;
  std::vector<PLFLT> px, py;
  for (const Eigen::VectorXd& s : figure.spectra) {
    points(figure.frequency_hz, s, false, true, px, py, 0.0, fmax);
    for (double v : py) y.add(v);
  }
  if (y.empty()) y = {-6, 0};
  // Show at most eight decades below the highest peak.
  y.lo = std::max(y.lo, y.hi - 8.0);
  y = y.padded(0.05, 0.5);
  y.hi += 0.4;  // room for the band labels

  Plot plot(file, size);
  plvpor(0.13, 0.96, 0.13, 0.90);
  plwind(0.0, fmax, y.lo, y.hi);
  grid("g", "gl");
  for (const LabelledBand& b : figure.bands) {
    const PLFLT bx[4] = {b.lo_hz, b.hi_hz, b.hi_hz, b.lo_hz};
    const PLFLT by[4] = {y.lo, y.lo, y.hi, y.hi};
    plcol0(kBand);
    plfill(4, bx, by);
  }
  const PLINT colours[4] = {kMean, kChannel2, kModel2, kModel3};
  std::vector<LegendEntry> entries;
  for (size_t c = 0; c < figure.spectra.size(); ++c) {
    points(figure.frequency_hz, figure.spectra[c], false, true, px, py, 0.0, fmax);
    line(px, py, colours[c % 4], 1.2);
    entries.push_back({figure.channel_names[c], colours[c % 4]});
  }
  entries.push_back({"analysis bands", kBand, true});
  plcol0(kBlack);
  plschr(0, 0.9);
  for (const LabelledBand& b : figure.bands)
    plptex(0.5 * (b.lo_hz + b.hi_hz), y.hi - 0.2, 1.0, 0.0, 0.5, b.label.c_str());
  plschr(0, 1.15);
  axes("bcnst", "bcstl");
  log_y_labels(y.lo, y.hi, 0.05);
  plmtex("b", 3.2, 0.5, 0.5, "frequency [Hz]");
  plmtex("l", 5.6, 0.5, 0.5, figure.amplitude_label.c_str());
  plmtex("t", 1.2, 0.5, 0.5, figure.title.c_str());
  legend(entries, PL_POSITION_RIGHT | PL_POSITION_TOP);
  plot.finish();
}

void plot_mac(const Eigen::Ref<const Eigen::MatrixXd>& mac, const std::vector<std::string>& rows,
              const std::vector<std::string>& columns, const std::string& title,
              const fs::path& file, const FigureSize& size, const std::vector<MacCell>& marked) {
  const Eigen::Index nr = mac.rows(), nc = mac.cols();
  if (nr == 0 || nc == 0 || static_cast<Eigen::Index>(rows.size()) != nr ||
      static_cast<Eigen::Index>(columns.size()) != nc)
    throw InputError(fmt::format("{}: a {}x{} MAC matrix needs {} row and {} column labels",
                                 file.string(), nr, nc, nr, nc));
  // Room on the left for the longest row label ("test 1 (127.9 Hz)").
  size_t longest = 0;
  for (const std::string& r : rows) longest = std::max(longest, r.size());
  const double left = std::clamp(0.05 + 0.012 * static_cast<double>(longest), 0.22, 0.40);
  Plot plot(file, size);
  plvpor(left, 0.92, 0.16, 0.86);
  plwind(0, static_cast<PLFLT>(nc), 0, static_cast<PLFLT>(nr));
  plschr(0, nr > 8 || nc > 8 ? 0.75 : 1.0);
  for (Eigen::Index i = 0; i < nr; ++i) {
    for (Eigen::Index j = 0; j < nc; ++j) {
      const double v = std::clamp(mac(i, j), 0.0, 1.0);
      const int g = static_cast<int>(std::lround(255 * (1.0 - 0.85 * v)));
      plscol0a(kCell, g, g, g, 1.0);
      plcol0(kCell);
      const PLFLT y0 = static_cast<PLFLT>(nr - 1 - i), x0 = static_cast<PLFLT>(j);
      const PLFLT bx[4] = {x0, x0 + 1, x0 + 1, x0};
      const PLFLT by[4] = {y0, y0, y0 + 1, y0 + 1};
      plfill(4, bx, by);
      plcol0(v > 0.55 ? kWhite : kBlack);
      plptex(x0 + 0.5, y0 + 0.5, 1.0, 0.0, 0.5, fmt::format("{:.2f}", v).c_str());
    }
  }
  // The pairs: a red frame inside each paired cell.
  for (const auto& [i, j] : marked) {
    if (i < 0 || j < 0 || i >= nr || j >= nc) continue;
    const PLFLT y0 = static_cast<PLFLT>(nr - 1 - i), x0 = static_cast<PLFLT>(j);
    const PLFLT bx[5] = {x0 + 0.04, x0 + 0.96, x0 + 0.96, x0 + 0.04, x0 + 0.04};
    const PLFLT by[5] = {y0 + 0.04, y0 + 0.04, y0 + 0.96, y0 + 0.96, y0 + 0.04};
    plcol0(kModel1);
    plwidth(3.0);
    plline(5, bx, by);
    plwidth(1.0);
  }
  plcol0(kBlack);
  plbox("bc", 1.0, 0, "bc", 1.0, 0);
  // More than five columns: labels on two staggered lines, so that neighbours never overlap.
  const bool stagger = nc > 5;
  for (Eigen::Index j = 0; j < nc; ++j)
    plmtex("b", stagger && j % 2 ? 2.7 : 1.5, (j + 0.5) / static_cast<double>(nc), 0.5,
           columns[j].c_str());
  for (Eigen::Index i = 0; i < nr; ++i)
    plmtex("lv", 1.0, 1.0 - (i + 0.5) / static_cast<double>(nr), 1.0, rows[i].c_str());
  plschr(0, 1.15);
  plmtex("b", stagger ? 4.0 : 3.2, 0.5, 0.5, "model mode");
  plmtex("l", std::max(8.0, 0.45 * static_cast<double>(longest) + 1.5), 0.5, 0.5, "measured mode");
  plmtex("t", 2.4, 0.5, 0.5, title.c_str());
  plschr(0, 0.9);
  plmtex("t", 0.8, 0.5, 0.5,
         marked.empty() ? "MAC = |x^H y|^2 / ((x^H x)(y^H y)), 1 for collinear shapes"
                        : "MAC = |x^H y|^2 / ((x^H x)(y^H y)); pairs framed in red");
  plschr(0, 1.15);
  plot.finish();
}

void plot_frequency_errors(const std::vector<std::string>& modes,
                           const std::vector<ErrorSeries>& series, const std::string& title,
                           const fs::path& file, const FigureSize& size) {
  const size_t nm = modes.size();
  if (nm == 0 || series.empty())
    throw InputError(fmt::format("{}: no modes or no error series to plot", file.string()));
  Range y;
  y.add(0.0);
  for (const ErrorSeries& s : series) {
    if (s.percent.size() != nm)
      throw InputError(fmt::format("{}: series '{}' has {} values for {} modes", file.string(),
                                   s.label, s.percent.size(), nm));
    for (double v : s.percent) y.add(v);
  }
  y = y.padded(0.15, 0.5);
  // Room above the bars for the legend (two lines take about a tenth of the height each).
  y.hi += (0.12 * static_cast<double>(series.size()) + 0.05) * (y.hi - y.lo);
  const PLINT colours[4] = {kModel1, kMean, kModel2, kModel3};
  Plot plot(file, size);
  plvpor(0.13, 0.96, 0.13, 0.90);
  plwind(0, static_cast<PLFLT>(nm), y.lo, y.hi);
  grid("", "g");
  const double group = 0.7, w = group / static_cast<double>(series.size());
  std::vector<LegendEntry> entries;
  plschr(0, 0.8);
  for (size_t s = 0; s < series.size(); ++s) {
    for (size_t m = 0; m < nm; ++m) {
      const double x0 = m + 0.5 - group / 2 + s * w, v = series[s].percent[m];
      const PLFLT bx[4] = {x0, x0 + w * 0.9, x0 + w * 0.9, x0};
      const PLFLT by[4] = {0, 0, v, v};
      plcol0(colours[s % 4]);
      plfill(4, bx, by);
      plcol0(kBlack);
      const double off = 0.03 * (y.hi - y.lo);
      plptex(x0 + 0.45 * w, v >= 0 ? v + off : v - off, 1.0, 0.0, 0.5,
             fmt::format("{:.2f}", v).c_str());
    }
    entries.push_back({series[s].label, colours[s % 4], true});
  }
  plschr(0, 1.15);
  const PLFLT zx[2] = {0, static_cast<PLFLT>(nm)}, zy[2] = {0, 0};
  plcol0(kBlack);
  plline(2, zx, zy);
  axes("bc", "bcnstv");
  for (size_t m = 0; m < nm; ++m)
    plmtex("b", 1.5, (m + 0.5) / static_cast<double>(nm), 0.5, modes[m].c_str());
  plmtex("l", 5.6, 0.5, 0.5, "(model - test) / test [%]");
  plmtex("t", 1.2, 0.5, 0.5, title.c_str());
  legend(entries, PL_POSITION_RIGHT | PL_POSITION_TOP);
  plot.finish();
}

void plot_panels(const std::vector<LinePanel>& panels, const std::string& title,
                 const fs::path& file, const FigureSize& size) {
  if (panels.empty()) throw InputError(fmt::format("{}: no panel to plot", file.string()));
  const int n = static_cast<int>(panels.size());
  const int cols = n > 2 ? 2 : 1, rows = (n + cols - 1) / cols;
  const PLINT colours[6] = {kModel1, kMean, kModel2, kModel3, kChannel2, kBlack};
  const PLINT styles[3] = {1, 2, 3};
  Plot plot(file, size);
  const double top = 0.93, bottom = 0.04, height = (top - bottom) / rows;
  for (int p = 0; p < n; ++p) {
    const LinePanel& panel = panels[static_cast<size_t>(p)];
    const int r = p / cols, c = p % cols;
    const double x0 = cols == 1 ? 0.11 : (c == 0 ? 0.09 : 0.50),
                 x1 = cols == 1 ? 0.76 : (c == 0 ? 0.38 : 0.79);
    const double y1 = top - r * height - 0.04, y0 = top - (r + 1) * height + 0.07;
    auto tx = [&](double v) { return panel.log_x ? (v > 0 ? std::log10(v) : NAN) : v; };
    auto ty = [&](double v) { return panel.log_y ? (v > 0 ? std::log10(v) : NAN) : v; };
    Range xr, yr;
    for (const LineSeries& s : panel.series)
      for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
        if (!s.y[i]) continue;
        const double u = tx(s.x[i]), v = ty(*s.y[i]);
        if (std::isfinite(u) && std::isfinite(v)) xr.add(u), yr.add(v);
      }
    for (double m : panel.marks_x) xr.add(tx(m));
    xr = xr.padded(0.02, 0.5);
    yr = yr.padded(0.08, panel.log_y ? 0.5 : 1.0);
    plvpor(x0, x1, y0, y1);
    plwind(xr.lo, xr.hi, yr.lo, yr.hi);
    // A log y axis is labelled by log_y_labels (PLplot labels every decade, which crowd).
    const std::string xo = panel.log_x ? "bcnstl" : "bcnst", yo = panel.log_y ? "bcstl" : "bcnstv";
    grid(panel.log_x ? "gl" : "g", panel.log_y ? "gl" : "g");
    std::vector<LegendEntry> entries;
    for (size_t k = 0; k < panel.series.size(); ++k) {
      const LineSeries& s = panel.series[k];
      const PLINT colour = colours[k % 6], style = styles[(k / 6) % 3];
      std::vector<PLFLT> px, py;
      auto flush = [&] {
        if (px.size() == 1) {
          plcol0(colour);
          plpoin(1, px.data(), py.data(), 17);
        }
        line(px, py, colour, 2.0, style);
        px.clear();
        py.clear();
      };
      for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
        const double u = tx(s.x[i]), v = s.y[i] ? ty(*s.y[i]) : NAN;
        if (!std::isfinite(u) || !std::isfinite(v)) {
          flush();
          continue;
        }
        px.push_back(u);
        py.push_back(v);
      }
      flush();
      entries.push_back({s.label, colour, false, 2.0, style});
    }
    for (double m : panel.marks_x) {
      const PLFLT mx[2] = {tx(m), tx(m)}, my[2] = {yr.lo, yr.hi};
      if (std::isfinite(mx[0])) line({mx[0], mx[1]}, {my[0], my[1]}, kBlack, 1.5, 2);
    }
    if (!panel.marks_x.empty() && !panel.marks_label.empty())
      entries.push_back({panel.marks_label, kBlack, false, 1.5, 2});
    plschr(0, 0.85);
    axes(xo.c_str(), yo.c_str());
    if (panel.log_y) log_y_labels(yr.lo, yr.hi, 0.07);
    plmtex("b", 3.0, 0.5, 0.5, panel.x_label.c_str());
    plmtex("l", panel.log_y ? 6.4 : 4.6, 0.5, 0.5, panel.y_label.c_str());
    plmtex("t", 0.8, 0.5, 0.5, panel.title.c_str());
    // Two columns share one legend (the same series in every panel), right of the top row.
    if (cols == 1) legend(entries, PL_POSITION_RIGHT | PL_POSITION_TOP, true);
    if (cols == 2 && p == 1) legend(entries, PL_POSITION_RIGHT, true);
    plschr(0, 1.15);
  }
  plvpor(0, 1, 0, 1);
  plwind(0, 1, 0, 1);
  plmtex("t", -1.6, 0.5, 0.5, title.c_str());
  plot.finish();
}

}  // namespace jointlab::campaign
