// Tests of iwan_targets(): the weights from the scatter between hits and the points' own
// uncertainty, flagged hits left out, and the joint-slip screen.
#include "jointlab/campaign/iwan_targets.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <gtest/gtest.h>

#include "jointlab/correlate/two_chain.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::campaign {
namespace {

using testing::Close;

// A backbone of hit `id`: amplitudes 1e-3 .. 1.9e-3 (one bin at 5 per decade), constant
// frequency f and damping z, at times 0.1, 0.2, ... (amplitude falling).
Curve flat(const std::string& id, double f, double z, double scale = 1.0) {
  Curve c;
  c.id = id;
  const int n = 10;
  c.time_s = Eigen::VectorXd::LinSpaced(n, 0.1, 1.0);
  c.amplitude = scale * Eigen::VectorXd::LinSpaced(n, 1.9e-3, 1.0e-3);
  c.frequency_hz = Eigen::VectorXd::Constant(n, f);
  c.damping = Eigen::VectorXd::Constant(n, z);
  return c;
}

// Three hits at 100, 101 and 102 Hz (sample std 1 Hz) and damping 0.010, 0.012, 0.014 (std
// 0.002): sigma is the bin's std, whatever the points' own; with one hit left out the bins
// hold two curves and each point keeps its own uncertainty (0 where unknown: the floor).
TEST(IwanTargets, WeightsFromTheScatterOrTheOwnUncertainty) {
  const model::Model m = correlate::two_chain_structure({.iwan = true});
  const std::vector<correlate::Sensor> sensors{{"s", 5, 1.0}};
  ModeBackbones mb;
  mb.name = "mode 1";
  mb.model_mode = 1;
  mb.curves = {flat("a", 100, 0.010), flat("b", 101, 0.012), flat("c", 102, 0.014)};
  mb.sensors = {0, 0, 0};
  mb.frequency_std_hz = {Eigen::VectorXd::Constant(10, 0.5), Eigen::VectorXd::Constant(10, 3.0),
                         Eigen::VectorXd()};
  mb.damping_std = {Eigen::VectorXd::Constant(10, 1e-4), Eigen::VectorXd::Constant(10, 1e-3),
                    Eigen::VectorXd()};
  ScatterOptions so;
  so.outlier_threshold = 100;  // nobody flagged
  mb.scatter = summarize_scatter(mb.curves, so);
  const IwanTargets t = iwan_targets(m, sensors, {mb}, {});
  ASSERT_EQ(t.fitted.size(), 1u);
  ASSERT_EQ(t.fitted[0].curves.size(), 3u);
  EXPECT_EQ(t.screened, 0);
  for (const correlate::MeasuredBackbone& c : t.fitted[0].curves) {
    EXPECT_TRUE(Close(c.frequency_std_hz(3), 1.0, 1e-12));
    EXPECT_TRUE(Close(c.damping_std(3), 0.002, 1e-9));
  }
  // Hit b flagged and left out: two curves per bin.
  mb.scatter.hits[1].outlier = true;
  for (ScatterBin& b : mb.scatter.bins) b.curves = 2;  // as the bins without hit b
  const IwanTargets two = iwan_targets(m, sensors, {mb}, {});
  ASSERT_EQ(two.fitted[0].curves.size(), 2u);
  // Each curve is named by its hit, as the report names a curve apart from the others.
  EXPECT_EQ(two.fitted[0].curves[0].source, "a");
  EXPECT_EQ(two.fitted[0].curves[1].source, "c");
  EXPECT_EQ(two.fitted[0].curves[0].frequency_std_hz(3), 0.5);
  EXPECT_EQ(two.fitted[0].curves[0].damping_std(3), 1e-4);
  EXPECT_EQ(two.fitted[0].curves[1].frequency_std_hz(3), 0.0);
  mb.scatter.options.exclude_outliers = false;
  EXPECT_EQ(iwan_targets(m, sensors, {mb}, {}).fitted[0].curves.size(), 3u);
}

// Three hits of one mode read at two channels, b2 seeing it three times as strongly as a5; the
// frequency falls 1 % per decade of amplitude. Hit 1 names a5 its reference channel, hits 2
// and 3 name b2. Each hit read at its own reference channel put hit 1's curve 0.48 decades
// down the amplitude axis, 0.48 % above the others in frequency: the scatter summary flagged it
// (robust z far over 3.5) and the fit left it out without a word (the example campaign's
// low_hit1 with update-iwan's default channels). Read at one channel (b2: backbones in all
// three hits, named by two), the three curves are one and nothing is flagged; the note says
// which channel was taken.
TEST(IwanTargets, HitsWhoseReferenceChannelsDifferAreReadAtOneChannel) {
  const std::filesystem::path d = testing::scratch_folder("iwan_targets_two_references");
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  std::string files;
  for (int hit = 1; hit <= 3; ++hit) {
    files += fmt::format(
        R"({}{{"file": "hit{}.csv",
     "bands": [{{"band": 1, "low_hz": 80, "high_hz": 120, "reference_channel": "{}",
                "operating_shape": []}}],
     "outputs": [{{"channel": "a5", "band": 1, "file": "hit{}.a5.band1.csv"}},
                 {{"channel": "b2", "band": 1, "file": "hit{}.b2.band1.csv"}}]}})",
        hit == 1 ? "" : ",\n", hit, hit == 1 ? "a5" : "b2", hit, hit);
    for (const auto& [channel, scale] : {std::pair<std::string, double>{"a5", 1.0}, {"b2", 3.0}}) {
      std::string text =
          "time_s,amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std\n";
      for (int i = 0; i < 20; ++i) {
        const double a = 1e-2 * std::pow(10.0, -i / 10.0);  // the a5 amplitude, 2 decades
        text += fmt::format("{},{},{},0.002,0.001,1e-5\n", 0.1 * (i + 1), scale * a,
                            100 * (1 - 0.01 * std::log10(scale * a / 1e-4)));
      }
      std::ofstream(d / fmt::format("hit{}.{}.band1.csv", hit, channel)) << text;
    }
  }
  std::ofstream(d / "summary.json")
      << R"({"program": "jointlab process", "amplitude_quantity": "velocity",
  "amplitude_unit": "m/s", "files": [)"
      << files << "]}";
  const std::vector<correlate::Sensor> sensors{{"a5", 5, 1.0}, {"b2", 7, 1.0}};
  const ModeBackbones mb =
      process_run_backbones(data::read_process_run(d), sensors, 1, {}, ScatterOptions{});
  ASSERT_EQ(mb.curves.size(), 3u);
  EXPECT_EQ(mb.sensors, (std::vector<int>{1, 1, 1}));
  for (const HitDeviation& h : mb.scatter.hits) EXPECT_FALSE(h.outlier) << h.id << " " << h.reason;
  EXPECT_NE(mb.channel_note.find("(a5 in hit1; b2 in the other 2): every hit is read at b2"),
            std::string::npos)
      << mb.channel_note;
  // Each hit at its own reference channel, as before: hit 1 is flagged.
  std::vector<Curve> own;
  for (const auto& [id, scale] :
       {std::pair<std::string, double>{"hit1", 1.0}, {"hit2", 3.0}, {"hit3", 3.0}}) {
    Curve c = mb.curves[0];
    c.id = id;
    c.amplitude *= scale / 3.0;  // mb's curves are b2's
    own.push_back(c);
  }
  const ScatterSummary mixed = summarize_scatter(own, ScatterOptions{});
  EXPECT_TRUE(mixed.hits[0].outlier) << mixed.hits[0].reason;
}

