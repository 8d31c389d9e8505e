// End-to-end tests of `jointlab update-linear` and `jointlab update-iwan`: a two-chain model
// (correlate/two_chain.h) written as a model file, `process`-shaped measured data synthesised
// from known parameters (summary.json and band CSVs), updates started 3-10x off the truth.
#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/correlate/qsma_at.h"
#include "jointlab/correlate/two_chain.h"
#include "jointlab/data/json_writer.h"
#include "jointlab/data/matrix_market.h"
#include "jointlab/model/joint_condensation.h"
#include "jointlab/model/linear_modes.h"
#include "jointlab/model/model_file.h"
#include "jointlab/model/model_file_writer.h"
#include "jointlab/tests/cli.h"
#include "jointlab/tests/test_util.h"

namespace jointlab {
namespace {

namespace fs = std::filesystem;
using correlate::AmplitudeQuantity;
using correlate::Sensor;

// Sensors on A1, A2, A3, A5, B1, B2, B3, B5 (a5 reads with the opposite sign).
const std::vector<Sensor> kSensors{{"a1", 1, 1.0}, {"a2", 2, 1.0}, {"a3", 3, 1.0}, {"a5", 5, -1.0},
                                   {"b1", 7, 1.0}, {"b2", 8, 1.0}, {"b3", 9, 1.0}, {"b5", 11, 1.0}};

std::string sensors_text() {
  std::string t = "channel,dof,sign\n";
  for (const Sensor& s : kSensors) t += fmt::format("{},{},{}\n", s.channel, s.dof, s.sign);
  return t;
}

// Writes the model's matrices and a model file referencing them into dir.
std::string write_model(const fs::path& dir, const model::Model& m, const std::string& name) {
  data::write_matrix_market(dir / "M.mtx", m.mass, true);
  data::write_matrix_market(dir / "K.mtx", m.stiffness, true);
  model::write_model_file(dir / name, m, {dir / "M.mtx", dir / "K.mtx", {}});
  return (dir / name).string();
}

// One hit of `process` output: linear data per band and backbone files.
struct Hit {
  std::string source;
  std::vector<double> frequency_hz;                    // per band
  std::vector<Eigen::VectorXcd> shape;                 // per band, at kSensors
  std::vector<std::string> reference;                  // per band
  std::vector<correlate::MeasuredBackbone> backbones;  // at their sensor
  std::vector<int> backbone_bands;                     // per backbone (none: band 1)
};

void write_process_output(const fs::path& dir, const std::vector<Hit>& hits) {
  fs::create_directories(dir);
  data::JsonWriter j;
  j.begin_object();
  j.key("program").value("jointlab process");
  j.key("method").value("hilbert");
  j.key("amplitude_quantity").value("velocity");
  j.key("amplitude_unit").value("m/s");
  j.key("files").begin_array();
  for (const Hit& h : hits) {
    j.begin_object();
    j.key("file").value(h.source);
    j.key("bands").begin_array();
    for (size_t b = 0; b < h.frequency_hz.size(); ++b) {
      j.begin_object();
      j.key("band").value(static_cast<int>(b) + 1);
      j.key("low_hz").value(0.9 * h.frequency_hz[b]);
      j.key("high_hz").value(1.1 * h.frequency_hz[b]);
      j.key("reference_channel").value(h.reference[b]);
      j.key("linear_frequency_hz").value(h.frequency_hz[b]);
      j.key("linear_damping_ratio").value(0.001);
      j.key("operating_shape").begin_array();
      for (size_t s = 0; s < kSensors.size(); ++s) {
        j.begin_object();
        j.key("channel").value(kSensors[s].channel);
        j.key("real_m").value(h.shape[b](static_cast<Eigen::Index>(s)).real());
        j.key("imag_m").value(h.shape[b](static_cast<Eigen::Index>(s)).imag());
        j.end_object();
      }
      j.end_array();
      j.end_object();
    }
    j.end_array();
    j.key("outputs").begin_array();
    for (size_t bi = 0; bi < h.backbones.size(); ++bi) {
      const correlate::MeasuredBackbone& c = h.backbones[bi];
      const int band = bi < h.backbone_bands.size() ? h.backbone_bands[bi] : 1;
      const std::string channel = kSensors[static_cast<size_t>(c.sensor)].channel;
      const std::string file =
          fmt::format("{}.{}.band{}.csv", fs::path(h.source).stem().string(), channel, band);
      j.begin_object();
      j.key("channel").value(channel);
      j.key("measured_quantity").value("acceleration");
      j.key("band").value(band);
      j.key("noise_floor_m").value(1e-9);
      j.key("file").value(file);
      j.key("points").value(static_cast<long>(c.amplitude.size()));
      j.end_object();
      // As process writes it: time increasing, amplitude falling.
      std::string t =
          "time_s,amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std,snr\n";
      const Eigen::Index n = c.amplitude.size();
      for (Eigen::Index i = n - 1; i >= 0; --i) {
        t += fmt::format("{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},50\n", 0.01 * (n - 1 - i),
                         c.amplitude(i), c.frequency_hz(i), c.damping_ratio(i),
                         c.frequency_std_hz(i), c.damping_std(i));
      }
      testing::write_text((dir / file).string(), t);
    }
    j.end_array();
    j.end_object();
  }
  j.end_array();
  j.end_object();
  testing::write_text((dir / "summary.json").string(), j.str());
}

// Linear data of the first `count` elastic modes of `m` as one hit.
Hit linear_hit(const model::Model& m, int count) {
  const model::LinearModes modes = model::linear_modes(m.mass, m.linear_stiffness());
  Hit h;
  h.source = "hit1.csv";
  const std::complex<double> scale(2e-3, 5e-4);  // any complex scaling: MAC ignores it
  for (int k = 0; k < count; ++k) {
    const int col = modes.rigid_count + k;
    h.frequency_hz.push_back(modes.frequency_hz(col));
    Eigen::VectorXcd s(static_cast<Eigen::Index>(kSensors.size()));
    Eigen::Index best = 0;
    for (size_t i = 0; i < kSensors.size(); ++i) {
      s(static_cast<Eigen::Index>(i)) =
          scale * kSensors[i].sign * modes.shapes(kSensors[i].dof, col);
      if (std::abs(s(static_cast<Eigen::Index>(i))) > std::abs(s(best)))
        best = static_cast<Eigen::Index>(i);
    }
    h.shape.push_back(s);
    h.reference.push_back(kSensors[static_cast<size_t>(best)].channel);
  }
  return h;
}

// parameters.csv as name -> cells.
std::map<std::string, std::vector<std::string>> read_parameters(const fs::path& path) {
  std::ifstream in(path);
  std::map<std::string, std::vector<std::string>> out;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(c);
    if (!line.empty() && line.back() == ',') cells.push_back("");  // a trailing empty cell
    out[cells.at(0)] = cells;
  }
  return out;
}

double joint_stiffness(const model::Model& m, const std::string& element) {
  for (const model::Joint& j : m.joints) {
    if (j.element == element) return j.stiffness;
  }
  return 0;
}

// Exactly one line on stderr and exit status 2 (the contract's for bad input).
void expect_one_line_error(const std::string& args, const std::string& says) {
  const testing::CommandResult r = testing::run_jointlab(args);
  EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(says), std::string::npos) << args << "\n" << r.err;
}

