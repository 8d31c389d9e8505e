#include "jointlab/correlate/measured_data.h"

#include <complex>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/correlate/two_chain.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::correlate {
namespace {

namespace fs = std::filesystem;

// Every backbone of band_outputs(), read at the edge (data::read_process_backbone) and made a
// curve at its sensor, as update-iwan's inputs read them.
std::vector<MeasuredBackbone> measured_backbones(const data::ProcessRun& run,
                                                 const std::vector<Sensor>& sensors, int band,
                                                 const std::vector<std::string>& channels) {
  std::vector<MeasuredBackbone> out;
  for (const BandOutput& b : band_outputs(run, sensors, band, channels))
    out.push_back(
        measured_backbone(data::read_process_backbone(run.dir / b.output->file), b.sensor));
  return out;
}

// A modes table read at the edge (data::read_modes_table against the sensors' channels) and
// realised (measured_modes), its mode numbers into `numbers` (if given).
MeasuredModes read_table_modes(const fs::path& path, const std::vector<Sensor>& sensors,
                               std::vector<int>* numbers) {
  const data::ModesTable table = data::read_modes_table(path, channels_of(sensors));
  if (numbers) *numbers = table.modes;
  return measured_modes(table, sensors);
}

fs::path fresh(const std::string& name) {
  const fs::path d = jointlab::testing::scratch_folder("jointlab_measured_data_test_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

// Two hits; band 1 seen by a5 and b2 (b2 reference in hit 2), band 2 without linear data.
const char* kSummary = R"({
  "program": "jointlab process", "amplitude_quantity": "velocity", "amplitude_unit": "m/s",
  "files": [
    {"file": "hit1.csv",
     "bands": [{"band": 1, "low_hz": 40, "high_hz": 70, "reference_channel": "a5",
                "linear_frequency_hz": 58.0, "linear_damping_ratio": 0.001,
                "operating_shape": [{"channel": "a5", "real_m": 1e-3, "imag_m": 0},
                                    {"channel": "x9", "real_m": 1, "imag_m": 0}]},
               {"band": 2, "low_hz": 80, "high_hz": 90, "reference_channel": "a5",
                "operating_shape": []}],
     "outputs": [{"channel": "a5", "band": 1, "file": "hit1.a5.band1.csv"},
                 {"channel": "b2", "band": 1, "file": null, "reason": "too short"}]},
    {"file": "hit2.csv",
     "bands": [{"band": 1, "low_hz": 40, "high_hz": 70, "reference_channel": "b2",
                "linear_frequency_hz": 58.2,
                "operating_shape": [{"channel": "a5", "real_m": 2e-3, "imag_m": 1e-4},
                                    {"channel": "b2", "real_m": -1e-4, "imag_m": 0}]}],
     "outputs": [{"channel": "a5", "band": 1, "file": "hit2.a5.band1.csv"},
                 {"channel": "b2", "band": 1, "file": "hit2.b2.band1.csv"}]}
  ]
})";

const char* kBackbone =
    "time_s,amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std,snr\n"
    "0.1,0.02,57.5,0.004,0.01,0.0001,40\n"
    "0.2,0.01,57.8,0.003,0.01,0.0001,30\n";

TEST(MeasuredData, ReadsSummaryModesAndBackbones) {
  const fs::path d = fresh("good");
  write(d / "summary.json", kSummary);
  for (const char* f : {"hit1.a5.band1.csv", "hit2.a5.band1.csv", "hit2.b2.band1.csv"})
    write(d / f, kBackbone);
  const std::vector<Sensor> sensors{{"b2", 7, 1.0}, {"a5", 5, -1.0}};
  const data::ProcessRun run = data::read_process_run(d);
  EXPECT_EQ(run.amplitude, Quantity::kVelocity);
  ASSERT_EQ(run.bands.size(), 3u);
  ASSERT_EQ(run.outputs.size(), 4u);
  EXPECT_EQ(run.outputs[1].file, "");
  std::vector<int> bands;
  const MeasuredModes m = measured_modes(run, sensors, &bands);
  ASSERT_EQ(bands, std::vector<int>{1});  // band 2 has no linear frequency
  EXPECT_DOUBLE_EQ(m.frequency_hz(0), 58.1);
  // The shape of hit 2 (both sensors measured), in sensor order.
  EXPECT_EQ(m.shapes(0, 0), std::complex<double>(-1e-4, 0));
  EXPECT_EQ(m.shapes(1, 0), std::complex<double>(2e-3, 1e-4));
  // Default: one channel for every hit, so that their curves share one amplitude. The hits'
  // reference channels differ (hit1 a5, hit2 b2); a5 has a backbone in both hits, b2 in hit2
  // alone, so both are read at a5 (each hit at its own reference channel mixed two amplitudes,
  // b2's the mode shape's ratio times a5's, in the hits' scatter summary).
  const BandChannel bc = band_channel(run, sensors, 1);
  EXPECT_EQ(bc.channel, "a5");
  EXPECT_EQ(bc.note,
            "band 1: the hits' reference channels differ (b2 in hit2; a5 in the other 1): every "
            "hit is read at a5 (a backbone there in 2 of 2 hits), so that their curves share one "
            "amplitude (--channel chooses another)");
  const auto refs = measured_backbones(run, sensors, 1, {});
  ASSERT_EQ(refs.size(), 2u);
  EXPECT_EQ(refs[0].sensor, 1);
  EXPECT_EQ(refs[1].sensor, 1);
  EXPECT_EQ(refs[0].amplitude(1), 0.01);
  EXPECT_EQ(refs[0].damping_std(0), 0.0001);
  // Each curve says which backbone file (so which hit) it is: compare() returns them by it.
  EXPECT_TRUE(refs[0].source.ends_with("hit1.a5.band1.csv")) << refs[0].source;
  EXPECT_TRUE(refs[1].source.ends_with("hit2.a5.band1.csv")) << refs[1].source;
  // A third hit naming b2 with a backbone at b2 alone: a5 and b2 each have backbones in 2 of the
  // 3 hits, b2 is named by 2: every hit is read at b2, and hit1, without one there, is named as
  // left out. A fourth naming a5 with backbones at both: a tie (3 hits each, named by 2 each),
  // b2 first in the sensors file; the note names a5's two hits once.
  {
    const fs::path d3 = fresh("three");
    std::string three = kSummary;
    const std::string tail = "\n  ]\n}";
    three.replace(three.rfind(tail), tail.size(), R"(,
    {"file": "hit3.csv",
     "bands": [{"band": 1, "low_hz": 40, "high_hz": 70, "reference_channel": "b2",
                "operating_shape": [{"channel": "b2", "real_m": -1e-4, "imag_m": 0}]}],
     "outputs": [{"channel": "b2", "band": 1, "file": "hit3.b2.band1.csv"}]}
  ]
})");
    std::string four = three;
    four.replace(four.rfind(tail), tail.size(), R"(,
    {"file": "hit4.csv",
     "bands": [{"band": 1, "low_hz": 40, "high_hz": 70, "reference_channel": "a5",
                "operating_shape": []}],
     "outputs": [{"channel": "a5", "band": 1, "file": "hit4.a5.band1.csv"},
                 {"channel": "b2", "band": 1, "file": "hit4.b2.band1.csv"}]}
  ]
})");
    write(d3 / "summary.json", three);
    for (const char* f :
         {"hit1.a5.band1.csv", "hit2.a5.band1.csv", "hit2.b2.band1.csv", "hit3.b2.band1.csv"})
      write(d3 / f, kBackbone);
    const BandChannel c3 = band_channel(data::read_process_run(d3), sensors, 1);
    EXPECT_EQ(c3.channel, "b2");
    EXPECT_NE(c3.note.find("every hit is read at b2 (a backbone there in 2 of 3 hits)"),
              std::string::npos)
        << c3.note;
    EXPECT_NE(c3.note.find("; one hit has no backbone there and is left out: hit1"),
              std::string::npos)
        << c3.note;
    const fs::path d4 = fresh("four");
    write(d4 / "summary.json", four);
    for (const char* f : {"hit1.a5.band1.csv", "hit2.a5.band1.csv", "hit2.b2.band1.csv",
                          "hit3.b2.band1.csv", "hit4.a5.band1.csv", "hit4.b2.band1.csv"})
      write(d4 / f, kBackbone);
    const BandChannel c4 = band_channel(data::read_process_run(d4), sensors, 1);
    EXPECT_EQ(c4.note,
              "band 1: the hits' reference channels differ (a5 in hit1, hit4; b2 in the other 2): "
              "every hit is read at b2 (a backbone there in 3 of 4 hits), so that their curves "
              "share one amplitude (--channel chooses another); one hit has no backbone there and "
              "is left out: hit1");
  }
  // Both hits naming b2, where hit1 has no backbone (its ring-down there failed): hit1 is left
  // out all the same, and named (the note was empty where the reference channels agreed).
  {
    const fs::path db = fresh("both_b2");
    std::string both = kSummary;
    const std::string ref = R"("band": 1, "low_hz": 40, "high_hz": 70, "reference_channel": "a5")";
    both.replace(both.find(ref), ref.size(),
                 R"("band": 1, "low_hz": 40, "high_hz": 70, "reference_channel": "b2")");
    write(db / "summary.json", both);
    for (const char* f : {"hit1.a5.band1.csv", "hit2.a5.band1.csv", "hit2.b2.band1.csv"})
      write(db / f, kBackbone);
    const data::ProcessRun rb = data::read_process_run(db);
    const BandChannel cb = band_channel(rb, sensors, 1);
    EXPECT_EQ(cb.channel, "b2");
    EXPECT_EQ(cb.note,
              "band 1: every hit is read at its reference channel b2 (a backbone there in 1 of 2 "
              "hits; --channel chooses another); one hit has no backbone there and is left out: "
              "hit1");
    EXPECT_EQ(measured_backbones(rb, sensors, 1, {}).size(), 1u);
  }
  EXPECT_EQ(measured_backbones(run, sensors, 1, {"a5"}).size(), 2u);
  EXPECT_NE(testing::input_error_of([&] {
              measured_backbones(run, sensors, 2, {});
            }).find("no backbone of band 2"),
            std::string::npos);
  EXPECT_NE(testing::input_error_of([&] {
              measured_backbones(run, sensors, 1, {"zz"});
            }).find("'zz' is not in the sensors file"),
            std::string::npos);
}

