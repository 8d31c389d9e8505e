// The command under hostile input and failing disks: every error is one line with exit
// status 2; sizes are refused before they are allocated; a command's outputs replace the
// previous ones as a set or not at all, and temporaries of killed runs are removed.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/data/json_reader.h"
#include "jointlab/tests/cli.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::testing {
namespace {

namespace fs = std::filesystem;

// Every entry of `dir` (hidden ones too) with its contents; folders as "<dir>".
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(dir))
    files[e.path().filename().string()] = e.is_directory() ? "<dir>" : testing::read_file(e.path());
  return files;
}

// Two decaying modes (80 Hz on acc1, 150 Hz on acc2), 4 s at 1 kHz, times `scale`.
std::string ringdown_csv(const std::string& header = "time,acc1 [m/s^2],acc2 [m/s^2]",
                         double scale = 1) {
  std::string s = header + "\n";
  for (int k = 0; k < 4000; ++k) {
    const double t = k * 1e-3;
    s += fmt::format("{},{},{}\n", t, scale * std::exp(-t) * std::sin(2 * M_PI * 80 * t),
                     scale * std::exp(-2 * t) * std::sin(2 * M_PI * 150 * t));
  }
  return s;
}

// The numbers of a backbone CSV, row by row (header dropped).
std::vector<std::vector<double>> backbone_rows(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::vector<double>> rows;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

// Exit status 2 and one error line, the last on stderr (progress lines may precede it),
// holding `fragment`.
void expect_error(const CommandResult& r, const std::string& fragment) {
  EXPECT_EQ(r.status, 2) << r.err.substr(0, 500);
  std::string err = r.err;
  while (!err.empty() && err.back() == '\n') err.pop_back();
  const std::string msg =
      err.substr(err.rfind('\n') == std::string::npos ? 0 : err.rfind('\n') + 1);
  EXPECT_EQ(msg.rfind("jointlab: error: ", 0), 0u) << msg.substr(0, 500);
  EXPECT_EQ(err.find("jointlab: error: "), err.rfind("jointlab: error: ")) << "two error lines";
  EXPECT_NE(msg.find(fragment), std::string::npos) << msg.substr(0, 500);
}

TEST(ArgumentErrors, OneLineWithReadableBoundsAndStatus2) {
  const std::string dir = scratch_dir("rel_args");
  write_text(dir + "/hit.csv", ringdown_csv());
  const std::string p = "process " + dir + "/hit.csv ";
  expect_error(run_jointlab(p + "--modes 0 --out " + dir + "/o"),
               "--modes: 0 is not a positive number");
  expect_error(run_jointlab(p + "--band 70:90 --snr-min 0.5 --out " + dir + "/o"),
               "--snr-min: 0.5 is not between 1 and 1e+06");
  expect_error(run_jointlab(p + "--band 70:90 --min-share 2 --out " + dir + "/o"),
               "2 is not between 0 and 0.99");
  expect_error(run_jointlab(p + "--band 70:90 --out"), "--out");
  expect_error(run_jointlab(p + "--band 70:90 --colour red --out " + dir + "/o"), "red");
  expect_error(run_jointlab("frobnicate"), "unknown command 'frobnicate' (commands: process,");
  expect_error(run_jointlab(""), "subcommand");
  EXPECT_EQ(run_jointlab("--version").status, 0);
  EXPECT_EQ(run_jointlab("process --help").status, 0);
  EXPECT_FALSE(fs::exists(dir + "/o"));
}

// Every LO:HI option given a number that is not a finite double (1e400 overflows, 1e-400
// underflows to 0, nan and inf are none) names the option and the problem on one line, exit
// status 2, before any file is read (the paths need not exist); so do values outside the
// parameter's domain. The values that were once printed as "inf" or "0" are named as typed.
TEST(ArgumentErrors, RangeValuesThatAreNotFiniteDoublesAreNamed) {
  const std::string dir = scratch_dir("rel_ranges");
  const std::string iwan = "update-iwan " + dir + "/m.toml --measured " + dir + "/p --sensors " +
                           dir + "/s.csv --set iwan.j --mode 1:1 --out " + dir + "/o ";
  const std::string big = "overflows a double (largest 1.8e+308)";
  expect_error(run_jointlab(iwan + "--fs-range 1e400:1e500"), "--fs-range: 1e400 " + big);
  expect_error(run_jointlab(iwan + "--fs-range 10:1e500"), "--fs-range: 1e500 " + big);
  expect_error(run_jointlab(iwan + "--gamma-range 1e-400:1"),
               "--gamma-range: 1e-400 underflows to 0 in a double");
  expect_error(run_jointlab(iwan + "--chi-range nan:0"), "--chi-range: nan is not a finite number");
  expect_error(run_jointlab(iwan + "--beta-range 0.1:inf"),
               "--beta-range: inf is not a finite number");
  expect_error(run_jointlab(iwan + "--fs-range -5:10"),
               "--fs-range -5:10: need LO < HI with both Fs > 0");
  expect_error(run_jointlab(iwan + "--gamma 1e999"), "--gamma: 1e999 " + big);
  const std::string lin = "update-linear " + dir + "/m.toml --measured " + dir + "/p --sensors " +
                          dir + "/s.csv --set spring.k --out " + dir + "/o ";
  expect_error(run_jointlab(lin + "--bound-factors 1e-3:1e400"), "--bound-factors: 1e400 " + big);
  expect_error(run_jointlab(lin + "--bound-factors 0:10"), "--bound-factors 0:10: need 0 < LO < 1");
  expect_error(run_jointlab(lin + "--bound spring.k=1:1e400"),
               "--bound spring.k=1:1e400: 1e400 " + big);
  expect_error(run_jointlab(lin + "--bound spring.k=-1:10"),
               "--bound spring.k=-1:10: need 0 < LO < HI");
  write_text(dir + "/hit.csv", ringdown_csv());
  expect_error(run_jointlab("process " + dir + "/hit.csv --band 1e400:1e500 --out " + dir + "/o"),
               "--band 1e400:1e500: 1e400 " + big);
  expect_error(run_jointlab("process " + dir + "/hit.csv --band 70:1e309 --out " + dir + "/o"),
               "--band 70:1e309: 1e309 " + big);
  EXPECT_FALSE(fs::exists(dir + "/o"));
}

// A band that gives a backbone at no channel fails `process` as `run` fails for a mode
// without a backbone (contract: "writes what it can and exits non-zero"): the other band's
// backbones and summary.json (with the empty band's reason) are written, and one stderr
// line names the band in Hz and why, exit status 2. A band empty at some channels only
// (70:90 Hz sees nothing at acc2) is normal and exits 0.
TEST(ProcessEmptyBand, FailsAfterWritingTheOtherBands) {
  const std::string dir = scratch_dir("rel_empty_band");
  write_text(dir + "/hit.csv", ringdown_csv());
  const CommandResult ok =
      run_jointlab("process " + dir + "/hit.csv --band 70:90 --out " + dir + "/ok");
  EXPECT_EQ(ok.status, 0) << ok.err;
  EXPECT_TRUE(fs::exists(dir + "/ok/hit.acc1.band1.csv"));
  EXPECT_FALSE(fs::exists(dir + "/ok/hit.acc2.band1.csv"));

  const CommandResult r = run_jointlab("process " + dir + "/hit.csv --band 70:90 --band 300:360 " +
                                       "--out " + dir + "/out");
  expect_error(r, "band 2 (300:360 Hz): no backbone at any channel; acc");
  EXPECT_NE(r.err.find("everything else is written to " + dir + "/out"), std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::exists(dir + "/out/hit.acc1.band1.csv"));
  EXPECT_FALSE(fs::exists(dir + "/out/hit.acc1.band2.csv"));
  const data::JsonValue summary = data::read_json(dir + "/out/summary.json");
  const std::vector<data::JsonValue>& bands =
      summary.find("files")->items().at(0).find("bands")->items();
  ASSERT_EQ(bands.size(), 2u);
  EXPECT_EQ(bands[0].find("reason"), nullptr);
  ASSERT_NE(bands[1].find("reason"), nullptr);
  EXPECT_NE(r.err.find(bands[1].find("reason")->string()), std::string::npos) << r.err;
  // No staging folder or temporary is left behind.
  for (const auto& e : fs::directory_iterator(dir + "/out"))
    EXPECT_EQ(e.path().filename().string().find(".process.stage-"), std::string::npos);
}

// A process that refuses its input (a sample rate no analysis can afford, a band too narrow
// for the record) or its arguments leaves no output folder it created for the run, however
// deep; a folder that was there stays, with what it held.
TEST(ProcessRefusals, LeaveNoFolderTheyCreated) {
  const std::string dir = scratch_dir("rel_refusal_folders");
  write_text(dir + "/hit.csv", ringdown_csv());
  std::string fast = "time,acc1 [m/s^2]\n";
  for (int k = 0; k < 1000; ++k) fast += fmt::format("{},{}\n", k * 1e-30, std::sin(k * 0.5));
  write_text(dir + "/fast.csv", fast);
  expect_error(run_jointlab("process " + dir + "/fast.csv --band 70:90 --out " + dir + "/a/b/c"),
               "sample rate 1e+30 Hz");
  EXPECT_FALSE(fs::exists(dir + "/a"));
  expect_error(run_jointlab("process " + dir + "/hit.csv --band 80:80.0001 --out " + dir + "/o"),
               "too narrow");
  EXPECT_FALSE(fs::exists(dir + "/o"));
  expect_error(run_jointlab("process " + dir + "/hit.csv --band 70: --out " + dir + "/o"),
               "--band 70:: HI is missing; give LO:HI in Hz");
  expect_error(run_jointlab("process " + dir + "/hit.csv --band :90 --out " + dir + "/o"),
               "--band :90: LO is missing; give LO:HI in Hz");
  EXPECT_FALSE(fs::exists(dir + "/o"));
  fs::create_directories(dir + "/kept");
  write_text(dir + "/kept/notes.txt", "mine");
  expect_error(run_jointlab("process " + dir + "/fast.csv --band 70:90 --out " + dir + "/kept"),
               "sample rate 1e+30 Hz");
  EXPECT_EQ(snapshot(dir + "/kept"), (std::map<std::string, std::string>{{"notes.txt", "mine"}}));
  fs::create_directories(dir + "/empty");
  expect_error(run_jointlab("process " + dir + "/fast.csv --band 70:90 --out " + dir + "/empty"),
               "sample rate 1e+30 Hz");
  EXPECT_TRUE(fs::is_directory(dir + "/empty"));
}

// The exit status of a command whose stdout and stderr cannot be written (here /dev/full: every
// write fails with "no space") is its own: 0 with every output written, 2 for an error. The
// lines are lost, not the run (fmt::print's exception once aborted it with status 134).
TEST(ConsoleWrites, FailuresToPrintLeaveTheExitStatusAlone) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  const std::string dir = scratch_dir("rel_dev_full");
  write_text(dir + "/hit.csv", ringdown_csv());
  const auto status = [&](const std::string& args) {
    const std::string cmd =
        binary_dir() + "/bin/jointlab " + args + " > /dev/full 2> /dev/full < /dev/null";
    const int raw = std::system(cmd.c_str());
    return WIFEXITED(raw) ? WEXITSTATUS(raw) : 1000 + WTERMSIG(raw);
  };
  EXPECT_EQ(status("process " + dir + "/hit.csv --band 70:90 --out " + dir + "/o"), 0);
  EXPECT_TRUE(fs::exists(dir + "/o/hit.acc1.band1.csv"));
  EXPECT_TRUE(fs::exists(dir + "/o/summary.json"));
  EXPECT_EQ(status("process " + dir + "/hit.csv --band 70:90 --band 300:360 --out " + dir + "/o2"),
            2);
  EXPECT_EQ(status("process " + dir + "/missing.csv --band 70:90 --out " + dir + "/o3"), 2);
  EXPECT_EQ(status("process " + dir + "/hit.csv --band 70 --out " + dir + "/o3"), 2);
  EXPECT_EQ(status("frobnicate"), 2);
}