// The screen: another mode of the same model that slips the same joint, ringing in the same
// hit at a hundred times the amplitude, carries far more than 5 % of the slip, so every point
// goes; the same curve from another hit, or a mode that is not fitted, leaves them all.
TEST(IwanTargets, PointsWhereAnotherModeSlipsTheJointsAreLeftOut) {
  const model::Model m = correlate::two_chain_structure({.iwan = true});
  const model::LinearModes lm = model::linear_modes(m.mass, m.linear_stiffness());
  // Chain A's first two modes: both slip the A1-A2 joint.
  std::vector<int> chain_a;
  for (int j = lm.rigid_count; j < lm.size() && chain_a.size() < 2; ++j)
    if (lm.shapes.col(j).head(6).norm() > lm.shapes.col(j).tail(6).norm())
      chain_a.push_back(j - lm.rigid_count + 1);
  ASSERT_EQ(chain_a.size(), 2u);
  const std::vector<correlate::Sensor> sensors{{"s", 5, 1.0}};
  const auto mode = [&](int model_mode, const Curve& c) {
    ModeBackbones mb;
    mb.name = std::to_string(model_mode);
    mb.model_mode = model_mode;
    mb.curves = {c};
    mb.sensors = {0};
    mb.scatter = summarize_scatter(mb.curves, {});
    return mb;
  };
  const ModeBackbones first = mode(chain_a[0], flat("hit", 50, 0.01));
  const IwanTargets alone = iwan_targets(m, sensors, {first}, {});
  EXPECT_EQ(alone.screened, 0);
  const IwanTargets loud =
      iwan_targets(m, sensors, {first, mode(chain_a[1], flat("hit", 150, 0.01, 100))}, {});
  EXPECT_EQ(loud.screened, 10);
  for (const correlate::IwanTarget& t : loud.fitted) EXPECT_NE(t.mode, chain_a[0]);
  const IwanTargets other_hit =
      iwan_targets(m, sensors, {first, mode(chain_a[1], flat("other", 150, 0.01, 100))}, {});
  EXPECT_EQ(other_hit.screened, 0);
  ModeBackbones reported = first;
  reported.fitted = false;
  const IwanTargets kept =
      iwan_targets(m, sensors, {reported, mode(chain_a[1], flat("hit", 150, 0.01, 100))}, {});
  ASSERT_FALSE(kept.every.empty());
  EXPECT_EQ(kept.every.front().first, 0u);
  ASSERT_EQ(kept.every.front().second.curves.size(), 1u);
  EXPECT_EQ(kept.every.front().second.curves[0].amplitude.size(), 10);
  // Three modes at once: each mode's count of points and of points left out, in its order,
  // and one report line per fitted mode (issue 28: `--mode 1:1 --mode 2:2 --mode 3:3`).
  const std::vector<ModeBackbones> three = {first, mode(chain_a[1], flat("hit", 150, 0.01, 100)),
                                            mode(chain_a[1], flat("other", 150, 0.01))};
  const IwanTargets t3 = iwan_targets(m, sensors, three, {});
  ASSERT_EQ(t3.points_screened.size(), 3u);
  EXPECT_EQ(t3.points_screened[0], std::make_pair(Eigen::Index{10}, Eigen::Index{10}));
  EXPECT_EQ(t3.points_screened[2].first, 10);
  EXPECT_EQ(t3.screened, t3.points_screened[0].second + t3.points_screened[1].second +
                             t3.points_screened[2].second);
  EXPECT_EQ(t3.fitted.size(), 2u);  // the first mode lost every point, the others are fitted
  const std::string report = t3.screen_report(three);
  EXPECT_NE(report.find(three[0].name + ": 10 of 10 points left out"), std::string::npos) << report;
  EXPECT_EQ(std::count(report.begin(), report.end(), '\n'), 3) << report;
  EXPECT_EQ(t3.screened_out(three, 0.05), "");  // two modes are left to fit
  // The loud mode only reported: the fitted mode loses every point, and why is said with the
  // counts, not as "fit the modes one at a time" (its one-mode curve would take the other
  // mode's slip as its own).
  ModeBackbones loud_reported = mode(chain_a[1], flat("hit", 150, 0.01, 100));
  loud_reported.fitted = false;
  const std::vector<ModeBackbones> none_left = {first, loud_reported};
  const IwanTargets t0 = iwan_targets(m, sensors, none_left, {});
  EXPECT_TRUE(t0.fitted.empty());
  const std::string why = t0.screened_out(none_left, 0.05);
  EXPECT_NE(why.find("over 5 % of the joint slip is left out (" + first.name + ": 10 of 10, "),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("strike where the fitted modes dominate the joint slip"), std::string::npos)
      << why;
  EXPECT_EQ(alone.screened_out({first}, 0.05), "");
}