// A mode whose joint still microslips at the lowest amplitudes read: the two-joint-set beam's
// mode 2 (true linear frequency 246.62 Hz), two hits at 5 N and two at 15 N, each file's linear
// frequency read at its lowest amplitude with its stated uncertainty (process's summary.json).
// Before, the update fitted their mean 244.98 Hz at the default 0.1 % (0.245 Hz): the truth 6.7
// of those away, and the rivet stiffness came out 6.5 % low at +/- 1.54 % (z = -4.2). Now the
// lowest-level files' value with the spread's uncertainty: the truth within 3 sigmas (the
// defect is a value stated |z| > 3 from the truth), and a note that says why.
std::vector<LinearReading> beam_mode2() {
  return {{"node_5N_h1", 245.510911063, 0.00400495137233, 0.000220497225511},
          {"node_5N_h2", 245.478452086, 0.0039823860269, 0.000255372347025},
          {"node_15N_h1", 244.47747553, 0.0169183002537, 0.00101466899234},
          {"node_15N_h2", 244.463152645, 0.0259836358323, 0.00153038316168}};
}

TEST(MeasuredData, LinearFrequenciesThatFallWithTheLevelTakeTheLowestAndTheSpread) {
  const LinearSpread s = linear_spread("band 2", beam_mode2(), 1e-3, "m/s");
  EXPECT_TRUE(s.falls_with_level);
  // The two 5 N files' mean, to rounding.
  EXPECT_NEAR(s.frequency_hz, (245.510911063 + 245.478452086) / 2, 1e-9);
  EXPECT_NEAR(s.relative_std, (245.510911063 - 244.463152645) / s.frequency_hz, 1e-12);
  const double z = (246.62 - s.frequency_hz) / (s.relative_std * s.frequency_hz);
  EXPECT_LT(std::abs(z), 3) << z;
  for (const char* part : {"band 2: the 4 files' linear frequencies",
                           "node_15N_h2 244.46 Hz at "
                           "0.00153 m/s",
                           "the joint still slips at the lowest amplitudes read", "biased low",
                           "lowest-level files' 245.49 Hz", "0.43 %"})
    EXPECT_NE(s.note.find(part), std::string::npos) << part << "\n" << s.note;
  // Where the update's own uncertainty already covers the range: the mean, no note.
  const LinearSpread wide = linear_spread("band 2", beam_mode2(), 0.01);
  EXPECT_NEAR(wide.frequency_hz, 244.982497831, 1e-8);
  EXPECT_TRUE(wide.note.empty());
}

