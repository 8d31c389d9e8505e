#include "jointlab/apps/stepped_sine_figure.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <plplot.h>
#include <unistd.h>

#include "jointlab/core/error.h"

namespace jointlab::apps {

namespace {

struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  void add(double v) {
    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  }
  void pad(double f) {
    const double w = hi > lo ? hi - lo : 1.0;
    lo -= f * w, hi += f * w;
  }
};

// Colour map indices set in plot_sine_figure: 1 black, 2..6 series colours, 7 grey.
const PLINT kSeriesColours[] = {2, 3, 4, 5, 6};
// Damping is drawn in percent on a linear axis.

}  // namespace

void plot_sine_figure(const std::vector<FigureSeries>& series, const std::string& title,
                      const std::string& amplitude_label, const std::filesystem::path& file) {
  const std::string ext = file.extension().string();
  const char* device = ext == ".png"   ? "pngcairo"
                       : ext == ".svg" ? "svgcairo"
                       : ext == ".pdf" ? "pdfcairo"
                                       : nullptr;
  if (!device) {
    throw InputError(
        fmt::format("--figure {}: the extension must be .png, .svg or .pdf", file.string()));
  }
  Range ax, fy, zy;
  for (const FigureSeries& s : series) {
    for (Eigen::Index i = 0; i < s.amplitude.size(); ++i) {
      if (!(s.amplitude(i) > 0) || !(s.damping(i) > 0)) continue;
      ax.add(std::log10(s.amplitude(i)));
      const double ef = s.points ? s.frequency_std_hz(i) : 0.0;
      fy.add(s.frequency_hz(i) - ef);
      fy.add(s.frequency_hz(i) + ef);
      const double ez = s.points ? s.damping_std(i) : 0.0;
      zy.add(100 * (s.damping(i) - ez));
      zy.add(100 * (s.damping(i) + ez));
    }
  }
  if (!(ax.hi >= ax.lo)) throw InputError(fmt::format("{}: nothing to plot", file.string()));
  ax.pad(0.05), fy.pad(0.08), zy.pad(0.08);

  const std::filesystem::path tmp = file.string() + fmt::format(".tmp-{}{}", ::getpid(), ext);
  PLINT previous = 0, stream = 0;
  plgstrm(&previous);
  plmkstrm(&stream);
  plsdev(device);
  plsfnam(tmp.c_str());
  plspage(0, 0, 1000, 760, 0, 0);
  plscol0(0, 255, 255, 255);
  plscol0(1, 0, 0, 0);
  plscol0(2, 214, 39, 40);
  plscol0(3, 31, 119, 180);
  plscol0(4, 44, 160, 44);
  plscol0(5, 148, 103, 189);
  plscol0(6, 255, 127, 14);
  plscol0(7, 200, 200, 200);
  plinit();
  pladv(0);
  auto panel = [&](bool damping) {
    const Range& y = damping ? zy : fy;
    plwind(ax.lo, ax.hi, y.lo, y.hi);
    plcol0(7);
    pllsty(2);
    plbox("gl", 0, 0, "g", 0, 0);
    pllsty(1);
    for (size_t k = 0; k < series.size(); ++k) {
      const FigureSeries& s = series[k];
      std::vector<PLFLT> x, v, lo, hi;
      for (Eigen::Index i = 0; i < s.amplitude.size(); ++i) {
        if (!(s.amplitude(i) > 0) || !(s.damping(i) > 0)) continue;
        x.push_back(std::log10(s.amplitude(i)));
        const double val = damping ? s.damping(i) : s.frequency_hz(i);
        const double e = s.points ? (damping ? s.damping_std(i) : s.frequency_std_hz(i)) : 0.0;
        const double scale = damping ? 100.0 : 1.0;  // damping in percent
        v.push_back(scale * val);
        lo.push_back(scale * (val - e));
        hi.push_back(scale * (val + e));
      }
      if (x.empty()) continue;
      plcol0(kSeriesColours[k % 5]);
      const auto n = static_cast<PLINT>(x.size());
      if (s.points) {
        plwidth(1.5);
        plerry(n, x.data(), lo.data(), hi.data());
        plpoin(n, x.data(), v.data(), k % 2 ? 6 : 17);
      } else {
        plwidth(2.0);
        plline(n, x.data(), v.data());
      }
      plwidth(1.0);
    }
    plcol0(1);
    plbox(damping ? "bcnstl" : "bcstl", 0, 0, "bcnstv", 0, 0);
  };
  plvpor(0.12, 0.62, 0.55, 0.93);
  panel(false);
  plcol0(1);
  plmtex("l", 5.0, 0.5, 0.5, "frequency [Hz]");
  plmtex("t", 1.0, 0.5, 0.5, title.c_str());
  plvpor(0.12, 0.62, 0.10, 0.48);
  panel(true);
  plcol0(1);
  plmtex("l", 5.0, 0.5, 0.5, "damping ratio [%]");
  plmtex("b", 3.0, 0.5, 0.5, amplitude_label.c_str());
  // Legend: one coloured line of text per series, right of the panels.
  plvpor(0.64, 0.99, 0.10, 0.93);
  plwind(0, 1, 0, 1);
  plschr(0, 0.62);
  for (size_t k = 0; k < series.size(); ++k) {
    plcol0(kSeriesColours[k % 5]);
    const std::string text = (series[k].points ? (k % 2 ? "o " : "* ") : "- ") + series[k].label;
    plptex(0.02, 0.97 - 0.05 * static_cast<double>(k), 1, 0, 0, text.c_str());
  }
  plend1();
  plsstrm(previous);
  std::error_code ec;
  if (!std::filesystem::exists(tmp)) {
    throw InputError(fmt::format("{}: the plot driver wrote no file", file.string()));
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw InputError(fmt::format("{}: cannot write the figure", file.string()));
  }
}

}  // namespace jointlab::apps