class ProcessOutputs : public ::testing::Test {
 protected:
  void SetUp() override {
    // ctest runs the cases side by side: one folder each.
    dir_ = scratch_dir(std::string("rel_outputs_") +
                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    out_ = dir_ + "/out";
    write_text(dir_ + "/good.csv", ringdown_csv());
    write_text(dir_ + "/other.csv", ringdown_csv());
    write_text(dir_ + "/bad.csv", "time,acc1\n0,1\n0.001,abc\n");
    const CommandResult r = run_jointlab("process " + dir_ + "/good.csv --band 70:90 --band " +
                                         "140:160 --out " + out_);
    ASSERT_EQ(r.status, 0) << r.err;
    before_ = snapshot(out_);
    ASSERT_TRUE(before_.count("summary.json"));
    ASSERT_TRUE(before_.count("good.acc1.band1.csv"));
    ASSERT_TRUE(before_.count("good.acc2.band2.csv"));
  }
  std::string dir_, out_;
  std::map<std::string, std::string> before_;
};

TEST_F(ProcessOutputs, AFailingInputLeavesThePreviousOutputs) {
  // other.csv processes fine, bad.csv fails: nothing of other.csv may appear.
  expect_error(run_jointlab("process " + dir_ + "/other.csv " + dir_ + "/bad.csv --band 70:90 " +
                            "--out " + out_),
               "bad.csv:3: column 'acc1': 'abc' is not a number");
  EXPECT_EQ(snapshot(out_), before_);
}

TEST_F(ProcessOutputs, AFullDiskLeavesThePreviousOutputs) {
  // The backbones are written, then summary.json fails as on a full disk.
  const std::string shim = binary_dir() + "/tests/libjointlab_fail_writes.so";
  ASSERT_TRUE(fs::exists(shim));
  const std::string env = "LD_PRELOAD=" + shim +
                          " ASAN_OPTIONS=verify_asan_link_order=0 JOINTLAB_FAIL_WRITES_TO=summary";
  const std::string cmd = env + " " + binary_dir() + "/bin/jointlab process " + dir_ +
                          "/other.csv --band 70:90 --out " + out_ + " 2> " + dir_ + "/err.txt";
  const int raw = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(raw));
  CommandResult r;
  r.status = WEXITSTATUS(raw);
  r.err = testing::read_file(dir_ + "/err.txt");
  expect_error(r, "out/summary.json: write failed (disk full?)");
  EXPECT_EQ(snapshot(out_), before_);
}