TEST(MeasuredData, LinearFrequenciesWithinTheirUncertaintyOrWithoutTrendKeepTheMean) {
  // Agreeing within their stated uncertainties: the mean, no uncertainty of its own.
  const LinearSpread agree = linear_spread(
      "band 1", {{"a", 100.0, 0.1, 1e-4}, {"b", 100.1, 0.1, 1e-3}, {"c", 99.95, 0.1, 1e-2}}, 1e-3);
  EXPECT_NEAR(agree.frequency_hz, (100.0 + 100.1 + 99.95) / 3, 1e-12);
  EXPECT_EQ(agree.relative_std, 0);
  EXPECT_TRUE(agree.note.empty());
  // Disagreeing at one level (no trend can show): the mean, widened to the files' standard
  // deviation (0.5 Hz over 100 Hz: 0.5 %).
  const LinearSpread same = linear_spread(
      "band 1", {{"a", 99.5, 0.01, 1e-3}, {"b", 100.5, 0.01, 1.2e-3}, {"c", 100.0, 0.01, 1e-3}},
      1e-3);
  EXPECT_FALSE(same.falls_with_level);
  EXPECT_NEAR(same.frequency_hz, 100.0, 1e-12);
  EXPECT_NEAR(same.relative_std, 0.005, 1e-12);
  EXPECT_NE(same.note.find("with no trend with the hit's level"), std::string::npos) << same.note;
  // Rising with the level is no joint slipping: the mean and its standard deviation.
  const LinearSpread rise = linear_spread(
      "band 1", {{"a", 99.0, 0.01, 1e-4}, {"b", 100.0, 0.01, 1e-3}, {"c", 101.0, 0.01, 1e-2}},
      1e-3);
  EXPECT_FALSE(rise.falls_with_level);
  EXPECT_NEAR(rise.frequency_hz, 100.0, 1e-12);
  EXPECT_NEAR(rise.relative_std, 0.01, 1e-12);
}

