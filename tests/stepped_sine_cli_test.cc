// End-to-end tests of `jointlab stepped-sine`: the Brake-Reuss .mat gives one backbone file
// in the format of `process`; a synthetic CSV sweep comes back right; bad input gets one line,
// exit 2 and no output.
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/tests/cli.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::testing {
namespace {

std::vector<std::string> lines_of(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

std::vector<double> row(const std::string& line) {
  std::vector<double> v;
  std::stringstream ss(line);
  for (std::string c; std::getline(ss, c, ',');) v.push_back(std::stod(c));
  return v;
}

TEST(SteppedSineCli, BrakeReussMatGivesOneBackboneInProcessFormat) {
  const std::string dir = scratch_dir("sine_brake_reuss");
  const CommandResult r =
      run_jointlab("stepped-sine " + source_dir() +
                   "/data/examples/brake-reuss-beam/forced_frequency_responses.mat --out " + dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto lines = lines_of(dir + "/forced_frequency_responses.backbone.csv");
  ASSERT_EQ(lines.size(), 13u);  // header and 12 levels
  EXPECT_EQ(lines[0].rfind("amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std,", 0),
            0u);
  double last = 0;
  for (size_t i = 1; i < lines.size(); ++i) {
    const auto v = row(lines[i]);
    EXPECT_GT(v[0], last);  // amplitude increasing
    last = v[0];
    EXPECT_GT(v[1], 79.0);
    EXPECT_LT(v[1], 81.0);
    EXPECT_GT(v[2], 0.0);
    EXPECT_GT(v[3], 0.0);
    EXPECT_GT(v[4], 0.0);
  }
  EXPECT_TRUE(std::filesystem::exists(dir + "/summary.json"));
  EXPECT_NE(r.err.find("FRdata.ResponseControl(8): response-controlled"), std::string::npos);
  // The figure, with this run's own backbone as a ring-down curve (any process-format CSV).
  const CommandResult f = run_jointlab(
      "stepped-sine " + source_dir() +
      "/data/examples/brake-reuss-beam/forced_frequency_responses.mat --ringdown " + dir +
      "/forced_frequency_responses.backbone.csv --figure " + dir + "/f.png --out " + dir + "/2");
  ASSERT_EQ(f.status, 0) << f.err;
  EXPECT_GT(std::filesystem::file_size(dir + "/f.png"), 1000u);
  const CommandResult bad = run_jointlab("stepped-sine " + source_dir() +
                                         "/data/examples/brake-reuss-beam/"
                                         "forced_frequency_responses.mat --figure " +
                                         dir + "/f.gif --out " + dir + "/3");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("--figure"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir + "/3/summary.json"));
}

// A linear hysteretic mode (f_n 80 Hz, zeta 0.3 %) held at 20 mm/s: the point is the mode at
// 20 mm/s, as velocity and as displacement (exact data: 1e-8).
TEST(SteppedSineCli, SyntheticCsvSweepComesBack) {
  const std::string dir = scratch_dir("sine_csv");
  const double fn = 80.0, zeta = 0.003, v = 0.02;
  std::string text =
      "# control: response\n# level: 20 mm/s\nfrequency_hz;force [N];response [mm/s];phase [deg]\n";
  for (int k = 0; k < 31; ++k) {
    const double f = 79.0 + k * 2.0 / 30, w = 2 * std::numbers::pi * f,
                 wn = 2 * std::numbers::pi * fn;
    // Velocity receptance i w / (wn^2 - w^2 + 2 i zeta wn^2) for a unit modal mass.
    const std::complex<double> h =
        std::complex<double>(0, w) / std::complex<double>(wn * wn - w * w, 2 * zeta * wn * wn);
    text += fmt::format("{:.12g};{:.12g};{:.12g};{:.12g}\n", f, v / std::abs(h), 1000 * v,
                        std::arg(h) * 180 / std::numbers::pi);
  }
  write_text(dir + "/sweep.csv", text);
  for (const char* q : {"velocity", "displacement"}) {
    const CommandResult r = run_jointlab(
        fmt::format("stepped-sine {}/sweep.csv --amplitude {} --out {}/out", dir, q, dir));
    ASSERT_EQ(r.status, 0) << r.err;
    const auto lines = lines_of(dir + "/out/sweep.backbone.csv");
    ASSERT_EQ(lines.size(), 2u);
    const auto p = row(lines[1]);
    const double amp = std::string(q) == "velocity" ? v : v / (2 * std::numbers::pi * fn);
    EXPECT_TRUE(Close(p[0], amp, 1e-8)) << q;
    EXPECT_TRUE(Close(p[1], fn, 1e-10));
    EXPECT_TRUE(Close(p[2], zeta, 1e-8));
  }
}

TEST(SteppedSineCli, BadInputOneLineExitTwoNoOutput) {
  const std::string dir = scratch_dir("sine_bad");
  write_text(dir + "/bad.csv",
             "# control: force\nfrequency_hz,force [N],response [m/s^2],phase [deg]\n"
             "1,1,1,0\n2,1,1,0\n3,1,nan,0\n4,1,1,0\n5,1,1,0\n");
  const CommandResult r = run_jointlab("stepped-sine " + dir + "/bad.csv --out " + dir + "/out");
  EXPECT_EQ(r.status, 2);
  std::string msg = r.err;
  while (!msg.empty() && msg.back() == '\n') msg.pop_back();
  EXPECT_EQ(msg.find('\n'), std::string::npos) << r.err;
  EXPECT_NE(msg.find("bad.csv:5: column 'response [m/s^2]': 'nan' is not a finite number"),
            std::string::npos)
      << msg;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/summary.json"));
}

}  // namespace
}  // namespace jointlab::testing