TEST_F(ProcessOutputs, ANewRunReplacesTheOldSetAndRemovesLeftovers) {
  // What killed runs leave: an unclaimed temporary and a staging folder.
  write_text(out_ + "/good.acc1.band1.csv.tmp-0123abcd", "half");
  fs::create_directory(out_ + "/.process.stage-89abcdef");
  write_text(out_ + "/.process.stage-89abcdef/good.acc1.band1.csv", "half");
  write_text(out_ + "/notes.txt", "mine");
  const CommandResult r =
      run_jointlab("process " + dir_ + "/other.csv --band 140:160 --out " + out_);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto after = snapshot(out_);
  std::map<std::string, std::string> names;
  for (const auto& [name, text] : after) names[name] = "";
  EXPECT_EQ(names, (std::map<std::string, std::string>{{".process.outputs", ""},
                                                       {"notes.txt", ""},
                                                       {"other.acc2.band1.csv", ""},
                                                       {"summary.json", ""}}));
  EXPECT_EQ(after.at("notes.txt"), "mine");
  EXPECT_EQ(after.at("summary.json").find("good.csv"), std::string::npos);
}

TEST_F(ProcessOutputs, OutputsOfAnOlderVersionAreReplacedToo) {
  // A folder written before outputs were recorded: process's own file names identify them.
  fs::remove(out_ + "/.process.outputs");
  const CommandResult r = run_jointlab("process " + dir_ + "/other.csv --band 70:90 --out " + out_);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto after = snapshot(out_);
  EXPECT_FALSE(after.count("good.acc1.band1.csv"));
  EXPECT_FALSE(after.count("good.acc2.band2.csv"));
  EXPECT_TRUE(after.count("other.acc1.band1.csv"));
}

TEST(ProcessOutputsInAForeignFolder, FilesOfOthersAreKept) {
  // No summary.json: nothing there was written by process, whatever its name.
  const std::string dir = scratch_dir("rel_foreign");
  write_text(dir + "/hit.csv", ringdown_csv());
  write_text(dir + "/survey.band1.csv", "someone else's");
  const CommandResult r = run_jointlab("process " + dir + "/hit.csv --band 70:90 --out " + dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(testing::read_file(dir + "/survey.band1.csv"), "someone else's");
  EXPECT_TRUE(fs::exists(dir + "/hit.acc1.band1.csv"));
}

// ringdown_csv's record with white noise at 1e-4 (a fixed draw), times `scale`.
std::string noisy_ringdown_csv(double scale) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-4);
  std::string s = "time,acc1 [m/s^2],acc2 [m/s^2]\n";
  for (int k = 0; k < 4000; ++k) {
    const double t = k * 1e-3;
    const double a = std::exp(-t) * std::sin(2 * M_PI * 80 * t) + noise(rng);
    const double b = std::exp(-2 * t) * std::sin(2 * M_PI * 150 * t) + noise(rng);
    s += fmt::format("{},{},{}\n", t, scale * a, scale * b);
  }
  return s;
}