// From process's summary.json to the update: the band's files' stated uncertainties and lowest
// amplitudes are read, the band's frequency is the lowest-level files', and update_linear() weighs
// that band's residual by the spread's uncertainty (before: 0.1 %, whatever the files showed).
TEST(MeasuredData, ABandThatFallsWithTheLevelWidensTheLinearUpdate) {
  TwoChainParameters p;
  const model::Model model = two_chain_structure(p);
  // Two sensors on each chain: each mode's shape reads at two (a chain's mode does not move the
  // other chain), so the MAC pairs it with its own chain's mode; with one sensor on each, each
  // mode would be paired by frequency alone, and the chains' first modes fit as well crosswise.
  const std::vector<Sensor> sensors{
      {"a2", 2, 1.0}, {"a5", 5, 1.0}, {"b2", 8, 1.0}, {"b5", 11, 1.0}};
  const model::LinearModes lm = model::linear_modes(model.mass, model.linear_stiffness());
  const int first = lm.rigid_count;
  std::string files;
  // Band 1 (chain A's mode), four hits that fall with the level by 0.6 %; band 2 (chain B's),
  // exact in each.
  const double level[4] = {1e-4, 1.2e-4, 5e-4, 6e-4}, drop[4] = {0.002, 0.0021, 0.0078, 0.008};
  for (int h = 0; h < 4; ++h) {
    std::string bands;
    for (int b = 0; b < 2; ++b) {
      const int col = first + b;
      const double f = lm.frequency_hz(col) * (b == 0 ? 1 - drop[h] : 1.0);
      bands += fmt::format(
          R"({}{{"band": {}, "reference_channel": "a2", "linear_frequency_hz": {:.12g},
              "linear_frequency_std_hz": 0.001, "linear_fit_amplitude_min": {},
              "operating_shape": [{{"channel": "a2", "real_m": {:.12g}, "imag_m": 0}},
                                  {{"channel": "a5", "real_m": {:.12g}, "imag_m": 0}},
                                  {{"channel": "b2", "real_m": {:.12g}, "imag_m": 0}},
                                  {{"channel": "b5", "real_m": {:.12g}, "imag_m": 0}}]}})",
          b ? "," : "", b + 1, f, level[h], lm.shapes(2, col), lm.shapes(5, col), lm.shapes(8, col),
          lm.shapes(11, col));
    }
    files += fmt::format(R"({}{{"file": "hit{}.csv", "bands": [{}], "outputs": []}})", h ? "," : "",
                         h, bands);
  }
  const fs::path d = fresh("falls_with_level");
  write(d / "summary.json",
        fmt::format(R"({{"program": "jointlab process", "amplitude_quantity": "velocity",
                        "files": [{}]}})",
                    files));
  const data::ProcessRun run = data::read_process_run(d);
  EXPECT_EQ(run.bands[4].linear_fit_amplitude_min, 5e-4);  // hit 2, band 1
  EXPECT_EQ(run.bands[4].linear_frequency_std_hz, 0.001);
  const MeasuredModes m = measured_modes(run, sensors);
  const double f1 = lm.frequency_hz(first);
  EXPECT_NEAR(m.frequency_hz(0), f1 * (1 - 0.00205), 1e-9 * f1);
  EXPECT_NEAR(m.frequency_hz(1), lm.frequency_hz(first + 1), 1e-9 * f1);
  ASSERT_EQ(m.frequency_std.size(), 2);
  EXPECT_NEAR(m.frequency_std(0), 0.006 * f1 / m.frequency_hz(0), 1e-9);
  EXPECT_EQ(m.frequency_std(1), 0);
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_NE(m.warnings[0].find("band 1: the 4 files'"), std::string::npos) << m.warnings[0];
  LinearUpdateSummary s;
  update_linear(model, {"spring.ka", "spring.kb"}, sensors, m, LinearUpdateOptions{}, &s);
  // Each mode its own uncertainty: band 1's residual over its spread, band 2's over the update's.
  EXPECT_EQ(s.frequency_std, LinearUpdateOptions{}.frequency_std) << s.report();
  ASSERT_EQ(s.mode_frequency_std.size(), 2);
  EXPECT_NEAR(s.mode_frequency_std(0), m.frequency_std(0), 1e-15);
  EXPECT_EQ(s.mode_frequency_std(1), LinearUpdateOptions{}.frequency_std);
  ASSERT_FALSE(s.warnings.empty());
  EXPECT_EQ(s.warnings[0], m.warnings[0]);
}

TEST(MeasuredData, PairsTheBandWithTheModelModeByShape) {
  TwoChainParameters p;
  const model::Model model = two_chain_structure(p);
  const std::vector<Sensor> sensors{
      {"a2", 2, 1.0}, {"a5", 5, 1.0}, {"b2", 8, 1.0}, {"b5", 11, 1.0}};
  // Measured "band 7": chain B's first mode shape (model mode 2) at the sensors.
  MeasuredModes m;
  m.frequency_hz = Eigen::VectorXd::Constant(1, 59.9);
  m.shapes = Eigen::MatrixXcd::Zero(4, 1);
  m.shapes(2, 0) = 0.6;
  m.shapes(3, 0) = 1.0;
  EXPECT_EQ(measured_mode_of(model, sensors, m, 2, 0.6), 0);
  EXPECT_EQ(measured_mode_of(model, sensors, m, 1, 0.6), -1);
}