TEST(UpdateCli, LinearRecoversIdentifiableStiffnessesAndReportsTheFlatOne) {
  const fs::path dir = testing::scratch_dir("update_linear_cli");
  correlate::TwoChainParameters truth;
  write_process_output(dir / "measured", {linear_hit(correlate::two_chain_structure(truth), 6)});
  testing::write_text((dir / "sensors.csv").string(), sensors_text());
  correlate::TwoChainParameters start = truth;
  start.ka *= 10;  // across the crossing of chain A's and chain B's first modes
  start.kb /= 3;
  start.kflat /= 5;
  const std::string model = write_model(dir, correlate::two_chain_structure(start), "start.toml");
  const std::string common = fmt::format("--measured {} --sensors {}", (dir / "measured").string(),
                                         (dir / "sensors.csv").string());
  const testing::CommandResult r = testing::run_jointlab(
      fmt::format("update-linear {} {} --set spring.ka --set spring.kb --set spring.kflat "
                  "--tolerance 0.005 --out {}",
                  model, common, (dir / "out").string()));
  ASSERT_EQ(r.status, 0) << r.err;
  RecordProperty("report", r.out);
  EXPECT_NE(r.out.find("FLAT"), std::string::npos) << r.out;
  const auto p = read_parameters(dir / "out" / "parameters.csv");
  ASSERT_EQ(p.size(), 3u);
  EXPECT_TRUE(testing::Close(std::stod(p.at("spring.ka").at(2)), truth.ka, 0.02));
  EXPECT_TRUE(testing::Close(std::stod(p.at("spring.kb").at(2)), truth.kb, 0.02));
  EXPECT_EQ(p.at("spring.ka").at(5), "1");
  EXPECT_EQ(p.at("spring.kflat").at(5), "0");           // flat: not identifiable
  EXPECT_GT(std::stod(p.at("spring.kflat").at(6)), 0);  // lowered within the tolerance
  // The updated model file reads back with the updated stiffnesses.
  const model::Model updated = model::read_model(dir / "out" / "model.toml");
  EXPECT_TRUE(testing::Close(joint_stiffness(updated, "spring.ka"), truth.ka, 0.02));
  EXPECT_TRUE(testing::Close(joint_stiffness(updated, "spring.kb"), truth.kb, 0.02));
  std::ifstream history(dir / "out" / "history.csv");
  std::string header;
  std::getline(history, header);
  EXPECT_EQ(header, "iteration,objective,spring.ka,spring.kb,spring.kflat");

  // Bad input: one line, non-zero exit.
  expect_one_line_error(fmt::format("update-linear {}/none.toml {} --set spring.ka --out {}",
                                    dir.string(), common, (dir / "bad").string()),
                        "none.toml");
  expect_one_line_error(fmt::format("update-linear {} {} --set spring.nope --out {}", model, common,
                                    (dir / "bad").string()),
                        "spring.nope");
  testing::write_text((dir / "bad_sensors.csv").string(), "channel,dof\na1,1\nb9,99\n");
  expect_one_line_error(
      fmt::format("update-linear {} --measured {} --sensors {} --set spring.ka --out {}", model,
                  (dir / "measured").string(), (dir / "bad_sensors.csv").string(),
                  (dir / "bad").string()),
      "bad_sensors.csv:3");
  fs::create_directories(dir / "broken");
  testing::write_text((dir / "broken" / "summary.json").string(), "{\"files\": [1, 2,]}");
  expect_one_line_error(
      fmt::format("update-linear {} --measured {} --sensors {} --set spring.ka --out {}", model,
                  (dir / "broken").string(), (dir / "sensors.csv").string(),
                  (dir / "bad").string()),
      "summary.json:1: column");
  expect_one_line_error(
      fmt::format("update-linear {} --measured {} --sensors {} --set spring.ka --out {}", model,
                  (dir / "nothing").string(), (dir / "sensors.csv").string(),
                  (dir / "bad").string()),
      "nothing");
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// CSV file as rows of cells (header included).
std::vector<std::vector<std::string>> read_csv_cells(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> out;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(c);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    out.push_back(cells);
  }
  return out;
}