// Samples of 1e300 or 1e-290 are finite: process analyses them as it analyses the same
// record at unit scale, with the amplitudes scaled and every other column the same up to the
// once-rounded scaled samples (1e-290 keeps the smallest displacements normal doubles);
// summary.json holds no NaN or Inf.
TEST(HugeSamples, AreProcessedLikeTheSameRecordAtUnitScale) {
  const std::string dir = scratch_dir("rel_huge");
  write_text(dir + "/hit.csv", noisy_ringdown_csv(1.0));
  const std::string bands = " --band 70:90 --band 140:160 --out ";
  ASSERT_EQ(run_jointlab("process " + dir + "/hit.csv" + bands + dir + "/plain").status, 0);
  for (const double scale : {1e300, 1e-290}) {
    SCOPED_TRACE(scale);
    const std::string out = fmt::format("{}/scaled{:g}", dir, scale);
    write_text(dir + "/hit.csv", noisy_ringdown_csv(scale));
    const CommandResult r = run_jointlab("process " + dir + "/hit.csv" + bands + out);
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string json = testing::read_file(out + "/summary.json");
    EXPECT_NO_THROW(data::parse_json(json, "summary.json"));
    EXPECT_EQ(json.find("nan"), std::string::npos);
    EXPECT_EQ(json.find("inf"), std::string::npos);
    for (const char* name : {"hit.acc1.band1.csv", "hit.acc2.band2.csv"}) {
      const auto plain = backbone_rows(dir + "/plain/" + name);
      const auto scaled = backbone_rows(out + "/" + name);
      ASSERT_GT(plain.size(), 10u) << name;
      ASSERT_EQ(scaled.size(), plain.size()) << name;
      for (size_t i = 0; i < plain.size(); ++i) {
        ASSERT_EQ(scaled[i].size(), plain[i].size());
        for (size_t j = 0; j < plain[i].size(); ++j) {
          // Columns 1 (amplitude) and 8 (displacement_m) scale; the rest do not. The
          // damping (3) and decay rate (7) follow the band-gain correction, whose iteration
          // stops at a change of 1e-4 and so carries the samples' rounding as 1e-7 (measured
          // 9e-8, 7e-5 of the damping's uncertainty); the uncertainties (4, 5) as 1e-4
          // (measured 8e-5); the rest 1e-9 (measured 9.9e-10).
          const double expected = plain[i][j] * (j == 1 || j == 8 ? scale : 1.0);
          const double tolerance = j == 3 || j == 7 ? 1e-6 : j == 4 || j == 5 ? 1e-3 : 1e-8;
          EXPECT_NEAR(scaled[i][j], expected, tolerance * std::abs(expected) + 1e-300)
              << name << " row " << i << " column " << j;
        }
      }
    }
  }
  // Displacements of 1e306 at 80 Hz reach 2.5e311 m/s^2, past the largest double: that
  // channel has no backbone and says why, the other channel is processed (acc2 has no mode
  // at 80 Hz, so the band has no backbone at all: exit 2 with summary.json written).
  write_text(dir + "/hit.csv", ringdown_csv("time,d1 [m],acc2 [m/s^2]", 1e306));
  const CommandResult r = run_jointlab("process " + dir + "/hit.csv --band 70:90 --amplitude " +
                                       "acceleration --out " + dir + "/over");
  expect_error(r,
               "band 1 (70:90 Hz): no backbone at any channel; d1: the backbone's amplitudes "
               "exceed the largest double");
  EXPECT_NE(r.err.find("d1 band 1: no backbone: the backbone's amplitudes exceed the largest "
                       "double"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("acc2 band 1: no backbone: "), std::string::npos) << r.err;
  EXPECT_NO_THROW(data::read_json(dir + "/over/summary.json"));

  // A velocity of 1e300 m/s sampled at 1e-250 Hz, its mode at 8e-252 Hz: the displacement,
  // 1e300 / (2 pi 8e-252) = 2e550 m, is past the largest double already in the envelope (the
  // noise floor summary.json reports), not only in the backbone (the fuzzer's finding: the
  // summary was refused for an infinite noise floor). No backbone, the reason, no Inf.
  std::string slow = "# fs: 1e-250\nv1 [m/s]\n";
  for (int k = 0; k < 4000; ++k) {
    const double t = k * 1e-3;
    slow += fmt::format("{}\n", 1e300 * std::exp(-t) * std::sin(2 * M_PI * 80 * t));
  }
  write_text(dir + "/slow.csv", slow);
  const CommandResult s =
      run_jointlab("process " + dir + "/slow.csv --band 7e-252:9e-252 --out " + dir + "/slow");
  expect_error(s, "v1: the band's displacement envelope exceeds the largest double");
  const std::string json = testing::read_file(dir + "/slow/summary.json");
  EXPECT_NO_THROW(data::parse_json(json, "summary.json"));
  EXPECT_EQ(json.find("inf"), std::string::npos);
}

TEST(Readers, NonUtf8HeaderGivesValidJson) {
  const std::string dir = scratch_dir("rel_utf8");
  write_text(dir + "/hit.csv", ringdown_csv("time,acc\xff\xfe [m/s^2],caf\xc3\xa9 [m/s^2]"));
  const CommandResult r =
      run_jointlab("process " + dir + "/hit.csv --band 70:90 --out " + dir + "/o");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json = testing::read_file(dir + "/o/summary.json");
  EXPECT_NE(json.find("acc\\ufffd\\ufffd"), std::string::npos);
  EXPECT_NE(json.find("caf\xc3\xa9"), std::string::npos);  // valid UTF-8 stays as it is
  EXPECT_NO_THROW(data::parse_json(json, "summary.json"));
}

// File names are built from channel names with bytes that are not UTF-8, '/' and control
// characters replaced by '_' (data/names.h): every file summary.json links exists under that
// name, and the folder holds no other backbone.
TEST(Readers, SummaryLinksTheBackbonesOfOddlyNamedChannels) {
  const std::string dir = scratch_dir("rel_utf8_links");
  write_text(dir + "/hit.csv",
             ringdown_csv("time,acc\xff\xfe [m/s^2],caf\xc3\xa9\x7f\x01/x [m/s^2]"));
  const CommandResult r =
      run_jointlab("process " + dir + "/hit.csv --band 70:90 --band 140:160 --out " + dir + "/o");
  ASSERT_EQ(r.status, 0) << r.err;
  const data::JsonValue summary = data::read_json(dir + "/o/summary.json");
  std::vector<std::string> linked;
  for (const data::JsonValue& o : summary.find("files")->items().at(0).find("outputs")->items())
    if (o.find("file")->is_string()) linked.push_back(o.find("file")->string());
  std::sort(linked.begin(), linked.end());
  EXPECT_EQ(linked,
            (std::vector<std::string>{"hit.acc__.band1.csv", "hit.caf\xc3\xa9___x.band2.csv"}));
  std::vector<std::string> on_disk;
  for (const auto& e : fs::directory_iterator(dir + "/o")) {
    const std::string name = e.path().filename().string();
    if (name.size() > 4 && name.substr(name.size() - 4) == ".csv") on_disk.push_back(name);
  }
  std::sort(on_disk.begin(), on_disk.end());
  EXPECT_EQ(on_disk, linked);
}

// A channel name longer than 128 bytes is refused when the file is read, in one short line
// (outputs are named after channels; a 50 MB name once made a 52 MB progress line and a 210 MB
// summary.json, and a 300-byte one a "File name too long" naming a temporary). A 128-byte
// name is processed; with a long file name too, the output name that would be too long is
// named with the file and channel, not as a temporary.
TEST(Readers, LongChannelNamesAreRefusedWhenRead) {
  const std::string dir = scratch_dir("rel_long_names");
  const std::string name(129, 'n');
  write_text(dir + "/hit.csv", ringdown_csv("time," + name + " [m/s^2],acc2 [m/s^2]"));
  CommandResult r = run_jointlab("process " + dir + "/hit.csv --band 70:90 --out " + dir + "/o");
  expect_error(r, dir + "/hit.csv:1: channel name of 129 bytes ('nnnnnnnnnn");
  expect_error(r, "'): at most 128 (names make output file names)");
  EXPECT_LT(r.err.size(), 300u);
  EXPECT_FALSE(fs::exists(dir + "/o"));

  write_text(dir + "/hit.csv", ringdown_csv("time," + name.substr(1) + " [m/s^2],acc2 [m/s^2]"));
  r = run_jointlab("process " + dir + "/hit.csv --band 70:90 --out " + dir + "/o");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir + "/o/hit." + name.substr(1) + ".band1.csv"));

  const std::string stem(120, 's');
  write_text(dir + "/" + stem + ".csv",
             ringdown_csv("time," + name.substr(1) + " [m/s^2],acc2 [m/s^2]"));
  r = run_jointlab("process " + dir + "/" + stem + ".csv --band 70:90 --out " + dir + "/o2");
  expect_error(r, "band 1: its output file name would be 259 bytes ('ssss");
  expect_error(r, "more than the 242 a file name may have; shorten the file's or the channel's");
  EXPECT_EQ(r.err.find(".tmp-"), std::string::npos) << r.err;
}

TEST(Readers, TrailingCommaOnOneRowIsAnError) {
  const std::string dir = scratch_dir("rel_comma");
  write_text(dir + "/hit.csv", "time,x\n0,1\n0.001,2,\n0.002,3\n");
  expect_error(run_jointlab("process " + dir + "/hit.csv --band 10:20 --out " + dir + "/o"),
               "hit.csv:3: 3 fields where the header has 2");
}

TEST(Readers, HugeNamesAreCutInMessages) {
  const std::string dir = scratch_dir("rel_long");
  const std::string name(1 << 20, 'a');
  write_text(dir + "/hit.csv", "time,x [" + name + "]\n0,1\n0.001,x\n");
  const CommandResult r =
      run_jointlab("process " + dir + "/hit.csv --band 10:20 --out " + dir + "/o");
  expect_error(r, "... (1048576 bytes)");
  EXPECT_LT(r.err.size(), 500u);
}

// A two-DOF model file with one Iwan joint; `chi` and the matrices as given.
std::string write_model(const std::string& dir, const std::string& chi,
                        const std::string& mass =
                            "%%MatrixMarket matrix coordinate real "
                            "symmetric\n2 2 2\n1 1 1\n2 2 1\n") {
  write_text(dir + "/M.mtx", mass);
  write_text(dir + "/K.mtx",
             "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 2e4\n2 1 -1e4\n2 2 "
             "1e4\n");
  write_text(dir + "/model.toml",
             "[matrices]\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n\n"
             "[iwan.rivet]\nFs = 40.0\nKt = 2.0e4\nchi = " +
                 chi +
                 "\nbeta = 1.0\n\n[spring]\nkz = 1e4\n\n"
                 "[[joint]]\na = 0\nb = \"ground\"\nelement = \"iwan.rivet\"\n");
  return dir + "/model.toml";
}