TEST(MeasuredData, DefectsNameFileAndField) {
  const fs::path d = fresh("bad");
  EXPECT_NE(
      testing::input_error_of([&] { data::read_process_run(d / "none"); }).find("not a directory"),
      std::string::npos);
  EXPECT_NE(
      testing::input_error_of([&] { data::read_process_run(d); }).find("summary.json: missing"),
      std::string::npos);
  write(d / "summary.json", "{\"amplitude_quantity\": \"velocity\", \"files\": [{\"file\": 3}]}");
  EXPECT_NE(testing::input_error_of([&] {
              data::read_process_run(d);
            }).find("summary.json: files[0].file: expected a string, found a number"),
            std::string::npos);
  write(d / "summary.json", "{\"amplitude_quantity\": \"velocity\", \"files\": [}");
  EXPECT_NE(
      testing::input_error_of([&] { data::read_process_run(d); }).find("summary.json:1: column"),
      std::string::npos);
  write(d / "b.csv", "time_s,amplitude,frequency_hz,damping_ratio,frequency_std_hz\n");
  EXPECT_NE(testing::input_error_of([&] {
              data::read_process_backbone(d / "b.csv");
            }).find("b.csv:1: no column 'damping_std'"),
            std::string::npos);
  write(d / "b.csv", std::string(kBackbone) + "0.3,-1,57,0.003,0.01,0.0001,20\n");
  EXPECT_NE(testing::input_error_of([&] {
              data::read_process_backbone(d / "b.csv");
            }).find("b.csv:4: amplitude must be > 0"),
            std::string::npos);
  write(d / "b.csv", std::string(kBackbone) + "0.3,0.01,nan,0.003,0.01,0.0001,20\n");
  EXPECT_NE(
      testing::input_error_of([&] { data::read_process_backbone(d / "b.csv"); }).find("b.csv:4:"),
      std::string::npos);
  // process's std columns are k sigma, k in its coverage_factor column: read with the curve
  // (none: 1), one number >= 1.
  write(d / "b.csv", kBackbone);
  EXPECT_EQ(data::read_process_backbone(d / "b.csv").coverage_factor, 1.0);
  const std::string head =
      "time_s,amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std,coverage_factor\n";
  write(d / "k.csv",
        head + "0.1,0.02,57.5,0.004,0.03,0.0003,3\n0.2,0.01,57.8,0.003,0.03,0.0003,3\n");
  const data::BackboneTable k = data::read_process_backbone(d / "k.csv");
  EXPECT_EQ(k.coverage_factor, 3.0);
  EXPECT_EQ(k.frequency_std_hz(0), 0.03);  // as written
  write(d / "k.csv", head + "0.1,0.02,57.5,0.004,0.03,0.0003,0.5\n");
  EXPECT_NE(testing::input_error_of([&] {
              data::read_process_backbone(d / "k.csv");
            }).find("k.csv:2: coverage_factor '0.5' must be a finite number >= 1"),
            std::string::npos);
}

// The amplitudes of a process folder are read as SI: a summary.json naming another amplitude
// unit (hand-edited, or from another tool) is refused naming the field, not read as SI.
TEST(MeasuredData, AnAmplitudeUnitOtherThanSiIsRefused) {
  const fs::path d = fresh("unit");
  std::string summary = kSummary;
  summary.replace(summary.find("\"m/s\""), 5, "\"mm/s\"");
  write(d / "summary.json", summary);
  const std::string m = testing::input_error_of([&] { data::read_process_run(d); });
  EXPECT_NE(m.find("summary.json: amplitude_unit: \"mm/s\": the backbones' amplitudes are read "
                   "as SI (m/s for velocity)"),
            std::string::npos)
      << m;
  summary = kSummary;  // the SI unit, or none: read
  write(d / "summary.json", summary);
  EXPECT_EQ(data::read_process_run(d).amplitude, Quantity::kVelocity);
}

// Rows of a process backbone marked as not the mode's own (harmonic n > 1, exchange 1, whose
// apparent damping may be negative) are no target of the update: skipped, not refused.
TEST(MeasuredData, SkipsBackboneRowsMarkedHarmonicOrExchange) {
  const fs::path d = fresh("marked");
  write(d / "b.csv",
        "time_s,amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std,harmonic,"
        "exchange,coverage_factor\n"
        "0.1,0.03,57.1,-0.001,0.01,0.0001,0,1,3\n"
        "0.2,0.02,114.9,0.006,0.01,0.0001,2,0,3\n"
        "0.3,0.01,57.8,0.003,0.01,0.0001,0,0,3\n");
  const data::BackboneTable b = data::read_process_backbone(d / "b.csv");
  ASSERT_EQ(b.amplitude.size(), 1);
  EXPECT_EQ(b.amplitude(0), 0.01);
  EXPECT_EQ(b.damping_ratio(0), 0.003);
  ASSERT_EQ(b.time_s.size(), 1);  // the campaign's curves keep each point's time
  EXPECT_EQ(b.time_s(0), 0.3);
  EXPECT_TRUE(b.has_uncertainty);
  // Every point marked: a table of no point, the caller's to judge (a hit's curve is left empty,
  // a stepped-sine backbone refused naming the file), not an error of the file.
  write(d / "all.csv",
        "time_s,amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std,harmonic\n"
        "0.1,0.03,114.2,0.004,0.01,0.0001,2\n");
  EXPECT_EQ(data::read_process_backbone(d / "all.csv").size(), 0);
}