// The paper's rule from the command line, and the same update from a plain modes table made
// from the process run: the table carries the run's frequencies and its shapes made real
// (the run's complex scaling divided out), so the two updates must agree to solver precision.
// Pairs that cannot be decided, and shapes that cannot pair, stop the command with exit 2.
// One sensor per chain (a0, b0) and a test shape [1, 1]: MAC 0.5 with every mode of either
// chain (threshold 0.4 here). At 58.856 Hz, the geometric mean of chain A's first mode (57.898
// Hz) and chain B's (59.830 Hz), frequency cannot tell them apart either, and ka can bring the
// one, kb the other, exactly onto it: both pairings fit to a cost of about 0, the data cannot
// decide, and the command says so in its last line after its progress lines. An all-zero shape
// is refused before any work, with one line naming its mode.
TEST(UpdateCli, UndecidablePairsAndZeroShapesAreRefused) {
  const fs::path dir = testing::scratch_dir("update_linear_undecidable");
  const std::string model = write_model(dir, correlate::two_chain_structure(), "model.toml");
  std::ofstream(dir / "sensors.csv") << "channel,dof\na0,0\nb0,6\n";
  std::ofstream(dir / "tie.csv") << "mode,frequency_hz,a0,b0\n1,58.856,1,1\n";
  const std::string common = fmt::format("--sensors {} --set spring.ka --set spring.kb --out {}",
                                         (dir / "sensors.csv").string(), (dir / "out").string());
  const testing::CommandResult r =
      testing::run_jointlab(fmt::format("update-linear {} --modes-table {} {} --mac-threshold 0.4",
                                        model, (dir / "tie.csv").string(), common));
  EXPECT_EQ(r.status, 2) << r.out << r.err;
  const size_t last = r.err.rfind('\n', r.err.size() - 2);
  const std::string last_line = r.err.substr(last == std::string::npos ? 0 : last + 1);
  EXPECT_NE(last_line.find("the pairs cannot be decided: at the start, test mode 1 (58.856 Hz)"),
            std::string::npos)
      << r.err;
  EXPECT_NE(last_line.find("that the data cannot tell apart"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  // A set named twice, and a negative thread count, each say so in one line.
  expect_one_line_error(fmt::format("update-linear {} --modes-table {} {} --set spring.ka", model,
                                    (dir / "tie.csv").string(), common),
                        "parameter set 'spring.ka' is named twice");
  expect_one_line_error(
      fmt::format("update-iwan {} --set rivet --mode 1 --backbone {} --threads -1 --out {}", model,
                  (dir / "tie.csv").string(), (dir / "out").string()),
      "-1 is not between 0 and 1024");
  std::ofstream(dir / "zero.csv") << "mode,frequency_hz,a0,b0\n1,57.9,1,0\n2,59.9,0,0\n";
  expect_one_line_error(fmt::format("update-linear {} --modes-table {} {}", model,
                                    (dir / "zero.csv").string(), common),
                        "measured mode 2 at 59.9 Hz: its shape is zero at every sensor");
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(UpdateCli, SmallestRuleWritesThePapersTablesAndAModesTableGivesTheSameUpdate) {
  const fs::path dir = testing::scratch_dir("update_linear_smallest_cli");
  correlate::TwoChainParameters truth;
  truth.kflat = 3e9;
  const Hit hit = linear_hit(correlate::two_chain_structure(truth), 6);
  write_process_output(dir / "measured", {hit});
  testing::write_text((dir / "sensors.csv").string(), sensors_text());
  std::string table = "mode,frequency_hz";
  for (const Sensor& s : kSensors) table += fmt::format(",{}", s.channel);
  table += "\n";
  const std::complex<double> phase = std::polar(1.0, -std::arg(std::complex<double>(2e-3, 5e-4)));
  for (size_t k = 0; k < hit.frequency_hz.size(); ++k) {
    table += fmt::format("{},{:.17g}", k + 1, hit.frequency_hz[k]);
    for (Eigen::Index i = 0; i < hit.shape[k].size(); ++i)
      table += fmt::format(",{:.17g}", (hit.shape[k](i) * phase).real());
    table += "\n";
  }
  testing::write_text((dir / "modes.csv").string(), table);
  correlate::TwoChainParameters start = truth;
  start.ka *= 2;
  start.kb /= 2;
  start.kflat = 1e9;
  const std::string model = write_model(dir, correlate::two_chain_structure(start), "start.toml");
  const std::string args = fmt::format(
      "--sensors {} --set spring.ka --set spring.kb --set spring.kflat --rule smallest "
      "--minimize spring.kflat --tolerance 0.01 --bound-factors 1e-4:1e3",
      (dir / "sensors.csv").string());
  const testing::CommandResult r =
      testing::run_jointlab(fmt::format("update-linear {} --measured {} {} --out {}", model,
                                        (dir / "measured").string(), args, (dir / "run").string()));
  ASSERT_EQ(r.status, 0) << r.err;
  SCOPED_TRACE(r.out);
  for (const char* f : {"modes.csv", "mac.csv", "mac.png", "sweeps.csv", "history.csv"})
    EXPECT_TRUE(fs::exists(dir / "run" / f)) << f;
  const auto modes = read_csv_cells(dir / "run" / "modes.csv");
  ASSERT_EQ(modes.size(), 7u);
  EXPECT_EQ(modes[0][4], "error");
  for (size_t i = 1; i < modes.size(); ++i) EXPECT_LE(std::abs(std::stod(modes[i][4])), 0.01);
  const auto mac = read_csv_cells(dir / "run" / "mac.csv");
  ASSERT_EQ(mac.size(), 7u);
  EXPECT_GE(mac[0].size(), 7u);
  const auto sweeps = read_csv_cells(dir / "run" / "sweeps.csv");
  EXPECT_EQ(sweeps[0].size(), 4u + 6u);
  EXPECT_EQ(sweeps.size(), 1u + 3u * 9u);

  const testing::CommandResult t = testing::run_jointlab(
      fmt::format("update-linear {} --modes-table {} {} --out {}", model,
                  (dir / "modes.csv").string(), args, (dir / "table").string()));
  ASSERT_EQ(t.status, 0) << t.err;
  const auto a = read_parameters(dir / "run" / "parameters.csv");
  const auto b = read_parameters(dir / "table" / "parameters.csv");
  for (const char* name : {"spring.ka", "spring.kb", "spring.kflat"}) {
    EXPECT_TRUE(testing::Close(std::stod(b.at(name).at(2)), std::stod(a.at(name).at(2)), 1e-6))
        << name;
  }

  // A lower bound above the smallest feasible value: the set ends there, with a warning, once
  // (in the report on stdout; stderr carries progress only).
  const testing::CommandResult w = testing::run_jointlab(
      fmt::format("update-linear {} --measured {} {} --bound spring.kflat=2e9:1e11 --out {}", model,
                  (dir / "measured").string(), args, (dir / "bound").string()));
  ASSERT_EQ(w.status, 0) << w.err;
  const std::string bound_warning = "spring.kflat ends at its lower bound";
  const size_t at = w.out.find(bound_warning);
  EXPECT_NE(at, std::string::npos) << w.out;
  EXPECT_EQ(w.out.find(bound_warning, at + 1), std::string::npos) << w.out;
  EXPECT_EQ(w.err.find("WARNING"), std::string::npos) << w.err;
  expect_one_line_error(fmt::format("update-linear {} --modes-table {} {} --out {}", model,
                                    (dir / "sensors.csv").string(), args, (dir / "bad").string()),
                        "sensors.csv:1");
  expect_one_line_error(
      fmt::format("update-linear {} --measured {} {} --bound spring.kflat=3 --out {}", model,
                  (dir / "measured").string(), args, (dir / "bad").string()),
      "--bound spring.kflat=3");
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// A mode-1 velocity backbone of `m` at sensor a5: `points` points up to `top` times the
// full-macroslip amplitude, relative frequency and damping noise, random seed.
correlate::MeasuredBackbone a5_backbone(const model::Model& m, int points, double top,
                                        double frequency_noise, double damping_noise,
                                        unsigned seed) {
  return correlate::synthetic_backbone(m, 1, kSensors, correlate::find_sensor(kSensors, "a5"),
                                       AmplitudeQuantity::kVelocity, points, top, frequency_noise,
                                       damping_noise, seed);
}

// The process folder `dir` of two hits of `m` (hit1.csv, hit2.csv; reference channels a5 and
// b5), each with one backbone.
void write_two_hits(const fs::path& dir, const model::Model& m, correlate::MeasuredBackbone b1,
                    correlate::MeasuredBackbone b2) {
  Hit h1 = linear_hit(m, 2), h2 = h1;
  h2.source = "hit2.csv";
  h1.reference = h2.reference = {"a5", "b5"};
  h1.backbones.push_back(std::move(b1));
  h2.backbones.push_back(std::move(b2));
  write_process_output(dir, {h1, h2});
}

// Backbone top: the measured curves run up to twice the end of the automatic QSMA range
// (full macroslip of the element), well into macroslip, where F_S shows.
constexpr double kTop = 2.0;

TEST(UpdateCli, IwanRecoversTheParametersFromTwoHits) {
  const fs::path dir = testing::scratch_dir("update_iwan_cli");
  correlate::TwoChainParameters truth;
  truth.iwan = true;
  const model::Model m = correlate::two_chain_structure(truth);
  write_two_hits(dir / "measured", m, a5_backbone(m, 30, kTop, 5e-4, 0.03, 7),
                 a5_backbone(m, 25, kTop, 5e-4, 0.03, 11));
  testing::write_text((dir / "sensors.csv").string(), sensors_text());
  correlate::TwoChainParameters start = truth;
  start.Fs *= 3;
  start.ka *= 3;
  start.chi = -0.1;
  start.beta /= 5;
  const std::string model = write_model(dir, correlate::two_chain_structure(start), "start.toml");
  const testing::CommandResult r = testing::run_jointlab(fmt::format(
      "update-iwan {} --measured {} --sensors {} --set iwan.rivet --mode 1:1 --out {}", model,
      (dir / "measured").string(), (dir / "sensors.csv").string(), (dir / "out").string()));
  ASSERT_EQ(r.status, 0) << r.err;
  RecordProperty("report", r.out);
  SCOPED_TRACE(r.out);
  const auto p = read_parameters(dir / "out" / "parameters.csv");
  ASSERT_EQ(p.size(), 5u);  // Fs, Kt, chi, beta, gamma (no modal_ratio: held)
  // gamma = Kt / Ks, Ks the start's 3 x the truth's (10 digits each in the file).
  EXPECT_TRUE(testing::Close(std::stod(p.at("gamma").at(2)),
                             std::stod(p.at("Kt").at(2)) / (3 * truth.ka), 1e-9));
  EXPECT_TRUE(testing::Close(std::stod(p.at("Kt").at(2)), truth.ka, 0.02));
  // Issue 5: Fs, chi and beta within 5 %, Kt within 2 % (the backbones reach macroslip).
  EXPECT_TRUE(testing::Close(std::stod(p.at("Fs").at(2)), truth.Fs, 0.05));
  EXPECT_TRUE(testing::Close(std::stod(p.at("chi").at(2)), truth.chi, 0.05));
  EXPECT_TRUE(testing::Close(std::stod(p.at("beta").at(2)), truth.beta, 0.05));
  const model::Model updated = model::read_model(dir / "out" / "model.toml");
  ASSERT_TRUE(updated.joints.size() == m.joints.size());
  EXPECT_TRUE(testing::Close(joint_stiffness(updated, "iwan.rivet"), truth.ka, 0.02));
  // The start's K_T of 3 x the truth puts chain A's mode above chain B's; the band's shape is
  // checked against the updated model, where mode 1 is chain A's again: no warning.
  EXPECT_EQ(r.out.find("WARNING: --mode"), std::string::npos) << r.out;
  // history.csv covers the whole fit: the fit with beta held, then (the data reach macroslip)
  // the one with beta free, numbered on; every objective is a cost the model gave (a set it
  // could not evaluate is left out: before, it was written as 1e6, and the history held the free
  // fit alone); best is the running minimum of the objectives (exactly: the same doubles, 10
  // digits each in the file).
  const auto history = read_csv_cells(dir / "out" / "history.csv");
  ASSERT_GT(history.size(), 2u);
  EXPECT_EQ(history[0], (std::vector<std::string>{"evaluation", "objective", "best", "stage"}));
  int held = 0, free = 0, previous = 0;
  double running = INFINITY;
  for (size_t i = 1; i < history.size(); ++i) {
    const int evaluation = std::stoi(history[i][0]);
    const double objective = std::stod(history[i][1]), best = std::stod(history[i][2]);
    EXPECT_GT(evaluation, previous) << "row " << i;
    previous = evaluation;
    EXPECT_TRUE(std::isfinite(objective) && objective != 1e6) << "row " << i;
    running = std::min(running, objective);
    EXPECT_EQ(best, running) << "row " << i;
    if (history[i][3] == "beta held") {
      ++held;
      EXPECT_EQ(free, 0) << "a beta held row after the beta free ones, row " << i;
    } else {
      EXPECT_EQ(history[i][3], "beta free") << "row " << i;
      ++free;
    }
  }
  EXPECT_GT(held, 100);
  EXPECT_GT(free, 100);
  // The last row is near the reported total (the evaluations after the search, for the
  // covariance and slips, are not the objective's history).
  const size_t at = r.out.find(" QSMA evaluations");
  ASSERT_NE(at, std::string::npos);
  const int total = std::stoi(r.out.substr(r.out.rfind(", ", at) + 2));
  RecordProperty("history_rows",
                 fmt::format("{} held, {} free, last {}, total {}", held, free, previous, total));
  EXPECT_LE(previous, total);
  EXPECT_GT(previous, 0.9 * total);

  // --gamma holds K_T at gamma K_s (K_s = the start's 1.5e6); the Pareto table carries both
  // measured linear modes' errors.
  const testing::CommandResult g = testing::run_jointlab(fmt::format(
      "update-iwan {} --measured {} --sensors {} --set iwan.rivet --mode 1:1 --gamma 0.1 "
      "--pareto 0.1,0.3333333333 --evaluations 300 --out {}",
      model, (dir / "measured").string(), (dir / "sensors.csv").string(),
      (dir / "gamma").string()));
  ASSERT_EQ(g.status, 0) << g.err;
  const auto pg = read_parameters(dir / "gamma" / "parameters.csv");
  EXPECT_TRUE(testing::Close(std::stod(pg.at("Kt").at(2)), 0.1 * 3 * truth.ka, 1e-9));
  EXPECT_NE(g.out.find("  Pareto gamma 0.1: Fs "), std::string::npos) << g.out;
  EXPECT_NE(g.out.find("    linear error per measured mode [%]: 1: "), std::string::npos) << g.out;
  const auto pareto = read_csv_cells(dir / "gamma" / "pareto.csv");
  ASSERT_EQ(pareto.size(), 3u);
  ASSERT_EQ(pareto[0].size(), 10u);
  EXPECT_EQ(pareto[0][8], "linear_error1");
  EXPECT_TRUE(testing::Close(std::stod(pareto[1][2]), 0.1 * 3 * truth.ka, 1e-9));
  // gamma 1/3 is the truth: mode 1 (the Iwan joint's) within 0.1 %, mode 2 (chain B) exact.
  EXPECT_LT(std::abs(std::stod(pareto[2][8])), 1e-3);
  EXPECT_LT(std::abs(std::stod(pareto[2][9])), 1e-6);
  EXPECT_GT(std::abs(std::stod(pareto[1][8])), 0.05);  // gamma 0.1: mode 1 far off

  expect_one_line_error(
      fmt::format("update-iwan {} --measured {} --sensors {} --set iwan.none --mode 1:1 --out {}",
                  model, (dir / "measured").string(), (dir / "sensors.csv").string(),
                  (dir / "bad").string()),
      "iwan.none");
  // A range far from the truth (20 N) and the start (60 N): the result lies inside it.
  const testing::CommandResult far = testing::run_jointlab(fmt::format(
      "update-iwan {} --measured {} --sensors {} --set iwan.rivet --mode 1:1 --fs-range "
      "1000:2000 --evaluations 200 --out {}",
      model, (dir / "measured").string(), (dir / "sensors.csv").string(), (dir / "far").string()));
  ASSERT_EQ(far.status, 0) << far.err;
  const double fs_far = std::stod(read_parameters(dir / "far" / "parameters.csv").at("Fs").at(2));
  EXPECT_GE(fs_far, 1000.0) << far.out;
  EXPECT_LE(fs_far, 2000.0) << far.out;
  // The optimum (Fs near the truth's 20 N) lies below the range, so the fit ends at its lower
  // bound: the bound is named, and the fit is not called converged.
  EXPECT_NE(far.out.find("WARNING: Fs at its lower bound 1000 N"), std::string::npos) << far.out;
  EXPECT_EQ(far.out.find("Iwan update: converged"), std::string::npos) << far.out;
  // ... and parameters.csv says which bound (column at_bound), and gives gamma = Kt / Ks.
  const auto far_p = read_parameters(dir / "far" / "parameters.csv");
  EXPECT_EQ(far_p.at("Fs").at(6), "lower") << far.out;
  EXPECT_EQ(far_p.at("chi").at(6), "") << far.out;
  EXPECT_TRUE(far_p.count("gamma"));

  const std::string iwan = fmt::format(
      "update-iwan {} --measured {} --sensors {} --set iwan.rivet --out {} ", model,
      (dir / "measured").string(), (dir / "sensors.csv").string(), (dir / "bad").string());
  expect_one_line_error(iwan + "--mode 1:4", "measured has no band 4 (bands: 1, 2)");
  expect_one_line_error(iwan + "--mode 999:1",
                        "--mode 999:1: model mode 999 does not exist: " + model + " has");
  expect_one_line_error(iwan + "--mode 999", "--mode 999: model mode 999 does not exist");
  expect_one_line_error(iwan + "--mode 1:1 --fs-range 2000:1000",
                        "--fs-range 2000:1000: need LO < HI with both Fs > 0");
  expect_one_line_error(iwan + "--mode 1:1 --beta-range 0:5",
                        "--beta-range 0:5: need 0 < LO < HI (beta is searched on a log scale");
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// --mode R:BAND takes the band as mode R's; the band's measured shape is then checked against
// mode R of the updated model. A sensors file with the rows of a1 and a5 exchanged (a wiring
// list mixed up) makes a5's backbone read at A1 and the band's shape unlike mode 1 (MAC about
// 0.1): the fit moves Fs far from the truth and, before, said nothing. The start orders the modes
// as the truth does (K_T x 1.1), so a check at the start would pass wrongly just as often as at
// the result; the correct file gives no warning. MACs are of exact model shapes at the sensors,
// so the two cases lie far either side of the 0.6 threshold.
TEST(UpdateCli, IwanWarnsWhenTheBandDoesNotLookLikeTheModeOfTheUpdatedModel) {
  const fs::path dir = testing::scratch_dir("update_iwan_band_shape");
  correlate::TwoChainParameters truth;
  truth.iwan = true;
  const model::Model m = correlate::two_chain_structure(truth);
  write_two_hits(dir / "measured", m, a5_backbone(m, 20, kTop, 5e-4, 0.03, 7),
                 a5_backbone(m, 20, kTop, 5e-4, 0.03, 11));
  testing::write_text((dir / "sensors.csv").string(), sensors_text());
  std::string swapped = sensors_text();
  swapped.replace(swapped.find("a1,1,1"), 6, "a5,1,1");
  swapped.replace(swapped.find("a5,5,-1"), 7, "a1,5,-1");
  testing::write_text((dir / "swapped.csv").string(), swapped);
  correlate::TwoChainParameters start = truth;
  start.Fs *= 1.5;
  start.ka *= 1.1;
  start.chi = -0.3;
  start.beta = 0.6;
  const std::string model = write_model(dir, correlate::two_chain_structure(start), "start.toml");
  const auto fit = [&](const std::string& sensors, const std::string& out) {
    const testing::CommandResult r = testing::run_jointlab(fmt::format(
        "update-iwan {} --measured {} --sensors {} --set iwan.rivet --mode 1:1 --evaluations 400 "
        "--out {}",
        model, (dir / "measured").string(), (dir / sensors).string(), (dir / out).string()));
    EXPECT_EQ(r.status, 0) << r.err;
    RecordProperty(out + "_Fs", read_parameters(dir / out / "parameters.csv").at("Fs").at(2));
    return r.out;
  };
  const std::string right = fit("sensors.csv", "right");
  EXPECT_EQ(right.find("WARNING: --mode"), std::string::npos) << right;
  const std::string wrong = fit("swapped.csv", "swapped");
  EXPECT_NE(wrong.find("WARNING: --mode 1:1: band 1's measured shape and mode 1 of the updated "
                       "model have MAC"),
            std::string::npos)
      << wrong;
  RecordProperty("swapped_report", wrong);
}

// A `stepped-sine` output folder as the command writes it (summary.json naming the program
// and each file's backbone CSV with process's five columns).
void write_stepped_sine_output(const fs::path& dir, const correlate::MeasuredBackbone& b) {
  fs::create_directories(dir);
  testing::write_text((dir / "summary.json").string(),
                      "{\"program\": \"jointlab stepped-sine\", \"amplitude_quantity\": "
                      "\"velocity\", \"amplitude_unit\": \"m/s\", \"files\": [{\"file\": "
                      "\"sweeps.csv\", \"output\": \"sweeps.backbone.csv\", \"levels\": []}]}\n");
  std::string t = "amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std\n";
  for (Eigen::Index j = 0; j < b.amplitude.size(); ++j) {
    t += fmt::format("{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}\n", b.amplitude(j), b.frequency_hz(j),
                     b.damping_ratio(j), b.frequency_std_hz(j), b.damping_std(j));
  }
  testing::write_text((dir / "sweeps.backbone.csv").string(), t);
}

// Hammer hits that stay in microslip (tops at 0.3 and 0.4 times the full-macroslip amplitude)
// and one stepped sine up to twice it: update-iwan fits both, each against its own model pair,
// and finds F_S and beta within 5 %, K_T and chi within 2 % (issue acceptance); the hammer
// alone is microslip only and says so. A process folder given as --stepped-sine is refused.
TEST(UpdateCli, IwanFitsHammerAndSteppedSineTogether) {
  const fs::path dir = testing::scratch_dir("update_iwan_stepped_sine");
  correlate::TwoChainParameters truth;
  truth.iwan = true;
  const model::Model m = correlate::two_chain_structure(truth);
  write_two_hits(dir / "measured", m, a5_backbone(m, 20, 0.3, 2e-4, 0.02, 21),
                 a5_backbone(m, 20, 0.4, 2e-4, 0.02, 22));
  const int a5 = correlate::find_sensor(kSensors, "a5");
  write_stepped_sine_output(
      dir / "sine",
      correlate::synthetic_backbone(m, 1, kSensors, a5, AmplitudeQuantity::kVelocity, 10, 2.0, 1e-4,
                                    0.03, 23, correlate::BackboneKind::kSteppedSine));
  testing::write_text((dir / "sensors.csv").string(), sensors_text());
  correlate::TwoChainParameters start = truth;
  start.Fs *= 1.5;
  start.ka *= 1.2;
  start.chi = -0.3;
  start.beta = 0.6;
  const std::string model = write_model(dir, correlate::two_chain_structure(start), "start.toml");
  const std::string common =
      fmt::format("update-iwan {} --measured {} --sensors {} --set iwan.rivet --mode 1:1", model,
                  (dir / "measured").string(), (dir / "sensors.csv").string());
  const testing::CommandResult r =
      testing::run_jointlab(fmt::format("{} --stepped-sine {} --stepped-sine-channel a5 --out {}",
                                        common, (dir / "sine").string(), (dir / "both").string()));
  ASSERT_EQ(r.status, 0) << r.err;
  SCOPED_TRACE(r.out);
  const auto p = read_parameters(dir / "both" / "parameters.csv");
  EXPECT_TRUE(testing::Close(std::stod(p.at("Fs").at(2)), truth.Fs, 0.05));
  EXPECT_TRUE(testing::Close(std::stod(p.at("beta").at(2)), truth.beta, 0.05));
  EXPECT_TRUE(testing::Close(std::stod(p.at("Kt").at(2)), truth.ka, 0.02));
  EXPECT_TRUE(testing::Close(std::stod(p.at("chi").at(2)), truth.chi, 0.02));
  EXPECT_NE(r.out.find("the data reach macroslip"), std::string::npos);
  const testing::CommandResult h = testing::run_jointlab(
      fmt::format("{} --beta-range 0.5:2 --out {}", common, (dir / "hammer").string()));
  ASSERT_EQ(h.status, 0) << h.err;
  EXPECT_NE(h.out.find("microslip only"), std::string::npos) << h.out;
  expect_one_line_error(fmt::format("{} --stepped-sine {} --stepped-sine-channel a5 --out {}",
                                    common, (dir / "measured").string(), (dir / "bad").string()),
                        "not a 'jointlab stepped-sine' output");
  expect_one_line_error(fmt::format("{} --stepped-sine {} --out {}", common,
                                    (dir / "sine").string(), (dir / "bad").string()),
                        "--stepped-sine-channel");
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// A plain backbone table of a one-mode model's (correlate::one_mode_structure) QSMA ring-down pair
// in modal amplitude, with its own damping Z added, as another lab's tool would give it: rows in no
// particular order, 1e-4 (frequency_noise) / 2 % noise stated as such; frequency_scale multiplies
// every frequency (a linear part off the truth's).
void write_backbone_table(const fs::path& path, const model::Model& truth, int points, double top,
                          unsigned seed, double frequency_scale = 1,
                          double frequency_noise = 1e-4) {
  const model::JointCondensation jc(truth);
  std::vector<double> q;
  for (int i = 0; i < points; ++i) q.push_back(1e-8 * std::pow(top / 1e-8, i / (points - 1.0)));
  const auto at = correlate::qsma_at(jc, 1, 0, q, correlate::AmplitudeFrequency::kFirstHarmonic);
  ASSERT_EQ(at.size(), q.size());
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<std::string> rows;
  for (size_t i = 0; i < q.size(); ++i) {
    const model::QsmaPoint& p = at[i].point;
    const double f = frequency_scale * p.ringdown_frequency_hz;
    rows.push_back(fmt::format("{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},extra\n", q[i],
                               f * (1 + frequency_noise * n(rng)),
                               p.ringdown_damping_ratio * (1 + 0.02 * n(rng)), frequency_noise * f,
                               0.02 * p.ringdown_damping_ratio));
  }
  std::shuffle(rows.begin(), rows.end(), rng);
  std::string text = "amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std,note\n";
  for (const std::string& r : rows) text += r;
  testing::write_text(path.string(), text);
}

// update-iwan --backbone (modal amplitude) --linear-damping fit: the structure's own damping
// is identified with the joint and written to the updated model and parameters.csv; progress
// lines on stderr; a table with a negative damping is refused with its file and line. Two
// hits of 40 points to 1.5 and 2.5 phi_max; acceptance 2 % in every parameter (the library
// test FitsTheStructuresOwnDampingWithTheJoint checks the same within 3 stated sigma).
TEST(UpdateCli, IwanFitsBackboneTablesWithTheStructuresOwnDamping) {
  const fs::path dir = testing::scratch_dir("update_iwan_backbone");
  const double k_total = std::pow(2 * M_PI * 177.0, 2);
  const model::IwanParameters truth{0.5, 0.04 * k_total, -0.5, 0.5};
  const double z = 5e-4, phi = model::Iwan(truth).phi_max();
  const model::Model m = correlate::one_mode_structure(0.96 * k_total, truth, z);
  write_backbone_table(dir / "hit1.csv", m, 40, 1.5 * phi, 31);
  write_backbone_table(dir / "hit2.csv", m, 40, 2.5 * phi, 32);
  const std::string model = write_model(
      dir, correlate::one_mode_structure(0.96 * k_total, {1.5, 0.8 * truth.Kt, -0.3, 2.0}, 0),
      "s.toml");
  const std::string common =
      fmt::format("update-iwan {} --set j --mode 1 --backbone {} --backbone {} --fs-range 0.005:50",
                  model, (dir / "hit1.csv").string(), (dir / "hit2.csv").string());
  const testing::CommandResult r =
      testing::run_jointlab(common + " --linear-damping fit --out " + (dir / "fit").string());
  ASSERT_EQ(r.status, 0) << r.err;
  SCOPED_TRACE(r.out);
  RecordProperty("report", r.out);
  EXPECT_NE(r.err.find("update-iwan: 250 QSMA evaluations, best cost"), std::string::npos) << r.err;
  const auto p = read_parameters(dir / "fit" / "parameters.csv");
  ASSERT_TRUE(p.count("modal_ratio"));
  // The rows in the contract's order (Fs, Kt, chi, beta and, when fitted, modal_ratio), the
  // paper's gamma = Kt / Ks after them.
  {
    std::ifstream in(dir / "fit" / "parameters.csv");
    std::string line, names;
    std::getline(in, line);
    while (std::getline(in, line)) names += line.substr(0, line.find(',')) + " ";
    EXPECT_EQ(names, "Fs Kt chi beta modal_ratio gamma ");
  }
  EXPECT_TRUE(testing::Close(std::stod(p.at("modal_ratio").at(2)), z, 0.02));
  EXPECT_NE(p.at("modal_ratio").at(3), "");  // its sigma
  EXPECT_TRUE(testing::Close(std::stod(p.at("Fs").at(2)), truth.Fs, 0.02));
  EXPECT_TRUE(testing::Close(std::stod(p.at("Kt").at(2)), truth.Kt, 0.02));
  EXPECT_TRUE(testing::Close(std::stod(p.at("chi").at(2)), truth.chi, 0.02));
  EXPECT_TRUE(testing::Close(std::stod(p.at("beta").at(2)), truth.beta, 0.02));
  const model::Model updated = model::read_model(dir / "fit" / "model.toml");
  EXPECT_TRUE(testing::Close(updated.modal_ratio, std::stod(p.at("modal_ratio").at(2)), 1e-9));
  EXPECT_GT(fs::file_size(dir / "fit" / "backbones.png"), 10000u);  // a drawn figure

  // compare: the start and the result over the same tables, labelled, with the CSV of what is
  // drawn beside the figure. The updated model's curve carries its fitted Z: at the lowest
  // amplitude (Z is 90 % of the damping there) it is the truth's within 3 % (the fit's
  // parameters are within 2 %; measured -0.23 %).
  const testing::CommandResult c = testing::run_jointlab(fmt::format(
      "compare {} {} --backbone {} --backbone {} --mode 1 --label start --label updated --out {}",
      model, (dir / "fit" / "model.toml").string(), (dir / "hit1.csv").string(),
      (dir / "hit2.csv").string(), (dir / "cmp" / "fig.png").string()));
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_GT(fs::file_size(dir / "cmp" / "fig.png"), 10000u);
  // A folder that cannot be made (under a file) is one line and exit 2; before, "internal
  // error: filesystem error".
  const testing::CommandResult nf = testing::run_jointlab(
      fmt::format("compare {} --backbone {} --mode 1 --out {}", model, (dir / "hit1.csv").string(),
                  (dir / "hit1.csv" / "sub" / "fig.png").string()));
  EXPECT_EQ(nf.status, 2) << nf.err;
  EXPECT_NE(nf.err.find("cannot create the folder"), std::string::npos) << nf.err;
  EXPECT_EQ(nf.err.find("internal error"), std::string::npos) << nf.err;
  const auto cells = read_csv_cells(dir / "cmp" / "fig.csv");
  ASSERT_GT(cells.size(), 100u);
  EXPECT_EQ(cells[0],
            (std::vector<std::string>{"model", "amplitude", "frequency_hz", "damping_ratio"}));
  EXPECT_EQ(cells[1][0], "start");
  EXPECT_EQ(cells.back()[0], "updated");
  size_t first_updated = 1;
  while (cells[first_updated][0] != "updated") ++first_updated;
  const model::JointCondensation truth_jc(m);
  const auto bottom =
      correlate::qsma_at(truth_jc, 1, 0, {1e-8}, correlate::AmplitudeFrequency::kFirstHarmonic);
  ASSERT_EQ(bottom.size(), 1u);
  EXPECT_TRUE(testing::Close(std::stod(cells[first_updated][3]),
                             bottom[0].point.ringdown_damping_ratio, 0.03))
      << cells[first_updated][3] << " vs " << bottom[0].point.ringdown_damping_ratio;
  RecordProperty(
      "bottom_damping_rel_error",
      std::to_string(std::stod(cells[first_updated][3]) / bottom[0].point.ringdown_damping_ratio -
                     1));

  // Held (the default): the model's Z (none: 0), no modal_ratio row, and the start's model has
  // no [damping] to write back.
  const testing::CommandResult h =
      testing::run_jointlab(common + " --evaluations 300 --out " + (dir / "held").string());
  ASSERT_EQ(h.status, 0) << h.err;
  EXPECT_FALSE(read_parameters(dir / "held" / "parameters.csv").count("modal_ratio"));
  EXPECT_EQ(model::read_model(dir / "held" / "model.toml").modal_ratio, 0.0);
  // Held parameters show no sigma of 0.
  const testing::CommandResult g = testing::run_jointlab(
      common + " --gamma 0.9 --evaluations 300 --out " + (dir / "gamma").string());
  ASSERT_EQ(g.status, 0) << g.err;
  const auto pg = read_parameters(dir / "gamma" / "parameters.csv");
  EXPECT_EQ(pg.at("Kt").at(3), "");
  EXPECT_EQ(pg.at("Kt").at(5), "1");
  EXPECT_NE(g.out.find("(held)"), std::string::npos) << g.out;

  // A negative damping value: one line naming the file and the line, exit 2, nothing written.
  testing::write_text((dir / "bad.csv").string(),
                      "amplitude,frequency_hz,damping_ratio\n1e-6,177,7e-4\n2e-6,177,-1e-5\n");
  expect_one_line_error(fmt::format("update-iwan {} --set j --mode 1 --backbone {} --out {}", model,
                                    (dir / "bad.csv").string(), (dir / "bad").string()),
                        (dir / "bad.csv").string() + ":3: damping_ratio '-1e-5' must be");
  expect_one_line_error(
      fmt::format("update-iwan {} --set j --mode 1 --backbone {} --amplitude velocity --out {}",
                  model, (dir / "hit1.csv").string(), (dir / "bad").string()),
      "--amplitude velocity: give --dof");
  expect_one_line_error(
      fmt::format("update-iwan {} --set j --mode 1 --out {}", model, (dir / "bad").string()),
      "give --measured DIR with --sensors FILE, or --backbone FILE");
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// The one-mode truth of the beta checks below: 177 Hz, K_T 4 % of the stiffness, F_S 0.5 N,
// chi -0.5, beta 0.5, no floor.
struct OneModeTruth {
  double k_total = std::pow(2 * M_PI * 177.0, 2);
  model::IwanParameters iwan{0.5, 0.04 * k_total, -0.5, 0.5};
};

// Two hits of the one-mode truth, 40 points each to top1 and top2 times phi_max (seeds seed and
// seed + 1), as dir/hit1.csv and dir/hit2.csv, and the start (F_S x2, K_T x0.9, chi -0.3, beta
// 1) as dir/s.toml; returns the update-iwan command on them with --fs-range 0.05:50, without
// --out.
std::string two_hits_command(const fs::path& dir, double top1, double top2, unsigned seed) {
  const OneModeTruth t;
  const double phi = model::Iwan(t.iwan).phi_max();
  const model::Model m = correlate::one_mode_structure(0.96 * t.k_total, t.iwan, 0);
  write_backbone_table(dir / "hit1.csv", m, 40, top1 * phi, seed);
  write_backbone_table(dir / "hit2.csv", m, 40, top2 * phi, seed + 1);
  const std::string model = write_model(
      dir, correlate::one_mode_structure(0.96 * t.k_total, {1.0, 0.9 * t.iwan.Kt, -0.3, 1.0}, 0),
      "s.toml");
  return fmt::format(
      "update-iwan {} --set j --mode 1 --backbone {} --backbone {} --fs-range 0.05:50", model,
      (dir / "hit1.csv").string(), (dir / "hit2.csv").string());
}

// Microslip backbones fix K_T, chi and R, not F_S and beta apart. With beta held at its start by
// the fit (the default) the F_S line says it is F_S given that beta and not identified, with the
// combination's sigma spelled out as at that beta, and the slip line lists the (F_S, beta) pairs
// that fit alike; parameters.csv leaves F_S's relative_std empty and marks beta held 0 (not as
// asked) with a note. Before (the trial's cantilever): "Fs 0.5 -> 0.564065 N +/- 2.3 %, ...,
// beta 1 -> 1 (held)" with the truth 0.7 N at beta 0.6 (z -2 to -13 over 10 seeds), parameters.csv
// beta held 1 as if asked. Held as asked (--beta at the truth's 0.5), F_S is F_S given it: the
// truth's within 3 % (measured +0.6 %). One-mode model, two hits of 40 points to 0.3 and 0.4
// phi_max, start F_S x2, K_T x0.9, chi -0.3, beta 1.
TEST(UpdateCli, IwanMicroslipSaysFsIsGivenBetaAndWhoHeldBeta) {
  const fs::path dir = testing::scratch_dir("update_iwan_microslip");
  const std::string common = two_hits_command(dir, 0.3, 0.4, 41);
  const double truth_fs = OneModeTruth{}.iwan.Fs;
  const testing::CommandResult r = testing::run_jointlab(common + " --out " + (dir / "a").string());
  ASSERT_EQ(r.status, 0) << r.err;
  SCOPED_TRACE(r.out);
  RecordProperty("report", r.out);
  const auto p = read_parameters(dir / "a" / "parameters.csv");
  const std::string fs_line = fmt::format(
      "Fs 1 -> {:.6g} N given beta = 1 (not identified, microslip only: the data "
      "fix only the combination of Fs and beta, below; +/- ",
      std::stod(p.at("Fs").at(2)));
  EXPECT_NE(r.out.find(fs_line), std::string::npos);
  EXPECT_NE(r.out.find("% at that beta), Kt"), std::string::npos);
  EXPECT_NE(r.out.find("beta 1 -> 1 (held at its start by the fit, not fitted: microslip only)"),
            std::string::npos);
  EXPECT_NE(r.out.find("microslip only, Fs and beta are not identified separately: every (Fs, "
                       "beta) with the fitted Kt and chi and the same microslip dissipation fits "
                       "these data alike ("),
            std::string::npos);
  EXPECT_NE(r.out.find("hold beta at a known value with --beta"), std::string::npos);
  EXPECT_EQ(p.at("Fs").at(3), "");   // relative_std: not identified
  EXPECT_EQ(p.at("Fs").at(4), "0");  // identifiable
  EXPECT_EQ(p.at("Fs").at(7),
            "given beta = 1: not identified (microslip only: the data fix only the combination of "
            "Fs and beta)");
  EXPECT_EQ(p.at("beta").at(3), "");
  EXPECT_EQ(p.at("beta").at(5), "0");  // held, but not as asked
  EXPECT_EQ(p.at("beta").at(7), "held at its start by the fit: microslip only so not identified");
  EXPECT_NE(p.at("Kt").at(3), "");  // K_T and chi are identified
  EXPECT_NE(p.at("chi").at(3), "");

  // Held as asked at the truth's beta: F_S given it, with its sigma, and held 1.
  const testing::CommandResult b =
      testing::run_jointlab(common + " --beta 0.5 --out " + (dir / "b").string());
  ASSERT_EQ(b.status, 0) << b.err;
  SCOPED_TRACE(b.out);
  const auto pb = read_parameters(dir / "b" / "parameters.csv");
  const double fs = std::stod(pb.at("Fs").at(2));
  RecordProperty("fs_given_truth_beta", std::to_string(fs));
  EXPECT_TRUE(testing::Close(fs, truth_fs, 0.03)) << fs;
  EXPECT_NE(b.out.find(" % given beta = 0.5 as held (microslip only), Kt"), std::string::npos);
  EXPECT_NE(b.out.find("beta 1 -> 0.5 (held)"), std::string::npos);
  EXPECT_NE(pb.at("Fs").at(3), "");
  EXPECT_EQ(pb.at("beta").at(5), "1");
  EXPECT_EQ(pb.at("beta").at(7), "held as asked");
}

// Backbones that reach macroslip identify beta; where the fit with beta freed ends above the fit
// with it held at its start (here the Monte Carlo paper-log search: 59.68 held, 235.6 free), beta
// was held by the fit, not as asked, and is no result of the data: the report says so on beta's
// line and in a warning with both costs, and parameters.csv has held 0 and a note. Before: "beta
// 1 -> 1 (held)" and held 1, as if --beta had held it (the trial's I1/macroT_10, the
// global-local search before its polish). One-mode model, two hits of 40 points to 1.5 and 2.5
// phi_max, start F_S x2, K_T x0.9, chi -0.3, beta 1.
TEST(UpdateCli, IwanSaysWhenTheFitWithBetaFreeDidNoBetter) {
  const fs::path dir = testing::scratch_dir("update_iwan_free_beta");
  const testing::CommandResult r =
      testing::run_jointlab(two_hits_command(dir, 1.5, 2.5, 31) + " --optimizer paper-log --out " +
                            (dir / "out").string());
  ASSERT_EQ(r.status, 0) << r.err;
  SCOPED_TRACE(r.out);
  RecordProperty("report", r.out);
  EXPECT_NE(r.out.find("beta 1 -> 1 (held at its start by the fit, not fitted: the fit with it "
                       "free did no better, below)"),
            std::string::npos);
  EXPECT_NE(r.out.find("WARNING: the data reach macroslip, where beta is identified, but the fit "
                       "with beta free ended at cost "),
            std::string::npos);
  EXPECT_NE(r.out.find("with beta held at its start 1: beta is not fitted and has no sigma"),
            std::string::npos);
  EXPECT_EQ(r.out.find("(held)"), std::string::npos);
  const auto p = read_parameters(dir / "out" / "parameters.csv");
  EXPECT_EQ(p.at("beta").at(3), "");
  EXPECT_EQ(p.at("beta").at(5), "0");
  EXPECT_EQ(p.at("beta").at(7),
            "held at its start by the fit: the fit with beta free did no better");
}

// A backbone table with its damping in per cent (`damping_ratio [%]`, `damping_std [%]`) is
// the same backbone as in fractions: the two fits give the same parameters. Before, the unit was
// ignored and the fit targeted 100 times the damping. The per cent values are the fractions
// times 100 printed to 17 digits and divided by 100 on reading: a rounding apart, which the fit
// (300 evaluations, the same samples) can carry to about 1e-9 of a parameter; 1e-6 allows for it
// and is far below what a factor 100 in damping moves them. A unit not understood is refused
// with the file, the column and the unit, never ignored.
TEST(UpdateCli, IwanReadsBackboneTablesInPerCentAndRefusesUnitsItDoesNotUnderstand) {
  const fs::path dir = testing::scratch_dir("update_iwan_units");
  const double k_total = std::pow(2 * M_PI * 177.0, 2);
  const model::IwanParameters truth{0.5, 0.04 * k_total, -0.5, 0.5};
  const double phi = model::Iwan(truth).phi_max();
  const model::Model m = correlate::one_mode_structure(0.96 * k_total, truth, 5e-4);
  write_backbone_table(dir / "fraction.csv", m, 30, 2 * phi, 41);
  // The same table in per cent.
  const auto cells = read_csv_cells(dir / "fraction.csv");
  std::string percent =
      "amplitude,frequency_hz [Hz],damping_ratio [%],frequency_std_hz,damping_std [%],note\n";
  for (size_t i = 1; i < cells.size(); ++i) {
    percent += fmt::format("{},{},{:.17g},{},{:.17g},x\n", cells[i][0], cells[i][1],
                           100 * std::stod(cells[i][2]), cells[i][3], 100 * std::stod(cells[i][4]));
  }
  testing::write_text((dir / "percent.csv").string(), percent);
  const std::string model = write_model(
      dir, correlate::one_mode_structure(0.96 * k_total, {1.5, 0.8 * truth.Kt, -0.3, 2.0}, 5e-4),
      "s.toml");
  const auto fit = [&](const std::string& table, const std::string& out) {
    const testing::CommandResult r = testing::run_jointlab(fmt::format(
        "update-iwan {} --set j --mode 1 --backbone {} --fs-range 0.005:50 --evaluations 300 "
        "--out {}",
        model, (dir / table).string(), (dir / out).string()));
    EXPECT_EQ(r.status, 0) << r.err;
    // The default read of the amplitudes is said: a sensor's displacement read as modal
    // scales F_S and fits as well, so only the report can tell the user.
    EXPECT_NE(r.out.find("amplitudes read as mode 1's QSMA modal amplitude q (--amplitude modal, "
                         "the default)"),
              std::string::npos)
        << r.out;
    return read_parameters(dir / out / "parameters.csv");
  };
  const auto pf = fit("fraction.csv", "fraction");
  const auto pp = fit("percent.csv", "percent");
  for (const char* name : {"Fs", "Kt", "chi", "beta"}) {
    const double a = std::stod(pf.at(name).at(2)), b = std::stod(pp.at(name).at(2));
    RecordProperty(std::string(name) + "_fraction_vs_percent", fmt::format("{} {}", a, b));
    EXPECT_TRUE(testing::Close(b, a, 1e-6)) << name << ": " << a << " vs " << b;
  }

  // Units the columns do not take: one line naming the file, the column and the unit, exit 2.
  const std::string rows = "\n1e-6,177,7e-4\n2e-6,176,8e-4\n";
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"amplitude [m/s],frequency_hz,damping_ratio",
       ":1: column 'amplitude [m/s]': unit 'm/s' refused: a modal amplitude"},
      {"amplitude,frequency_hz [rad/s],damping_ratio",
       ":1: column 'frequency_hz [rad/s]': unit 'rad/s' refused: frequency_hz is in Hz"},
      {"amplitude,frequency_hz,damping_ratio [permille]",
       ":1: column 'damping_ratio [permille]': unit 'permille' refused"},
  };
  int i = 0;
  for (const auto& [header, says] : refused) {
    const fs::path bad = dir / fmt::format("unit{}.csv", ++i);
    testing::write_text(bad.string(), header + rows);
    expect_one_line_error(fmt::format("update-iwan {} --set j --mode 1 --backbone {} --out {}",
                                      model, bad.string(), (dir / "bad").string()),
                          bad.string() + says);
  }
  // A measured amplitude's unit must measure the quantity --amplitude names; one that does is
  // converted (mm/s to m/s: the fit runs).
  const fs::path mm = dir / "mm.csv";
  testing::write_text(mm.string(), "amplitude [mm],frequency_hz,damping_ratio" + rows);
  expect_one_line_error(
      fmt::format("update-iwan {} --set j --mode 1 --backbone {} --amplitude velocity --dof 0 "
                  "--out {}",
                  model, mm.string(), (dir / "bad").string()),
      mm.string() +
          ":1: column 'amplitude [mm]': unit 'mm' measures displacement, the amplitude "
          "is a velocity");
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// Frequencies the model's mode cannot reach: the one-mode model (k0 = 0.96 k, one Iwan element
// of K_s = 0.032 k to ground) spans sqrt(k0) / 2 pi (the element slipped) to
// sqrt(k0 + gamma_max K_s) / 2 pi (stuck at the top of the gamma range, 2) whatever F_S, chi and
// beta. Tables at twice and half the measured frequencies are refused with those two numbers,
// closed form against the dense eigen-solve, compared as printed (6 digits; the solve agrees to
// about 1e-12). Before, every cost was clipped to the 1e6 penalty and the message said no
// parameter set gave a curve "over the measured amplitudes".
TEST(UpdateCli, IwanRefusesFrequenciesTheModeCannotReachNamingTheReach) {
  const fs::path dir = testing::scratch_dir("update_iwan_reach");
  const double k_total = std::pow(2 * M_PI * 177.0, 2);
  const model::IwanParameters truth{0.5, 0.04 * k_total, -0.5, 0.5};
  const model::Model m = correlate::one_mode_structure(0.96 * k_total, truth, 0);
  write_backbone_table(dir / "hit.csv", m, 20, 2 * model::Iwan(truth).phi_max(), 51);
  const double ks = 0.8 * truth.Kt;
  const std::string model = write_model(
      dir, correlate::one_mode_structure(0.96 * k_total, {1.5, ks, -0.3, 2.0}, 0), "s.toml");
  const double slipped = std::sqrt(0.96 * k_total) / (2 * M_PI);
  const double stuck = std::sqrt(0.96 * k_total + 2 * ks) / (2 * M_PI);
  const auto cells = read_csv_cells(dir / "hit.csv");
  for (const double factor : {2.0, 0.5}) {
    std::string t = "amplitude,frequency_hz,damping_ratio\n";
    for (size_t i = 1; i < cells.size(); ++i)
      t +=
          fmt::format("{},{:.17g},{}\n", cells[i][0], factor * std::stod(cells[i][1]), cells[i][2]);
    const fs::path table = dir / fmt::format("x{}.csv", factor);
    testing::write_text(table.string(), t);
    const std::string says =
        factor > 1 ? fmt::format(
                         "lies above {:.6g} Hz, the highest model mode 1 reaches (every "
                         "element of the set stuck at K_T = 2 x K_s",
                         stuck)
                   : fmt::format("lies below {:.6g} Hz, the lowest model mode 1 reaches", slipped);
    expect_one_line_error(fmt::format("update-iwan {} --set j --mode 1 --backbone {} --out {}",
                                      model, table.string(), (dir / "bad").string()),
                          says);
    const testing::CommandResult r =
        testing::run_jointlab(fmt::format("update-iwan {} --set j --mode 1 --backbone {} --out {}",
                                          model, table.string(), (dir / "bad").string()));
    const std::string other = factor > 1 ? fmt::format("slipped, it falls to {:.6g} Hz", slipped)
                                         : fmt::format("it rises to {:.6g} Hz", stuck);
    EXPECT_NE(r.err.find(other), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("measured amplitudes"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// A backbone 1.5 % above the model's linear frequency (the one-mode model with K_s 0.8 of the
// truth's K_T, the truth's QSMA curve with its frequencies times 1.015, 60 points to 2 phi_max)
// runs K_T to the top of its range (gamma 2; 1.5 % needs about 2.2) while every frequency stays
// within the model's reach. The report names what pressed it there, the measured low-amplitude
// frequency above the linear limit, and the model as given 1.85 % below it: update-linear first.
// Before, the bound's line said "the misfit below pressed it there; a wider range would not cure
// that", while a wider range does move K_T onto the data, taking up the linear part's error.
TEST(UpdateCli, IwanKtAtABoundNamesTheLinearLimitThatPressedIt) {
  const fs::path dir = testing::scratch_dir("update_iwan_kt_bound");
  const double k_total = std::pow(2 * M_PI * 177.0, 2);
  const model::IwanParameters truth{0.5, 0.04 * k_total, -0.5, 0.5};
  const model::Model m = correlate::one_mode_structure(0.96 * k_total, truth, 0);
  write_backbone_table(dir / "truth.csv", m, 60, 2 * model::Iwan(truth).phi_max(), 71);
  const auto cells = read_csv_cells(dir / "truth.csv");
  std::string t = "amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std\n";
  for (size_t i = 1; i < cells.size(); ++i) {
    t += fmt::format("{},{:.17g},{},{:.17g},{}\n", cells[i][0], 1.015 * std::stod(cells[i][1]),
                     cells[i][2], 1.015 * std::stod(cells[i][3]), cells[i][4]);
  }
  testing::write_text((dir / "above.csv").string(), t);
  const std::string model = write_model(
      dir, correlate::one_mode_structure(0.96 * k_total, {1.5, 0.8 * truth.Kt, -0.3, 2.0}, 0),
      "s.toml");
  const testing::CommandResult r = testing::run_jointlab(
      fmt::format("update-iwan {} --set j --mode 1 --backbone {} --fs-range 0.005:50 --out {}",
                  model, (dir / "above.csv").string(), (dir / "out").string()));
  ASSERT_EQ(r.status, 0) << r.err;
  RecordProperty("report", r.out);
  EXPECT_NE(r.out.find("gamma (Kt/Ks) at its upper bound 2: the measured low-amplitude frequency "
                       "pressed it there, beyond the linear limit Kt reaches in its range"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("with Kt at its upper bound, and mode 1 of the model as given (Kt = Ks, "
                       "176.291 Hz) by -1.8"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("update-linear first"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("a wider range would not cure that"), std::string::npos) << r.out;
}

// K_T held (--gamma 1) on a model whose linear frequency lies 0.5 % above the data (the one-mode
// truth's microslip curve, 40 points to 0.33 phi_max, every frequency times 0.995, 6e-4 frequency
// noise stated as such): chi stays inside its range and the fitted curve misses the low data by
// +0.52 to +0.59 % (9 to 9.8 times the noise) at a reduced chi-square of 37-38. The report names
// the linear part (update-linear first). Before, the rule for K_T held asked for chi at a bound
// and the fitted curve's miss had to pass ten times the noise (linear_limit_off()): no cause was
// named on any of the three seeds (nor on the riveted beam held at K_T = 1.2e7 N/m with 5e-4
// noise: +0.497 %, 9.9 times, reduced chi-square 51.7). Seeds 1-3, each a 0.2 s fit; the rule's
// three times the noise (0.18 %) lies far below the 0.5 % offset whatever the seed.
TEST(UpdateCli, IwanKtHeldWithDataBelowTheLinearFrequencyNamesTheLinearPart) {
  const fs::path dir = testing::scratch_dir("update_iwan_kt_held_low");
  const OneModeTruth t;
  const model::Model m = correlate::one_mode_structure(0.96 * t.k_total, t.iwan, 0);
  const std::string model = write_model(
      dir, correlate::one_mode_structure(0.96 * t.k_total, {1.0, t.iwan.Kt, -0.3, 1.0}, 0),
      "s.toml");
  for (unsigned seed : {1u, 2u, 3u}) {
    const fs::path table = dir / fmt::format("low{}.csv", seed);
    write_backbone_table(table, m, 40, 0.33 * model::Iwan(t.iwan).phi_max(), seed, 0.995, 6e-4);
    const testing::CommandResult r = testing::run_jointlab(fmt::format(
        "update-iwan {} --set j --mode 1 --backbone {} --gamma 1 --fs-range 0.05:50 --out {}",
        model, table.string(), (dir / fmt::format("out{}", seed)).string()));
    ASSERT_EQ(r.status, 0) << r.err;
    SCOPED_TRACE(r.out);
    EXPECT_NE(r.out.find("WARNING the model does not describe the data"), std::string::npos);
    EXPECT_NE(r.out.find("with Kt held, mode 1's linear frequency"), std::string::npos);
    EXPECT_NE(r.out.find("update-linear first"), std::string::npos);
    EXPECT_EQ(r.out.find("widen it"), std::string::npos);
    EXPECT_EQ(r.out.find("--evaluations"), std::string::npos);
  }
}

// The report and parameters.csv call modal_ratio at a bound exactly when it is there: Z is the
// clamped weighted mean of the damping residuals, so at a bound it is the bound itself. Before,
// anything below 1e-3 of --linear-damping-max (5e-5 by default) was called "at its lower bound
// 0" while its value was reported beside it. Planted Z = 2e-5 (its sigma from 2 % damping noise
// is about 3e-6, so the fit lands well inside (0, 5e-5)); with --linear-damping-max 2e-4 below
// a planted 5e-4 the fit ends exactly at the upper bound and says so.
TEST(UpdateCli, IwanCallsModalRatioAtABoundOnlyWhenItIsThere) {
  const fs::path dir = testing::scratch_dir("update_iwan_modal_ratio_bound");
  const double k_total = std::pow(2 * M_PI * 177.0, 2);
  const model::IwanParameters truth{0.5, 0.04 * k_total, -0.5, 0.5};
  const double phi = model::Iwan(truth).phi_max();
  const std::string model = write_model(
      dir, correlate::one_mode_structure(0.96 * k_total, {1.5, 0.8 * truth.Kt, -0.3, 2.0}, 0),
      "s.toml");
  const auto fit = [&](double z, const std::string& out, const std::string& extra) {
    const model::Model m = correlate::one_mode_structure(0.96 * k_total, truth, z);
    write_backbone_table(dir / (out + "1.csv"), m, 40, 1.5 * phi, 61);
    write_backbone_table(dir / (out + "2.csv"), m, 40, 2.5 * phi, 62);
    const testing::CommandResult r = testing::run_jointlab(fmt::format(
        "update-iwan {} --set j --mode 1 --backbone {} --backbone {} --fs-range 0.005:50 "
        "--linear-damping fit {} --out {}",
        model, (dir / (out + "1.csv")).string(), (dir / (out + "2.csv")).string(), extra,
        (dir / out).string()));
    EXPECT_EQ(r.status, 0) << r.err;
    RecordProperty(out, r.out);
    return std::pair{r.out, read_parameters(dir / out / "parameters.csv").at("modal_ratio")};
  };
  const auto [small_report, small] = fit(2e-5, "small", "");
  const double z_small = std::stod(small.at(2));
  EXPECT_GT(z_small, 5e-6) << small_report;
  EXPECT_LT(z_small, 5e-5) << small_report;
  EXPECT_EQ(small.at(6), "") << small_report;
  EXPECT_EQ(small_report.find("modal_ratio at its"), std::string::npos) << small_report;
  const auto [capped_report, capped] = fit(5e-4, "capped", "--linear-damping-max 2e-4");
  EXPECT_EQ(std::stod(capped.at(2)), 2e-4) << capped_report;
  EXPECT_EQ(capped.at(6), "upper") << capped_report;
  EXPECT_NE(capped_report.find("modal_ratio at its upper bound 0.0002"), std::string::npos)
      << capped_report;
}

// Three modes at once (issue 28: `--mode 1:1 --mode 2:2 --mode 3:3` failed with "no measured
// backbone to update against"): chain A's first three modes, each measured in a hit of its own
// (so no other mode slips the joints in it and the screen leaves every point), fitted together.
// The report lists each mode's screen; the fit runs on all three.
TEST(UpdateCli, IwanFitsThreeModesAtOnce) {
  const fs::path dir = testing::scratch_dir("update_iwan_three_modes");
  correlate::TwoChainParameters truth;
  truth.iwan = true;
  const model::Model m = correlate::two_chain_structure(truth);
  const model::LinearModes lm = model::linear_modes(m.mass, m.linear_stiffness());
  std::vector<int> chain_a;  // elastic mode numbers of chain A's modes
  for (int j = lm.rigid_count; j < lm.size() && chain_a.size() < 3; ++j)
    if (lm.shapes.col(j).head(6).norm() > lm.shapes.col(j).tail(6).norm())
      chain_a.push_back(j - lm.rigid_count + 1);
  ASSERT_EQ(chain_a.size(), 3u);
  const Hit linear = linear_hit(m, chain_a.back());
  std::vector<Hit> hits;
  for (size_t k = 0; k < 3; ++k) {
    Hit h = linear;
    h.source = fmt::format("hit{}.csv", k + 1);
    const int band = chain_a[k];
    const int sensor =
        correlate::find_sensor(kSensors, linear.reference[static_cast<size_t>(band - 1)]);
    h.backbones.push_back(correlate::synthetic_backbone(
        m, band, kSensors, sensor, AmplitudeQuantity::kVelocity, 20, 0.5, 2e-4, 0.02, 40 + k));
    h.backbone_bands.push_back(band);
    hits.push_back(h);
  }
  write_process_output(dir / "measured", hits);
  testing::write_text((dir / "sensors.csv").string(), sensors_text());
  const std::string model = write_model(dir, m, "m.toml");
  std::string modes;
  for (int r : chain_a) modes += fmt::format(" --mode {}:{}", r, r);
  const testing::CommandResult r = testing::run_jointlab(fmt::format(
      "update-iwan {} --measured {} --sensors {} --set iwan.rivet{} --evaluations 200 --out {}",
      model, (dir / "measured").string(), (dir / "sensors.csv").string(), modes,
      (dir / "out").string()));
  ASSERT_EQ(r.status, 0) << r.err << r.out;
  for (int k : chain_a) {
    EXPECT_NE(r.out.find(fmt::format("mode {}:{}: 0 of 20 points left out", k, k)),
              std::string::npos)
        << r.out;
  }
  EXPECT_TRUE(fs::exists(dir / "out" / "parameters.csv"));
  EXPECT_TRUE(fs::exists(dir / "out" / "backbones_3.png"));
}

}  // namespace
}  // namespace jointlab