// One domain, chi > -1 (method.md, contract.md; model::iwan_parameter_domain): chi above 0 is
// read by every reader (it was refused, "chi = 0.5 must be in (-1, 0]"), chi at or below -1 and
// no finite number are refused naming the field.
TEST(ModelDomains, ChiAboveMinusOneIsReadByEveryReader) {
  const std::string dir = scratch_dir("rel_chi");
  for (const char* chi : {"0.5", "1.0", "5.0"}) {
    const std::string model = write_model(dir, chi);
    const CommandResult r = run_jointlab("modes " + model + " --out " + dir + "/modes.csv");
    EXPECT_EQ(r.status, 0) << chi << ": " << r.err;
    const CommandResult sim = run_jointlab("simulate " + model +
                                           " --impact 0 --force 50 --duration 0.05 --fs 4000 "
                                           "--quiet --out " +
                                           dir + "/hit.csv");
    EXPECT_EQ(sim.status, 0) << chi << ": " << sim.err;
  }
  for (const char* chi : {"-1.0", "-3.0", "inf"}) {
    const std::string model = write_model(dir, chi);
    expect_error(run_jointlab("modes " + model + " --out " + dir + "/modes.csv"),
                 fmt::format("iwan.rivet: chi = {} must be {}> -1", std::stod(chi),
                             std::isfinite(std::stod(chi)) ? "" : "a finite number "));
  }
  write_text(dir + "/beam.toml", "[joints]\nchi = -1.0\n");
  expect_error(run_jointlab("build-model " + dir + "/beam.toml --out " + dir + "/m"),
               "field 'joints.chi' = -1 must be > -1");
  const std::string model = write_model(dir, "-0.5");
  EXPECT_EQ(run_jointlab("modes " + model + " --out " + dir + "/modes.csv").status, 0);
  const std::string iwan = "update-iwan " + model + " --measured " + dir + " --sensors " + dir +
                           "/s.csv --mode 1 --out " + dir + "/u ";
  expect_error(run_jointlab(iwan + "--set rivet --chi-range -1:0.5"),
               "--chi-range -1:0.5: need LO < HI with both chi > -1");
  // A range past 0 passes the checks (the command then fails on the measured data that are not
  // there).
  const CommandResult above = run_jointlab(iwan + "--set rivet --chi-range 0.1:0.5");
  EXPECT_EQ(above.status, 2) << above.err;
  EXPECT_EQ(above.err.find("--chi-range"), std::string::npos) << above.err;
  expect_error(run_jointlab(iwan + "--set rivet --fs-range 0:10"),
               "--fs-range 0:10: need LO < HI with both Fs > 0");
  expect_error(run_jointlab(iwan + "--set spring.kz"), "--set spring.kz: update-iwan updates");
  // beta >= 0, as in model files (method.md: beta = 0 leaves the macroslip delta out): --beta 0
  // passes the checks (the command then fails on the measured data that are not there), a
  // negative value does not.
  const CommandResult zero = run_jointlab(iwan + "--set rivet --beta 0");
  EXPECT_EQ(zero.status, 2) << zero.err;
  EXPECT_EQ(zero.err.find("--beta"), std::string::npos) << zero.err;
  expect_error(run_jointlab(iwan + "--set rivet --beta=-1"), "--beta: -1 is negative");
  // A parameter that is no finite number says so.
  std::string text = testing::read_file(model);
  text.replace(text.find("Kt = 2.0e4"), 10, "Kt = inf");
  write_text(model, text);
  expect_error(run_jointlab("modes " + model + " --out " + dir + "/modes.csv"),
               "iwan.rivet: Kt = inf must be a finite number > 0");
  text.replace(text.find("Kt = inf"), 8, "Kt = 2.0e4");
  text.replace(text.find("beta = 1.0"), 10, "beta = nan");
  write_text(model, text);
  expect_error(run_jointlab("modes " + model + " --out " + dir + "/modes.csv"),
               "iwan.rivet: beta = nan must be a finite number >= 0");
}

TEST(Limits, SizesAreRefusedBeforeAllocating) {
  const std::string dir = scratch_dir("rel_sizes");
  // A Matrix Market size line declaring 1e12 entries in a file of a few bytes.
  std::string model = write_model(
      dir, "-0.5", "%%MatrixMarket matrix coordinate real symmetric\n2 2 1000000000000\n1 1 1\n");
  expect_error(run_jointlab("modes " + model + " --out " + dir + "/m.csv"),
               "M.mtx:2: size line declares 1000000000000 entries; the file's");
  // 2e9 x 2e9: the model is solved dense, far beyond memory.
  model = write_model(
      dir, "-0.5",
      "%%MatrixMarket matrix coordinate real symmetric\n2000000000 2000000000 1\n1 1 1\n");
  expect_error(run_jointlab("modes " + model + " --out " + dir + "/m.csv"),
               "M.mtx:2: size 2000000000 x 2000000000 exceeds the limit of");
  model = write_model(dir, "-0.5");
  expect_error(run_jointlab("simulate " + model + " --impact 1 --force 1 --duration 1 --fs 1e9 " +
                            "--out " + dir + "/sim.csv"),
               "simulate: the record would hold 1e+09 samples x 1 sensor(s) = 1e+09 values; the "
               "limit is 5e7");
  EXPECT_FALSE(fs::exists(dir + "/sim.csv"));
  // Within that limit, 1e9 Hz for 0.04 s is 1.6e8 steps of 2.5e-10 s against a 13 Hz mode
  // (w_1 dt = 2e-8): refused at once rather than run for a minute into a drifting record.
  expect_error(run_jointlab("simulate " + model + " --impact 1 --force 1 --duration 0.04 " +
                            "--fs 1e9 --out " + dir + "/sim.csv"),
               "would lose the acceleration to rounding; lower --fs");
  EXPECT_FALSE(fs::exists(dir + "/sim.csv"));
  write_text(dir + "/beam.toml", "[mesh]\nelement = \"beam\"\nsize = 1e-7\n");
  expect_error(run_jointlab("build-model " + dir + "/beam.toml --out " + dir + "/m"),
               "field 'mesh.size' = 1e-07 m is too small: 5e+06 beam elements per strip, the "
               "limit is 100000");
  EXPECT_FALSE(fs::exists(dir + "/m/model.toml"));
  write_text(dir + "/shell.toml", "[mesh]\nelement = \"shell\"\nsize = 1e-7\n");
  expect_error(run_jointlab("build-model " + dir + "/shell.toml --out " + dir + "/m"),
               "field 'mesh.size' = 1e-07 m is too small: 1.27e+12 shell elements per strip, "
               "the limit is 2000000");
  EXPECT_FALSE(fs::exists(dir + "/m/model.toml"));
  // Kt = 1e-300 puts phi_max beyond double precision; the joint to ground is named so.
  model = write_model(dir, "-0.5");
  std::string text = testing::read_file(model);
  text.replace(text.find("Kt = 2.0e4"), 10, "Kt = 1e-300");
  write_text(model, text);
  expect_error(run_jointlab("qsma " + model + " --mode 1 --out " + dir + "/q.csv"),
               "QSMA: the Iwan element between DOF 0 and ground (Fs = 40, Kt = 1e-300,");
}

// The rows of a numeric CSV (header dropped), every cell parsed.
std::vector<std::vector<double>> csv_rows(const fs::path& p) { return backbone_rows(p); }

// A one-mode model: unit mass on k0 = 3.47e5 N/m with an Iwan element to ground of K_T = 66.9
// N/m, F_S = 5.1e4 N, chi = -0.52, beta = 2.29 (the one-mode equivalent of a bolted-beam fit:
// K_T / k0 = 1.9e-4, phi_max = 959 m).
std::string write_soft_joint_model(const std::string& dir) {
  write_text(dir + "/M.mtx", "%%MatrixMarket matrix coordinate real symmetric\n1 1 1\n1 1 1\n");
  write_text(dir + "/K.mtx",
             "%%MatrixMarket matrix coordinate real symmetric\n1 1 1\n1 1 3.47e5\n");
  write_text(dir + "/model.toml",
             "[matrices]\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\n\n"
             "[iwan.soft]\nFs = 5.1e4\nKt = 66.9\nchi = -0.52\nbeta = 2.29\n\n"
             "[[joint]]\na = 0\nb = \"ground\"\nelement = \"iwan.soft\"\n");
  return dir + "/model.toml";
}