TEST(MeasuredData, ReadsAPlainModesTable) {
  const fs::path d = fresh("table");
  const std::vector<Sensor> sensors{{"b2", 7, 1.0}, {"a5", 5, -1.0}, {"a1", 1, 1.0}};
  write(d / "modes.csv", "# two modes\nmode,frequency_hz,a5,b2\n1,57.9,0.5,-0.25\n3,120,,1\n");
  std::vector<int> numbers;
  const MeasuredModes m = read_table_modes(d / "modes.csv", sensors, &numbers);
  ASSERT_EQ(m.frequency_hz.size(), 2);
  EXPECT_EQ(numbers, (std::vector<int>{1, 3}));
  EXPECT_EQ(m.frequency_hz(1), 120.0);
  ASSERT_EQ(m.shapes.rows(), 3);
  // Sensor order (b2, a5, a1); empty cells and sensors without a column are 0.
  EXPECT_EQ(m.shapes(0, 0), std::complex<double>(-0.25, 0));
  EXPECT_EQ(m.shapes(1, 0), std::complex<double>(0.5, 0));
  EXPECT_EQ(m.shapes(2, 0), std::complex<double>(0, 0));
  EXPECT_EQ(m.shapes(1, 1), std::complex<double>(0, 0));
  write(d / "bad1.csv", "mode,f\n1,2\n");
  EXPECT_NE(testing::input_error_of([&] {
              read_table_modes(d / "bad1.csv", sensors, nullptr);
            }).find("bad1.csv:1"),
            std::string::npos);
  // A header that differs in case is read (Frequency_Hz names its unit);
  // ModesTableFromAnotherTool.FrequencyHeadersWithTheirUnitAreRead has the rest.
  write(d / "caps.csv", "Mode,Frequency_Hz\n1,2\n");
  EXPECT_EQ(read_table_modes(d / "caps.csv", sensors, nullptr).frequency_hz(0), 2.0);
  write(d / "bad2.csv", "mode,frequency_hz,zz\n1,2,3\n");
  EXPECT_NE(testing::input_error_of([&] {
              read_table_modes(d / "bad2.csv", sensors, nullptr);
            }).find("'zz' is not a sensor channel"),
            std::string::npos);
  write(d / "bad3.csv", "mode,frequency_hz\n1,2\n1,3\n");
  EXPECT_NE(testing::input_error_of([&] {
              read_table_modes(d / "bad3.csv", sensors, nullptr);
            }).find("bad3.csv:3: mode 1 twice"),
            std::string::npos);
  write(d / "bad4.csv", "mode,frequency_hz\n1,-2\n");
  EXPECT_NE(testing::input_error_of([&] {
              read_table_modes(d / "bad4.csv", sensors, nullptr);
            }).find("bad4.csv:2"),
            std::string::npos);
}