// A hit whose every point the screen leaves out is named, not only counted: the 0.4 m beam of
// 16 rivets struck at its end lost 3 of mode 1's 9 hits to the screen, and the report said only
// "6 curves". Here the other mode rings loud in hit "b" alone: "b" is named, "a" is fitted.
TEST(IwanTargets, AHitTheScreenEmptiesIsNamed) {
  const model::Model m = correlate::two_chain_structure({.iwan = true});
  const model::LinearModes lm = model::linear_modes(m.mass, m.linear_stiffness());
  std::vector<int> chain_a;
  for (int j = lm.rigid_count; j < lm.size() && chain_a.size() < 2; ++j)
    if (lm.shapes.col(j).head(6).norm() > lm.shapes.col(j).tail(6).norm())
      chain_a.push_back(j - lm.rigid_count + 1);
  ASSERT_EQ(chain_a.size(), 2u);
  const std::vector<correlate::Sensor> sensors{{"s", 5, 1.0}};
  ModeBackbones fitted;
  fitted.name = "mode 1";
  fitted.model_mode = chain_a[0];
  fitted.curves = {flat("a", 50, 0.01), flat("b", 50, 0.01)};
  fitted.sensors = {0, 0};
  fitted.scatter = summarize_scatter(fitted.curves, {});
  ModeBackbones other;
  other.name = "band 2";
  other.model_mode = chain_a[1];
  other.fitted = false;
  other.curves = {flat("b", 150, 0.01, 100)};
  other.sensors = {0};
  other.scatter = summarize_scatter(other.curves, {});
  const std::vector<ModeBackbones> modes = {fitted, other};
  const IwanTargets t = iwan_targets(m, sensors, modes, {});
  ASSERT_EQ(t.fitted.size(), 1u);
  ASSERT_EQ(t.fitted.front().curves.size(), 1u);
  EXPECT_EQ(t.fitted.front().curves.front().source, "a");
  ASSERT_EQ(t.hits_screened_out.size(), 2u);
  EXPECT_EQ(t.hits_screened_out[0], std::vector<std::string>{"b"});
  EXPECT_TRUE(t.hits_screened_out[1].empty());  // not fitted: keeps every point
  const std::string report = t.screen_report(modes);
  EXPECT_NE(
      report.find("mode 1: 10 of 20 points left out where other modes carry the joint "
                  "slip; every point but at most one of b, so that hit is left out of the fit"),
      std::string::npos)
      << report;
}

}  // namespace
}  // namespace jointlab::campaign
