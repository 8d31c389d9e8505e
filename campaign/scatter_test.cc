#include "jointlab/campaign/scatter.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::campaign {
namespace {

// "h" followed by a number (fmt avoids a GCC 12 -Wrestrict false positive).
std::string label(const char* prefix, int i) { return fmt::format("{}{}", prefix, i); }

using jointlab::testing::Close;

// Published two-sided 95 % and 99 % critical values of Student's t (e.g. NIST/SEMATECH
// e-Handbook, table 1.3.6.7.2), given to 10 digits; bisection of the CDF reaches 1e-12.
TEST(StudentT, MatchesPublishedTable) {
  EXPECT_TRUE(Close(student_t_quantile(0.975, 1), 12.70620474, 1e-9));
  EXPECT_TRUE(Close(student_t_quantile(0.975, 2), 4.302652730, 1e-9));
  EXPECT_TRUE(Close(student_t_quantile(0.975, 4), 2.776445105, 1e-9));
  EXPECT_TRUE(Close(student_t_quantile(0.975, 10), 2.228138852, 1e-9));
  EXPECT_TRUE(Close(student_t_quantile(0.975, 100), 1.983971519, 1e-9));
  EXPECT_TRUE(Close(student_t_quantile(0.995, 5), 4.032142984, 1e-9));
  EXPECT_TRUE(Close(student_t_quantile(0.025, 4), -2.776445105, 1e-9));
  EXPECT_THROW(student_t_quantile(1.0, 3), InputError);
}

// A curve of constant frequency and damping over [a_lo, a_hi], 40 log-spaced points.
Curve flat_curve(const std::string& id, double a_lo, double a_hi, double f, double z) {
  Curve c;
  c.id = id;
  c.group = "g";
  const int n = 40;
  c.amplitude.resize(n);
  for (int i = 0; i < n; ++i)
    c.amplitude(i) = a_hi * std::pow(a_lo / a_hi, (i + 0.5) / n);  // decreasing, as in time
  c.frequency_hz = Eigen::VectorXd::Constant(n, f);
  c.damping = Eigen::VectorXd::Constant(n, z);
  c.has_linear = true;
  c.linear_frequency_hz = f + 0.01;
  c.linear_damping = 0.9 * z;
  return c;
}

// Bins against a direct computation: curves of known constant values over different
// amplitude ranges, so each bin has a known set of members.
TEST(Scatter, BinsMatchDirectComputation) {
  // Five bins per decade, edges 10^(k/5); ranges chosen away from edges.
  std::vector<Curve> curves = {
      flat_curve("h1", 1.1e-3, 0.9e-1, 100.00, 0.0030),
      flat_curve("h2", 1.1e-3, 0.9e-1, 100.02, 0.0032),
      flat_curve("h3", 1.1e-3, 0.9e-2, 99.99, 0.0029),
      flat_curve("h4", 1.1e-2, 0.9e-1, 100.01, 0.0031),
      flat_curve("h5", 1.1e-3, 0.9e-1, 99.98, 0.0033),
  };
  ScatterOptions opt;
  opt.bins_per_decade = 5;
  const ScatterSummary s = summarize_scatter(curves, opt);
  EXPECT_EQ(s.outliers(), 0);
  ASSERT_FALSE(s.bins.empty());
  int checked = 0;
  for (const ScatterBin& b : s.bins) {
    // Members: the curves whose range covers the bin centre (ranges avoid edges).
    std::vector<double> f, z;
    for (const Curve& c : curves) {
      if (c.amplitude.minCoeff() < b.amplitude_high && c.amplitude.maxCoeff() >= b.amplitude_low) {
        f.push_back(c.frequency_hz(0));
        z.push_back(c.damping(0));
      }
    }
    ASSERT_EQ(b.curves, static_cast<int>(f.size()));
    const double n = f.size();
    double mf = 0, mz = 0;
    for (size_t i = 0; i < f.size(); ++i) mf += f[i] / n, mz += z[i] / n;
    double sf = 0, sz = 0;
    for (size_t i = 0; i < f.size(); ++i)
      sf += (f[i] - mf) * (f[i] - mf), sz += (z[i] - mz) * (z[i] - mz);
    sf = std::sqrt(sf / (n - 1));
    sz = std::sqrt(sz / (n - 1));
    const double t = n == 4 ? 3.182446305 : 2.776445105;  // t_0.975 for 3 and 4 dof (table)
    ASSERT_TRUE(n == 4 || n == 5);
    // Sums of 40 equal doubles: relative rounding well under 1e-12.
    EXPECT_TRUE(Close(b.frequency_hz.mean, mf, 1e-12));
    EXPECT_TRUE(Close(b.frequency_hz.std, sf, 1e-7));  // std of values differing in digit 5
    EXPECT_TRUE(Close(b.frequency_hz.ci_high - b.frequency_hz.mean, t * sf / std::sqrt(n), 1e-7));
    EXPECT_TRUE(Close(b.frequency_hz.mean - b.frequency_hz.ci_low, t * sf / std::sqrt(n), 1e-7));
    EXPECT_TRUE(Close(b.damping.mean, mz, 1e-12));
    EXPECT_TRUE(Close(b.damping.std, sz, 1e-9));
    EXPECT_TRUE(Close(b.damping.ci_high - b.damping.mean, t * sz / std::sqrt(n), 1e-9));
    EXPECT_TRUE(Close(b.amplitude_center, std::sqrt(b.amplitude_low * b.amplitude_high), 1e-14));
    EXPECT_TRUE(Close(std::log10(b.amplitude_high / b.amplitude_low), 0.2, 1e-12));
    ++checked;
  }
  // 1.1e-3 .. 0.9e-1 spans bins k = -15 .. -6 (10 bins), all with at least 4 curves.
  EXPECT_EQ(checked, 10);
  EXPECT_EQ(s.linear_count, 5);
  EXPECT_TRUE(Close(s.linear_frequency_hz.mean, 100.01, 1e-12));
}

// Points of one curve falling in one bin are averaged before the statistics over curves.
TEST(Scatter, CurveValueIsMeanOfItsPointsInTheBin) {
  Curve a, b;
  a.id = "a";
  b.id = "b";
  // Both inside [10^-1, 10^-0.8): bin k = -5 at 5 bins per decade.
  a.amplitude = Eigen::Vector3d(0.11, 0.12, 0.13);
  a.frequency_hz = Eigen::Vector3d(10, 11, 15);   // mean 12
  a.damping = Eigen::Vector3d(0.01, 0.02, 0.03);  // mean 0.02
  b.amplitude = Eigen::Vector2d(0.14, 0.15);
  b.frequency_hz = Eigen::Vector2d(13, 15);  // mean 14
  b.damping = Eigen::Vector2d(0.03, 0.05);   // mean 0.04
  const ScatterSummary s = summarize_scatter({a, b}, {});
  ASSERT_EQ(s.bins.size(), 1u);
  EXPECT_EQ(s.bins[0].curves, 2);
  EXPECT_TRUE(Close(s.bins[0].frequency_hz.mean, 13.0, 1e-14));
  EXPECT_TRUE(Close(s.bins[0].frequency_hz.std, std::sqrt(2.0), 1e-14));
  // n = 2: t_0.975,1 = 12.70620474 (table); half-width t s / sqrt(2) = t.
  EXPECT_TRUE(Close(s.bins[0].frequency_hz.ci_high, 13.0 + 12.70620474, 1e-9));
  EXPECT_TRUE(Close(s.bins[0].damping.mean, 0.03, 1e-13));
}

// A planted outlier: eight hits scattered by +-0.01 Hz and +-3 % damping, one 0.3 Hz high
// (30 spreads out), another with 40 % more damping. Both are flagged, with the right reason,
// and left out of the bins; no other hit is flagged.
TEST(Scatter, PlantedOutlierIsFlagged) {
  std::vector<Curve> curves;
  const double df[8] = {-0.010, 0.004, 0.008, -0.006, 0.0, 0.010, -0.003, 0.006};
  const double dz[8] = {0.03, -0.02, 0.01, -0.03, 0.0, 0.02, -0.01, 0.015};
  for (int i = 0; i < 8; ++i) {
    curves.push_back(flat_curve(label("h", i + 1), 2e-3, 5e-2, 120.0 + df[i], 0.004 * (1 + dz[i])));
  }
  curves.push_back(flat_curve("freq_out", 2e-3, 5e-2, 120.3, 0.004));
  curves.push_back(flat_curve("damp_out", 2e-3, 5e-2, 120.0, 0.0056));
  const ScatterSummary s = summarize_scatter(curves, {});
  ASSERT_EQ(s.hits.size(), 10u);
  for (int i = 0; i < 8; ++i) EXPECT_FALSE(s.hits[i].outlier) << s.hits[i].id << s.hits[i].reason;
  EXPECT_TRUE(s.hits[8].outlier);
  EXPECT_NE(s.hits[8].reason.find("frequency"), std::string::npos);
  EXPECT_GT(s.hits[8].frequency_z, 3.5);
  EXPECT_TRUE(s.hits[9].outlier);
  EXPECT_NE(s.hits[9].reason.find("damping"), std::string::npos);
  EXPECT_EQ(s.outliers(), 2);
  // Excluded from the bins: every bin holds the 8 regular hits and counts 2 flagged.
  for (const ScatterBin& b : s.bins) {
    EXPECT_EQ(b.curves, 8);
    EXPECT_EQ(b.flagged, 2);
    EXPECT_LT(std::abs(b.frequency_hz.mean - 120.0), 0.01);
  }
  // Kept in with exclude_outliers = false.
  ScatterOptions keep;
  keep.exclude_outliers = false;
  const ScatterSummary k = summarize_scatter(curves, keep);
  EXPECT_EQ(k.outliers(), 2);
  for (const ScatterBin& b : k.bins) EXPECT_EQ(b.curves, 10);
}

// Identical hits: the floors keep rounding-level differences from being flagged.
TEST(Scatter, IdenticalHitsAreNotFlagged) {
  std::vector<Curve> curves;
  for (int i = 0; i < 5; ++i)
    curves.push_back(flat_curve(label("h", i), 1e-3, 1e-2, 50.0 * (1 + 1e-9 * i), 0.01));
  const ScatterSummary s = summarize_scatter(curves, {});
  EXPECT_EQ(s.outliers(), 0);
  for (const ScatterBin& b : s.bins) EXPECT_EQ(b.curves, 5);
}

TEST(Scatter, WritesFilesWithoutNaN) {
  std::vector<Curve> curves = {flat_curve("a", 1e-3, 1e-2, 10, 0.01),
                               flat_curve("b", 1e-3, 1e-2, 10.1, 0.011)};
  const ScatterSummary s = summarize_scatter(curves, {});
  const auto dir = jointlab::testing::scratch_folder("jointlab_scatter_test");
  std::filesystem::create_directories(dir);
  write_scatter_bins_csv(dir / "bins.csv", s);
  write_scatter_hits_csv(dir / "hits.csv", s);
  write_scatter_json(dir / "scatter.json", "mode 1", s);
  for (const char* name : {"bins.csv", "hits.csv", "scatter.json"}) {
    const std::string text = testing::read_file(dir / name);
    EXPECT_FALSE(text.empty()) << name;
    EXPECT_EQ(text.find("nan"), std::string::npos) << name;
  }
  std::filesystem::remove_all(dir);
}

// One hit has no spread between tests: its linear statistics say so (no std, no interval),
// where they once gave a standard deviation of 0 and an interval of zero width.
TEST(Scatter, OneHitHasNoSpreadRatherThanASpreadOfZero) {
  const ScatterSummary s = summarize_scatter({flat_curve("a", 1e-3, 1e-2, 10, 0.01)}, {});
  EXPECT_EQ(s.linear_count, 1);
  EXPECT_FALSE(s.linear_frequency_hz.has_spread());
  EXPECT_FALSE(s.linear_damping.has_spread());
  EXPECT_EQ(s.linear_frequency_hz.mean, 10.01);  // the hit's own value, exactly
  EXPECT_NE(s.report().find("one hit: no spread"), std::string::npos) << s.report();
  EXPECT_EQ(s.report().find("std"), std::string::npos) << s.report();
  const auto dir = jointlab::testing::scratch_folder("jointlab_scatter_one");
  std::filesystem::create_directories(dir);
  write_scatter_json(dir / "scatter.json", "mode 1", s);
  const std::string json = testing::read_file(dir / "scatter.json");
  const std::string linear = json.substr(json.find("\"linear\""));
  EXPECT_NE(linear.find("\"mean\""), std::string::npos) << linear;
  EXPECT_EQ(linear.find("\"std\""), std::string::npos) << linear;
  EXPECT_EQ(linear.find("\"ci_low\""), std::string::npos) << linear;
  std::filesystem::remove_all(dir);
  // Two hits do have one.
  const ScatterSummary two = summarize_scatter(
      {flat_curve("a", 1e-3, 1e-2, 10, 0.01), flat_curve("b", 1e-3, 1e-2, 10.1, 0.011)}, {});
  EXPECT_TRUE(two.linear_frequency_hz.has_spread());
  EXPECT_GT(two.linear_frequency_hz.std, 0);
}

TEST(Scatter, RejectsBadInput) {
  ScatterOptions bad;
  bad.confidence = 1.0;
  EXPECT_THROW(summarize_scatter({}, bad), InputError);
  Curve c = flat_curve("a", 1e-3, 1e-2, 10, 0.01);
  c.amplitude(3) = -1;
  EXPECT_THROW(summarize_scatter({c}, {}), InputError);
}

}  // namespace
}  // namespace jointlab::campaign