// A test-modal tool's complex shapes: a real shape y times e^{i phi} written as a+bi, a-bj,
// (a+bj) and (a,b) cells, as _re/_im column pairs and tab-separated comes back as y up to sign
// (written with 17 digits: 1e-12 relative), MPC 1, no warning; (1, e^{i alpha}) has MPC
// cos^2 alpha (mac.h): alpha = 26.57 deg gives 0.800, warned naming the mode, and 60 deg gives
// 0.250, refused naming it.
TEST(MeasuredData, ComplexShapeCellsAreRealisedAndTheirMpcJudged) {
  const fs::path d = fresh("complex");
  const std::vector<Sensor> sensors{{"s1", 1, 1.0}, {"s2", 2, 1.0}, {"s3", 3, 1.0}};
  const Eigen::Vector3d y(0.4, -1.0, 0.25);
  const double phi = 2.2;  // the largest entry, -1, turns positive: -y
  const auto z = [&](int k) { return std::polar(1.0, phi) * y(k); };
  const auto ij = [&](int k, char unit) {
    return fmt::format("{:.17g}{:+.17g}{}", z(k).real(), z(k).imag(), unit);
  };
  const auto pair = [&](int k) {
    return fmt::format("({:.17g},{:.17g})", z(k).real(), z(k).imag());
  };
  const auto expect_minus_y = [&](const MeasuredModes& m, Eigen::Index col) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(m.shapes(k, col).real(), -y(k), 1e-12) << k;
      EXPECT_EQ(m.shapes(k, col).imag(), 0.0) << k;
    }
  };
  write(d / "cells.csv",
        fmt::format("mode,frequency_hz,s1,s2,s3\n1,50,{},{},\"{}\"\n2,80,({}),{},{}\n", ij(0, 'i'),
                    ij(1, 'j'), pair(2), ij(0, 'j'), ij(1, 'I'), ij(2, 'i')));
  const MeasuredModes cells = read_table_modes(d / "cells.csv", sensors, nullptr);
  expect_minus_y(cells, 0);
  expect_minus_y(cells, 1);
  EXPECT_TRUE(cells.warnings.empty());
  write(
      d / "parts.tsv",
      fmt::format("mode\tfrequency_hz\ts1_re\ts1_im\ts2 Real\ts2 Imag\ts3\n1\t50\t{:.17g}\t{:.17g}"
                  "\t{:.17g}\t{:.17g}\t{}\n",
                  z(0).real(), z(0).imag(), z(1).real(), z(1).imag(), pair(2)));
  expect_minus_y(read_table_modes(d / "parts.tsv", sensors, nullptr), 0);
  // MPC cos^2 alpha at two sensors, the third not measured (left out, still 0).
  const auto two = [&](double alpha) {
    const std::complex<double> w = std::polar(1.0, alpha);
    return fmt::format("mode,frequency_hz,s1,s2\n3,50,1,{:.17g}{:+.17g}i\n", w.real(), w.imag());
  };
  write(d / "poor.csv", two(std::atan(0.5)));  // cos^2 = 0.8
  const MeasuredModes poor = read_table_modes(d / "poor.csv", sensors, nullptr);
  ASSERT_EQ(poor.warnings.size(), 1u);
  EXPECT_NE(poor.warnings[0].find("poor.csv:2: mode 3's shape is complex: its modal phase "
                                  "collinearity MPC is 0.800"),
            std::string::npos)
      << poor.warnings[0];
  EXPECT_EQ(poor.shapes(2, 0), std::complex<double>(0.0));
  EXPECT_NEAR(poor.shapes(0, 0).real(), poor.shapes(1, 0).real(), 1e-12);  // cos(alpha/2) (1, 1)
  write(d / "bad.csv", two(std::numbers::pi / 3));                         // cos^2 = 0.25
  EXPECT_NE(testing::input_error_of([&] { read_table_modes(d / "bad.csv", sensors, nullptr); })
                .find("bad.csv:2: mode 3's shape is complex: its modal phase collinearity MPC is "
                      "0.250"),
            std::string::npos);
  // Defects name the column or cell.
  const auto error_of = [&](const std::string& file, const std::string& text) {
    write(d / file, text);
    return testing::input_error_of([&] { read_table_modes(d / file, sensors, nullptr); });
  };
  EXPECT_NE(error_of("lone.csv", "mode,frequency_hz,s1_re\n1,50,1\n")
                .find("lone.csv:1: column 's1_re' has no imaginary part beside it (s1_im)"),
            std::string::npos);
  EXPECT_NE(error_of("half.csv", "mode,frequency_hz,s1_re,s1_im\n1,50,1,\n")
                .find("half.csv:2: sensor s1: its real part is given and its imaginary part empty"),
            std::string::npos);
  EXPECT_NE(error_of("twice.csv", "mode,frequency_hz,s1,s1_im,s1_re\n1,50,1,1,1\n")
                .find("twice.csv:1: column 's1_im': sensor channel s1 twice"),
            std::string::npos);
  EXPECT_NE(error_of("mag.csv", "mode,frequency_hz,s1_mag,s1_phase\n1,50,1,0\n")
                .find("column 's1_mag': magnitude or phase columns are not read"),
            std::string::npos);
  EXPECT_NE(error_of("word.csv", "mode,frequency_hz,s1\n1,50,1+2k\n")
                .find("word.csv:2: shape entry '1+2k' of column 's1' is not a number"),
            std::string::npos);
  EXPECT_NE(error_of("split.csv", "mode,frequency_hz,s1\n1,50,(1,2)\n")
                .find("split.csv:2: 4 cells where the header has 3 (a complex cell written "
                      "(re,im) splits at its comma"),
            std::string::npos);
}

TEST(MeasuredData, ASizedBackboneHasEveryColumnAtThatLengthAndZero) {
  const MeasuredBackbone b = sized_backbone(BackboneKind::kSteppedSine, 3, 4);
  EXPECT_EQ(b.kind, BackboneKind::kSteppedSine);
  EXPECT_EQ(b.sensor, 3);
  for (const Eigen::VectorXd* v :
       {&b.amplitude, &b.frequency_hz, &b.damping_ratio, &b.frequency_std_hz, &b.damping_std})
    EXPECT_EQ(*v, Eigen::VectorXd::Zero(4));
}

// A band whose shape is mode 1's with one sensor's sign wrong: its MAC with mode 1 is low, and
// the match names that sensor, whose reversal gives MAC 1 (to rounding); the right shape
// names none.
TEST(MeasuredData, ModeShapeMatchNamesASensorWhoseReversalExplainsALowMac) {
  TwoChainParameters p;
  const model::Model m = two_chain_structure(p);
  std::vector<Sensor> sensors;
  for (const int dof : {0, 2, 3, 5}) sensors.push_back({fmt::format("s{}", dof), dof, 1.0});
  const model::LinearModes modes = model::linear_modes(m.mass, m.linear_stiffness());
  const int elastic = modes.size() - modes.rigid_count;
  const Eigen::VectorXd at = shapes_at_sensors(sensors, modes.shapes.rightCols(elastic)).col(0);
  MeasuredModes measured;
  measured.frequency_hz = Eigen::VectorXd::Constant(1, modes.frequency_hz(modes.rigid_count));
  measured.shapes = at.cast<std::complex<double>>();
  ModeShapeMatch right = mode_shape_match(m, sensors, measured, 0, 1);
  EXPECT_NEAR(right.mac, 1.0, 1e-12);
  EXPECT_TRUE(right.reversed.empty());
  Eigen::Index top = 0;
  at.cwiseAbs().maxCoeff(&top);
  measured.shapes(top, 0) *= -1.0;
  const ModeShapeMatch wrong = mode_shape_match(m, sensors, measured, 0, 1);
  ASSERT_LT(wrong.mac, 0.6);
  EXPECT_EQ(wrong.reversed, std::vector<int>{static_cast<int>(top)});
  EXPECT_NEAR(wrong.reversed_mac, 1.0, 1e-12);
}