// The SDOF closed form of method.md section 3 with unit mass: omega^2 = (k0 q + F(q)) / q,
// F the Iwan element's virgin force below phi_max (written out here from method.md, not
// taken from the library).
double soft_joint_frequency_hz(double q) {
  const double k0 = 3.47e5, fs = 5.1e4, kt = 66.9, chi = -0.52, beta = 2.29;
  const double c = (chi + 1) / (chi + 2);
  const double phi_max = fs * (1 + beta) / (kt * (beta + c));
  const double r = fs * (chi + 1) / (std::pow(phi_max, chi + 2) * (beta + c));
  const double f = kt * q - r * std::pow(q, chi + 2) / ((chi + 1) * (chi + 2));
  return std::sqrt((k0 * q + f) / q) / (2 * M_PI);
}

// The soft joint once crashed qsma (exit 139) with the default range and wrote 11 identical
// rows for q in [1e-7, 1e-3]. The given range now has 11 increasing amplitudes from q_min to
// q_max whose frequencies match the closed form within 1e-6 (the CSV's 10 significant digits
// and Newton solves to 1e-12 of the forces leave ~1e-10); the default range gives finite
// rows, exit 0; q_max = 1e100 is reached (the spring carries any load) rather than cut off.
TEST(QsmaSoftJoint, EveryRangeGivesDistinctCorrectPoints) {
  const std::string dir = scratch_dir("rel_soft_joint");
  const std::string model = write_soft_joint_model(dir);
  CommandResult r = run_jointlab("qsma " + model + " --mode 1 --out " + dir + "/default.csv");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto full = csv_rows(dir + "/default.csv");
  ASSERT_EQ(full.size(), 50u);
  for (const auto& row : full)
    for (double v : row) EXPECT_TRUE(std::isfinite(v));

  r = run_jointlab("qsma " + model + " --mode 1 --qmin 1e-7 --qmax 1e-3 --points 11 --out " + dir +
                   "/range.csv");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rows = csv_rows(dir + "/range.csv");
  ASSERT_EQ(rows.size(), 11u);
  EXPECT_TRUE(Close(rows.front()[1], 1e-7, 1e-9));
  EXPECT_TRUE(Close(rows.back()[1], 1e-3, 1e-9));
  for (size_t i = 0; i < rows.size(); ++i) {
    if (i > 0) {
      EXPECT_GT(rows[i][1], rows[i - 1][1]) << i;
    }
    EXPECT_TRUE(Close(rows[i][2], soft_joint_frequency_hz(rows[i][1]), 1e-6)) << i;
  }

  r = run_jointlab("qsma " + model + " --mode 1 --qmax 1e100 --points 50 --out " + dir +
                   "/huge.csv");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto huge = csv_rows(dir + "/huge.csv");
  ASSERT_EQ(huge.size(), 50u);
  EXPECT_TRUE(Close(huge.back()[1], 1e100, 1e-9));
}

// simulate refuses a force whose energies leave double precision and a pulse that falls
// between the time steps (it once wrote accelerations of 3.6e301 with an energy closure of
// NaN, and an all-zero record whose header said 10 N), before writing anything.
TEST(SimulateLimits, ForcesAndPulsesItCannotRepresentAreRefused) {
  const std::string dir = scratch_dir("rel_sim_limits");
  const std::string model = write_model(dir, "-0.5");
  const std::string sim =
      "simulate " + model + " --impact 0 --duration 0.5 --fs 2000 --out " + dir + "/sim.csv ";
  expect_error(run_jointlab(sim + "--force 1e300"),
               "force 1e+300 N is outside the magnitudes 1e-100 to 1e100 N");
  expect_error(run_jointlab(sim + "--force 10 --pulse 1e-300"),
               "the pulse of 1e-300 s is shorter than two time steps");
  EXPECT_FALSE(fs::exists(dir + "/sim.csv"));
}

// What would stop simulate from writing its record is refused before the simulation runs
// (two sensors on one channel and an unknown extension once failed only after seconds of
// work): without --quiet, the first progress line ("... impact at ...") would have come first.
TEST(SimulateLimits, WhatTheRecordCannotBeIsRefusedBeforeSimulating) {
  const std::string dir = scratch_dir("rel_sim_before");
  const std::string model = write_model(dir, "-0.5");
  const std::string sim = "simulate " + model + " --impact 0 --force 10 --duration 0.5 --fs 2000 ";
  const auto refused_first = [](const CommandResult& r, const std::string& fragment) {
    expect_error(r, fragment);
    EXPECT_EQ(r.err.find("impact at"), std::string::npos) << r.err.substr(0, 500);
  };
  refused_first(run_jointlab(sim + "--sensors 0 --sensors 0 --out " + dir + "/s.csv"),
                "simulate: sensor 0 is given twice");
  refused_first(run_jointlab(sim + "--out " + dir + "/s.xls"),
                "s.xls: cannot tell the format to write from extension '.xls' (.csv, .uff, .mat)");
  refused_first(run_jointlab(sim + "--out " + dir + "/no/such/s.csv"),
                "the folder '" + dir + "/no/such' does not exist: create it first");
  refused_first(run_jointlab(sim + "--out " + dir), "is a folder: give a file name");
  EXPECT_FALSE(fs::exists(dir + "/s.csv"));
  // The check passes what write_record writes.
  const CommandResult ok = run_jointlab(sim + "--out " + dir + "/s.uff");
  EXPECT_EQ(ok.status, 0) << ok.err;
  EXPECT_NE(ok.err.find("impact at"), std::string::npos) << ok.err;
}

// What is not a regular file is refused before it is read, naming it: a FIFO once hung, a
// directory read as "empty file" or as the default beam description, /dev/zero read 2 GB.
TEST(Readers, WhatIsNotARegularFileIsRefusedBeforeReading) {
  const std::string dir = scratch_dir("rel_not_regular");
  const std::string fifo = dir + "/pipe.csv";
  ASSERT_EQ(std::system(("mkfifo " + fifo).c_str()), 0);
  expect_error(run_jointlab("process " + fifo + " --band 70:90 --out " + dir + "/o"),
               fifo + ": is a FIFO (named pipe), not a file");
  fs::create_directories(dir + "/adir");
  expect_error(run_jointlab("build-model " + dir + "/adir --out " + dir + "/m"),
               dir + "/adir: is a directory, not a file");
  EXPECT_FALSE(fs::exists(dir + "/m"));
  std::string model = write_model(dir, "-0.5");
  std::string text = testing::read_file(model);
  text.replace(text.find("\"M.mtx\""), 7, "\"adir\"");
  write_text(model, text);
  expect_error(run_jointlab("modes " + model + " --out " + dir + "/modes.csv"),
               "adir: is a directory, not a file");
  if (fs::exists("/dev/zero")) {
    text.replace(text.find("\"adir\""), 6, "\"/dev/zero\"");
    write_text(model, text);
    expect_error(run_jointlab("modes " + model + " --out " + dir + "/modes.csv"),
                 "/dev/zero: is a character device, not a file");
  }
}

