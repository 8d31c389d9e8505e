#include "jointlab/campaign/figures.h"
#include "jointlab/campaign/backbone_comparison.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <plplot.h>

#include "jointlab/campaign/plot_layout.h"
#include "jointlab/core/error.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::campaign {
namespace {

// "h" followed by a number (fmt avoids a GCC 12 -Wrestrict false positive).
std::string label(const char* prefix, int i) { return fmt::format("{}{}", prefix, i); }

namespace fs = std::filesystem;

// The first bytes of a file.
std::string head(const fs::path& p, size_t n) {
  std::ifstream in(p, std::ios::binary);
  std::string s(n, '\0');
  in.read(s.data(), static_cast<std::streamsize>(n));
  s.resize(static_cast<size_t>(in.gcount()));
  return s;
}

fs::path scratch() {
  const fs::path d = jointlab::testing::scratch_folder("jointlab_figures_test");
  fs::create_directories(d);
  return d;
}

// A softening, increasingly damped backbone over two decades.
Curve backbone(const std::string& id, double shift) {
  Curve c;
  c.id = id;
  const int n = 60;
  c.amplitude.resize(n);
  c.frequency_hz.resize(n);
  c.damping.resize(n);
  for (int i = 0; i < n; ++i) {
    const double a = 1e-2 * std::pow(1e-2, i / (n - 1.0));
    c.amplitude(i) = a;
    c.frequency_hz(i) = 120.0 - 0.5 * std::sqrt(a / 1e-2) + shift;
    c.damping(i) = 0.002 * (1 + 3 * std::sqrt(a / 1e-2)) * (1 + shift);
  }
  return c;
}

bool is_png(const fs::path& p) { return head(p, 8) == std::string("\x89PNG\r\n\x1a\n", 8); }

// Every figure writes a PNG (and SVG/PDF by extension), leaves no temporary behind and
// restores the caller's PLplot stream.
TEST(Figures, WriteFilesAndLeaveNoState) {
  const fs::path dir = scratch();
  PLINT before = -1;
  plgstrm(&before);

  BackboneFigure f;
  f.title = "mode 1";
  f.amplitude_label = "velocity amplitude [m/s]";
  for (int h = 0; h < 5; ++h) f.hits.push_back(backbone(label("h", h), 0.01 * h));
  f.summary = summarize_scatter(f.hits, {});
  ModelCurve m;
  m.label = "model (QSMA)";
  m.amplitude = f.hits[0].amplitude;
  m.frequency_hz = f.hits[0].frequency_hz.array() + 0.2;
  m.damping = f.hits[0].damping;
  f.model.push_back(m);
  plot_backbones(f, dir / "backbone.png");
  plot_backbones(f, dir / "backbone.svg");
  plot_backbones(f, dir / "backbone.pdf");
  EXPECT_TRUE(is_png(dir / "backbone.png"));
  EXPECT_EQ(head(dir / "backbone.pdf", 4), "%PDF");
  EXPECT_NE(head(dir / "backbone.svg", 200).find("<svg"), std::string::npos);

  SpectrumFigure s;
  s.title = "spectrum";
  s.amplitude_label = "acceleration [m/s^2]";
  s.frequency_hz = Eigen::VectorXd::LinSpaced(500, 0, 1000);
  s.channel_names = {"a", "b"};
  s.spectra.push_back((1.0 / (1.0 + (s.frequency_hz.array() - 120).square())).matrix());
  s.spectra.push_back((0.5 / (1.0 + (s.frequency_hz.array() - 290).square())).matrix());
  s.bands = {{"mode 1", 100, 140}, {"mode 2", 260, 320}};
  plot_spectrum(s, dir / "spectrum.png");
  EXPECT_TRUE(is_png(dir / "spectrum.png"));

  Eigen::MatrixXd mac(2, 3);
  mac << 0.99, 0.02, 0.1, 0.01, 0.97, 0.3;
  plot_mac(mac, {"1", "2"}, {"1", "2", "3"}, "MAC", dir / "mac.png");
  EXPECT_TRUE(is_png(dir / "mac.png"));

  plot_frequency_errors({"1", "2"}, {{"before", {2.0, -1.0}}, {"after", {0.1, 0.05}}}, "errors",
                        dir / "errors.png");
  EXPECT_TRUE(is_png(dir / "errors.png"));

  PLINT after = -2;
  plgstrm(&after);
  EXPECT_EQ(before, after);
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  if (!std::getenv("JOINTLAB_KEEP_FIGURES")) fs::remove_all(dir);
}

// A curve that starts left of the window, ends right of it, and one that jumps across it in
// one segment: what is drawn stays inside, ends on the frame at the interpolated value, and
// keeps the points inside.
TEST(PlotLayout, CurvesAreCutAtTheWindow) {
  std::vector<double> x{-2, 0.5, 1.5, 4}, y{0, 5, 15, 40};  // y = 10 x but for the first
  clip_x(x, y, 0.0, 2.0);
  ASSERT_EQ(x.size(), 4u);
  EXPECT_DOUBLE_EQ(x.front(), 0.0);
  EXPECT_DOUBLE_EQ(y.front(), 4.0);  // 0.8 of the way from (-2, 0) to (0.5, 5)
  EXPECT_DOUBLE_EQ(x.back(), 2.0);
  EXPECT_DOUBLE_EQ(y.back(), 20.0);
  EXPECT_DOUBLE_EQ(x[1], 0.5);
  EXPECT_DOUBLE_EQ(x[2], 1.5);
  std::vector<double> a{3, -1}, b{3, -1};  // decreasing, across the whole window
  clip_x(a, b, 0.0, 2.0);
  EXPECT_EQ(a, (std::vector<double>{2.0, 0.0}));
  EXPECT_EQ(b, (std::vector<double>{2.0, 0.0}));
  std::vector<double> c{3, 4}, d{1, 1};  // wholly outside
  clip_x(c, d, 0.0, 2.0);
  EXPECT_TRUE(c.empty());
}

// Log-axis labels for ranges from a fifth of a decade to five decades: at least two, in
// range, increasing, and never closer than the gap asked for (9 and 8 x 10^k sit 0.05
// decades apart, so a 0.6-decade axis used to print labels on top of each other).
TEST(PlotLayout, LogLabelsKeepApart) {
  for (const double span : {0.2, 0.6, 0.9, 1.7, 2.5, 5.0}) {
    const double lo = -3.3, hi = lo + span, gap = 0.1;
    const std::vector<double> v = log_label_values(lo, hi, gap);
    ASSERT_GE(v.size(), 2u) << span;
    for (size_t i = 0; i < v.size(); ++i) {
      const double p = std::log10(v[i]);
      EXPECT_GE(p, lo - 1e-12);
      EXPECT_LE(p, hi + 1e-12);
      if (i > 0) {
        EXPECT_GE((p - std::log10(v[i - 1])) / span, gap - 1e-12) << span;
      }
    }
  }
}

TEST(Figures, RejectsBadInput) {
  const fs::path dir = scratch();
  EXPECT_THROW(plot_mac(Eigen::MatrixXd::Identity(2, 2), {"1"}, {"1", "2"}, "", dir / "m.png"),
               InputError);
  EXPECT_THROW(plot_frequency_errors({"1"}, {{"x", {1.0, 2.0}}}, "", dir / "e.png"), InputError);
  EXPECT_THROW(plot_frequency_errors({"1"}, {{"x", {1.0}}}, "", dir / "e.gif"), InputError);
  EXPECT_FALSE(fs::exists(dir / "m.png"));
}

// update-iwan's and compare's figure draws the curves the fit used: none of them is drawn as a
// flagged hit, and the mean runs over all of them. Before, the figure summarised them once more
// and flagged one the fit had used: six curves, one 0.5 % off in frequency (its robust z far
// past 3.5), were drawn as "hits (5)" and "flagged hit (1)" with the mean over five.
TEST(BackboneComparisonFigure, TheCurvesTheFitUsedAreNoneOfThemFlagged) {
  BackboneComparison c;
  for (int h = 0; h < 6; ++h) {
    correlate::MeasuredBackbone b;
    b.source = fmt::format("hit{}", h + 1);
    b.amplitude = Eigen::VectorXd::LinSpaced(8, 1.9e-3, 1.0e-3);
    b.frequency_hz = Eigen::VectorXd::Constant(8, (h == 5 ? 100.5 : 100.0) + 0.01 * h);
    b.damping_ratio = Eigen::VectorXd::Constant(8, 1e-3 * (1 + 0.01 * h));
    c.measured.push_back(b);
  }
  // The default screen flags the sixth: the case the figure met.
  std::vector<Curve> curves;
  for (const correlate::MeasuredBackbone& b : c.measured) {
    Curve cv;
    cv.id = b.source;
    cv.amplitude = b.amplitude;
    cv.frequency_hz = b.frequency_hz;
    cv.damping = b.damping_ratio;
    curves.push_back(cv);
  }
  int flagged_by_default = 0;
  for (const HitDeviation& h : summarize_scatter(curves, {}).hits) flagged_by_default += h.outlier;
  ASSERT_EQ(flagged_by_default, 1);
  const BackboneFigure f = comparison_figure(c);
  ASSERT_EQ(f.hits.size(), 6u);
  for (const HitDeviation& h : f.summary.hits) EXPECT_FALSE(h.outlier) << h.id;
  ASSERT_FALSE(f.summary.bins.empty());
  for (const ScatterBin& b : f.summary.bins) EXPECT_EQ(b.curves, 6);
}

}  // namespace
}  // namespace jointlab::campaign