// The report's amplitude line: a measured amplitude is zero to peak, and a table whose header
// gives no unit is named with the SI unit assumed (an acceleration table in g read so gave F_S
// 4.08 N against 40, exit 0, every check passed: the scale cannot be seen in the fit).
TEST(MeasuredData, TheAmplitudeLineSaysZeroToPeakAndTheUnitAssumed) {
  const std::string given = amplitude_reading(1, "acceleration", false, "9003:3", "9003:3", {});
  EXPECT_NE(given.find("zero to peak"), std::string::npos) << given;
  EXPECT_EQ(given.find("assumed"), std::string::npos) << given;
  const std::string none =
      amplitude_reading(1, "acceleration", false, "9003:3", "9003:3", {"hit1.csv", "hit2.csv"});
  EXPECT_NE(none.find("hit1.csv, hit2.csv give no unit in the amplitude header, so m/s^2 is "
                      "assumed"),
            std::string::npos)
      << none;
  const std::string displacement =
      amplitude_reading(1, "displacement", false, "9003:3", "9003:3", {"hit.csv"});
  EXPECT_NE(displacement.find("hit.csv gives no unit in the amplitude header, so m is assumed"),
            std::string::npos)
      << displacement;
}

// Review findings on linear_spread (helper-52): process states k sigma (summary.json's
// coverage_factor), which the agreement test must divide out; the chi-square is about the
// weighted mean; a slope whose variance comes from the residuals is judged by Student's t.
TEST(MeasuredData, TheSpreadsTestsReadOneSigmaTheWeightedMeanAndStudentsT) {
  // Two files 0.6 Hz apart at 0.08 Hz one sigma, written as process writes them, 0.24 Hz at k 3:
  // read as one sigma the chi-square is 3.1 and they agreed; it is 28, and they disagree.
  const auto modes_with = [](const std::string& coverage, double half_apart = 0.3,
                             double stated = 0.24, double frequency_std = 1e-3) {
    std::string files;
    for (int h = 0; h < 2; ++h) {
      files += fmt::format(
          R"({}{{"file": "hit{}.csv", "bands": [{{"band": 1, "reference_channel": "a",
              "linear_frequency_hz": {}, "linear_frequency_std_hz": {},
              "operating_shape": [{{"channel": "a", "real_m": 1, "imag_m": 0}}]}}],
              "outputs": []}})",
          h ? "," : "", h, 245.0 + (h ? half_apart : -half_apart), stated);
    }
    const fs::path d = fresh("coverage_factor" + coverage);
    write(d / "summary.json",
          fmt::format(R"({{"program": "jointlab process", "amplitude_quantity": "velocity",
                          {}"files": [{}]}})",
                      coverage.empty() ? "" : "\"coverage_factor\": " + coverage + ", ", files));
    return measured_modes(data::read_process_run(d), {{"a", 0, 1.0}}, nullptr, frequency_std);
  };
  EXPECT_EQ(modes_with("1").frequency_std(0), 0);  // 0.24 Hz as one sigma: they agree
  EXPECT_EQ(modes_with("").frequency_std(0), 0);   // no coverage_factor: one sigma
  const MeasuredModes k3 = modes_with("3");
  EXPECT_NEAR(k3.frequency_std(0), 0.6 / std::sqrt(2.0) / 245.0, 1e-12);  // their std
  // Files 0.2 Hz apart (0.058 %) at 0.01 Hz: within update-linear's default 0.1 %, no note; the
  // update's own --frequency-std 0.05 % reaches the test (it was always judged against 0.1 %).
  EXPECT_TRUE(modes_with("3", 0.1, 0.03).warnings.empty());
  EXPECT_EQ(modes_with("3", 0.1, 0.03, 5e-4).warnings.size(), 1u);
  // Two precise files that agree and a third ten times less precise 0.5 Hz off: about the
  // weighted mean the chi-square is 0.25 (they agree); about the plain mean it was 555.
  const LinearSpread w = linear_spread(
      "band 1", {{"a", 100.0, 0.01, 0}, {"b", 100.0, 0.01, 0}, {"c", 100.5, 1.0, 0}}, 1e-3);
  EXPECT_EQ(w.relative_std, 0);
  EXPECT_TRUE(w.note.empty());
  // Three levels without stated uncertainties, a slope of t = -8.7 from its residuals: beyond
  // the normal's 3 (falling, before), within Student's t with 1 degree of freedom (31.8).
  const LinearSpread t = linear_spread(
      "band 1", {{"a", 100.3, 0, 1e-4}, {"b", 100.0, 0, 2e-4}, {"c", 99.8, 0, 4e-4}}, 1e-3);
  EXPECT_FALSE(t.falls_with_level);
  EXPECT_NEAR(t.frequency_hz, (100.3 + 100.0 + 99.8) / 3, 1e-12);
  EXPECT_GT(t.relative_std, 1e-3);  // they disagree all the same: their spread
}

}  // namespace
}  // namespace jointlab::correlate