// A time base stated twice, a quoted empty name with a unit after it and an unbalanced quote
// in the header are refused with the file and line (the last "# fs:" once silently won, and
// `time,"" [m/s^2]` made a channel named `"`).
TEST(Readers, AmbiguousHeadersAreRefusedWithFileAndLine) {
  const std::string dir = scratch_dir("rel_headers");
  const std::string rows = "0,1\n0.001,2\n0.002,3\n";
  write_text(dir + "/fs2.csv", "# fs: 1000\n# fs: 2000\nacc1 [m/s^2]\n1\n2\n3\n");
  expect_error(run_jointlab("process " + dir + "/fs2.csv --band 70:90 --out " + dir + "/o"),
               "fs2.csv:2: a second '# fs:' line (2000)");
  write_text(dir + "/empty_name.csv", "time,\"\" [m/s^2]\n" + rows);
  expect_error(run_jointlab("process " + dir + "/empty_name.csv --band 70:90 --out " + dir + "/o"),
               "empty_name.csv:1: header field 2");
  write_text(dir + "/quote.csv", "time,\"acc1 [m/s^2]\n" + rows);
  expect_error(run_jointlab("process " + dir + "/quote.csv --band 70:90 --out " + dir + "/o"),
               "quote.csv:1: the header row has an unbalanced quote");
  EXPECT_FALSE(fs::exists(dir + "/o"));
}

// A clean single-mode ring-down, f_n = 100 Hz, zeta = 0.05, at 10 kHz for 1 s, band
// 80:120 Hz: summary.json once said linear frequency 0 +- 0 Hz and damping 0 +- 0 with exit 0,
// every point marked superharmonic (the mode's own tail in 40:60 Hz, integrated to
// displacement, outweighed the band). Now no point is marked and the linear values are right
// within the acceptance's 0.5 % in frequency and 10 % in damping (measured: 9e-8 and 1.3e-6
// relative; the record is exact, so only the method's bias is left).
TEST(NoMadeUpZeros, HeavilyDampedModeGivesItsLinearValues) {
  const std::string dir = scratch_dir("rel_zeta05");
  const double fn = 100, zeta = 0.05, fs = 1e4;
  const double wn = 2 * M_PI * fn, wd = wn * std::sqrt(1 - zeta * zeta);
  std::string text = "time,acc1 [m/s^2]\n";
  for (int k = 0; k < 10000; ++k) {
    const double t = k / fs;
    text += fmt::format("{},{}\n", t, std::exp(-zeta * wn * t) * std::sin(wd * t));
  }
  write_text(dir + "/hit.csv", text);
  const CommandResult r =
      run_jointlab("process " + dir + "/hit.csv --band 80:120 --out " + dir + "/o");
  ASSERT_EQ(r.status, 0) << r.err;
  const data::JsonValue summary = data::read_json(dir + "/o/summary.json");
  const data::JsonValue& band = summary.find("files")->items().at(0).find("bands")->items().at(0);
  ASSERT_NE(band.find("linear_frequency_hz"), nullptr);
  EXPECT_TRUE(Close(band.find("linear_frequency_hz")->number(), fn, 5e-3))
      << band.find("linear_frequency_hz")->number();
  EXPECT_TRUE(Close(band.find("linear_damping_ratio")->number(), zeta, 0.1))
      << band.find("linear_damping_ratio")->number();
  EXPECT_GT(band.find("linear_frequency_std_hz")->number(), 0);
  EXPECT_GT(band.find("linear_damping_std")->number(), 0);
  EXPECT_EQ(band.find("linear_reason"), nullptr);
  const auto rows = backbone_rows(dir + "/o/hit.acc1.band1.csv");
  ASSERT_GE(rows.size(), 2u);
  for (const auto& row : rows) EXPECT_EQ(row.at(11), 0) << "a point marked harmonic";
}

// A band that holds only the second harmonic of a stronger 80 Hz mode (0.1 of it, phase
// locked): every point is superharmonic, so there is nothing to fit linear values on.
// summary.json says why instead of writing 0 +- 0, and process exits 2 naming the band.
TEST(NoMadeUpZeros, ABandOfSuperharmonicsHasNoLinearValuesAndSaysWhy) {
  const std::string dir = scratch_dir("rel_superharmonic");
  std::string text = "time,acc1 [m/s^2]\n";
  for (int k = 0; k < 4000; ++k) {
    const double t = k * 1e-3, w = 2 * M_PI * 80;
    text +=
        fmt::format("{},{}\n", t,
                    std::exp(-t) * std::sin(w * t) + 0.1 * std::exp(-2 * t) * std::sin(2 * w * t));
  }
  write_text(dir + "/hit.csv", text);
  const CommandResult r =
      run_jointlab("process " + dir + "/hit.csv --band 140:180 --out " + dir + "/o");
  expect_error(r,
               "band 1 (140:180 Hz): acc1: no linear values: every one of the 80 points follows a "
               "multiple of a stronger mode's frequency (superharmonic); everything else is "
               "written to " +
                   dir + "/o");
  const data::JsonValue summary = data::read_json(dir + "/o/summary.json");
  const data::JsonValue& band = summary.find("files")->items().at(0).find("bands")->items().at(0);
  EXPECT_EQ(band.find("linear_frequency_hz"), nullptr);
  EXPECT_EQ(band.find("linear_damping_ratio"), nullptr);
  ASSERT_NE(band.find("linear_reason"), nullptr);
  EXPECT_NE(band.find("linear_reason")->string().find("superharmonic"), std::string::npos);
  const std::string json = testing::read_file(dir + "/o/summary.json");
  EXPECT_EQ(json.find("\"linear_frequency_hz\""), std::string::npos) << "a made-up value";
}

// A record on Unix time (1.7e9 s) keeps distinct backbone times: time_s is written in full
// precision (10 significant digits once gave 76 rows 5 distinct times).
TEST(BackboneTimes, AreWrittenInFullPrecision) {
  const std::string dir = scratch_dir("rel_unix_time");
  std::string s = "time,acc1 [m/s^2]\n";
  for (int k = 0; k < 4000; ++k) {
    const double t = k * 1e-3;
    s += fmt::format("{},{}\n", 1.7e9 + t, std::exp(-t) * std::sin(2 * M_PI * 80 * t));
  }
  write_text(dir + "/hit.csv", s);
  const CommandResult r =
      run_jointlab("process " + dir + "/hit.csv --band 70:90 --out " + dir + "/o");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rows = backbone_rows(dir + "/o/hit.acc1.band1.csv");
  ASSERT_GT(rows.size(), 10u);
  for (size_t i = 1; i < rows.size(); ++i) EXPECT_GT(rows[i][0], rows[i - 1][0]) << i;
  EXPECT_GE(rows.front()[0], 1.7e9);
}

