#include "jointlab/campaign/figures.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <plplot.h>

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

TEST(Figures, RejectsBadInput) {
  const fs::path dir = scratch();
  EXPECT_THROW(plot_mac(Eigen::MatrixXd::Identity(2, 2), {"1"}, {"1", "2"}, "", dir / "m.png"),
               InputError);
  EXPECT_THROW(plot_frequency_errors({"1"}, {{"x", {1.0, 2.0}}}, "", dir / "e.png"), InputError);
  EXPECT_THROW(plot_frequency_errors({"1"}, {{"x", {1.0}}}, "", dir / "e.gif"), InputError);
  EXPECT_FALSE(fs::exists(dir / "m.png"));
}

}  // namespace
}  // namespace jointlab::campaign