// A stepped-sine run whose every file gives no point fails as process does (it once exited 0
// with "0 backbone file(s)"); summary.json with the reasons is still written.
TEST(SteppedSineEmpty, NoBackboneAtAllExitsTwo) {
  const std::string dir = scratch_dir("rel_sine_empty");
  write_text(dir + "/flat.csv",
             "# control: force\nfrequency_hz,force [N],response [m/s^2],phase [deg]\n"
             "10,1,1,0\n11,1,1,0\n12,1,1,0\n13,1,1,0\n14,1,1,0\n15,1,1,0\n");
  const CommandResult r = run_jointlab("stepped-sine " + dir + "/flat.csv --out " + dir + "/o");
  expect_error(r, "stepped-sine: no backbone from any of the 1 file(s)");
  EXPECT_NE(r.err.find("no backbone point"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(dir + "/o/summary.json"));
}

// process killed after its commit point (its staging folder renamed to .process.commit, the
// files half moved) leaves a folder that may mix two runs: update-linear and update-iwan
// --measured refuse it, saying to re-run process (they once read such a mix with exit 0); a
// re-run completes the commit and the folder reads again.
TEST(KilledCommit, ReadersRefuseAFolderMidCommit) {
  const std::string dir = scratch_dir("rel_killed_commit");
  write_text(dir + "/hit.csv", ringdown_csv());
  const std::string process = "process " + dir + "/hit.csv --band 70:90 --out " + dir + "/p";
  ASSERT_EQ(run_jointlab(process).status, 0);
  fs::create_directory(dir + "/p/.process.commit");
  write_text(dir + "/p/.process.commit/.manifest", "hit.acc1.band1.csv\nsummary.json\n");
  write_text(dir + "/p/.process.commit/summary.json", "{}");
  const std::string model = write_model(dir, "-0.5");
  write_text(dir + "/s.csv", "channel,dof\nacc1,0\n");
  const std::string measured = " --measured " + dir + "/p --sensors " + dir + "/s.csv";
  const std::string mix =
      "/p: a 'process' run was killed while putting its results in place (.process.commit is "
      "left): the folder may mix old and new results; re-run process into it";
  expect_error(run_jointlab("update-iwan " + model + " --set iwan.rivet --mode 1" + measured +
                            " --out " + dir + "/u"),
               mix);
  expect_error(run_jointlab("update-linear " + model + " --set spring.kz" + measured + " --out " +
                            dir + "/l"),
               mix);
  ASSERT_EQ(run_jointlab(process).status, 0);
  EXPECT_FALSE(fs::exists(dir + "/p/.process.commit"));
  const CommandResult again = run_jointlab("update-iwan " + model + " --set iwan.rivet --mode 1" +
                                           measured + " --out " + dir + "/u");
  EXPECT_EQ(again.err.find("was killed while"), std::string::npos) << again.err;
}

// Out of memory (an address-space limit, ulimit -v), whatever runs out first (mapping the
// file, the columns, the spectrum, FFTW's plans): one line naming the record, exit status 2,
// never "internal error: std::bad_alloc" nor FFTW's abort (exit 134) in its own planning. A
// one-channel record of 1e6 samples under limits from 80 MB to 512 MB.
TEST(OutOfMemory, TheRecordIsNamedAtEveryLimit) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space";
#endif
  const std::string dir = scratch_dir("out_of_memory");
  const std::string path = dir + "/long.csv";
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fputs("# fs: 10000\nacc1 [m/s^2]\n", f);
    for (int k = 0; k < 1000000; ++k) {
      const double t = k * 1e-4;
      std::fprintf(
          f, "%.9g\n",
          std::exp(-2 * M_PI * t) * std::sin(2 * M_PI * 100 * t) + 1e-4 * std::sin(0.7 * k * k));
    }
    std::fclose(f);
  }
  std::map<int, int> statuses;
  for (const int mb : {80, 100, 120, 130, 140, 150, 160, 192, 256, 512}) {
    SCOPED_TRACE(fmt::format("ulimit -v {} MB", mb));
    const std::string cmd = fmt::format(
        "ulimit -v {}; exec {}/bin/jointlab process {} --band 80:120 --threads 1 --out {}/out "
        ">/dev/null 2>{}/err.txt",
        mb * 1024, binary_dir(), path, dir, dir);
    const int raw = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(raw)) << "killed by signal " << WTERMSIG(raw);
    const int status = WEXITSTATUS(raw);
    statuses[mb] = status;
    const std::string err = testing::read_file(dir + "/err.txt");
    if (status == 0) continue;
    EXPECT_EQ(status, 2) << err;
    EXPECT_EQ(err, fmt::format("jointlab: error: {}: out of memory while reading and processing "
                               "this record ({:.3g} MB on disk, 1 file(s) at once); give it alone "
                               "with --threads 1, or a shorter record\n",
                               path, static_cast<double>(fs::file_size(path)) / 1e6));
  }
  EXPECT_EQ(statuses[80], 2);   // the limits reach from too little ...
  EXPECT_EQ(statuses[512], 0);  // ... to enough
}

// A record's peak memory is at most three doubles a sample plus a fixed amount. A 5e6-sample
// channel (above 2^22 analysed samples: the long-record path, padded by its filters' settling
// times) is processed by the command in a child of its own, whose peak resident set
// (wait4's ru_maxrss) must stay below 24 bytes a sample plus 40 MB: the program with its
// libraries takes about 17 MB before it reads anything, and this record measured 131 MB
// (243 MB when long records were padded to twice their length).
TEST(OutOfMemory, ALongRecordPeaksBelowThreeDoublesASample) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's shadow memory is not the program's";
#endif
  constexpr int kSamples = 5000000;
  const std::string dir = scratch_dir("peak_memory");
  const std::string path = dir + "/long.csv";
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fputs("# fs: 10000\nacc1 [m/s^2]\n", f);
    for (int k = 0; k < kSamples; ++k) {
      const double t = k * 1e-4;
      std::fprintf(f, "%.7g\n",
                   100 * std::exp(-2 * M_PI * 0.1 * t) * std::sin(2 * M_PI * 100 * t) +
                       1e-4 * std::sin(0.7 * k * k));
    }
    std::fclose(f);
  }
  const std::string binary = binary_dir() + "/bin/jointlab";
  const std::string out = dir + "/out";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::freopen("/dev/null", "w", stdout);
    std::freopen((dir + "/err.txt").c_str(), "w", stderr);
    execl(binary.c_str(), binary.c_str(), "process", path.c_str(), "--band", "80:120", "--threads",
          "1", "--out", out.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  ASSERT_EQ(wait4(pid, &status, 0, &usage), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  ASSERT_EQ(WEXITSTATUS(status), 0) << testing::read_file(dir + "/err.txt");
  const double peak = static_cast<double>(usage.ru_maxrss) * 1024;  // ru_maxrss is in kB
  EXPECT_LE(peak, 24.0 * kSamples + 40e6) << fmt::format("{:.1f} bytes a sample", peak / kSamples);
  EXPECT_TRUE(fs::exists(out + "/long.acc1.band1.csv"));
}

TEST(ArgumentErrors, NegativeThreadsAreNamedWithReadableBounds) {
  const std::string dir = scratch_dir("rel_threads");
  write_text(dir + "/hit.csv", ringdown_csv());
  const CommandResult r =
      run_jointlab("process " + dir + "/hit.csv --band 70:90 --threads -1 --out " + dir + "/o");
  expect_error(r, "--threads: -1 is not between 0 and 1024");
  EXPECT_LT(r.err.size(), 200u);
  write_text(dir + "/c.toml", "");
  expect_error(run_jointlab("run " + dir + "/c.toml --threads -1"),
               "--threads: -1 is not between 0 and 1024");
}

}  // namespace
}  // namespace jointlab::testing
